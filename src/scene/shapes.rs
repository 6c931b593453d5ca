//! Host geometry of each primitive type: bounds, surface area, whether a record is usable
//! in f32, and polygon normals. The flattener, the light list and validation share these;
//! the intersection tests themselves live in `shaders/shared/intersect.wgsl` and its CPU
//! twin `cpu/intersect.rs`.

use glam::{Mat3, Vec3};

use super::bvh::Aabb;
use super::records::{self, Primitive};

/// Half-extent along each world axis of a disk of radius r with unit normal n.
pub fn disk_extent(n: Vec3, r: f32) -> Vec3 {
    r * (Vec3::ONE - n * n).max(Vec3::ZERO).powf(0.5)
}

/// Object-space bounds of a bounded primitive.
pub fn local_bounds(p: &Primitive) -> Aabb {
    let (a, b, c) = (
        Vec3::from_slice(&p.a),
        Vec3::from_slice(&p.b),
        Vec3::from_slice(&p.c),
    );
    let r = p.a[3];
    let (lo, hi) = match p.tag {
        records::PRIM_SPHERE => (a - r, a + r),
        records::PRIM_TRIANGLE => (a.min(b).min(c), a.max(b).max(c)),
        records::PRIM_BOX => (a, b),
        records::PRIM_CYLINDER => {
            let e = disk_extent((b - a).normalize(), r);
            (a.min(b) - e, a.max(b) + e)
        }
        records::PRIM_DISK => {
            let e = disk_extent(b, r);
            (a - e, a + e)
        }
        _ => (Vec3::ZERO, Vec3::ZERO),
    };
    Aabb { lo, hi }
}

/// World-space bounds: transformed primitives bound the eight corners of their object box.
pub fn world_bounds(p: &Primitive, shape_data: &[[f32; 4]]) -> Aabb {
    let local = local_bounds(p);
    if p.flags & records::PRIM_FLAG_TRANSFORM == 0 {
        return local;
    }
    let d = p.data as usize + 3;
    let rows = [0, 1, 2].map(|r| glam::Vec4::from_array(shape_data[d + r]));
    let mut out = Aabb {
        lo: Vec3::splat(f32::MAX),
        hi: Vec3::splat(f32::MIN),
    };
    for k in 0..8 {
        let corner = Vec3::select(
            glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0),
            local.hi,
            local.lo,
        )
        .extend(1.0);
        let q = Vec3::new(
            rows[0].dot(corner),
            rows[1].dot(corner),
            rows[2].dot(corner),
        );
        out.lo = out.lo.min(q);
        out.hi = out.hi.max(q);
    }
    out
}

/// Surface area of a primitive in world space (planes: 0, they are never emitters). A
/// transformed primitive's area is its object-space area times |det|^(2/3), exact for
/// similarities and an estimate otherwise.
pub fn primitive_area(p: &Primitive, shape_data: &[[f32; 4]]) -> f32 {
    use std::f32::consts::PI;
    let (a, b, c) = (
        Vec3::from_slice(&p.a),
        Vec3::from_slice(&p.b),
        Vec3::from_slice(&p.c),
    );
    let r = p.a[3];
    let local = match p.tag {
        records::PRIM_SPHERE => 4.0 * PI * r * r,
        records::PRIM_TRIANGLE => 0.5 * (b - a).cross(c - a).length(),
        records::PRIM_BOX => {
            let e = b - a;
            2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
        }
        records::PRIM_CYLINDER => {
            let caps = if p.flags & records::PRIM_FLAG_CAPS != 0 {
                2.0 * PI * r * r
            } else {
                0.0
            };
            2.0 * PI * r * (b - a).length() + caps
        }
        records::PRIM_DISK => PI * r * r,
        _ => 0.0,
    };
    if p.flags & records::PRIM_FLAG_TRANSFORM == 0 {
        return local;
    }
    let d = p.data as usize + 3;
    let m = Mat3::from_cols(
        Vec3::from_slice(&shape_data[d]),
        Vec3::from_slice(&shape_data[d + 1]),
        Vec3::from_slice(&shape_data[d + 2]),
    );
    local * m.determinant().abs().powf(2.0 / 3.0)
}

/// Whether a primitive's record, and its transform and bounds, are usable in f32: finite,
/// with non-zero sizes and unit normals. A valid scene can still fail this under an extreme
/// transform (a scale that underflows or overflows f32, a matrix that is singular in f32).
pub fn record_ok(p: &Primitive, shape_data: &[[f32; 4]]) -> bool {
    let (a, b) = (Vec3::from_slice(&p.a), Vec3::from_slice(&p.b));
    let unit = |n: Vec3| (n.length() - 1.0).abs() < 1e-3;
    let finite = [p.a, p.b, p.c].iter().flatten().all(|x| x.is_finite());
    let shape = match p.tag {
        records::PRIM_SPHERE => p.a[3] > 0.0,
        records::PRIM_PLANE => unit(b),
        records::PRIM_DISK => unit(b) && p.a[3] > 0.0,
        records::PRIM_BOX => a.cmplt(b).all(),
        records::PRIM_CYLINDER => (b - a).length().is_normal() && p.a[3] > 0.0,
        _ => true,
    };
    let transform = p.flags & records::PRIM_FLAG_TRANSFORM == 0
        || shape_data[p.data as usize..][..records::TRANSFORM_ENTRIES as usize]
            .iter()
            .flatten()
            .all(|x| x.is_finite());
    let bounded = p.tag == records::PRIM_PLANE || {
        let bb = world_bounds(p, shape_data);
        bb.lo.is_finite() && bb.hi.is_finite()
    };
    finite && shape && transform && bounded
}

/// Area-weighted normal of a planar polygon (Newell's method): length = 2 x area.
pub fn polygon_normal(pts: &[Vec3]) -> Vec3 {
    let mut n = Vec3::ZERO;
    for i in 1..pts.len() - 1 {
        n += (pts[i] - pts[0]).cross(pts[i + 1] - pts[0]);
    }
    n
}
