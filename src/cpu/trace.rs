//! Mirrors `shaders/trace.wgsl`: camera rays, the bounce loop, and the per-pixel entry point.

use glam::Vec3;
use rayon::prelude::*;

use super::bindings::Bindings;
use super::intersect::{intersect_scene, surface_at};
use super::materials::{emitted, scatter};
use super::samplers::{bounce_2d, sample_2d};
use super::sampling::{offset_ray, sample_disk};
use super::textures::material_at;
use super::types::{xyz, Ray, NO_HIT};
use crate::scene::FlatScene;

pub use super::samplers::{DIM_BSDF, DIM_LENS, DIM_PIXEL};

/// Camera ray through a point of pixel (x, y); pixel (0, 0) is the top-left.
pub fn camera_ray(b: &Bindings, x: u32, y: u32, jitter: [f32; 2], lens: [f32; 2]) -> Ray {
    let p = &b.params;
    let s = (x as f32 + jitter[0]) / p.width as f32;
    let t = (y as f32 + jitter[1]) / p.height as f32;
    let right = xyz(p.cam_right);
    let up = xyz(p.cam_up);
    let forward = xyz(p.cam_forward);
    let target_offset = forward * p.cam_forward[3]
        + right * ((2.0 * s - 1.0) * p.cam_right[3])
        + up * ((1.0 - 2.0 * t) * p.cam_up[3]);
    let d = sample_disk(lens) * p.cam_origin[3];
    let lens_offset = right * d.x + up * d.y;
    Ray {
        origin: xyz(p.cam_origin) + lens_offset,
        dir: (target_offset - lens_offset).normalize(),
    }
}

/// Radiance of a ray leaving the scene: the constant, or the vertical gradient.
pub fn background_radiance(b: &Bindings, d: Vec3) -> Vec3 {
    let p = &b.params;
    if p.background_top[3] > 0.5 {
        return xyz(p.background).lerp(xyz(p.background_top), 0.5 * (d.y + 1.0));
    }
    xyz(p.background)
}

/// Radiance along one camera path; max_depth counts rays.
pub fn trace_path(b: &Bindings, pixel: u32, sample: u32, camera: Ray) -> Vec3 {
    let p = &b.params;
    let mut ray = camera;
    let mut radiance = Vec3::ZERO;
    let mut throughput = Vec3::ONE;
    for depth in 0..p.max_depth {
        let cand = intersect_scene(b, &ray);
        if cand.prim == NO_HIT {
            radiance += throughput * background_radiance(b, ray.dir);
            break;
        }
        let hit = surface_at(b, &ray, &cand);
        let mat = &material_at(b, &b.materials[hit.material as usize], &hit);
        radiance += throughput * emitted(mat, &hit);
        if depth + 1 >= p.max_depth {
            break;
        }
        let u = bounce_2d(b, pixel, sample, depth, DIM_BSDF);
        let s = scatter(mat, &ray, &hit, u);
        if !s.ok {
            break;
        }
        throughput *= s.weight;
        let side = if s.dir.dot(hit.ng) > 0.0 {
            hit.ng
        } else {
            -hit.ng
        };
        ray = Ray {
            origin: offset_ray(hit.p, side, hit.err),
            dir: s.dir,
        };
    }
    radiance
}

/// The shader's `main` for one pixel: the sample's radiance.
pub fn trace_pixel(b: &Bindings, x: u32, y: u32) -> Vec3 {
    let p = &b.params;
    let pixel = y * p.width + x;
    let sample = p.sample_index;
    let jitter = sample_2d(b, pixel, sample, DIM_PIXEL);
    let lens = sample_2d(b, pixel, sample, DIM_LENS);
    trace_path(b, pixel, sample, camera_ray(b, x, y, jitter, lens))
}

/// Progressive CPU renderer: one sample per pixel per pass, accumulated exactly as the GPU
/// accumulates (two vec4 per pixel: sum and sum of squares, in f32, in pass order).
pub struct CpuRenderer {
    scene: FlatScene,
    accum: Vec<[f32; 4]>,
}

impl CpuRenderer {
    pub fn new(scene: &FlatScene) -> Self {
        let n = scene.width as usize * scene.height as usize;
        Self {
            scene: scene.clone(),
            accum: vec![[0.0; 4]; 2 * n],
        }
    }

    /// Name of the backend, for the user.
    pub fn name(&self) -> String {
        format!("CPU reference ({} threads)", rayon::current_num_threads())
    }

    /// Adds sample `sample_index` of every pixel.
    pub fn render_pass(&mut self, sample_index: u32) {
        let scene = &self.scene;
        let bindings = Bindings::new(scene, scene.params(sample_index, scene.full_tile()));
        let width = scene.width as usize;
        self.accum
            .par_chunks_mut(2 * width)
            .enumerate()
            .for_each(|(y, row)| {
                for x in 0..width {
                    let c = trace_pixel(&bindings, x as u32, y as u32);
                    let sum = &mut row[2 * x];
                    sum[0] += c.x;
                    sum[1] += c.y;
                    sum[2] += c.z;
                    sum[3] += 1.0;
                    let sq = &mut row[2 * x + 1];
                    sq[0] += c.x * c.x;
                    sq[1] += c.y * c.y;
                    sq[2] += c.z * c.z;
                }
            });
    }

    /// The accumulation buffer: two `[f32; 4]` per pixel, row-major from the top-left.
    pub fn accumulation(&self) -> Vec<[f32; 4]> {
        self.accum.clone()
    }

    /// Image width and height.
    pub fn size(&self) -> (u32, u32) {
        (self.scene.width, self.scene.height)
    }
}
