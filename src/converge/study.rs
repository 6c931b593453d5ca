//! The study itself: every configuration at every point of the sample ladder in every run,
//! each render read back at its points, each measurement written as soon as it is taken.

use std::io::Write as _;
use std::path::PathBuf;
use std::time::Duration;

use super::config::Config;
use super::error::{file_err, ConvergeError};
use super::metrics::{efficiency, rel_mse, rmse};
use super::options::{ladder, Event, Options};
use super::reference::{load, reference, session};
use super::report::write_report;
use super::results::{csv_row, Measurement, Study, CSV_HEADER, DENOISED};
use crate::aov::denoise;
use crate::denoise::Denoiser;
use crate::engine::BackendChoice;
use crate::scene::flat::FlatScene;
use crate::scene::load::Overrides;
use crate::session::{Finished, StopRule};

/// The seed of run `run` of configuration `config`: distinct for every pair, and never the
/// reference's.
fn run_seed(config: usize, run: u32) -> u32 {
    0x9e37_79b9u32
        .wrapping_mul(config as u32 + 1)
        .wrapping_add(run.wrapping_mul(0x85eb_ca6b))
        | 1
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
        denoised: opts.denoise,
    };
    // fail now rather than after the first render
    let denoiser = opts.denoise.then(Denoiser::shared).transpose()?;
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
                let mut scene = load(
                    &opts.scene,
                    &Overrides {
                        spp: Some(last),
                        ..overrides.clone()
                    },
                )?;
                scene.aovs = opts.denoise;
                let render = Render {
                    config,
                    run,
                    points: &points,
                    denoiser,
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
    /// Also measure each point denoised.
    denoiser: Option<&'static Denoiser>,
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
        if let Some(note) = session.note() {
            event(Event::Note(note));
        }
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
            let mut taken = vec![m];
            if let Some(d) = render.denoiser {
                taken.push(denoised(d, &taken[0], busy, &finished, reference)?);
            }
            for m in taken {
                writeln!(self.csv, "{}", csv_row(&m)).map_err(|e| file_err(&self.path, e))?;
                self.csv.flush().map_err(|e| file_err(&self.path, e))?;
                event(Event::Measured(&m));
                study.measurements.push(m);
            }
        }
        Ok(())
    }
}

/// `plain`'s render denoised: its seconds the render's and the denoiser's.
fn denoised(
    d: &Denoiser,
    plain: &Measurement,
    busy: Duration,
    finished: &Finished,
    reference: &[f32],
) -> Result<Measurement, ConvergeError> {
    let acc = &finished.accumulation;
    let start = std::time::Instant::now();
    let rgb = denoise(d, acc, &acc.to_rgb())?;
    let seconds = (busy + start.elapsed()).as_secs_f64();
    let rel = rel_mse(&rgb, reference);
    Ok(Measurement {
        config: plain.config.clone() + DENOISED,
        seconds,
        msamples_per_s: f64::from(plain.spp) * acc.pixel_count() as f64 / seconds.max(1e-9) / 1e6,
        rmse: rmse(&rgb, reference),
        rel_mse: rel,
        // the variance estimate says nothing of a denoised image
        est_rel_mse: f64::NAN,
        efficiency: efficiency(rel, seconds),
        ..plain.clone()
    })
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
