//! Mirrors `shaders/shared/bsdf.wgsl`: what scattering returns, and the pieces several
//! materials share (mirror directions, Fresnel, the GGX distribution, Smith's masking, the
//! visible-normal sampler and the two-lobe mixture of a GGX and a cosine lobe).

use glam::Vec3;

use super::bindings::Bindings;
use super::sampling::{erf_approx, erfinv_approx, onb_tangents, sample_cosine_hemisphere, PI};
use super::types::{Hit, Ray};
use crate::scene::records::{MS_IORS, MS_IOR_MAX, MS_TABLE_SIZE};

pub use crate::scene::records::ALPHA_SMOOTH;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scatter {
    /// false: the path ends here (absorbed).
    pub ok: bool,
    pub dir: Vec3,
    /// BSDF * cos / pdf of the sampled direction.
    pub weight: Vec3,
    /// The pdf of the sampled direction (what MIS weighs against light sampling).
    pub pdf: f32,
    /// The direction came from a delta lobe (mirror, refraction, fuzzy metal).
    pub delta: bool,
}

/// A material's shading, implemented by its CPU twin (`cpu/materials/NAME.rs`) for its
/// view (`scene::materials::NAME::Params`): the functions `NAME_scatter`, `NAME_eval`,
/// `NAME_pdf` and `NAME_textures` of `shaders/materials/NAME.wgsl`.
pub trait Shading: Copy {
    /// The look-ups of its own textures at a hit: only a material whose view has some
    /// (`View::own_textures`) has them, and the WGSL function with them.
    fn textures(&self, _: &Bindings, _: &Hit) -> Self {
        *self
    }
    /// A direction, its weight (BSDF x cos / pdf), pdf, and whether from a delta lobe:
    /// a material with a lobe has it (`Lobes::any` of its type), one without absorbs.
    fn scatter(&self, _: &Ray, _: &Hit, _: [f32; 2]) -> Scatter {
        ABSORBED
    }
    /// BSDF x cos(theta_i) for unit wo and wi about the unit normal n on wo's side: a
    /// material with a lobe that has a density has it (`Lobes::density` of its type); a
    /// delta weighs 0.
    fn eval(&self, _: Vec3, _: Vec3, _: Vec3) -> Vec3 {
        Vec3::ZERO
    }
    /// The density with which `scatter` draws wi (as `eval`).
    fn pdf(&self, _: Vec3, _: Vec3, _: Vec3) -> f32 {
        0.0
    }
}

/// The path ends here (bsdf.wgsl's `absorbed()`).
pub const ABSORBED: Scatter = Scatter {
    ok: false,
    dir: Vec3::ZERO,
    weight: Vec3::ZERO,
    pdf: 0.0,
    delta: true,
};

/// A delta lobe's mirror reflection of the ray about n, weighted `weight` (bsdf.wgsl's
/// `mirror_scatter`).
pub fn mirror_scatter(ray: &Ray, hit: &Hit, side: f32, n: Vec3, weight: Vec3) -> Scatter {
    let wi = over_surface(reflect_dir(ray.dir, n), side, hit);
    if side * wi.dot(hit.ng) <= 0.0 {
        return ABSORBED;
    }
    Scatter {
        ok: true,
        dir: wi,
        weight,
        pdf: 0.0,
        delta: true,
    }
}

