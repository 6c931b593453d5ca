//! `type = "emissive"`: a light that absorbs what reaches it. Its radiance is the
//! surface's emission (`common::Surface`); it scatters nothing. Shading:
//! `shaders/materials/emissive.wgsl`, CPU twin `cpu/materials/emissive.rs`.

use serde::Deserialize;

use super::common::{material_view, Check, ColorDesc, Lobes, Model, TextureNames};
use crate::scene::records::Material;

/// Its entry in the scene format.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Desc {
    /// Emitted from the front side, or both with `two_sided`.
    pub radiance: ColorDesc,
    #[serde(default)]
    pub two_sided: bool,
}

material_view! {
    /// It has no parameters of its own.
    pub struct Params("EmissiveParams") {}
}

/// The lobes of its type: none; it absorbs.
pub const LOBES: Lobes = Lobes {
    density: false,
    delta: false,
    transmission: false,
};

impl Model for Desc {
    fn check(&self, c: &mut Check) {
        c.color("radiance", &self.radiance, false);
    }

    fn emission(&self) -> (&ColorDesc, bool) {
        (&self.radiance, self.two_sided)
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn pack(&self, _: &TextureNames, _: &mut Material) {}
}
