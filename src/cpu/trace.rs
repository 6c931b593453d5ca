//! Mirrors `shaders/trace.wgsl`: camera rays, the bounce loop, and the per-pixel entry point.

use glam::Vec3;
use rayon::prelude::*;

use super::bindings::Bindings;
use super::intersect::{intersect_scene, occluded, surface_at};
use super::lights::{
    background_radiance, light_pdf, light_pdf_total, power_heuristic, sample_light, sample_punctual,
};
use super::materials::blend;
use super::materials::{
    alpha_u, bent_normal, bsdf_eval, bsdf_pdf, bsdf_scatter, emitted, material_at, mixture_applies,
    nee_applies, normal_mapped, scatter_pdf, transparent_at,
};
use super::rng::rand_2d;
use super::samplers::{
    bounce_2d, pixel_position, sample_2d, splat_weight, DIM_ALPHA, DIM_BLEND, DIM_PUNCTUAL, DIM_RR,
};
use super::sampling::{offset_ray, sample_disk};
use super::types::{xyz, Candidate, Hit, Ray, FAR, NO_HIT};
use crate::scene::flat::FlatScene;
use crate::scene::materials::MaterialKind;
use crate::scene::records::{
    accum_entries, Material, LIGHT_ENVIRONMENT, LIGHT_SAMPLING_MIS, LIGHT_SAMPLING_MIXTURE,
    MAX_ALPHA_SKIPS, NO_LIGHT, PRIM_LIGHT_SHIFT, SPLAT_DROPPED,
};

pub use super::samplers::{DIM_BSDF, DIM_LENS, DIM_LIGHT, DIM_LIGHT_CHOICE, DIM_PIXEL};

/// Camera ray through a point of pixel (x, y); pixel (0, 0) is the top-left. It starts
/// at the near clip plane (`near_clip` in front of the camera along its forward vector).
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
    let (origin, dir) = if p.orthographic != 0 {
        (
            xyz(p.cam_origin) + target_offset - forward * p.cam_forward[3],
            forward,
        )
    } else {
        (
            xyz(p.cam_origin) + lens_offset,
            (target_offset - lens_offset).normalize(),
        )
    };
    // from the near clip plane on (0: the camera itself)
    Ray {
        origin: origin + dir * (p.near_clip / dir.dot(forward)),
        dir,
    }
}

/// A ray leaving a hit in direction dir, from just off the surface on dir's side.
pub fn spawn_ray(hit: &Hit, dir: Vec3) -> Ray {
    let side = if dir.dot(hit.ng) > 0.0 {
        hit.ng
    } else {
        -hit.ng
    };
    Ray {
        origin: offset_ray(hit.p, side, hit.err),
        dir,
    }
}

/// Whether anything opaque lies on a shadow ray before t_max (trace.wgsl's `shadowed`):
/// with alpha materials, the surfaces on the way are passed through where transparent.
pub fn shadowed(b: &Bindings, ray: &Ray, t_max: f32, u: f32) -> bool {
    if !b.has_alpha {
        return occluded(b, ray, t_max);
    }
    let mut r = *ray;
    let mut t = t_max;
    for k in 0..MAX_ALPHA_SKIPS {
        let cand = intersect_scene(b, &r, t);
        if cand.prim == NO_HIT {
            return false;
        }
        let hit = surface_at(b, &r, &cand);
        if !transparent_at(b, &hit, alpha_u(u, k)) {
            return true;
        }
        let next = spawn_ray(&hit, r.dir);
        // the rest of the segment, shortened by 2^-16 of itself, so it stops short of the
        // light's own surface whatever the rounding of the pass-through (trace.wgsl)
        t = (t - (next.origin - r.origin).dot(r.dir)) * (1.0 - 1.0 / 65536.0);
        if t <= 0.0 {
            return false;
        }
        r = next;
    }
    true
}

