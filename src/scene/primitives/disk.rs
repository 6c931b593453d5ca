//! A disk: `type = "disk"`. Intersection, surface and sampling as a light:
//! `shaders/primitives/disk.wgsl`, CPU twin `cpu/primitives/disk.rs`.

use glam::{Mat3, Vec3};

use super::common::{disk_extent, unit, Shape};
use crate::scene::bvh::Aabb;
use crate::scene::materials::common::material_view;

material_view! {
    /// Its places in the record.
    pub struct Params("DiskParams") of Primitive {
        center: vec3 = a,
        radius: f32 = a.w,
        /// Unit; the front side's.
        normal: vec3 = b,
    }
}

impl Shape for Params {
    const LIGHT: bool = true;

    fn bounds(&self) -> Aabb {
        let e = disk_extent(self.normal, self.radius);
        Aabb {
            lo: self.center - e,
            hi: self.center + e,
        }
    }

    fn area(&self) -> f32 {
        std::f32::consts::PI * self.radius * self.radius
    }

    fn usable(&self) -> bool {
        unit(self.normal) && self.radius > 0.0
    }

    fn light(&self, m: Mat3, t: Vec3, s: f32) -> Option<Self> {
        Some(Params {
            center: m * self.center + t,
            radius: self.radius * s,
            normal: (m * self.normal).normalize(),
        })
    }
}
