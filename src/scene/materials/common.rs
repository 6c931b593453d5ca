//! What every material module is made of: the colour parameter of the format
//! ([`ColorDesc`]), the checks of its values ([`Check`]), the answers the integrator asks
//! for ([`Lobes`]), the trait each material's description implements ([`Model`]), and the
//! views that name a material's places in the record ([`material_view!`], [`Surface`]).
//! The material modules import this file; it imports none of them.

use glam::Vec3;
use serde::Deserialize;

use crate::scene::records::{Material, NO_TEXTURE};

/// A colour parameter: `[r, g, b]`, or the name of a `[textures]` entry.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum ColorDesc {
    Rgb([f32; 3]),
    Texture(String),
}

impl ColorDesc {
    /// The colour, or white where a texture gives it.
    pub fn rgb(&self) -> [f32; 3] {
        match self {
            ColorDesc::Rgb(c) => *c,
            ColorDesc::Texture(_) => [1.0; 3],
        }
    }

    pub fn texture(&self) -> Option<&str> {
        match self {
            ColorDesc::Rgb(_) => None,
            ColorDesc::Texture(name) => Some(name),
        }
    }

    /// Whether it is a light's radiance that gives light: a texture, or a component
    /// above 0.
    pub fn is_bright(&self) -> bool {
        self.texture().is_some() || self.rgb().iter().any(|&c| c > 0.0)
    }
}

/// `opacity` of any material (Mitsuba's `mask`): a number in [0, 1], or a texture's name
/// whose luminance is the opacity at a hit. Where it is below 1 a ray passes through with
/// probability 1 - opacity (stochastic transparency, as glTF's blend), shadow rays too.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum OpacityDesc {
    Value(f32),
    Texture(String),
}

impl OpacityDesc {
    /// Its problems under `field`: a value in [0, 1], or a texture that exists.
    pub fn check(&self, field: &str, c: &mut Check) {
        match self {
            OpacityDesc::Value(v) => c.unit(field, *v),
            OpacityDesc::Texture(name) => c.texture(field, name),
        }
    }
}

impl Default for ColorDesc {
    fn default() -> Self {
        ColorDesc::Rgb([0.0; 3])
    }
}

/// White, the default of tints and base colours.
pub fn white_color() -> ColorDesc {
    ColorDesc::Rgb([1.0; 3])
}

/// The index of refraction of glass, the default of every `ior`.
pub fn glass_ior() -> f32 {
    1.5
}

pub fn one() -> f32 {
    1.0
}

/// A .mtl colour component clamped to 1; an infinity or a NaN is kept for the
/// material's check to find.
pub fn at_most_one(x: f32) -> f32 {
    if x.is_finite() && x > 1.0 {
        1.0
    } else {
        x
    }
}

/// The lobes a material scatters by: what light sampling can do at it. Its module
/// answers once for a material ([`Model::lobes`]); the answer is packed into the record's
/// flags (`MAT_FLAG_NEE`, `MAT_FLAG_DELTA`), which the shaders, the CPU reference and the
/// GPU plan read. The lobes a type may have at all (its module's `LOBES`) say which of
/// its functions exist: `NAME_scatter` with any lobe, `NAME_eval` and `NAME_pdf` with a
/// density; the dispatch's default (absorb, 0) serves the others.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Lobes {
    /// A lobe with a density (`eval`, `pdf`): next-event estimation weighs light samples
    /// at the material.
    pub density: bool,
    /// A delta lobe (a mirror, a refraction), found only by the material's own sampling:
    /// the 50/50 mixture, whose pdf cannot hold it, leaves the material out.
    pub delta: bool,
    /// Its lobe with a density transmits (rough glass): `bsdf_eval` weighs directions
    /// under the surface too, and shading normals send nothing over it.
    pub transmission: bool,
}

impl Lobes {
    /// Whether it scatters at all.
    pub fn any(self) -> bool {
        self.density || self.delta
    }

    /// Whether every lobe of `self` is one of `kind`'s.
    pub fn within(self, kind: Lobes) -> bool {
        (!self.density || kind.density)
            && (!self.delta || kind.delta)
            && (!self.transmission || kind.transmission)
    }
}