/// Next-event estimation at a hit: shadow ray to just short of a sampled light point, the
/// light's emission there times BSDF x cos, power-heuristic weight, over the light's pdf.
pub fn direct_light(
    b: &Bindings,
    mat: &Material,
    ray: &Ray,
    hit: &Hit,
    u_light: f32,
    u: [f32; 2],
    u_alpha: f32,
) -> Vec3 {
    let ls = sample_light(b, hit.p, u_light, u);
    if ls.light == NO_LIGHT {
        return Vec3::ZERO;
    }
    let f = bsdf_eval(mat, ray, hit, ls.dir);
    if f == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let mut shadow = spawn_ray(hit, ls.dir);
    let mut t_max = FAR;
    // the material's pdf for the MIS weight is taken from the ray origin, as a bounce ray
    // toward the same point has it, so the two weights of a path add up to one
    let mut pdf_dir = ls.dir;
    let e = &b.emitters[ls.light as usize];
    let le = if e.kind == LIGHT_ENVIRONMENT {
        background_radiance(b, ls.dir)
    } else {
        let to_light = Ray {
            origin: hit.p,
            dir: ls.dir,
        };
        let cand = Candidate {
            t: ls.dist,
            prim: e.primitive,
            u: ls.uv.x,
            v: ls.uv.y,
            inst: NO_HIT,
        };
        let lh = surface_at(b, &to_light, &cand);
        let mut le = emitted(
            &material_at(b, &b.materials[lh.material as usize], &lh),
            &lh,
        );
        // a light point where the emitter is cut out or passed through emits nothing
        // there, as a bounce ray finds it
        if b.has_alpha && transparent_at(b, &lh, alpha_u(u_alpha, MAX_ALPHA_SKIPS)) {
            le = Vec3::ZERO;
        }
        if le == Vec3::ZERO {
            return Vec3::ZERO;
        }
        pdf_dir = (lh.p - shadow.origin).normalize();
        let facing = if ls.dir.dot(lh.ng) < 0.0 {
            lh.ng
        } else {
            -lh.ng
        };
        let v = offset_ray(lh.p, facing, lh.err) - shadow.origin;
        t_max = v.length();
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if !(t_max > 0.0) {
            return Vec3::ZERO;
        }
        shadow.dir = v / t_max;
        le
    };
    if shadowed(b, &shadow, t_max, u_alpha) {
        return Vec3::ZERO;
    }
    let w = power_heuristic(ls.pdf, bsdf_pdf(mat, ray, hit, pdf_dir));
    f * le * (w / ls.pdf)
}

/// Next-event estimation toward a light without a surface, chosen among them in
/// proportion to its power: a shadow ray to its position (or out of the scene, for a
/// directional light), f x intensity x the spot's falloff / d^2 (or f x irradiance) over
/// the choice's probability, no MIS weight (trace.wgsl's `direct_punctual`).
pub fn direct_punctual(
    b: &Bindings,
    mat: &Material,
    ray: &Ray,
    hit: &Hit,
    u: f32,
    u_alpha: f32,
) -> Vec3 {
    let s = sample_punctual(b, hit.p, u);
    let mut shadow = spawn_ray(hit, s.dir);
    let mut t_max = FAR;
    if s.positioned {
        let w = s.position - shadow.origin;
        t_max = w.length();
        shadow.dir = w / t_max;
    }
    let f = bsdf_eval(mat, ray, hit, s.dir);
    let lit = s.prob > 0.0 && s.d2 > 0.0 && t_max > 0.0 && f != Vec3::ZERO && s.le != Vec3::ZERO;
    if !lit || shadowed(b, &shadow, t_max, u_alpha) {
        return Vec3::ZERO;
    }
    f * s.le / s.prob
}

/// A camera path being traced (trace.wgsl's `Path`): the next ray, the radiance so far,
/// the throughput, the previous vertex for MIS, and the rays traced so far.
pub struct Path {
    pub ray: Ray,
    pub radiance: Vec3,
    pub throughput: Vec3,
    pub prev_p: Vec3,
    pub prev_pdf: f32,
    pub prev_delta: bool,
    pub depth: u32,
    /// The sample's AOVs (the shader's, with `HAS_AOVS`): albedo and normal of the first
    /// vertex whose bounce is not a delta lobe's (`found` once it is known), distance and
    /// point of the first hit.
    pub albedo: Vec3,
    pub normal: Vec3,
    pub position: Vec3,
    pub distance: f32,
    pub found: bool,
}

