//! Mirrors the non-record structs of `shaders/shared/types.wgsl`.

use glam::{Vec2, Vec3, Vec4};

pub use crate::scene::records::{FAR, NO_HIT};

/// WGSL's `.xyz` (and `.rgb`) swizzle of a record's vec4.
#[inline]
pub fn xyz(v: [f32; 4]) -> Vec3 {
    Vec3::new(v[0], v[1], v[2])
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
}

/// A hit in a primitive's own space (each type's `surface`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Surface {
    pub p: Vec3,
    pub ng: Vec3,
    pub ns: Vec3,
    pub uv: Vec2,
    pub err: f32,
    pub tangent: Vec4,
    /// A triangle's second uv set (`PRIM_FLAG_UV1`) and vertex colour
    /// (`PRIM_FLAG_COLORS`).
    pub uv1: Vec2,
    pub color: Vec4,
}

/// A point sampled on a light with a surface (each such type's `light_sample`): the
/// point, its solid-angle pdf (0: none), its (u, v) as a hit's candidate would have them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightPoint {
    pub x: Vec3,
    pub pdf: f32,
    pub uv: Vec2,
}

/// Closest-hit search result: distance, primitive, primitive-specific parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    pub t: f32,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
    /// The instance the primitive was hit through (`NO_HIT`: none; `prim` is then its
    /// group's).
    pub inst: u32,
}

/// Shading record of the closest hit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    pub p: Vec3,
    /// Geometric normal on the front side.
    pub ng: Vec3,
    /// Shading normal, on the same side as `ng` (interpolated vertex normals, else `ng`;
    /// then as a normal or bump map turns it).
    pub ns: Vec3,
    /// The shading normal before a normal or bump map turned it.
    pub unmapped: Vec3,
    /// uv set 0 in `.xy`, set 1 in `.zw` (set 0's where the surface has one set).
    pub uv: Vec4,
    pub front_face: bool,
    pub material: u32,
    /// Bound on the absolute error of each coordinate of p.
    pub err: f32,
    /// Interpolated vertex tangent (xyz, not unit) and bitangent sign (w) of a triangle
    /// with tangents, else zero.
    pub tangent: Vec4,
    /// Interpolated vertex colour (linear rgb, alpha) of a triangle with vertex colours,
    /// else 1.
    pub color: Vec4,
    /// The derivatives of p along the first uv set (`surface_uv_derivatives`), for a
    /// surface with a bump map; else zero.
    pub dpdu: Vec3,
    pub dpdv: Vec3,
}
