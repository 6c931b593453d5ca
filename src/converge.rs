//! Convergence measurements: how error falls with samples and seconds, per sampler and
//! light-sampling strategy (and path length), against a reference image. `wgtrace
//! converge` drives [`run`]; the metrics and fits are plain functions the tests check on
//! synthetic data.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

use crate::accumulation::REL_MSE_EPSILON;
use crate::engine::BackendChoice;
use crate::gpu::error::GpuError;
use crate::scene::error::SceneError;
use crate::scene::flat::FlatScene;
use crate::scene::format::{LightSampling, SamplerKind};
use crate::scene::load::Overrides;
use crate::session::{load_scene, Finished, Session, SessionError, SessionOptions, StopRule};

/// Root mean squared error over every channel of every pixel (linear RGB, same layout).
pub fn rmse(x: &[f32], reference: &[f32]) -> f64 {
    assert_eq!(x.len(), reference.len());
    let sum: f64 = x
        .iter()
        .zip(reference)
        .map(|(&a, &r)| (f64::from(a) - f64::from(r)).powi(2))
        .sum();
    (sum / x.len().max(1) as f64).sqrt()
}

/// Relative MSE, mean((x - r)^2 / (r^2 + 0.01)) over every channel of every pixel.
pub fn rel_mse(x: &[f32], reference: &[f32]) -> f64 {
    assert_eq!(x.len(), reference.len());
    let sum: f64 = x
        .iter()
        .zip(reference)
        .map(|(&a, &r)| {
            let (a, r) = (f64::from(a), f64::from(r));
            (a - r).powi(2) / (r * r + REL_MSE_EPSILON)
        })
        .sum();
    sum / x.len().max(1) as f64
}

/// Efficiency of a render: 1 / (relative MSE x seconds). Doubling the samples of an
/// unbiased Monte Carlo estimator halves the MSE and doubles the time, so this stays
/// constant along a convergence curve of slope -1 in MSE; higher is better.
pub fn efficiency(rel_mse: f64, seconds: f64) -> f64 {
    1.0 / (rel_mse * seconds).max(f64::MIN_POSITIVE)
}

