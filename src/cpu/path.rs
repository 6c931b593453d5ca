//! Mirrors `shaders/shared/path.wgsl`: a camera path one bounce at a time, in stages over
//! a vertex (next_hit or escape, surface_vertex, add_emission, next_event, sample_bounce,
//! continue_path), and what they use: camera rays, shadow rays, next-event estimation.

use glam::Vec3;

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
use super::media::{
    hg_eval, hg_sample, media_at, medium_after, medium_albedo, medium_flight, medium_record,
    transmittance,
};
use super::rng::rand_2d;
use super::samplers::{
    bounce_2d, DIM_ALPHA, DIM_BLEND, DIM_BSDF, DIM_LIGHT, DIM_LIGHT_CHOICE, DIM_PUNCTUAL, DIM_RR,
};
use super::sampling::{offset_ray, sample_disk};
use super::types::{xyz, Candidate, Hit, Ray, FAR, NO_HIT};
use crate::scene::materials::MaterialKind;
use crate::scene::records::{
    Material, DIM_MEDIUM, LIGHT_ENVIRONMENT, LIGHT_SAMPLING_MIS, LIGHT_SAMPLING_MIXTURE,
    MAX_ALPHA_SKIPS, MEDIUM_HIT, NO_LIGHT, NO_MEDIUM, PRIM_LIGHT_SHIFT,
};

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

/// Whether anything opaque lies on a shadow ray before t_max (path.wgsl's `shadowed`):
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
        // light's own surface whatever the rounding of the pass-through (path.wgsl)
        t = (t - (next.origin - r.origin).dot(r.dir)) * (1.0 - 1.0 / 65536.0);
        if t <= 0.0 {
            return false;
        }
        r = next;
    }
    true
}

/// A vertex of the path (path.wgsl's `Vertex`): a surface hit, its shading normal as the
/// material bends it, and the material there, a blend's part already chosen.
pub struct Vertex {
    pub hit: Hit,
    pub mat: Material,
    /// The medium the path's ray arrived in, the media word of the surface's shape (0 at
    /// a medium point), whether it is a point where the path scatters in a medium, and
    /// that medium's phase asymmetry.
    pub medium: u32,
    pub media: u32,
    pub scatter: bool,
    pub g: f32,
}

/// What the vertex scatters from the path's ray toward dir: BSDF x cos, or the phase
/// function.
pub fn vertex_eval(v: &Vertex, ray: &Ray, dir: Vec3) -> Vec3 {
    if v.scatter {
        return Vec3::splat(hg_eval(ray.dir.dot(dir), v.g));
    }
    bsdf_eval(&v.mat, ray, &v.hit, dir)
}

/// The density with which the vertex's own sampling picks dir (for MIS).
pub fn vertex_pdf(v: &Vertex, ray: &Ray, dir: Vec3) -> f32 {
    if v.scatter {
        return hg_eval(ray.dir.dot(dir), v.g);
    }
    bsdf_pdf(&v.mat, ray, &v.hit, dir)
}

/// A ray leaving the vertex along dir (from a surface, just off it on dir's side).
pub fn vertex_spawn(v: &Vertex, dir: Vec3) -> Ray {
    if v.scatter {
        return Ray {
            origin: v.hit.p,
            dir,
        };
    }
    spawn_ray(&v.hit, dir)
}

/// Whether light sampling applies at the vertex (a lobe with a density; a medium point).
pub fn vertex_nee(v: &Vertex) -> bool {
    v.scatter || nee_applies(&v.mat)
}

/// The medium a ray leaving the vertex along dir travels in.
pub fn vertex_medium(v: &Vertex, dir: Vec3) -> u32 {
    medium_after(v.media, v.hit.ng, dir, v.medium)
}

