//! Mirrors `shaders/materials/pbr.wgsl`.

use glam::Vec3;

use crate::cpu::bindings::Bindings;
use crate::cpu::bsdf::{
    density_sample, ggx_d, ggx_lobes_pdf, lobe_prob, luminance, ms_lobe, ms_loss, ms_scaling,
    ms_schlick_single, ms_schlick_single_average, ms_under, sample_ggx_lobes, smith_g2, Scatter,
    Shading, ABSORBED, ALPHA_SMOOTH,
};
use crate::cpu::sampling::{sample_cosine_hemisphere, PI};
use crate::cpu::textures::{map_normal, texture_alpha, texture_at};
use crate::cpu::types::{Hit, Ray};
use crate::scene::materials::pbr::{sheen_albedo_table, Params};
use crate::scene::records::{
    MAT_FLAG_ENERGY, MS_GGX_CORRELATED, NO_TEXTURE, SHEEN_ALPHA_MIN, SHEEN_TABLE_SIZE,
};

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

/// The base's BSDF x cos (pbr.wgsl's `pbr_base_eval`, which says why the base is
/// weighted as it is): mix((1 - F_d(cos_i)) (1 - F_d(cos_o)) base / pi cos_i + F_d(v . h)
/// S, F_m(v . h) S, metallic), S = D G2 / (4 cos_o).
pub fn base_eval(p: &Params, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
    let cos_o = n.dot(wo);
    let cos_i = n.dot(wi);
    if cos_o <= 0.0 || cos_i <= 0.0 {
        return Vec3::ZERO;
    }
    let alpha = p.alpha;
    let h = (wo + wi).normalize();
    let vh = wo.dot(h);
    let spec = ggx_d(n.dot(h), alpha) * smith_g2(cos_o, cos_i, alpha) / (4.0 * cos_o);
    let mut through =
        (Vec3::ONE - dielectric_fresnel(p, cos_i)) * (Vec3::ONE - dielectric_fresnel(p, cos_o));
    let metallic = p.metallic;
    let mut ms = Vec3::ZERO;
    // compensated: both lobes' multiple scattering, and the base under what the
    // compensated dielectric lobe reflects
    if p.flags & MAT_FLAG_ENERGY != 0 {
        let f0 = dielectric_fresnel(p, 1.0);
        let f90 = Vec3::splat(p.specular);
        through = ms_under(MS_GGX_CORRELATED, alpha, cos_o, cos_i, f0, f90);
        let f_avg = (f0 + (f90 - f0) / 21.0)
            .lerp(p.base_color + (Vec3::ONE - p.base_color) / 21.0, metallic);
        ms = ms_lobe(MS_GGX_CORRELATED, alpha, cos_o, cos_i, f_avg);
    }
    let dielectric = through * p.base_color * (cos_i / PI) + dielectric_fresnel(p, vh) * spec;
    dielectric * (1.0 - metallic) + metal_fresnel(p, vh) * spec * metallic + ms
}

/// The Charlie sheen distribution at cos(theta_h) = c (pbr.wgsl's `charlie_d`).
pub fn charlie_d(c: f32, alpha: f32) -> f32 {
    let inv = 1.0 / alpha;
    (2.0 + inv) * (1.0 - c * c).max(0.0).powf(0.5 * inv) / (2.0 * PI)
}

/// Estevez and Kulla's fit of the Charlie distribution's log Lambda (pbr.wgsl's
/// `charlie_l`).
pub fn charlie_l(x: f32, alpha: f32) -> f32 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let mix = |a: f32, b: f32| a + (b - a) * t;
    let (a, b, c) = (
        mix(21.5473, 25.3245),
        mix(3.82987, 3.32435),
        mix(0.19823, 0.16801),
    );
    let (d, e) = (mix(-1.97760, -1.27393), mix(-4.32054, -4.85967));
    a / (1.0 + b * x.powf(c)) + d * x + e
}

/// Smith's Lambda of the Charlie distribution at cos c (pbr.wgsl's `charlie_lambda`).
pub fn charlie_lambda(c: f32, alpha: f32) -> f32 {
    if c < 0.5 {
        return charlie_l(c, alpha).exp();
    }
    (2.0 * charlie_l(0.5, alpha) - charlie_l(1.0 - c, alpha)).exp()
}

/// The white sheen's directional albedo at cos c and alpha, read bilinearly from the
/// table in sqrt(c) and alpha (pbr.wgsl's `sheen_albedo`, which reads the scene's copy
/// of it).
pub fn sheen_albedo(c: f32, alpha: f32) -> f32 {
    let table = sheen_albedo_table();
    let size = SHEEN_TABLE_SIZE;
    let last = (size - 1) as f32;
    let x = c.clamp(0.0, 1.0).sqrt() * last;
    let y = alpha.clamp(0.0, 1.0) * last;
    let x0 = (x as u32).min(size - 2);
    let y0 = (y as u32).min(size - 2);
    let (fx, fy) = (x - x0 as f32, y - y0 as f32);
    let i = (y0 * size + x0) as usize;
    let j = i + size as usize;
    let mix = |a: f32, b: f32, t: f32| a + (b - a) * t;
    let e0 = mix(table[i], table[i + 1], fx);
    let e1 = mix(table[j], table[j + 1], fx);
    mix(e0, e1, fy)
}

