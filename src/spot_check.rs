//! The spot check: before a GPU render accumulates, the first sample of the image is
//! rendered on the GPU, with the render's own shader, record placements and dispatches,
//! and the first sample of a few hundred of its pixels spread over the image (a grid of
//! small tiles) on the CPU reference, which shares its random numbers and algorithms, and
//! the two are compared pixel by pixel with the tolerances the tests use (three channels
//! within 1e-3, relative above 1, plus the effect of the kernel tests' 1e-3 on texture
//! coordinates, [`PIXEL_TOLERANCE`]; at least [`MIN_AGREEMENT`] of the pixels, the image
//! tests' bound). A driver that computes the scene wrong (Mesa 22.3.6's
//! lavapipe on some AVX-512 CPUs fetches record textures wrong) is caught before it hands
//! out an image: the render falls back to safer record placements (textures, then uniform
//! buffers and constants in the shader, to storage buffers) with a one-line note, and is
//! refused with [`GpuError::WrongResults`] when none agrees. `--tune no-spot-check` skips
//! it. It sits beside `engine.rs`, the one other module that holds both backends.

use std::collections::HashMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

use rayon::prelude::*;

use crate::cpu::bindings::Bindings;
use crate::cpu::samplers::pixel_position;
use crate::cpu::trace::{accumulate, gather, splat_record, trace_pixel};
use crate::gpu::bindings::{Placement, Slot};
use crate::gpu::context::GpuContext;
use crate::gpu::error::GpuError;
use crate::gpu::plan::GpuPlan;
use crate::gpu::render::GpuRenderer;
use crate::scene::flat::{Band, FlatScene};
use crate::scene::records::SPLAT_DROPPED;
use crate::tuning::Tuning;

/// Side of a tile of the spot check, in pixels.
pub const TILE: u32 = 4;

/// Tiles per side of the grid the spot check spreads over the image: 5 x 5 tiles of
/// 4 x 4 pixels, 400 pixels.
pub const GRID: u32 = 5;

/// The least share of pixels that must agree: the tests' `agree_fraction` bound. A path
/// whose ray grazes an edge may take either side of it on the two backends, so a few
/// pixels of a right GPU may differ; a wrong one differs on most of what it gets wrong.
pub const MIN_AGREEMENT: f64 = 0.99;

/// The tiles of the spot check on a `width` x `height` image: a [`GRID`] x [`GRID`] grid of
/// tiles of [`TILE`] x [`TILE`] pixels centred in the grid's cells (on an image too small
/// for that, as many tiles per side as fit, clipped to the image), none overlapping.
pub fn tiles(width: u32, height: u32) -> Vec<Band> {
    let (tw, th) = (TILE.min(width), TILE.min(height));
    let (nx, ny) = ((width / tw).clamp(1, GRID), (height / th).clamp(1, GRID));
    let at = |i: u32, n: u32, size: u32, side: u32| {
        let centre = (2 * i + 1) * size / (2 * n);
        centre.saturating_sub(side / 2).min(size - side)
    };
    (0..ny)
        .flat_map(|j| {
            (0..nx).map(move |i| Band {
                x: at(i, nx, width, tw),
                y: at(j, ny, height, th),
                width: tw,
                height: th,
            })
        })
        .collect()
}

/// The pixels of `tiles`, tile by tile, row by row: the order of [`first_sample`]'s
/// entries and of [`cpu_tiles`]'.
fn tile_pixels(tiles: &[Band]) -> impl Iterator<Item = (u32, u32)> + '_ {
    tiles.iter().flat_map(|t| {
        (t.y..t.y + t.height).flat_map(move |y| (t.x..t.x + t.width).map(move |x| (x, y)))
    })
}

