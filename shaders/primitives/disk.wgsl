// A disk (scene::primitives::disk: DiskParams): intersection, surface, uv derivatives, and
// sampling as a light. CPU twin: src/cpu/primitives/disk.rs.
#import shared/geometry
#import shared/sampling
#import shared/types

// Returns (t, 0, 0) (intersect_disk).
fn disk_intersect(p: DiskParams, ray: Ray, t_max: f32) -> vec3<f32> {
    return vec3<f32>(intersect_disk(p.center, p.normal, p.radius, ray, t_max), 0.0, 0.0);
}

// The hit projected onto the disk's plane; uv: the angle about the normal and the radius.
fn disk_surface(p: DiskParams, ray: Ray, cand: Candidate) -> Surface {
    var s = blank_surface();
    let n = p.normal;
    let q = ray.origin + cand.t * ray.dir - p.center;
    let qp = q - dot(q, n) * n;
    s.p = p.center + qp;
    s.ng = n;
    s.ns = n;
    s.uv = vec2<f32>(angle_uv(qp, n), length(qp) / p.radius);
    s.err = (max_abs(p.center) + p.radius) * (1.0 / 1048576.0);
    return s;
}

// The direction of growing angle times the circumference's length, and the radius's
// direction times the radius.
fn disk_uv_derivatives(p: DiskParams, s: Surface, cand: Candidate) -> array<vec3<f32>, 2> {
    let qp = s.p - p.center;
    let len = max(length(qp), 1e-12);
    let tb = onb_tangents(p.normal);
    let c = qp / len;
    let around = dot(c, tb[0]) * tb[1] - dot(c, tb[1]) * tb[0];
    return array<vec3<f32>, 2>(2.0 * PI * len * around, c * p.radius);
}

// A point uniform by area: rho = R sqrt(xi1), theta = 2 pi xi2 in the disk's plane.
fn disk_light_sample(p: DiskParams, area: f32, origin: vec3<f32>, u: vec2<f32>) -> LightPoint {
    let d = sample_disk(u) * p.radius;
    let tb = onb_tangents(p.normal);
    let x = p.center + d.x * tb[0] + d.y * tb[1];
    return LightPoint(x, area_pdf(origin, x, p.normal, area), vec2<f32>(0.0));
}

// The solid-angle pdf of disk_light_sample toward x.
fn disk_light_pdf(p: DiskParams, area: f32, origin: vec3<f32>, x: vec3<f32>) -> f32 {
    return area_pdf(origin, x, p.normal, area);
}

// Where the ray from `origin` along unit d meets the disk (FAR: nowhere).
fn disk_light_distance(p: DiskParams, origin: vec3<f32>, d: vec3<f32>) -> f32 {
    return intersect_disk(p.center, p.normal, p.radius, Ray(origin, d), FAR);
}