/// The sheen over the layer under it (pbr.wgsl's `pbr_sheen_over`, which says why the
/// lobe is divided by max(1, E(cos_o), E(cos_i))).
pub fn sheen_over(p: &Params, n: Vec3, wo: Vec3, wi: Vec3, under: Vec3) -> Vec3 {
    let cos_o = n.dot(wo);
    let cos_i = n.dot(wi);
    if cos_o <= 0.0 || cos_i <= 0.0 {
        return under;
    }
    let a = p.sheen_alpha;
    let m = p.sheen_color.max_element();
    let (e_o, e_i) = (sheen_albedo(cos_o, a), sheen_albedo(cos_i, a));
    let scale = (1.0 - m * e_o.min(1.0)).min(1.0 - m * e_i.min(1.0));
    let h = (wo + wi).normalize();
    let s = charlie_d(n.dot(h), a)
        / (4.0
            * cos_o
            * (1.0 + charlie_lambda(cos_o, a) + charlie_lambda(cos_i, a))
            * e_o.max(e_i).max(1.0));
    under * scale + p.sheen_color * s
}

/// The coat's normal toward wo (pbr.wgsl's `pbr_coat_normal`).
pub fn coat_normal(p: &Params, n: Vec3, wo: Vec3) -> Vec3 {
    let c = p.coat_normal;
    if c.dot(c) > 0.0 {
        let nc = c * if c.dot(n) >= 0.0 { 1.0 } else { -1.0 };
        if nc.dot(wo) > 0.0 {
            return nc;
        }
    }
    n
}

/// Fresnel-Schlick of the coat, ior 1.5 (pbr.wgsl's `pbr_coat_fresnel`).
pub fn coat_fresnel(c: f32) -> f32 {
    let m = 1.0 - c.clamp(0.0, 1.0);
    0.04 + 0.96 * (m * m * m * m * m)
}

/// The clearcoat over the layer under it (pbr.wgsl's `pbr_coat_over`).
pub fn coat_over(p: &Params, n: Vec3, wo: Vec3, wi: Vec3, under: Vec3) -> Vec3 {
    let nc = coat_normal(p, n, wo);
    let cos_o = nc.dot(wo);
    let cos_i = nc.dot(wi);
    let cc = p.clearcoat;
    let mut through =
        Vec3::splat((1.0 - cc * coat_fresnel(cos_o)) * (1.0 - cc * coat_fresnel(cos_i)));
    if p.flags & MAT_FLAG_ENERGY != 0 {
        let (f0, f90) = (Vec3::splat(0.04 * cc), Vec3::splat(cc));
        let (a, v) = (p.coat_alpha, MS_GGX_CORRELATED);
        through = ms_scaling(
            ms_schlick_single(v, a, cos_o, f0, f90),
            ms_schlick_single(v, a, cos_i, f0, f90),
            ms_schlick_single_average(v, a, f0, f90),
        );
    }
    let mut f = under * through;
    if cos_o > 0.0 && cos_i > 0.0 {
        let h = (wo + wi).normalize();
        let a = p.coat_alpha;
        f += Vec3::splat(
            cc * coat_fresnel(wo.dot(h)) * ggx_d(nc.dot(h), a) * smith_g2(cos_o, cos_i, a)
                / (4.0 * cos_o),
        );
    }
    f
}

/// Whether the material has a layer (the GPU's HAS_PBR_LAYERS code, which gives a
/// material without one the base's values exactly).
fn layered(p: &Params) -> bool {
    p.clearcoat > 0.0 || p.sheen_color != Vec3::ZERO
}

/// The probabilities of the coat's lobe and the sheen's (pbr.wgsl's `pbr_layer_probs`).
pub fn layer_probs(p: &Params, n: Vec3, wo: Vec3) -> [f32; 2] {
    let cos_o = n.dot(wo);
    let coat = p.clearcoat * coat_fresnel(coat_normal(p, n, wo).dot(wo));
    let mut through = 1.0 - coat;
    let e = sheen_albedo(cos_o, p.sheen_alpha).min(1.0);
    let sheen = through * luminance(p.sheen_color) * e;
    through *= 1.0 - p.sheen_color.max_element() * e;
    let fd = dielectric_fresnel(p, cos_o);
    let m = p.metallic;
    let base = through
        * luminance(
            (fd + (Vec3::ONE - fd) * p.base_color) * (1.0 - m) + metal_fresnel(p, cos_o) * m,
        );
    let mut pc = 0.0;
    let mut ps = 0.0;
    if coat > 0.0 {
        pc = (coat / (coat + sheen + base)).clamp(0.1, 0.9);
    }
    if sheen > 0.0 {
        ps = (1.0 - pc) * (sheen / (sheen + base)).clamp(0.1, 0.9);
    }
    [pc, ps]
}

