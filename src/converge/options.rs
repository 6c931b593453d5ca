//! What a study is asked for ([`Options`]) and what it reports as it goes ([`Event`]).

use std::path::{Path, PathBuf};

use super::config::Config;
use super::results::Measurement;
use crate::engine::BackendChoice;
use crate::scene::load::Overrides;

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
    /// Also measure each point denoised by Open Image Denoise (the renders then sum the
    /// albedo and normal that guide it): a curve `LABEL +oidn` per configuration, its
    /// seconds the render's plus the denoiser's.
    pub denoise: bool,
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
    /// A note from opening a render's backend (a spot check that fell back to safer
    /// record placements), for the user.
    Note(&'a str),
    /// Work units (passes) done of the total, for a bar.
    Passes {
        done: u64,
        total: u64,
    },
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