/// Least-squares line through (log x, log y): (slope, intercept). None for fewer than two
/// points with positive coordinates or all x equal.
pub fn fit_loglog(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let n = logs.len() as f64;
    if logs.len() < 2 {
        return None;
    }
    let (mx, my) = (
        logs.iter().map(|p| p.0).sum::<f64>() / n,
        logs.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxx: f64 = logs.iter().map(|p| (p.0 - mx).powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let sxy: f64 = logs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let slope = sxy / sxx;
    Some((slope, my - slope * mx))
}

/// Where a curve of (x, error) points, x increasing, first gets down to `target`:
/// interpolated linearly in log-log between the two points around the crossing; the first
/// x when it starts below. None when it never does.
pub fn first_crossing(points: &[(f64, f64)], target: f64) -> Option<f64> {
    let first = points.first()?;
    if first.1 <= target {
        return Some(first.0);
    }
    points.windows(2).find_map(|w| {
        let ((x0, e0), (x1, e1)) = (w[0], w[1]);
        (e1 <= target).then(|| {
            let t = (target.ln() - e0.ln()) / (e1.ln() - e0.ln());
            (x0.ln() + t * (x1.ln() - x0.ln())).exp()
        })
    })
}

/// One configuration of a convergence study: pixel sampler, light-sampling strategy, and
/// optionally a path length other than the scene's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Config {
    pub sampler: SamplerKind,
    pub strategy: LightSampling,
    pub max_depth: Option<u32>,
}

impl Config {
    /// `sampler:strategy` or `sampler:strategy:depth`, e.g. `sobol:mis` or `random:bsdf:4`.
    pub fn parse(s: &str) -> Result<Config, String> {
        use clap::ValueEnum;
        let parts: Vec<&str> = s.split(':').collect();
        if !(2..=3).contains(&parts.len()) {
            return Err(format!(
                "\"{s}\": a configuration is sampler:strategy[:max_depth], e.g. sobol:mis or random:bsdf:4"
            ));
        }
        let sampler = SamplerKind::from_str(parts[0], true).map_err(|_| {
            format!(
                "\"{s}\": unknown sampler \"{}\" (random, jittered, hammersley, sobol)",
                parts[0]
            )
        })?;
        let strategy = LightSampling::from_str(parts[1], true).map_err(|_| {
            format!(
                "\"{s}\": unknown light sampling \"{}\" (bsdf, mixture, mis)",
                parts[1]
            )
        })?;
        let max_depth = match parts.get(2) {
            None => None,
            Some(d) => match d.parse::<u32>() {
                Ok(d) if d >= 1 => Some(d),
                _ => return Err(format!("\"{s}\": max_depth must be a whole number >= 1")),
            },
        };
        Ok(Config {
            sampler,
            strategy,
            max_depth,
        })
    }

    /// Every sampler with every strategy, at the scene's path length.
    pub fn defaults() -> Vec<Config> {
        let samplers = [
            SamplerKind::Random,
            SamplerKind::Jittered,
            SamplerKind::Hammersley,
            SamplerKind::Sobol,
        ];
        let strategies = [
            LightSampling::Bsdf,
            LightSampling::Mixture,
            LightSampling::Mis,
        ];
        strategies
            .iter()
            .flat_map(|&strategy| {
                samplers.iter().map(move |&sampler| Config {
                    sampler,
                    strategy,
                    max_depth: None,
                })
            })
            .collect()
    }

    /// The name used in tables, plots and `--configs`.
    pub fn label(&self) -> String {
        let mut s = format!("{}:{}", self.sampler.name(), self.strategy.name());
        if let Some(d) = self.max_depth {
            let _ = write!(s, ":{d}");
        }
        s
    }

    /// Whether a render's first k passes are the image a k-pass render would make, so one
    /// render can be measured at every point of the ladder; a sampler whose points depend
    /// on the total count renders each point separately.
    fn prefix_is_a_render(&self) -> bool {
        !self.sampler.depends_on_spp()
    }
}

/// One measurement: a configuration at a sample count, in one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Measurement {
    pub config: String,
    pub run: u32,
    pub spp: u32,
    /// Seconds of rendering (passes only: no readback, no pipeline creation).
    pub seconds: f64,
    pub msamples_per_s: f64,
    pub rmse: f64,
    pub rel_mse: f64,
    /// The renderer's own estimate of rel_mse from per-pixel variance (what
    /// `--target-error` uses), for comparison with the true one.
    pub est_rel_mse: f64,
    pub efficiency: f64,
}

/// What `run` needs.
#[derive(Debug, Clone)]
pub struct Options {
    pub scene: PathBuf,
    /// Image size and other settings applied to every render (the reference's too).
    pub overrides: Overrides,
    /// A reference EXR to use instead of rendering one.
    pub reference: Option<PathBuf>,
    /// Samples per pixel of the reference when it is rendered.
    pub reference_spp: u32,
    /// Backend of the reference render (the CPU reference is the faster one on lavapipe
    /// machines; any backend converges to the same image).
    pub reference_backend: BackendChoice,
    /// Largest sample count of the ladder 1, 2, 4, ...
    pub spp_max: u32,
    /// Independent runs (seeds) per point.
    pub runs: u32,
    pub configs: Vec<Config>,
    /// Backend of the measured renders.
    pub backend: BackendChoice,
    pub out: PathBuf,
}

/// Where a study stands, for a progress display.
#[derive(Debug, Clone)]
pub enum Event<'a> {
    Reference {
        spp: u32,
        done: u32,
    },
    ReferenceReady {
        path: &'a Path,
        cached: bool,
    },
    Measured(&'a Measurement),
    /// Work units (passes) done of the total, for a bar.
    Passes {
        done: u64,
        total: u64,
    },
}

