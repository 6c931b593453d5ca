//! Loading: a scene file read (size checked first), parsed, validated, its meshes, glTF
//! files and images read relative to it, and flattened; or a glTF file on its own, with a
//! scene made around it (its camera or one that frames it, a background when it has no
//! light).

use std::cell::Cell;
use std::path::Path;

use glam::Vec3;
use toml::Spanned;

use super::error::{self, Problem, SceneError};
use super::flat::FlatScene;
use super::flatten::{self, Build, FlattenError, SceneFiles};
use super::format::{
    BackgroundDesc, CameraDesc, ColorSpace, FilterKind, LightSampling, MediumDesc, ObjectDesc,
    Projection, RenderDesc, SamplerKind, SceneFile, TextureDesc, MESH_ATTRIBUTES,
};
use super::gltf::{self, GltfError};
use super::imported::ImportedScene;
use super::materials::{reads_texture, reads_uv_derivatives, MaterialDesc};
use super::{mesh, mitsuba, mtl, textures, validate, volume};

/// Largest scene file read (64 MiB).
pub const MAX_SCENE_FILE_BYTES: u64 = 1 << 26;

/// Command-line values that replace the scene's `[render]` settings, its background, and
/// for a glTF file the camera.
#[derive(Debug, Clone, Default)]
pub struct Overrides {
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spp: Option<u32>,
    pub max_depth: Option<u32>,
    pub seed: Option<u32>,
    pub sampler: Option<SamplerKind>,
    pub light_sampling: Option<LightSampling>,
    /// The pixel filter (its radius and deviation from the file, else the defaults).
    pub filter: Option<FilterKind>,
    /// A constant background radiance instead of the scene's.
    pub background: Option<[f32; 3]>,
    /// A glTF file's camera by its name or its node's (default: the first).
    pub camera: Option<String>,
    /// Energy compensation of every microfacet lobe (`[render] energy_compensation`).
    pub energy_compensation: bool,
    /// A Mitsuba scene file's `<default>` values replaced (`-D name=value`).
    pub defines: Vec<(String, String)>,
}

/// Whether `path` names a glTF file (`.gltf`, `.glb`, any case).
pub fn is_gltf(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// Whether `path` names a Mitsuba 3 scene file (`.xml`, any case).
pub fn is_mitsuba(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("xml"))
}

/// Reads, validates and flattens a scene file: TOML, a Mitsuba 3 XML file, or a glTF file
/// on its own.
pub fn load(path: &Path, overrides: &Overrides, build: Build) -> Result<FlatScene, SceneError> {
    if is_gltf(path) {
        return load_gltf_scene(path, overrides, build);
    }
    if is_mitsuba(path) {
        return load_mitsuba(path, overrides, build);
    }
    if !overrides.defines.is_empty() {
        return Err(SceneError::Invalid {
            path: path.to_path_buf(),
            problems: vec![Problem::at(
                "",
                0,
                "-D",
                "sets a Mitsuba scene file's defaults; this is not one (.xml)",
            )],
        });
    }
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
    load_str(&src, path, overrides, build)
}

/// A Mitsuba 3 scene file mapped onto the scene format (`-D` defines applied), as the TOML
/// text `wgtrace convert` writes; its file paths relative to `base` where they lie under
/// it. Problems name the XML file, line and column.
pub fn convert_mitsuba(
    path: &Path,
    defines: &[(String, String)],
    base: &Path,
) -> Result<mitsuba::Imported, SceneError> {
    let xml = |e: mitsuba::XmlError| SceneError::Invalid {
        path: path.to_path_buf(),
        problems: vec![xml_problem(path, &e.pos, String::new(), e.message)],
    };
    let tree = mitsuba::parse_file(path, defines).map_err(xml)?;
    mitsuba::import(&tree, base).map_err(xml)
}

/// A problem at a position in `path` or a file it includes (named in the message).
fn xml_problem(path: &Path, pos: &mitsuba::Pos, key: String, message: String) -> Problem {
    let message = if pos.file.as_path() == path {
        message
    } else {
        format!("(in {}) {message}", pos.file.display())
    };
    Problem {
        line: pos.line as usize,
        column: pos.col as usize,
        key,
        message,
    }
}

