//! A finite cylinder: `type = "cylinder"`, closed by two disks with `PRIM_FLAG_CAPS`.
//! Intersection and surface: `shaders/primitives/cylinder.wgsl`, CPU twin
//! `cpu/primitives/cylinder.rs`.

use std::f32::consts::PI;

use super::common::{disk_extent, Shape};
use crate::scene::bvh::Aabb;
use crate::scene::materials::common::material_view;
use crate::scene::records::PRIM_FLAG_CAPS;

material_view! {
    /// Its places in the record.
    pub struct Params("CylinderParams") of Primitive {
        /// The centers of its end disks.
        base: vec3 = a,
        top: vec3 = b,
        radius: f32 = a.w,
        /// `PRIM_FLAG_CAPS`: closed.
        flags: u32 = flags,
    }
}

impl Shape for Params {
    fn bounds(&self) -> Aabb {
        let e = disk_extent((self.top - self.base).normalize(), self.radius);
        Aabb {
            lo: self.base.min(self.top) - e,
            hi: self.base.max(self.top) + e,
        }
    }

    fn area(&self) -> f32 {
        let r = self.radius;
        let caps = if self.flags & PRIM_FLAG_CAPS != 0 {
            2.0 * PI * r * r
        } else {
            0.0
        };
        2.0 * PI * r * (self.top - self.base).length() + caps
    }

    fn usable(&self) -> bool {
        (self.top - self.base).length().is_normal() && self.radius > 0.0
    }
}
