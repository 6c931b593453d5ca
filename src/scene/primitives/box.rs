//! An axis-aligned box: `type = "box"` (in its own space when transformed). Intersection
//! and surface: `shaders/primitives/box.wgsl`, CPU twin `cpu/primitives/box.rs`.

use super::common::Shape;
use crate::scene::bvh::Aabb;
use crate::scene::materials::common::material_view;

material_view! {
    /// Its places in the record.
    pub struct Params("BoxParams") of Primitive {
        lo: vec3 = a,
        hi: vec3 = b,
    }
}

impl Shape for Params {
    fn bounds(&self) -> Aabb {
        Aabb {
            lo: self.lo,
            hi: self.hi,
        }
    }

    fn area(&self) -> f32 {
        let e = self.hi - self.lo;
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    fn usable(&self) -> bool {
        self.lo.cmplt(self.hi).all()
    }
}
