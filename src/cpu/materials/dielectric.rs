//! Mirrors `shaders/materials/dielectric.wgsl`.

use glam::Vec3;

use crate::cpu::bsdf::{
    fresnel_dielectric, ggx_d, mf_d, mf_g1, mf_sample_visible, ms_alpha, ms_dielectric_albedo,
    ms_dielectric_lobe, ms_dielectric_split, reflect_dir, sample_ggx_vndf, smith_g2, smith_lambda,
    tangent_frame, Microfacet, Scatter, Shading, ABSORBED, ALPHA_SMOOTH,
};
use crate::cpu::sampling::{onb_tangents, sample_cosine_hemisphere, PI};
use crate::cpu::types::{Hit, Ray};
use crate::scene::materials::dielectric::{self, Params};
use crate::scene::records::{
    MAT_FLAG_ENERGY, MS_DIELECTRIC_BECKMANN_CORRELATED, MS_DIELECTRIC_GGX_CORRELATED,
};

impl Shading for Params {
    /// Rough glass: specular (reflected) or tint (transmitted) x BSDF x
    /// |cos| (`rough_lobes`); 0 for the deltas.
    fn eval(&self, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
        if !has_density(self) {
            return Vec3::ZERO;
        }
        let tint = if n.dot(wi) > 0.0 {
            self.specular
        } else {
            self.tint
        };
        tint * lobes(self, n, wo, wi, eta(self)).0
    }

    fn pdf(&self, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        if !has_density(self) {
            return 0.0;
        }
        lobes(self, n, wo, wi, eta(self)).1
    }

    /// Snell refraction (eta = 1 / ior entering, ior leaving, the normal turned toward
    /// the incoming ray), total internal reflection, reflection with the exact Fresnel
    /// probability; weight = specular (reflected) or tint (refracted). Deltas when
    /// smooth; rough glass by `rough_scatter`. (Absorption inside is a medium.)
    fn scatter(&self, ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
        let entering = hit.front_face;
        let n = if entering { hit.ns } else { -hit.ns };
        let eta = if entering { 1.0 / self.ior } else { self.ior };
        if self.alpha.max(self.alpha_v) >= ALPHA_SMOOTH {
            return rough_scatter(self, ray, hit, n, eta, u);
        }
        let cos_i = (-ray.dir.dot(n)).clamp(0.0, 1.0);
        let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
        let reflected = Scatter {
            ok: true,
            dir: reflect_dir(ray.dir, n),
            weight: self.specular,
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
            weight: self.tint,
            pdf: 0.0,
            delta: true,
        }
    }
}

/// The exact Fresnel reflectance at cosine c > 0 on the side of relative index eta (1
/// under total internal reflection).
pub fn fresnel(c: f32, eta: f32) -> f32 {
    let sin2_t = eta * eta * (1.0 - c * c).max(0.0);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    fresnel_dielectric(c, (1.0 - sin2_t).sqrt(), eta)
}

/// The probability of sampling reflection off rough glass seen at cos_o: the mean
/// surface's Fresnel reflectance, kept in [0.1, 0.9].
pub fn reflect_prob(cos_o: f32, eta: f32) -> f32 {
    fresnel(cos_o, eta).clamp(0.1, 0.9)
}

/// The microfacet normal of wo and wi about n (wo's side, eta = eta_o / eta_i): the half
/// vector of a reflection, the generalized eta wo + wi of a refraction, on n's side;
/// zero when none is.
pub fn half(n: Vec3, wo: Vec3, wi: Vec3, eta: f32) -> Vec3 {
    let h = if n.dot(wi) > 0.0 {
        wo + wi
    } else {
        eta * wo + wi
    };
    let len = h.length();
    if len == 0.0 {
        return Vec3::ZERO;
    }
    let h = h / len;
    if h.dot(n) > 0.0 {
        h
    } else {
        -h
    }
}

/// Rough glass's microfacets (dielectric.wgsl's `dielectric_microfacet`).
pub fn microfacet(p: &Params) -> Microfacet {
    Microfacet {
        alpha_u: p.alpha,
        alpha_v: p.alpha_v,
        beckmann: p.beckmann > 0.5,
    }
}

/// Whether rough glass is other than isotropic GGX (dielectric.wgsl's
/// `dielectric_general`).
pub fn general(p: &Params) -> bool {
    p.beckmann > 0.5 || p.alpha != p.alpha_v
}

