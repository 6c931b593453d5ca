//! Mirrors `shaders/materials/metal.wgsl`.

use crate::cpu::bsdf::{reflect_dir, Scatter, Shading, ABSORBED};
use crate::cpu::sampling::sample_sphere;
use crate::cpu::types::{Hit, Ray};
use crate::scene::materials::metal::Params;

impl Shading for Params {
    /// The mirror direction about the shading normal, perturbed by fuzz x a uniform unit
    /// vector; weight = albedo. A direction under the geometric surface (or a
    /// perturbation that cancels the reflection) is absorbed. A delta: no density.
    fn scatter(&self, ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
        let side = if hit.front_face { 1.0 } else { -1.0 };
        let v = reflect_dir(ray.dir, side * hit.ns) + self.fuzz * sample_sphere(u);
        let len = v.length();
        // Written as in WGSL, so a NaN length takes the same branch on both backends.
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if !(len > 0.0) || side * v.dot(hit.ng) <= 0.0 {
            return ABSORBED;
        }
        Scatter {
            ok: true,
            dir: v / len,
            weight: self.albedo,
            pdf: 0.0,
            delta: true,
        }
    }
}
