//! `type = "blend"`: two materials mixed, `(1 - weight) first + weight second`, by a
//! weight in [0, 1] or a texture's luminance (Mitsuba's `blendbsdf`). It has no lobes
//! of its own: at each hit one of the two is chosen with the probability of its share
//! (`blend_choice`, before the material's textures are looked up), and the path goes on
//! with the chosen one for everything, its light sampling included. The expected BSDF
//! is the blend's, and next-event estimation and MIS weigh the chosen material's own
//! densities, which is unbiased (stochastic material selection). Either part may be a
//! blend itself, to `MAX_BLEND_DEPTH` levels. Shading: `shaders/materials/blend.wgsl`,
//! CPU twin `cpu/materials/blend.rs`.

use serde::Deserialize;

use super::common::{material_view, Check, ColorDesc, Lobes, Model, OpacityDesc, TextureNames};
use crate::scene::records::{Material, NO_TEXTURE};

pub use crate::scene::records::MAX_BLEND_DEPTH;

/// Its entry in the scene format.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Desc {
    /// The materials mixed, by name (`[materials]` entries).
    pub first: String,
    pub second: String,
    /// The second's share: a number in [0, 1] or a texture's name (its luminance).
    pub weight: OpacityDesc,
    /// A blend emits nothing of its own (its parts may not emit either).
    #[serde(skip)]
    pub emission: ColorDesc,
}

material_view! {
    /// What the shaders read of it.
    pub struct Params("BlendParams") {
        /// The second material's share, where no texture gives it.
        weight: f32 = scalars.x,
        /// A texture whose luminance (clamped to [0, 1]) is the share, or `NO_TEXTURE`.
        weight_texture: u32 = tex_color,
        /// The two materials' indices in the material list (set by the flattener).
        first: u32 = table,
        second: u32 = pad1,
    }
}

/// The lobes of its type: none of its own (its parts' are chosen at each hit).
pub const LOBES: Lobes = Lobes {
    density: false,
    delta: false,
    transmission: false,
};

/// Points a blend's record at its two parts' places in the material list.
pub fn point_at_parts(m: &mut Material, first: u32, second: u32) {
    let mut p = Params::read(m);
    p.first = first;
    p.second = second;
    p.write(m);
}

impl Model for Desc {
    fn check(&self, c: &mut Check) {
        self.weight.check("weight", c);
    }

    fn emission(&self) -> (&ColorDesc, bool) {
        (&self.emission, false)
    }

    fn lobes(&self) -> Lobes {
        LOBES
    }

    fn pack(&self, t: &TextureNames, record: &mut Material) {
        let (weight, weight_texture) = match &self.weight {
            OpacityDesc::Value(v) => (*v, NO_TEXTURE),
            OpacityDesc::Texture(name) => (0.0, t.index(name)),
        };
        Params {
            weight,
            weight_texture,
            first: 0,
            second: 0,
        }
        .write(record);
    }
}