/// Rough glass toward wi: (BSDF x |cos(theta_i)|, the pdf of `rough_scatter`'s
/// directions), computed together. BSDF (D, Smith's height-correlated G2, exact F):
/// reflection F D G2 / (4 cos_o); refraction, for radiance, eta^2 (1 - F) D G2 |wi . h|
/// |wo . h| / ((wi . h + eta wo . h)^2 cos_o). pdf: the visible normal's density through
/// the reflection (probability `reflect_prob`, 1 where h reflects totally) or the
/// refraction (the rest).
pub fn rough_lobes(p: &Params, n: Vec3, wo: Vec3, wi: Vec3, eta: f32) -> (f32, f32) {
    let cos_o = n.dot(wo);
    let cos_i = n.dot(wi);
    let h = half(n, wo, wi, eta);
    let oh = wo.dot(h);
    let ih = wi.dot(h);
    if cos_o <= 0.0 || cos_i == 0.0 || oh <= 0.0 || ih * cos_i <= 0.0 {
        return (0.0, 0.0);
    }
    let (d, g2, visible) = if general(p) {
        let m = microfacet(p);
        let tb = tangent_frame(n, p.tangent);
        let lh = Vec3::new(h.dot(tb[0]), h.dot(tb[1]), h.dot(n));
        let g_o = mf_g1(&m, Vec3::new(wo.dot(tb[0]), wo.dot(tb[1]), cos_o), lh);
        let g_i = mf_g1(&m, Vec3::new(wi.dot(tb[0]), wi.dot(tb[1]), cos_i), lh);
        let d = mf_d(&m, lh);
        // 1 / (1 + Lambda(wo) + Lambda(wi)), Lambda = 1 / G1 - 1
        let g2 = if g_o * g_i > 0.0 {
            g_o * g_i / (g_o + g_i - g_o * g_i)
        } else {
            0.0
        };
        (d, g2, d * g_o / cos_o)
    } else {
        let alpha = p.alpha;
        let d = ggx_d(n.dot(h), alpha);
        let g2 = smith_g2(cos_o, cos_i.abs(), alpha);
        (d, g2, d / ((1.0 + smith_lambda(cos_o, alpha)) * cos_o))
    };
    let f = fresnel(oh, eta);
    let p_r = reflect_prob(cos_o, eta);
    if cos_i > 0.0 {
        let tir = eta * eta * (1.0 - oh * oh) >= 1.0;
        let p = if tir { 1.0 } else { p_r };
        return (f * d * g2 / (4.0 * cos_o), p * visible / 4.0);
    }
    let denom = ih + eta * oh;
    let jacobian = ih.abs() * oh / (denom * denom);
    (
        eta * eta * (1.0 - f) * d * g2 * jacobian / cos_o,
        (1.0 - p_r) * visible * jacobian,
    )
}

/// Rough glass's lobes x |cos(theta_i)| and the pdf of `rough_scatter`'s directions:
/// `rough_lobes`, with energy compensation its lobe (`ms_lobes`) beside them.
pub fn lobes(p: &Params, n: Vec3, wo: Vec3, wi: Vec3, eta: f32) -> (f32, f32) {
    let (f, pdf) = rough_lobes(p, n, wo, wi, eta);
    if compensated(p) {
        let (f_ms, pdf_ms) = ms_lobes(p, n, wo, wi, eta);
        let p_ms = ms_probs(p, n.dot(wo), eta).0;
        return (f + f_ms, pdf + (pdf_ms - pdf) * p_ms);
    }
    (f, pdf)
}

/// Whether rough glass is compensated (`MAT_FLAG_ENERGY`).
pub fn compensated(p: &Params) -> bool {
    p.flags & MAT_FLAG_ENERGY != 0
}

/// The dielectric tables' variant of rough glass.
pub fn ms_variant(p: &Params) -> u32 {
    if p.beckmann > 0.5 {
        MS_DIELECTRIC_BECKMANN_CORRELATED
    } else {
        MS_DIELECTRIC_GGX_CORRELATED
    }
}

/// (the probability of sampling the compensation at cos_o, the share it transmits).
pub fn ms_probs(p: &Params, cos_o: f32, eta: f32) -> (f32, f32) {
    let v = ms_variant(p);
    let ior = eta.max(1.0 / eta);
    let side = if eta < 1.0 { 0 } else { 1 };
    let alpha = ms_alpha(p.alpha, p.alpha_v);
    let loss = (1.0 - ms_dielectric_albedo(v, ior, side, cos_o, alpha)).clamp(0.0, 0.9);
    let split = ms_dielectric_split(v, ior, alpha);
    (loss, if side == 1 { split[1] } else { split[0] })
}

