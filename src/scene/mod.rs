//! Scenes: parse (`format`), validate and flatten into the records both backends read.
//!
//! Data flows one way: file -> [`format::SceneFile`] -> validation -> [`FlatScene`] (records).
//! This module knows nothing of the backends.

pub mod bvh;
pub mod error;
pub mod flatten;
pub mod format;
pub mod lights;
pub mod mesh;
pub mod records;
pub mod textures;
pub mod validate;

use std::path::Path;

use glam::Vec3;

pub use error::{Problem, SceneError};
use format::TextureDesc;
use format::{ObjectDesc, SceneFile};
use records::{BvhNode, Emitter, Material, Params, Primitive, Texture};

/// Command-line values that replace the scene's `[render]` settings.
#[derive(Debug, Clone, Copy, Default)]
pub struct Overrides {
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spp: Option<u32>,
    pub max_depth: Option<u32>,
    pub seed: Option<u32>,
    /// Test every primitive on every ray instead of traversing the BVH (benchmarks, tests).
    pub no_bvh: bool,
    /// Traverse the BVH even in a scene small enough for the plain loop
    /// ([`SMALL_SCENE_PRIMITIVES`]), for comparisons.
    pub force_bvh: bool,
    /// Keep every record array in a storage buffer, none in a uniform buffer (for
    /// comparisons; `gpu::shader::UNIFORM_DEFINES`).
    pub no_uniform_records: bool,
    /// Read a small scene's primitives, materials and lights from their buffers, not as
    /// constants written into its shader (for comparisons; `gpu::shader::scene_shader`).
    pub no_baked_records: bool,
    /// One sample per GPU invocation instead of a group of them (for comparisons;
    /// `gpu::render::SAMPLE_GROUP`).
    pub no_sample_groups: bool,
    /// Trace every path to max_depth (or until it escapes or goes black), without Russian
    /// roulette (for comparisons).
    pub no_russian_roulette: bool,
    pub sampler: Option<format::SamplerKind>,
    pub light_sampling: Option<format::LightSampling>,
    /// Assemble the full shader instead of one specialized to the scene's features.
    pub no_specialize: bool,
}

/// Scenes with at most this many bounded primitives, none of them transformed, test them
/// all in a plain loop rather than walking the BVH. On lavapipe the loop was 1.3x to 2.1x
/// faster on every such scene in `scenes/` (all SIMD lanes walk it together, where the
/// BVH walk diverges); transformed primitives cost enough per test that the BVH won
/// there (transforms.toml, 10 primitives: 0.78 against 0.67 Msamples/s).
pub const SMALL_SCENE_PRIMITIVES: usize = 16;

/// The first ray Russian roulette may stop: the fourth (after the camera ray and two
/// bounces), as pbrt-v4 starts it after depth 1. A path then goes on with probability
/// min(1, max(throughput)) and its throughput is divided by that: unbiased.
pub const RR_DEPTH: u32 = 3;

/// Largest image side accepted.
pub const MAX_IMAGE_SIDE: u32 = 16384;
/// Most samples per pixel accepted (2^24): sample indices stay exact in f32 and far from
/// the u32 limit of the random streams.
pub const MAX_SPP: u32 = 1 << 24;
/// Longest path accepted (rays per path).
pub const MAX_DEPTH_LIMIT: u32 = 1024;
/// Largest scene file read (64 MiB).
pub const MAX_SCENE_FILE_BYTES: u64 = 1 << 26;

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
}

