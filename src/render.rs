//! Backend choice and the progressive render loop shared by both backends.

use std::time::{Duration, Instant};

use crate::cpu::CpuRenderer;
use crate::gpu::{GpuContext, GpuError, GpuRenderer};
use crate::scene::FlatScene;

/// Which backend renders.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BackendChoice {
    /// Vulkan adapter by index of [`crate::gpu::list_adapters`] (0: the preferred one).
    Gpu { adapter: usize },
    /// The CPU reference.
    Cpu,
}

/// An open backend holding one scene and its accumulation buffer.
pub enum Engine {
    Gpu(Box<GpuRenderer>),
    Cpu(Box<CpuRenderer>),
}

impl Engine {
    /// Opens the GPU backend; fails when no Vulkan adapter exists.
    pub fn gpu(scene: &FlatScene, adapter: usize) -> Result<Self, GpuError> {
        let ctx = GpuContext::shared(adapter)?;
        Ok(Engine::Gpu(Box::new(GpuRenderer::new(ctx, scene)?)))
    }

    /// Opens the CPU reference.
    pub fn cpu(scene: &FlatScene) -> Self {
        Engine::Cpu(Box::new(CpuRenderer::new(scene)))
    }

    /// Opens the chosen backend. When the GPU is chosen but no Vulkan adapter exists, falls
    /// back to the CPU and returns a one-line note saying so.
    pub fn open(
        scene: &FlatScene,
        choice: BackendChoice,
    ) -> Result<(Self, Option<String>), GpuError> {
        match choice {
            BackendChoice::Cpu => Ok((Self::cpu(scene), None)),
            BackendChoice::Gpu { adapter } => match Self::gpu(scene, adapter) {
                Ok(e) => Ok((e, None)),
                Err(GpuError::NoAdapter) => Ok((
                    Self::cpu(scene),
                    Some(format!(
                        "{}; rendering on the CPU instead",
                        GpuError::NoAdapter
                    )),
                )),
                Err(e) => Err(e),
            },
        }
    }

    /// The device that renders, for the user.
    pub fn name(&self) -> String {
        match self {
            Engine::Gpu(g) => g.name(),
            Engine::Cpu(c) => c.name(),
        }
    }

    /// Adds one sample per pixel.
    pub fn render_pass(&mut self, sample_index: u32) -> Result<(), GpuError> {
        self.render_samples(sample_index..sample_index + 1)
    }

    /// Adds the samples with indices `samples` to every pixel.
    pub fn render_samples(&mut self, samples: std::ops::Range<u32>) -> Result<(), GpuError> {
        match self {
            Engine::Gpu(g) => g.render_samples(samples),
            Engine::Cpu(c) => {
                samples.for_each(|i| c.render_pass(i));
                Ok(())
            }
        }
    }

    /// How many samples per pixel one [`Engine::render_samples`] call should ask for: the
    /// GPU's submissions grow to several samples when one takes much less than its target
    /// time; the CPU renders one at a time.
    pub fn samples_per_call(&self) -> u32 {
        match self {
            Engine::Gpu(g) => g.samples_per_call(),
            Engine::Cpu(_) => 1,
        }
    }

    /// Ends the GPU device as a driver reset would, for tests of a render's recovery; the
    /// CPU has nothing to lose.
    pub fn lose_device(&mut self) {
        if let Engine::Gpu(g) = self {
            g.lose_device();
        }
    }

    /// The time one GPU submission should take (see
    /// [`crate::gpu::render::DEFAULT_SUBMISSION_TARGET`]); the CPU ignores it.
    pub fn set_submission_target(&mut self, target: Duration) {
        if let Engine::Gpu(g) = self {
            g.set_submission_target(target);
        }
    }

    /// Replaces the accumulated sums with `acc` (of this engine's size): a resumed render
    /// continues from them.
    pub fn set_accumulation(&mut self, acc: &Accumulation) -> Result<(), GpuError> {
        match self {
            Engine::Gpu(g) => g.set_accumulation(&acc.data),
            Engine::Cpu(c) => {
                c.set_accumulation(&acc.data);
                Ok(())
            }
        }
    }

    /// The accumulated samples so far.
    pub fn accumulation(&mut self) -> Result<Accumulation, GpuError> {
        let ((width, height), data) = match self {
            Engine::Gpu(g) => (g.size(), g.accumulation()?),
            Engine::Cpu(c) => (c.size(), c.accumulation()),
        };
        Ok(Accumulation {
            width,
            height,
            data,
        })
    }
}

