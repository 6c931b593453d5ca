//! Mirrors `shaders/shared/bsdf.wgsl`: what scattering returns, and the pieces several
//! materials share (mirror directions, Fresnel, the GGX distribution, Smith's masking, the
//! visible-normal sampler and the two-lobe mixture of a GGX and a cosine lobe).

use glam::Vec3;

use super::bindings::Bindings;
use super::sampling::{onb_tangents, sample_cosine_hemisphere, PI};
use super::types::{Hit, Ray};

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
    let vh = Vec3::new(alpha * wo.x, alpha * wo.y, wo.z).normalize();
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
    Vec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize()
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
