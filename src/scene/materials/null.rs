//! `type = "null"`: no surface at all, only a boundary: rays pass straight through it,
//! uncounted (as through a transparent alpha surface: its opacity is 0), and a shape of it
//! with `interior` or `exterior` media is where a medium begins and ends (Mitsuba's
//! `null`). Shading: `shaders/materials/null.wgsl`, CPU twin `cpu/materials/null.rs`.

use serde::Deserialize;

use super::common::{material_view, Check, ColorDesc, Lobes, Model, OpacityDesc, TextureNames};
use crate::scene::records::Material;

/// Its entry in the scene format: no keys.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Desc {}

material_view! {
    /// It has no parameters of its own.
    pub struct Params("NullParams") {}
}

/// The lobes of its type: a delta straight on, for a ray that meets it after the alpha
/// loop's last pass-through (`MAX_ALPHA_SKIPS`).
pub const LOBES: Lobes = Lobes {
    density: false,
    delta: true,
    transmission: false,
};

static BLACK: ColorDesc = ColorDesc::Rgb([0.0; 3]);
static CLEAR: OpacityDesc = OpacityDesc::Value(0.0);

impl Model for Desc {
    fn check(&self, _: &mut Check) {}

    fn emission(&self) -> (&ColorDesc, bool) {
        (&BLACK, false)
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn opacity(&self) -> Option<&OpacityDesc> {
        Some(&CLEAR)
    }

    fn pack(&self, _: &TextureNames, _: &mut Material) {}
}