/// Next-event estimation at a vertex: shadow ray to just short of a sampled light point, the
/// light's emission there times BSDF x cos, power-heuristic weight, over the light's pdf.
pub fn direct_light(
    b: &Bindings,
    v: &Vertex,
    ray: &Ray,
    u_light: f32,
    u: [f32; 2],
    u_alpha: f32,
) -> Vec3 {
    let ls = sample_light(b, v.hit.p, u_light, u);
    if ls.light == NO_LIGHT {
        return Vec3::ZERO;
    }
    let f = vertex_eval(v, ray, ls.dir);
    if f == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let mut shadow = vertex_spawn(v, ls.dir);
    let mut t_max = FAR;
    // the material's pdf for the MIS weight is taken from the ray origin, as a bounce ray
    // toward the same point has it, so the two weights of a path add up to one
    let mut pdf_dir = ls.dir;
    let e = &b.emitters[ls.light as usize];
    let le = if e.kind == LIGHT_ENVIRONMENT {
        background_radiance(b, ls.dir)
    } else {
        let to_light = Ray {
            origin: v.hit.p,
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
    if b.has_media {
        let tr = transmittance(b, &shadow, t_max, u_alpha, vertex_medium(v, ls.dir), u);
        if tr == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let w = power_heuristic(ls.pdf, vertex_pdf(v, ray, pdf_dir));
        return f * tr * le * (w / ls.pdf);
    }
    if shadowed(b, &shadow, t_max, u_alpha) {
        return Vec3::ZERO;
    }
    let w = power_heuristic(ls.pdf, vertex_pdf(v, ray, pdf_dir));
    f * le * (w / ls.pdf)
}

/// Next-event estimation toward a light without a surface, chosen among them in
/// proportion to its power: a shadow ray to its position (or out of the scene, for a
/// directional light), f x intensity x the spot's falloff / d^2 (or f x irradiance) over
/// the choice's probability, no MIS weight (path.wgsl's `direct_punctual`).
pub fn direct_punctual(b: &Bindings, v: &Vertex, ray: &Ray, u: f32, u_alpha: f32) -> Vec3 {
    let s = sample_punctual(b, v.hit.p, u);
    let mut shadow = vertex_spawn(v, s.dir);
    let mut t_max = FAR;
    if s.positioned {
        let w = s.position - shadow.origin;
        t_max = w.length();
        shadow.dir = w / t_max;
    }
    let f = vertex_eval(v, ray, s.dir);
    let lit = s.prob > 0.0 && s.d2 > 0.0 && t_max > 0.0 && f != Vec3::ZERO && s.le != Vec3::ZERO;
    if b.has_media {
        if !lit {
            return Vec3::ZERO;
        }
        let tr = transmittance(
            b,
            &shadow,
            t_max,
            u_alpha,
            vertex_medium(v, s.dir),
            [u, 0.5],
        );
        if tr == Vec3::ZERO {
            return Vec3::ZERO;
        }
        return f * tr * s.le / s.prob;
    }
    if !lit || shadowed(b, &shadow, t_max, u_alpha) {
        return Vec3::ZERO;
    }
    f * s.le / s.prob
}

/// A camera path being traced (path.wgsl's `Path`): the next ray, the radiance so far,
/// the throughput, the previous vertex for MIS, and the rays traced so far.
pub struct Path {
    pub ray: Ray,
    pub radiance: Vec3,
    pub throughput: Vec3,
    pub prev_p: Vec3,
    pub prev_pdf: f32,
    pub prev_delta: bool,
    pub depth: u32,
    /// The medium the ray travels in (`NO_MEDIUM`: none; the shader's with HAS_MEDIA).
    pub medium: u32,
    /// The sample's AOVs (the shader's, with `HAS_AOVS`): albedo and normal of the first
    /// vertex whose bounce is not a delta lobe's (`found` once it is known), distance and
    /// point of the first hit.
    pub albedo: Vec3,
    pub normal: Vec3,
    pub position: Vec3,
    pub distance: f32,
    pub found: bool,
}

pub fn start_path(b: &Bindings, camera: Ray) -> Path {
    Path {
        ray: camera,
        radiance: Vec3::ZERO,
        throughput: Vec3::ONE,
        prev_p: camera.origin,
        prev_pdf: 0.0,
        prev_delta: true,
        depth: 0,
        medium: if b.has_media {
            b.params.camera_medium
        } else {
            NO_MEDIUM
        },
        albedo: Vec3::ZERO,
        normal: Vec3::ZERO,
        position: Vec3::ZERO,
        distance: 0.0,
        found: false,
    }
}

/// Russian roulette from ray rr_depth on (path.wgsl's `survives_roulette`); false when
/// the path stops.
pub fn survives_roulette(b: &Bindings, path: &mut Path, pixel: u32, sample: u32) -> bool {
    let p = &b.params;
    if p.rr_depth != 0 && path.depth >= p.rr_depth {
        let survive = path.throughput.max_element().min(1.0);
        if rand_2d(pixel, sample, path.depth, DIM_RR, p.seed)[0] >= survive {
            return false;
        }
        path.throughput /= survive;
    }
    true
}

/// The next vertex along the path's ray: the closest surface, passing through those
/// transparent where the ray meets them as the shader does (the last surface kept
/// whatever); with media, a free flight along each stretch (`flies`), and `MEDIUM_HIT`
/// where the path scatters first.
pub fn next_hit(b: &Bindings, path: &mut Path, u: f32, pixel: u32, sample: u32) -> Candidate {
    let mut cand = intersect_scene(b, &path.ray, FAR);
    let skips = if b.has_alpha { MAX_ALPHA_SKIPS } else { 1 };
    for k in 0..skips {
        if b.has_media && flies(b, path, &mut cand, pixel, sample, k) {
            break;
        }
        if k + 1 == skips || cand.prim == NO_HIT {
            break;
        }
        let h = surface_at(b, &path.ray, &cand);
        if !transparent_at(b, &h, alpha_u(u, k)) {
            break;
        }
        if b.has_media {
            path.medium = medium_after(media_at(b, &h), h.ng, path.ray.dir, path.medium);
        }
        path.ray = spawn_ray(&h, path.ray.dir);
        cand = intersect_scene(b, &path.ray, FAR);
    }
    cand
}

/// The free flight through the path's medium up to the surface cand found (the k-th
/// stretch of this bounce's ray): true when the path scatters before it, cand then
/// `MEDIUM_HIT` at the event's distance; the throughput takes the flight's weight.
pub fn flies(
    b: &Bindings,
    path: &mut Path,
    cand: &mut Candidate,
    pixel: u32,
    sample: u32,
    k: u32,
) -> bool {
    if path.medium == NO_MEDIUM {
        return false;
    }
    let t_max = if cand.prim != NO_HIT { cand.t } else { FAR };
    let u = bounce_2d(b, pixel, sample, path.depth, DIM_MEDIUM + k);
    let flight = medium_flight(b, &medium_record(b, path.medium), &path.ray, t_max, u, k);
    path.throughput *= flight.weight;
    if flight.t >= 0.0 {
        cand.prim = MEDIUM_HIT;
        cand.t = flight.t;
        return true;
    }
    false
}

/// The AOVs of a medium vertex that comes first: its distance and point, the normal
/// facing the ray, the medium's single-scattering albedo.
pub fn medium_aovs(b: &Bindings, path: &mut Path, v: &Vertex) {
    if path.depth == 0 {
        path.distance = v.hit.p.distance(path.prev_p);
        path.position = v.hit.p;
    }
    if !path.found {
        path.normal = -path.ray.dir;
        path.albedo = medium_albedo(b, &medium_record(b, v.medium), v.hit.p);
        path.found = true;
    }
}

/// The vertex where the path scatters in its medium, at distance t along its ray.
pub fn medium_vertex(b: &Bindings, path: &Path, t: f32) -> Vertex {
    let zero = Vec3::ZERO;
    Vertex {
        hit: Hit {
            p: path.ray.origin + t * path.ray.dir,
            ng: zero,
            ns: zero,
            unmapped: zero,
            uv: glam::Vec4::ZERO,
            front_face: false,
            material: 0,
            err: 0.0,
            tangent: glam::Vec4::ZERO,
            color: glam::Vec4::ZERO,
            dpdu: zero,
            dpdv: zero,
        },
        mat: Material::default(),
        medium: path.medium,
        media: 0,
        scatter: true,
        g: medium_record(b, path.medium).g,
    }
}

/// Whether an emitter the path's ray finds is weighed against light sampling: under MIS,
/// after a bounce that light sampling could have made.
pub fn weighs_emission(b: &Bindings, path: &Path) -> bool {
    b.params.light_sampling == LIGHT_SAMPLING_MIS && !path.prev_delta
}

/// The path's ray leaves the scene: the background's radiance, weighed by MIS against
/// sampling the environment light.
pub fn escape(b: &Bindings, path: &mut Path) {
    let p = &b.params;
    let mut le = background_radiance(b, path.ray.dir);
    // the background's radiance, clamped, is the albedo of a path that escapes
    if !path.found {
        path.albedo = le.clamp(Vec3::ZERO, Vec3::ONE);
        path.found = true;
    }
    if weighs_emission(b, path) && p.env_light != NO_LIGHT {
        le *= power_heuristic(
            path.prev_pdf,
            light_pdf(b, p.env_light, path.prev_p, path.prev_p, path.ray.dir),
        );
    }
    if p.hide_emitters != 0 && path.depth == 0 {
        le = Vec3::ZERO;
    }
    path.radiance += path.throughput * le;
}

/// The vertex at a surface the path's ray found: a blend's part chosen, the material,
/// its normal map and shading normal.
pub fn surface_vertex(
    b: &Bindings,
    path: &Path,
    cand: &Candidate,
    pixel: u32,
    sample: u32,
) -> Vertex {
    let surface = surface_at(b, &path.ray, cand);
    let mut record = b.materials[surface.material as usize];
    if record.tag == MaterialKind::Blend.tag() {
        let u_blend = bounce_2d(b, pixel, sample, path.depth, DIM_BLEND)[0];
        record = blend::choice(b, surface.material, &surface, u_blend);
    }
    let mat = material_at(b, &record, &surface);
    let hit = bent_normal(&mat, &normal_mapped(b, &mat, &surface), &path.ray);
    Vertex {
        hit,
        mat,
        medium: path.medium,
        media: if b.has_media {
            media_at(b, &surface)
        } else {
            0
        },
        scatter: false,
        g: 0.0,
    }
}

/// What the vertex emits toward the path, weighed by MIS when prim is a light; the AOVs
/// of a first hit.
pub fn add_emission(b: &Bindings, path: &mut Path, v: &Vertex, prim: u32) {
    let p = &b.params;
    let mut le = emitted(&v.mat, &v.hit);
    if path.depth == 0 {
        // prev_p is still the camera ray's origin (passing through alpha keeps it)
        path.distance = v.hit.p.distance(path.prev_p);
        path.position = v.hit.p;
    }
    if !path.found {
        // the shading normal facing the ray; an emitter's albedo is its emission, clamped
        path.normal = if v.hit.ns.dot(path.ray.dir) < 0.0 {
            v.hit.ns
        } else {
            -v.hit.ns
        };
        if le.cmpgt(Vec3::ZERO).any() {
            path.albedo = le.clamp(Vec3::ZERO, Vec3::ONE);
            path.found = true;
        }
    }
    let light = b.primitives[prim as usize].flags >> PRIM_LIGHT_SHIFT;
    if weighs_emission(b, path) && light != 0 && le.cmpgt(Vec3::ZERO).any() {
        le *= power_heuristic(
            path.prev_pdf,
            light_pdf(b, light - 1, path.prev_p, v.hit.p, path.ray.dir),
        );
    }
    if p.hide_emitters != 0 && path.depth == 0 {
        le = Vec3::ZERO;
    }
    path.radiance += path.throughput * le;
}

/// Next-event estimation at the vertex: a light with a surface or the background under
/// MIS, the lights without a surface under every strategy.
pub fn next_event(
    b: &Bindings,
    path: &mut Path,
    v: &Vertex,
    pixel: u32,
    sample: u32,
    u_alpha: f32,
) {
    let p = &b.params;
    if p.light_sampling == LIGHT_SAMPLING_MIS && vertex_nee(v) {
        let ul = bounce_2d(b, pixel, sample, path.depth, DIM_LIGHT);
        let uc = bounce_2d(b, pixel, sample, path.depth, DIM_LIGHT_CHOICE);
        path.radiance += path.throughput * direct_light(b, v, &path.ray, uc[0], ul, u_alpha);
    }
    if p.num_punctual > 0 && vertex_nee(v) {
        let up = bounce_2d(b, pixel, sample, path.depth, DIM_PUNCTUAL);
        path.radiance += path.throughput * direct_punctual(b, v, &path.ray, up[0], u_alpha);
    }
}

/// A direction the path goes on in from a vertex (path.wgsl's `Bounce`): its weight
/// (f x cos / pdf), the pdf MIS weighs the next emitter by, whether it came from a delta
/// lobe; `ok` false: the path ends.
#[derive(Clone, Copy, Debug, Default)]
pub struct Bounce {
    pub ok: bool,
    pub dir: Vec3,
    pub weight: Vec3,
    pub pdf: f32,
    pub delta: bool,
}

pub fn no_bounce() -> Bounce {
    Bounce::default()
}

/// The bounce from a vertex: the 50/50 mixture of light and material sampling
/// (mixture, at a material without a delta lobe), or the material's own.
pub fn sample_bounce(b: &Bindings, path: &Path, v: &Vertex, pixel: u32, sample: u32) -> Bounce {
    let p = &b.params;
    let u = bounce_2d(b, pixel, sample, path.depth, DIM_BSDF);
    if v.scatter {
        // the phase function's own sample: weight 1
        let dir = hg_sample(path.ray.dir, v.g, u);
        return Bounce {
            ok: true,
            dir,
            weight: Vec3::ONE,
            pdf: hg_eval(path.ray.dir.dot(dir), v.g),
            delta: false,
        };
    }
    if p.light_sampling == LIGHT_SAMPLING_MIXTURE && p.num_emitters != 0 && mixture_applies(&v.mat)
    {
        let uc = bounce_2d(b, pixel, sample, path.depth, DIM_LIGHT_CHOICE);
        let dir = if uc[1] < 0.5 {
            let ul = bounce_2d(b, pixel, sample, path.depth, DIM_LIGHT);
            let ls = sample_light(b, v.hit.p, uc[0], ul);
            if ls.light == NO_LIGHT {
                return no_bounce();
            }
            ls.dir
        } else {
            let s = bsdf_scatter(&v.mat, &path.ray, &v.hit, u);
            if !s.ok {
                return no_bounce();
            }
            s.dir
        };
        let f = vertex_eval(v, &path.ray, dir);
        let pdf = 0.5 * light_pdf_total(b, v.hit.p, dir) + 0.5 * vertex_pdf(v, &path.ray, dir);
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if !(pdf > 0.0) || f == Vec3::ZERO {
            return no_bounce();
        }
        return Bounce {
            ok: true,
            dir,
            weight: f / pdf,
            pdf,
            delta: false,
        };
    }
    let s = bsdf_scatter(&v.mat, &path.ray, &v.hit, u);
    Bounce {
        ok: s.ok,
        dir: s.dir,
        weight: s.weight,
        pdf: scatter_pdf(&v.mat, &path.ray, &v.hit, &s),
        delta: s.delta,
    }
}

/// The path goes on from the vertex along the bounce: throughput, the first albedo (the
/// weight of the first bounce off a lobe with a density), the vertex MIS remembers, the
/// next ray. False when it ends.
pub fn continue_path(b: &Bindings, path: &mut Path, v: &Vertex, bounce: &Bounce) -> bool {
    if !bounce.ok {
        return false;
    }
    path.throughput *= bounce.weight;
    if !path.found && !bounce.delta {
        path.albedo = bounce.weight;
        path.found = true;
    }
    if path.throughput == Vec3::ZERO {
        // nothing further along this path can add to the pixel
        return false;
    }
    path.prev_p = v.hit.p;
    path.prev_pdf = bounce.pdf;
    path.prev_delta = bounce.delta;
    if b.has_media {
        path.medium = vertex_medium(v, bounce.dir);
    }
    path.ray = vertex_spawn(v, bounce.dir);
    path.depth += 1;
    path.depth < b.params.max_depth
}

/// Traces the path's next ray and adds what it finds; false when the path has ended.
/// max_depth counts rays; light_sampling picks bsdf, mixture or mis (see path.wgsl).
pub fn extend_path(b: &Bindings, path: &mut Path, pixel: u32, sample: u32) -> bool {
    if !survives_roulette(b, path, pixel, sample) {
        return false;
    }
    let u_alpha = if b.has_alpha {
        bounce_2d(b, pixel, sample, path.depth, DIM_ALPHA)
    } else {
        [0.0; 2]
    };
    let cand = next_hit(b, path, u_alpha[0], pixel, sample);
    if cand.prim == NO_HIT {
        escape(b, path);
        return false;
    }
    let v = if cand.prim == MEDIUM_HIT {
        let v = medium_vertex(b, path, cand.t);
        medium_aovs(b, path, &v);
        v
    } else {
        let v = surface_vertex(b, path, &cand, pixel, sample);
        add_emission(b, path, &v, cand.prim);
        v
    };
    if path.depth + 1 >= b.params.max_depth {
        return false;
    }
    next_event(b, path, &v, pixel, sample, u_alpha[1]);
    let bounce = sample_bounce(b, path, &v, pixel, sample);
    continue_path(b, path, &v, &bounce)
}
