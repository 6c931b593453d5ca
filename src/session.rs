//! A render session: one scene on one backend, rendered in progressive passes. It owns
//! everything between a loaded scene and its finished sums: opening the backend (the CPU
//! when no Vulkan adapter exists), resuming a checkpoint, batching passes into the
//! backend's submissions, the stop rules (all passes, a time limit, a target error, an
//! interrupt), previews, checkpoints kept on disk or in memory, and, when the device is
//! lost, writing the samples last read back so that a long render never loses finished
//! work. `wgtrace render`, `converge`, the gallery example and the benchmarks all render
//! through it.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::accumulation::Accumulation;
use crate::aov::{check_output, write_output, Aov, OutputError};
use crate::checkpoint::{Checkpoint, CheckpointError};
use crate::denoise::{DenoiseError, Denoiser};
use crate::engine::{BackendChoice, Engine};
use crate::gpu::error::GpuError;
use crate::gpu::render::DEFAULT_SUBMISSION_TARGET;
use crate::image_io::{check_writable, probe_writable, write_error_map, ImageError};
use crate::scene::error::SceneError;
use crate::scene::flat::FlatScene;
use crate::scene::load::Overrides;
use crate::tuning::Tuning;

/// Reads, validates and flattens a scene file under the default tuning.
pub fn load_scene(path: &Path, overrides: &Overrides) -> Result<FlatScene, SceneError> {
    crate::scene::load::load(path, overrides, Tuning::default().build())
}

/// Validates and flattens scene text under the default tuning; `path` names it in errors.
pub fn load_scene_str(
    src: &str,
    path: &Path,
    overrides: &Overrides,
) -> Result<FlatScene, SceneError> {
    crate::scene::load::load_str(src, path, overrides, Tuning::default().build())
}

/// The most passes of an uncapped render ([`Passes::Uncapped`]).
pub const UNCAPPED_PASSES: u32 = 1 << 20;

/// Which sample indices a session renders. The scene's `spp` is the N of its point set
/// (what a sampler that depends on it sees); the passes a session runs are this.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub enum Passes {
    /// `0..spp`: the scene's samples.
    #[default]
    Scene,
    /// These indices only, ending at most at spp (`--sample-range`; ranges rendered apart
    /// are combined by `wgtrace merge`).
    Range(Range<u32>),
    /// As many as the stop rule lets run (a time limit or a target error with no sample
    /// count given): up to [`UNCAPPED_PASSES`], or to spp for a sampler whose points
    /// depend on it (`SamplerKind::depends_on_spp`).
    Uncapped,
}

impl Passes {
    /// The indices to render for `scene`.
    pub fn range(&self, scene: &FlatScene) -> Result<Range<u32>, SessionError> {
        match self {
            Passes::Scene => Ok(0..scene.spp),
            Passes::Uncapped if scene.sampler.depends_on_spp() => Ok(0..scene.spp),
            Passes::Uncapped => Ok(0..UNCAPPED_PASSES.max(scene.spp)),
            Passes::Range(r) if r.end > scene.spp => Err(SessionError::Invalid(format!(
                "--sample-range {}..{} ends past the render's {} samples per pixel",
                r.start, r.end, scene.spp
            ))),
            Passes::Range(r) => Ok(r.clone()),
        }
    }
}

/// Passes before the error estimate is trusted to stop a render: below this a pixel's
/// sample variance is itself too noisy (a pixel whose few samples all missed a light reads
/// as converged).
pub const MIN_PASSES_FOR_ERROR: u32 = 16;

/// When a progressive render may stop before its last pass.
#[derive(Debug, Clone, Default)]
pub struct StopRule {
    /// Start no pass that is not expected to end within this time.
    pub time_limit: Option<Duration>,
    /// Stop once the estimated relative error (`Accumulation::estimated_rel_error`) is at
    /// most this.
    pub target_error: Option<f64>,
    /// Stop after the current batch once this is set (Ctrl-C), writing the image and a
    /// checkpoint.
    pub interrupt: Option<Arc<AtomicBool>>,
    /// End before this sample index instead of the session's last (a convergence study
    /// reads the sums at points along one render).
    pub until: Option<u32>,
}

/// Why a progressive render ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stopped {
    /// Every pass asked for ran.
    AllPasses,
    TimeLimit,
    TargetError,
}