/// A validated scene flattened into shader records.
#[derive(Debug, Clone)]
pub struct FlatScene {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: u32,
    pub seed: u32,
    /// `records::SAMPLER_*`.
    pub sampler: u32,
    pub camera: CameraFrame,
    /// Background radiance: the constant colour, or the bottom of the gradient.
    pub background: [f32; 3],
    /// The top of the gradient, when the background is one.
    pub background_top: Option<[f32; 3]>,
    /// The image background, when it is one.
    pub env: Option<EnvironmentMap>,
    /// `records::LIGHT_SAMPLING_*`.
    pub light_sampling: u32,
    /// Assemble the GPU shader for the scene's features only (false: the full shader).
    pub specialize: bool,
    /// Bind record arrays that fit as uniform buffers (a specialized shader only).
    pub uniform_records: bool,
    /// Write a small scene's primitives, materials and lights into its shader as
    /// constants (a specialized shader only; `gpu::shader::scene_shader`).
    pub baked_records: bool,
    /// Let one GPU invocation trace a group of samples (`gpu::render::SAMPLE_GROUP`).
    pub sample_groups: bool,
    /// The first ray Russian roulette may stop ([`RR_DEPTH`]; 0: none).
    pub rr_depth: u32,
    pub primitives: Vec<Primitive>,
    pub materials: Vec<Material>,
    /// The light list: emissive primitives that can be sampled, then the image background.
    pub emitters: Vec<Emitter>,
    /// Material names, in record order.
    pub material_names: Vec<String>,
    /// BVH over primitives `num_unbounded..`, depth-first.
    pub bvh: Vec<BvhNode>,
    /// Depth of the deepest BVH leaf (the root is 0).
    pub bvh_depth: u32,
    /// Transforms and triangle vertex attributes, indexed by `Primitive::data`.
    pub shape_data: Vec<[f32; 4]>,
    /// Primitives `0..num_unbounded` are planes, outside the BVH.
    pub num_unbounded: u32,
    pub use_bvh: bool,
    /// Texture records, in `[textures]` name order.
    pub textures: Vec<Texture>,
    /// Image texels (linear RGB) and Perlin tables, indexed by `Texture::offset`.
    pub texels: Vec<[f32; 4]>,
}

/// An equirectangular image background.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnvironmentMap {
    /// Its texture record.
    pub texture: u32,
    /// First `texels` entry of its sampling distribution.
    pub cdf: u32,
    /// Its index in the light list (`records::NO_LIGHT` when it is black).
    pub light: u32,
    /// cos and sin of its rotation about +y.
    pub rotation: [f32; 2],
    pub strength: f32,
}

/// A rectangle of pixels rendered by one dispatch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tile {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