/// Each pixel of `tiles` (tile by tile, row by row) after sample `sample` on the CPU
/// reference: its first two accumulation entries, as [`first_sample`] gives them.
pub fn cpu_tiles(scene: &FlatScene, tiles: &[Band], sample: u32) -> Vec<[[f32; 4]; 2]> {
    let b = Bindings::new(scene, scene.params(sample, scene.full_band()));
    let pixels: Vec<(u32, u32)> = tile_pixels(tiles).collect();
    if b.params.splat != 0 {
        return splatted_tiles(&b, tiles, &pixels);
    }
    pixels
        .par_iter()
        .map(|&(x, y)| {
            let (mut sum, mut sq) = ([0.0; 4], [0.0; 4]);
            accumulate(&mut sum, &mut sq, trace_pixel(&b, x, y).radiance);
            [sum, sq]
        })
        .collect()
}

/// [`cpu_tiles`] of a render that splats: the samples of the tiles and of the pixels
/// around them that their filters reach, then each tile pixel's gather of them.
fn splatted_tiles(b: &Bindings, tiles: &[Band], pixels: &[(u32, u32)]) -> Vec<[[f32; 4]; 2]> {
    let p = &b.params;
    let reach = (p.filter_shape[0] - 0.5).ceil() as u32;
    let mut around: Vec<(u32, u32)> = tiles
        .iter()
        .flat_map(|t| {
            let (x0, y0) = (t.x.saturating_sub(reach), t.y.saturating_sub(reach));
            let x1 = (t.x + t.width + reach).min(p.width);
            let y1 = (t.y + t.height + reach).min(p.height);
            (y0..y1).flat_map(move |y| (x0..x1).map(move |x| (x, y)))
        })
        .collect();
    around.sort_unstable();
    around.dedup();
    let samples: HashMap<(u32, u32), [u32; 4]> = around
        .par_iter()
        .map(|&(x, y)| {
            let jitter = pixel_position(b, y * p.width + x, p.sample_index);
            ((x, y), splat_record(trace_pixel(b, x, y).radiance, jitter))
        })
        .collect();
    pixels
        .par_iter()
        .map(|&(x, y)| {
            let (mut sum, mut sq) = ([0.0; 4], [0.0; 4]);
            if samples[&(x, y)][0] == SPLAT_DROPPED {
                sq[3] += 1.0;
            }
            gather(b, |xx, yy| samples[&(xx, yy)], x, y, &mut sum, &mut sq);
            [sum, sq]
        })
        .collect()
}

/// What one spot check found.
#[derive(Debug, Clone)]
pub struct Verdict {
    pub pixels: usize,
    /// Pixels whose GPU and CPU values agree.
    pub agreeing: usize,
    /// The first pixel that differs, with both values.
    pub first_difference: Option<String>,
    /// Time on the GPU (its first dispatch may include the driver's compile) and on the
    /// CPU.
    pub gpu_time: Duration,
    pub cpu_time: Duration,
}

impl Verdict {
    /// Whether the GPU agrees with the CPU reference.
    pub fn passed(&self) -> bool {
        self.agreeing as f64 >= MIN_AGREEMENT * self.pixels as f64
    }

    /// One line for the user: how many pixels differ, and the first.
    pub fn describe(&self) -> String {
        let differ = self.pixels - self.agreeing;
        match &self.first_difference {
            None => format!("all {} pixels agree", self.pixels),
            Some(first) => format!("{differ} of {} pixels differ (first: {first})", self.pixels),
        }
    }
}

/// How far a channel of a right GPU's pixel may be from the CPU's, as a share of the
/// pixel's brightest channel (on top of 1e-3, relative above 1). The two backends' atan2,
/// acos and sqrt differ in the last bits, so a texture coordinate may differ by up to 1e-3
/// (the kernel tests' bound): on a detailed image texture that moves a first sample by
/// about 1% (Earth's coastlines, `scenes/earth.toml`, 8 of its 400 pixels at 1.2%). A
/// driver that fetches records wrong moves pixels by far more (a black speckle, another
/// primitive, another material).
pub const PIXEL_TOLERANCE: f32 = 0.05;