/// Mirror direction of d about the unit normal n.
#[inline]
pub fn reflect_dir(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Schlick's Fresnel reflectance at cosine c for relative index eta.
#[inline]
pub fn schlick(c: f32, eta: f32) -> f32 {
    let r = (1.0 - eta) / (1.0 + eta);
    let r0 = r * r;
    let m = 1.0 - c;
    r0 + (1.0 - r0) * m * m * m * m * m
}

/// Exact Fresnel reflectance of unpolarised light at a smooth dielectric boundary, for
/// cosines on the two sides and eta = eta_i / eta_t; 0 at matched indices.
#[inline]
pub fn fresnel_dielectric(cos_i: f32, cos_t: f32, eta: f32) -> f32 {
    let r_pa = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let r_pe = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    0.5 * (r_pa * r_pa + r_pe * r_pe)
}

#[inline]
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// GGX normal distribution at cos(theta_h) = c.
#[inline]
pub fn ggx_d(c: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let k = c * c * (a2 - 1.0) + 1.0;
    a2 / (PI * k * k)
}

/// Smith's Lambda for GGX at cos(theta) = c > 0.
#[inline]
pub fn smith_lambda(c: f32, alpha: f32) -> f32 {
    let c2 = c * c;
    0.5 * ((c2 + alpha * alpha * (1.0 - c2)).sqrt() / c - 1.0)
}

/// Smith's height-correlated masking-shadowing G2.
pub fn smith_g2(cos_o: f32, cos_i: f32, alpha: f32) -> f32 {
    1.0 / (1.0 + smith_lambda(cos_o, alpha) + smith_lambda(cos_i, alpha))
}

/// A visible normal of GGX seen from wo (local frame, z = normal), Heitz 2018.
pub fn sample_ggx_vndf(wo: Vec3, alpha: f32, u: [f32; 2]) -> Vec3 {
    sample_ggx_vndf_aniso(wo, alpha, alpha, u)
}

/// The same for roughness alpha_u along x and alpha_v along y.
pub fn sample_ggx_vndf_aniso(wo: Vec3, alpha_u: f32, alpha_v: f32, u: [f32; 2]) -> Vec3 {
    let vh = Vec3::new(alpha_u * wo.x, alpha_v * wo.y, wo.z).normalize();
    let len2 = vh.x * vh.x + vh.y * vh.y;
    let mut t1 = Vec3::X;
    if len2 > 0.0 {
        t1 = Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt();
    }
    let t2 = vh.cross(t1);
    let r = u[0].sqrt();
    let phi = 2.0 * PI * u[1];
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
    Vec3::new(alpha_u * nh.x, alpha_v * nh.y, nh.z.max(0.0)).normalize()
}

/// The probability of the specular lobe of weight ws beside the diffuse one of weight wd:
/// its share, kept in [0.1, 0.9] when both reflect.
pub fn lobe_prob(ws: f32, wd: f32) -> f32 {
    if ws <= 0.0 {
        return 0.0;
    }
    if wd <= 0.0 {
        return 1.0;
    }
    (ws / (ws + wd)).clamp(0.1, 0.9)
}

/// The pdf of sample_ggx_lobes's directions: G1(wo) D(h) / (4 cos_o) with probability
/// p_s, else the cosine pdf (the GGX lobe left out below ALPHA_SMOOTH).
pub fn ggx_lobes_pdf(p_s: f32, alpha: f32, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
    let cos_o = n.dot(wo);
    let cos_i = n.dot(wi);
    if cos_o <= 0.0 || cos_i <= 0.0 {
        return 0.0;
    }
    let diff = (1.0 - p_s) * cos_i / PI;
    if alpha < ALPHA_SMOOTH {
        return diff;
    }
    let h = (wo + wi).normalize();
    let spec = ggx_d(n.dot(h), alpha) / ((1.0 + smith_lambda(cos_o, alpha)) * 4.0 * cos_o);
    p_s * spec + diff
}

/// A direction from a GGX lobe of roughness alpha (a visible normal, then the mirror
/// direction about it) with probability p_s, else from the cosine lobe.
pub fn sample_ggx_lobes(p_s: f32, alpha: f32, n: Vec3, wo: Vec3, u: [f32; 2]) -> Vec3 {
    if u[0] < p_s {
        let tb = onb_tangents(n);
        let local = Vec3::new(wo.dot(tb[0]), wo.dot(tb[1]), n.dot(wo));
        let h_l = sample_ggx_vndf(local, alpha, [u[0] / p_s, u[1]]);
        let h = h_l.x * tb[0] + h_l.y * tb[1] + h_l.z * n;
        return (2.0 * wo.dot(h) * h - wo).normalize();
    }
    sample_cosine_hemisphere(n, [(u[0] - p_s) / (1.0 - p_s), u[1]])
}

/// `wi` as scattering sends it (bsdf.wgsl's `over_surface`): where the hit's shading
/// normal differs from its geometric one, a direction under the geometric surface (`ng`
/// turned to the ray's `side`) is mirrored over it rather than lost; elsewhere `wi`.
pub fn over_surface(wi: Vec3, side: f32, hit: &Hit) -> Vec3 {
    if hit.ns != hit.ng && side * wi.dot(hit.ng) < 0.0 {
        return mirrored(wi, hit);
    }
    wi
}

/// The direction mirrored over the hit's geometric surface (bsdf.wgsl's `mirrored`).
pub fn mirrored(wi: Vec3, hit: &Hit) -> Vec3 {
    wi - 2.0 * wi.dot(hit.ng) * hit.ng
}

/// A direction `wi` drawn from a lobe with a density, weighted by BSDF x cos `f` over its
/// `pdf`, sent over the surface (`over_surface`); absorbed when the pdf is not positive or
/// the direction is under the geometric surface (`ng` turned to the ray's `side`).
pub fn density_sample(wi: Vec3, f: Vec3, pdf: f32, side: f32, hit: &Hit) -> Scatter {
    let dir = over_surface(wi, side, hit);
    // Written as in WGSL, so a NaN pdf takes the same branch on both backends.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(pdf > 0.0) || side * dir.dot(hit.ng) <= 0.0 {
        return ABSORBED;
    }
    Scatter {
        ok: true,
        dir,
        weight: f / pdf,
        pdf,
        delta: false,
    }
}

