//! Mirrors `shaders/shared/materials.wgsl`.

use glam::Vec3;

use super::sampling::{onb_tangents, sample_cosine_hemisphere, sample_sphere, PI};
use super::types::{xyz, Hit, Ray};
use crate::scene::records::{
    Material, MAT_DIELECTRIC, MAT_FLAG_TWO_SIDED, MAT_LAMBERTIAN, MAT_METAL, MAT_MICROFACET,
    MAT_PBR,
};

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

/// Radiance the surface emits toward the ray that hit it.
pub fn emitted(mat: &Material, hit: &Hit) -> Vec3 {
    if hit.front_face || (mat.flags & MAT_FLAG_TWO_SIDED) != 0 {
        xyz(mat.emission)
    } else {
        Vec3::ZERO
    }
}

/// Lambertian: cosine-weighted about the shading normal on the side the ray came from; a
/// direction under the geometric surface ends the path.
pub fn scatter_lambertian(mat: &Material, hit: &Hit, u: [f32; 2]) -> Scatter {
    let side = if hit.front_face { 1.0 } else { -1.0 };
    let dir = sample_cosine_hemisphere(side * hit.ns, u);
    if side * dir.dot(hit.ng) <= 0.0 {
        return ABSORBED;
    }
    Scatter {
        ok: true,
        dir,
        weight: xyz(mat.albedo),
        pdf: (side * hit.ns).dot(dir) / PI,
        delta: false,
    }
}