/// Per-pixel sums of samples: `data[2 i]` = (sum r, sum g, sum b, count),
/// `data[2 i + 1]` = (sum r^2, sum g^2, sum b^2, samples dropped as not finite), pixel i
/// row-major from the top-left.
#[derive(Debug, Clone, PartialEq)]
pub struct Accumulation {
    pub width: u32,
    pub height: u32,
    pub data: Vec<[f32; 4]>,
}

impl Accumulation {
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Samples accumulated in pixel `i`.
    pub fn samples(&self, i: usize) -> f32 {
        self.data[2 * i][3]
    }

    /// Mean radiance of pixel `i`.
    pub fn mean(&self, i: usize) -> [f32; 3] {
        let s = self.data[2 * i];
        let n = s[3].max(1.0);
        [s[0] / n, s[1] / n, s[2] / n]
    }

    /// Unbiased sample variance of one sample of pixel `i`, per channel.
    pub fn variance(&self, i: usize) -> [f32; 3] {
        let s = self.data[2 * i];
        let q = self.data[2 * i + 1];
        let n = s[3];
        if n < 2.0 {
            return [0.0; 3];
        }
        std::array::from_fn(|c| ((q[c] - s[c] * s[c] / n) / (n - 1.0)).max(0.0))
    }

    /// Samples dropped because they were not finite (NaN or infinite), over all pixels.
    pub fn non_finite(&self) -> u64 {
        (0..self.pixel_count())
            .map(|i| self.data[2 * i + 1][3] as u64)
            .sum()
    }

    /// Mean radiance of every pixel, as `width * height * 3` linear floats.
    pub fn to_rgb(&self) -> Vec<f32> {
        (0..self.pixel_count()).flat_map(|i| self.mean(i)).collect()
    }

    /// Estimated relative squared error of pixel `i`'s mean, averaged over its channels:
    /// (variance / n) / (mean^2 + 0.01), the relative MSE of the convergence reports with
    /// the unknown true value replaced by the mean. Unbiased for independent samples;
    /// the low-discrepancy samplers converge faster than the variance says, so for them
    /// it is an overestimate.
    pub fn pixel_rel_mse(&self, i: usize) -> f64 {
        let (m, v, n) = (
            self.mean(i),
            self.variance(i),
            self.samples(i).max(1.0) as f64,
        );
        (0..3)
            .map(|c| v[c] as f64 / n / ((m[c] as f64).powi(2) + REL_MSE_EPSILON))
            .sum::<f64>()
            / 3.0
    }

    /// Estimated relative MSE of the whole image (`pixel_rel_mse` averaged over pixels).
    pub fn estimated_rel_mse(&self) -> f64 {
        (0..self.pixel_count())
            .map(|i| self.pixel_rel_mse(i))
            .sum::<f64>()
            / self.pixel_count().max(1) as f64
    }

    /// Estimated relative error: the square root of `estimated_rel_mse`.
    pub fn estimated_rel_error(&self) -> f64 {
        self.estimated_rel_mse().sqrt()
    }
}

/// The 0.01 in relative MSE, mean((x - r)^2 / (r^2 + 0.01)): keeps black pixels from
/// dominating.
pub const REL_MSE_EPSILON: f64 = 0.01;

/// When a progressive render may stop before its last pass.
#[derive(Debug, Clone, Copy, Default)]
pub struct StopRule {
    /// Start no pass that is not expected to end within this time.
    pub time_limit: Option<Duration>,
    /// Stop once the estimated relative error (`Accumulation::estimated_rel_error`) is at
    /// most this.
    pub target_error: Option<f64>,
}

/// Why a progressive render ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stopped {
    /// Every pass of the scene's spp ran.
    AllPasses,
    TimeLimit,
    TargetError,
}

/// Passes before the error estimate is trusted to stop a render: below this a pixel's
/// sample variance is itself too noisy (a pixel whose few samples all missed a light reads
/// as converged).
pub const MIN_PASSES_FOR_ERROR: u32 = 16;

/// Where a progressive render stands after a pass.
#[derive(Debug, Clone, Copy)]
pub struct Progress {
    pub passes_done: u32,
    pub passes_total: u32,
    pub elapsed: Duration,
    /// Pixel samples traced so far.
    pub samples: u64,
}

impl Progress {
    pub fn samples_per_second(&self) -> f64 {
        self.samples as f64 / self.elapsed.as_secs_f64().max(1e-9)
    }
}

/// Renders `scene.spp` passes (sample indices 0..spp), calling `on_pass` after each; an error
/// from `on_pass` stops the render. Returns the final progress.
pub fn render_progressive<E>(
    engine: &mut Engine,
    scene: &FlatScene,
    on_pass: impl FnMut(&Progress, &mut Engine) -> Result<(), E>,
) -> Result<Progress, E>
where
    E: From<GpuError>,
{
    render_until(engine, scene, StopRule::default(), on_pass).map(|(p, _, _)| p)
}

