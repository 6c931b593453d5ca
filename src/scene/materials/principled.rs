//! `type = "principled"`: the Disney principled BSDF (Burley 2012, 2015) as Mitsuba 3's
//! `principled` defines it, parameter for parameter, so that its scenes render alike.
//! With m = metallic, t = spec_trans, the lobes' weights are brdf = (1 - m)(1 - t) and
//! bsdf = (1 - m) t; alpha = max(0.001, roughness^2), over (anisotropic) sqrt(1 - 0.9
//! anisotropic) along the tangent and times it along the bitangent; GGX with Smith's
//! separable G1(wo) G1(wi); eta = `eta`, or 2 / (1 - sqrt(0.08 specular)) - 1. From
//! outside (the front, or either side of one that does not transmit):
//! - main reflection F D G / (4 cos_o), F = (1 - m)(1 - spec_tint) F_dielectric(wo . h)
//!   + m Schlick(base_color) + (1 - m) spec_tint Schlick(base_color / lum x R0(eta));
//! - transmission sqrt(base_color) bsdf (1 - F_d) D G |wo.h wi.h| / (cos_o (wo.h + eta
//!   wi.h)^2) (radiance: the 1 / eta^2 across the boundary included);
//! - clearcoat 0.25 clearcoat Schlick(0.04) D_GTR1 G (alpha 0.25) cos_i, GTR1's alpha
//!   mix(0.1, 0.001, clearcoat_gloss) (without the 4 cos_o cos_i of a microfacet lobe:
//!   Mitsuba's, as Disney's reference code);
//! - diffuse brdf base_color / pi cos_i mix(f_d + f_retro, f_ss, flatness) with Burley's
//!   retro-reflection and Hanrahan-Krueger's flattened subsurface;
//! - sheen sheen (1 - m) Schlick weight(wi . h) mix(1, base_color / lum, sheen_tint)
//!   cos_i, where brdf > 0.
//!
//! From inside one that transmits: bsdf F_d reflected, bsdf (1 - F_d) sqrt(base_color)
//! transmitted. Like Mitsuba's, it is not energy-conserving: the diffuse lobe's
//! retro-reflection, sheen and clearcoat add to the specular reflection, so a white one
//! may reflect more than it receives at grazing angles. With `energy_compensation`, Kulla
//! and Conty's lobe gives the main reflection back what its microfacets scatter more than
//! once, coloured by the average of its Fresnel. Every parameter but `eta` and
//! `specular` may be a texture (its luminance, for the scalars). Shading:
//! `shaders/materials/principled.wgsl`, CPU twin `cpu/materials/principled.rs`.

use serde::Deserialize;

use super::common::{
    material_view, one, Check, ColorDesc, Lobes, Model, OpacityDesc, TextureNames,
};
use crate::scene::microfacet_albedo;
use crate::scene::records::{Material, MAT_FLAG_ANISOTROPIC};

fn half_grey() -> ColorDesc {
    ColorDesc::Rgb([0.5; 3])
}

fn half() -> OpacityDesc {
    OpacityDesc::Value(0.5)
}

fn zero() -> OpacityDesc {
    OpacityDesc::Value(0.0)
}

/// Its entry in the scene format (Mitsuba's parameter names and defaults).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Desc {
    #[serde(default = "half_grey")]
    pub base_color: ColorDesc,
    #[serde(default = "half")]
    pub roughness: OpacityDesc,
    #[serde(default = "zero")]
    pub anisotropic: OpacityDesc,
    #[serde(default = "zero")]
    pub metallic: OpacityDesc,
    /// The share of the dielectric part that transmits (0: opaque).
    #[serde(default = "zero")]
    pub spec_trans: OpacityDesc,
    #[serde(default = "zero")]
    pub spec_tint: OpacityDesc,
    #[serde(default = "zero")]
    pub sheen: OpacityDesc,
    #[serde(default = "zero")]
    pub sheen_tint: OpacityDesc,
    /// Blends the diffuse lobe toward the flattened subsurface one.
    #[serde(default = "zero")]
    pub flatness: OpacityDesc,
    #[serde(default = "zero")]
    pub clearcoat: OpacityDesc,
    #[serde(default = "zero")]
    pub clearcoat_gloss: OpacityDesc,
    /// The index of refraction (interior over exterior); or `specular`, not both.
    pub eta: Option<f32>,
    /// The dielectric's reflectance at normal incidence x 12.5 (default 0.5: eta 1.5).
    pub specular: Option<f32>,
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
    /// The back side is black (Mitsuba's principled without `twosided`); by default it
    /// reflects as the front does. Not for one that transmits, whose back is its inside.
    #[serde(default)]
    pub one_sided: bool,
    /// Give the main reflection back the energy it loses to multiple scattering (Kulla
    /// and Conty); default: `[render] energy_compensation` (off, as Mitsuba has none).
    pub energy_compensation: Option<bool>,
}

