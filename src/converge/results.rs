//! What a study measured ([`Study`], [`Measurement`], the [`ReferenceInfo`] it measured
//! against), its CSV rows, the mean curve of a configuration and the samples and seconds
//! it needs to reach an error.

use serde::{Deserialize, Serialize};

use super::config::Config;
use super::metrics::{efficiency, first_crossing, fit_loglog};

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

pub(super) const CSV_HEADER: &str =
    "config,run,spp,seconds,msamples_per_s,rmse,rel_mse,est_rel_mse,efficiency";

pub(super) fn csv_row(m: &Measurement) -> String {
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
    /// Whether each point was also measured denoised ([`DENOISED`] curves).
    pub denoised: bool,
}

/// What a configuration's label gains for its denoised curve.
pub const DENOISED: &str = " +oidn";

impl Study {
    /// The curves' labels: every configuration's, then (when denoised) each one's
    /// denoised curve.
    pub fn labels(&self) -> Vec<String> {
        let plain = self.configs.iter().map(Config::label);
        let denoised = self
            .configs
            .iter()
            .filter(|_| self.denoised)
            .map(|c| c.label() + DENOISED);
        plain.chain(denoised).collect()
    }

    /// The scene's file name, for titles.
    pub fn scene_name(&self) -> String {
        std::path::Path::new(&self.scene)
            .file_name()
            .map_or(self.scene.clone(), |n| n.to_string_lossy().into_owned())
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
