//! The GPU plan of a render, built once from the flattened scene, the device's facts
//! ([`DeviceFit`]) and the tuning ([`Tuning`], defaults = fastest): which features the
//! shader holds code for ([`FeatureSet`]), where each record array lives ([`Placements`]:
//! storage buffer, uniform buffer, texture, or written into the shader), how many samples one
//! invocation traces, and whether the loops fit the device. The defines, the generated
//! WGSL, the bind group layout and the buffers all derive from it.

use std::collections::BTreeSet;

use super::bindings::{
    texture_rows, wgsl_accessors, wgsl_declarations, wgsl_texel_load, Placement, Placements, Slot,
    UNIFORM_BYTES,
};
use super::codegen;
use super::error::GpuError;
use super::limits::{DeviceFit, LLVMPIPE_LOOP_LIMIT};
use super::shader::{self, ShaderError};
use crate::scene::flat::FlatScene;
use crate::scene::format::{FilterKind, LightSampling, SamplerKind};
use crate::scene::materials::common::Surface;
use crate::scene::materials::MaterialKind;
use crate::scene::materials::{conductor, dielectric, pbr, plastic, reads_uv_derivatives};
use crate::scene::primitives::PrimitiveKind;
use crate::scene::records as r;
use crate::tuning::Tuning;

/// A piece of shader code that a scene may leave out: llvmpipe runs untaken branches and
/// switch cases under a mask, so absent code still costs time there. The thin lens is
/// always there: a pinhole without it measured slower on llvmpipe (ARCHITECTURE.md, Known
/// costs). Random sampling and bsdf light sampling are always there too.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Feature {
    /// A primitive type of the type list (`scene::primitives`): its file and its cases.
    Primitive(PrimitiveKind),
    /// Object-space intersection of transformed analytic shapes.
    Transforms,
    /// The BVH walk.
    Bvh,
    /// The plain loop over a list of primitives grouped by type.
    PrimitiveLoop,
    /// Instances of groups (`PRIM_INSTANCE`): the walk goes on into a group's BVH in the
    /// group's space, and a hit names its instance.
    Instances,
    /// A material's type: its shading (`shaders/materials/NAME.wgsl`) and its case of
    /// the dispatch.
    Material(MaterialKind),
    /// Textured material colours at all.
    Textures,
    /// Tangent-space normal maps (pbr's `normal_map`), with the vertex tangents they need;
    /// anisotropic roughness (its frame follows the tangents).
    NormalMap,
    /// Shading normals that differ from the geometric one (interpolated vertex normals,
    /// normal maps): bent toward the viewer where it is under them, and directions under
    /// the geometric surface sent over it (`bent_normal`, `over_surface`).
    ShadingNormals,
    /// Triangles with a second uv set, which textures may read (`uv_set = 1`).
    SecondUv,
    /// Triangles with vertex colours, which multiply their material's colour and opacity.
    VertexColors,
    /// Rough glass (`dielectric` with a roughness): its microfacet lobes.
    RoughDielectric,
    /// Rough glass of Beckmann or anisotropic microfacets: the general distribution in
    /// the tangent's frame (isotropic GGX glass keeps its own shorter code).
    GlassMicrofacets,
    /// Beckmann microfacets (a conductor's or a plastic's `distribution`): their
    /// masking's error function and the visible-slope sampler's search.
    Beckmann,
    /// pbr's clearcoat (KHR_materials_clearcoat): its lobe and what it lets through.
    Clearcoat,
    /// pbr's sheen (KHR_materials_sheen): the Charlie lobe and its albedo table.
    Sheen,
    /// Either of pbr's layers: the choice among their lobes and the base's.
    PbrLayers,
    /// Materials with alpha (pbr's `alpha_mode` mask or blend): rays pass through where a
    /// surface is transparent.
    Alpha,
    ImageTexture,
    /// 8-bit sRGB images: their texels' colour is decoded at look-up.
    SrgbTexture,
    NoiseTexture,
    CheckerTexture,
    Jittered,
    Hammersley,
    Sobol,
    /// Next-event estimation with MIS.
    Mis,
    /// The 50/50 mixture of light and material sampling.
    Mixture,
    /// Lights without a surface (point, spot, directional): next-event estimation toward
    /// them under every strategy.
    Punctual,
    /// The image background.
    EnvMap,
    /// Anything emits: without it no path is traced.
    Emission,
    /// The AOVs' sums beside the colour's (albedo, normal, depth, position).
    Aovs,
    /// A pixel filter other than the box (tent, Gaussian): each sample's position in the
    /// pixel drawn from it.
    PixelFilter,
    /// Splat reconstruction (`[render] reconstruction = "splat"`): the sample buffer and
    /// the gather pass.
    Splat,
    /// Projectors among the lights without a surface: their frustum and texture.
    Projector,
    /// Opacity masks read from a texture (`opacity = "NAME"` of any material).
    OpacityTexture,
    /// Materials whose back side is black (`one_sided`).
    OneSided,
    /// Bump maps: the hit's uv derivatives and the height's slopes.
    Bump,
    /// `mesh_attribute` textures: the hit's colour as a texture.
    MeshAttribute,
    /// Energy compensation of microfacet lobes (`MAT_FLAG_ENERGY`): the albedo tables.
    EnergyCompensation,
    /// Participating media (`[media]`): free flights, medium vertices and their phase
    /// function, transmittance along shadow rays.
    Media,
    /// Heterogeneous media (`type = "heterogeneous"`): density grids, delta and ratio
    /// tracking through their majorant cells.
    GridMedia,
}