material_view! {
    /// What the shaders read of it.
    pub struct Params("PrincipledParams") {
        /// A reflectance: its texture is clamped to 1.
        base_color: rgb = color,
        base_color_texture: u32 = tex_color,
        roughness: f32 = scalars.x,
        anisotropic: f32 = scalars.y,
        metallic: f32 = scalars.z,
        spec_trans: f32 = scalars.w,
        spec_tint: f32 = scalars2.x,
        sheen: f32 = scalars2.y,
        sheen_tint: f32 = scalars2.z,
        flatness: f32 = scalars2.w,
        clearcoat: f32 = color3.x,
        clearcoat_gloss: f32 = color3.y,
        /// The index of refraction, interior over exterior.
        eta: f32 = color3.z,
        /// 1: it transmits (spec_trans given), and its back side is its inside.
        transmits: f32 = color3.w,
        /// The hit's tangent, which `material_at` writes for an anisotropic one.
        tangent: rgb = normal2,
        /// 1 at a hit on the back side (`material_at` writes it).
        back_face: f32 = normal2.w,
        /// The scalars' textures, two 16-bit indices a word (low half first, in the order
        /// of [`SCALARS`]; `NO_SCALAR_TEXTURE` where none).
        textures0: u32 = tex_data0,
        textures1: u32 = tex_data1,
        textures2: u32 = tex_data2,
        textures3: u32 = tex_data3,
        textures4: u32 = tex_data4,
        /// The exact dielectric Fresnel's average over the hemisphere at `eta`.
        fresnel_avg: f32 = color2.x,
        /// The record's flags (`MAT_FLAG_ENERGY`: compensated).
        flags: u32 = flags,
    }
}

/// A scalar without a texture, in its half of a `textures` word.
pub const NO_SCALAR_TEXTURE: u32 = 0xffff;

/// The scalar parameters that take a texture, in the order of the `textures` words.
pub const SCALARS: [&str; 10] = [
    "roughness",
    "anisotropic",
    "metallic",
    "spec_trans",
    "spec_tint",
    "sheen",
    "sheen_tint",
    "flatness",
    "clearcoat",
    "clearcoat_gloss",
];

/// The lobes of its type: all have a density (alpha is at least 0.001), and one that
/// transmits weighs directions through the surface.
pub const LOBES: Lobes = Lobes {
    density: true,
    delta: false,
    transmission: true,
};

impl Desc {
    /// The scalars in the order of [`SCALARS`].
    fn scalars(&self) -> [&OpacityDesc; 10] {
        [
            &self.roughness,
            &self.anisotropic,
            &self.metallic,
            &self.spec_trans,
            &self.spec_tint,
            &self.sheen,
            &self.sheen_tint,
            &self.flatness,
            &self.clearcoat,
            &self.clearcoat_gloss,
        ]
    }

    /// Whether it transmits: `spec_trans` a texture or above 0 (Mitsuba's flag).
    pub fn transmits(&self) -> bool {
        !matches!(self.spec_trans, OpacityDesc::Value(v) if v <= 0.0)
    }

