//! Tuning: how a render runs, not what it computes. Every knob is at its fastest by
//! default; the benchmarks turn them off one at a time to measure what each gives
//! (`wgtrace render --tune no-uniform-records,...`; docs/performance.md). The scene layer
//! gets the two knobs that shape the flattened scene ([`Tuning::build`]); the GPU plan
//! reads the rest.

use crate::scene::flatten::{Acceleration, Build};

/// Scenes of at most this many bounded primitives, none of them transformed, are tested
/// as a plain list rather than through a BVH (and the GPU plan writes such a list into
/// the shader, `gpu::plan::BAKED_PRIMITIVES_MAX`): on lavapipe all SIMD lanes walk a list
/// together, where the BVH walk diverges. docs/performance.md (`--tune bvh`) measures what
/// the list gives on the suite.
pub const LIST_MAX_PRIMITIVES: usize = 64;

/// Most pixels of one band of rows of the GPU's image (one accumulation buffer, 8 MiB),
/// unless the tuning says fewer.
pub const MAX_BAND_PIXELS: u32 = 1 << 18;

/// The knobs, each on (fastest) unless turned off.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tuning {
    /// Which structure closest-hit searches walk (both backends).
    pub acceleration: Acceleration,
    /// Russian roulette from the fourth ray on (both backends; unbiased).
    pub russian_roulette: bool,
    /// A shader holding only the code of the scene's features (else the full shader).
    pub specialize: bool,
    /// Record arrays that fit in 64 KiB bound as uniform buffers.
    pub uniform_records: bool,
    /// A small scene's primitives, materials and lights written into its shader.
    pub baked_records: bool,
    /// One GPU invocation traces a group of samples.
    pub sample_groups: bool,
    /// Primitives and BVH nodes too large for a uniform buffer read from textures.
    pub texture_records: bool,
    /// The BVH walk's stack in registers where the tree is shallow enough
    /// (`gpu::plan::REGISTER_STACK`).
    pub register_stack: bool,
    /// Most pixels per band of rows (one accumulation buffer each): fewer, smaller
    /// buffers change no image (the tests hold renders in many bands to one in one).
    pub band_pixels: u32,
    /// A diagnostic, off unless asked for: the GPU counts with subgroup operations how
    /// many lanes of each subgroup take part in each turn of the bounce loop, each BVH
    /// node step and each primitive test, and sums those counts instead of light
    /// (`gpu::plan::LANE_STATS`; the render then prints the shares).
    pub lane_stats: bool,
    /// Before a GPU render accumulates, a few hundred pixels of its first sample are
    /// rendered on both backends and compared (`crate::spot_check`); on a mismatch the
    /// render falls back to safer record placements, and errors when none agrees.
    pub spot_check: bool,
    /// Fault injection for tests, off unless asked for: the GPU side's records in these
    /// placements (bits of [`PLACEMENT_NAMES`]) are perturbed, one texel of every record,
    /// as a driver that fetches them wrong would (`gpu::fault`); the CPU's are not.
    pub perturb: u8,
}

/// The record placements a `perturb=` knob may name, bit i for name i (the GPU plan's
/// `gpu::bindings::Placement`, `Placement::bit`).
pub const PLACEMENT_NAMES: [&str; 4] = ["storage", "uniform", "shader", "texture"];

/// Every placement's bit.
pub const ALL_PLACEMENTS: u8 = (1 << PLACEMENT_NAMES.len()) - 1;

impl Default for Tuning {
    fn default() -> Self {
        Tuning {
            acceleration: Acceleration::Auto {
                list_max: LIST_MAX_PRIMITIVES,
            },
            russian_roulette: true,
            specialize: true,
            uniform_records: true,
            baked_records: true,
            sample_groups: true,
            texture_records: true,
            register_stack: true,
            band_pixels: MAX_BAND_PIXELS,
            lane_stats: false,
            spot_check: true,
            perturb: 0,
        }
    }
}

