//! Mirrors `shaders/materials/metal.wgsl`.

use crate::cpu::bsdf::{over_surface, reflect_dir, Scatter, Shading, ABSORBED};
use crate::cpu::sampling::sample_sphere;
use crate::cpu::types::{Hit, Ray};
use crate::scene::materials::metal::Params;

impl Shading for Params {
    /// The mirror direction about the shading normal, perturbed by fuzz x a uniform unit
    /// vector; weight = albedo. A direction under the surface (the shading normal's
    /// horizon), or a perturbation that cancels the reflection, is absorbed; one a shading
    /// normal tilts under the geometric surface only is sent over it. A delta: no density.
    fn scatter(&self, ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
        let side = if hit.front_face { 1.0 } else { -1.0 };
        let v = reflect_dir(ray.dir, side * hit.ns) + self.fuzz * sample_sphere(u);
        let len = v.length();
        let dir = over_surface(v, side, hit);
        // Written as in WGSL, so a NaN length takes the same branch on both backends.
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if !(len > 0.0) || side * v.dot(hit.ns) <= 0.0 || side * dir.dot(hit.ng) <= 0.0 {
            return ABSORBED;
        }
        Scatter {
            ok: true,
            dir: dir / len,
            weight: self.albedo,
            pdf: 0.0,
            delta: true,
        }
    }
}
