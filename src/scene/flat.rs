//! The flattened scene: the records both backends read, the camera and the render
//! settings, and the per-dispatch parameter block built from them. Nothing here knows
//! which backend renders.

use glam::Vec3;

use super::format::{LightSampling, PixelFilter, SamplerKind};
use super::records::{self, BvhNode, Emitter, Material, Params, Primitive, Texture};
use super::texels::Texels;

/// The first ray Russian roulette may stop: the fourth (after the camera ray and two
/// bounces), as pbrt-v4 starts it after depth 1. A path then goes on with probability
/// min(1, max(throughput)) and its throughput is divided by that: unbiased.
pub const RR_DEPTH: u32 = 3;

/// The camera reduced to what the shader needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraFrame {
    pub origin: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    pub forward: Vec3,
    pub half_width: f32,
    pub half_height: f32,
    pub focus_distance: f32,
    pub lens_radius: f32,
    /// Parallel rays along `forward` from the rectangle of half sizes `half_width` x
    /// `half_height` about `origin` (no lens).
    pub orthographic: bool,
    /// Rays start at the plane this far in front of the camera (0: at the camera).
    pub near_clip: f32,
}

/// A validated scene flattened into shader records.
#[derive(Debug, Clone)]
pub struct FlatScene {
    /// What the loader left out or approximated (a glTF file's unsupported parts, a
    /// background it chose), one line each, for stderr.
    pub warnings: Vec<String>,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: u32,
    pub seed: u32,
    pub sampler: SamplerKind,
    /// The pixel filter a sample's position follows.
    pub filter: PixelFilter,
    pub camera: CameraFrame,
    /// Background radiance: the constant colour, or the bottom of the gradient.
    pub background: [f32; 3],
    /// The top of the gradient, when the background is one.
    pub background_top: Option<[f32; 3]>,
    /// The image background, when it is one.
    pub env: Option<EnvironmentMap>,
    pub light_sampling: LightSampling,
    /// The first ray Russian roulette may stop ([`RR_DEPTH`]; 0: none).
    pub rr_depth: u32,
    /// Camera rays see no emitter and no background (`[render] hide_emitters`).
    pub hide_emitters: bool,
    pub primitives: Vec<Primitive>,
    pub materials: Vec<Material>,
    /// The light list: emissive primitives that can be sampled, then the image background,
    /// then the lights without a surface.
    pub emitters: Vec<Emitter>,
    /// Material names, in record order.
    pub material_names: Vec<String>,
    /// The compressed 8-wide BVH over primitives `num_unbounded..` (`bvh::collapse`: the
    /// root first, a node's child nodes side by side); empty when `use_bvh` is false.
    pub bvh: Vec<BvhNode>,
    /// The last `num_punctual` emitters are the lights without a surface (`[[lights]]`),
    /// chosen among themselves.
    pub num_punctual: u32,
    /// Depth of the deepest BVH node (the root is 0).
    pub bvh_depth: u32,
    /// Transforms and triangle vertex attributes, indexed by `Primitive::data`.
    pub shape_data: Vec<[f32; 4]>,
    /// Primitives `0..num_unbounded` are planes, outside the BVH.
    pub num_unbounded: u32,
    /// Closest-hit searches walk the BVH; else they test the bounded primitives as a list,
    /// grouped by type (`flatten::Acceleration`).
    pub use_bvh: bool,
    /// Texture records, in `[textures]` name order.
    pub textures: Vec<Texture>,
    /// Image texels at their source precision, in banks (`scene::texels`), found by a
    /// texture record's `bank`, `layer`, `x` and `y`.
    pub texels: Texels,
    /// The Perlin tables (at `Texture::offset`) and the image background's sampling
    /// distribution (at `EnvironmentMap::cdf`), four f32 scalars to an entry.
    pub tables: Vec<[f32; 4]>,
    /// The first `tables` entry of the microfacet albedo tables (0 without any).
    pub ms_tables: u32,
    /// The first `tables` entry of the media (`MEDIUM_ENTRIES` each, in `[media]` name
    /// order; 0 without any), and how many there are.
    pub media: u32,
    pub num_media: u32,
    /// The medium camera rays start in, else `NO_MEDIUM`.
    pub camera_medium: u32,
    /// The first `tables` entry of the material records' media words (`MEDIA_SIDE`;
    /// four to an entry), and whether any word is not 0.
    pub material_media: u32,
    pub shapes_hold_media: bool,
    /// A medium is heterogeneous (`Medium::grid`): the shader's HAS_GRID_MEDIA.
    pub grid_media: bool,
    /// Whether renders accumulate the AOVs (albedo, normal, depth, position; `crate::aov`)
    /// beside the colour. Not part of the scene file: a render asks for them.
    pub aovs: bool,
}

