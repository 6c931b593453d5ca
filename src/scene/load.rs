//! Loading: a scene file read (size checked first), parsed, validated, its meshes and
//! images read relative to it, and flattened.

use std::cell::Cell;
use std::path::Path;

use super::error::{self, Problem, SceneError};
use super::flat::FlatScene;
use super::flatten::{self, Build};
use super::format::{LightSampling, ObjectDesc, SamplerKind, SceneFile, TextureDesc};
use super::{mesh, textures, validate};

/// Largest scene file read (64 MiB).
pub const MAX_SCENE_FILE_BYTES: u64 = 1 << 26;

/// Command-line values that replace the scene's `[render]` settings.
#[derive(Debug, Clone, Copy, Default)]
pub struct Overrides {
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spp: Option<u32>,
    pub max_depth: Option<u32>,
    pub seed: Option<u32>,
    pub sampler: Option<SamplerKind>,
    pub light_sampling: Option<LightSampling>,
}

/// Reads, validates and flattens a scene file.
pub fn load_scene(
    path: &Path,
    overrides: &Overrides,
    build: Build,
) -> Result<FlatScene, SceneError> {
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
    load_scene_str(&src, path, overrides, build)
}

/// Validates and flattens scene text; `path` names it in errors, and the files it names
/// are read relative to its folder.
pub fn load_scene_str(
    src: &str,
    path: &Path,
    overrides: &Overrides,
    build: Build,
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
    let overridden = apply_overrides(&mut file, overrides);
    let problems = validate::validate(&file, src, &overridden);
    if !problems.is_empty() {
        return Err(invalid(problems));
    }
    let dir = path.parent().unwrap_or(Path::new(""));
    let (meshes, images) = read_files(&file, src, dir).map_err(invalid)?;
    flatten::flatten(&file, &meshes, &images, build).map_err(|objects| {
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

/// Meshes of one object each (None for other objects) and images of one texture each.
type SceneFiles = (
    Vec<Option<mesh::MeshData>>,
    Vec<Option<textures::ImageData>>,
);

/// Reads the files the scene names (OBJ meshes, images), relative to its folder `dir`;
/// every problem with its line and key. The caps hold for all meshes and all images of the
/// scene together, counted as they load, so that naming one file many times cannot
/// exhaust memory either.
fn read_files(file: &SceneFile, src: &str, dir: &Path) -> Result<SceneFiles, Vec<Problem>> {
    let mut problems = Vec::new();
    let triangles = Cell::new(0u64);
    let texels = Cell::new(0u64);
    let meshes = file
        .objects
        .iter()
        .enumerate()
        .map(|(i, obj)| match obj.get_ref() {
            ObjectDesc::Mesh { path, .. } => read_relative(
                (src, dir, path),
                obj.span().start,
                format!("objects[{i}].path"),
                |p| {
                    let m = mesh::load_mesh(p)?;
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
    let images = file
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
    if problems.is_empty() {
        Ok((meshes, images))
    } else {
        Err(problems)
    }
}

/// Adds `n` to the scene's running `total` of `what`, or fails once it would pass `cap`.
fn count_toward(total: &Cell<u64>, n: u64, cap: u64, what: &str) -> Result<(), String> {
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

/// Replaces the file's `[render]` values by the overrides given; returns the keys whose
/// problems then belong to the command line.
fn apply_overrides(file: &mut SceneFile, o: &Overrides) -> Vec<&'static str> {
    let r = &mut file.render;
    r.width = o.width.unwrap_or(r.width);
    r.height = o.height.unwrap_or(r.height);
    r.spp = o.spp.unwrap_or(r.spp);
    r.max_depth = o.max_depth.unwrap_or(r.max_depth);
    r.seed = o.seed.unwrap_or(r.seed);
    r.sampler = o.sampler.unwrap_or(r.sampler);
    r.light_sampling = o.light_sampling.unwrap_or(r.light_sampling);
    [
        ("width", o.width.is_some()),
        ("height", o.height.is_some()),
        ("spp", o.spp.is_some()),
        ("max_depth", o.max_depth.is_some()),
    ]
    .into_iter()
    .filter_map(|(k, set)| set.then_some(k))
    .collect()
}