/// The features after the primitives' and before the materials' in define order.
const GEOMETRY: [Feature; 4] = [
    Feature::Transforms,
    Feature::Bvh,
    Feature::PrimitiveLoop,
    Feature::Instances,
];

/// The features after the materials'.
const SHADING: [Feature; 35] = [
    Feature::Textures,
    Feature::NormalMap,
    Feature::ShadingNormals,
    Feature::SecondUv,
    Feature::VertexColors,
    Feature::RoughDielectric,
    Feature::Beckmann,
    Feature::Clearcoat,
    Feature::Sheen,
    Feature::PbrLayers,
    Feature::Alpha,
    Feature::ImageTexture,
    Feature::SrgbTexture,
    Feature::NoiseTexture,
    Feature::CheckerTexture,
    Feature::Jittered,
    Feature::Hammersley,
    Feature::Sobol,
    Feature::Mis,
    Feature::Mixture,
    Feature::Punctual,
    Feature::EnvMap,
    Feature::Emission,
    Feature::Aovs,
    Feature::PixelFilter,
    Feature::Splat,
    Feature::Projector,
    Feature::OpacityTexture,
    Feature::GlassMicrofacets,
    Feature::OneSided,
    Feature::Bump,
    Feature::MeshAttribute,
    Feature::EnergyCompensation,
    Feature::Media,
    Feature::GridMedia,
];

impl Feature {
    /// Every feature, in define order: one per primitive and one per material of the type
    /// lists among them.
    pub fn all() -> impl Iterator<Item = Feature> {
        PrimitiveKind::ALL
            .iter()
            .map(|&k| Feature::Primitive(k))
            .chain(GEOMETRY)
            .chain(MaterialKind::ALL.iter().map(|&k| Feature::Material(k)))
            .chain(SHADING)
    }

    /// The preprocessor define that keeps its code (`#ifdef HAS_SPHERE`).
    pub fn define(self) -> &'static str {
        match self {
            Feature::Primitive(kind) => kind.define(),
            Feature::Transforms => "HAS_TRANSFORMS",
            Feature::Bvh => "HAS_BVH",
            Feature::PrimitiveLoop => "HAS_PRIMITIVE_LOOP",
            Feature::Instances => "HAS_INSTANCES",
            Feature::Material(kind) => kind.define(),
            Feature::Textures => "HAS_TEXTURES",
            Feature::NormalMap => "HAS_NORMAL_MAP",
            Feature::ShadingNormals => "HAS_SHADING_NORMALS",
            Feature::SecondUv => "HAS_UV1",
            Feature::VertexColors => "HAS_VERTEX_COLORS",
            Feature::RoughDielectric => "HAS_ROUGH_DIELECTRIC",
            Feature::Beckmann => "HAS_BECKMANN",
            Feature::Clearcoat => "HAS_CLEARCOAT",
            Feature::Sheen => "HAS_SHEEN",
            Feature::PbrLayers => "HAS_PBR_LAYERS",
            Feature::Alpha => "HAS_ALPHA",
            Feature::Media => "HAS_MEDIA",
            Feature::GridMedia => "HAS_GRID_MEDIA",
            Feature::ImageTexture => "HAS_IMAGE_TEXTURE",
            Feature::SrgbTexture => "HAS_SRGB_TEXTURE",
            Feature::NoiseTexture => "HAS_NOISE_TEXTURE",
            Feature::CheckerTexture => "HAS_CHECKER_TEXTURE",
            Feature::Jittered => "HAS_JITTERED",
            Feature::Hammersley => "HAS_HAMMERSLEY",
            Feature::Sobol => "HAS_SOBOL",
            Feature::Mis => "HAS_MIS",
            Feature::Mixture => "HAS_MIXTURE",
            Feature::Aovs => "HAS_AOVS",
            Feature::Punctual => "HAS_PUNCTUAL",
            Feature::EnvMap => "HAS_ENV_MAP",
            Feature::Emission => "HAS_EMISSION",
            Feature::PixelFilter => "HAS_PIXEL_FILTER",
            Feature::Splat => "HAS_SPLAT",
            Feature::Projector => "HAS_PROJECTOR",
            Feature::OpacityTexture => "HAS_OPACITY_TEXTURE",
            Feature::GlassMicrofacets => "HAS_GLASS_MICROFACETS",
            Feature::OneSided => "HAS_ONE_SIDED",
            Feature::Bump => "HAS_BUMP",
            Feature::MeshAttribute => "HAS_MESH_ATTRIBUTE",
            Feature::EnergyCompensation => "HAS_ENERGY_COMPENSATION",
        }
    }

    /// Its name for people (`wgtrace features`): the define, lower case, without `HAS_`.
    pub fn name(self) -> String {
        self.define()
            .trim_start_matches("HAS_")
            .to_ascii_lowercase()
    }

    /// Its bit in a [`FeatureSet`]: the others' order, the primitives' from
    /// `PRIMITIVE_BITS` on by tag, the materials' from `MATERIAL_BITS` on by tag.
    fn bit(self) -> u32 {
        match self {
            Feature::Primitive(kind) => PRIMITIVE_BITS + kind.tag(),
            Feature::Material(kind) => MATERIAL_BITS + kind.tag(),
            f => GEOMETRY
                .iter()
                .chain(&SHADING)
                .position(|&g| g == f)
                .expect("every other feature is listed") as u32,
        }
    }
}

