//! Mirrors `shaders/materials/microfacet.wgsl`.

use glam::Vec3;

use crate::cpu::bsdf::{
    density_sample, ggx_d, ggx_lobes_pdf, lobe_prob, luminance, ms_lobe, ms_loss, ms_under,
    over_surface, reflect_dir, sample_ggx_lobes, schlick, smith_g2, Scatter, Shading, ABSORBED,
    ALPHA_SMOOTH,
};
use crate::cpu::sampling::PI;
use crate::cpu::types::{Hit, Ray};
use crate::scene::materials::microfacet::Params;
use crate::scene::records::{MAT_FLAG_ENERGY, MS_GGX_CORRELATED};

/// Probability of sampling the specular lobe: its share by Fresnel at the view angle and
/// the lobes' colours (depends on wo only, so the mixture's pdf is exact).
pub fn spec_prob(p: &Params, cos_o: f32) -> f32 {
    let f = schlick(cos_o, p.ior);
    let mut wd = luminance(p.diffuse) * (1.0 - f);
    if p.flags & MAT_FLAG_ENERGY != 0 && p.alpha >= ALPHA_SMOOTH {
        wd += luminance(p.specular) * ms_loss(MS_GGX_CORRELATED, p.alpha, cos_o);
    }
    lobe_prob(luminance(p.specular) * f, wd)
}

impl Shading for Params {
    /// Cook-Torrance BSDF x cos(theta_i): ks D G2 F / (4 cos_o) + kd (1 - F(cos_i)) (1 -
    /// F(cos_o)) cos_i / pi; the mirror lobe left out when smooth.
    fn eval(&self, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
        let cos_o = n.dot(wo);
        let cos_i = n.dot(wi);
        if cos_o <= 0.0 || cos_i <= 0.0 {
            return Vec3::ZERO;
        }
        let alpha = self.alpha;
        let ior = self.ior;
        let diff = (1.0 - schlick(cos_i, ior)) * (1.0 - schlick(cos_o, ior)) * cos_i / PI;
        if alpha < ALPHA_SMOOTH {
            return self.diffuse * diff;
        }
        let h = (wo + wi).normalize();
        let spec = ggx_d(n.dot(h), alpha) * smith_g2(cos_o, cos_i, alpha) * schlick(wi.dot(h), ior)
            / (4.0 * cos_o);
        if self.flags & MAT_FLAG_ENERGY != 0 {
            let r = (1.0 - ior) / (1.0 + ior);
            let f0 = self.specular * (r * r);
            let under = ms_under(MS_GGX_CORRELATED, alpha, cos_o, cos_i, f0, self.specular);
            let ms = ms_lobe(
                MS_GGX_CORRELATED,
                alpha,
                cos_o,
                cos_i,
                f0 + (self.specular - f0) / 21.0,
            );
            return self.specular * spec + ms + self.diffuse * under * (cos_i / PI);
        }
        self.specular * spec + self.diffuse * diff
    }

    /// The pdf of scatter's directions.
    fn pdf(&self, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        ggx_lobes_pdf(spec_prob(self, n.dot(wo)), self.alpha, n, wo, wi)
    }

    /// The specular lobe (a visible normal, then the mirror direction about it; the
    /// mirror direction itself when smooth) or the diffuse one, chosen by spec_prob;
    /// weight = eval / pdf of the whole mixture.
    fn scatter(&self, ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
        let side = if hit.front_face { 1.0 } else { -1.0 };
        let n = side * hit.ns;
        let wo = -ray.dir;
        let cos_o = n.dot(wo);
        if cos_o <= 0.0 {
            return ABSORBED;
        }
        let p_s = spec_prob(self, cos_o);
        let is_smooth = self.alpha < ALPHA_SMOOTH;
        if is_smooth && u[0] < p_s {
            // the mirror lobe: weight = ks F(cos_o) / p_s
            let wi = over_surface(reflect_dir(ray.dir, n), side, hit);
            if side * wi.dot(hit.ng) <= 0.0 {
                return ABSORBED;
            }
            return Scatter {
                ok: true,
                dir: wi,
                weight: self.specular * (schlick(cos_o, self.ior) / p_s),
                pdf: 0.0,
                delta: true,
            };
        }
        let wi = sample_ggx_lobes(p_s, self.alpha, n, wo, u);
        density_sample(wi, self.eval(n, wo, wi), self.pdf(n, wo, wi), side, hit)
    }
}
