//! Mirrors `shaders/materials/plastic.wgsl`. A rough coating's transmittance table is
//! the one the flattener places in `tables` for the shader, computed here from the
//! record's alpha, ior and distribution (once per thread and material).

use std::cell::RefCell;
use std::collections::HashMap;
use std::rc::Rc;

use glam::Vec3;

use crate::cpu::bsdf::{
    density_sample, fresnel_dielectric, mf_d, mf_g1, mf_pdf_visible, mf_sample_visible,
    mirror_scatter, Microfacet, Scatter, Shading, ABSORBED, ALPHA_SMOOTH,
};
use crate::cpu::bsdf::{ms_dielectric_albedo, ms_dielectric_lobe, ms_dielectric_split};
use crate::cpu::sampling::{onb_tangents, sample_cosine_hemisphere, PI};
use crate::cpu::types::{Hit, Ray};
use crate::scene::materials::plastic::{self, transmittance_table, Params};
use crate::scene::records::{
    MS_DIELECTRIC_BECKMANN_SEPARABLE, MS_DIELECTRIC_GGX_SEPARABLE, PLASTIC_TABLE_SIZE,
};

/// The coating's exact Fresnel reflectance seen from outside at cosine c.
pub fn fresnel(c: f32, ior: f32) -> f32 {
    let eta = 1.0 / ior;
    let sin2_t = eta * eta * (1.0 - c * c).max(0.0);
    if sin2_t >= 1.0 {
        1.0
    } else {
        fresnel_dielectric(c, (1.0 - sin2_t).max(0.0).sqrt(), eta)
    }
}

/// Rough coatings' tables by the bits of (alpha, ior) and Beckmann.
type Tables = HashMap<(u32, u32, bool), Rc<Vec<f32>>>;

thread_local! {
    static TABLES: RefCell<Tables> = RefCell::new(HashMap::new());
}

/// The coating's transmittance at cosine c (1 - F when smooth, else its table).
pub fn transmittance(p: &Params, c: f32) -> f32 {
    if p.alpha < ALPHA_SMOOTH {
        return 1.0 - fresnel(c, p.ior);
    }
    let beckmann = p.beckmann > 0.5;
    let table = TABLES.with(|t| {
        t.borrow_mut()
            .entry((p.alpha.to_bits(), p.ior.to_bits(), beckmann))
            .or_insert_with(|| Rc::new(transmittance_table(p.alpha, p.ior, beckmann)))
            .clone()
    });
    let x = c.clamp(0.0, 1.0) * (PLASTIC_TABLE_SIZE - 1) as f32;
    let i = (x as u32).min(PLASTIC_TABLE_SIZE - 2) as usize;
    let (a, b) = (table[i], table[i + 1]);
    let mut t = a + (b - a) * (x - i as f32);
    if compensated(p) {
        let v = ms_variant(p);
        let split = ms_dielectric_split(v, p.ior, p.alpha);
        t += split[0] * (1.0 - ms_dielectric_albedo(v, p.ior, 0, c, p.alpha)).max(0.0);
    }
    t
}

/// Whether the coating is compensated (plastic.wgsl's `plastic_compensated`).
pub fn compensated(p: &Params) -> bool {
    plastic::compensates(p)
}

/// The dielectric tables' variant of the coating.
pub fn ms_variant(p: &Params) -> u32 {
    if p.beckmann > 0.5 {
        MS_DIELECTRIC_BECKMANN_SEPARABLE
    } else {
        MS_DIELECTRIC_GGX_SEPARABLE
    }
}

/// The base's albedo over 1 - R_int (or 1 - albedo R_int when nonlinear).
pub fn diffuse(p: &Params) -> Vec3 {
    let mut internal = p.internal;
    if compensated(p) {
        let split = ms_dielectric_split(ms_variant(p), p.ior, p.alpha);
        internal += (1.0 - split[1]) * split[3];
    }
    let r = if p.nonlinear > 0.5 {
        p.diffuse * internal
    } else {
        Vec3::splat(internal)
    };
    p.diffuse / (Vec3::ONE - r)
}

