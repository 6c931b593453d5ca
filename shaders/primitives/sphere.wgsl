// A sphere (scene::primitives::sphere: SphereParams): intersection, surface, uv
// derivatives, and sampling as a light. CPU twin: src/cpu/primitives/sphere.rs.
#import shared/geometry
#import shared/sampling
#import shared/types

// Numerically stable form (Ray Tracing Gems, chapter 7). `dir` is unit length. Returns
// (t, 0, 0): the nearest root in (0, t_max), else FAR.
fn sphere_intersect(p: SphereParams, ray: Ray, t_max: f32) -> vec3<f32> {
    let f = ray.origin - p.center;
    let b = dot(f, ray.dir);
    let perp = f - b * ray.dir;
    let r2 = p.radius * p.radius;
    let disc = r2 - dot(perp, perp);
    let c = dot(f, f) - r2;
    // No early return: llvmpipe runs both sides of every branch under a mask, and a
    // masked return costs more than a select; with the triangle's, 10% fewer instructions
    // in the Cornell box's bounce loop. A value of a missed case (the sqrt of disc < 0, a
    // division by q = 0) is never picked.
    let q = -b - select(-1.0, 1.0, b >= 0.0) * sqrt(disc);
    let t0 = min(c / q, q);
    let t1 = max(c / q, q);
    let t = select(select(FAR, t1, t1 > 0.0 && t1 < t_max), t0, t0 > 0.0 && t0 < t_max);
    return vec3<f32>(select(FAR, t, disc >= 0.0 && q != 0.0), 0.0, 0.0);
}

// The hit re-projected onto the sphere; uv: longitude from atan2(-z, x), latitude from
// the south pole (v = 0) up.
fn sphere_surface(p: SphereParams, ray: Ray, cand: Candidate) -> Surface {
    var s = blank_surface();
    let n = normalize(ray.origin + cand.t * ray.dir - p.center);
    s.p = p.center + p.radius * n;
    s.ng = n;
    s.ns = n;
    s.uv = vec2<f32>(atan2(-n.z, n.x) * (0.5 / PI) + 0.5, acos(clamp(-n.y, -1.0, 1.0)) / PI);
    s.err = (max_abs(p.center) + p.radius) * (1.0 / 1048576.0);
    return s;
}

// dp/du and dp/dv of the longitude and latitude (kept off the poles' singularity).
fn sphere_uv_derivatives(p: SphereParams, s: Surface, cand: Candidate) -> array<vec3<f32>, 2> {
    let n = s.ng;
    let rho = max(sqrt(n.x * n.x + n.z * n.z), 1e-6);
    return array<vec3<f32>, 2>(2.0 * PI * p.radius * vec3<f32>(n.z, 0.0, -n.x),
        PI * p.radius * vec3<f32>(-n.y * n.x / rho, rho, -n.y * n.z / rho));
}

// Whether `origin` is inside the sphere for sampling: within radius x (1 + 1/1024), squared
// 1 + 1/512. On and just outside the surface (a point shaded on the light itself) the cone
// degenerates into a cap of nearly zero size whose directions rounding destroys; area
// sampling is exact there.
fn sphere_inside(p: SphereParams, origin: vec3<f32>) -> bool {
    let v = origin - p.center;
    return dot(v, v) <= p.radius * p.radius * (1.0 + 1.0 / 512.0);
}

// 1 - cos(theta_max) of the cone a sphere of radius r subtends at squared distance dc2
// from its centre (sin^2 / 2 for small cones, where the subtraction would cancel).
fn sphere_cone(r: f32, dc2: f32) -> f32 {
    let sin2_max = r * r / dc2;
    if (sin2_max < 0.00068523) {
        return 0.5 * sin2_max;
    }
    return 1.0 - sqrt(max(0.0, 1.0 - sin2_max));
}

// A point seen from `origin`: uniform in the cone of directions the sphere subtends
// (pbrt-v4's Sphere::Sample, small cones by the series), or uniform by area from inside
// (sphere_inside).
fn sphere_light_sample(p: SphereParams, area: f32, origin: vec3<f32>, u: vec2<f32>) -> LightPoint {
    let center = p.center;
    let r = p.radius;
    let oc = center - origin;
    let dc2 = dot(oc, oc);
    if (sphere_inside(p, origin)) {
        let n = sample_sphere(u);
        let x = center + r * n;
        return LightPoint(x, area_pdf(origin, x, n, 4.0 * PI * r * r), vec2<f32>(0.0));
    }
    let sin2_max = r * r / dc2;
    let sin_max = sqrt(sin2_max);
    let cos_max = sqrt(max(0.0, 1.0 - sin2_max));
    var cos_t = (cos_max - 1.0) * u.x + 1.0;
    var sin2_t = 1.0 - cos_t * cos_t;
    if (sin2_max < 0.00068523) {
        sin2_t = sin2_max * u.x;
        cos_t = sqrt(1.0 - sin2_t);
    }
    let cos_a = sin2_t / sin_max + cos_t * sqrt(max(0.0, 1.0 - sin2_t / sin2_max));
    let sin_a = sqrt(max(0.0, 1.0 - cos_a * cos_a));
    let phi = 2.0 * PI * u.y;
    let wc = oc / sqrt(dc2);
    let tb = onb_tangents(wc);
    let n = -(sin_a * cos(phi) * tb[0] + sin_a * sin(phi) * tb[1] + cos_a * wc);
    return LightPoint(center + r * n, 1.0 / (2.0 * PI * sphere_cone(r, dc2)), vec2<f32>(0.0));
}

// The solid-angle pdf of sphere_light_sample toward x.
fn sphere_light_pdf(p: SphereParams, area: f32, origin: vec3<f32>, x: vec3<f32>) -> f32 {
    if (sphere_inside(p, origin)) {
        return area_pdf(origin, x, normalize(x - p.center), area);
    }
    return 1.0 / (2.0 * PI * sphere_cone(p.radius, dot(p.center - origin, p.center - origin)));
}

// Where the ray from `origin` along unit d meets the sphere as light sampling sees it (FAR:
// nowhere): from inside, the far root (the way out).
fn sphere_light_distance(p: SphereParams, origin: vec3<f32>, d: vec3<f32>) -> f32 {
    if (sphere_inside(p, origin)) {
        let oc = origin - p.center;
        let b = dot(oc, d);
        let c = dot(oc, oc) - p.radius * p.radius;
        let t = -b + sqrt(max(0.0, b * b - c));
        return select(FAR, t, t > 0.0);
    }
    return sphere_intersect(p, Ray(origin, d), FAR).x;
}