/// The first bit of the primitives in a [`FeatureSet`], after every other feature's but
/// the materials'.
const PRIMITIVE_BITS: u32 = 39;

/// The first bit of the materials in a [`FeatureSet`], after every other feature's.
const MATERIAL_BITS: u32 = 48;

// the other features' bits stay under the primitives', the primitives' under the
// materials', and the materials' in a u64
const _: () = assert!(GEOMETRY.len() + SHADING.len() <= PRIMITIVE_BITS as usize);
const _: () = assert!(PRIMITIVE_BITS as usize + PrimitiveKind::ALL.len() <= MATERIAL_BITS as usize);
const _: () = assert!(MATERIAL_BITS as usize + MaterialKind::ALL.len() <= 64);

/// A set of [`Feature`]s.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct FeatureSet(u64);

impl FeatureSet {
    /// Every feature: the full shader, which picks the sampler, the light-sampling
    /// strategy and BVH or not at run time from `Params`.
    pub fn all() -> Self {
        Feature::all().collect()
    }

    pub fn contains(self, f: Feature) -> bool {
        self.0 & (1 << f.bit()) != 0
    }

    pub fn insert(&mut self, f: Feature) {
        self.0 |= 1 << f.bit();
    }

    /// `f` added when `on`.
    pub fn with(mut self, f: Feature, on: bool) -> Self {
        if on {
            self.insert(f);
        }
        self
    }

    pub fn iter(self) -> impl Iterator<Item = Feature> {
        Feature::all().filter(move |&f| self.contains(f))
    }
}

impl FromIterator<Feature> for FeatureSet {
    fn from_iter<I: IntoIterator<Item = Feature>>(iter: I) -> Self {
        let mut s = FeatureSet::default();
        for f in iter {
            s.insert(f);
        }
        s
    }
}