/// As `render_progressive`, but ends early by `rule`. With a time limit, a pass starts only
/// if the mean pass time so far, and the last batch's, say it ends within the limit (the
/// first always runs). With a target error, the estimate is read back after `MIN_PASSES_FOR_ERROR` passes and then
/// whenever the passes since the last look took as long as the look itself or the pass
/// count is a power of two, so reading back costs at most about half the render. Returns
/// the progress, why it ended, and the last error estimate (when a target was set).
pub fn render_until<E>(
    engine: &mut Engine,
    scene: &FlatScene,
    rule: StopRule,
    on_pass: impl FnMut(&Progress, &mut Engine) -> Result<(), E>,
) -> Result<(Progress, Stopped, Option<f64>), E>
where
    E: From<GpuError>,
{
    render_from(engine, scene, rule, 0..scene.spp, on_pass)
}

/// [`render_until`] over the sample indices `passes` only: a resumed render starts past 0
/// (its engine holding the samples before), a range of a distributed render ends before
/// `scene.spp`. `Progress` counts passes as sample indices (`passes_done` is the next
/// index), and the time and samples of this run only. Passes go to the engine in batches
/// of [`Engine::samples_per_call`], and `on_pass` is called after each batch.
pub fn render_from<E>(
    engine: &mut Engine,
    scene: &FlatScene,
    rule: StopRule,
    passes: std::ops::Range<u32>,
    mut on_pass: impl FnMut(&Progress, &mut Engine) -> Result<(), E>,
) -> Result<(Progress, Stopped, Option<f64>), E>
where
    E: From<GpuError>,
{
    let start = Instant::now();
    let first = passes.start;
    let pixels = scene.width as u64 * scene.height as u64;
    let mut progress = Progress {
        passes_done: first,
        passes_total: passes.end,
        elapsed: Duration::ZERO,
        samples: 0,
    };
    let mut estimate = None;
    let mut look_cost = Duration::ZERO;
    let mut last_look = Duration::ZERO;
    let mut pass = first;
    // seconds per pass of the last batch
    let mut last_pass = 0.0;
    while pass < passes.end {
        let mut batch = engine.samples_per_call().clamp(1, passes.end - pass);
        if let Some(limit) = rule.time_limit {
            if pass > first {
                // as many passes as end within the limit at the mean pass time so far or at
                // the last batch's, whichever is longer (the machine may have got busier)
                let mean_pass = progress.elapsed.as_secs_f64() / (pass - first) as f64;
                let pass_time = mean_pass.max(last_pass);
                let left = limit.saturating_sub(start.elapsed()).as_secs_f64();
                let fit = (left / pass_time.max(1e-9)).floor().min(u32::MAX as f64) as u32;
                if fit == 0 {
                    return Ok((progress, Stopped::TimeLimit, estimate));
                }
                // at most half of what fits, so that batches shrink to single passes as
                // the limit nears and the last one's misprediction stays one pass's
                batch = batch.min((fit / 2).max(1));
            }
        }
        let batch_start = Instant::now();
        engine.render_samples(pass..pass + batch)?;
        last_pass = batch_start.elapsed().as_secs_f64() / batch as f64;
        let before = pass;
        pass += batch;
        progress.passes_done = pass;
        progress.samples = pixels * (pass - first) as u64;
        progress.elapsed = start.elapsed();
        on_pass(&progress, engine)?;
        if let Some(target) = rule.target_error {
            let n = progress.passes_done;
            let since = start.elapsed().saturating_sub(last_look);
            // a power of two reached in this batch
            let doubled = before.checked_ilog2() != n.checked_ilog2();
            if n >= MIN_PASSES_FOR_ERROR && (doubled || since >= look_cost) {
                let t0 = Instant::now();
                let e = engine.accumulation()?.estimated_rel_error();
                look_cost = t0.elapsed();
                last_look = start.elapsed();
                estimate = Some(e);
                if e <= target {
                    return Ok((progress, Stopped::TargetError, estimate));
                }
            }
        }
    }
    if rule.target_error.is_some() {
        estimate = Some(engine.accumulation()?.estimated_rel_error());
    }
    Ok((progress, Stopped::AllPasses, estimate))
}

/// Renders a whole scene with no progress reporting: the final accumulation.
pub fn render_scene(scene: &FlatScene, choice: BackendChoice) -> Result<Accumulation, GpuError> {
    let mut engine = match choice {
        BackendChoice::Cpu => Engine::cpu(scene),
        BackendChoice::Gpu { adapter } => Engine::gpu(scene, adapter)?,
    };
    render_progressive(&mut engine, scene, |_, _| Ok::<(), GpuError>(()))?;
    engine.accumulation()
}
