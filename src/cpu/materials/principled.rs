//! Mirrors `shaders/materials/principled.wgsl`.

use glam::Vec3;

use crate::cpu::bindings::Bindings;
use crate::cpu::bsdf::{
    density_sample, fresnel_dielectric, luminance, mf_d, mf_g1, mf_pdf_visible, mf_sample_visible,
    ms_alpha, ms_lobe, ms_loss, tangent_frame, Microfacet, Scatter, Shading, ABSORBED,
};
use crate::cpu::sampling::{sample_cosine_hemisphere, PI};
use crate::cpu::textures::texture_at;
use crate::cpu::types::{Hit, Ray};
use crate::scene::materials::principled::{Params, NO_SCALAR_TEXTURE};
use crate::scene::records::{MAT_FLAG_ENERGY, MS_GGX_SEPARABLE};

/// Schlick's weight (1 - c)^5.
pub fn schlick_weight(c: f32) -> f32 {
    let m = (1.0 - c).clamp(0.0, 1.0);
    m * m * m * m * m
}

/// Schlick's Fresnel of reflectance r0 at the microfacet cosine c from outside, of c or,
/// where eta < 1, of the refracted cosine.
pub fn schlick(r0: Vec3, c: f32, eta: f32) -> Vec3 {
    let mut w = schlick_weight(c.abs());
    if eta <= 1.0 {
        let cos2_t = 1.0 - (1.0 - c * c) / (eta * eta);
        w = schlick_weight(cos2_t.max(0.0).sqrt());
    }
    r0 + (Vec3::ONE - r0) * w
}

/// The exact dielectric Fresnel reflectance at cosine c > 0 toward relative index e.
pub fn fresnel(c: f32, e: f32) -> f32 {
    let eta = 1.0 / e;
    let sin2_t = eta * eta * (1.0 - c * c).max(0.0);
    if sin2_t >= 1.0 {
        1.0
    } else {
        fresnel_dielectric(c, (1.0 - sin2_t).max(0.0).sqrt(), eta)
    }
}

/// The main lobes' GGX.
pub fn microfacet(p: &Params) -> Microfacet {
    let r2 = p.roughness * p.roughness;
    let aspect = (1.0 - 0.9 * p.anisotropic).sqrt();
    Microfacet {
        alpha_u: (r2 / aspect).max(0.001),
        alpha_v: (r2 * aspect).max(0.001),
        beckmann: false,
    }
}

/// The clearcoat's GTR1 alpha.
pub fn coat_alpha(p: &Params) -> f32 {
    0.1 + (0.001 - 0.1) * p.clearcoat_gloss
}

/// GTR1's density of normals at cosine c.
pub fn gtr1(c: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let d = (a2 - 1.0) / (PI * a2.ln() * (1.0 + (a2 - 1.0) * c * c));
    if c > 0.0 && d * c > 1e-20 {
        d
    } else {
        0.0
    }
}

/// Whether wo sees it from outside.
pub fn outside(p: &Params) -> bool {
    p.back_face < 0.5 || p.transmits < 0.5
}

/// (diffuse, clearcoat, transmission given the main lobes) probabilities.
pub fn probs(p: &Params, outside: bool, cos_o: f32, e: f32) -> Vec3 {
    let bsdf = (1.0 - p.metallic) * p.spec_trans;
    let t = if bsdf > 0.0 {
        (1.0 - fresnel(cos_o, e)).clamp(0.1, 0.9)
    } else {
        0.0
    };
    if !outside {
        return Vec3::new(0.0, 0.0, t);
    }
    let brdf = (1.0 - p.metallic) * (1.0 - p.spec_trans);
    let coat = 0.25 * p.clearcoat;
    let total = 1.0 + coat + brdf;
    Vec3::new(brdf / total, coat / total, bsdf * t)
}