/// Every knob a `--tune` list may name, with what it does.
pub const KNOBS: &[(&str, &str)] = &[
    (
        "no-bvh",
        "test every primitive on every ray instead of walking the BVH",
    ),
    (
        "bvh",
        "walk the BVH even in a scene small enough for the plain list",
    ),
    (
        "no-specialize",
        "the full shader instead of one holding only the scene's features",
    ),
    (
        "no-uniform-records",
        "every record array in a storage buffer, none in a uniform buffer",
    ),
    (
        "no-baked-records",
        "read a small scene's records from buffers, not as constants in its shader",
    ),
    (
        "no-sample-groups",
        "one sample per GPU invocation instead of a group of up to 16",
    ),
    (
        "no-texture-records",
        "primitives and BVH nodes in storage buffers, never in textures",
    ),
    (
        "no-register-stack",
        "the BVH walk's stack in workgroup memory, not in registers, whatever the tree's depth",
    ),
    (
        "no-russian-roulette",
        "trace every path to max_depth (or until it escapes or goes black)",
    ),
    (
        "lane-stats",
        "diagnostic (GPU, subgroup operations): print the share of live lanes per bounce, \
         BVH node step and primitive test; the image then holds those counts, not light",
    ),
    (
        "no-spot-check",
        "skip the spot check that renders a few hundred pixels of the first sample on both \
         backends before a GPU render and refuses a GPU that disagrees",
    ),
    (
        "perturb=PLACES",
        "fault injection for tests: perturb one texel of every GPU-side record placed in \
         PLACES (storage, uniform, shader, texture, joined by +, or all), as a driver that \
         fetched them wrong would",
    ),
    (
        "band-pixels=N",
        "at most N pixels per band of rows on the GPU (default 262144: 8 MiB of sums)",
    ),
];

impl Tuning {
    /// The settings the scene is flattened with.
    pub fn build(&self) -> Build {
        Build {
            acceleration: self.acceleration,
            russian_roulette: self.russian_roulette,
        }
    }

    /// The default tuning with the comma-separated knobs of [`KNOBS`] turned off (or, for
    /// `bvh`, on; `band-pixels=N` set), e.g. `no-bvh,no-specialize`.
    pub fn parse(list: &str) -> Result<Tuning, String> {
        let mut t = Tuning::default();
        for knob in list.split(',').map(str::trim).filter(|k| !k.is_empty()) {
            match knob {
                "no-bvh" | "bvh" => {
                    let a = if knob == "bvh" {
                        Acceleration::Bvh
                    } else {
                        Acceleration::List
                    };
                    if t.acceleration != Tuning::default().acceleration && t.acceleration != a {
                        return Err("\"bvh\" and \"no-bvh\" contradict each other".into());
                    }
                    t.acceleration = a;
                }
                "no-specialize" => t.specialize = false,
                "no-uniform-records" => t.uniform_records = false,
                "no-baked-records" => t.baked_records = false,
                "no-sample-groups" => t.sample_groups = false,
                "no-texture-records" => t.texture_records = false,
                "no-register-stack" => t.register_stack = false,
                "no-russian-roulette" => t.russian_roulette = false,
                "lane-stats" => t.lane_stats = true,
                "no-spot-check" => t.spot_check = false,
                _ if knob.starts_with("perturb=") => {
                    for place in knob["perturb=".len()..].split('+') {
                        t.perturb |= match place {
                            "all" => ALL_PLACEMENTS,
                            _ => PLACEMENT_NAMES
                                .iter()
                                .position(|&n| n == place)
                                .map(|i| 1 << i)
                                .ok_or_else(|| {
                                    format!(
                                        "\"{knob}\": perturb takes {} or all, joined by +",
                                        PLACEMENT_NAMES.join(", ")
                                    )
                                })?,
                        };
                    }
                }
                _ if knob.starts_with("band-pixels=") => {
                    t.band_pixels = knob["band-pixels=".len()..]
                        .parse()
                        .ok()
                        .filter(|&n| n > 0)
                        .ok_or_else(|| {
                            format!("\"{knob}\": band-pixels needs a whole number > 0")
                        })?;
                }
                _ => {
                    let names: Vec<&str> = KNOBS.iter().map(|(n, _)| *n).collect();
                    return Err(format!(
                        "unknown tuning knob \"{knob}\" (knobs: {})",
                        names.join(", ")
                    ));
                }
            }
        }
        Ok(t)
    }
}