/// Where a progressive render stands after a batch of passes.
#[derive(Debug, Clone, Copy)]
pub struct Progress {
    /// The next sample index (passes are counted as sample indices).
    pub passes_done: u32,
    /// The sample index the run ends before.
    pub passes_total: u32,
    /// Time and pixel samples of this run only.
    pub elapsed: Duration,
    pub samples: u64,
    /// Of `samples`, those rendered before the run's time began: sample 0 when the GPU's
    /// spot check rendered it and the render kept it.
    pub untimed: u64,
}

impl Progress {
    /// The samples rendered in `elapsed`, per second.
    pub fn samples_per_second(&self) -> f64 {
        (self.samples - self.untimed.min(self.samples)) as f64
            / self.elapsed.as_secs_f64().max(1e-9)
    }
}

/// Where a session keeps its state between runs and processes.
#[derive(Debug, Clone)]
pub struct Saving {
    /// The checkpoint file. An interrupt, or a lost device, always writes it.
    pub path: PathBuf,
    /// Also write it every `every` (else the sums read back then are kept in memory, for a
    /// lost device).
    pub periodic: bool,
    /// How often the sums are read back (0: after every batch).
    pub every: Duration,
    /// Also write it when the render ends.
    pub at_end: bool,
}

/// Where the session writes the image.
#[derive(Debug, Clone)]
pub struct Output {
    /// The image (the format by its extension), written at the end, on an interrupt and
    /// when the device is lost.
    pub image: PathBuf,
    /// Also the per-pixel relative error estimate, at the end.
    pub error_map: Option<PathBuf>,
    /// Rewrite the image every N passes.
    pub preview_every: Option<u32>,
    /// AOVs written beside the colour (an EXR file's layers); those summed need a scene
    /// that accumulates them (`FlatScene::aovs`).
    pub aovs: Vec<Aov>,
    /// Denoise the colour with Open Image Denoise (the noisy one kept as the `noisy`
    /// layer of an EXR file); needs the AOVs' sums.
    pub denoise: bool,
}

/// What a session needs besides the scene.
#[derive(Debug, Clone)]
pub struct SessionOptions {
    pub backend: BackendChoice,
    /// Render on the CPU, with a note, when the GPU is chosen and no Vulkan adapter exists
    /// (`wgtrace render`); else that is an error.
    pub cpu_fallback: bool,
    pub tuning: Tuning,
    /// The sample indices the session holds when it ends.
    pub passes: Passes,
    /// Continue from this checkpoint (same scene and settings, holding samples from the
    /// range's start).
    pub resume: Option<PathBuf>,
    pub saving: Option<Saving>,
    pub output: Option<Output>,
    /// The time one GPU submission should take.
    pub submission_target: Duration,
}

impl Default for SessionOptions {
    fn default() -> Self {
        SessionOptions {
            backend: BackendChoice::Gpu { adapter: 0 },
            cpu_fallback: false,
            tuning: Tuning::default(),
            passes: Passes::Scene,
            resume: None,
            saving: None,
            output: None,
            submission_target: DEFAULT_SUBMISSION_TARGET,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    #[error(transparent)]
    Image(#[from] ImageError),
    #[error(transparent)]
    Denoise(#[from] DenoiseError),
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error("{}: cannot write checkpoint: {cause}", path.display())]
    WriteCheckpoint {
        path: PathBuf,
        cause: std::io::Error,
    },
    #[error("{0}")]
    Invalid(String),
    /// Ctrl-C or SIGTERM: the image so far and a checkpoint were written.
    #[error(
        "interrupted at sample {at}: wrote {} and checkpoint {}",
        image.as_ref().map_or("no image".into(), |p| p.display().to_string()),
        checkpoint.display()
    )]
    Interrupted {
        at: u32,
        image: Option<PathBuf>,
        checkpoint: PathBuf,
    },
    /// The device was lost (or failed) mid-render.
    #[error("{0}")]
    DeviceLost(Box<LostDevice>),
}

/// A device lost (or failed) mid-render, and what the session saved of its work.
#[derive(Debug)]
pub struct LostDevice {
    pub error: GpuError,
    /// The next sample when it happened.
    pub at: u32,
    /// The samples last read back, written as image and checkpoint, if any had been.
    pub saved: Option<Range<u32>>,
    pub image: Option<PathBuf>,
    pub checkpoint: PathBuf,
    /// How often the sums were read back.
    pub every: Duration,
}

impl std::fmt::Display for LostDevice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (error, at) = (&self.error, self.at);
        match &self.saved {
            Some(r) => write!(
                f,
                "{error} at sample {at}; wrote samples {}..{} (the last read back) to \
                 {}checkpoint {}",
                r.start,
                r.end,
                self.image
                    .as_ref()
                    .map_or(String::new(), |p| format!("{} and ", p.display())),
                self.checkpoint.display()
            ),
            None => write!(
                f,
                "{error} at sample {at}; no samples had been read back yet (that happens \
                 every --checkpoint-every {} s), so nothing was written",
                self.every.as_secs_f64()
            ),
        }
    }
}