/// The exact Fresnel reflectance off a conductor of complex relative index eta + i k per
/// channel at cosine c (bsdf.wgsl's `fresnel_conductor`).
pub fn fresnel_conductor(c: f32, eta: Vec3, k: Vec3) -> Vec3 {
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let t1 = eta * eta - k * k - Vec3::splat(s2);
    let sqrt = |v: Vec3| {
        let v = v.max(Vec3::ZERO);
        Vec3::new(v.x.sqrt(), v.y.sqrt(), v.z.sqrt())
    };
    let a2b2 = sqrt(t1 * t1 + 4.0 * eta * eta * k * k);
    let a = sqrt(0.5 * (a2b2 + t1));
    let t2 = a2b2 + Vec3::splat(c2);
    let t3 = 2.0 * c * a;
    // a ratio 0 / 0 (eta = k = 0 seen head-on) is its limit, 1
    let ratio = |n: Vec3, d: Vec3| {
        let q = n / d.max(Vec3::splat(1e-30));
        Vec3::select(d.cmpgt(Vec3::ZERO), q, Vec3::ONE)
    };
    let r_s = ratio(t2 - t3, t2 + t3);
    let t4 = a2b2 * c2 + Vec3::splat(s2 * s2);
    let t5 = t3 * s2;
    let r_p = r_s * ratio(t4 - t5, t4 + t5);
    0.5 * (r_s + r_p)
}

/// A microfacet distribution (bsdf.wgsl's `Microfacet`): GGX or Beckmann, roughness
/// alpha_u along the frame's tangent and alpha_v along its bitangent; its functions take
/// local directions, z the normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Microfacet {
    pub alpha_u: f32,
    pub alpha_v: f32,
    pub beckmann: bool,
}

/// Its density of normals D(h).
pub fn mf_d(m: &Microfacet, h: Vec3) -> f32 {
    let c2 = (h.z * h.z).max(1e-12);
    let e = (h.x * h.x) / (m.alpha_u * m.alpha_u) + (h.y * h.y) / (m.alpha_v * m.alpha_v);
    let norm = PI * m.alpha_u * m.alpha_v;
    let d = if m.beckmann {
        (-e / c2).exp() / (norm * c2 * c2)
    } else {
        let k = e + c2;
        1.0 / (norm * k * k)
    };
    if h.z > 0.0 && d * h.z > 1e-20 {
        d
    } else {
        0.0
    }
}