fn load_mitsuba(path: &Path, overrides: &Overrides, build: Build) -> Result<FlatScene, SceneError> {
    let dir = path.parent().unwrap_or(Path::new(""));
    let imported = convert_mitsuba(path, &overrides.defines, dir)?;
    let overrides = Overrides {
        defines: Vec::new(),
        ..overrides.clone()
    };
    let mut scene = load_str(&imported.toml, path, &overrides, build).map_err(|e| match e {
        SceneError::Invalid { path, problems } => {
            let problems = problems
                .into_iter()
                .map(|p| match imported.origin(p.line) {
                    Some(o) if p.line > 0 => xml_problem(
                        &path,
                        &o.pos,
                        format!("{} (converted: {})", o.what, p.key),
                        p.message,
                    ),
                    _ => p,
                })
                .collect();
            SceneError::Invalid { path, problems }
        }
        other => other,
    })?;
    scene.warnings.extend(imported.notes);
    Ok(scene)
}

/// Validates and flattens scene text; `path` names it in errors, and the files it names
/// are read relative to its folder.
pub fn load_str(
    src: &str,
    path: &Path,
    overrides: &Overrides,
    build: Build,
) -> Result<FlatScene, SceneError> {
    let invalid = invalid_in(path);
    let mut file: SceneFile = toml::from_str(src).map_err(|e| {
        let offset = e.span().map_or(0, |s| s.start);
        let message = e.message().trim();
        let message = match error::did_you_mean(message) {
            Some(name) => format!("{message}; did you mean `{name}`?"),
            None => message.to_string(),
        };
        invalid(vec![Problem::at(src, offset, "", message)])
    })?;
    file.gather_groups();
    if overrides.camera.is_some() {
        return Err(invalid(vec![Problem::at(
            src,
            0,
            "--camera",
            "chooses among a glTF file's cameras; a scene file has its [camera]",
        )]));
    }
    let overridden = apply_overrides(&mut file, overrides);
    let problems = validate::validate(&file, src, &overridden);
    if !problems.is_empty() {
        return Err(invalid(problems));
    }
    let dir = path.parent().unwrap_or(Path::new(""));
    let files = read_files(&file, src, dir).map_err(invalid)?;
    // a group's OBJ file with its own .mtl may bring an emitting material
    let emitting: Vec<Problem> = (0..file.objects.len())
        .filter(|&i| file.group_of(i).is_some())
        .filter(|&i| files.imported[i].as_ref().is_some_and(|g| g.emits()))
        .map(|i| {
            Problem::at(
                src,
                file.objects[i].span().start,
                file.object_key(i),
                "an emitting .mtl material in a group (a light is sampled on its own \
                 surface, which an instance does not place): make it an object",
            )
        })
        .collect();
    if !emitting.is_empty() {
        return Err(invalid(emitting));
    }
    let scene_file = &file;
    let warnings = files
        .imported
        .iter()
        .zip(&file.objects)
        .enumerate()
        .filter_map(|(i, (g, o))| Some((i, g.as_ref()?, o.get_ref())))
        .flat_map(|(i, g, o)| {
            let (ObjectDesc::Gltf { path, .. } | ObjectDesc::Mesh { path, .. }) = o else {
                unreachable!("only glTF and mesh objects import a scene")
            };
            g.warnings
                .iter()
                .map(move |w| format!("{} ({path}): {w}", scene_file.object_key(i)))
        })
        .collect();
    let mut scene = flatten::flatten(&file, &files, build).map_err(|e| {
        invalid(match e {
            FlattenError::Degenerate(objects) => objects
                .into_iter()
                .map(|i| {
                    Problem::at(
                        src,
                        file.objects[i].span().start,
                        file.object_key(i),
                        "degenerates in f32 under its transform (a size, normal or matrix \
                         becomes zero, infinite or NaN)",
                    )
                })
                .collect(),
            FlattenError::Texels(why) => vec![Problem::at(src, 0, "textures", why)],
            FlattenError::Depth(d) => vec![Problem::at(src, 0, "groups", depth_problem(d))],
            FlattenError::Media(n) => vec![Problem::at(src, 0, "media", media_problem(n))],
        })
    })?;
    scene.warnings = warnings;
    Ok(scene)
}

/// A grid whose file's box can place it where `use_grid_bbox` asks (a box of positive
/// size), else why not.
fn placeable(g: volume::DensityGrid, use_grid_bbox: bool) -> Result<volume::DensityGrid, String> {
    let (lo, hi) = g.bbox;
    if use_grid_bbox && (0..3).any(|k| hi[k] <= lo[k]) {
        return Err(format!(
            "its box {lo:?} to {hi:?} is empty, and use_grid_bbox places the grid by it"
        ));
    }
    Ok(g)
}

