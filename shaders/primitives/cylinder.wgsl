// A finite cylinder (scene::primitives::cylinder: CylinderParams), closed by two disks
// with PRIM_FLAG_CAPS: intersection, surface, uv derivatives. CPU twin:
// src/cpu/primitives/cylinder.rs.
#import shared/geometry
#import shared/sampling
#import shared/types

// The side: a t^2 + 2 b t + c = 0 for the squared distance to the axis of the ray's
// components across the axis, in the stable form (the discriminant b^2 - a c = a (r^2 -
// |op - (b / a) dp|^2), the larger-magnitude root first), each root kept only within the
// height. With caps, the two end disks too. Returns (t, part, 0): part 0 = side, 1 = base
// cap, 2 = top cap.
fn cylinder_intersect(p: CylinderParams, ray: Ray, t_max: f32) -> vec3<f32> {
    let base = p.base;
    let top = p.top;
    let radius = p.radius;
    let axis = top - base;
    let h = length(axis);
    let ax = axis / h;
    let oc = ray.origin - base;
    let o_ax = dot(oc, ax);
    let d_ax = dot(ray.dir, ax);
    let op = oc - o_ax * ax;
    let dp = ray.dir - d_ax * ax;
    var best = vec3<f32>(FAR, 0.0, 0.0);
    var t_lim = t_max;
    let a = dot(dp, dp);
    // a = 0: the ray runs along the axis and only the caps can be hit.
    if (a > 1e-20) {
        let b = dot(op, dp);
        let perp = op - (b / a) * dp;
        let r2 = radius * radius;
        let disc = r2 - dot(perp, perp);
        if (disc >= 0.0) {
            let c = dot(op, op) - r2;
            let q = -b - select(-1.0, 1.0, b >= 0.0) * sqrt(a * disc);
            if (q != 0.0) {
                let t0 = min(q / a, c / q);
                let t1 = max(q / a, c / q);
                let s0 = o_ax + t0 * d_ax;
                let s1 = o_ax + t1 * d_ax;
                if (t0 > 0.0 && t0 < t_lim && s0 >= 0.0 && s0 <= h) {
                    best = vec3<f32>(t0, 0.0, 0.0);
                    t_lim = t0;
                } else if (t1 > 0.0 && t1 < t_lim && s1 >= 0.0 && s1 <= h) {
                    best = vec3<f32>(t1, 0.0, 0.0);
                    t_lim = t1;
                }
            }
        }
    }
    if ((p.flags & PRIM_FLAG_CAPS) != 0u) {
        let t_base = intersect_disk(base, ax, radius, ray, t_lim);
        if (t_base < t_lim) {
            best = vec3<f32>(t_base, 1.0, 0.0);
            t_lim = t_base;
        }
        let t_top = intersect_disk(top, ax, radius, ray, t_lim);
        if (t_top < t_lim) {
            best = vec3<f32>(t_top, 2.0, 0.0);
        }
    }
    return best;
}

// The hit re-projected onto the side (the candidate's u is 0) or a cap; uv: the angle
// about the axis and the height, or on a cap the angle and the radius.
fn cylinder_surface(p: CylinderParams, ray: Ray, cand: Candidate) -> Surface {
    var s = blank_surface();
    let base = p.base;
    let top = p.top;
    let radius = p.radius;
    let axis = top - base;
    let h = length(axis);
    let ax = axis / h;
    let q = ray.origin + cand.t * ray.dir - base;
    let q_ax = dot(q, ax);
    let radial = q - q_ax * ax;
    if (cand.u == 0.0) {
        let n = normalize(radial);
        let height = clamp(q_ax, 0.0, h);
        s.p = base + height * ax + radius * n;
        s.ng = n;
        s.uv = vec2<f32>(angle_uv(n, ax), height / h);
    } else {
        let top_cap = cand.u == 2.0;
        s.p = select(base, top, top_cap) + radial;
        s.ng = select(-ax, ax, top_cap);
        s.uv = vec2<f32>(angle_uv(radial, ax), length(radial) / radius);
    }
    s.ns = s.ng;
    s.err = (max(max_abs(base), max_abs(top)) + radius) * (1.0 / 1048576.0);
    return s;
}

// The direction of growing angle (angle_uv) times the circumference's length, and the
// axis (the side) or the radius's direction times the radius (a cap).
fn cylinder_uv_derivatives(p: CylinderParams, s: Surface, cand: Candidate) -> array<vec3<f32>, 2> {
    let axis = p.top - p.base;
    let ax = normalize(axis);
    let q = s.p - p.base;
    let radial = q - dot(q, ax) * ax;
    let len = max(length(radial), 1e-12);
    let tb = onb_tangents(ax);
    let c = radial / len;
    let around = dot(c, tb[0]) * tb[1] - dot(c, tb[1]) * tb[0];
    return array<vec3<f32>, 2>(2.0 * PI * len * around, select(c * p.radius, axis, cand.u == 0.0));
}