#[derive(Debug, thiserror::Error)]
pub enum ConvergeError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error(transparent)]
    Session(#[from] SessionError),
    #[error(transparent)]
    Image(#[from] crate::image_io::ImageError),
    #[error("{}: {message}", path.display())]
    File { path: PathBuf, message: String },
    #[error("{0}")]
    Invalid(String),
}

fn file_err(path: &Path, e: impl std::fmt::Display) -> ConvergeError {
    ConvergeError::File {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// What the reference was rendered with, stored beside it as `reference.toml`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReferenceInfo {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub seed: u32,
    pub max_depth: u32,
    pub sampler: String,
    pub light_sampling: String,
    pub backend: String,
    pub seconds: f64,
    /// The reference's own estimated relative MSE (per-pixel variance): the floor under
    /// every measured error.
    #[serde(default)]
    pub est_rel_mse: f64,
}

/// The sample counts measured: 1, 2, 4, ... up to `spp_max` (and `spp_max` itself).
pub fn ladder(spp_max: u32) -> Vec<u32> {
    let mut v: Vec<u32> = (0..32)
        .map(|k| 1u32 << k)
        .take_while(|&s| s < spp_max)
        .collect();
    v.push(spp_max.max(1));
    v
}

/// The seed of run `run` of configuration `config`: distinct for every pair, and never the
/// reference's.
fn run_seed(config: usize, run: u32) -> u32 {
    0x9e37_79b9u32
        .wrapping_mul(config as u32 + 1)
        .wrapping_add(run.wrapping_mul(0x85eb_ca6b))
        | 1
}

const REFERENCE_SEED: u32 = 0x5eed_0000;

fn load(scene: &Path, overrides: &Overrides) -> Result<FlatScene, ConvergeError> {
    Ok(load_scene(scene, overrides)?)
}

/// A session rendering `scene` on `backend`, writing nothing.
fn session(scene: FlatScene, backend: BackendChoice) -> Result<Session, ConvergeError> {
    Ok(Session::open(
        scene,
        SessionOptions {
            backend,
            ..Default::default()
        },
    )?)
}

/// The reference image (linear RGB), rendered or read, and what it is.
pub fn reference(
    opts: &Options,
    max_depth: u32,
    mut event: impl FnMut(Event),
) -> Result<(Vec<f32>, ReferenceInfo, PathBuf), ConvergeError> {
    let probe = load(&opts.scene, &opts.overrides)?;
    if let Some(path) = &opts.reference {
        let rgb = given_reference(path, &probe)?;
        let info = ReferenceInfo {
            scene: opts.scene.display().to_string(),
            width: probe.width,
            height: probe.height,
            spp: 0,
            seed: 0,
            max_depth: 0,
            sampler: "given".into(),
            light_sampling: "given".into(),
            backend: "given".into(),
            seconds: 0.0,
            est_rel_mse: 0.0,
        };
        event(Event::ReferenceReady { path, cached: true });
        return Ok((rgb, info, path.clone()));
    }
    let exr = opts.out.join("reference.exr");
    let meta = opts.out.join("reference.toml");
    if let Some((rgb, info)) = cached_reference(opts, &probe, max_depth)? {
        event(Event::ReferenceReady {
            path: &exr,
            cached: true,
        });
        return Ok((rgb, info, exr));
    }
    let overrides = Overrides {
        spp: Some(opts.reference_spp),
        seed: Some(REFERENCE_SEED),
        max_depth: Some(max_depth),
        sampler: Some(SamplerKind::Sobol),
        light_sampling: Some(LightSampling::Mis),
        ..opts.overrides.clone()
    };
    let scene = load(&opts.scene, &overrides)?;
    let mut session = session(scene.clone(), opts.reference_backend)?;
    let start = Instant::now();
    let Finished {
        accumulation: acc, ..
    } = session.run(&StopRule::default(), |p| {
        event(Event::Reference {
            spp: scene.spp,
            done: p.passes_done,
        })
    })?;
    let seconds = start.elapsed().as_secs_f64();
    let rgb = acc.to_rgb();
    crate::image_io::write_image(&exr, scene.width, scene.height, &rgb)?;
    let info = ReferenceInfo {
        scene: opts.scene.display().to_string(),
        width: scene.width,
        height: scene.height,
        spp: scene.spp,
        seed: REFERENCE_SEED,
        max_depth,
        sampler: "sobol".into(),
        light_sampling: "mis".into(),
        backend: session.device(),
        seconds,
        est_rel_mse: acc.estimated_rel_mse(),
    };
    let text = toml::to_string(&info).map_err(|e| file_err(&meta, e))?;
    std::fs::write(&meta, text).map_err(|e| file_err(&meta, e))?;
    event(Event::ReferenceReady {
        path: &exr,
        cached: false,
    });
    Ok((rgb, info, exr))
}

/// A reference EXR the user gave, which must have the renders' size.
fn given_reference(path: &Path, probe: &FlatScene) -> Result<Vec<f32>, ConvergeError> {
    let img = crate::scene::textures::load_image(path, true).map_err(|e| file_err(path, e))?;
    if (img.width, img.height) != (probe.width, probe.height) {
        return Err(file_err(
            path,
            format!(
                "is {}x{}, the renders are {}x{} (set --width and --height to match)",
                img.width, img.height, probe.width, probe.height
            ),
        ));
    }
    Ok(img.texels.iter().flat_map(|t| [t[0], t[1], t[2]]).collect())
}

/// The reference an earlier study left in the output folder, when it was rendered for
/// this scene, size and path length with at least the samples asked for.
fn cached_reference(
    opts: &Options,
    probe: &FlatScene,
    max_depth: u32,
) -> Result<Option<(Vec<f32>, ReferenceInfo)>, ConvergeError> {
    let exr = opts.out.join("reference.exr");
    let meta = opts.out.join("reference.toml");
    let (Ok(text), true) = (std::fs::read_to_string(&meta), exr.exists()) else {
        return Ok(None);
    };
    let Ok(info) = toml::from_str::<ReferenceInfo>(&text) else {
        return Ok(None);
    };
    let wanted = info.scene == opts.scene.display().to_string()
        && (info.width, info.height) == (probe.width, probe.height)
        && info.max_depth == max_depth
        && info.spp >= opts.reference_spp;
    if !wanted {
        return Ok(None);
    }
    let img = crate::scene::textures::load_image(&exr, true).map_err(|e| file_err(&exr, e))?;
    let rgb = img.texels.iter().flat_map(|t| [t[0], t[1], t[2]]).collect();
    Ok(Some((rgb, info)))
}

const CSV_HEADER: &str =
    "config,run,spp,seconds,msamples_per_s,rmse,rel_mse,est_rel_mse,efficiency";

fn csv_row(m: &Measurement) -> String {
    format!(
        "{},{},{},{:.6},{:.6},{:.6e},{:.6e},{:.6e},{:.6e}",
        m.config,
        m.run,
        m.spp,
        m.seconds,
        m.msamples_per_s,
        m.rmse,
        m.rel_mse,
        m.est_rel_mse,
        m.efficiency
    )
}

/// Everything a study measured, for reports.
#[derive(Debug, Clone)]
pub struct Study {
    pub scene: String,
    pub device: String,
    pub width: u32,
    pub height: u32,
    pub max_depth: u32,
    pub reference: ReferenceInfo,
    pub configs: Vec<Config>,
    pub measurements: Vec<Measurement>,
}

/// Runs the study: the reference, then every configuration at every point of the ladder
/// in every run. Each measurement is appended to `out/results.csv` and flushed as soon as
/// it is taken, and the report and plots are rewritten after each configuration, so an
/// interrupted study keeps what it measured.
pub fn run(opts: &Options, mut event: impl FnMut(Event)) -> Result<Study, ConvergeError> {
    if opts.configs.is_empty() || opts.runs == 0 || opts.spp_max == 0 {
        return Err(ConvergeError::Invalid(
            "nothing to measure: give at least one configuration, run and sample".into(),
        ));
    }
    std::fs::create_dir_all(&opts.out).map_err(|e| file_err(&opts.out, e))?;
    let base = load(&opts.scene, &opts.overrides)?;
    let pixels = base.pixels();
    let max_depth = opts
        .configs
        .iter()
        .filter_map(|c| c.max_depth)
        .chain([base.max_depth])
        .max()
        .unwrap_or(base.max_depth);
    let (reference, info, _) = reference(opts, max_depth, &mut event)?;
    let csv_path = opts.out.join("results.csv");
    let mut csv = std::fs::File::create(&csv_path).map_err(|e| file_err(&csv_path, e))?;
    writeln!(csv, "{CSV_HEADER}").map_err(|e| file_err(&csv_path, e))?;

    let ladder = ladder(opts.spp_max);
    let passes_per_run = |c: &Config| -> u64 {
        if c.prefix_is_a_render() {
            u64::from(opts.spp_max)
        } else {
            ladder.iter().map(|&s| u64::from(s)).sum()
        }
    };
    let total: u64 = opts
        .configs
        .iter()
        .map(|c| passes_per_run(c) * u64::from(opts.runs))
        .sum();
    let mut log = Log {
        csv,
        path: csv_path,
        done: 0,
        total,
        pixels,
    };
    let mut study = Study {
        scene: opts.scene.display().to_string(),
        device: String::new(),
        width: base.width,
        height: base.height,
        max_depth: base.max_depth,
        reference: info,
        configs: opts.configs.clone(),
        measurements: Vec::new(),
    };
    for (ci, config) in opts.configs.iter().enumerate() {
        for run in 0..opts.runs {
            let overrides = Overrides {
                seed: Some(run_seed(ci, run)),
                sampler: Some(config.sampler),
                light_sampling: Some(config.strategy),
                max_depth: config.max_depth.or(opts.overrides.max_depth),
                ..opts.overrides.clone()
            };
            // one render per run, measured at each ladder point; or one render per point
            let renders: Vec<Vec<u32>> = if config.prefix_is_a_render() {
                vec![ladder.clone()]
            } else {
                ladder.iter().map(|&s| vec![s]).collect()
            };
            for points in renders {
                let last = *points.last().expect("a ladder has points");
                let scene = load(
                    &opts.scene,
                    &Overrides {
                        spp: Some(last),
                        ..overrides.clone()
                    },
                )?;
                let render = Render {
                    config,
                    run,
                    points: &points,
                };
                log.measure(
                    scene,
                    opts.backend,
                    render,
                    &reference,
                    &mut study,
                    &mut event,
                )?;
            }
        }
        write_report(&study, &opts.out)?;
    }
    Ok(study)
}

/// One render of a study: a run of a configuration, measured at each of its points.
struct Render<'a> {
    config: &'a Config,
    run: u32,
    points: &'a [u32],
}

/// Where a study's measurements go as they are taken, and how far it has come.
struct Log {
    csv: std::fs::File,
    path: PathBuf,
    /// Passes rendered so far, of the study's `total`.
    done: u64,
    total: u64,
    pixels: u64,
}

impl Log {
    /// Renders `scene` (spp = the last point) in one session, reading the sums back at
    /// each point; each measurement is appended to the CSV and flushed at once.
    fn measure(
        &mut self,
        scene: FlatScene,
        backend: BackendChoice,
        render: Render,
        reference: &[f32],
        study: &mut Study,
        event: &mut impl FnMut(Event),
    ) -> Result<(), ConvergeError> {
        let mut session = session(scene, backend)?;
        study.device = session.device();
        let mut busy = Duration::ZERO;
        for &spp in render.points {
            let from = self.done;
            let (pixels, total) = (self.pixels, self.total);
            let until = StopRule {
                until: Some(spp),
                ..Default::default()
            };
            let finished = session.run(&until, |p| {
                event(Event::Passes {
                    done: from + p.samples / pixels,
                    total,
                })
            })?;
            busy += finished.progress.elapsed;
            self.done = from + finished.progress.samples / pixels;
            let m = measurement(render.config, render.run, spp, busy, &finished, reference);
            writeln!(self.csv, "{}", csv_row(&m)).map_err(|e| file_err(&self.path, e))?;
            self.csv.flush().map_err(|e| file_err(&self.path, e))?;
            event(Event::Measured(&m));
            study.measurements.push(m);
        }
        Ok(())
    }
}

/// The measurement of a render of `config` holding `spp` samples after `busy` seconds.
fn measurement(
    config: &Config,
    run: u32,
    spp: u32,
    busy: Duration,
    finished: &Finished,
    reference: &[f32],
) -> Measurement {
    let acc = &finished.accumulation;
    let rgb = acc.to_rgb();
    let seconds = busy.as_secs_f64();
    let rel = rel_mse(&rgb, reference);
    Measurement {
        config: config.label(),
        run,
        spp,
        seconds,
        msamples_per_s: f64::from(spp) * acc.pixel_count() as f64 / seconds.max(1e-9) / 1e6,
        rmse: rmse(&rgb, reference),
        rel_mse: rel,
        est_rel_mse: acc.estimated_rel_mse(),
        efficiency: efficiency(rel, seconds),
    }
}

/// Mean over runs of one configuration's measurements at each sample count, in spp order.
pub fn curve(study: &Study, config: &str) -> Vec<Measurement> {
    let mut spps: Vec<u32> = study
        .measurements
        .iter()
        .filter(|m| m.config == config)
        .map(|m| m.spp)
        .collect();
    spps.sort_unstable();
    spps.dedup();
    spps.iter()
        .map(|&spp| {
            let ms: Vec<&Measurement> = study
                .measurements
                .iter()
                .filter(|m| m.config == config && m.spp == spp)
                .collect();
            let n = ms.len() as f64;
            let mean = |f: fn(&Measurement) -> f64| ms.iter().map(|m| f(m)).sum::<f64>() / n;
            let (seconds, rel) = (mean(|m| m.seconds), mean(|m| m.rel_mse));
            Measurement {
                config: config.to_string(),
                run: ms.len() as u32,
                spp,
                seconds,
                msamples_per_s: mean(|m| m.msamples_per_s),
                // RMSE over runs: the root of the mean squared error
                rmse: ms.iter().map(|m| m.rmse * m.rmse).sum::<f64>().sqrt() / n.sqrt(),
                rel_mse: rel,
                est_rel_mse: mean(|m| m.est_rel_mse),
                efficiency: efficiency(rel, seconds),
            }
        })
        .collect()
}

/// The relative-MSE levels the report gives time and samples for.
pub const TARGETS: [f64; 3] = [1e-2, 1e-3, 1e-4];

/// How far past the measured range `to_reach` extrapolates (in samples).
pub const MAX_EXTRAPOLATION: f64 = 100.0;

/// Samples and seconds a curve needs to reach `target` relative MSE: measured (interpolated)
/// when it gets there (`Reach::Measured`); else extrapolated along the slope fitted to its
/// points, up to `MAX_EXTRAPOLATION` times its last sample count (`Reach::Extrapolated`);
/// `Reach::Never` when it has levelled off (a slope in relMSE above -0.3 over its last three
/// points or all of them:
/// bias, such as a path too short for the reference) and `Reach::Beyond` past the range.
pub fn to_reach(points: &[Measurement], target: f64) -> Reach {
    let by_spp: Vec<(f64, f64)> = points
        .iter()
        .map(|m| (f64::from(m.spp), m.rel_mse))
        .collect();
    let by_time: Vec<(f64, f64)> = points.iter().map(|m| (m.seconds, m.rel_mse)).collect();
    if let (Some(spp), Some(t)) = (
        first_crossing(&by_spp, target),
        first_crossing(&by_time, target),
    ) {
        return Reach::Measured { spp, seconds: t };
    }
    let (Some((slope, _)), Some(last)) = (fit_loglog(&by_spp), points.last()) else {
        return Reach::Never;
    };
    // the slope over the last three points: one segment alone is too noisy to call
    let tail = fit_loglog(&by_spp[by_spp.len().saturating_sub(3)..]).map_or(slope, |f| f.0);
    let levelled = |v: f64| v.is_nan() || v >= -0.3;
    if levelled(tail) || levelled(slope) {
        return Reach::Never;
    }
    let factor = (target / last.rel_mse).powf(1.0 / slope);
    if factor > MAX_EXTRAPOLATION {
        return Reach::Beyond {
            spp: f64::from(last.spp) * MAX_EXTRAPOLATION,
        };
    }
    Reach::Extrapolated {
        spp: f64::from(last.spp) * factor,
        seconds: last.seconds * factor,
    }
}

/// See [`to_reach`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Reach {
    Measured { spp: f64, seconds: f64 },
    Extrapolated { spp: f64, seconds: f64 },
    Beyond { spp: f64 },
    Never,
}

