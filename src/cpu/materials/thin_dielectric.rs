//! Mirrors `shaders/materials/thin_dielectric.wgsl`.

use crate::cpu::bsdf::{fresnel_dielectric, mirror_scatter, Scatter, Shading};
use crate::cpu::types::{Hit, Ray};
use crate::scene::materials::thin_dielectric::Params;

/// The sheet's reflectance at cosine c, its inner reflections summed.
pub fn reflectance(c: f32, ior: f32) -> f32 {
    let eta = 1.0 / ior;
    let sin2_t = eta * eta * (1.0 - c * c).max(0.0);
    let mut r = 1.0;
    if sin2_t < 1.0 {
        r = fresnel_dielectric(c, (1.0 - sin2_t).sqrt(), eta);
    }
    let t = 1.0 - r;
    if r < 1.0 {
        r + t * t * r / (1.0 - r * r)
    } else {
        1.0
    }
}

impl Shading for Params {
    /// Reflection with the sheet's reflectance (weight specular), else straight through
    /// (weight tint).
    fn scatter(&self, ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
        let side = if hit.front_face { 1.0 } else { -1.0 };
        let n = side * hit.ns;
        let c = (-ray.dir.dot(n)).clamp(0.0, 1.0);
        if u[0] < reflectance(c, self.ior) {
            return mirror_scatter(ray, hit, side, n, self.specular);
        }
        Scatter {
            ok: true,
            dir: ray.dir,
            weight: self.tint,
            pdf: 0.0,
            delta: true,
        }
    }
}