/// The features a scene uses: code for the others is left out.
pub fn scene_features(scene: &FlatScene) -> FeatureSet {
    let prim = |tag: u32| scene.primitives.iter().any(|p| p.tag == tag);
    let kind = |k: MaterialKind| scene.materials.iter().any(|m| m.tag == k.tag());
    let texture = |tag: u32| scene.textures.iter().any(|t| t.tag == tag);
    let flag = |f: u32| scene.primitives.iter().any(|p| p.flags & f != 0);
    let bounded = scene.primitives.len() > scene.num_unbounded as usize;
    // next-event estimation applies at a material with a density, and at every point
    // where a path scatters in a medium
    let nee = scene.has_media() || scene.materials.iter().any(|m| m.nee());
    let is_pbr = |m: &r::Material| m.tag == MaterialKind::Pbr.tag();
    let clearcoat = scene
        .materials
        .iter()
        .any(|m| is_pbr(m) && pbr::has_clearcoat(m));
    let sheen = scene
        .materials
        .iter()
        .any(|m| is_pbr(m) && pbr::has_sheen(m));
    let lit = scene.emitters.len() > scene.num_punctual as usize && nee;
    let materials = MaterialKind::ALL
        .iter()
        .filter(|&&k| kind(k))
        .map(|&k| Feature::Material(k));
    let shapes = PrimitiveKind::ALL
        .iter()
        .filter(|&&k| prim(k.tag()))
        .map(|&k| Feature::Primitive(k));
    shapes
        .chain(materials)
        .collect::<FeatureSet>()
        .with(
            Feature::Transforms,
            scene
                .primitives
                .iter()
                .any(|p| p.flags & r::PRIM_FLAG_TRANSFORM != 0),
        )
        .with(Feature::Bvh, bounded && scene.use_bvh)
        .with(Feature::PrimitiveLoop, bounded && !scene.use_bvh)
        .with(Feature::Instances, prim(r::PRIM_INSTANCE))
        .with(Feature::Textures, !scene.textures.is_empty())
        .with(
            Feature::NormalMap,
            scene.materials.iter().any(|m| {
                Surface::read(m).normal_texture != r::NO_TEXTURE
                    || (is_pbr(m) && pbr::has_coat_normal_map(m))
                    || m.flags & r::MAT_FLAG_ANISOTROPIC != 0
            }),
        )
        .with(
            Feature::ShadingNormals,
            flag(r::PRIM_FLAG_SHADING_NORMALS)
                || scene
                    .materials
                    .iter()
                    .any(|m| Surface::read(m).normal_texture != r::NO_TEXTURE),
        )
        .with(
            Feature::Alpha,
            scene
                .materials
                .iter()
                .any(|m| m.flags & (r::MAT_FLAG_ALPHA_MASK | r::MAT_FLAG_ALPHA_BLEND) != 0),
        )
        // a texture of uv set 1 reads set 0 where no triangle has a second one: the code
        // is there for it all the same, as the CPU's is
        .with(
            Feature::SecondUv,
            flag(r::PRIM_FLAG_UV1) || scene.textures.iter().any(|t| t.uv_set != 0),
        )
        .with(Feature::VertexColors, flag(r::PRIM_FLAG_COLORS))
        .with(
            Feature::RoughDielectric,
            scene
                .materials
                .iter()
                .any(|m| m.tag == MaterialKind::Dielectric.tag() && dielectric::is_rough(m)),
        )
        .with(
            Feature::Beckmann,
            scene.materials.iter().any(|m| {
                (m.tag == MaterialKind::Conductor.tag() && conductor::is_beckmann(m))
                    || (m.tag == MaterialKind::Plastic.tag() && plastic::is_beckmann(m))
                    || (m.tag == MaterialKind::Dielectric.tag() && dielectric::is_beckmann(m))
            }),
        )
        .with(
            Feature::GlassMicrofacets,
            scene
                .materials
                .iter()
                .any(|m| m.tag == MaterialKind::Dielectric.tag() && dielectric::is_general(m)),
        )
        .with(
            Feature::OneSided,
            scene
                .materials
                .iter()
                .any(|m| m.flags & r::MAT_FLAG_ONE_SIDED != 0),
        )
        .with(
            Feature::Bump,
            scene.materials.iter().any(reads_uv_derivatives),
        )
        .with(Feature::MeshAttribute, texture(r::TEX_MESH_ATTRIBUTE))
        .with(
            Feature::EnergyCompensation,
            scene
                .materials
                .iter()
                .any(|m| m.flags & r::MAT_FLAG_ENERGY != 0),
        )
        .with(Feature::Clearcoat, clearcoat)
        .with(Feature::Sheen, sheen)
        .with(Feature::PbrLayers, clearcoat || sheen)
        .with(Feature::ImageTexture, texture(r::TEX_IMAGE))
        .with(
            Feature::SrgbTexture,
            scene
                .textures
                .iter()
                .any(|t| t.tag == r::TEX_IMAGE && t.flags & r::TEX_FLAG_SRGB != 0),
        )
        .with(Feature::NoiseTexture, texture(r::TEX_NOISE))
        .with(Feature::CheckerTexture, texture(r::TEX_CHECKER))
        .with(Feature::Jittered, scene.sampler == SamplerKind::Jittered)
        .with(
            Feature::Hammersley,
            scene.sampler == SamplerKind::Hammersley,
        )
        .with(Feature::Sobol, scene.sampler == SamplerKind::Sobol)
        .with(
            Feature::Mis,
            lit && scene.light_sampling == LightSampling::Mis,
        )
        .with(
            Feature::Mixture,
            lit && scene.light_sampling == LightSampling::Mixture,
        )
        .with(Feature::Punctual, scene.num_punctual > 0 && nee)
        .with(Feature::EnvMap, scene.env.is_some())
        .with(Feature::Emission, scene.emits() || scene.aovs)
        .with(Feature::Aovs, scene.aovs)
        .with(Feature::PixelFilter, scene.filter.kind != FilterKind::Box)
        .with(Feature::Splat, scene.filter.splat)
        .with(
            Feature::Projector,
            scene.num_punctual > 0
                && nee
                && scene.emitters.iter().any(|e| e.kind == r::LIGHT_PROJECTOR),
        )
        .with(
            Feature::OpacityTexture,
            scene
                .materials
                .iter()
                .any(|m| m.flags & r::MAT_FLAG_OPACITY_TEXTURE != 0),
        )
        .with(Feature::Media, scene.has_media())
        .with(Feature::GridMedia, scene.has_media() && scene.grid_media)
}