/// The probability of sampling the energy compensation's lobe from outside at cos_o.
pub fn ms_prob(p: &Params, outside: bool, cos_o: f32) -> f32 {
    if outside && p.flags & MAT_FLAG_ENERGY != 0 {
        let m = microfacet(p);
        ms_loss(MS_GGX_SEPARABLE, ms_alpha(m.alpha_u, m.alpha_v), cos_o)
    } else {
        0.0
    }
}

/// The compensation lobe x cos_i of the main reflection.
pub fn ms(p: &Params, cos_o: f32, cos_i: f32) -> Vec3 {
    let m = microfacet(p);
    let r = (p.eta - 1.0) / (p.eta + 1.0);
    let r0 = tint(p.base_color) * (r * r);
    let f_avg = Vec3::splat((1.0 - p.metallic) * (1.0 - p.spec_tint) * p.fresnel_avg)
        + p.metallic * (p.base_color + (Vec3::ONE - p.base_color) / 21.0)
        + (1.0 - p.metallic) * p.spec_tint * (r0 + (Vec3::ONE - r0) / 21.0);
    ms_lobe(
        MS_GGX_SEPARABLE,
        ms_alpha(m.alpha_u, m.alpha_v),
        cos_o,
        cos_i,
        f_avg,
    )
}

/// The pdf of the lobes but the compensation's (principled.wgsl's
/// `principled_lobes_pdf`).
pub fn lobes_pdf(p: &Params, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
    let cos_o = n.dot(wo);
    let cos_i = n.dot(wi);
    let outside = outside(p);
    let e = if outside { p.eta } else { 1.0 / p.eta };
    if cos_o <= 0.0 || cos_i == 0.0 {
        return 0.0;
    }
    let probs = probs(p, outside, cos_o, e);
    let spec = 1.0 - probs.x - probs.y;
    let [lo, li, h] = local(p, n, wo, wi, e);
    let oh = lo.dot(h);
    let ih = li.dot(h);
    let visible = mf_pdf_visible(&microfacet(p), lo, h);
    if cos_i < 0.0 {
        if oh <= 0.0 || ih >= 0.0 {
            return 0.0;
        }
        let denom = oh + e * ih;
        return spec * probs.z * visible * e * e * ih.abs() / (denom * denom);
    }
    if oh <= 0.0 || ih <= 0.0 {
        return 0.0;
    }
    let tir = (1.0 - oh * oh) >= e * e;
    let reflect = if tir { 1.0 } else { 1.0 - probs.z };
    let coat = probs.y * gtr1(h.z, coat_alpha(p)) * h.z;
    (spec * reflect * visible + coat) / (4.0 * oh) + probs.x * cos_i / PI
}

/// wo, wi in the tangent's frame and the microfacet normal joining them on wo's side.
pub fn local(p: &Params, n: Vec3, wo: Vec3, wi: Vec3, e: f32) -> [Vec3; 3] {
    let tb = tangent_frame(n, p.tangent);
    let lo = Vec3::new(wo.dot(tb[0]), wo.dot(tb[1]), wo.dot(n));
    let li = Vec3::new(wi.dot(tb[0]), wi.dot(tb[1]), wi.dot(n));
    let h = if li.z > 0.0 { lo + li } else { lo + e * li };
    let len = h.length();
    let h = if len > 0.0 { h / len } else { Vec3::Z };
    [lo, li, if h.z >= 0.0 { h } else { -h }]
}

/// base_color's hue: over its luminance (white where it is black).
pub fn tint(base: Vec3) -> Vec3 {
    let lum = luminance(base);
    if lum > 0.0 {
        base / lum
    } else {
        Vec3::ONE
    }
}

