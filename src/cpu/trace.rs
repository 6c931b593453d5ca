//! Mirrors `shaders/trace.wgsl`: the per-pixel entry point (a sample's path traced by
//! `path::extend_path`), accumulation, splatting.

use glam::Vec3;
use rayon::prelude::*;

use super::bindings::Bindings;
use super::path::{camera_ray, extend_path, start_path, Path};
use super::samplers::{pixel_position, sample_2d, splat_weight};
use super::types::Ray;
use crate::scene::flat::FlatScene;
use crate::scene::records::{accum_entries, SPLAT_DROPPED};

pub use super::samplers::{DIM_BSDF, DIM_LENS, DIM_LIGHT, DIM_LIGHT_CHOICE, DIM_PIXEL};

/// Radiance along one camera path: extend_path until it ends, as the shader's `main`
/// does for each sample of its group.
pub fn trace_path(b: &Bindings, pixel: u32, sample: u32, camera: Ray) -> Path {
    let mut path = start_path(b, camera);
    if b.params.max_depth > 0 {
        while extend_path(b, &mut path, pixel, sample) {}
    }
    path
}

/// The shader's `main` for one pixel: the sample's path, its radiance and AOVs.
pub fn trace_pixel(b: &Bindings, x: u32, y: u32) -> Path {
    let p = &b.params;
    let pixel = y * p.width + x;
    let sample = p.sample_index;
    let jitter = pixel_position(b, pixel, sample);
    let lens = sample_2d(b, pixel, sample, DIM_LENS);
    trace_path(b, pixel, sample, camera_ray(b, x, y, jitter, lens))
}

/// Whether every component is a finite number, judged by its bits as the shader does.
pub fn all_finite(v: Vec3) -> bool {
    v.to_array()
        .iter()
        .all(|x| x.to_bits() & 0x7f80_0000 != 0x7f80_0000)
}

/// Adds one sample to a pixel's two accumulation entries: a sample that is not finite (or
/// whose square is not) is dropped and counted in `sq[3]`, as the shader's `main` does
/// (which first sums a group of samples, then adds the group).
pub fn accumulate(sum: &mut [f32; 4], sq: &mut [f32; 4], c: Vec3) {
    if all_finite(c) && all_finite(c * c) {
        sum[0] += c.x;
        sum[1] += c.y;
        sum[2] += c.z;
        sum[3] += 1.0;
        sq[0] += c.x * c.x;
        sq[1] += c.y * c.y;
        sq[2] += c.z * c.z;
    } else {
        sq[3] += 1.0;
    }
}

/// Adds one sample's AOVs to a pixel's three AOV entries, as the shader's `main` does (a
/// splat render counting them in the normal's fourth component).
pub fn accumulate_aovs(aovs: &mut [[f32; 4]], path: &Path, splat: bool) {
    let albedo = if all_finite(path.albedo) {
        path.albedo
    } else {
        Vec3::ZERO
    };
    let add = |e: &mut [f32; 4], v: Vec3, w: f32| {
        e[0] += v.x;
        e[1] += v.y;
        e[2] += v.z;
        e[3] += w;
    };
    add(&mut aovs[0], albedo, path.distance);
    add(&mut aovs[1], path.normal, splat as u32 as f32);
    add(&mut aovs[2], path.position, 0.0);
}

/// A sample as the splat sample buffer holds it (trace.wgsl's `splat_record`): its
/// colour's bits (`SPLAT_DROPPED` first when it or its square is not finite) and its
/// position in the pixel as two 16-bit fixed-point numbers, floor(65536 p).
pub fn splat_record(c: Vec3, jitter: [f32; 2]) -> [u32; 4] {
    // as WGSL's u32(f32): toward zero, negatives to 0
    let fixed = |v: f32| ((v * 65536.0) as u32).min(65535);
    let packed = fixed(jitter[0]) | (fixed(jitter[1]) << 16);
    if all_finite(c) && all_finite(c * c) {
        [c.x.to_bits(), c.y.to_bits(), c.z.to_bits(), packed]
    } else {
        [SPLAT_DROPPED, 0, 0, packed]
    }
}

/// The position in its pixel a [`splat_record`] holds (trace.wgsl's `splat_position`).
pub fn splat_position(packed: u32) -> [f32; 2] {
    [
        ((packed & 0xffff) as f32 + 0.5) / 65536.0,
        ((packed >> 16) as f32 + 0.5) / 65536.0,
    ]
}