/// Compares the GPU's and the CPU's entries of the pixels of `tiles`: a pixel agrees when
/// both kept or both dropped its sample and each channel of the sum is within 1e-3
/// (relative above 1) plus [`PIXEL_TOLERANCE`] of its brightest channel.
pub fn compare(
    tiles: &[Band],
    gpu: &[[[f32; 4]; 2]],
    cpu: &[[[f32; 4]; 2]],
) -> (usize, Option<String>) {
    let coords = tile_pixels(tiles);
    let mut agreeing = 0;
    let mut first = None;
    for ((x, y), (g, c)) in coords.zip(gpu.iter().zip(cpu)) {
        // a count, or a splat render's sum of weights (the backends' exp differ in the
        // last bits)
        let same_count = (g[0][3] - c[0][3]).abs() <= 1e-4 * c[0][3].max(1.0) && g[1][3] == c[1][3];
        let brightest = c[0][..3].iter().fold(0.0f32, |m, v| m.max(v.abs()));
        let close = (0..3).all(|k| {
            (g[0][k] - c[0][k]).abs() <= 1e-3 * c[0][k].abs().max(1.0) + PIXEL_TOLERANCE * brightest
        });
        if same_count && close {
            agreeing += 1;
        } else if first.is_none() {
            let rgb = |e: &[[f32; 4]; 2]| {
                if e[0][3] == 0.0 {
                    "dropped".to_string()
                } else if e[0][3] == 1.0 {
                    format!("[{:.4}, {:.4}, {:.4}]", e[0][0], e[0][1], e[0][2])
                } else {
                    // a splat render's sums, with their weight
                    let [r, g, b, w] = e[0];
                    format!("[{r:.4}, {g:.4}, {b:.4}] of weight {w:.4}")
                }
            };
            first = Some(format!(
                "pixel ({x}, {y}): GPU {} against CPU {}",
                rgb(g),
                rgb(c)
            ));
        }
    }
    (agreeing, first)
}

/// Runs the spot check of `renderer`, open on `scene` (the scene as it is: a perturbed
/// device copy, `--tune perturb`, is the renderer's own), on the first sample.
pub fn check(renderer: &mut GpuRenderer, scene: &FlatScene) -> Result<Verdict, GpuError> {
    let tiles = tiles(scene.width, scene.height);
    let start = Instant::now();
    let gpu = first_sample(renderer, &tiles)?;
    let gpu_time = start.elapsed();
    let start = Instant::now();
    let cpu = cpu_tiles(scene, &tiles, 0);
    let cpu_time = start.elapsed();
    let (agreeing, first_difference) = compare(&tiles, &gpu, &cpu);
    Ok(Verdict {
        pixels: cpu.len(),
        agreeing,
        first_difference,
        gpu_time,
        cpu_time,
    })
}

/// The GPU's entries for the pixels of `tiles` (tile by tile, row by row) after the
/// first sample, rendered as the render renders it: a pass over the whole image, band by
/// band, in the render's own dispatches, which the renderer keeps as the render's first
/// sample ([`GpuRenderer::render_first_sample`]), so the check costs the render only the
/// readback and the CPU's pixels. The render's own dispatches matter: a driver may
/// render small dispatches of the tiles alone right and the render's wrong
/// (docs/robustness.md).
fn first_sample(
    renderer: &mut GpuRenderer,
    tiles: &[Band],
) -> Result<Vec<[[f32; 4]; 2]>, GpuError> {
    let sums = renderer.render_first_sample()?;
    let (width, height) = renderer.size();
    let entries = sums.len() / (width as usize * height as usize);
    Ok(tile_pixels(tiles)
        .map(|(x, y)| {
            let at = entries * (y as usize * width as usize + x as usize);
            [sums[at], sums[at + 1]]
        })
        .collect())
}