/// A material's values checked: each problem under the key its source gives the field
/// (`materials.NAME.fuzz` in a scene file, `materials[2].pbrMetallicRoughness
/// .roughnessFactor` in a glTF file, `Ns` in a .mtl file), so a scene file's materials
/// and imported ones pass the same checks with their own names.
pub struct Check<'a> {
    key: &'a dyn Fn(&str) -> String,
    /// The textures a colour may name.
    textures: &'a [String],
    problems: Vec<(String, String)>,
}

impl<'a> Check<'a> {
    pub fn new(key: &'a dyn Fn(&str) -> String, textures: &'a [String]) -> Self {
        Check {
            key,
            textures,
            problems: Vec::new(),
        }
    }

    /// Every problem found, as (key, message).
    pub fn problems(self) -> Vec<(String, String)> {
        self.problems
    }

    pub fn push(&mut self, field: &str, message: String) {
        self.problems.push(((self.key)(field), message));
    }

    /// A number in [0, 1].
    pub fn unit(&mut self, field: &str, x: f32) {
        if !(0.0..=1.0).contains(&x) {
            self.push(field, format!("must be in [0, 1], got {x}"));
        }
    }

    /// A finite number above 0.
    pub fn positive(&mut self, field: &str, x: f32) {
        if !(x > 0.0 && x.is_finite()) {
            self.push(field, format!("must be > 0, got {x}"));
        }
    }

    /// A finite number of at least `lo`.
    pub fn at_least(&mut self, field: &str, x: f32, lo: f32) {
        if !(x >= lo && x.is_finite()) {
            self.push(field, format!("must be >= {lo}, got {x}"));
        }
    }

    pub fn finite(&mut self, field: &str, x: f32) {
        if !x.is_finite() {
            self.push(field, format!("must be finite, got {x}"));
        }
    }

    /// Three finite numbers; false (and a problem) when one is not.
    pub fn finite3(&mut self, field: &str, v: [f32; 3]) -> bool {
        let ok = v.iter().all(|x| x.is_finite());
        if !ok {
            self.push(field, format!("must be finite, got {v:?}"));
        }
        ok
    }

    /// Three finite numbers, none below 0.
    pub fn nonnegative3(&mut self, field: &str, v: [f32; 3]) {
        if self.finite3(field, v) && v.iter().any(|&x| x < 0.0) {
            self.push(field, format!("must be >= 0, got {v:?}"));
        }
    }

    /// A colour (each component >= 0, and <= 1 for a reflectance), or the name of a
    /// texture that exists (reflectance textures are clamped to 1 at look-up).
    pub fn color(&mut self, field: &str, c: &ColorDesc, reflectance: bool) {
        match c {
            ColorDesc::Rgb(rgb) => {
                self.nonnegative3(field, *rgb);
                if reflectance && rgb.iter().any(|&a| a > 1.0) {
                    self.push(field, "components must be <= 1".into());
                }
            }
            ColorDesc::Texture(name) => self.texture(field, name),
        }
    }

    /// The name of a texture that exists.
    /// The record index texture `name` will have, if it is defined.
    pub fn texture_position(&self, name: &str) -> Option<usize> {
        self.textures.iter().position(|n| n == name)
    }

    pub fn texture(&mut self, field: &str, name: &str) {
        if !self.textures.iter().any(|n| n == name) {
            let known = if self.textures.is_empty() {
                "none".to_string()
            } else {
                self.textures.join(", ")
            };
            self.push(
                field,
                format!("unknown texture \"{name}\" (defined: {known})"),
            );
        }
    }
}

/// The scene's textures by name, in record order: a name's index is its record's.
pub struct TextureNames<'a>(pub &'a [String]);

impl TextureNames<'_> {
    /// The index of texture `name` (validated to exist).
    pub fn index(&self, name: &str) -> u32 {
        self.0
            .iter()
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("texture {name} was validated to exist")) as u32
    }

    /// A colour parameter's value (white where a texture gives it) and its texture (or
    /// `NO_TEXTURE`).
    pub fn color(&self, c: &ColorDesc) -> (Vec3, u32) {
        match c {
            ColorDesc::Rgb(rgb) => (Vec3::from(*rgb), NO_TEXTURE),
            ColorDesc::Texture(name) => (Vec3::ONE, self.index(name)),
        }
    }

    /// An optional texture's index, or `NO_TEXTURE`.
    pub fn optional(&self, name: Option<&str>) -> u32 {
        name.map_or(NO_TEXTURE, |n| self.index(n))
    }
}