/// What a shader is assembled from: its features, where its record arrays live, and the
/// code generated for one scene (records written in as constants; empty for a shader that
/// serves every scene of its feature set). Trace pipelines are compiled once per spec and
/// process.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ShaderSpec {
    pub features: FeatureSet,
    /// The lane statistics of `--tune lane-stats` ([`LANE_STATS`]).
    pub lane_stats: bool,
    /// The BVH walk's stack in registers ([`REGISTER_STACK`]): a specialized shader, a
    /// tree of depth at most `BVH_REGISTER_STACK`, no instances.
    pub register_stack: bool,
    pub placements: Placements,
    /// Image texel banks the scene has (`scene::texels`): `texel_load` reads these.
    pub banks: u32,
    pub scene_code: String,
}

impl ShaderSpec {
    /// A spec with `features`, every record array in a storage buffer, one texel bank, no
    /// scene code.
    pub fn of(features: FeatureSet) -> Self {
        ShaderSpec {
            features,
            banks: 1,
            ..Default::default()
        }
    }

    /// Every feature, storage buffers only: what the shader files can hold at most.
    pub fn full() -> Self {
        Self::of(FeatureSet::all())
    }

    /// Features the full shader of `--tune no-specialize` holds only for a scene that
    /// uses them: alpha adds two closest-hit searches (the shadow rays' `shadowed`,
    /// which llvmpipe inlines at each call) to a shader that serves every other scene,
    /// and llvmpipe's compile of it went from 153 s to 232 s with them; a second uv set
    /// and vertex colours add reads to every triangle hit; rough glass a branch to
    /// every glass hit; shading normals a second eval and pdf to every light sample;
    /// pbr's layers two lobes to every pbr hit (and with them all in, llvmpipe's cold
    /// compile of the full shader took minutes longer). The materials added after pbr
    /// (conductor, thin_dielectric, plastic, blend, principled), the pixel filters, splatting, projectors, opacity
    /// textures, Beckmann or anisotropic glass, one-sided materials, bump maps, mesh attributes, energy compensation, null and media too: the full shader of every other
    /// scene stays as it was.
    pub const OPTIONAL_IN_FULL: [Feature; 29] = [
        Feature::Instances,
        Feature::Aovs,
        Feature::Alpha,
        Feature::NormalMap,
        Feature::ShadingNormals,
        Feature::SecondUv,
        Feature::VertexColors,
        Feature::RoughDielectric,
        Feature::Clearcoat,
        Feature::Sheen,
        Feature::PbrLayers,
        Feature::Material(MaterialKind::Conductor),
        Feature::Material(MaterialKind::ThinDielectric),
        Feature::Material(MaterialKind::Plastic),
        Feature::Material(MaterialKind::Blend),
        Feature::Material(MaterialKind::Principled),
        Feature::Beckmann,
        Feature::PixelFilter,
        Feature::Splat,
        Feature::Projector,
        Feature::OpacityTexture,
        Feature::GlassMicrofacets,
        Feature::OneSided,
        Feature::Bump,
        Feature::MeshAttribute,
        Feature::EnergyCompensation,
        Feature::Material(MaterialKind::Null),
        Feature::Media,
        Feature::GridMedia,
    ];

    /// The full shader for a scene with `scene` features (`--tune no-specialize`):
    /// every feature but the optional ones the scene does not use; storage buffers
    /// only. Every scene without them shares it.
    pub fn full_for(scene: FeatureSet) -> Self {
        let features = Feature::all()
            .filter(|f| !Self::OPTIONAL_IN_FULL.contains(f) || scene.contains(*f))
            .collect();
        Self::of(features)
    }