fn mix(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

// written as in WGSL, so that a NaN takes the same branch on both backends
#[allow(clippy::neg_cmp_op_on_partial_ord)]
impl Shading for Params {
    fn textures(&self, b: &Bindings, hit: &Hit) -> Self {
        let mut q = *self;
        let words = [
            self.textures0,
            self.textures1,
            self.textures2,
            self.textures3,
            self.textures4,
        ];
        let mut s = [
            self.roughness,
            self.anisotropic,
            self.metallic,
            self.spec_trans,
            self.spec_tint,
            self.sheen,
            self.sheen_tint,
            self.flatness,
            self.clearcoat,
            self.clearcoat_gloss,
        ];
        for (i, x) in s.iter_mut().enumerate() {
            let t = (words[i >> 1] >> (16 * (i & 1))) & 0xffff;
            if t != NO_SCALAR_TEXTURE {
                *x = luminance(texture_at(b, t, hit)).clamp(0.0, 1.0);
            }
        }
        q.roughness = s[0];
        q.anisotropic = s[1];
        q.metallic = s[2];
        q.spec_trans = s[3] * self.transmits;
        q.spec_tint = s[4];
        q.sheen = s[5];
        q.sheen_tint = s[6];
        q.flatness = s[7];
        q.clearcoat = s[8];
        q.clearcoat_gloss = s[9];
        q
    }

    fn eval(&self, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
        let p = self;
        let cos_o = n.dot(wo);
        let cos_i = n.dot(wi);
        let outside = outside(p);
        let e = if outside { p.eta } else { 1.0 / p.eta };
        let bsdf = (1.0 - p.metallic) * p.spec_trans;
        let brdf = (1.0 - p.metallic) * (1.0 - p.spec_trans);
        if cos_o <= 0.0 || cos_i == 0.0 || (cos_i < 0.0 && !(bsdf > 0.0)) {
            return Vec3::ZERO;
        }
        let [lo, li, h] = local(p, n, wo, wi, e);
        let oh = lo.dot(h);
        let ih = li.dot(h);
        let m = microfacet(p);
        let f = fresnel(oh.max(0.0), e);
        let dg = mf_d(&m, h) * mf_g1(&m, lo, h) * mf_g1(&m, li, h);
        if cos_i < 0.0 {
            if oh <= 0.0 || ih >= 0.0 || f >= 1.0 {
                return Vec3::ZERO;
            }
            let denom = oh + e * ih;
            return Vec3::new(
                p.base_color.x.sqrt(),
                p.base_color.y.sqrt(),
                p.base_color.z.sqrt(),
            ) * (bsdf * (1.0 - f) * dg * (oh * ih).abs() / (cos_o * denom * denom));
        }
        if oh <= 0.0 || ih <= 0.0 {
            return Vec3::ZERO;
        }
        if !outside {
            return Vec3::splat(bsdf * f * dg / (4.0 * cos_o));
        }
        let mut value = Vec3::ZERO;
        if f > 0.0 {
            let r = (p.eta - 1.0) / (p.eta + 1.0);
            let fp = Vec3::splat((1.0 - p.metallic) * (1.0 - p.spec_tint) * f)
                + p.metallic * schlick(p.base_color, oh, p.eta)
                + (1.0 - p.metallic)
                    * p.spec_tint
                    * schlick(tint(p.base_color) * (r * r), oh, p.eta);
            value = fp * (dg / (4.0 * cos_o));
        }
        if p.clearcoat > 0.0 {
            let coat = Microfacet {
                alpha_u: 0.25,
                alpha_v: 0.25,
                beckmann: false,
            };
            let g = mf_g1(&coat, lo, h) * mf_g1(&coat, li, h);
            let fc = schlick(Vec3::splat(0.04), oh, p.eta).x;
            value += Vec3::splat(0.25 * p.clearcoat * fc * gtr1(h.z, coat_alpha(p)) * g * cos_i);
        }
        if brdf > 0.0 {
            let fo = schlick_weight(cos_i);
            let fi = schlick_weight(cos_o);
            let f_diff = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo);
            let rr = 2.0 * p.roughness * ih * ih;
            let f_retro = rr * (fo + fi + fo * fi * (rr - 1.0));
            let fss = mix(1.0, 0.5 * rr, fo) * mix(1.0, 0.5 * rr, fi);
            let f_ss = 1.25 * (fss * (1.0 / (cos_o + cos_i) - 0.5) + 0.5);
            value += p.base_color * (brdf * cos_i / PI * mix(f_diff + f_retro, f_ss, p.flatness));
            if p.sheen > 0.0 {
                let sheen = Vec3::ONE + (tint(p.base_color) - Vec3::ONE) * p.sheen_tint;
                value += sheen * (p.sheen * (1.0 - p.metallic) * schlick_weight(ih) * cos_i);
            }
        }
        if p.flags & MAT_FLAG_ENERGY != 0 {
            value += ms(p, cos_o, cos_i);
        }
        value
    }

    fn pdf(&self, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        let pdf = lobes_pdf(self, n, wo, wi);
        let p_ms = ms_prob(self, outside(self), n.dot(wo));
        (1.0 - p_ms) * pdf + p_ms * n.dot(wi).max(0.0) / PI
    }

    fn scatter(&self, ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
        let mut q = *self;
        q.back_face = if hit.front_face { 0.0 } else { 1.0 };
        let side = if hit.front_face { 1.0 } else { -1.0 };
        let n = side * hit.ns;
        let wo = -ray.dir;
        let cos_o = n.dot(wo);
        if cos_o <= 0.0 {
            return ABSORBED;
        }
        let outside = outside(&q);
        let e = if outside { q.eta } else { 1.0 / q.eta };
        let probs = probs(&q, outside, cos_o, e);
        let tb = tangent_frame(n, q.tangent);
        let mut refracted = false;
        let wi;
        // the compensation's cosine lobe with ms_prob, u.x reused
        let p_ms = ms_prob(&q, outside, cos_o);
        let chose_ms = u[0] < p_ms;
        let ux = if chose_ms {
            u[0] / p_ms
        } else {
            (u[0] - p_ms) / (1.0 - p_ms)
        };
        if chose_ms {
            wi = sample_cosine_hemisphere(n, [ux, u[1]]);
        } else if ux < probs.x {
            wi = sample_cosine_hemisphere(n, [ux / probs.x, u[1]]);
        } else if ux < probs.x + probs.y {
            let a2 = coat_alpha(&q) * coat_alpha(&q);
            let cos2 = (1.0 - a2.powf(1.0 - u[1])) / (1.0 - a2);
            let sin_t = (1.0 - cos2).max(0.0).sqrt();
            let phi = 2.0 * PI * (ux - probs.x) / probs.y;
            let h =
                sin_t * phi.cos() * tb[0] + sin_t * phi.sin() * tb[1] + cos2.max(0.0).sqrt() * n;
            wi = (2.0 * wo.dot(h) * h - wo).normalize();
        } else {
            let x = (ux - probs.x - probs.y) / (1.0 - probs.x - probs.y);
            let refracts = x < probs.z;
            let xh = if refracts {
                x / probs.z
            } else {
                (x - probs.z) / (1.0 - probs.z)
            };
            let lo = Vec3::new(wo.dot(tb[0]), wo.dot(tb[1]), cos_o);
            let h_l = mf_sample_visible(&microfacet(&q), lo, [xh.min(0.99999994), u[1]]);
            let h = h_l.x * tb[0] + h_l.y * tb[1] + h_l.z * n;
            let oh = wo.dot(h);
            let eta = 1.0 / e;
            let sin2_t = eta * eta * (1.0 - oh * oh).max(0.0);
            if refracts && sin2_t < 1.0 {
                refracted = true;
                wi = (-eta * wo + (eta * oh - (1.0 - sin2_t).sqrt()) * h).normalize();
            } else {
                wi = (2.0 * oh * h - wo).normalize();
            }
        }
        let f = q.eval(n, wo, wi);
        let pdf = q.pdf(n, wo, wi);
        if q.transmits < 0.5 {
            return density_sample(wi, f, pdf, side, hit);
        }
        let over = wi.dot(n) > 0.0;
        if !(pdf > 0.0) || over == refracted || (side * wi.dot(hit.ng) > 0.0) != over {
            return ABSORBED;
        }
        Scatter {
            ok: true,
            dir: wi,
            weight: f / pdf,
            pdf,
            delta: false,
        }
    }
}