/// What each material's description does, whatever its type: its module implements it,
/// and `scene::materials::MaterialDesc` dispatches to it.
pub trait Model {
    /// Its problems, under the format's own key names (the [`Check`] maps them).
    fn check(&self, c: &mut Check);
    /// The radiance it emits from its front side, and whether from both sides.
    fn emission(&self) -> (&ColorDesc, bool);
    /// The lobes it scatters by: some of its type's (its module's `LOBES`).
    fn lobes(&self) -> Lobes;
    /// Writes its parameters into the record through its view (the caller has set the
    /// tag, the emission and the flags of [`Model::emission`] and [`Model::lobes`]).
    fn pack(&self, textures: &TextureNames, record: &mut Material);
    /// The normal map it reads (its mesh then needs tangents).
    fn normal_map(&self) -> Option<&str> {
        None
    }
    /// Whether its roughness is anisotropic (its mesh then needs tangents too).
    fn anisotropic(&self) -> bool {
        false
    }
    /// Its opacity mask (`opacity`), for the types that take one.
    fn opacity(&self) -> Option<&OpacityDesc> {
        None
    }
    /// Its bump map (`bump`, `bump_scale`), for the types that take one.
    fn bump(&self) -> Option<(&str, f32)> {
        None
    }
    /// Its normal map in the frame of dp/du (`normal_map` of the types that take a bump
    /// map: Mitsuba's `normalmap`), for the types that take one.
    fn uv_normal_map(&self) -> Option<&str> {
        None
    }
    /// Whether its back side is black (`one_sided`), for the types that only reflect.
    fn one_sided(&self) -> bool {
        false
    }
    /// For a type with microfacet lobes that energy compensation applies to, its own
    /// `energy_compensation` key (None: as `[render]` says); None for the other types.
    fn energy_compensation(&self) -> Option<Option<bool>> {
        None
    }
}

/// A microfacet distribution's name in the format: `ggx` (the default) or `beckmann`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Distribution {
    #[default]
    Ggx,
    Beckmann,
}

impl Distribution {
    /// As the record holds it: 1 for Beckmann, 0 for GGX.
    pub fn code(self) -> f32 {
        match self {
            Distribution::Ggx => 0.0,
            Distribution::Beckmann => 1.0,
        }
    }
}

/// Isotropic `roughness` or anisotropic `roughness_u` and `roughness_v` (the other
/// axis defaulting to `roughness`, else 0), checked: each in [0, 1]. Perceptual, as
/// dielectric's and glTF's: the distribution's alpha is its square. (The format's
/// entries list the three keys themselves: serde's flatten cannot refuse unknown keys.)
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Roughness {
    pub roughness: Option<f32>,
    pub roughness_u: Option<f32>,
    pub roughness_v: Option<f32>,
}

impl Roughness {
    /// (alpha along the tangent, alpha along the bitangent): the squares.
    pub fn alphas(&self) -> (f32, f32) {
        let r = self.roughness.unwrap_or(0.0);
        let (u, v) = (self.roughness_u.unwrap_or(r), self.roughness_v.unwrap_or(r));
        (u * u, v * v)
    }

    /// Below `ALPHA_SMOOTH` on both axes: a mirror (a delta).
    pub fn smooth(&self) -> bool {
        let (u, v) = self.alphas();
        u.max(v) < crate::scene::records::ALPHA_SMOOTH
    }

    pub fn anisotropic(&self) -> bool {
        let (u, v) = self.alphas();
        u != v
    }

    /// The alphas the record holds: as given when smooth, else at least 1e-4 on each
    /// axis (a rough lobe divides by both).
    pub fn packed(&self) -> (f32, f32) {
        let (u, v) = self.alphas();
        if self.smooth() {
            (u, v)
        } else {
            (u.max(1e-4), v.max(1e-4))
        }
    }

