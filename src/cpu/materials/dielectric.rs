//! Mirrors `shaders/materials/dielectric.wgsl`.

use crate::cpu::bsdf::{fresnel_dielectric, reflect_dir, Scatter, Shading};
use crate::cpu::types::{Hit, Ray};
use crate::scene::materials::dielectric::Params;

impl Shading for Params {
    /// Snell refraction (eta = 1 / ior entering, ior leaving, the normal turned toward
    /// the incoming ray), total internal reflection, reflection with the exact Fresnel
    /// probability; weight = tint, times the Beer-Lambert transmittance exp(-absorption x
    /// distance) for a segment that ran inside. Deltas only.
    fn scatter(&self, ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
        let entering = hit.front_face;
        let n = if entering { hit.ns } else { -hit.ns };
        let eta = if entering { 1.0 / self.ior } else { self.ior };
        let cos_i = (-ray.dir.dot(n)).clamp(0.0, 1.0);
        let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
        let mut weight = self.tint;
        if !entering {
            weight *= (-self.absorption * (hit.p - ray.origin).length()).exp();
        }
        let reflected = Scatter {
            ok: true,
            dir: reflect_dir(ray.dir, n),
            weight,
            pdf: 0.0,
            delta: true,
        };
        if sin2_t >= 1.0 {
            return reflected;
        }
        let cos_t = (1.0 - sin2_t).sqrt();
        if u[0] < fresnel_dielectric(cos_i, cos_t, eta) {
            return reflected;
        }
        Scatter {
            ok: true,
            dir: (eta * ray.dir + (eta * cos_i - cos_t) * n).normalize(),
            weight,
            pdf: 0.0,
            delta: true,
        }
    }
}
