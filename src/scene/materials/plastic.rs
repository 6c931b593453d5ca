//! `type = "plastic"`: a dielectric coating (`ior`, default 1.49) over a Lambertian base,
//! as Mitsuba 3's `plastic` (smooth) and `roughplastic` (GGX or Beckmann, `roughness`
//! with alpha = its square) define it. The coating reflects by the exact Fresnel
//! reflectance (a mirror, or microfacets with Smith's separable G1(wo) G1(wi)); the base
//! gets what the coating lets in, T(cos_i), and sends out what it lets out, T(cos_o),
//! its light bounced inside the coating accounted by dividing by 1 - R_int (the coating's
//! internal reflectance of diffuse light), or with `nonlinear` by 1 - albedo R_int, and
//! by ior^2 for the radiance across the boundary:
//! albedo T(cos_i) T(cos_o) cos_i / (pi ior^2 (1 - R_int)). Smooth, T = 1 - F and R_int is
//! that of a smooth boundary; rough, T is the rough boundary's transmittance (a table of
//! 64 cosines per material, in `tables`) and R_int its internal reflectance, as Mitsuba's
//! roughplastic precomputes them. Shading: `shaders/materials/plastic.wgsl`, CPU twin
//! `cpu/materials/plastic.rs`.

use std::f64::consts::PI;

use glam::DVec3;
use serde::Deserialize;

use super::common::{
    material_view, one, white_color, Check, ColorDesc, Distribution, Lobes, Model, OpacityDesc,
    TextureNames,
};
use crate::scene::microfacet_albedo::erf_approx;
use crate::scene::records::{
    Material, ALPHA_SMOOTH, MAT_FLAG_COLOR2_CLAMPED, MAT_FLAG_ENERGY,
    MS_DIELECTRIC_BECKMANN_SEPARABLE, MS_DIELECTRIC_GGX_SEPARABLE, PLASTIC_TABLE_SIZE,
};

/// Mitsuba's default diffuse reflectance of a plastic.
fn half_grey() -> ColorDesc {
    ColorDesc::Rgb([0.5; 3])
}

/// Polypropylene, Mitsuba's default `int_ior` of a plastic.
fn plastic_ior() -> f32 {
    1.49
}

/// Its entry in the scene format.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Desc {
    /// The base's reflectance (Mitsuba's `diffuse_reflectance`).
    #[serde(default = "half_grey")]
    pub albedo: ColorDesc,
    /// A tint of the coating's reflection (Mitsuba's `specular_reflectance`).
    #[serde(default = "white_color")]
    pub specular: ColorDesc,
    #[serde(default = "plastic_ior")]
    pub ior: f32,
    /// Perceptual roughness of the coating (alpha = its square); 0 is smooth.
    #[serde(default)]
    pub roughness: f32,
    #[serde(default)]
    pub distribution: Distribution,
    /// The base's light bounced inside the coating saturates its colour (Mitsuba's
    /// `nonlinear`).
    #[serde(default)]
    pub nonlinear: bool,
    #[serde(default)]
    pub emission: ColorDesc,
    /// Emit from the back side too.
    #[serde(default)]
    pub two_sided: bool,
    /// An opacity mask: a number in [0, 1] or a texture's name.
    #[serde(default)]
    pub opacity: Option<OpacityDesc>,
    /// A bump map: a height texture (its luminance) that tilts the shading normal, times
    /// `bump_scale`.
    pub bump: Option<String>,
    #[serde(default = "one")]
    pub bump_scale: f32,
    /// A normal map (Mitsuba's `normalmap`): a texture's raw colour c as the normal
    /// 2c - 1 in the frame of the surface's dp/du, n x dp/du and shading normal n.
    pub normal_map: Option<String>,
    /// The back side is black (Mitsuba's BSDFs without `twosided`); by default it
    /// reflects as the front does.
    #[serde(default)]
    pub one_sided: bool,
    /// Give a rough coating back the energy its microfacets lose to multiple
    /// scattering, reflected by the coating and let through to the base (Kulla and
    /// Conty); default: `[render] energy_compensation`.
    pub energy_compensation: Option<bool>,
}

