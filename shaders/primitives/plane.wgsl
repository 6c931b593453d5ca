// An infinite plane (scene::primitives::plane: PlaneParams): intersection, surface, uv
// derivatives. CPU twin: src/cpu/primitives/plane.rs.
#import shared/geometry
#import shared/sampling
#import shared/types

// Returns (t, 0, 0) (intersect_plane).
fn plane_intersect(p: PlaneParams, ray: Ray, t_max: f32) -> vec3<f32> {
    return vec3<f32>(intersect_plane(p.point, p.normal, ray, t_max), 0.0, 0.0);
}

// The hit projected onto the plane; uv = uv_scale x its coordinates in the normal's
// onb_tangents frame.
fn plane_surface(p: PlaneParams, ray: Ray, cand: Candidate) -> Surface {
    var s = blank_surface();
    let n = p.normal;
    let q = ray.origin + cand.t * ray.dir - p.point;
    let qp = q - dot(q, n) * n;
    s.p = p.point + qp;
    s.ng = n;
    s.ns = n;
    let tb = onb_tangents(n);
    s.uv = p.uv_scale * vec2<f32>(dot(qp, tb[0]), dot(qp, tb[1]));
    s.err = (max_abs(p.point) + max_abs(qp)) * (1.0 / 1048576.0);
    return s;
}

// The frame's axes over the uv scale.
fn plane_uv_derivatives(p: PlaneParams, s: Surface, cand: Candidate) -> array<vec3<f32>, 2> {
    let tb = onb_tangents(p.normal);
    return array<vec3<f32>, 2>(tb[0] / p.uv_scale, tb[1] / p.uv_scale);
}
