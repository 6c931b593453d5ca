//! `type = "microfacet"`: Cook-Torrance, a GGX specular lobe (`roughness` taken as GGX
//! alpha, Schlick's Fresnel from `ior`, colour `specular`, default `albedo`) over a
//! Lambertian base that receives what the specular lobe does not reflect. Below
//! `ALPHA_SMOOTH` the specular lobe is a mirror: a delta. Shading:
//! `shaders/materials/microfacet.wgsl`, CPU twin `cpu/materials/microfacet.rs`.

use serde::Deserialize;

use super::common::{
    glass_ior, material_view, one, Check, ColorDesc, Lobes, Model, OpacityDesc, TextureNames,
};
use crate::scene::records::{Material, ALPHA_SMOOTH, MAT_FLAG_COLOR2_CLAMPED};

/// Its entry in the scene format.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Desc {
    pub albedo: ColorDesc,
    pub specular: Option<ColorDesc>,
    pub roughness: f32,
    #[serde(default = "glass_ior")]
    pub ior: f32,
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
    /// Give the GGX lobe back the energy it loses to multiple scattering, and the base
    /// what the compensated lobe leaves (Kulla and Conty); default: `[render]
    /// energy_compensation`.
    pub energy_compensation: Option<bool>,
}

material_view! {
    /// What the shaders read of it.
    pub struct Params("MicrofacetParams") {
        /// The Lambertian base's colour.
        diffuse: rgb = color,
        diffuse_texture: u32 = tex_color,
        /// GGX alpha (the format's `roughness` as it is).
        alpha: f32 = scalars.x,
        ior: f32 = scalars.y,
        /// The specular lobe's colour (a reflectance: its texture is clamped to 1,
        /// `MAT_FLAG_COLOR2_CLAMPED`).
        specular: rgb = color2,
        specular_texture: u32 = tex_color2,
        /// The record's flags (`MAT_FLAG_ENERGY`: compensated).
        flags: u32 = flags,
    }
}

/// The lobes of its type: the diffuse base and the GGX lobe, with a density; the mirror
/// a smooth one samples, a delta.
pub const LOBES: Lobes = Lobes {
    density: true,
    delta: true,
    transmission: false,
};

impl Model for Desc {
    fn check(&self, c: &mut Check) {
        c.color("albedo", &self.albedo, true);
        if let Some(ks) = &self.specular {
            c.color("specular", ks, true);
        }
        c.unit("roughness", self.roughness);
        c.positive("ior", self.ior);
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
            delta: self.roughness < ALPHA_SMOOTH,
            transmission: false,
        }
    }

    fn pack(&self, t: &TextureNames, record: &mut Material) {
        let (diffuse, diffuse_texture) = t.color(&self.albedo);
        let (specular, specular_texture) = t.color(self.specular.as_ref().unwrap_or(&self.albedo));
        Params {
            diffuse,
            diffuse_texture,
            alpha: self.roughness,
            ior: self.ior,
            specular,
            specular_texture,
            flags: record.flags,
        }
        .write(record);
        // the specular colour is a reflectance: a texture may not push it past 1
        record.flags |= MAT_FLAG_COLOR2_CLAMPED;
    }
}