material_view! {
    /// What the shaders read of it.
    pub struct Params("PlasticParams") {
        /// The base's reflectance.
        diffuse: rgb = color,
        diffuse_texture: u32 = tex_color,
        /// The coating's tint (a reflectance: its texture is clamped to 1).
        specular: rgb = color2,
        specular_texture: u32 = tex_color2,
        ior: f32 = scalars.x,
        /// GGX or Beckmann alpha of the coating; below ALPHA_SMOOTH a mirror.
        alpha: f32 = scalars.y,
        /// 1: Beckmann, 0: GGX.
        beckmann: f32 = scalars.z,
        /// The coating's internal reflectance of diffuse light, R_int.
        internal: f32 = scalars.w,
        /// 1: divide by 1 - albedo R_int, 0: by 1 - R_int.
        nonlinear: f32 = scalars2.x,
        /// The share of the coating in choosing a lobe (the specular colour's mean over
        /// both colours' means, as Mitsuba weighs them).
        spec_weight: f32 = scalars2.y,
        /// A rough coating's transmittance table: its first `tables` entry (placed by
        /// the flattener).
        table: u32 = table,
        /// The record's flags (`MAT_FLAG_ENERGY`: compensated).
        flags: u32 = flags,
    }
}

/// The lobes of its type: the base and a rough coating, with a density; a smooth
/// coating's mirror, a delta.
pub const LOBES: Lobes = Lobes {
    density: true,
    delta: true,
    transmission: false,
};

impl Model for Desc {
    fn check(&self, c: &mut Check) {
        c.color("albedo", &self.albedo, true);
        c.color("specular", &self.specular, true);
        c.positive("ior", self.ior);
        c.unit("roughness", self.roughness);
        c.color("emission", &self.emission, false);
    }

    fn emission(&self) -> (&ColorDesc, bool) {
        (&self.emission, self.two_sided)
    }

    fn opacity(&self) -> Option<&OpacityDesc> {
        self.opacity.as_ref()
    }

    fn bump(&self) -> Option<(&str, f32)> {
        Some((self.bump.as_deref()?, self.bump_scale))
    }

    fn uv_normal_map(&self) -> Option<&str> {
        self.normal_map.as_deref()
    }

    fn one_sided(&self) -> bool {
        self.one_sided
    }

    fn energy_compensation(&self) -> Option<Option<bool>> {
        Some(self.energy_compensation)
    }

    fn lobes(&self) -> Lobes {
        Lobes {
            density: true,
            delta: self.roughness * self.roughness < ALPHA_SMOOTH,
            transmission: false,
        }
    }

    fn pack(&self, t: &TextureNames, record: &mut Material) {
        let (diffuse, diffuse_texture) = t.color(&self.albedo);
        let (specular, specular_texture) = t.color(&self.specular);
        let alpha = self.roughness * self.roughness;
        let beckmann = self.distribution == Distribution::Beckmann;
        let (s, d) = (specular.element_sum() / 3.0, diffuse.element_sum() / 3.0);
        Params {
            diffuse,
            diffuse_texture,
            specular,
            specular_texture,
            ior: self.ior,
            alpha,
            beckmann: self.distribution.code(),
            internal: internal_reflectance(alpha, self.ior, beckmann),
            nonlinear: if self.nonlinear { 1.0 } else { 0.0 },
            spec_weight: if s + d > 0.0 { s / (s + d) } else { 0.0 },
            table: 0,
            flags: record.flags,
        }
        .write(record);
        record.flags |= MAT_FLAG_COLOR2_CLAMPED;
    }
}

/// Whether a plastic's record has a rough coating, which reads a transmittance table.
pub fn is_rough(m: &Material) -> bool {
    Params::read(m).alpha >= ALPHA_SMOOTH
}

/// Whether a plastic's record is compensated for its coating's multiple scattering: a
/// rough coating of ior above 1 with `MAT_FLAG_ENERGY` (plastic.wgsl's
/// `plastic_compensated`).
pub fn is_compensated(m: &Material) -> bool {
    compensates(&Params::read(m))
}