impl SessionError {
    /// Whether the render's work so far is in a checkpoint it can be resumed from.
    pub fn resumable(&self) -> Option<&Path> {
        match self {
            SessionError::Interrupted { checkpoint, .. } => Some(checkpoint),
            SessionError::DeviceLost(lost) if lost.saved.is_some() => Some(&lost.checkpoint),
            _ => None,
        }
    }
}

/// A render that ran to its end: its sums, and how it went.
#[derive(Debug, Clone)]
pub struct Finished {
    pub progress: Progress,
    pub stopped: Stopped,
    /// The last error estimate (with a target error).
    pub estimate: Option<f64>,
    pub accumulation: Accumulation,
}

/// A session's start, checked before its backend opens: the samples it renders, and the
/// sums of a resumed checkpoint with the sample they end at.
struct Start {
    range: Range<u32>,
    resumed: Option<(Accumulation, u32)>,
}

/// One scene on one open backend, and where its samples stand.
pub struct Session {
    scene: FlatScene,
    engine: Engine,
    opts: SessionOptions,
    /// A note for the user (the CPU renders because no Vulkan adapter exists; the spot
    /// check fell back to safer record placements).
    note: Option<String>,
    range: Range<u32>,
    /// The next sample index.
    next: u32,
    /// The sample a resumed checkpoint ended at.
    resumed_at: Option<u32>,
    /// The sums last read back (not written to disk), with the sample they end at.
    kept: Option<(u32, Accumulation)>,
    /// Whether the checkpoint file holds this render's state (as a resume left it, or as
    /// written since).
    on_disk: bool,
    last_save: Instant,
}

impl Session {
    /// Opens the backend for `scene` and, with `resume`, loads the checkpoint's sums. An
    /// output, error map or checkpoint that cannot be written, a sample range past the
    /// scene's samples and a checkpoint that does not fit are refused before the backend
    /// opens (which may compile a shader).
    pub fn open(mut scene: FlatScene, opts: SessionOptions) -> Result<Session, SessionError> {
        scene.aovs |= Self::needs_aovs(&opts);
        let start = Self::prepare(&mut scene, &opts, false)?;
        let (engine, note) = if opts.cpu_fallback {
            Engine::open(&scene, opts.backend, &opts.tuning)?
        } else {
            (Engine::with(&scene, opts.backend, &opts.tuning)?, None)
        };
        let note = note.or_else(|| engine.note().map(str::to_string));
        let mut session = Self::start(scene, engine, opts, start)?;
        session.note = note;
        Ok(session)
    }

    /// A session on an engine already open for `scene` (tests and benchmarks that must
    /// render on one backend, with no fallback); `opts.backend`, `opts.cpu_fallback` and
    /// `opts.tuning` are not read.
    pub fn with_engine(
        mut scene: FlatScene,
        engine: Engine,
        opts: SessionOptions,
    ) -> Result<Session, SessionError> {
        let start = Self::prepare(&mut scene, &opts, true)?;
        let note = engine.note().map(str::to_string);
        let mut session = Self::start(scene, engine, opts, start)?;
        session.note = note;
        Ok(session)
    }

