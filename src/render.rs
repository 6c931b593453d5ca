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
        let ctx = GpuContext::new(adapter)?;
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
        match self {
            Engine::Gpu(g) => g.render_pass(sample_index),
            Engine::Cpu(c) => {
                c.render_pass(sample_index);
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
/// `data[2 i + 1]` = (sum r^2, sum g^2, sum b^2, 0), pixel i row-major from the top-left.
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

    /// Mean radiance of every pixel, as `width * height * 3` linear floats.
    pub fn to_rgb(&self) -> Vec<f32> {
        (0..self.pixel_count()).flat_map(|i| self.mean(i)).collect()
    }
}

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
    mut on_pass: impl FnMut(&Progress, &mut Engine) -> Result<(), E>,
) -> Result<Progress, E>
where
    E: From<GpuError>,
{
    let start = Instant::now();
    let pixels = scene.width as u64 * scene.height as u64;
    let mut progress = Progress {
        passes_done: 0,
        passes_total: scene.spp,
        elapsed: Duration::ZERO,
        samples: 0,
    };
    for pass in 0..scene.spp {
        engine.render_pass(pass)?;
        progress.passes_done = pass + 1;
        progress.samples = pixels * progress.passes_done as u64;
        progress.elapsed = start.elapsed();
        on_pass(&progress, engine)?;
    }
    Ok(progress)
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