/// The probability of sampling the coating seen at cos_o.
pub fn spec_prob(p: &Params, cos_o: f32) -> f32 {
    let t = transmittance(p, cos_o);
    let s = (1.0 - t) * p.spec_weight;
    let d = t * (1.0 - p.spec_weight);
    if s + d <= 0.0 {
        0.0
    } else {
        s / (s + d)
    }
}

fn microfacet(p: &Params) -> Microfacet {
    Microfacet {
        alpha_u: p.alpha,
        alpha_v: p.alpha,
        beckmann: p.beckmann > 0.5,
    }
}

/// wo and wi in a frame about n.
fn local(n: Vec3, wo: Vec3, wi: Vec3) -> (Vec3, Vec3) {
    let tb = onb_tangents(n);
    (
        Vec3::new(wo.dot(tb[0]), wo.dot(tb[1]), n.dot(wo)),
        Vec3::new(wi.dot(tb[0]), wi.dot(tb[1]), n.dot(wi)),
    )
}

impl Shading for Params {
    /// The base plus a rough coating's specular (and its compensation).
    fn eval(&self, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
        let cos_o = n.dot(wo);
        let cos_i = n.dot(wi);
        if cos_o <= 0.0 || cos_i <= 0.0 {
            return Vec3::ZERO;
        }
        let base = diffuse(self)
            * (transmittance(self, cos_o) * transmittance(self, cos_i) * cos_i
                / (PI * self.ior * self.ior));
        if self.alpha < ALPHA_SMOOTH {
            return base;
        }
        let m = microfacet(self);
        let (lo, li) = local(n, wo, wi);
        let h = (lo + li).normalize();
        let g = mf_g1(&m, lo, h) * mf_g1(&m, li, h);
        let mut spec = fresnel(lo.dot(h), self.ior) * mf_d(&m, h) * g / (4.0 * cos_o);
        if compensated(self) {
            spec += ms_dielectric_lobe(ms_variant(self), self.ior, self.alpha, 0, cos_o, cos_i);
        }
        self.specular * spec + base
    }

    /// The coating's visible normals with spec_prob (when rough), else the cosine lobe.
    fn pdf(&self, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        let cos_o = n.dot(wo);
        let cos_i = n.dot(wi);
        if cos_o <= 0.0 || cos_i <= 0.0 {
            return 0.0;
        }
        let p_s = spec_prob(self, cos_o);
        let diff = (1.0 - p_s) * cos_i / PI;
        if self.alpha < ALPHA_SMOOTH {
            return diff;
        }
        let (lo, li) = local(n, wo, wi);
        let h = (lo + li).normalize();
        p_s * mf_pdf_visible(&microfacet(self), lo, h) / (4.0 * lo.dot(h)) + diff
    }

    /// The coating (its mirror when smooth) or the base, chosen by spec_prob.
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
            let weight = self.specular * (fresnel(cos_o, self.ior) / p_s);
            return mirror_scatter(ray, hit, side, n, weight);
        }
        let wi = if u[0] < p_s {
            let tb = onb_tangents(n);
            let lo = Vec3::new(wo.dot(tb[0]), wo.dot(tb[1]), cos_o);
            let h_l = mf_sample_visible(&microfacet(self), lo, [u[0] / p_s, u[1]]);
            let h = h_l.x * tb[0] + h_l.y * tb[1] + h_l.z * n;
            (2.0 * wo.dot(h) * h - wo).normalize()
        } else {
            sample_cosine_hemisphere(n, [(u[0] - p_s) / (1.0 - p_s), u[1]])
        };
        density_sample(wi, self.eval(n, wo, wi), self.pdf(n, wo, wi), side, hit)
    }
}
