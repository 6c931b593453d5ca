//! Mirrors `shaders/materials/lambertian.wgsl` (`lambertian_scatter` is `scatter`, ...).

use glam::Vec3;

use crate::cpu::bsdf::{over_surface, Scatter, Shading, ABSORBED};
use crate::cpu::sampling::{sample_cosine_hemisphere, PI};
use crate::cpu::types::{Hit, Ray};
use crate::scene::materials::lambertian::Params;

impl Shading for Params {
    /// Cosine-weighted about the shading normal on the side the ray came from; a
    /// direction a shading normal tilts under the geometric surface is sent over it
    /// (`over_surface`), its pdf the drawn one's. Weight = albedo exactly.
    fn scatter(&self, _: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
        let side = if hit.front_face { 1.0 } else { -1.0 };
        let drawn = sample_cosine_hemisphere(side * hit.ns, u);
        let dir = over_surface(drawn, side, hit);
        if side * dir.dot(hit.ng) <= 0.0 {
            return ABSORBED;
        }
        Scatter {
            ok: true,
            dir,
            weight: self.albedo,
            pdf: (side * hit.ns).dot(drawn) / PI,
            delta: false,
        }
    }

    /// albedo / pi x cos.
    fn eval(&self, n: Vec3, _: Vec3, wi: Vec3) -> Vec3 {
        self.albedo * (n.dot(wi).max(0.0) / PI)
    }

    fn pdf(&self, n: Vec3, _: Vec3, wi: Vec3) -> f32 {
        n.dot(wi).max(0.0) / PI
    }
}