    pub fn check(&self, c: &mut Check) {
        for (key, x) in [
            ("roughness", self.roughness),
            ("roughness_u", self.roughness_u),
            ("roughness_v", self.roughness_v),
        ] {
            if let Some(x) = x {
                c.unit(key, x);
            }
        }
        if self.roughness.is_some() && self.roughness_u.is_some() && self.roughness_v.is_some() {
            c.push(
                "roughness",
                "give roughness, or roughness_u and roughness_v, not all three".into(),
            );
        }
    }
}

/// The type of a field of a view: a colour (the `.xyz` of a vec4 place), one scalar lane
/// of a vec4 place, or a u32 place (a texture index).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldKind {
    Rgb,
    /// A point or a direction (a primitive's): a vec3 as `Rgb` is.
    Vec3,
    F32,
    U32,
}

impl FieldKind {
    /// Its WGSL type.
    pub fn wgsl(self) -> &'static str {
        match self {
            FieldKind::Rgb | FieldKind::Vec3 => "vec3<f32>",
            FieldKind::F32 => "f32",
            FieldKind::U32 => "u32",
        }
    }
}

/// One named parameter of a view and its place in the record: a field of
/// [`Material`] and, for a scalar, its lane (`x`, `y`, `z`, `w`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Field {
    pub name: &'static str,
    pub kind: FieldKind,
    pub place: &'static str,
    pub lane: Option<&'static str>,
}

impl Field {
    /// The record's components it occupies, as (field, lane) pairs: a colour the first
    /// three lanes, a scalar its lane, a u32 the whole field.
    pub fn components(&self) -> Vec<(&'static str, &'static str)> {
        match (self.kind, self.lane) {
            (FieldKind::Rgb | FieldKind::Vec3, _) => {
                ["x", "y", "z"].map(|l| (self.place, l)).to_vec()
            }
            (_, Some(lane)) => vec![(self.place, lane)],
            (_, None) => vec![(self.place, "")],
        }
    }
}

/// A view: the WGSL struct written from it and its fields, in order. `gpu::codegen`
/// writes the struct, `NAME_params(m: Material) -> NAMEParams` reading each field from its
/// place, and `NAME_record(p, m) -> Material` writing them back.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct View {
    pub wgsl_struct: &'static str,
    /// The record it views: `Material`, or `Primitive` (a shape's, `scene::primitives`).
    pub record: &'static str,
    pub fields: &'static [Field],
}

impl View {
    /// Whether the material has textures of its own (a field in `tex_data0` to
    /// `tex_data5` or `tex_normal2`): its shading then has a texture hook
    /// (`NAME_textures` in WGSL, `Shading::textures` on the CPU) that looks them up at a
    /// hit.
    pub fn own_textures(&self) -> bool {
        self.fields
            .iter()
            .any(|f| f.place.starts_with("tex_data") || f.place == "tex_normal2")
    }
}

