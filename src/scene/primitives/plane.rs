//! An infinite plane: `type = "plane"`; unbounded, so tested on its own before the BVH.
//! Intersection and surface: `shaders/primitives/plane.wgsl`, CPU twin
//! `cpu/primitives/plane.rs`.

use glam::Vec3;

use super::common::{unit, Shape};
use crate::scene::bvh::Aabb;
use crate::scene::materials::common::material_view;

material_view! {
    /// Its places in the record.
    pub struct Params("PlaneParams") of Primitive {
        point: vec3 = a,
        /// uv = this x the coordinates in a tangent frame.
        uv_scale: f32 = a.w,
        /// Unit; the front side's.
        normal: vec3 = b,
    }
}

impl Shape for Params {
    const BOUNDED: bool = false;

    fn bounds(&self) -> Aabb {
        Aabb {
            lo: Vec3::NEG_INFINITY,
            hi: Vec3::INFINITY,
        }
    }

    /// Planes are never lights.
    fn area(&self) -> f32 {
        0.0
    }

    fn usable(&self) -> bool {
        unit(self.normal)
    }
}