/// Smith's masking G1(v, h) = 1 / (1 + Lambda(v)), exact for both distributions; 0
/// where v sees h's back.
pub fn mf_g1(m: &Microfacet, v: Vec3, h: Vec3) -> f32 {
    let xy = (m.alpha_u * v.x) * (m.alpha_u * v.x) + (m.alpha_v * v.y) * (m.alpha_v * v.y);
    let tan2 = xy / (v.z * v.z);
    let mut g = if m.beckmann {
        let a = 1.0 / tan2.sqrt();
        let lambda = 0.5 * (erf_approx(a) - 1.0) + 0.282_094_8 * (-a * a).exp() / a;
        1.0 / (1.0 + lambda.max(0.0))
    } else {
        2.0 / (1.0 + (1.0 + tan2).sqrt())
    };
    if xy == 0.0 {
        g = 1.0;
    }
    if v.dot(h) * v.z > 0.0 {
        g
    } else {
        0.0
    }
}

/// The state of beckmann_slope's search (bsdf.wgsl's `BeckmannSearch`).
#[derive(Clone, Copy, Debug)]
pub struct BeckmannSearch {
    pub b: f32,
    pub lo: f32,
    pub hi: f32,
}

/// One Newton-bisection step of beckmann_slope's search.
#[allow(clippy::excessive_precision)]
pub fn beckmann_step(s: BeckmannSearch, x: f32, tan_i: f32, norm: f32) -> BeckmannSearch {
    let mut r = s;
    if !(r.b >= r.lo && r.b <= r.hi) {
        r.b = 0.5 * (r.lo + r.hi);
    }
    let e = erfinv_approx(r.b);
    let value = norm * (1.0 + r.b + 0.5641895835 * tan_i * (-e * e).exp()) - x;
    let derivative = norm * (1.0 - e * tan_i);
    if value > 0.0 {
        r.hi = r.b;
    } else {
        r.lo = r.b;
    }
    let ok = derivative != 0.0;
    let next = r.b - value / if ok { derivative } else { 1.0 };
    r.b = if ok && next >= r.lo && next <= r.hi {
        next
    } else {
        0.5 * (r.lo + r.hi)
    };
    r
}

/// A slope of Beckmann's unit-roughness visible normals seen at cos_i (bsdf.wgsl's
/// `beckmann_slope`).
#[allow(clippy::excessive_precision)]
pub fn beckmann_slope(cos_i: f32, u: [f32; 2]) -> [f32; 2] {
    let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
    let tan_i = sin_i / cos_i;
    let cot_i = cos_i / sin_i.max(1e-7);
    let x = u[0].max(1e-6);
    let hi = erf_approx(cot_i);
    let theta = cos_i.clamp(-1.0, 1.0).acos();
    let fit = 1.0 + theta * (-0.876 + theta * (0.4265 - 0.0594 * theta));
    let norm = 1.0 / (1.0 + hi + 0.5641895835 * tan_i * (-cot_i * cot_i).exp());
    let mut s = BeckmannSearch {
        b: hi - (1.0 + hi) * (1.0 - x).powf(fit),
        lo: -1.0,
        hi,
    };
    for _ in 0..6 {
        s = beckmann_step(s, x, tan_i, norm);
    }
    let b = if s.b >= s.lo && s.b <= s.hi {
        s.b
    } else {
        0.5 * (s.lo + s.hi)
    };
    if cos_i > 0.99999 {
        let r = (-(1.0 - u[0]).max(1e-30).ln()).sqrt();
        let phi = 2.0 * PI * u[1];
        return [r * phi.cos(), r * phi.sin()];
    }
    [
        erfinv_approx(b.clamp(-0.9999999, 0.9999999)),
        erfinv_approx(2.0 * u[1].max(1e-6) - 1.0),
    ]
}