    /// Its index of refraction: `eta`, or the one of `specular` (0.5: 1.5); a
    /// transmitting one's is kept off 1 (1.001), as Mitsuba's.
    pub fn eta(&self) -> f32 {
        match (self.eta, self.specular) {
            (Some(eta), _) => {
                if self.transmits() && eta == 1.0 {
                    1.001
                } else {
                    eta
                }
            }
            (None, s) => {
                let mut s = s.unwrap_or(0.5);
                if self.transmits() && s == 0.0 {
                    s = 1e-3;
                }
                2.0 / (1.0 - (0.08 * s).sqrt()) - 1.0
            }
        }
    }
}

impl Model for Desc {
    fn check(&self, c: &mut Check) {
        c.color("base_color", &self.base_color, true);
        for (name, s) in SCALARS.iter().zip(self.scalars()) {
            s.check(name, c);
            if let OpacityDesc::Texture(t) = s {
                if c.texture_position(t)
                    .is_some_and(|i| i >= NO_SCALAR_TEXTURE as usize)
                {
                    c.push(name, format!("a principled material's textures are the scene's first {NO_SCALAR_TEXTURE}"));
                }
            }
        }
        match (self.eta, self.specular) {
            (Some(_), Some(_)) => c.push("eta", "give eta or specular, not both".into()),
            (Some(eta), None) => c.positive("eta", eta),
            (None, Some(s)) => c.unit("specular", s),
            (None, None) => {}
        }
        c.color("emission", &self.emission, false);
        if self.one_sided && self.transmits() {
            c.push(
                "one_sided",
                "a principled material that transmits (spec_trans) has an inside for a back side"
                    .into(),
            );
        }
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

    fn anisotropic(&self) -> bool {
        !matches!(self.anisotropic, OpacityDesc::Value(v) if v == 0.0)
    }

    fn energy_compensation(&self) -> Option<Option<bool>> {
        Some(self.energy_compensation)
    }

    fn lobes(&self) -> Lobes {
        Lobes {
            density: true,
            delta: false,
            transmission: self.transmits(),
        }
    }

    fn pack(&self, t: &TextureNames, record: &mut Material) {
        let (base_color, base_color_texture) = t.color(&self.base_color);
        let mut value = [0.0f32; 10];
        let mut words = [u32::MAX; 5];
        for (i, s) in self.scalars().into_iter().enumerate() {
            let index = match s {
                OpacityDesc::Value(v) => {
                    value[i] = *v;
                    NO_SCALAR_TEXTURE
                }
                OpacityDesc::Texture(name) => t.index(name),
            };
            let shift = 16 * (i % 2);
            words[i / 2] = (words[i / 2] & !(0xffff << shift)) | (index << shift);
        }
        Params {
            base_color,
            base_color_texture,
            roughness: value[0],
            anisotropic: value[1],
            metallic: value[2],
            spec_trans: if self.transmits() { value[3] } else { 0.0 },
            spec_tint: value[4],
            sheen: value[5],
            sheen_tint: value[6],
            flatness: value[7],
            clearcoat: value[8],
            clearcoat_gloss: value[9],
            eta: self.eta(),
            transmits: if self.transmits() { 1.0 } else { 0.0 },
            tangent: glam::Vec3::ZERO,
            back_face: 0.0,
            textures0: words[0],
            textures1: words[1],
            textures2: words[2],
            textures3: words[3],
            textures4: words[4],
            fresnel_avg: microfacet_albedo::dielectric_average(self.eta()),
            flags: record.flags,
        }
        .write(record);
        if self.anisotropic() {
            record.flags |= MAT_FLAG_ANISOTROPIC;
        }
    }
}

/// The texture indices a principled record reads for its scalars (for
/// `materials::mark_own_colors`, which looks at whole words).
pub fn scalar_textures(m: &Material) -> Vec<u32> {
    let p = Params::read(m);
    [
        p.textures0,
        p.textures1,
        p.textures2,
        p.textures3,
        p.textures4,
    ]
    .iter()
    .flat_map(|w| [w & 0xffff, w >> 16])
    .filter(|&i| i != NO_SCALAR_TEXTURE)
    .collect()
}