impl FlatScene {
    /// The uniform block for one dispatch: pass `sample_index` over `tile`.
    pub fn params(&self, sample_index: u32, tile: Tile) -> Params {
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
            num_emitters: self.emitters.len() as u32,
            tile_x: tile.x,
            tile_y: tile.y,
            tile_width: tile.width,
            tile_height: tile.height,
            num_unbounded: self.num_unbounded,
            use_bvh: self.use_bvh as u32,
            sampler: self.sampler,
            strata_log2: strata_log2(self.spp),
            spp: self.spp,
            light_sampling: self.light_sampling,
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
            ..Default::default()
        }
    }

    /// The whole image as one tile.
    pub fn full_tile(&self) -> Tile {
        Tile {
            x: 0,
            y: 0,
            width: self.width,
            height: self.height,
        }
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

/// Reads, validates and flattens a scene file.
pub fn load_scene(path: &Path, overrides: &Overrides) -> Result<FlatScene, SceneError> {
    let io = |cause| SceneError::Io {
        path: path.to_path_buf(),
        cause,
    };
    let bytes = std::fs::metadata(path).map_err(io)?.len();
    if bytes > MAX_SCENE_FILE_BYTES {
        return Err(io(std::io::Error::other(format!(
            "it is {bytes} bytes, more than the {MAX_SCENE_FILE_BYTES} read for a scene file \
             (meshes belong in OBJ files)"
        ))));
    }
    let src = std::fs::read_to_string(path).map_err(io)?;
    load_scene_str(&src, path, overrides)
}

/// Validates and flattens scene text; `path` names it in errors.
pub fn load_scene_str(
    src: &str,
    path: &Path,
    overrides: &Overrides,
) -> Result<FlatScene, SceneError> {
    let invalid = |problems| SceneError::Invalid {
        path: path.to_path_buf(),
        problems,
    };
    let mut file: SceneFile = toml::from_str(src).map_err(|e| {
        let offset = e.span().map_or(0, |s| s.start);
        let message = e.message().trim();
        let message = match error::did_you_mean(message) {
            Some(name) => format!("{message}; did you mean `{name}`?"),
            None => message.to_string(),
        };
        invalid(vec![Problem::at(src, offset, "", message)])
    })?;
    apply_overrides(&mut file, overrides);
    let o = overrides;
    let overridden: Vec<&str> = [
        ("width", o.width.is_some()),
        ("height", o.height.is_some()),
        ("spp", o.spp.is_some()),
        ("max_depth", o.max_depth.is_some()),
    ]
    .into_iter()
    .filter_map(|(k, set)| set.then_some(k))
    .collect();
    let problems = validate::validate(&file, src, &overridden);
    if !problems.is_empty() {
        return Err(invalid(problems));
    }

    // Files the scene names (OBJ meshes, images), relative to it.
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut problems = Vec::new();
    // the caps hold for all meshes and all images of the scene together, counted as they
    // load, so that naming one file many times cannot exhaust memory either
    let triangles = std::cell::Cell::new(0u64);
    let texels = std::cell::Cell::new(0u64);
    let meshes: Vec<Option<mesh::MeshData>> = file
        .objects
        .iter()
        .enumerate()
        .map(|(i, obj)| match obj.get_ref() {
            ObjectDesc::Mesh { path, .. } => read_relative(
                (src, dir, path),
                obj.span().start,
                format!("objects[{i}].path"),
                |p| {
                    let m = mesh::load_obj(p)?;
                    count_toward(
                        &triangles,
                        m.triangles.len() as u64,
                        mesh::MAX_TRIANGLES as u64,
                        "mesh triangles",
                    )?;
                    Ok(m)
                },
                &mut problems,
            ),
            _ => None,
        })
        .collect();
    let images: Vec<Option<textures::ImageData>> = file
        .textures
        .iter()
        .map(|(name, t)| match t.get_ref() {
            TextureDesc::Image { path, .. } => read_relative(
                (src, dir, path),
                t.span().start,
                format!("textures.{name}.path"),
                |p| {
                    let img = textures::load_image(p)?;
                    let n = img.width as u64 * img.height as u64;
                    count_toward(&texels, n, textures::MAX_TEXELS, "image texels")?;
                    Ok(img)
                },
                &mut problems,
            ),
            _ => None,
        })
        .collect();
    if !problems.is_empty() {
        return Err(invalid(problems));
    }

    let bvh_choice = if overrides.no_bvh {
        flatten::BvhChoice::Never
    } else if overrides.force_bvh {
        flatten::BvhChoice::Always
    } else {
        flatten::BvhChoice::Auto
    };
    flatten::flatten(&file, &meshes, &images, bvh_choice)
        .map(|scene| FlatScene {
            specialize: !overrides.no_specialize,
            uniform_records: !overrides.no_uniform_records,
            baked_records: !overrides.no_baked_records,
            sample_groups: !overrides.no_sample_groups,
            rr_depth: if overrides.no_russian_roulette {
                0
            } else {
                RR_DEPTH
            },
            ..scene
        })
        .map_err(|objects| {
            invalid(
                objects
                    .into_iter()
                    .map(|i| {
                        Problem::at(
                            src,
                            file.objects[i].span().start,
                            format!("objects[{i}]"),
                            "degenerates in f32 under its transform (a size, normal or matrix \
                         becomes zero, infinite or NaN)",
                        )
                    })
                    .collect(),
            )
        })
}

/// Adds `n` to the scene's running `total` of `what`, or fails once it would pass `cap`.
fn count_toward(total: &std::cell::Cell<u64>, n: u64, cap: u64, what: &str) -> Result<(), String> {
    let sum = total.get() + n;
    if sum > cap {
        return Err(format!(
            "brings the scene's {what} to {sum}, more than the {cap} accepted"
        ));
    }
    total.set(sum);
    Ok(())
}

/// Loads `rel` (relative to the scene's folder `dir`) with `load`; a failure becomes a
/// problem at byte `offset` of the scene text, naming `key` and the full path.
fn read_relative<T>(
    (src, dir, rel): (&str, &Path, &str),
    offset: usize,
    key: String,
    load: impl Fn(&Path) -> Result<T, String>,
    problems: &mut Vec<Problem>,
) -> Option<T> {
    let full = dir.join(rel);
    load(&full)
        .map_err(|e| {
            problems.push(Problem::at(
                src,
                offset,
                key,
                format!("{}: {e}", full.display()),
            ))
        })
        .ok()
}

fn apply_overrides(file: &mut SceneFile, o: &Overrides) {
    let r = &mut file.render;
    r.width = o.width.unwrap_or(r.width);
    r.height = o.height.unwrap_or(r.height);
    r.spp = o.spp.unwrap_or(r.spp);
    r.max_depth = o.max_depth.unwrap_or(r.max_depth);
    r.seed = o.seed.unwrap_or(r.seed);
    r.sampler = o.sampler.unwrap_or(r.sampler);
    r.light_sampling = o.light_sampling.unwrap_or(r.light_sampling);
}