/// A visible normal of the distribution seen from wo (bsdf.wgsl's `mf_sample_visible`).
pub fn mf_sample_visible(m: &Microfacet, wo: Vec3, u: [f32; 2]) -> Vec3 {
    if m.beckmann {
        let vh = Vec3::new(m.alpha_u * wo.x, m.alpha_v * wo.y, wo.z).normalize();
        let len = vh.truncate().length();
        let cs = if len > 0.0 {
            vh.truncate() / len
        } else {
            glam::Vec2::X
        };
        let s = beckmann_slope(vh.z, u);
        let slope = glam::Vec2::new(cs.x * s[0] - cs.y * s[1], cs.y * s[0] + cs.x * s[1])
            * glam::Vec2::new(m.alpha_u, m.alpha_v);
        return Vec3::new(-slope.x, -slope.y, 1.0).normalize();
    }
    sample_ggx_vndf_aniso(wo, m.alpha_u, m.alpha_v, u)
}

/// The density of mf_sample_visible's normals: G1(wo, h) max(0, wo . h) D(h) / wo.z.
pub fn mf_pdf_visible(m: &Microfacet, wo: Vec3, h: Vec3) -> f32 {
    mf_g1(m, wo, h) * wo.dot(h).max(0.0) * mf_d(m, h) / wo.z
}

/// A frame about the unit normal n whose first axis follows `tangent` (bsdf.wgsl's
/// `tangent_frame`); where it is zero or along n, +y x n (onb_tangents(n)'s at the
/// poles).
pub fn tangent_frame(n: Vec3, tangent: Vec3) -> [Vec3; 2] {
    let t = tangent - n * n.dot(tangent);
    let len = t.length();
    if len > 1e-6 {
        let tu = t / len;
        return [tu, n.cross(tu)];
    }
    let around = Vec3::new(n.z, 0.0, -n.x);
    let l = around.length();
    if l > 1e-3 {
        let tu = around / l;
        return [tu, n.cross(tu)];
    }
    onb_tangents(n)
}

// ------------------------------------------- multiple-scattering energy compensation

/// Float i of the albedo tables (`scene::microfacet_albedo`, which the GPU reads from
/// `tables` at `Params::ms_tables`).
pub fn ms_float(i: u32) -> f32 {
    use crate::scene::microfacet_albedo::{self as ma, DielectricVariant};
    let i = i as usize;
    if i < 3 * ma::BLOCK {
        return ma::tables()[i];
    }
    let (v, j) = (
        (i - 3 * ma::BLOCK) / ma::DIELECTRIC_BLOCK,
        (i - 3 * ma::BLOCK) % ma::DIELECTRIC_BLOCK,
    );
    ma::dielectric_block(DielectricVariant::ALL[v])[j]
}

/// The first float of a variant's table t (0: E1, 1: E5).
pub fn ms_offset(variant: u32, t: u32) -> u32 {
    let block = MS_TABLE_SIZE * MS_TABLE_SIZE + MS_TABLE_SIZE;
    (2 * variant + t) * block
}