/// Why a scene of too many media is refused.
fn media_problem(n: u32) -> String {
    format!(
        "{n} media, counting one inside each glass of its own absorption: at most {}",
        crate::scene::records::MEDIA_SIDE - 1
    )
}

/// Why a scene whose BVH and a group's are too deep together is refused.
fn depth_problem(depth: u32) -> String {
    format!(
        "the scene's BVH and a group's are {depth} levels deep together, more than the \
         walk's stack holds ({}): make the deepest group's objects objects",
        crate::scene::records::BVH_STACK_SIZE
    )
}

/// The error of a scene at `path` with `problems`.
fn invalid_in(path: &Path) -> impl Fn(Vec<Problem>) -> SceneError + Copy + '_ {
    move |problems| SceneError::Invalid {
        path: path.to_path_buf(),
        problems,
    }
}

/// A glTF file rendered on its own: its first scene, under its first camera (or the one
/// `overrides.camera` names; without any, one that frames the scene), the render
/// settings' defaults and overrides, and, when it has no punctual light, the studio
/// environment (`textures::studio_environment`), sampled as the image background is;
/// emissive surfaces add to it. The overrides' background replaces it.
fn load_gltf_scene(
    path: &Path,
    overrides: &Overrides,
    build: Build,
) -> Result<FlatScene, SceneError> {
    let invalid = invalid_in(path);
    let gltf_problem = |e: GltfError| Problem::at("", 0, e.key, e.message);
    let g = gltf::load_gltf(path, "").map_err(|e| invalid(vec![gltf_problem(e)]))?;
    let mut warnings = g.warnings.clone();
    let bounds = g.bounds();
    if bounds.is_empty() {
        return Err(invalid(vec![Problem::at(
            "",
            0,
            "",
            "its scene places no triangles (nothing to render)",
        )]));
    }
    let mut file = SceneFile {
        render: RenderDesc::default(),
        // replaced below, once the overrides give the image's aspect
        camera: framing_camera(bounds.lo, bounds.hi, 1.0),
        background: BackgroundDesc::default(),
        textures: Default::default(),
        materials: Default::default(),
        objects: vec![Spanned::new(
            0..0,
            ObjectDesc::Gltf {
                path: path.display().to_string(),
                transform: None,
            },
        )],
        lights: Vec::new(),
        media: Default::default(),
        groups: Default::default(),
        members: Vec::new(),
    };
    let overridden = apply_overrides(&mut file, overrides);
    let aspect = file.render.width.max(1) as f32 / file.render.height.max(1) as f32;
    file.camera = match &overrides.camera {
        Some(name) => g
            .cameras
            .iter()
            .find(|c| c.name == *name || c.node_name.as_deref() == Some(name))
            .map(|c| c.desc.clone())
            .ok_or_else(|| {
                let known: Vec<&str> = g.cameras.iter().map(|c| c.name.as_str()).collect();
                invalid(vec![Problem::at(
                    "",
                    0,
                    "--camera",
                    format!(
                        "no camera named \"{name}\" (the file has: {})",
                        if known.is_empty() {
                            "none".to_string()
                        } else {
                            known.join(", ")
                        }
                    ),
                )])
            })?,
        None => match g.cameras.first() {
            Some(c) => c.desc.clone(),
            None => {
                warnings.push("no camera: a view that frames the scene's bounds".into());
                framing_camera(bounds.lo, bounds.hi, aspect)
            }
        },
    };
    let mut images = Vec::new();
    if overrides.background.is_none() && g.lights.is_empty() {
        warnings.push(
            "no punctual light: the studio environment lights it, a sky over a grey ground \
             (emissive surfaces add to it; --background R,G,B replaces it: 1,1,1 for a \
             white furnace, 0,0,0 for none)"
                .into(),
        );
        let name = "studio environment".to_string();
        file.textures.insert(
            name.clone(),
            Spanned::new(
                0..0,
                TextureDesc::Image {
                    path: "(built in)".into(),
                    wrap: Default::default(),
                    filter: Default::default(),
                    uv_set: 0,
                    factor: [1.0; 3],
                    color_space: ColorSpace::Linear,
                    transform: None,
                },
            ),
        );
        file.background.texture = Some(name);
        images.push(Some(textures::studio_environment()));
    }
    let problems = validate::validate(&file, "", &overridden);
    if !problems.is_empty() {
        return Err(invalid(problems));
    }
    let files = SceneFiles {
        meshes: vec![None],
        imported: vec![Some(g)],
        images,
        grids: Vec::new(),
        albedo_grids: Vec::new(),
    };
    let mut scene = flatten::flatten(&file, &files, build).map_err(|e| {
        let why = match e {
            FlattenError::Degenerate(_) => {
                "a mesh degenerates in f32 under its node's transform".to_string()
            }
            FlattenError::Texels(why) => why,
            FlattenError::Depth(d) => depth_problem(d),
            FlattenError::Media(n) => media_problem(n),
        };
        invalid(vec![Problem::at("", 0, "", why)])
    })?;
    scene.warnings = warnings;
    Ok(scene)
}