/// Where a plan keeps the record arrays its trace shader reads, for the user: "primitives
/// and bvh in textures, materials in the shader, ...".
pub fn placements(plan: &GpuPlan) -> String {
    let read = plan.shader.trace_slots();
    // an array written into the shader is bound to no slot
    let used = |s: &Slot| read.contains(s) || plan.shader.placements.get(*s) == Placement::Shader;
    let mut parts = Vec::new();
    for (place, where_) in [
        (Placement::Texture, "in textures"),
        (Placement::Uniform, "in uniform buffers"),
        (Placement::Shader, "in the shader"),
        (Placement::Storage, "in storage buffers"),
    ] {
        let names: Vec<&str> = Slot::RECORDS
            .into_iter()
            .filter(|s| used(s) && plan.shader.placements.get(*s) == place)
            .map(Slot::name)
            .collect();
        if let Some((last, rest)) = names.split_last() {
            let list = if rest.is_empty() {
                last.to_string()
            } else {
                format!("{} and {last}", rest.join(", "))
            };
            parts.push(format!("{list} {where_}"));
        }
    }
    if parts.is_empty() {
        parts.push("no records".into());
    }
    if plan.shader.register_stack {
        parts.push("the BVH walk's stack in registers".into());
    }
    parts.join(", ")
}

/// The next safer tuning after `plan` (made under `tuning`) disagreed: records in textures
/// go to storage buffers; then those in uniform buffers or written into the shader; then
/// the BVH walk's stack leaves its registers for workgroup memory. None when every array
/// the shader reads is already in a storage buffer and the stack in workgroup memory.
pub fn safer(tuning: &Tuning, plan: &GpuPlan) -> Option<Tuning> {
    let read = plan.shader.trace_slots();
    let any = |place: Placement| {
        Slot::RECORDS.into_iter().any(|s| {
            let at = plan.shader.placements.get(s);
            at == place && (read.contains(&s) || at == Placement::Shader)
        })
    };
    let mut t = *tuning;
    if any(Placement::Texture) && t.texture_records {
        t.texture_records = false;
        Some(t)
    } else if (any(Placement::Uniform) || any(Placement::Shader))
        && (t.uniform_records || t.baked_records)
    {
        t.uniform_records = false;
        t.baked_records = false;
        Some(t)
    } else if plan.shader.register_stack && t.register_stack {
        t.register_stack = false;
        Some(t)
    } else {
        None
    }
}

/// Opens a GPU renderer for `scene` under `tuning` and spot-checks it (unless the tuning
/// turns the check off, or counts lanes instead of light); on a mismatch, opens it again
/// under [`safer`] tunings until one agrees, with a note naming what disagreed, or refuses
/// the adapter when none does.
pub fn open_checked(
    ctx: Arc<GpuContext>,
    scene: &FlatScene,
    tuning: &Tuning,
) -> Result<GpuRenderer, GpuError> {
    let mut renderer = GpuRenderer::new(ctx.clone(), scene, tuning)?;
    if !tuning.spot_check || tuning.lane_stats {
        return Ok(renderer);
    }
    let mut tuning = *tuning;
    let mut tried = Vec::new();
    loop {
        let verdict = check(&mut renderer, scene)?;
        let what = placements(renderer.plan());
        if verdict.passed() {
            if !tried.is_empty() {
                renderer.set_note(Some(format!(
                    "spot check: on {}, {}; rendering with {what}, which agrees with the CPU \
                     reference",
                    renderer.name(),
                    tried.join("; ")
                )));
            }
            return Ok(renderer);
        }
        tried.push(format!("{what}: {}", verdict.describe()));
        match safer(&tuning, renderer.plan()) {
            Some(next) => {
                tuning = next;
                renderer = GpuRenderer::new(ctx.clone(), scene, &tuning)?;
            }
            None => {
                return Err(GpuError::WrongResults {
                    adapter: renderer.name(),
                    pixels: verdict.pixels,
                    tried: tried.join("; "),
                })
            }
        }
    }
}