/// An axis label: 3 significant digits, no float noise.
fn tick(v: f64) -> String {
    if v == 0.0 || (1e-2..1e4).contains(&v.abs()) {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.1e}")
    }
}

fn fmt_amount(x: f64) -> String {
    if x >= 100.0 {
        format!("{x:.0}")
    } else if x >= 10.0 {
        format!("{x:.1}")
    } else {
        format!("{x:.2}")
    }
}

fn scene_name(path: &str) -> String {
    Path::new(path)
        .file_name()
        .map_or(path.to_string(), |n| n.to_string_lossy().into_owned())
}

/// Writes `report.md` and the two plots for a study.
pub fn write_report(study: &Study, out: &Path) -> Result<(), ConvergeError> {
    let mut md = String::new();
    let r = &study.reference;
    let _ = writeln!(md, "## {}\n", scene_name(&study.scene));
    let _ = writeln!(
        md,
        "{}x{} pixels, max_depth {} (scene), device: {}. Reference: {} spp ({} / {}, max_depth {}, seed {:#x}, {:.0} s on {}; its own estimated relMSE {:.1e}).\n",
        study.width,
        study.height,
        study.max_depth,
        study.device,
        r.spp,
        r.sampler,
        r.light_sampling,
        r.max_depth,
        r.seed,
        r.seconds,
        r.backend,
        r.est_rel_mse
    );
    let _ = writeln!(
        md,
        "Slope: least-squares fit of log RMSE against log spp over the ladder (-0.5 is plain Monte Carlo). \
         relMSE and seconds at the largest spp are means over runs; efficiency is 1 / (relMSE x seconds). \
         est/true: the renderer's own error estimate (per-pixel variance, what `--target-error` uses) over the true relMSE. \
         Time and spp to reach each relMSE are interpolated between measured points; `~` marks an extrapolation along the fitted slope \
         (at most {MAX_EXTRAPOLATION}x the largest spp, `>` beyond), `never` a curve that has levelled off over its last three points (bias).\n"
    );
    md += &results_table(study);
    let _ = writeln!(
        md,
        "\n![RMSE against samples per pixel](rmse_vs_spp.svg)\n![RMSE against seconds](rmse_vs_seconds.svg)\n"
    );
    md += &estimate_table(study);
    let path = out.join("report.md");
    std::fs::write(&path, md).map_err(|e| file_err(&path, e))?;
    plot(study, out, false)?;
    plot(study, out, true)?;
    Ok(())
}