/// The path ends here.
const ABSORBED: Scatter = Scatter {
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

/// Metal: mirror direction perturbed by fuzz x a uniform unit vector; weight = albedo.
pub fn scatter_metal(mat: &Material, ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
    let side = if hit.front_face { 1.0 } else { -1.0 };
    let v = reflect_dir(ray.dir, side * hit.ns) + mat.params[0] * sample_sphere(u);
    let len = v.length();
    // Written as in WGSL, so a NaN length takes the same branch on both backends.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(len > 0.0) || side * v.dot(hit.ng) <= 0.0 {
        return ABSORBED;
    }
    Scatter {
        ok: true,
        dir: v / len,
        weight: xyz(mat.albedo),
        pdf: 0.0,
        delta: true,
    }
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

/// Dielectric: Snell refraction, total internal reflection, exact Fresnel choice, tint
/// and Beer-Lambert absorption inside.
pub fn scatter_dielectric(mat: &Material, ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
    let entering = hit.front_face;
    let n = if entering { hit.ns } else { -hit.ns };
    let eta = if entering {
        1.0 / mat.params[0]
    } else {
        mat.params[0]
    };
    let cos_i = (-ray.dir.dot(n)).clamp(0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    let mut weight = xyz(mat.albedo);
    if !entering {
        weight *= (-xyz(mat.extra) * (hit.p - ray.origin).length()).exp();
    }
    let reflected = Scatter {
        ok: true,
        dir: reflect_dir(ray.dir, n),
        weight,
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
        weight,
        pdf: 0.0,
        delta: true,
    }
}

pub use crate::scene::records::ALPHA_SMOOTH;

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

/// A visible normal of GGX seen from wo (local frame, z = normal), Heitz 2018.
/// Smith's height-correlated masking-shadowing G2 (materials.wgsl's `smith_g2`).
pub fn smith_g2(cos_o: f32, cos_i: f32, alpha: f32) -> f32 {
    1.0 / (1.0 + smith_lambda(cos_o, alpha) + smith_lambda(cos_i, alpha))
}

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

/// Probability of sampling the specular lobe (depends on wo only).
pub fn microfacet_spec_prob(mat: &Material, cos_o: f32) -> f32 {
    let f = schlick(cos_o, mat.params[1]);
    lobe_prob(
        luminance(xyz(mat.extra)) * f,
        luminance(xyz(mat.albedo)) * (1.0 - f),
    )
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

/// Cook-Torrance BSDF x cos(theta_i).
pub fn microfacet_eval(mat: &Material, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
    let cos_o = n.dot(wo);
    let cos_i = n.dot(wi);
    if cos_o <= 0.0 || cos_i <= 0.0 {
        return Vec3::ZERO;
    }
    let alpha = mat.params[0];
    let ior = mat.params[1];
    let diff = (1.0 - schlick(cos_i, ior)) * (1.0 - schlick(cos_o, ior)) * cos_i / PI;
    if alpha < ALPHA_SMOOTH {
        return xyz(mat.albedo) * diff;
    }
    let h = (wo + wi).normalize();
    let spec = ggx_d(n.dot(h), alpha) * smith_g2(cos_o, cos_i, alpha) * schlick(wi.dot(h), ior)
        / (4.0 * cos_o);
    xyz(mat.extra) * spec + xyz(mat.albedo) * diff
}

/// The pdf of scatter_microfacet's directions.
pub fn microfacet_pdf(mat: &Material, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
    ggx_lobes_pdf(
        microfacet_spec_prob(mat, n.dot(wo)),
        mat.params[0],
        n,
        wo,
        wi,
    )
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

/// Microfacet: specular (visible normal) or diffuse (cosine) lobe; weight = eval / pdf.
pub fn scatter_microfacet(mat: &Material, ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
    let side = if hit.front_face { 1.0 } else { -1.0 };
    let n = side * hit.ns;
    let wo = -ray.dir;
    let cos_o = n.dot(wo);
    if cos_o <= 0.0 {
        return ABSORBED;
    }
    let p_s = microfacet_spec_prob(mat, cos_o);
    let is_smooth = mat.params[0] < ALPHA_SMOOTH;
    if is_smooth && u[0] < p_s {
        let wi = reflect_dir(ray.dir, n);
        if side * wi.dot(hit.ng) <= 0.0 {
            return ABSORBED;
        }
        return Scatter {
            ok: true,
            dir: wi,
            weight: xyz(mat.extra) * (schlick(cos_o, mat.params[1]) / p_s),
            pdf: 0.0,
            delta: true,
        };
    }
    let wi = sample_ggx_lobes(p_s, mat.params[0], n, wo, u);
    let pdf = microfacet_pdf(mat, n, wo, wi);
    // Written as in WGSL, so a NaN pdf takes the same branch on both backends.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(pdf > 0.0) || side * wi.dot(hit.ng) <= 0.0 {
        return ABSORBED;
    }
    Scatter {
        ok: true,
        dir: wi,
        weight: microfacet_eval(mat, n, wo, wi) / pdf,
        pdf,
        delta: false,
    }
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

/// Fresnel-Schlick of the metallic-roughness material's dielectric layer at cos c:
/// F0 = min(((ior - 1) / (ior + 1))^2 specular colour, 1) specular, F90 = specular.
pub fn pbr_dielectric_fresnel(mat: &Material, c: f32) -> Vec3 {
    let r = (mat.params[1] - 1.0) / (mat.params[1] + 1.0);
    let f0 = (Vec3::splat(r * r) * xyz(mat.extra)).min(Vec3::ONE) * mat.params[3];
    let m = 1.0 - c.clamp(0.0, 1.0);
    f0 + (Vec3::splat(mat.params[3]) - f0) * (m * m * m * m * m)
}

/// Fresnel-Schlick of its metal: F0 = the base colour.
pub fn pbr_metal_fresnel(mat: &Material, c: f32) -> Vec3 {
    let m = 1.0 - c.clamp(0.0, 1.0);
    let base = xyz(mat.albedo);
    base + (Vec3::ONE - base) * (m * m * m * m * m)
}

/// glTF's metallic-roughness BSDF x cos(theta_i) (materials.wgsl's `pbr_eval`, which says
/// why the base is weighted as it is): mix((1 - F_d(cos_i)) (1 - F_d(cos_o)) base / pi
/// cos_i + F_d(v . h) S, F_m(v . h) S, metallic), S = D G2 / (4 cos_o).
pub fn pbr_eval(mat: &Material, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
    let cos_o = n.dot(wo);
    let cos_i = n.dot(wi);
    if cos_o <= 0.0 || cos_i <= 0.0 {
        return Vec3::ZERO;
    }
    let alpha = mat.params[0];
    let h = (wo + wi).normalize();
    let vh = wo.dot(h);
    let spec = ggx_d(n.dot(h), alpha) * smith_g2(cos_o, cos_i, alpha) / (4.0 * cos_o);
    let through = (Vec3::ONE - pbr_dielectric_fresnel(mat, cos_i))
        * (Vec3::ONE - pbr_dielectric_fresnel(mat, cos_o));
    let dielectric =
        through * xyz(mat.albedo) * (cos_i / PI) + pbr_dielectric_fresnel(mat, vh) * spec;
    let metallic = mat.params[2];
    dielectric * (1.0 - metallic) + pbr_metal_fresnel(mat, vh) * spec * metallic
}

/// Probability of sampling the GGX lobe of the metallic-roughness material.
pub fn pbr_spec_prob(mat: &Material, cos_o: f32) -> f32 {
    let fd = pbr_dielectric_fresnel(mat, cos_o);
    let metallic = mat.params[2];
    let ws = luminance(fd * (1.0 - metallic) + pbr_metal_fresnel(mat, cos_o) * metallic);
    let wd = (1.0 - mat.params[2]) * luminance((Vec3::ONE - fd) * xyz(mat.albedo));
    lobe_prob(ws, wd)
}

pub fn pbr_pdf(mat: &Material, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
    ggx_lobes_pdf(pbr_spec_prob(mat, n.dot(wo)), mat.params[0], n, wo, wi)
}

/// The metallic-roughness material: the GGX lobe or the cosine one; weight = eval / pdf.
pub fn scatter_pbr(mat: &Material, ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
    let side = if hit.front_face { 1.0 } else { -1.0 };
    let n = side * hit.ns;
    let wo = -ray.dir;
    let cos_o = n.dot(wo);
    if cos_o <= 0.0 {
        return ABSORBED;
    }
    let wi = sample_ggx_lobes(pbr_spec_prob(mat, cos_o), mat.params[0], n, wo, u);
    let pdf = pbr_pdf(mat, n, wo, wi);
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(pdf > 0.0) || side * wi.dot(hit.ng) <= 0.0 {
        return ABSORBED;
    }
    Scatter {
        ok: true,
        dir: wi,
        weight: pbr_eval(mat, n, wo, wi) / pdf,
        pdf,
        delta: false,
    }
}

pub fn scatter(mat: &Material, ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
    match mat.tag {
        MAT_LAMBERTIAN => scatter_lambertian(mat, hit, u),
        MAT_METAL => scatter_metal(mat, ray, hit, u),
        MAT_DIELECTRIC => scatter_dielectric(mat, ray, hit, u),
        MAT_MICROFACET => scatter_microfacet(mat, ray, hit, u),
        MAT_PBR => scatter_pbr(mat, ray, hit, u),
        // emissive and unknown materials absorb
        _ => ABSORBED,
    }
}

/// BSDF x cos toward wi for the materials light sampling serves (0 for the others), 0
/// under the geometric surface; the smooth microfacet's mirror lobe is left out.
pub fn bsdf_eval(mat: &Material, ray: &Ray, hit: &Hit, wi: Vec3) -> Vec3 {
    let side = if hit.front_face { 1.0 } else { -1.0 };
    if side * wi.dot(hit.ng) <= 0.0 {
        return Vec3::ZERO;
    }
    let n = side * hit.ns;
    match mat.tag {
        MAT_LAMBERTIAN => xyz(mat.albedo) * (n.dot(wi).max(0.0) / PI),
        MAT_MICROFACET => microfacet_eval(mat, n, -ray.dir, wi),
        MAT_PBR => pbr_eval(mat, n, -ray.dir, wi),
        _ => Vec3::ZERO,
    }
}

/// The density with which scatter draws wi, for the materials light sampling serves.
pub fn bsdf_pdf(mat: &Material, ray: &Ray, hit: &Hit, wi: Vec3) -> f32 {
    let n = if hit.front_face { hit.ns } else { -hit.ns };
    match mat.tag {
        MAT_LAMBERTIAN => n.dot(wi).max(0.0) / PI,
        MAT_MICROFACET => microfacet_pdf(mat, n, -ray.dir, wi),
        MAT_PBR => pbr_pdf(mat, n, -ray.dir, wi),
        _ => 0.0,
    }
}

/// Whether next-event estimation applies: the material has a lobe that is not a delta.
pub fn nee_applies(mat: &Material) -> bool {
    mat.tag == MAT_LAMBERTIAN || mat.tag == MAT_MICROFACET || mat.tag == MAT_PBR
}

/// Whether the 50/50 mixture samples lights: as `nee_applies`, less the smooth microfacet.
pub fn mixture_applies(mat: &Material) -> bool {
    mat.tag == MAT_LAMBERTIAN
        || mat.tag == MAT_PBR
        || (mat.tag == MAT_MICROFACET && mat.params[0] >= ALPHA_SMOOTH)
}