    /// What can be checked before a backend opens: the files to write, the sample range,
    /// and the checkpoint to resume (read, checked, and holding samples from the range's
    /// start). A resumed checkpoint's AOV sums go on with it: they make `scene` sum the
    /// AOVs, unless its engine is already open.
    fn prepare(
        scene: &mut FlatScene,
        opts: &SessionOptions,
        engine_open: bool,
    ) -> Result<Start, SessionError> {
        Self::check_writable(opts)?;
        if Self::needs_aovs(opts) && !scene.aovs {
            return Err(SessionError::Invalid(
                "the output asks for AOVs or denoising, which the scene was not opened to \
                 accumulate (FlatScene::aovs)"
                    .into(),
            ));
        }
        if opts.output.as_ref().is_some_and(|o| o.denoise) {
            // fail now rather than after the render
            Denoiser::shared()?;
        }
        let range = opts.passes.range(scene)?;
        let Some(path) = &opts.resume else {
            return Ok(Start {
                range,
                resumed: None,
            });
        };
        let ckpt = Checkpoint::read(path)?;
        ckpt.check(scene, range.end, path)?;
        if !engine_open {
            scene.aovs |= ckpt.accumulation.aovs;
        }
        if ckpt.accumulation.aovs != scene.aovs {
            return Err(SessionError::Invalid(if scene.aovs {
                format!(
                    "{}: holds no AOV sums, which this render needs (--aov, --denoise); \
                     render again with them from the start",
                    path.display()
                )
            } else {
                format!(
                    "{}: holds AOV sums, which the engine was opened without",
                    path.display()
                )
            }));
        }
        match ckpt.contiguous().filter(|r| r.start == range.start) {
            Some(held) => Ok(Start {
                range,
                resumed: Some((ckpt.accumulation, held.end)),
            }),
            None => Err(SessionError::Invalid(format!(
                "{}: holds samples {:?}, which do not start this render's samples {}..{}",
                path.display(),
                ckpt.samples,
                range.start,
                range.end
            ))),
        }
    }

    fn start(
        scene: FlatScene,
        mut engine: Engine,
        opts: SessionOptions,
        start: Start,
    ) -> Result<Session, SessionError> {
        engine.set_submission_target(opts.submission_target);
        let mut next = start.range.start;
        let mut resumed_at = None;
        if let Some((acc, end)) = &start.resumed {
            engine.set_accumulation(acc)?;
            next = *end;
            resumed_at = Some(*end);
        }
        // the checkpoint file holds this render's state when it is the one resumed
        let on_disk = start.resumed.is_some()
            && opts
                .saving
                .as_ref()
                .is_some_and(|s| Some(&s.path) == opts.resume.as_ref());
        Ok(Session {
            scene,
            engine,
            opts,
            note: None,
            range: start.range,
            next,
            resumed_at,
            kept: None,
            on_disk,
            last_save: Instant::now(),
        })
    }

    /// Whether the output needs the AOVs' sums: an AOV summed per sample, or denoising.
    fn needs_aovs(opts: &SessionOptions) -> bool {
        opts.output
            .as_ref()
            .is_some_and(|o| o.denoise || o.aovs.iter().any(|a| a.summed()))
    }

    /// Refuses an output, error map or checkpoint that cannot be written, and AOVs asked
    /// of an image format that cannot hold them.
    fn check_writable(opts: &SessionOptions) -> Result<(), SessionError> {
        if let Some(out) = &opts.output {
            check_writable(&out.image)?;
            check_output(&out.image, &out.aovs)?;
            if let Some(map) = &out.error_map {
                check_writable(map)?;
            }
        }
        if let Some(s) = &opts.saving {
            probe_writable(&s.path).map_err(|cause| SessionError::WriteCheckpoint {
                path: s.path.clone(),
                cause,
            })?;
        }
        Ok(())
    }

    pub fn scene(&self) -> &FlatScene {
        &self.scene
    }

    /// The backend, for what only it can say (a GPU renderer's plan and submissions).
    pub fn engine(&mut self) -> &mut Engine {
        &mut self.engine
    }

    /// The device that renders, for the user.
    pub fn device(&self) -> String {
        self.engine.name()
    }

    /// A note for the user about the backend (the CPU renders because no Vulkan adapter
    /// exists; the spot check fell back to safer record placements).
    pub fn note(&self) -> Option<&str> {
        self.note.as_deref()
    }

    /// The sample a resumed checkpoint ended at.
    pub fn resumed_at(&self) -> Option<u32> {
        self.resumed_at
    }

    /// The sample indices the session holds when it ends.
    pub fn range(&self) -> Range<u32> {
        self.range.clone()
    }