/// Declares a view of the record: a struct of named parameters, each read from and
/// written to one place of [`Material`] (`read`, `write`), and its [`View`] (`VIEW`),
/// from which `gpu::codegen` writes the same struct and functions in WGSL. The one
/// description of what a material's places mean, for both languages. `of Primitive`
/// views a primitive's record instead (`scene::primitives`: a shape's places, with
/// `vec3` fields for its points and directions).
///
/// ```text
/// material_view! {
///     pub struct Params("MetalParams") {
///         albedo: rgb = color,
///         albedo_texture: u32 = tex_color,
///         fuzz: f32 = scalars.x,
///     }
/// }
/// ```
macro_rules! material_view {
    (
        $(#[$meta:meta])*
        pub struct $name:ident($wgsl:literal) $(of $record:ident)? {
            $( $(#[$fmeta:meta])* $field:ident : $kind:ident = $place:ident $(. $lane:ident)? ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, Default, PartialEq)]
        pub struct $name {
            $( $(#[$fmeta])* pub $field: material_view!(@type $kind), )*
        }

        impl $name {
            /// The description `gpu::codegen` writes the WGSL view from.
            pub const VIEW: $crate::scene::materials::common::View =
                $crate::scene::materials::common::View {
                    wgsl_struct: $wgsl,
                    record: material_view!(@record_name $($record)?),
                    fields: &[$(
                        $crate::scene::materials::common::Field {
                            name: stringify!($field),
                            kind: material_view!(@kind $kind),
                            place: stringify!($place),
                            lane: material_view!(@lane $($lane)?),
                        }
                    ),*],
                };

            /// The parameters as the record holds them.
            #[allow(unused_variables)]
            pub fn read(m: &material_view!(@record $($record)?)) -> Self {
                Self { $( $field: material_view!(@read m, $kind, $place $(. $lane)?), )* }
            }

            /// Writes the parameters into their places of the record.
            #[allow(unused_variables)]
            pub fn write(&self, m: &mut material_view!(@record $($record)?)) {
                $( material_view!(@write m, self.$field, $kind, $place $(. $lane)?); )*
            }
        }
    };
    (@record) => { $crate::scene::records::Material };
    (@record $record:ident) => { $crate::scene::records::$record };
    (@record_name) => { "Material" };
    (@record_name $record:ident) => { stringify!($record) };
    (@type rgb) => { glam::Vec3 };
    (@type vec3) => { glam::Vec3 };
    (@type f32) => { f32 };
    (@type u32) => { u32 };
    (@kind rgb) => { $crate::scene::materials::common::FieldKind::Rgb };
    (@kind vec3) => { $crate::scene::materials::common::FieldKind::Vec3 };
    (@kind f32) => { $crate::scene::materials::common::FieldKind::F32 };
    (@kind u32) => { $crate::scene::materials::common::FieldKind::U32 };
    (@lane) => { None };
    (@lane $lane:ident) => { Some(stringify!($lane)) };
    (@index x) => { 0 };
    (@index y) => { 1 };
    (@index z) => { 2 };
    (@index w) => { 3 };
    (@read $m:ident, rgb, $place:ident) => {
        glam::Vec3::new($m.$place[0], $m.$place[1], $m.$place[2])
    };
    (@read $m:ident, vec3, $place:ident) => {
        material_view!(@read $m, rgb, $place)
    };
    (@read $m:ident, f32, $place:ident . $lane:ident) => {
        $m.$place[material_view!(@index $lane)]
    };
    (@read $m:ident, u32, $place:ident) => {
        $m.$place
    };
    (@write $m:ident, $v:expr, rgb, $place:ident) => {{
        let v: glam::Vec3 = $v;
        $m.$place[0] = v.x;
        $m.$place[1] = v.y;
        $m.$place[2] = v.z;
    }};
    (@write $m:ident, $v:expr, vec3, $place:ident) => {
        material_view!(@write $m, $v, rgb, $place)
    };
    (@write $m:ident, $v:expr, f32, $place:ident . $lane:ident) => {
        $m.$place[material_view!(@index $lane)] = $v
    };
    (@write $m:ident, $v:expr, u32, $place:ident) => {
        $m.$place = $v
    };
}
pub(crate) use material_view;

material_view! {
    /// What every material's record holds, whatever its type: its emission, and the
    /// alpha and normal map a surface may have (pbr's, today). Read by the generic code
    /// of the shaders and the CPU (`emitted`, `transparent_at`, `normal_mapped`).
    pub struct Surface("SurfaceParams") {
        /// Radiance emitted from the front side (both sides with `MAT_FLAG_TWO_SIDED`).
        emission: rgb = emission,
        emission_texture: u32 = tex_emission,
        /// Opacity; times the `color` texture's alpha at a hit, and the luminance of
        /// `opacity_texture` with `MAT_FLAG_OPACITY_TEXTURE`.
        opacity: f32 = color.w,
        opacity_texture: u32 = tex_opacity,
        /// Cut out below this alpha (`MAT_FLAG_ALPHA_MASK`).
        alpha_cutoff: f32 = emission.w,
        /// A tangent-space normal map (linear, +y along v), its x and y scaled by
        /// `normal_scale`; with `MAT_FLAG_BUMP`, a bump map's heights, times
        /// `normal_scale`.
        normal_texture: u32 = tex_normal,
        normal_scale: f32 = color2.w,
    }
}