/// An equirectangular image background.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnvironmentMap {
    /// Its texture record.
    pub texture: u32,
    /// First `tables` entry of its sampling distribution.
    pub cdf: u32,
    /// Its index in the light list (`records::NO_LIGHT` when it is black).
    pub light: u32,
    /// cos and sin of its rotation about +y.
    pub rotation: [f32; 2],
    pub strength: f32,
}

/// A band of the image: whole rows y .. y + height (x = 0, width = the image's), held by
/// one accumulation buffer of the GPU, or the rows of one that a dispatch covers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Band {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

impl FlatScene {
    /// Whether any path can enter a medium: the camera sits in one, or a shape bounds one.
    pub fn has_media(&self) -> bool {
        self.camera_medium != records::NO_MEDIUM || self.shapes_hold_media
    }

    /// The nodes of the BVH.
    pub fn bvh_node_count(&self) -> usize {
        self.bvh.len()
    }

    /// The uniform block for one dispatch: pass `sample_index` over `band`.
    pub fn params(&self, sample_index: u32, band: Band) -> Params {
        let c = &self.camera;
        Params {
            cam_origin: c.origin.extend(c.lens_radius).to_array(),
            cam_right: c.right.extend(c.half_width).to_array(),
            cam_up: c.up.extend(c.half_height).to_array(),
            cam_forward: c.forward.extend(c.focus_distance).to_array(),
            background: [
                self.background[0],
                self.background[1],
                self.background[2],
                0.0,
            ],
            background_top: match self.background_top {
                Some(t) => [t[0], t[1], t[2], 0.0],
                None => [0.0; 4],
            },
            env: match self.env {
                Some(e) => [e.rotation[0], e.rotation[1], e.strength, 0.0],
                None => [0.0; 4],
            },
            width: self.width,
            height: self.height,
            max_depth: self.max_depth,
            seed: self.seed,
            sample_index,
            num_primitives: self.primitives.len() as u32,
            num_emitters: self.emitters.len() as u32 - self.num_punctual,
            num_punctual: self.num_punctual,
            band_x: band.x,
            band_y: band.y,
            band_width: band.width,
            band_height: band.height,
            num_unbounded: self.num_unbounded,
            use_bvh: self.use_bvh as u32,
            sampler: self.sampler.record(),
            strata_log2: strata_log2(self.spp),
            spp: self.spp,
            light_sampling: self.light_sampling.record(),
            background_kind: if self.env.is_some() {
                records::BACKGROUND_IMAGE
            } else if self.background_top.is_some() {
                records::BACKGROUND_GRADIENT
            } else {
                records::BACKGROUND_CONSTANT
            },
            env_texture: self.env.map_or(0, |e| e.texture),
            env_cdf: self.env.map_or(0, |e| e.cdf),
            env_light: self.env.map_or(records::NO_LIGHT, |e| e.light),
            rr_depth: self.rr_depth,
            orthographic: c.orthographic as u32,
            pixel_filter: self.filter.kind.record(),
            ms_tables: self.ms_tables,
            hide_emitters: self.hide_emitters as u32,
            near_clip: c.near_clip,
            filter_shape: self.filter.shape(),
            filter_steps: self.filter.steps,
            splat: self.filter.splat as u32,
            media: self.media,
            camera_medium: self.camera_medium,
            material_media: self.material_media,
            ..Default::default()
        }
    }

    /// The whole image as one band.
    pub fn full_band(&self) -> Band {
        Band {
            x: 0,
            y: 0,
            width: self.width,
            height: self.height,
        }
    }

    /// Pixels of the image.
    pub fn pixels(&self) -> u64 {
        self.width as u64 * self.height as u64
    }

    /// Whether anything in the scene gives off light: an emitting material (a colour or an
    /// emission texture) or a background that is not black. Without it no path can carry
    /// light, and the image is black.
    pub fn emits(&self) -> bool {
        let bright = |c: &[f32]| c.iter().any(|&x| x > 0.0);
        self.materials.iter().any(|m| m.emits())
            || bright(&self.background)
            || self.background_top.is_some_and(|t| bright(&t))
            || self.env.is_some()
            || self.punctual().iter().any(|e| e.power > 0.0)
    }

    /// The lights without a surface: point, spot and directional lights.
    pub fn punctual(&self) -> &[Emitter] {
        &self.emitters[self.emitters.len() - self.num_punctual as usize..]
    }
}

/// The smallest k with 4^k >= spp: jittered sampling's grid is 2^k x 2^k.
pub fn strata_log2(spp: u32) -> u32 {
    let mut k = 0;
    while k < 15 && (1u64 << (2 * k)) < spp as u64 {
        k += 1;
    }
    k
}