/// The report's table of results: a row per configuration at its largest spp, with the
/// samples and seconds it needs for each relMSE of [`TARGETS`].
fn results_table(study: &Study) -> String {
    let mut md = String::new();
    let mut header =
        "| configuration | slope | relMSE | seconds | Msamples/s | efficiency | est/true |"
            .to_string();
    let mut rule = "|---|---|---|---|---|---|---|".to_string();
    for t in TARGETS {
        let _ = write!(header, " to {t:.0e}: spp, s |");
        rule += "---|";
    }
    let _ = writeln!(md, "{header}\n{rule}");
    for c in &study.configs {
        let label = c.label();
        let pts = curve(study, &label);
        let Some(last) = pts.last() else { continue };
        let slope = fit_loglog(
            &pts.iter()
                .map(|m| (f64::from(m.spp), m.rmse))
                .collect::<Vec<_>>(),
        )
        .map_or("-".to_string(), |(s, _)| format!("{s:.2}"));
        let mut row = format!(
            "| {label} | {slope} | {:.2e} | {:.2} | {:.3} | {:.3e} | {:.2} |",
            last.rel_mse,
            last.seconds,
            last.msamples_per_s,
            last.efficiency,
            last.est_rel_mse / last.rel_mse
        );
        for t in TARGETS {
            let cell = match to_reach(&pts, t) {
                Reach::Measured { spp, seconds } => {
                    format!(" {}, {} |", fmt_amount(spp), fmt_amount(seconds))
                }
                Reach::Extrapolated { spp, seconds } => {
                    format!(" ~{}, ~{} |", fmt_amount(spp), fmt_amount(seconds))
                }
                Reach::Beyond { spp } => format!(" > {} spp |", fmt_amount(spp)),
                Reach::Never => " never |".to_string(),
            };
            row += &cell;
        }
        let _ = writeln!(md, "{row}");
    }
    md
}