/// trace.wgsl's `gather` for pixel (x, y): every sample (`sample_at` a pixel: the pass's
/// one there) that its filter reaches, weighed by `splat_weight` along x times along y, added
/// row by row and column by column to the pixel's sum and sum of squares.
pub fn gather(
    b: &Bindings,
    sample_at: impl Fn(u32, u32) -> [u32; 4],
    x: u32,
    y: u32,
    sum: &mut [f32; 4],
    sq: &mut [f32; 4],
) {
    let p = &b.params;
    let reach = (p.filter_shape[0] - 0.5).ceil() as i32;
    for dy in -reach..=reach {
        let yy = y as i32 + dy;
        if yy < 0 || yy >= p.height as i32 {
            continue;
        }
        for dx in -reach..=reach {
            let xx = x as i32 + dx;
            if xx < 0 || xx >= p.width as i32 {
                continue;
            }
            let r = sample_at(xx as u32, yy as u32);
            if r[0] == SPLAT_DROPPED {
                continue;
            }
            let at = splat_position(r[3]);
            let w =
                splat_weight(p, 0.5 - at[0] - dx as f32) * splat_weight(p, 0.5 - at[1] - dy as f32);
            let c = Vec3::new(
                f32::from_bits(r[0]),
                f32::from_bits(r[1]),
                f32::from_bits(r[2]),
            );
            for k in 0..3 {
                sum[k] += w * c[k];
                sq[k] += w * c[k] * c[k];
            }
            sum[3] += w;
        }
    }
}

/// Progressive CPU renderer: one sample per pixel per pass, accumulated as the GPU
/// accumulates (`accum_entries` vec4 per pixel: sum and sum of squares, then the AOVs', in
/// f32, in pass order; the GPU adds a group of samples' sum at once, so the last bits may
/// differ).
pub struct CpuRenderer {
    scene: FlatScene,
    accum: Vec<[f32; 4]>,
}

impl CpuRenderer {
    pub fn new(scene: &FlatScene) -> Self {
        let n = scene.width as usize * scene.height as usize;
        Self {
            scene: scene.clone(),
            accum: vec![[0.0; 4]; accum_entries(scene.aovs) * n],
        }
    }

    /// Name of the backend, for the user.
    pub fn name(&self) -> String {
        format!("CPU reference ({} threads)", rayon::current_num_threads())
    }

    /// Adds sample `sample_index` of every pixel.
    pub fn render_pass(&mut self, sample_index: u32) {
        let scene = &self.scene;
        let bindings = Bindings::new(scene, scene.params(sample_index, scene.full_band()));
        let width = scene.width as usize;
        let entries = accum_entries(scene.aovs);
        let splat = bindings.params.splat != 0;
        // splatting: the pass's sample of every pixel, then their gather
        let mut samples = vec![[0u32; 4]; if splat { self.accum.len() / entries } else { 0 }];
        let trace_row = |y: usize, row: &mut [[f32; 4]], mut splatted: Option<&mut [[u32; 4]]>| {
            for (x, px) in row.chunks_exact_mut(entries).enumerate() {
                let path = trace_pixel(&bindings, x as u32, y as u32);
                let (sum, rest) = px.split_at_mut(1);
                let (sq, aovs) = rest.split_at_mut(1);
                match splatted.as_deref_mut() {
                    Some(out) => {
                        let pixel = (y * width + x) as u32;
                        let jitter = pixel_position(&bindings, pixel, sample_index);
                        out[x] = splat_record(path.radiance, jitter);
                        if out[x][0] == SPLAT_DROPPED {
                            sq[0][3] += 1.0;
                        }
                    }
                    None => accumulate(&mut sum[0], &mut sq[0], path.radiance),
                }
                if scene.aovs {
                    accumulate_aovs(aovs, &path, splat);
                }
            }
        };
        let rows = self.accum.par_chunks_mut(entries * width).enumerate();
        if splat {
            rows.zip(samples.par_chunks_mut(width))
                .for_each(|((y, row), out)| trace_row(y, row, Some(out)));
        } else {
            rows.for_each(|(y, row)| trace_row(y, row, None));
        }
        if splat {
            self.accum
                .par_chunks_mut(entries * width)
                .enumerate()
                .for_each(|(y, row)| {
                    for (x, px) in row.chunks_exact_mut(entries).enumerate() {
                        let (sum, rest) = px.split_at_mut(1);
                        let at = |xx: u32, yy: u32| samples[yy as usize * width + xx as usize];
                        gather(&bindings, at, x as u32, y as u32, &mut sum[0], &mut rest[0]);
                    }
                });
        }
    }

    /// The accumulation buffer: `accum_entries` `[f32; 4]` per pixel, row-major from the
    /// top-left.
    pub fn accumulation(&self) -> Vec<[f32; 4]> {
        self.accum.clone()
    }

    /// Replaces the sums (a resumed render); `data` has `accum_entries` entries per pixel.
    pub fn set_accumulation(&mut self, data: &[[f32; 4]]) {
        self.accum.copy_from_slice(data);
    }

    /// Image width and height.
    pub fn size(&self) -> (u32, u32) {
        (self.scene.width, self.scene.height)
    }
}
