//! A study's configurations: sampler, light-sampling strategy and path length, as
//! `--configs` names them.

use std::fmt::Write as _;

use crate::scene::format::{LightSampling, SamplerKind};

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
    pub(super) fn prefix_is_a_render(&self) -> bool {
        !self.sampler.depends_on_spp()
    }
}