/// The report's table of the error estimate `--target-error` stops on, against the truth,
/// along the ladder.
fn estimate_table(study: &Study) -> String {
    let mut md = String::new();
    let spps: Vec<u32> = ladder(study.measurements.iter().map(|m| m.spp).max().unwrap_or(1))
        .into_iter()
        .filter(|s| s.is_power_of_two() && *s >= 4 && s.trailing_zeros() % 2 == 0)
        .collect();
    let _ = writeln!(
        md,
        "### The error estimate against the truth\n\n\
         Estimated relative error (the square root of the per-pixel variance estimate, what \
         `--target-error` stops on) over the true relative error (the square root of relMSE \
         against the reference), means over runs. 1 is exact; above 1 the estimate is \
         conservative.\n"
    );
    let mut header = "| configuration |".to_string();
    let mut rule = "|---|".to_string();
    for spp in &spps {
        let _ = write!(header, " {spp} spp |");
        rule += "---|";
    }
    let _ = writeln!(md, "{header}\n{rule}");
    for c in &study.configs {
        let label = c.label();
        let pts = curve(study, &label);
        let mut row = format!("| {label} |");
        for spp in &spps {
            match pts.iter().find(|m| m.spp == *spp) {
                Some(m) => {
                    let _ = write!(row, " {:.2} |", (m.est_rel_mse / m.rel_mse).sqrt());
                }
                None => row += " - |",
            }
        }
        let _ = writeln!(md, "{row}");
    }
    md
}

