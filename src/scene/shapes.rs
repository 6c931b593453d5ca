//! Host geometry of primitives in world space: bounds, surface area, whether a record is
//! usable in f32, and polygon normals. The flattener, the light list and validation share
//! these; each type's own answers (in its own space) are its module's
//! (`scene::primitives`).

use glam::{Mat3, Vec3};

use super::bvh::Aabb;
use super::primitives::{self, PrimitiveKind};
use super::records::{self, Primitive};

/// Object-space bounds of a bounded primitive (its type's answer).
pub fn local_bounds(p: &Primitive) -> Aabb {
    primitives::local_bounds(p)
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
    let local = primitives::local_area(p);
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
    let finite = [p.a, p.b, p.c].iter().flatten().all(|x| x.is_finite());
    let shape = primitives::shape_ok(p);
    let transform = p.flags & records::PRIM_FLAG_TRANSFORM == 0
        || shape_data[p.data as usize..][..records::TRANSFORM_ENTRIES as usize]
            .iter()
            .flatten()
            .all(|x| x.is_finite());
    let unbounded = PrimitiveKind::from_tag(p.tag).is_some_and(|k| !k.bounded());
    let bounded = unbounded || {
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