pub fn start_path(camera: Ray) -> Path {
    Path {
        ray: camera,
        radiance: Vec3::ZERO,
        throughput: Vec3::ONE,
        prev_p: camera.origin,
        prev_pdf: 0.0,
        prev_delta: true,
        depth: 0,
        albedo: Vec3::ZERO,
        normal: Vec3::ZERO,
        position: Vec3::ZERO,
        distance: 0.0,
        found: false,
    }
}

/// Traces the path's next ray and adds what it finds; false when the path has ended.
/// max_depth counts rays; light_sampling picks bsdf, mixture or mis (see trace.wgsl).
pub fn extend_path(b: &Bindings, path: &mut Path, pixel: u32, sample: u32) -> bool {
    let p = &b.params;
    // Russian roulette from ray rr_depth on, as the shader does
    if p.rr_depth != 0 && path.depth >= p.rr_depth {
        let survive = path.throughput.max_element().min(1.0);
        if rand_2d(pixel, sample, path.depth, DIM_RR, p.seed)[0] >= survive {
            return false;
        }
        path.throughput /= survive;
    }
    let mut u_alpha = [0.0; 2];
    let mut cand = intersect_scene(b, &path.ray, FAR);
    if b.has_alpha {
        // surfaces transparent where the ray meets them are passed through, as the
        // shader does; the last surface is kept whatever
        u_alpha = bounce_2d(b, pixel, sample, path.depth, DIM_ALPHA);
        for k in 0..MAX_ALPHA_SKIPS - 1 {
            if cand.prim == NO_HIT {
                break;
            }
            let h = surface_at(b, &path.ray, &cand);
            if !transparent_at(b, &h, alpha_u(u_alpha[0], k)) {
                break;
            }
            path.ray = spawn_ray(&h, path.ray.dir);
            cand = intersect_scene(b, &path.ray, FAR);
        }
    }
    let mis = p.light_sampling == LIGHT_SAMPLING_MIS && !path.prev_delta;
    if cand.prim == NO_HIT {
        let mut le = background_radiance(b, path.ray.dir);
        // the background's radiance, clamped, is the albedo of a path that escapes
        if !path.found {
            path.albedo = le.clamp(Vec3::ZERO, Vec3::ONE);
            path.found = true;
        }
        if mis && p.env_light != NO_LIGHT {
            le *= power_heuristic(
                path.prev_pdf,
                light_pdf(b, p.env_light, path.prev_p, path.prev_p, path.ray.dir),
            );
        }
        if p.hide_emitters != 0 && path.depth == 0 {
            le = Vec3::ZERO;
        }
        path.radiance += path.throughput * le;
        return false;
    }
    let surface = surface_at(b, &path.ray, &cand);
    // a blend's part, chosen here for all the vertex does
    let mut record = b.materials[surface.material as usize];
    if record.tag == MaterialKind::Blend.tag() {
        let u_blend = bounce_2d(b, pixel, sample, path.depth, DIM_BLEND)[0];
        record = blend::choice(b, surface.material, &surface, u_blend);
    }
    let mat = &material_at(b, &record, &surface);
    let hit = bent_normal(mat, &normal_mapped(b, mat, &surface), &path.ray);
    let mut le = emitted(mat, &hit);
    if path.depth == 0 {
        // prev_p is still the camera ray's origin (passing through alpha keeps it)
        path.distance = hit.p.distance(path.prev_p);
        path.position = hit.p;
    }
    if !path.found {
        // the shading normal facing the ray; an emitter's albedo is its emission, clamped
        path.normal = if hit.ns.dot(path.ray.dir) < 0.0 {
            hit.ns
        } else {
            -hit.ns
        };
        if le.cmpgt(Vec3::ZERO).any() {
            path.albedo = le.clamp(Vec3::ZERO, Vec3::ONE);
            path.found = true;
        }
    }
    let light = b.primitives[cand.prim as usize].flags >> PRIM_LIGHT_SHIFT;
    if mis && light != 0 && le.cmpgt(Vec3::ZERO).any() {
        le *= power_heuristic(
            path.prev_pdf,
            light_pdf(b, light - 1, path.prev_p, hit.p, path.ray.dir),
        );
    }
    if p.hide_emitters != 0 && path.depth == 0 {
        le = Vec3::ZERO;
    }
    path.radiance += path.throughput * le;
    if path.depth + 1 >= p.max_depth {
        return false;
    }
    let u = bounce_2d(b, pixel, sample, path.depth, DIM_BSDF);
    if p.light_sampling == LIGHT_SAMPLING_MIS && nee_applies(mat) {
        let ul = bounce_2d(b, pixel, sample, path.depth, DIM_LIGHT);
        let uc = bounce_2d(b, pixel, sample, path.depth, DIM_LIGHT_CHOICE);
        path.radiance +=
            path.throughput * direct_light(b, mat, &path.ray, &hit, uc[0], ul, u_alpha[1]);
    }
    // the lights without a surface, under every strategy: only next-event estimation
    // finds them
    if p.num_punctual > 0 && nee_applies(mat) {
        let up = bounce_2d(b, pixel, sample, path.depth, DIM_PUNCTUAL);
        path.radiance +=
            path.throughput * direct_punctual(b, mat, &path.ray, &hit, up[0], u_alpha[1]);
    }
    if p.light_sampling == LIGHT_SAMPLING_MIXTURE && p.num_emitters != 0 && mixture_applies(mat) {
        let uc = bounce_2d(b, pixel, sample, path.depth, DIM_LIGHT_CHOICE);
        let dir = if uc[1] < 0.5 {
            let ul = bounce_2d(b, pixel, sample, path.depth, DIM_LIGHT);
            let ls = sample_light(b, hit.p, uc[0], ul);
            if ls.light == NO_LIGHT {
                return false;
            }
            ls.dir
        } else {
            let s = bsdf_scatter(mat, &path.ray, &hit, u);
            if !s.ok {
                return false;
            }
            s.dir
        };
        let f = bsdf_eval(mat, &path.ray, &hit, dir);
        let pdf = 0.5 * light_pdf_total(b, hit.p, dir) + 0.5 * bsdf_pdf(mat, &path.ray, &hit, dir);
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if !(pdf > 0.0) || f == Vec3::ZERO {
            return false;
        }
        if !path.found {
            path.albedo = f / pdf;
            path.found = true;
        }
        path.throughput *= f / pdf;
        path.ray = spawn_ray(&hit, dir);
        path.depth += 1;
        return path.depth < p.max_depth;
    }
    let s = bsdf_scatter(mat, &path.ray, &hit, u);
    if !s.ok {
        return false;
    }
    path.throughput *= s.weight;
    // the albedo is the weight of the first bounce off a lobe with a density: f cos / pdf,
    // whose mean is the surface's directional albedo
    if !path.found && !s.delta {
        path.albedo = s.weight;
        path.found = true;
    }
    if path.throughput == Vec3::ZERO {
        // nothing further along this path can add to the pixel
        return false;
    }
    path.prev_p = hit.p;
    path.prev_pdf = scatter_pdf(mat, &path.ray, &hit, &s);
    path.prev_delta = s.delta;
    path.ray = spawn_ray(&hit, s.dir);
    path.depth += 1;
    path.depth < p.max_depth
}

/// Radiance along one camera path: extend_path until it ends, as the shader's `main`
/// does for each sample of its group.
pub fn trace_path(b: &Bindings, pixel: u32, sample: u32, camera: Ray) -> Path {
    let mut path = start_path(camera);
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