/// Probability of sampling the GGX lobe: its share at the view angle.
pub fn spec_prob(p: &Params, cos_o: f32) -> f32 {
    let fd = dielectric_fresnel(p, cos_o);
    let metallic = p.metallic;
    let ws = luminance(fd * (1.0 - metallic) + metal_fresnel(p, cos_o) * metallic);
    let mut wd = (1.0 - p.metallic) * luminance((Vec3::ONE - fd) * p.base_color);
    // the cosine lobe samples the compensation's lobe too
    if p.flags & MAT_FLAG_ENERGY != 0 {
        wd += ms_loss(MS_GGX_CORRELATED, p.alpha, cos_o);
    }
    lobe_prob(ws, wd)
}

impl Shading for Params {
    /// glTF's metallicRoughnessTexture (green scales the roughness, so alpha by its
    /// square; blue the metallic factor) and KHR_materials_specular's specularTexture
    /// (its alpha scales the specular factor).
    fn textures(&self, b: &Bindings, hit: &Hit) -> Self {
        let mut q = *self;
        if self.clearcoat_texture != NO_TEXTURE {
            q.clearcoat *= texture_at(b, self.clearcoat_texture, hit).x.min(1.0);
        }
        if self.clearcoat_roughness_texture != NO_TEXTURE {
            let g = texture_at(b, self.clearcoat_roughness_texture, hit)
                .y
                .min(1.0);
            q.coat_alpha = (q.coat_alpha * g * g).max(ALPHA_SMOOTH);
        }
        // the coat's own normal map, else the surface's normal as it is where the base
        // has a normal map, which is not the coat's
        if self.coat_normal_texture != NO_TEXTURE {
            q.coat_normal = map_normal(b, self.coat_normal_texture, self.coat_normal_scale, hit);
        } else if self.base_normal_mapped > 0.0 {
            q.coat_normal = hit.ns;
        }
        if self.sheen_color_texture != NO_TEXTURE {
            q.sheen_color = texture_at(b, self.sheen_color_texture, hit).min(Vec3::ONE);
        }
        if self.sheen_roughness_texture != NO_TEXTURE {
            let a = texture_alpha(b, self.sheen_roughness_texture, hit.uv).min(1.0);
            q.sheen_alpha = (q.sheen_alpha * a * a).max(SHEEN_ALPHA_MIN);
        }
        if self.metallic_roughness_texture != NO_TEXTURE {
            let mr = texture_at(b, self.metallic_roughness_texture, hit).min(Vec3::ONE);
            q.alpha = (q.alpha * mr.y * mr.y).max(ALPHA_SMOOTH);
            q.metallic *= mr.z;
        }
        if self.specular_texture != NO_TEXTURE {
            q.specular *= texture_alpha(b, self.specular_texture, hit.uv).min(1.0);
        }
        q
    }

    /// BSDF x cos(theta_i) (pbr.wgsl's `pbr_eval`): the base under the sheen, under the
    /// clearcoat.
    fn eval(&self, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
        let mut f = base_eval(self, n, wo, wi);
        if self.sheen_color != Vec3::ZERO {
            f = sheen_over(self, n, wo, wi, f);
        }
        if self.clearcoat > 0.0 {
            f = coat_over(self, n, wo, wi, f);
        }
        f
    }

    /// The base's mixture and the layers' lobes with their probabilities (pbr.wgsl's
    /// `pbr_pdf`).
    fn pdf(&self, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        let pdf = ggx_lobes_pdf(spec_prob(self, n.dot(wo)), self.alpha, n, wo, wi);
        if !layered(self) {
            return pdf;
        }
        let [pc, ps] = layer_probs(self, n, wo);
        pdf * (1.0 - pc - ps)
            + pc * ggx_lobes_pdf(1.0, self.coat_alpha, coat_normal(self, n, wo), wo, wi)
            + ps * n.dot(wi).max(0.0) / PI
    }

    /// The coat's lobe, the sheen's or the base's (the GGX lobe or the cosine one, chosen
    /// by spec_prob), u.x reused; weight = eval / pdf of the mixture.
    fn scatter(&self, ray: &Ray, hit: &Hit, u: [f32; 2]) -> Scatter {
        let side = if hit.front_face { 1.0 } else { -1.0 };
        let n = side * hit.ns;
        let wo = -ray.dir;
        let cos_o = n.dot(wo);
        if cos_o <= 0.0 {
            return ABSORBED;
        }
        let wi = if !layered(self) {
            sample_ggx_lobes(spec_prob(self, cos_o), self.alpha, n, wo, u)
        } else {
            let [pc, ps] = layer_probs(self, n, wo);
            if u[0] < pc {
                let nc = coat_normal(self, n, wo);
                sample_ggx_lobes(1.0, self.coat_alpha, nc, wo, [u[0] / pc, u[1]])
            } else if u[0] < pc + ps {
                sample_cosine_hemisphere(n, [(u[0] - pc) / ps, u[1]])
            } else {
                let ub = [(u[0] - pc - ps) / (1.0 - pc - ps), u[1]];
                sample_ggx_lobes(spec_prob(self, cos_o), self.alpha, n, wo, ub)
            }
        };
        density_sample(wi, self.eval(n, wo, wi), self.pdf(n, wo, wi), side, hit)
    }
}
