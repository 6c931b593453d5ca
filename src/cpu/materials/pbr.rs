//! Mirrors `shaders/materials/pbr.wgsl`.

use glam::Vec3;

use crate::cpu::bindings::Bindings;
use crate::cpu::bsdf::{
    density_sample, ggx_d, ggx_lobes_pdf, lobe_prob, luminance, sample_ggx_lobes, smith_g2,
    Scatter, Shading, ABSORBED, ALPHA_SMOOTH,
};
use crate::cpu::sampling::PI;
use crate::cpu::textures::{texture_alpha, texture_value};
use crate::cpu::types::{Hit, Ray};
use crate::scene::materials::pbr::Params;
use crate::scene::records::NO_TEXTURE;

/// Fresnel-Schlick of the dielectric layer at cos c: F0 = min(((ior - 1) / (ior + 1))^2
/// specular colour, 1) specular, F90 = specular.
pub fn dielectric_fresnel(p: &Params, c: f32) -> Vec3 {
    let r = (p.ior - 1.0) / (p.ior + 1.0);
    let f0 = (Vec3::splat(r * r) * p.specular_color).min(Vec3::ONE) * p.specular;
    let m = 1.0 - c.clamp(0.0, 1.0);
    f0 + (Vec3::splat(p.specular) - f0) * (m * m * m * m * m)
}

/// Fresnel-Schlick of the metal: F0 = the base colour, F90 = 1.
pub fn metal_fresnel(p: &Params, c: f32) -> Vec3 {
    let m = 1.0 - c.clamp(0.0, 1.0);
    p.base_color + (Vec3::ONE - p.base_color) * (m * m * m * m * m)
}

/// Probability of sampling the GGX lobe: its share at the view angle.
pub fn spec_prob(p: &Params, cos_o: f32) -> f32 {
    let fd = dielectric_fresnel(p, cos_o);
    let metallic = p.metallic;
    let ws = luminance(fd * (1.0 - metallic) + metal_fresnel(p, cos_o) * metallic);
    let wd = (1.0 - p.metallic) * luminance((Vec3::ONE - fd) * p.base_color);
    lobe_prob(ws, wd)
}

impl Shading for Params {
    /// glTF's metallicRoughnessTexture (green scales the roughness, so alpha by its
    /// square; blue the metallic factor) and KHR_materials_specular's specularTexture
    /// (its alpha scales the specular factor).
    fn textures(&self, b: &Bindings, hit: &Hit) -> Self {
        let mut q = *self;
        if self.metallic_roughness_texture != NO_TEXTURE {
            let mr =
                texture_value(b, self.metallic_roughness_texture, hit.uv, hit.p).min(Vec3::ONE);
            q.alpha = (q.alpha * mr.y * mr.y).max(ALPHA_SMOOTH);
            q.metallic *= mr.z;
        }
        if self.specular_texture != NO_TEXTURE {
            q.specular *= texture_alpha(b, self.specular_texture, hit.uv).min(1.0);
        }
        q
    }

    /// BSDF x cos(theta_i) (pbr.wgsl's `pbr_eval`, which says why the base is weighted as
    /// it is): mix((1 - F_d(cos_i)) (1 - F_d(cos_o)) base / pi cos_i + F_d(v . h) S,
    /// F_m(v . h) S, metallic), S = D G2 / (4 cos_o).
    fn eval(&self, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
        let cos_o = n.dot(wo);
        let cos_i = n.dot(wi);
        if cos_o <= 0.0 || cos_i <= 0.0 {
            return Vec3::ZERO;
        }
        let alpha = self.alpha;
        let h = (wo + wi).normalize();
        let vh = wo.dot(h);
        let spec = ggx_d(n.dot(h), alpha) * smith_g2(cos_o, cos_i, alpha) / (4.0 * cos_o);
        let through = (Vec3::ONE - dielectric_fresnel(self, cos_i))
            * (Vec3::ONE - dielectric_fresnel(self, cos_o));
        let dielectric =
            through * self.base_color * (cos_i / PI) + dielectric_fresnel(self, vh) * spec;
        let metallic = self.metallic;
        dielectric * (1.0 - metallic) + metal_fresnel(self, vh) * spec * metallic
    }

    fn pdf(&self, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        ggx_lobes_pdf(spec_prob(self, n.dot(wo)), self.alpha, n, wo, wi)
    }

    /// The GGX lobe or the cosine one, chosen by spec_prob; weight = eval / pdf of the
    /// mixture.
    fn scatter(&self, ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
        let side = if hit.front_face { 1.0 } else { -1.0 };
        let n = side * hit.ns;
        let wo = -ray.dir;
        let cos_o = n.dot(wo);
        if cos_o <= 0.0 {
            return ABSORBED;
        }
        let wi = sample_ggx_lobes(spec_prob(self, cos_o), self.alpha, n, wo, u);
        density_sample(wi, self.eval(n, wo, wi), self.pdf(n, wo, wi), side, hit)
    }
}