    /// Renders from the next sample to the end of the range (or `rule.until`), calling
    /// `on_progress` after each batch, and ends as the rule says; then reads the sums back
    /// once, and writes the image, the error map and the checkpoint the options ask for.
    /// Interrupted, it writes the image and the checkpoint and returns
    /// [`SessionError::Interrupted`]; with the device lost, it writes the samples last read
    /// back and returns [`SessionError::DeviceLost`].
    pub fn run(
        &mut self,
        rule: &StopRule,
        mut on_progress: impl FnMut(&Progress),
    ) -> Result<Finished, SessionError> {
        let end = rule.until.map_or(self.range.end, |u| u.min(self.range.end));
        let result =
            self.passes(rule, end, &mut on_progress)
                .and_then(|(progress, stopped, estimate)| {
                    let accumulation = self.engine.accumulation()?;
                    Ok(Finished {
                        progress,
                        stopped,
                        estimate,
                        accumulation,
                    })
                });
        match result {
            Ok(done) => {
                self.finish(&done.accumulation)?;
                Ok(done)
            }
            Err(SessionError::Gpu(e @ (GpuError::Lost(_) | GpuError::Failed(_)))) => {
                Err(self.recover(e))
            }
            Err(SessionError::Interrupted { .. }) => {
                let acc = self.engine.accumulation()?;
                // the checkpoint first: writing the image may fail (a denoiser that runs
                // out of memory), and the work must not be lost with it
                let checkpoint = self.save(acc.clone(), self.next, true)?;
                self.write_image(&acc)?;
                Err(SessionError::Interrupted {
                    at: self.next,
                    image: self.opts.output.as_ref().map(|o| o.image.clone()),
                    checkpoint,
                })
            }
            Err(e) => Err(e),
        }
    }

    /// The end of a run: the image, the error map, and the checkpoint when kept at the end.
    fn finish(&mut self, acc: &Accumulation) -> Result<(), SessionError> {
        self.write_image(acc)?;
        if let Some(map) = self.opts.output.as_ref().and_then(|o| o.error_map.as_ref()) {
            let errors: Vec<f32> = (0..acc.pixel_count())
                .map(|i| acc.pixel_rel_mse(i).sqrt() as f32)
                .collect();
            write_error_map(map, acc.width, acc.height, &errors)?;
        }
        if self.opts.saving.as_ref().is_some_and(|s| s.at_end) {
            self.save(acc.clone(), self.next, true)?;
        }
        Ok(())
    }

    /// The device's sums are gone: writes the last ones read back (kept in memory, or in
    /// the checkpoint on disk) as image and checkpoint.
    fn recover(&mut self, error: GpuError) -> SessionError {
        let every = self
            .opts
            .saving
            .as_ref()
            .map_or(Duration::ZERO, |s| s.every);
        let checkpoint = self
            .opts
            .saving
            .as_ref()
            .map_or_else(PathBuf::new, |s| s.path.clone());
        let saved = match self.kept.take() {
            // the checkpoint first, as on an interrupt
            Some((held, acc)) => self
                .save(acc.clone(), held, true)
                .and_then(|_| self.write_image(&acc))
                .map(|_| Some(self.range.start..held)),
            None if self.on_disk => Checkpoint::read(&checkpoint)
                .map_err(SessionError::from)
                .and_then(|ckpt| {
                    self.write_image(&ckpt.accumulation)?;
                    let end = ckpt.samples.last().map_or(self.range.start, |r| r.end);
                    Ok(Some(self.range.start..end))
                }),
            None => Ok(None),
        };
        let saved = match saved {
            Ok(r) => r,
            Err(e) => return e,
        };
        let image = saved
            .as_ref()
            .and(self.opts.output.as_ref().map(|o| o.image.clone()));
        SessionError::DeviceLost(Box::new(LostDevice {
            error,
            at: self.next,
            saved,
            image,
            checkpoint,
            every,
        }))
    }

    fn write_image(&self, acc: &Accumulation) -> Result<(), SessionError> {
        if let Some(out) = &self.opts.output {
            let denoiser = if out.denoise {
                Some(Denoiser::shared()?)
            } else {
                None
            };
            write_output(&out.image, acc, &out.aovs, denoiser)?;
        }
        Ok(())
    }

    /// Writes the sums of samples `range.start..end` to the checkpoint file (when `disk`
    /// or the options keep one on disk), else keeps them in memory; returns the file.
    fn save(&mut self, acc: Accumulation, end: u32, disk: bool) -> Result<PathBuf, SessionError> {
        let Some(saving) = &self.opts.saving else {
            return Ok(PathBuf::new());
        };
        if !(disk || saving.periodic) {
            self.kept = Some((end, acc));
            return Ok(saving.path.clone());
        }
        let path = saving.path.clone();
        Checkpoint::new(&self.scene, self.range.start..end, acc)
            .write(&path)
            .map_err(|cause| SessionError::WriteCheckpoint {
                path: path.clone(),
                cause,
            })?;
        self.on_disk = true;
        Ok(path)
    }