    /// The preprocessor's defines: a `HAS_*` per feature, a `BAKED_*` per record array
    /// written into the shader, `BOUNDED_TRIANGLES_ONLY` when every primitive the BVH
    /// can hold is an untransformed triangle (its leaves then test without a `switch`),
    /// and `REGISTER_STACK` for the walk's stack in registers.
    pub fn defines(&self) -> BTreeSet<&'static str> {
        let mut d: BTreeSet<&'static str> = self.features.iter().map(Feature::define).collect();
        for (slot, define) in BAKED_DEFINES {
            if self.placements.get(slot) == Placement::Shader {
                d.insert(define);
            }
        }
        let f = |x: Feature| self.features.contains(x);
        let kinds = self.primitive_kinds();
        let bounded: Vec<_> = kinds.iter().filter(|k| k.bounded()).collect();
        if bounded == [&PrimitiveKind::Triangle] && !f(Feature::Transforms) {
            d.insert(BOUNDED_TRIANGLES_ONLY);
        }
        if kinds.iter().any(|k| !k.bounded()) {
            d.insert(HAS_UNBOUNDED);
        }
        if self.lane_stats {
            d.insert(LANE_STATS);
        }
        if self.register_stack && f(Feature::Bvh) && !f(Feature::Instances) {
            d.insert(REGISTER_STACK);
        }
        // splatting weighs samples by the filter's profile
        if f(Feature::Splat) {
            d.insert(Feature::PixelFilter.define());
        }
        if f(Feature::Beckmann) || f(Feature::PixelFilter) || f(Feature::Splat) {
            d.insert(HAS_ERF);
        }
        d
    }

    /// Every name a shader file's `#if` may ask about: each feature's define, each
    /// `BAKED_*`, `BOUNDED_TRIANGLES_ONLY`, `HAS_UNBOUNDED`, `LANE_STATS`,
    /// `REGISTER_STACK` and `HAS_ERF`.
    /// The preprocessor refuses any other.
    pub fn known_defines() -> BTreeSet<&'static str> {
        Feature::all()
            .map(Feature::define)
            .chain(BAKED_DEFINES.map(|(_, d)| d))
            .chain([
                BOUNDED_TRIANGLES_ONLY,
                HAS_UNBOUNDED,
                LANE_STATS,
                REGISTER_STACK,
                HAS_ERF,
            ])
            .collect()
    }

    /// The primitive types of the shader, in the type list's order.
    fn primitive_kinds(&self) -> Vec<PrimitiveKind> {
        self.features
            .iter()
            .filter_map(|f| match f {
                Feature::Primitive(k) => Some(k),
                _ => None,
            })
            .collect()
    }

    /// The assembled WGSL of entry point file `entry` (`trace` or `kernel`).
    pub fn wgsl(&self, entry: &str) -> Result<String, ShaderError> {
        let constants = codegen::constants();
        let bindings = wgsl_declarations(&self.placements)
            + &wgsl_accessors(&self.placements)
            + &wgsl_texel_load(self.banks);
        let kinds: Vec<MaterialKind> = self
            .features
            .iter()
            .filter_map(|f| match f {
                Feature::Material(k) => Some(k),
                _ => None,
            })
            .collect();
        let materials = codegen::materials(&kinds);
        let primitives = codegen::primitives(&self.primitive_kinds());
        let (known, set) = (Self::known_defines(), self.defines());
        shader::assemble(
            entry,
            shader::Defines {
                known: &known,
                set: &set,
            },
            &[
                ("generated/constants", &constants),
                ("generated/bindings", &bindings),
                ("generated/materials", &materials),
                ("generated/primitives", &primitives),
                ("generated/scene", &self.scene_code),
            ],
        )
    }

    /// The slots the trace entry point reads: its layout and bind groups hold these only.
    /// (`tests/shaders.rs` holds this to naga's analysis of the assembled shader for every
    /// feature set the scenes reach.)
    pub fn trace_slots(&self) -> Vec<Slot> {
        let f = |x: Feature| self.features.contains(x);
        let buffer = |s: Slot| self.placements.get(s) != Placement::Shader;
        // without emission no path is traced: only the sums are touched
        let traced = f(Feature::Emission);
        Slot::ALL
            .into_iter()
            .filter(|&slot| match slot {
                Slot::Params | Slot::Accum => true,
                Slot::Samples => f(Feature::Splat),
                _ if !traced => false,
                Slot::Primitives | Slot::Materials => buffer(slot),
                Slot::Emitters => {
                    buffer(slot) && (f(Feature::Mis) || f(Feature::Mixture) || f(Feature::Punctual))
                }
                Slot::Bvh => f(Feature::Bvh),
                Slot::ShapeData => {
                    f(Feature::Transforms)
                        || f(Feature::Instances)
                        || self.primitive_kinds().iter().any(|k| k.reads_shape_data())
                }
                Slot::Textures => f(Feature::Textures) || f(Feature::EnvMap),
                // image texels are read by image look-ups (of textured materials, and of
                // the image background, which goes through the same texture_value)
                Slot::Texels(i) => {
                    u32::from(i) < self.banks
                        && (f(Feature::Textures) || f(Feature::EnvMap))
                        && f(Feature::ImageTexture)
                }
                // the tables by noise look-ups, by the background's distribution when
                // lights are sampled, by pbr's sheen (its albedo table), by plastics
                // (a rough coating's transmittance) and by the materials that energy
                // compensation applies to (the microfacet albedo tables), and by media
                Slot::Tables => {
                    let env = f(Feature::EnvMap);
                    f(Feature::Media)
                        || (f(Feature::Textures) || env) && f(Feature::NoiseTexture)
                        || env && (f(Feature::Mis) || f(Feature::Mixture))
                        || f(Feature::Sheen) && f(Feature::Material(MaterialKind::Pbr))
                        || f(Feature::Material(MaterialKind::Plastic))
                        || f(Feature::EnergyCompensation)
                            && [
                                MaterialKind::Conductor,
                                MaterialKind::Dielectric,
                                MaterialKind::Microfacet,
                                MaterialKind::Pbr,
                                MaterialKind::Principled,
                            ]
                            .iter()
                            .any(|&k| f(Feature::Material(k)))
                }
            })
            .collect()
    }
}