/// A camera that frames the box lo..hi: looking at its centre from the front (+z, glTF's
/// front) and a little above, far enough that its bounding sphere fits the narrower
/// field of view (40 degrees vertically).
fn framing_camera(lo: Vec3, hi: Vec3, aspect: f32) -> CameraDesc {
    let vfov = 40.0f32;
    let center = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length()).max(1e-3);
    let half = (0.5 * vfov).to_radians();
    let narrow = if aspect < 1.0 {
        (half.tan() * aspect).atan()
    } else {
        half
    };
    let distance = radius / narrow.sin();
    let from = center + distance * Vec3::new(0.0, 0.25, 1.0).normalize();
    CameraDesc {
        look_from: from.into(),
        look_at: center.into(),
        up: [0.0, 1.0, 0.0],
        vfov,
        aperture: 0.0,
        focus_distance: None,
        projection: Projection::Perspective,
        height: None,
        mirror: false,
        near_clip: 0.0,
        medium: None,
    }
}

/// Reads the files the scene names (meshes, glTF files, images), relative to its folder
/// `dir`; every problem with its line and key. The caps hold for all meshes and all
/// images of the scene together, counted as they load, so that naming one file many
/// times cannot exhaust memory either.
fn read_files(file: &SceneFile, src: &str, dir: &Path) -> Result<SceneFiles, Vec<Problem>> {
    let mut problems = Vec::new();
    let triangles = Cell::new(0u64);
    let texels = Cell::new(0u64);
    // glTF files, and OBJ files that bring their own materials
    let imported = file
        .objects
        .iter()
        .enumerate()
        .map(|(i, obj)| match obj.get_ref() {
            ObjectDesc::Gltf { path, .. }
            | ObjectDesc::Mesh {
                path,
                material: None,
                ..
            } => read_relative(
                (src, dir, path),
                obj.span().start,
                format!("{}.path", file.object_key(i)),
                |p| {
                    let prefix = format!("{}/", file.object_key(i));
                    let g: ImportedScene = if let ObjectDesc::Mesh {
                        face_normals,
                        smooth_normals,
                        flip_normals,
                        color_space,
                        ..
                    } = obj.get_ref()
                    {
                        let adjust = mesh::Adjust {
                            face_normals: *face_normals,
                            smooth_normals: *smooth_normals,
                            flip_normals: *flip_normals,
                            ..Default::default()
                        };
                        if mesh::is_ply(p) || mesh::is_serialized(p) {
                            let kind = if mesh::is_ply(p) {
                                "PLY"
                            } else {
                                ".serialized"
                            };
                            return Err(format!(
                                "a {kind} file has no materials: give the object a `material`"
                            ));
                        }
                        let mut g = mtl::load_obj_scene(p, &prefix, *color_space)?;
                        for m in &mut g.meshes {
                            mesh::adjust(m, adjust);
                        }
                        g
                    } else {
                        gltf::load_gltf(p, &prefix).map_err(|e| e.to_string())?
                    };
                    count_toward(
                        &triangles,
                        g.instanced_triangles(),
                        mesh::MAX_TRIANGLES as u64,
                        "mesh triangles",
                    )?;
                    let n = g.unique_texels();
                    count_toward(&texels, n, textures::MAX_TEXELS, "image texels")?;
                    Ok(g)
                },
                &mut problems,
            ),
            _ => None,
        })
        .collect();
    let meshes = file
        .objects
        .iter()
        .enumerate()
        .map(|(i, obj)| match obj.get_ref() {
            ObjectDesc::Mesh {
                path,
                material: Some(material),
                face_normals,
                smooth_normals,
                flip_normals,
                shape_index,
                color_space,
                flip_tex_coords,
                placed_winding,
                transform,
                ..
            } => read_relative(
                (src, dir, path),
                obj.span().start,
                format!("{}.path", file.object_key(i)),
                |p| {
                    let read = attributes_read(file, material);
                    if let [a, b, ..] = &read[..] {
                        return Err(format!(
                            "material \"{material}\" reads the mesh attributes {a} and {b}; \
                             a mesh keeps one of its file's attributes as its colours"
                        ));
                    }
                    let named = read
                        .first()
                        .filter(|a| !MESH_ATTRIBUTES.contains(&a.as_str()));
                    if named.is_some() && !mesh::is_ply(p) {
                        return Err(format!(
                            "material \"{material}\" reads the mesh attribute {}, which only \
                             a PLY file names",
                            read[0]
                        ));
                    }
                    let colors = mesh::ColorChoice {
                        space: *color_space,
                        attribute: read.first().map(String::as_str),
                    };
                    if *flip_tex_coords && !mesh::is_ply(p) {
                        return Err("flip_tex_coords applies to PLY files (a .serialized \
                                    file's uvs are read with v down always, an OBJ file's \
                                    with v up)"
                            .into());
                    }
                    let mut m = mesh::load_mesh_at(p, *shape_index, colors)?;
                    mesh::adjust(
                        &mut m,
                        mesh::Adjust {
                            face_normals: *face_normals,
                            smooth_normals: *smooth_normals,
                            flip_normals: *flip_normals,
                            flip_tex_coords: *flip_tex_coords,
                            default_uvs_v_down: *flip_tex_coords || mesh::is_serialized(p),
                            corner_uvs: reads_uvs(file, material),
                            winding_front: *placed_winding
                                && transform.as_ref().is_some_and(|t| {
                                    flatten::transform_matrix(t).matrix3.determinant() < 0.0
                                }),
                        },
                    );
                    // a normal map or anisotropic roughness needs tangents:
                    // MikkTSpace's, over the mesh's uvs
                    let mapped = file
                        .materials
                        .get(material)
                        .is_some_and(|d| d.get_ref().needs_tangents());
                    if mapped {
                        mesh::generate_tangents(&mut m);
                    }
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
            TextureDesc::Image {
                path, color_space, ..
            } => read_relative(
                (src, dir, path),
                t.span().start,
                format!("textures.{name}.path"),
                |p| {
                    let img = textures::load_image(p, *color_space == ColorSpace::Srgb)?;
                    count_toward(
                        &texels,
                        img.texel_count(),
                        textures::MAX_TEXELS,
                        "image texels",
                    )?;
                    Ok(img)
                },
                &mut problems,
            ),
            _ => None,
        })
        .collect();
    // each heterogeneous medium's density grid and albedo grid, where it names them
    let mut grids = Vec::new();
    let mut albedo_grids = Vec::new();
    for (name, m) in &file.media {
        let (grid, albedo_grid, use_grid_bbox) = match m.get_ref() {
            MediumDesc::Heterogeneous {
                grid,
                albedo_grid,
                use_grid_bbox,
                ..
            } => (grid.as_deref(), albedo_grid.as_deref(), *use_grid_bbox),
            _ => (None, None, false),
        };
        let mut read = |rel: Option<&str>, key: &str, reader: fn(&Path) -> Result<_, String>| {
            rel.and_then(|rel| {
                read_relative(
                    (src, dir, rel),
                    m.span().start,
                    format!("media.{name}.{key}"),
                    |p| placeable(reader(p)?, use_grid_bbox),
                    &mut problems,
                )
            })
        };
        grids.push(read(grid, "grid", volume::read_vol));
        albedo_grids.push(read(albedo_grid, "albedo_grid", volume::read_albedo_vol));
    }
    if problems.is_empty() {
        Ok(SceneFiles {
            meshes,
            imported,
            images,
            grids,
            albedo_grids,
        })
    } else {
        Err(problems)
    }
}

/// The mesh attributes (`vertex_color`, `face_color`, a PLY file's named ones) material
/// `name` (or a part of it, for a blend) reads through `mesh_attribute` textures, each
/// once, in the textures' order. The file is validated.
fn attributes_read(file: &SceneFile, name: &str) -> Vec<String> {
    let names: Vec<String> = file.textures.keys().cloned().collect();
    let records: Vec<_> = materials_of(file, name).map(|d| d.record(&names)).collect();
    let mut read: Vec<String> = Vec::new();
    for (k, t) in file.textures.values().enumerate() {
        if let TextureDesc::MeshAttribute { name: a } = t.get_ref() {
            let reads = |m: &_| reads_texture(m, |t| t == k as u32);
            if !read.contains(a) && records.iter().any(reads) {
                read.push(a.clone());
            }
        }
    }
    read
}

/// Whether material `name` (or a part of a blend) reads a texture other than a mesh
/// attribute, or the uv derivatives: whether a mesh of it needs uvs.
fn reads_uvs(file: &SceneFile, name: &str) -> bool {
    let names: Vec<String> = file.textures.keys().cloned().collect();
    reads_any(file, name, |t| {
        !matches!(t, TextureDesc::MeshAttribute { .. })
    }) || materials_of(file, name)
        .any(|d| d.needs_tangents() || reads_uv_derivatives(&d.record(&names)))
}

/// Material `name` and, through blends, the materials it is made of (each once).
fn materials_of<'a>(file: &'a SceneFile, name: &str) -> impl Iterator<Item = &'a MaterialDesc> {
    let mut stack = vec![name.to_string()];
    let mut seen = std::collections::HashSet::new();
    std::iter::from_fn(move || {
        while let Some(n) = stack.pop() {
            let Some(desc) = file.materials.get(&n).filter(|_| seen.insert(n.clone())) else {
                continue;
            };
            if let MaterialDesc::Blend(b) = desc.get_ref() {
                stack.push(b.first.clone());
                stack.push(b.second.clone());
            }
            return Some(desc.get_ref());
        }
        None
    })
}

