//! Mirrors `shaders/materials/null.wgsl`: a boundary with no surface; straight on.

use glam::Vec3;

use crate::cpu::bsdf::{Scatter, Shading};
use crate::cpu::types::{Hit, Ray};
use crate::scene::materials::null::Params;

impl Shading for Params {
    /// Straight on, weight 1, a delta.
    fn scatter(&self, ray: &Ray, _: &Hit, _: [f32; 2]) -> Scatter {
        Scatter {
            ok: true,
            dir: ray.dir,
            weight: Vec3::ONE,
            pdf: 0.0,
            delta: true,
        }
    }
}