fn mix(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

/// The isotropic alpha whose tables stand for an anisotropic lobe's: the mean of the two.
pub fn ms_alpha(alpha_u: f32, alpha_v: f32) -> f32 {
    0.5 * (alpha_u + alpha_v)
}

/// A table's albedo at cosine c and alpha, bilinear in sqrt(c) and sqrt(alpha).
pub fn ms_albedo(offset: u32, c: f32, alpha: f32) -> f32 {
    let last = (MS_TABLE_SIZE - 1) as f32;
    let x = c.clamp(0.0, 1.0).sqrt() * last;
    let y = alpha.clamp(0.0, 1.0).sqrt() * last;
    let x0 = (x as u32).min(MS_TABLE_SIZE - 2);
    let y0 = (y as u32).min(MS_TABLE_SIZE - 2);
    let i = offset + y0 * MS_TABLE_SIZE + x0;
    let j = i + MS_TABLE_SIZE;
    let fx = x - x0 as f32;
    mix(
        mix(ms_float(i), ms_float(i + 1), fx),
        mix(ms_float(j), ms_float(j + 1), fx),
        y - y0 as f32,
    )
}

/// A table's average 2 int E(mu) mu dmu at alpha.
pub fn ms_average(offset: u32, alpha: f32) -> f32 {
    let last = (MS_TABLE_SIZE - 1) as f32;
    let y = alpha.clamp(0.0, 1.0).sqrt() * last;
    let y0 = (y as u32).min(MS_TABLE_SIZE - 2);
    let i = offset + MS_TABLE_SIZE * MS_TABLE_SIZE + y0;
    mix(ms_float(i), ms_float(i + 1), y - y0 as f32)
}

/// F_ms = F_avg^2 E_avg / (1 - F_avg (1 - E_avg)).
pub fn ms_fresnel(f_avg: Vec3, e_avg: f32) -> Vec3 {
    f_avg * f_avg * e_avg / (Vec3::ONE - f_avg * (1.0 - e_avg))
}

/// The compensation lobe x cos_i.
pub fn ms_lobe(variant: u32, alpha: f32, cos_o: f32, cos_i: f32, f_avg: Vec3) -> Vec3 {
    let o = ms_offset(variant, 0);
    let e_avg = ms_average(o, alpha);
    if cos_o <= 0.0 || cos_i <= 0.0 || e_avg >= 1.0 {
        return Vec3::ZERO;
    }
    let k = (1.0 - ms_albedo(o, cos_o, alpha)) * (1.0 - ms_albedo(o, cos_i, alpha))
        / (PI * (1.0 - e_avg));
    ms_fresnel(f_avg, e_avg) * (k * cos_i)
}

/// 1 - E1(cos_o), at most 0.9: the probability of sampling the compensation lobe.
pub fn ms_loss(variant: u32, alpha: f32, cos_o: f32) -> f32 {
    (1.0 - ms_albedo(ms_offset(variant, 0), cos_o, alpha)).clamp(0.0, 0.9)
}

/// The albedo at c of a Schlick lobe from f0 to f90 alone: f0 E1 + (f90 - f0) E5.
pub fn ms_schlick_single(variant: u32, alpha: f32, c: f32, f0: Vec3, f90: Vec3) -> Vec3 {
    f0 * ms_albedo(ms_offset(variant, 0), c, alpha)
        + (f90 - f0) * ms_albedo(ms_offset(variant, 1), c, alpha)
}

/// `ms_schlick_single` averaged over cosines.
pub fn ms_schlick_single_average(variant: u32, alpha: f32, f0: Vec3, f90: Vec3) -> Vec3 {
    f0 * ms_average(ms_offset(variant, 0), alpha)
        + (f90 - f0) * ms_average(ms_offset(variant, 1), alpha)
}

/// The albedo at c of a compensated Schlick lobe from f0 to f90.
pub fn ms_schlick_albedo(variant: u32, alpha: f32, c: f32, f0: Vec3, f90: Vec3) -> Vec3 {
    let o1 = ms_offset(variant, 0);
    let e1 = ms_albedo(o1, c, alpha);
    let f_ms = ms_fresnel(f0 + (f90 - f0) / 21.0, ms_average(o1, alpha));
    ms_schlick_single(variant, alpha, c, f0, f90) + f_ms * (1.0 - e1)
}

/// `ms_schlick_albedo` averaged over cosines.
pub fn ms_schlick_average(variant: u32, alpha: f32, f0: Vec3, f90: Vec3) -> Vec3 {
    let e1 = ms_average(ms_offset(variant, 0), alpha);
    let f_ms = ms_fresnel(f0 + (f90 - f0) / 21.0, e1);
    ms_schlick_single_average(variant, alpha, f0, f90) + f_ms * (1.0 - e1)
}

/// Kulla and Conty's albedo scaling: (1 - a_o) (1 - a_i) / (1 - avg).
pub fn ms_scaling(a_o: Vec3, a_i: Vec3, avg: Vec3) -> Vec3 {
    let v = (Vec3::ONE - a_o) * (Vec3::ONE - a_i) / (Vec3::ONE - avg);
    Vec3::select(avg.cmpge(Vec3::ONE), Vec3::ZERO, v)
}

/// The share of a layer under a compensated Schlick lobe (albedo scaling).
pub fn ms_under(variant: u32, alpha: f32, cos_o: f32, cos_i: f32, f0: Vec3, f90: Vec3) -> Vec3 {
    let avg = ms_schlick_average(variant, alpha, f0, f90);
    ms_scaling(
        ms_schlick_albedo(variant, alpha, cos_o, f0, f90),
        ms_schlick_albedo(variant, alpha, cos_i, f0, f90),
        avg,
    )
}

// ----- rough dielectrics (shared/bsdf.wgsl has the formulas)

/// Where an index ratio ior >= 1 lands on the tables' axis: (lower table, fraction).
pub fn ms_ior_position(ior: f32) -> (u32, f32) {
    let t = ((ior - 1.0) / (MS_IOR_MAX - 1.0)).clamp(0.0, 1.0).sqrt() * (MS_IORS - 1) as f32;
    let k = t.floor().min((MS_IORS - 2) as f32);
    (k as u32, t - k)
}

/// The first float of a dielectric variant's table of index k and side.
pub fn ms_dielectric_offset(variant: u32, k: u32, side: u32) -> u32 {
    let block = MS_TABLE_SIZE * MS_TABLE_SIZE + MS_TABLE_SIZE;
    6 * block + variant * (MS_IORS * 2 * block + MS_IORS) + (2 * k + side) * block
}

/// The total albedo at cosine c and alpha seen from `side` of index ratio ior >= 1.
pub fn ms_dielectric_albedo(variant: u32, ior: f32, side: u32, c: f32, alpha: f32) -> f32 {
    let (k, t) = ms_ior_position(ior);
    let a = ms_albedo(ms_dielectric_offset(variant, k, side), c, alpha);
    mix(
        a,
        ms_albedo(ms_dielectric_offset(variant, k + 1, side), c, alpha),
        t,
    )
}

/// (b from the lower side, b from the higher, 1 - E_avg of each).
pub fn ms_dielectric_split(variant: u32, ior: f32, alpha: f32) -> [f32; 4] {
    let (k, t) = ms_ior_position(ior);
    let avg = |side| {
        mix(
            ms_average(ms_dielectric_offset(variant, k, side), alpha),
            ms_average(ms_dielectric_offset(variant, k + 1, side), alpha),
            t,
        )
    };
    let (l_low, l_high) = (1.0 - avg(0), 1.0 - avg(1));
    let f = ms_dielectric_offset(variant, MS_IORS, 0) + k;
    let ior2 = ior * ior;
    let mut b_low = 1.0 - mix(ms_float(f), ms_float(f + 1), t);
    if l_low > 0.0 {
        b_low = b_low.min(ior2 * l_high / l_low);
    }
    let b_high = if l_high > 0.0 {
        b_low * l_low / (ior2 * l_high)
    } else {
        0.0
    };
    [b_low, b_high, l_low.max(0.0), l_high.max(0.0)]
}

/// The compensation x |cos_i| in energy between wo at cos_o on `side` and wi at cos_i
/// (negative: transmitted).
pub fn ms_dielectric_lobe(
    variant: u32,
    ior: f32,
    alpha: f32,
    side: u32,
    cos_o: f32,
    cos_i: f32,
) -> f32 {
    let s = ms_dielectric_split(variant, ior, alpha);
    let side_i = if cos_i > 0.0 { side } else { 1 - side };
    let avg = if side_i == 1 { s[3] } else { s[2] };
    if cos_o <= 0.0 || cos_i == 0.0 || avg <= 0.0 {
        return 0.0;
    }
    let b = if side == 1 { s[1] } else { s[0] };
    let share = if cos_i > 0.0 { 1.0 - b } else { b };
    let loss_o = (1.0 - ms_dielectric_albedo(variant, ior, side, cos_o, alpha)).max(0.0);
    let loss_i = (1.0 - ms_dielectric_albedo(variant, ior, side_i, cos_i.abs(), alpha)).max(0.0);
    share * loss_o * loss_i / (PI * avg) * cos_i.abs()
}
