//! A triangle: `type = "triangle"`, `polygon`, `tetrahedron` and meshes' faces, with their
//! vertex attributes in `shape_data` (`PRIM_FLAG_ATTRIBUTES` and the flags after it).
//! Intersection, surface and sampling as a light: `shaders/primitives/triangle.wgsl`, CPU
//! twin `cpu/primitives/triangle.rs`.

use glam::{Mat3, Vec3};

use super::common::Shape;
use crate::scene::bvh::Aabb;
use crate::scene::materials::common::material_view;

material_view! {
    /// Its places in the record: the vertices, and where its attributes are.
    pub struct Params("TriangleParams") of Primitive {
        v0: vec3 = a,
        v1: vec3 = b,
        v2: vec3 = c,
        flags: u32 = flags,
        data: u32 = data,
    }
}

impl Shape for Params {
    const LIGHT: bool = true;
    const SHAPE_DATA: bool = true;

    fn bounds(&self) -> Aabb {
        Aabb {
            lo: self.v0.min(self.v1).min(self.v2),
            hi: self.v0.max(self.v1).max(self.v2),
        }
    }

    fn area(&self) -> f32 {
        0.5 * (self.v1 - self.v0).cross(self.v2 - self.v0).length()
    }

    fn light(&self, m: Mat3, t: Vec3, _s: f32) -> Option<Self> {
        Some(Params {
            v0: m * self.v0 + t,
            v1: m * self.v1 + t,
            v2: m * self.v2 + t,
            flags: 0,
            data: 0,
        })
    }
}
