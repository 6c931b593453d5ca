//! `type = "conductor"`: a metal by its complex index of refraction, as Mitsuba 3's
//! `conductor` and `roughconductor` define it: the exact conductor Fresnel of `eta + i k`
//! per RGB channel (a named `material` from the measured table, `scene::metals`, or
//! `eta` and `k` given), tinted by `specular`; a mirror below `ALPHA_SMOOTH`, else GGX
//! or Beckmann microfacets (`distribution`) of alpha = `roughness`^2 (or `roughness_u`
//! along the tangent and `roughness_v` along the bitangent), sampled by their visible normals,
//! with Smith's separable masking-shadowing G1(wo) G1(wi); with `energy_compensation`,
//! Kulla and Conty's lobe for what the microfacets scatter more than once
//! (`scene::microfacet_albedo`), coloured by the Fresnel's average. Shading:
//! `shaders/materials/conductor.wgsl`, CPU twin `cpu/materials/conductor.rs`.

use serde::Deserialize;

use super::common::{
    material_view, one, white_color, Check, ColorDesc, Distribution, Lobes, Model, OpacityDesc,
    Roughness, TextureNames,
};
use crate::scene::metals::{metal, METALS};
use crate::scene::microfacet_albedo;
use crate::scene::records::{Material, MAT_FLAG_ANISOTROPIC};

/// Its entry in the scene format.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Desc {
    /// A named conductor (`"Au"`, `"Cu"`, ... `scene::metals`); `"none"`, a perfect
    /// mirror, when neither it nor `eta` and `k` are given.
    pub material: Option<String>,
    pub eta: Option<[f32; 3]>,
    pub k: Option<[f32; 3]>,
    /// A tint of the reflection (Mitsuba's `specular_reflectance`).
    #[serde(default = "white_color")]
    pub specular: ColorDesc,
    /// Perceptual roughness (alpha = its square; 0: a mirror), or `roughness_u` along
    /// the tangent and `roughness_v` along the bitangent.
    pub roughness: Option<f32>,
    pub roughness_u: Option<f32>,
    pub roughness_v: Option<f32>,
    #[serde(default)]
    pub distribution: Distribution,
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
    /// Give the rough lobe back the energy it loses to multiple scattering (Kulla and
    /// Conty); default: `[render] energy_compensation`.
    pub energy_compensation: Option<bool>,
}

material_view! {
    /// What the shaders read of it.
    pub struct Params("ConductorParams") {
        /// The tint (a reflectance: clamped to 1).
        specular: rgb = color,
        specular_texture: u32 = tex_color,
        /// The real and imaginary parts of the index of refraction, per channel.
        eta: rgb = color2,
        k: rgb = color3,
        /// GGX or Beckmann alpha along the tangent and the bitangent.
        alpha_u: f32 = scalars.x,
        alpha_v: f32 = scalars.y,
        /// 1: Beckmann, 0: GGX.
        beckmann: f32 = scalars.z,
        /// The hit's tangent, which `material_at` writes for an anisotropic one
        /// (`MAT_FLAG_ANISOTROPIC`); zero elsewhere (the normal's own frame).
        tangent: rgb = normal2,
        /// The Fresnel reflectance's average over the hemisphere, 2 int F(mu) mu dmu,
        /// per channel (the colour of the energy compensation).
        fresnel_avg: rgb = scalars2,
        /// The record's flags (`MAT_FLAG_ENERGY`: compensated).
        flags: u32 = flags,
    }
}

/// The lobes of its type: the microfacet lobe, with a density; the mirror a smooth one
/// is, a delta.
pub const LOBES: Lobes = Lobes {
    density: true,
    delta: true,
    transmission: false,
};

/// Whether a conductor's record has Beckmann microfacets (`HAS_BECKMANN`).
pub fn is_beckmann(m: &Material) -> bool {
    Params::read(m).beckmann > 0.5
}

/// The names `material` may take, for an error message.
pub fn known_metals() -> String {
    METALS.iter().map(|m| m.0).collect::<Vec<_>>().join(", ")
}

impl Desc {
    fn roughness(&self) -> Roughness {
        Roughness {
            roughness: self.roughness,
            roughness_u: self.roughness_u,
            roughness_v: self.roughness_v,
        }
    }

    /// (eta, k): given, or the named material's (`none` by default).
    fn index(&self) -> ([f32; 3], [f32; 3]) {
        match (self.eta, self.k) {
            (Some(eta), Some(k)) => (eta, k),
            _ => metal(self.material.as_deref().unwrap_or("none")).unwrap_or(([0.0; 3], [1.0; 3])),
        }
    }
}

impl Model for Desc {
    fn check(&self, c: &mut Check) {
        if let Some(name) = &self.material {
            if metal(name).is_none() {
                c.push(
                    "material",
                    format!("unknown conductor \"{name}\" (known: {})", known_metals()),
                );
            }
            if self.eta.is_some() || self.k.is_some() {
                c.push("material", "give material, or eta and k, not both".into());
            }
        }
        match (self.eta, self.k) {
            (Some(eta), Some(k)) => {
                c.nonnegative3("eta", eta);
                c.nonnegative3("k", k);
            }
            (Some(_), None) => c.push("eta", "needs k beside it".into()),
            (None, Some(_)) => c.push("k", "needs eta beside it".into()),
            (None, None) => {}
        }
        c.color("specular", &self.specular, true);
        self.roughness().check(c);
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

    fn lobes(&self) -> Lobes {
        let smooth = self.roughness().smooth();
        Lobes {
            density: !smooth,
            delta: smooth,
            transmission: false,
        }
    }

    fn anisotropic(&self) -> bool {
        !self.roughness().smooth() && self.roughness().anisotropic()
    }

    fn energy_compensation(&self) -> Option<Option<bool>> {
        Some(self.energy_compensation)
    }

    fn pack(&self, t: &TextureNames, record: &mut Material) {
        let (specular, specular_texture) = t.color(&self.specular);
        let (eta, k) = self.index();
        let (alpha_u, alpha_v) = self.roughness().packed();
        Params {
            specular,
            specular_texture,
            eta: eta.into(),
            k: k.into(),
            alpha_u,
            alpha_v,
            beckmann: self.distribution.code(),
            tangent: glam::Vec3::ZERO,
            fresnel_avg: microfacet_albedo::conductor_average(eta, k).into(),
            flags: record.flags,
        }
        .write(record);
        if self.anisotropic() {
            record.flags |= MAT_FLAG_ANISOTROPIC;
        }
    }
}
