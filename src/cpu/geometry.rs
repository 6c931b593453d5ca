//! Mirrors `shaders/shared/geometry.wgsl`: what several primitive types share.

use glam::{Vec2, Vec3, Vec4};

use super::sampling::{onb_tangents, PI};
use super::types::{Ray, Surface, FAR};
use crate::scene::records::{Emitter, Primitive, EDGE_ON_COS};

/// Plane through `point` with unit normal n; a ray parallel to it is a miss, t is finite.
pub fn intersect_plane(point: Vec3, n: Vec3, ray: &Ray, t_max: f32) -> f32 {
    let denom = ray.dir.dot(n);
    let num = -(ray.origin - point).dot(n);
    if num * denom > 0.0 && num.abs() < t_max * denom.abs() {
        return num / denom;
    }
    FAR
}

/// Disk: the plane of unit normal n through `center`, within `radius` of the center.
pub fn intersect_disk(center: Vec3, n: Vec3, radius: f32, ray: &Ray, t_max: f32) -> f32 {
    let t = intersect_plane(center, n, ray, t_max);
    if t < FAR {
        let q = ray.origin + t * ray.dir - center;
        if q.dot(q) <= radius * radius {
            return t;
        }
    }
    FAR
}

/// 1 / d with zero and tiny components first replaced by +-1e-30 (zero taken as +).
pub fn safe_inverse(d: Vec3) -> Vec3 {
    let tiny = Vec3::select(d.cmplt(Vec3::ZERO), Vec3::splat(-1e-30), Vec3::splat(1e-30));
    Vec3::ONE / Vec3::select(d.abs().cmplt(Vec3::splat(1e-30)), tiny, d)
}

/// Index of the largest component (the first of equals).
pub fn argmax3(v: Vec3) -> u32 {
    if v.x >= v.y && v.x >= v.z {
        return 0;
    }
    if v.y >= v.z {
        1
    } else {
        2
    }
}

/// Index of the smallest component (the first of equals).
pub fn argmin3(v: Vec3) -> u32 {
    if v.x <= v.y && v.x <= v.z {
        return 0;
    }
    if v.y <= v.z {
        1
    } else {
        2
    }
}

/// Angle of q about the unit axis n, as a fraction in [0, 1].
pub fn angle_uv(q: Vec3, n: Vec3) -> f32 {
    let tb = onb_tangents(n);
    q.dot(tb[1]).atan2(q.dot(tb[0])) * (0.5 / PI) + 0.5
}

/// Solid-angle pdf of a point drawn uniformly from an area, seen from p; 0 edge-on.
pub fn area_pdf(p: Vec3, x: Vec3, n: Vec3, area: f32) -> f32 {
    let v = x - p;
    let d2 = v.dot(v);
    let c = n.dot(v).abs() / d2.sqrt();
    // Written as in WGSL, so NaN takes the same branch on both backends.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(d2 > 0.0) || !(c >= EDGE_ON_COS) || c * area <= d2 * 1e-30 {
        return 0.0;
    }
    d2 / (c * area)
}

/// The surface a type's `surface` starts from: at 0, facing +z, uv 0, white.
pub fn blank_surface() -> Surface {
    Surface {
        p: Vec3::ZERO,
        ng: Vec3::Z,
        ns: Vec3::Z,
        uv: Vec2::ZERO,
        err: 0.0,
        tangent: Vec4::ZERO,
        uv1: Vec2::ZERO,
        color: Vec4::ONE,
    }
}

/// A light's geometry as its primitive's record, for the type's view to read.
pub fn emitter_shape(e: &Emitter) -> Primitive {
    Primitive {
        tag: e.kind,
        material: 0,
        flags: 0,
        data: 0,
        a: e.a,
        b: e.b,
        c: e.c,
    }
}
