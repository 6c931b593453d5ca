//! Mirrors `shaders/materials/conductor.wgsl`.

use glam::Vec3;

use crate::cpu::bsdf::{
    density_sample, fresnel_conductor, mf_d, mf_g1, mf_pdf_visible, mf_sample_visible,
    mirror_scatter, ms_alpha, ms_lobe, ms_loss, tangent_frame, Microfacet, Scatter, Shading,
    ABSORBED, ALPHA_SMOOTH,
};
use crate::cpu::sampling::{sample_cosine_hemisphere, PI};
use crate::cpu::types::{Hit, Ray};
use crate::scene::materials::conductor::Params;
use crate::scene::records::{MAT_FLAG_ENERGY, MS_BECKMANN_SEPARABLE, MS_GGX_SEPARABLE};

/// Its microfacet distribution.
pub fn microfacet(p: &Params) -> Microfacet {
    Microfacet {
        alpha_u: p.alpha_u,
        alpha_v: p.alpha_v,
        beckmann: p.beckmann > 0.5,
    }
}

/// The table variant of its compensation.
fn variant(p: &Params) -> u32 {
    if p.beckmann > 0.5 {
        MS_BECKMANN_SEPARABLE
    } else {
        MS_GGX_SEPARABLE
    }
}

/// The probability of sampling the energy compensation's lobe (0 without it).
pub fn ms_prob(p: &Params, cos_o: f32) -> f32 {
    if p.flags & MAT_FLAG_ENERGY != 0 {
        ms_loss(variant(p), ms_alpha(p.alpha_u, p.alpha_v), cos_o)
    } else {
        0.0
    }
}

/// The compensation lobe x cos_i (0 without it).
pub fn ms(p: &Params, cos_o: f32, cos_i: f32) -> Vec3 {
    if p.flags & MAT_FLAG_ENERGY == 0 {
        return Vec3::ZERO;
    }
    let alpha = ms_alpha(p.alpha_u, p.alpha_v);
    ms_lobe(variant(p), alpha, cos_o, cos_i, p.specular * p.fresnel_avg)
}

/// wo and wi in the frame of the tangent about n, and their half vector.
fn local(p: &Params, n: Vec3, wo: Vec3, wi: Vec3) -> (Vec3, Vec3) {
    let tb = tangent_frame(n, p.tangent);
    let lo = Vec3::new(wo.dot(tb[0]), wo.dot(tb[1]), n.dot(wo));
    let li = Vec3::new(wi.dot(tb[0]), wi.dot(tb[1]), n.dot(wi));
    (lo, li)
}

impl Shading for Params {
    /// specular x F(wo . h) D(h) G1(wo) G1(wi) / (4 cos_o); 0 when smooth.
    fn eval(&self, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
        let cos_o = n.dot(wo);
        let cos_i = n.dot(wi);
        if cos_o <= 0.0 || cos_i <= 0.0 || self.alpha_u.max(self.alpha_v) < ALPHA_SMOOTH {
            return Vec3::ZERO;
        }
        let m = microfacet(self);
        let (lo, li) = local(self, n, wo, wi);
        let h = (lo + li).normalize();
        let g = mf_g1(&m, lo, h) * mf_g1(&m, li, h);
        self.specular
            * fresnel_conductor(lo.dot(h), self.eta, self.k)
            * (mf_d(&m, h) * g / (4.0 * cos_o))
            + ms(self, cos_o, cos_i)
    }

    /// D(h) G1(wo) / (4 cos_o).
    fn pdf(&self, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        let cos_o = n.dot(wo);
        let cos_i = n.dot(wi);
        if cos_o <= 0.0 || cos_i <= 0.0 || self.alpha_u.max(self.alpha_v) < ALPHA_SMOOTH {
            return 0.0;
        }
        let m = microfacet(self);
        let (lo, li) = local(self, n, wo, wi);
        let h = (lo + li).normalize();
        let pdf = mf_pdf_visible(&m, lo, h) / (4.0 * lo.dot(h));
        let p_ms = ms_prob(self, cos_o);
        (1.0 - p_ms) * pdf + p_ms * cos_i / PI
    }

    /// The mirror direction when smooth, else the mirror about a visible normal.
    fn scatter(&self, ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
        let side = if hit.front_face { 1.0 } else { -1.0 };
        let n = side * hit.ns;
        let wo = -ray.dir;
        let cos_o = n.dot(wo);
        if cos_o <= 0.0 {
            return ABSORBED;
        }
        if self.alpha_u.max(self.alpha_v) < ALPHA_SMOOTH {
            let weight = self.specular * fresnel_conductor(cos_o, self.eta, self.k);
            return mirror_scatter(ray, hit, side, n, weight);
        }
        let tb = tangent_frame(n, self.tangent);
        let lo = Vec3::new(wo.dot(tb[0]), wo.dot(tb[1]), cos_o);
        // the compensation's cosine lobe with ms_prob, u.x reused
        let p_ms = ms_prob(self, cos_o);
        if u[0] < p_ms {
            let wc = sample_cosine_hemisphere(n, [u[0] / p_ms, u[1]]);
            return density_sample(wc, self.eval(n, wo, wc), self.pdf(n, wo, wc), side, hit);
        }
        let h_l = mf_sample_visible(&microfacet(self), lo, [(u[0] - p_ms) / (1.0 - p_ms), u[1]]);
        let h = h_l.x * tb[0] + h_l.y * tb[1] + h_l.z * n;
        let wi = (2.0 * wo.dot(h) * h - wo).normalize();
        density_sample(wi, self.eval(n, wo, wi), self.pdf(n, wo, wi), side, hit)
    }
}
