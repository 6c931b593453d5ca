//! A sphere: `type = "sphere"` (center, radius). Intersection, surface and sampling as a
//! light: `shaders/primitives/sphere.wgsl`, CPU twin `cpu/primitives/sphere.rs`.

use glam::{Mat3, Vec3};

use super::common::Shape;
use crate::scene::bvh::Aabb;
use crate::scene::materials::common::material_view;

material_view! {
    /// Its places in the record.
    pub struct Params("SphereParams") of Primitive {
        center: vec3 = a,
        radius: f32 = a.w,
    }
}

impl Shape for Params {
    const LIGHT: bool = true;

    fn bounds(&self) -> Aabb {
        Aabb {
            lo: self.center - self.radius,
            hi: self.center + self.radius,
        }
    }

    fn area(&self) -> f32 {
        4.0 * std::f32::consts::PI * self.radius * self.radius
    }

    fn usable(&self) -> bool {
        self.radius > 0.0
    }

    fn light(&self, m: Mat3, t: Vec3, s: f32) -> Option<Self> {
        Some(Params {
            center: m * self.center + t,
            radius: self.radius * s,
        })
    }
}
