// Geometry that several primitive types share (shaders/primitives/): the plane and disk
// tests (a disk is a cylinder's cap), slab helpers, the angle of a point about an axis,
// the solid-angle pdf of area sampling, a blank surface, and an emitter's geometry as its
// primitive's record.
#import shared/sampling
#import shared/types

// Plane through `point` with unit normal n: t = -((o - point) . n) / (d . n). The sign and
// range are tested before dividing (num * denom > 0, |num| < t_max |denom|), so a ray
// parallel to the plane (d . n = 0) is a miss and t is always finite.
fn intersect_plane(point: vec3<f32>, n: vec3<f32>, ray: Ray, t_max: f32) -> f32 {
    let denom = dot(ray.dir, n);
    let num = -dot(ray.origin - point, n);
    if (num * denom > 0.0 && abs(num) < t_max * abs(denom)) {
        return num / denom;
    }
    return FAR;
}

// Disk: the plane of unit normal n through `center`, within `radius` of the center.
fn intersect_disk(center: vec3<f32>, n: vec3<f32>, radius: f32, ray: Ray, t_max: f32) -> f32 {
    let t = intersect_plane(center, n, ray, t_max);
    if (t < FAR) {
        let q = ray.origin + t * ray.dir - center;
        if (dot(q, q) <= radius * radius) {
            return t;
        }
    }
    return FAR;
}

// 1 / d, with zero and tiny components first replaced by +-1e-30 (sign kept, zero taken as
// +), so that slab distances are finite and never 0 * inf = NaN.
fn safe_inverse(d: vec3<f32>) -> vec3<f32> {
    let tiny = select(vec3<f32>(1e-30), vec3<f32>(-1e-30), d < vec3<f32>(0.0));
    return 1.0 / select(d, tiny, abs(d) < vec3<f32>(1e-30));
}

// Index of the largest component (the first of equals).
fn argmax3(v: vec3<f32>) -> u32 {
    if (v.x >= v.y && v.x >= v.z) {
        return 0u;
    }
    return select(2u, 1u, v.y >= v.z);
}

// Index of the smallest component (the first of equals).
fn argmin3(v: vec3<f32>) -> u32 {
    if (v.x <= v.y && v.x <= v.z) {
        return 0u;
    }
    return select(2u, 1u, v.y <= v.z);
}

// Angle of q about the unit axis n, in the onb_tangents frame, as a fraction in [0, 1].
fn angle_uv(q: vec3<f32>, n: vec3<f32>) -> f32 {
    let tb = onb_tangents(n);
    return atan2(dot(q, tb[1]), dot(q, tb[0])) * (0.5 / PI) + 0.5;
}

// Solid-angle pdf of a point x with unit normal n drawn uniformly from an area, seen from
// p: |x - p|^2 / (|cos| area); 0 when seen edge-on (EDGE_ON_COS, types.wgsl's constants:
// below this cosine the light gets pdf 0 and no sample, never an unbounded weight).
fn area_pdf(p: vec3<f32>, x: vec3<f32>, n: vec3<f32>, area: f32) -> f32 {
    let v = x - p;
    let d2 = dot(v, v);
    let c = abs(dot(n, v)) / sqrt(d2);
    if (!(d2 > 0.0) || !(c >= EDGE_ON_COS) || c * area <= d2 * 1e-30) {
        return 0.0;
    }
    return d2 / (c * area);
}

// The surface a type's NAME_surface starts from: at 0, facing +z, uv 0, white.
fn blank_surface() -> Surface {
    return Surface(vec3<f32>(0.0), vec3<f32>(0.0, 0.0, 1.0), vec3<f32>(0.0, 0.0, 1.0), vec2<f32>(0.0), 0.0, vec4<f32>(0.0), vec2<f32>(0.0), vec4<f32>(1.0));
}

// A light's geometry as its primitive's record (its kind is the primitive's tag, its
// places the primitive's, in world space), for the type's view to read.
fn emitter_shape(e: Emitter) -> Primitive {
    return Primitive(e.kind, 0u, 0u, 0u, e.a, e.b, e.c);
}