/// Whether material `name` (or a part of a blend) reads a texture `pick` picks.
fn reads_any(file: &SceneFile, name: &str, pick: impl Fn(&TextureDesc) -> bool) -> bool {
    let names: Vec<String> = file.textures.keys().cloned().collect();
    let picked: Vec<u32> = file
        .textures
        .values()
        .enumerate()
        .filter(|(_, t)| pick(t.get_ref()))
        .map(|(k, _)| k as u32)
        .collect();
    materials_of(file, name).any(|d| reads_texture(&d.record(&names), |t| picked.contains(&t)))
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
    if let Some(c) = &mut r.crop {
        // a crop window inside the file's film keeps its place on a film of another size
        // (one outside it is left for validation to name)
        let inside = |o: u32, n: u32, side: u32| o as u64 + n as u64 <= side as u64;
        if inside(c[0], c[2], r.width) && inside(c[1], c[3], r.height) {
            // [start, size] of the span [o, o + n) of `from` pixels on `to`: at least one
            // pixel, inside the new side
            let span = |o: u32, n: u32, from: u32, to: Option<u32>| match to {
                Some(to) if from > 0 && to > 0 => {
                    let at =
                        |v: u32| ((v as u64 * to as u64 + from as u64 / 2) / from as u64) as u32;
                    let start = at(o).min(to - 1);
                    (start, at(o + n).saturating_sub(start).clamp(1, to - start))
                }
                _ => (o, n),
            };
            let (x, w) = span(c[0], c[2], r.width, o.width);
            let (y, h) = span(c[1], c[3], r.height, o.height);
            *c = [x, y, w, h];
        }
    }
    r.width = o.width.unwrap_or(r.width);
    r.height = o.height.unwrap_or(r.height);
    r.spp = o.spp.unwrap_or(r.spp);
    r.max_depth = o.max_depth.unwrap_or(r.max_depth);
    r.seed = o.seed.unwrap_or(r.seed);
    r.sampler = o.sampler.unwrap_or(r.sampler);
    r.light_sampling = o.light_sampling.unwrap_or(r.light_sampling);
    r.filter = o.filter.unwrap_or(r.filter);
    r.energy_compensation |= o.energy_compensation;
    if let Some(c) = o.background {
        file.background = BackgroundDesc {
            color: Some(c),
            ..Default::default()
        };
    }
    [
        ("width", o.width.is_some()),
        ("height", o.height.is_some()),
        ("spp", o.spp.is_some()),
        ("max_depth", o.max_depth.is_some()),
        ("filter", o.filter.is_some()),
    ]
    .into_iter()
    .filter_map(|(k, set)| set.then_some(k))
    .collect()
}