/// The define of a shader whose BVH leaves hold only untransformed triangles (they test
/// without the tag's switch).
const BOUNDED_TRIANGLES_ONLY: &str = "BOUNDED_TRIANGLES_ONLY";

/// The define of a shader with unbounded primitive types (planes): tested on their own,
/// before the BVH or the per-type loops.
const HAS_UNBOUNDED: &str = "HAS_UNBOUNDED";

/// The define of a shader that needs the error function and its inverse (sampling.wgsl):
/// Beckmann microfacets' masking and slopes, and the Gaussian pixel filter's inverse CDF.
const HAS_ERF: &str = "HAS_ERF";

/// The define of each record array that may be written into the shader.
const BAKED_DEFINES: [(Slot, &str); 3] = [
    (Slot::Primitives, "BAKED_PRIMITIVES"),
    (Slot::Materials, "BAKED_MATERIALS"),
    (Slot::Emitters, "BAKED_EMITTERS"),
];

/// The define of `--tune lane-stats` (`Tuning::lane_stats`): the trace shader enables
/// WGSL's subgroups and sums, per pixel, the lanes that took part in each turn of the
/// bounce loop, BVH node step and primitive test in the colour's sums, and each step's
/// share of the subgroup (subgroup size / active lanes) in the squares' (`lane_shares`).
pub const LANE_STATS: &str = "HAS_LANE_STATS";

/// The define of the BVH walk's stack in registers (`ShaderSpec::register_stack`): eight
/// entries, the top first, a push shifting them all down and a pop up (`intersect.wgsl`,
/// `WalkStack`), in place of a column of workgroup memory per invocation. For a tree of
/// depth at most `BVH_REGISTER_STACK` (a walk holds an entry per level at most) without
/// instances. The same walk: the same image.
pub const REGISTER_STACK: &str = "REGISTER_STACK";

/// The most primitives a scene's shader holds as constants: a scene without the BVH and
/// without transformed primitives (`codegen::baked_primitives`), which is every scene of
/// the plain list (`tuning::LIST_MAX_PRIMITIVES`).
pub const BAKED_PRIMITIVES_MAX: usize = crate::tuning::LIST_MAX_PRIMITIVES;

/// The most materials, and the most lights, a scene's shader holds as constants: each
/// look-up is a chain of selects over all of them.
pub const BAKED_RECORDS_MAX: usize = 8;

/// Most samples one invocation traces in a row (`shaders/trace.wgsl`, `main`): a lane
/// whose path ends starts its next sample at once, so the 8 lanes of a SIMD batch stay
/// busy (llvmpipe runs a loop until its last lane is done), and the pixel's sums are read
/// and written once per group. Each sample is still added in index order, so the sums do
/// not depend on how the samples were grouped.
pub const SAMPLE_GROUP: u32 = 16;

/// The GPU plan of one render.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GpuPlan {
    pub shader: ShaderSpec,
    /// Samples one invocation traces in a row: [`SAMPLE_GROUP`], fewer when that many
    /// paths would pass llvmpipe's loop limit, 1 with `--tune no-sample-groups`.
    pub sample_group: u32,
    /// Loop iterations that grow with the scene, of one invocation's group of paths (the
    /// trace pipeline) and of one ray (the test kernel).
    pub path_loops: u64,
    pub ray_loops: u64,
    /// The device's facts the plan was made for.
    pub fit: DeviceFit,
}

