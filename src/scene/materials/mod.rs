//! Materials, one module each: its entry in the scene format, the checks of its values,
//! its record (through its view, `Params`), the lobes it scatters by, and where it has
//! one, the mapping of glTF and .mtl materials onto it. Its shading is
//! `shaders/materials/NAME.wgsl`, with the CPU twin `cpu/materials/NAME.rs` beside it.
//!
//! The type list below is the one place that names them all: the scene format's `type`,
//! the record's tag (`MAT_NAME` in the shaders), the shader define of the code a scene
//! needs (`HAS_NAME`), the GPU and CPU dispatch and the shader files embedded all follow
//! from it. Adding a material: its module here, its WGSL file, its CPU twin, a line of the
//! list, its rows in the tests.
//!
//! The material modules import `common` and never this file: it imports them.

pub mod blend;
pub mod common;
pub mod conductor;
pub mod dielectric;
pub mod emissive;
pub mod lambertian;
pub mod metal;
pub mod microfacet;
pub mod null;
pub mod pbr;
pub mod plastic;
pub mod principled;
pub mod thin_dielectric;

use serde::Deserialize;

use crate::scene::records::{
    Material, MAT_FLAG_ALPHA_BLEND, MAT_FLAG_ANISOTROPIC, MAT_FLAG_BUMP, MAT_FLAG_DELTA,
    MAT_FLAG_ENERGY, MAT_FLAG_NEE, MAT_FLAG_ONE_SIDED, MAT_FLAG_OPACITY_TEXTURE,
    MAT_FLAG_OWN_COLORS, MAT_FLAG_STRICT_SHADING, MAT_FLAG_STRICT_VIEW, MAT_FLAG_TRANSMITS,
    MAT_FLAG_TWO_SIDED, MAT_FLAG_UV_NORMAL_MAP,
};
use common::{Check, Lobes, Model, OpacityDesc, Surface, TextureNames, View};

/// Calls macro `$then` with the type list: for each material, its doc comment, its
/// [`MaterialKind`] variant, its tag, its module (its name in the format, its WGSL file,
/// its CPU twin) and its shader define. `gpu::shader` (the embedded WGSL files) and
/// `cpu::materials` (the dispatch) expand it too.
macro_rules! for_each_material {
    ($then:ident) => {
        $then! {
            /// The ideal diffuse reflector.
            Lambertian = 0, lambertian, "HAS_LAMBERTIAN";
            /// A light that absorbs.
            Emissive = 1, emissive, "HAS_EMISSIVE";
            /// A mirror, perturbed by fuzz.
            Metal = 2, metal, "HAS_METAL";
            /// Smooth glass.
            Dielectric = 3, dielectric, "HAS_DIELECTRIC";
            /// Cook-Torrance over a Lambertian base.
            Microfacet = 4, microfacet, "HAS_MICROFACET";
            /// glTF's metallic-roughness material.
            Pbr = 5, pbr, "HAS_PBR";
            /// A metal by its complex index of refraction, smooth or rough.
            Conductor = 6, conductor, "HAS_CONDUCTOR";
            /// A window of zero thickness.
            ThinDielectric = 7, thin_dielectric, "HAS_THIN_DIELECTRIC";
            /// A dielectric coating over a Lambertian base.
            Plastic = 8, plastic, "HAS_PLASTIC";
            /// Two materials mixed by a weight.
            Blend = 9, blend, "HAS_BLEND";
            /// The Disney principled BSDF, as Mitsuba 3 defines it.
            Principled = 10, principled, "HAS_PRINCIPLED";
            /// No surface: a medium's boundary that rays pass straight through.
            Null = 11, null, "HAS_NULL";
        }
    };
}
pub(crate) use for_each_material;

