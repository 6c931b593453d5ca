//! `type = "metal"`: mirror reflection, the direction perturbed by up to `fuzz` ("Ray
//! Tracing in One Weekend"). Fuzzy metal counts as a delta: its sampling's density has no
//! closed form. Shading: `shaders/materials/metal.wgsl`, CPU twin `cpu/materials/metal.rs`.

use serde::Deserialize;

use super::common::{
    material_view, one, Check, ColorDesc, Lobes, Model, OpacityDesc, TextureNames,
};
use crate::scene::records::Material;

/// Its entry in the scene format.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Desc {
    pub albedo: ColorDesc,
    /// 0 is a perfect mirror.
    #[serde(default)]
    pub fuzz: f32,
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
}

material_view! {
    /// What the shaders read of it.
    pub struct Params("MetalParams") {
        /// Reflectance.
        albedo: rgb = color,
        albedo_texture: u32 = tex_color,
        /// Radius of the sphere the mirror direction is perturbed within.
        fuzz: f32 = scalars.x,
    }
}

/// The lobes of its type: a delta (fuzz perturbs it by a law without a closed-form
/// density).
pub const LOBES: Lobes = Lobes {
    density: false,
    delta: true,
    transmission: false,
};

impl Model for Desc {
    fn check(&self, c: &mut Check) {
        c.color("albedo", &self.albedo, true);
        c.unit("fuzz", self.fuzz);
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
        LOBES
    }

    fn pack(&self, t: &TextureNames, record: &mut Material) {
        let (albedo, albedo_texture) = t.color(&self.albedo);
        Params {
            albedo,
            albedo_texture,
            fuzz: self.fuzz,
        }
        .write(record);
    }
}