/// The compensation x |cos(theta_i)| for radiance and the density of its sampling.
pub fn ms_lobes(p: &Params, n: Vec3, wo: Vec3, wi: Vec3, eta: f32) -> (f32, f32) {
    let cos_o = n.dot(wo);
    let cos_i = n.dot(wi);
    let side = if eta < 1.0 { 0 } else { 1 };
    let f = ms_dielectric_lobe(
        ms_variant(p),
        eta.max(1.0 / eta),
        ms_alpha(p.alpha, p.alpha_v),
        side,
        cos_o,
        cos_i,
    );
    let b = ms_probs(p, cos_o, eta).1;
    let transmits = cos_i < 0.0;
    (
        f * if transmits { eta * eta } else { 1.0 },
        if transmits { b } else { 1.0 - b } * cos_i.abs() / PI,
    )
}

/// Rough glass: a visible normal, then the mirror direction about it or the refraction
/// through it (the mirror direction where it reflects totally); with energy
/// compensation, first its lobe (`ms_probs`: a cosine direction, mirrored through the
/// surface where it transmits). Weight = BSDF x cos / pdf (`lobes`) times specular
/// (reflected) or tint (transmitted); with its pdf.
pub fn rough_scatter(p: &Params, ray: &Ray, hit: &Hit, n: Vec3, eta: f32, u0: [f32; 2]) -> Scatter {
    let wo = -ray.dir;
    let cos_o = n.dot(wo);
    if cos_o <= 0.0 {
        return ABSORBED;
    }
    let mut u = u0;
    let mut sampled = None;
    if compensated(p) {
        let (p_ms, b) = ms_probs(p, cos_o, eta);
        if u[0] < p_ms {
            let v = u[0] / p_ms;
            let reflect = v >= b;
            let w = if reflect { (v - b) / (1.0 - b) } else { v / b };
            let mut wi = sample_cosine_hemisphere(n, [w, u[1]]);
            if !reflect {
                wi -= 2.0 * wi.dot(n) * n;
            }
            sampled = Some((wi, reflect));
        } else {
            u[0] = (u[0] - p_ms) / (1.0 - p_ms);
        }
    }
    let (wi, reflect) = match sampled {
        Some(s) => s,
        None => sample_microfacet(p, n, wo, cos_o, eta, u),
    };
    let side = if hit.front_face { 1.0 } else { -1.0 };
    let above = side * wi.dot(hit.ng) > 0.0;
    let (f, pdf) = lobes(p, n, wo, wi, eta);
    // written as in WGSL, so a NaN pdf takes the same branch on both backends
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(pdf > 0.0) || above != reflect {
        return ABSORBED;
    }
    let delta = !has_density(p);
    let weight = if reflect { p.specular } else { p.tint };
    Scatter {
        ok: true,
        dir: wi,
        weight: weight * (f / pdf),
        pdf: if delta { 0.0 } else { pdf },
        delta,
    }
}

/// The microfacet lobes' direction (`rough_scatter` without the compensation) and
/// whether it reflects.
fn sample_microfacet(
    p: &Params,
    n: Vec3,
    wo: Vec3,
    cos_o: f32,
    eta: f32,
    u: [f32; 2],
) -> (Vec3, bool) {
    let p_r = reflect_prob(cos_o, eta);
    let chose_reflection = u[0] < p_r;
    let uh = [
        if chose_reflection {
            u[0] / p_r
        } else {
            (u[0] - p_r) / (1.0 - p_r)
        },
        u[1],
    ];
    let (tb, h_l) = if general(p) {
        let tb = tangent_frame(n, p.tangent);
        let local = Vec3::new(wo.dot(tb[0]), wo.dot(tb[1]), cos_o);
        (tb, mf_sample_visible(&microfacet(p), local, uh))
    } else {
        let tb = onb_tangents(n);
        let local = Vec3::new(wo.dot(tb[0]), wo.dot(tb[1]), cos_o);
        (tb, sample_ggx_vndf(local, p.alpha, uh))
    };
    let h = h_l.x * tb[0] + h_l.y * tb[1] + h_l.z * n;
    let oh = wo.dot(h);
    let sin2_t = eta * eta * (1.0 - oh * oh).max(0.0);
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let reflect = chose_reflection || sin2_t >= 1.0;
    let wi = if reflect {
        (2.0 * oh * h - wo).normalize()
    } else {
        (-eta * wo + (eta * oh - cos_t) * h).normalize()
    };
    (wi, reflect)
}

/// eta = eta_o / eta_i at a hit (dielectric.wgsl's `dielectric_eta`).
pub fn eta(p: &Params) -> f32 {
    if p.back_face > 0.0 {
        p.ior
    } else {
        1.0 / p.ior
    }
}

/// Whether the glass has a density (dielectric.wgsl's `dielectric_has_density`): the
/// scene's own rule.
pub fn has_density(p: &Params) -> bool {
    dielectric::has_density((p.alpha, p.alpha_v))
}