/// `is_compensated` of a record's view.
pub fn compensates(p: &Params) -> bool {
    p.flags & MAT_FLAG_ENERGY != 0 && p.alpha >= ALPHA_SMOOTH && p.ior > 1.0
}

/// The dielectric albedo tables a compensated plastic's record reads
/// (`microfacet_albedo::DielectricVariant`: the separable masking's, by distribution).
pub fn ms_variant(m: &Material) -> Option<u32> {
    if !is_compensated(m) {
        return None;
    }
    Some(if Params::read(m).beckmann > 0.5 {
        MS_DIELECTRIC_BECKMANN_SEPARABLE
    } else {
        MS_DIELECTRIC_GGX_SEPARABLE
    })
}

/// Whether a rough plastic's record has Beckmann microfacets (`HAS_BECKMANN`).
pub fn is_beckmann(m: &Material) -> bool {
    is_rough(m) && Params::read(m).beckmann > 0.5
}

/// Points a rough plastic's record at its transmittance table, placed at `tables` entry
/// `offset`.
pub fn point_at_table(m: &mut Material, offset: u32) {
    let mut p = Params::read(m);
    p.table = offset;
    p.write(m);
}

/// A rough plastic's record's transmittance table (`transmittance_table` of its alpha,
/// ior and distribution).
pub fn table_of(m: &Material) -> Vec<f32> {
    let p = Params::read(m);
    transmittance_table(p.alpha, p.ior, p.beckmann > 0.5)
}

// ------------------------------------------------- the coating's tables (f64, on load)

/// The exact Fresnel reflectance of a dielectric boundary seen at cosine c > 0 from the
/// side of relative index eta = eta_i / eta_t (1 under total internal reflection).
fn fresnel(c: f64, eta: f64) -> f64 {
    let s2 = eta * eta * (1.0 - c * c).max(0.0);
    if s2 >= 1.0 {
        return 1.0;
    }
    let ct = (1.0 - s2).sqrt();
    let a = (c - eta * ct) / (c + eta * ct);
    let b = (eta * c - ct) / (eta * c + ct);
    0.5 * (a * a + b * b)
}

/// Smith's G1 of direction v (v.z > 0 the side it sees) for the isotropic distribution.
fn g1(v: DVec3, alpha: f64, beckmann: bool) -> f64 {
    let tan2 = (v.x * v.x + v.y * v.y) / (v.z * v.z);
    if tan2 == 0.0 {
        return 1.0;
    }
    let lambda = if beckmann {
        let a = 1.0 / (alpha * tan2.sqrt());
        0.5 * (erf_approx(a) - 1.0) + (-a * a).exp() / (2.0 * a * PI.sqrt())
    } else {
        0.5 * ((1.0 + alpha * alpha * tan2).sqrt() - 1.0)
    };
    1.0 / (1.0 + lambda)
}

/// The mean over the visible normals m of the distribution seen from wi (cos mu) of
/// `f(wi, m)`: the midpoint rule over normals drawn in proportion to D(m) cos(theta_m)
/// (the inverse CDF x of each distribution, reached as x = 1 - (1 - y)^2 from the rule's
/// y, whose Jacobian 2 (1 - y) cancels the weight's 1 / cos(theta_m) ~ (1 - x)^(-1/2)
/// singularity at GGX's grazing normals), weighted by G1(wi) (wi . m)^+ / cos(theta_m),
/// self-normalized.
fn visible_mean(mu: f64, alpha: f64, beckmann: bool, f: impl Fn(DVec3, DVec3) -> f64) -> f64 {
    const N: usize = 96;
    let wi = DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let g1_i = g1(wi, alpha, beckmann);
    let (mut sum, mut weight) = (0.0, 0.0);
    for i in 0..N {
        let y = (i as f64 + 0.5) / N as f64;
        let x = 1.0 - (1.0 - y) * (1.0 - y);
        let jacobian = 2.0 * (1.0 - y);
        let tan2 = if beckmann {
            -alpha * alpha * (1.0 - x).ln()
        } else {
            alpha * alpha * x / (1.0 - x)
        };
        let cos_m = 1.0 / (1.0 + tan2).sqrt();
        let sin_m = (1.0 - cos_m * cos_m).max(0.0).sqrt();
        for j in 0..N {
            let phi = 2.0 * PI * (j as f64 + 0.5) / N as f64;
            let m = DVec3::new(sin_m * phi.cos(), sin_m * phi.sin(), cos_m);
            let w = jacobian * g1_i * wi.dot(m).max(0.0) / cos_m;
            if w > 0.0 {
                sum += w * f(wi, m);
                weight += w;
            }
        }
    }
    if weight > 0.0 {
        sum / weight
    } else {
        0.0
    }
}

