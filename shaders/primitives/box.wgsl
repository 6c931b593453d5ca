// An axis-aligned box (scene::primitives::box: BoxParams): intersection, surface, uv
// derivatives. CPU twin: src/cpu/primitives/box.rs.
#import shared/geometry
#import shared/sampling
#import shared/types

// Slab method: per axis the distances to its two planes; the ray is inside between
// t_near = max of the per-axis minima and t_far = min of the maxima. Returns (t, axis of
// the face, 0): t_near when the box is ahead, t_far when the ray starts inside.
fn box_intersect(p: BoxParams, ray: Ray, t_max: f32) -> vec3<f32> {
    let inv = safe_inverse(ray.dir);
    let t0 = (p.lo - ray.origin) * inv;
    let t1 = (p.hi - ray.origin) * inv;
    let t_min = min(t0, t1);
    let t_max3 = max(t0, t1);
    let t_near = max(t_min.x, max(t_min.y, t_min.z));
    let t_far = min(t_max3.x, min(t_max3.y, t_max3.z));
    if (t_near <= t_far) {
        if (t_near > 0.0 && t_near < t_max) {
            return vec3<f32>(t_near, f32(argmax3(t_min)), 0.0);
        }
        if (t_far > 0.0 && t_far < t_max) {
            return vec3<f32>(t_far, f32(argmin3(t_max3)), 0.0);
        }
    }
    return vec3<f32>(FAR, 0.0, 0.0);
}

// The hit snapped to the face (the candidate's u is its axis); uv: the face's extent.
fn box_surface(p: BoxParams, ray: Ray, cand: Candidate) -> Surface {
    var s = blank_surface();
    let lo = p.lo;
    let hi = p.hi;
    let axis = u32(cand.u);
    var q = ray.origin + cand.t * ray.dir;
    let upper = q[axis] > 0.5 * (lo[axis] + hi[axis]);
    q[axis] = select(lo[axis], hi[axis], upper);
    var n = vec3<f32>(0.0);
    n[axis] = select(-1.0, 1.0, upper);
    let i = (axis + 1u) % 3u;
    let j = (axis + 2u) % 3u;
    s.p = q;
    s.ng = n;
    s.ns = n;
    s.uv = vec2<f32>((q[i] - lo[i]) / (hi[i] - lo[i]), (q[j] - lo[j]) / (hi[j] - lo[j]));
    // the face coordinate is exact; the others only move the point along the face
    s.err = max(max_abs(lo), max_abs(hi)) * (1.0 / 1048576.0);
    return s;
}

// The face's extent along its two other axes.
fn box_uv_derivatives(p: BoxParams, s: Surface, cand: Candidate) -> array<vec3<f32>, 2> {
    let axis = u32(cand.u);
    let i = (axis + 1u) % 3u;
    let j = (axis + 2u) % 3u;
    var d = array<vec3<f32>, 2>(vec3<f32>(0.0), vec3<f32>(0.0));
    d[0][i] = p.hi[i] - p.lo[i];
    d[1][j] = p.hi[j] - p.lo[j];
    return d;
}