    /// The passes from the next sample to `end`, in batches of the backend's size. With a
    /// time limit, a batch starts only if the mean pass time so far, and the last batch's,
    /// say it ends within the limit (the first always runs). With a target error, the
    /// estimate is read back after [`MIN_PASSES_FOR_ERROR`] passes and then whenever the
    /// passes since the last look took as long as the look itself or the pass count
    /// reaches a power of two, so reading back costs at most about half the render.
    fn passes(
        &mut self,
        rule: &StopRule,
        end: u32,
        on_progress: &mut dyn FnMut(&Progress),
    ) -> Result<(Progress, Stopped, Option<f64>), SessionError> {
        let start = Instant::now();
        let first = self.next;
        let pixels = self.scene.pixels();
        // sample 0 rendered before this began (the spot check's, kept) is not in its time
        let untimed = if first == 0 && self.engine.holds_first_sample() {
            pixels
        } else {
            0
        };
        let mut progress = Progress {
            passes_done: first,
            passes_total: end,
            elapsed: Duration::ZERO,
            samples: 0,
            untimed,
        };
        let mut estimate = None;
        let mut look_cost = Duration::ZERO;
        let mut last_look = Duration::ZERO;
        // seconds per pass of the last batch
        let mut last_pass = 0.0;
        while self.next < end {
            let pass = self.next;
            let mut batch = self.engine.samples_per_call().clamp(1, end - pass);
            if let (Some(limit), true) = (rule.time_limit, pass > first) {
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
            let batch_start = Instant::now();
            self.engine.render_samples(pass..pass + batch)?;
            last_pass = batch_start.elapsed().as_secs_f64() / batch as f64;
            self.next = pass + batch;
            progress.passes_done = self.next;
            progress.samples = pixels * (self.next - first) as u64;
            progress.elapsed = start.elapsed();
            on_progress(&progress);
            self.after_batch(pass)?;
            if let Some(target) = rule.target_error {
                let n = self.next;
                let since = start.elapsed().saturating_sub(last_look);
                // a power of two reached in this batch
                let doubled = pass.checked_ilog2() != n.checked_ilog2();
                if n >= MIN_PASSES_FOR_ERROR && (doubled || since >= look_cost) {
                    let t0 = Instant::now();
                    let e = self.engine.accumulation()?.estimated_rel_error();
                    look_cost = t0.elapsed();
                    last_look = start.elapsed();
                    estimate = Some(e);
                    if e <= target {
                        return Ok((progress, Stopped::TargetError, estimate));
                    }
                }
            }
            if rule
                .interrupt
                .as_ref()
                .is_some_and(|i| i.load(Ordering::SeqCst))
            {
                return Err(SessionError::Interrupted {
                    at: self.next,
                    image: None,
                    checkpoint: PathBuf::new(),
                });
            }
        }
        if rule.target_error.is_some() {
            estimate = Some(self.engine.accumulation()?.estimated_rel_error());
        }
        Ok((progress, Stopped::AllPasses, estimate))
    }

    /// After a batch that started at sample `before`: a preview when one is due, and the
    /// sums read back when a checkpoint is due.
    fn after_batch(&mut self, before: u32) -> Result<(), SessionError> {
        let n = self.next;
        let preview = self.opts.output.as_ref().and_then(|o| o.preview_every);
        if let Some(every) = preview {
            if n / every > before / every && n < self.range.end {
                let acc = self.engine.accumulation()?;
                self.write_image(&acc)?;
            }
        }
        let due = self
            .opts
            .saving
            .as_ref()
            .is_some_and(|s| self.last_save.elapsed() >= s.every);
        if due {
            let acc = self.engine.accumulation()?;
            self.save(acc, n, false)?;
            self.last_save = Instant::now();
        }
        Ok(())
    }
}

/// Renders a whole scene on `choice` under the default tuning, with no reporting: the
/// final sums.
pub fn render_scene(
    scene: &FlatScene,
    choice: BackendChoice,
) -> Result<Accumulation, SessionError> {
    let opts = SessionOptions {
        backend: choice,
        ..Default::default()
    };
    let mut session = Session::open(scene.clone(), opts)?;
    Ok(session.run(&StopRule::default(), |_| {})?.accumulation)
}