macro_rules! material_types {
    ($( $(#[$doc:meta])* $kind:ident = $tag:literal, $module:ident, $define:literal; )*) => {
        /// A material's type: the record's tag.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        #[repr(u32)]
        pub enum MaterialKind {
            $( $(#[$doc])* $kind = $tag, )*
        }

        impl MaterialKind {
            /// Every material, in tag order.
            pub const ALL: &'static [MaterialKind] = &[$(MaterialKind::$kind),*];

            /// Its tag in the record.
            pub fn tag(self) -> u32 {
                self as u32
            }

            pub fn from_tag(tag: u32) -> Option<Self> {
                match tag {
                    $( $tag => Some(MaterialKind::$kind), )*
                    _ => None,
                }
            }

            /// Its name: the format's `type`, its module, its WGSL file.
            pub fn name(self) -> &'static str {
                match self {
                    $( MaterialKind::$kind => stringify!($module), )*
                }
            }

            /// The shader define that keeps its code.
            pub fn define(self) -> &'static str {
                match self {
                    $( MaterialKind::$kind => $define, )*
                }
            }

            /// Its view: the names of its places in the record.
            pub fn view(self) -> &'static View {
                match self {
                    $( MaterialKind::$kind => &$module::Params::VIEW, )*
                }
            }

            /// The lobes a material of this type may have (which of its shading
            /// functions exist).
            pub fn lobes(self) -> Lobes {
                match self {
                    $( MaterialKind::$kind => $module::LOBES, )*
                }
            }
        }

        /// `[materials]` entries, selected by `type`. Every type may emit: `emission` (a
        /// colour or a texture) is the radiance of its front side, which makes it a light
        /// too (`emissive` calls it `radiance`).
        // pbr's (with its layers' keys) is the largest by far; a scene's materials are
        // few and read once, so they are not boxed
        #[allow(clippy::large_enum_variant)]
        #[derive(Debug, Clone, Deserialize)]
        #[serde(tag = "type", rename_all = "snake_case")]
        pub enum MaterialDesc {
            $( $(#[$doc])* $kind($module::Desc), )*
        }

        impl MaterialDesc {
            pub fn kind(&self) -> MaterialKind {
                match self {
                    $( MaterialDesc::$kind(_) => MaterialKind::$kind, )*
                }
            }

            /// Its module's answers.
            pub fn model(&self) -> &dyn Model {
                match self {
                    $( MaterialDesc::$kind(d) => d, )*
                }
            }
        }
    };
}

for_each_material!(material_types);

impl MaterialKind {
    /// Its tag's name in the shaders (`MAT_PBR`).
    pub fn wgsl_tag(self) -> String {
        format!("MAT_{}", self.name().to_ascii_uppercase())
    }
}

impl MaterialDesc {
    /// Its problems as (key, message), each under the key `key` gives its field (the
    /// format's name: `fuzz`, `base_color`, ...); colours may name `textures`.
    pub fn check(
        &self,
        key: &dyn Fn(&str) -> String,
        textures: &[String],
    ) -> Vec<(String, String)> {
        let mut c = Check::new(key, textures);
        let model = self.model();
        model.check(&mut c);
        if let Some((name, scale)) = model.bump() {
            c.texture("bump", name);
            c.finite("bump_scale", scale);
        }
        if let Some(name) = model.uv_normal_map() {
            c.texture("normal_map", name);
            if model.bump().is_some() {
                c.push(
                    "normal_map",
                    "a material takes a bump map or a normal map, not both".into(),
                );
            }
        }
        if let Some(o) = model.opacity() {
            o.check("opacity", &mut c);
            if self.emits() {
                c.push(
                    "opacity",
                    "a light cannot be masked: leave out the opacity or the emission".into(),
                );
            }
        }
        c.problems()
    }

    /// Whether its microfacet lobes are compensated for multiple scattering: its own
    /// `energy_compensation` key, else `render_default` (`[render]
    /// energy_compensation`); never for a type without such lobes.
    pub fn compensated(&self, render_default: bool) -> bool {
        match self.model().energy_compensation() {
            Some(own) => own.unwrap_or(render_default),
            None => false,
        }
    }

    /// The flags that take its shading normals strictly (`[render] shading_normals =
    /// "strict"`): `MAT_FLAG_STRICT_SHADING`, and `MAT_FLAG_STRICT_VIEW` where all its
    /// lobes reflect (not glass, smooth or rough, thin or not, nor a principled material
    /// that transmits).
    pub fn strict_shading_flags(&self) -> u32 {
        let reflects = !matches!(
            self.kind(),
            MaterialKind::Dielectric | MaterialKind::ThinDielectric
        ) && !self.model().lobes().transmission;
        MAT_FLAG_STRICT_SHADING | if reflects { MAT_FLAG_STRICT_VIEW } else { 0 }
    }

    /// Whether it emits light: a texture or a colour above 0 (a record's `emits`).
    pub fn emits(&self) -> bool {
        self.model().emission().0.is_bright()
    }

    /// The normal map it reads (its mesh then needs tangents).
    pub fn normal_map(&self) -> Option<&str> {
        self.model().normal_map()
    }

    /// Whether its mesh needs tangents: for a normal map, or anisotropic roughness.
    pub fn needs_tangents(&self) -> bool {
        self.normal_map().is_some() || self.model().anisotropic()
    }

    /// Its record, with `textures` in record order: the tag, the emission and the flags
    /// of its answers, then its own parameters through its view.
    pub fn record(&self, textures: &[String]) -> Material {
        let model = self.model();
        let names = TextureNames(textures);
        let (emission, two_sided) = model.emission();
        let lobes = model.lobes();
        debug_assert!(lobes.within(self.kind().lobes()), "{:?}", self.kind());
        let mut record = Material {
            tag: self.kind().tag(),
            ..Default::default()
        };
        let flag = |on: bool, f: u32| if on { f } else { 0 };
        record.flags = flag(two_sided, MAT_FLAG_TWO_SIDED)
            | flag(self.compensated(false), MAT_FLAG_ENERGY)
            | flag(model.one_sided(), MAT_FLAG_ONE_SIDED)
            | flag(lobes.density, MAT_FLAG_NEE)
            | flag(lobes.delta, MAT_FLAG_DELTA)
            | flag(lobes.transmission, MAT_FLAG_TRANSMITS);
        let mut surface = Surface::read(&record);
        (surface.emission, surface.emission_texture) = names.color(emission);
        surface.write(&mut record);
        model.pack(&names, &mut record);
        // an opacity mask: stochastic transparency where it is below 1
        let mut surface = Surface::read(&record);
        match model.opacity() {
            Some(OpacityDesc::Value(v)) if *v < 1.0 => {
                surface.opacity = *v;
                record.flags |= MAT_FLAG_ALPHA_BLEND;
            }
            Some(OpacityDesc::Texture(name)) => {
                surface.opacity = 1.0;
                surface.opacity_texture = names.index(name);
                record.flags |= MAT_FLAG_ALPHA_BLEND | MAT_FLAG_OPACITY_TEXTURE;
            }
            _ => {}
        }
        // a bump map, in the place of a normal map (no type has both)
        if let Some((name, scale)) = model.bump() {
            surface.normal_texture = names.index(name);
            surface.normal_scale = scale;
            record.flags |= MAT_FLAG_BUMP;
        }
        // a normal map in the frame of dp/du, in the same place (a type has one of the two)
        if let Some(name) = model.uv_normal_map() {
            surface.normal_texture = names.index(name);
            surface.normal_scale = 1.0;
            record.flags |= MAT_FLAG_UV_NORMAL_MAP;
        }
        surface.write(&mut record);
        record
    }
}

/// Whether a material's record reads the hit's dp/du (`HAS_BUMP`): for a bump map, for a
/// normal map in its frame (Mitsuba's), and for an anisotropic roughness taken strictly
/// (`MAT_FLAG_STRICT_SHADING`: Mitsuba's frames follow dp/du).
pub fn reads_uv_derivatives(m: &Material) -> bool {
    m.flags & (MAT_FLAG_BUMP | MAT_FLAG_UV_NORMAL_MAP) != 0
        || m.flags & (MAT_FLAG_ANISOTROPIC | MAT_FLAG_STRICT_SHADING)
            == MAT_FLAG_ANISOTROPIC | MAT_FLAG_STRICT_SHADING
}

/// Marks a material that reads a mesh attribute (`is_attribute` of a texture index) in any
/// of its texture places, so that `material_at` does not also tint it by the vertex colours
/// (`MAT_FLAG_OWN_COLORS`). The opacity texture counts where the flags say it is one.
pub fn mark_own_colors(m: &mut Material, is_attribute: impl Fn(u32) -> bool) {
    if reads_texture(m, is_attribute) {
        m.flags |= MAT_FLAG_OWN_COLORS;
    }
}

/// Whether a material's record reads a texture `is` picks in any of its texture places
/// (the opacity texture where the flags say it is one, a principled material's scalars).
pub fn reads_texture(m: &Material, is: impl Fn(u32) -> bool) -> bool {
    let places = [
        m.tex_color,
        m.tex_color2,
        m.tex_emission,
        m.tex_data0,
        m.tex_data1,
        m.tex_data2,
        m.tex_data3,
        m.tex_data4,
        m.tex_data5,
    ];
    let opacity = m.flags & MAT_FLAG_OPACITY_TEXTURE != 0 && is(m.tex_opacity);
    // a principled material packs two scalars' textures a word
    let scalars = m.tag == MaterialKind::Principled.tag()
        && principled::scalar_textures(m).into_iter().any(&is);
    opacity || scalars || places.into_iter().any(&is)
}

/// The key of field `field` of a material imported from a file whose fields have other
/// names (`keys`: glTF's JSON paths, .mtl statements), under `prefix`.
pub fn imported_key(prefix: &str, keys: &[(&str, &str)], field: &str) -> String {
    let name = keys
        .iter()
        .find(|(f, _)| *f == field)
        .map_or(field, |(_, k)| k);
    if prefix.is_empty() {
        name.to_string()
    } else {
        format!("{prefix}.{name}")
    }
}

/// The constants of the material tags, as the shaders get them (`MAT_PBR`).
pub fn tag_constants() -> Vec<(String, u32)> {
    MaterialKind::ALL
        .iter()
        .map(|k| (k.wgsl_tag(), k.tag()))
        .collect()
}

impl Material {
    /// Whether the record emits light: an emission texture or a colour above 0.
    pub fn emits(&self) -> bool {
        let s = Surface::read(self);
        s.emission_texture != crate::scene::records::NO_TEXTURE
            || s.emission.to_array().iter().any(|&c| c > 0.0)
    }

    /// Whether next-event estimation applies at it (its module's `Lobes::density`).
    pub fn nee(&self) -> bool {
        self.flags & MAT_FLAG_NEE != 0
    }
}