impl GpuPlan {
    /// The plan for `scene` on a device with `fit`, under `tuning`.
    pub fn new(scene: &FlatScene, fit: &DeviceFit, tuning: &Tuning) -> Self {
        let mut shader = if tuning.specialize {
            ShaderSpec::of(scene_features(scene))
        } else {
            ShaderSpec::full_for(scene_features(scene))
        };
        shader.banks = scene.texels.banks.len() as u32;
        shader.lane_stats = tuning.lane_stats;
        // (a specialized shader's: the full shader serves trees of every depth)
        shader.register_stack = tuning.register_stack
            && tuning.specialize
            && scene.use_bvh
            && !shader.features.contains(Feature::Instances)
            && scene.bvh_depth <= r::BVH_REGISTER_STACK;
        // the full shader reads every array from a storage buffer
        if tuning.specialize {
            for slot in Slot::RECORDS {
                shader
                    .placements
                    .set(slot, placement(slot, scene, fit, tuning));
            }
        }
        let shader_slot = |s| shader.placements.get(s) == Placement::Shader;
        if shader_slot(Slot::Primitives) {
            shader.scene_code += &codegen::baked_primitives(scene);
        }
        if shader_slot(Slot::Materials) {
            shader.scene_code += &codegen::baked_materials(scene);
        }
        if shader_slot(Slot::Emitters) {
            shader.scene_code += &codegen::baked_emitters(scene);
        }
        let ray_loops = ray_loop_iterations(scene, shader_slot(Slot::Primitives));
        let per_path = path_loop_iterations(scene, ray_loops);
        let sample_group = if tuning.sample_groups {
            (LLVMPIPE_LOOP_LIMIT / per_path.max(1)).clamp(1, SAMPLE_GROUP as u64) as u32
        } else {
            1
        };
        GpuPlan {
            shader,
            sample_group,
            path_loops: sample_group as u64 * per_path,
            ray_loops,
            fit: *fit,
        }
    }

    /// Refuses a render the device cannot hold (a record array past one storage binding)
    /// or would cut short (llvmpipe's loop limit), and lane statistics on a device
    /// without subgroup operations.
    pub fn check(&self, scene: &FlatScene) -> Result<(), GpuError> {
        if self.shader.lane_stats && !self.fit.subgroups {
            return Err(GpuError::Adapter(
                "--tune lane-stats needs subgroup operations, which this adapter lacks".into(),
            ));
        }
        self.fit.check_scene(scene)?;
        self.fit.check_loops(self.path_loops)
    }
}

/// Where `slot`'s records live in a specialized shader: written in when the scene is
/// small enough and the tuning allows; else a uniform buffer when they fit in
/// [`UNIFORM_BYTES`] and the device binds that many; else, for the primitives and the BVH
/// that the traversal reads most, a texture when it fits the device's; else a storage
/// buffer.
fn placement(slot: Slot, scene: &FlatScene, fit: &DeviceFit, tuning: &Tuning) -> Placement {
    let few = |n: usize| (1..=BAKED_RECORDS_MAX).contains(&n);
    let written_in = tuning.baked_records
        && match slot {
            Slot::Primitives => {
                let prims = &scene.primitives;
                !scene.use_bvh
                    && !prims.is_empty()
                    && prims.len() <= BAKED_PRIMITIVES_MAX
                    && prims.iter().all(|p| p.flags & r::PRIM_FLAG_TRANSFORM == 0)
            }
            Slot::Materials => few(scene.materials.len()),
            Slot::Emitters => few(scene.emitters.len()),
            _ => false,
        };
    let bytes = slot.bytes(scene).len();
    if written_in {
        Placement::Shader
    } else if tuning.uniform_records && fit.uniform_records && bytes as u64 <= UNIFORM_BYTES {
        Placement::Uniform
    } else if tuning.texture_records
        && matches!(slot, Slot::Primitives | Slot::Bvh)
        && texture_rows(bytes) <= fit.texture_rows
    {
        Placement::Texture
    } else {
        Placement::Storage
    }
}

/// Loop iterations of one ray's closest-hit search that grow with the scene: none with the
/// BVH or the primitives written into the shader, else one per primitive.
fn ray_loop_iterations(scene: &FlatScene, primitives_in_shader: bool) -> u64 {
    if scene.use_bvh || primitives_in_shader {
        0
    } else {
        scene.primitives.len() as u64 + 1
    }
}

/// Loop iterations of one path: a turn of the bounce loop per ray, plus the loops of its
/// rays (camera or bounce, the MIS shadow ray, the shadow ray to a light without a
/// surface) and, for the mixture, the loop over lights, and the binary search that
/// chooses a light without a surface.
fn path_loop_iterations(scene: &FlatScene, ray_loops: u64) -> u64 {
    let area = scene.emitters.len() - scene.num_punctual as usize;
    let lit = scene.light_sampling != LightSampling::Bsdf && area > 0;
    let punctual = scene.num_punctual > 0;
    let shadow = (lit && scene.light_sampling == LightSampling::Mis) as u64 + punctual as u64;
    let mixture = if lit && scene.light_sampling == LightSampling::Mixture {
        area as u64
    } else {
        0
    };
    let choice = u64::from(32 - scene.num_punctual.saturating_sub(1).leading_zeros());
    scene.max_depth as u64 * (1 + (1 + shadow) * ray_loops + mixture + choice)
}