/// The cosines the transmittance table is at: i / (SIZE - 1), the first at 1e-6 (as
/// Mitsuba's).
fn table_cosine(i: usize) -> f64 {
    (i as f64 / (PLASTIC_TABLE_SIZE - 1) as f64).max(1e-6)
}

/// The fraction of light arriving at cosine mu from outside that a rough boundary of
/// `ior` lets in: the visible normals' mean of (1 - F(wi . m)) G1(wt), wt refracted
/// through m.
fn transmittance(mu: f64, alpha: f64, ior: f64, beckmann: bool) -> f64 {
    let eta = 1.0 / ior;
    visible_mean(mu, alpha, beckmann, |wi, m| {
        let c = wi.dot(m);
        let s2 = eta * eta * (1.0 - c * c);
        if s2 >= 1.0 {
            return 0.0;
        }
        let ct = (1.0 - s2).sqrt();
        let wt = -eta * wi + (eta * c - ct) * m;
        if wt.z >= 0.0 {
            // refracted back up (a coating of ior below 1): nothing gets in
            return 0.0;
        }
        (1.0 - fresnel(c, eta)) * g1(-wt, alpha, beckmann)
    })
}

/// A rough coating's transmittance at PLASTIC_TABLE_SIZE cosines (`table_cosine`), what
/// plastic.wgsl's `plastic_transmittance` interpolates; rows of 4 for `tables`.
pub fn transmittance_table(alpha: f32, ior: f32, beckmann: bool) -> Vec<f32> {
    (0..PLASTIC_TABLE_SIZE as usize)
        .map(|i| transmittance(table_cosine(i), alpha as f64, ior as f64, beckmann) as f32)
        .collect()
}

/// The coating's internal reflectance of diffuse light from the base, R_int = 2 times the
/// integral over mu of R(mu) mu. Smooth: the exact Fresnel reflectance from inside,
/// taken as 1 - (1 - R_ext) / ior^2 from the external one R_ext (the identity of the two,
/// which keeps a white base's albedo at 1 exactly; the midpoint rule on 256 cosines).
/// Rough: the rough boundary's reflectance from inside, the visible normals' mean of
/// F(wi . m) G1(wr), wr reflected about m, averaged as Mitsuba 3's roughplastic averages
/// it: 2 times the mean of R(mu) mu over PLASTIC_TABLE_SIZE cosines evenly spaced from 0
/// to 1, both ends included (which reads about 1.6% under the integral; kept, so that
/// images agree with Mitsuba's).
pub fn internal_reflectance(alpha: f32, ior: f32, beckmann: bool) -> f32 {
    let (alpha, ior) = (alpha as f64, ior as f64);
    if alpha < ALPHA_SMOOTH as f64 {
        const N: usize = 256;
        let r_ext: f64 = (0..N)
            .map(|i| {
                let mu = (i as f64 + 0.5) / N as f64;
                2.0 * fresnel(mu, 1.0 / ior) * mu / N as f64
            })
            .sum();
        return (1.0 - (1.0 - r_ext) / (ior * ior)) as f32;
    }
    let n = PLASTIC_TABLE_SIZE as usize;
    let sum: f64 = (0..n)
        .map(|i| {
            let mu = table_cosine(i);
            let r = visible_mean(mu, alpha, beckmann, |wi, m| {
                let wr = 2.0 * wi.dot(m) * m - wi;
                if wr.z <= 0.0 {
                    return 0.0;
                }
                fresnel(wi.dot(m), ior) * g1(wr, alpha, beckmann)
            });
            r * mu
        })
        .sum();
    (2.0 * sum / n as f64) as f32
}