/// RMSE against spp (or seconds), log-log, a line per configuration and the ideal
/// N^-1/2 through the first configuration's first point.
fn plot(study: &Study, out: &Path, by_time: bool) -> Result<(), ConvergeError> {
    use plotters::prelude::*;
    let name = if by_time {
        "rmse_vs_seconds.svg"
    } else {
        "rmse_vs_spp.svg"
    };
    let path = out.join(name);
    let curves: Vec<(String, Vec<(f64, f64)>)> = study
        .configs
        .iter()
        .map(|c| {
            let pts = curve(study, &c.label());
            let xy = pts
                .iter()
                .map(|m| {
                    let x = if by_time { m.seconds } else { f64::from(m.spp) };
                    (x.max(1e-6), m.rmse.max(1e-12))
                })
                .collect();
            (c.label(), xy)
        })
        .filter(|(_, xy): &(String, Vec<(f64, f64)>)| !xy.is_empty())
        .collect();
    if curves.is_empty() {
        return Ok(());
    }
    let all = curves.iter().flat_map(|(_, xy)| xy.iter().copied());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for (x, y) in all {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let (x1, y0, y1) = (x1.max(x0 * 2.0), y0 / 1.5, y1 * 1.5);
    let draw = || -> Result<(), Box<dyn std::error::Error>> {
        let root = SVGBackend::new(&path, (900, 600)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!(
                    "{}: RMSE against {}",
                    scene_name(&study.scene),
                    if by_time {
                        "seconds"
                    } else {
                        "samples per pixel"
                    }
                ),
                ("sans-serif", 20),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
        chart
            .configure_mesh()
            .x_desc(if by_time {
                "seconds"
            } else {
                "samples per pixel"
            })
            .y_desc("RMSE")
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .draw()?;
        for (i, (label, xy)) in curves.iter().enumerate() {
            let color = Palette99::pick(i).stroke_width(2);
            chart
                .draw_series(LineSeries::new(xy.iter().copied(), color))?
                .label(label.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(
                        vec![(x, y), (x + 18, y)],
                        Palette99::pick(i).stroke_width(2),
                    )
                });
        }
        let (fx, fy) = curves[0].1[0];
        let ideal = [(fx, fy), (x1, fy * (x1 / fx).powf(-0.5))];
        chart
            .draw_series(LineSeries::new(ideal, BLACK.stroke_width(1)))?
            .label("ideal N^-1/2")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK));
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::LowerLeft)
            .draw()?;
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| file_err(&path, e))
}
