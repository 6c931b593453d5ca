//! `type = "thin_dielectric"`: a window of zero thickness (Mitsuba 3's
//! `thindielectric`): light goes straight through or reflects, with the multiple
//! reflections between its two faces summed, R' = R + T^2 R / (1 - R^2) for the exact
//! Fresnel reflectance R of `ior` and T = 1 - R; the transmission is 1 - R'. `tint`
//! multiplies what goes through, `specular` what reflects. Both deltas: no light is
//! sampled through it. Shading: `shaders/materials/thin_dielectric.wgsl`, CPU twin
//! `cpu/materials/thin_dielectric.rs`.

use serde::Deserialize;

use super::common::{
    glass_ior, material_view, one, white_color, Check, ColorDesc, Lobes, Model, OpacityDesc,
    TextureNames,
};
use crate::scene::records::{Material, MAT_FLAG_COLOR2_CLAMPED};

/// Its entry in the scene format.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Desc {
    #[serde(default = "glass_ior")]
    pub ior: f32,
    /// Multiplies the transmission (Mitsuba's `specular_transmittance`).
    #[serde(default = "white_color")]
    pub tint: ColorDesc,
    /// Multiplies the reflection (Mitsuba's `specular_reflectance`).
    #[serde(default = "white_color")]
    pub specular: ColorDesc,
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
}

material_view! {
    /// What the shaders read of it.
    pub struct Params("ThinDielectricParams") {
        tint: rgb = color,
        tint_texture: u32 = tex_color,
        /// The reflection's tint (a reflectance: its texture is clamped to 1).
        specular: rgb = color2,
        specular_texture: u32 = tex_color2,
        /// The index of refraction of the sheet (outside is 1).
        ior: f32 = scalars.x,
    }
}

/// The lobes of its type: two deltas (the reflection and the straight transmission).
pub const LOBES: Lobes = Lobes {
    density: false,
    delta: true,
    transmission: false,
};

impl Model for Desc {
    fn check(&self, c: &mut Check) {
        c.positive("ior", self.ior);
        c.color("tint", &self.tint, true);
        c.color("specular", &self.specular, true);
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

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn pack(&self, t: &TextureNames, record: &mut Material) {
        let (tint, tint_texture) = t.color(&self.tint);
        let (specular, specular_texture) = t.color(&self.specular);
        Params {
            tint,
            tint_texture,
            specular,
            specular_texture,
            ior: self.ior,
        }
        .write(record);
        record.flags |= MAT_FLAG_COLOR2_CLAMPED;
    }
}
