//! OBJ files with their .mtl materials, read with `tobj`: the objects of the file as
//! meshes, the materials mapped onto wgtrace's, their images read relative to the file.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3};

use super::format::{ColorSpace, Filter, TextureDesc, Wrap};
use super::imported::{ImportedScene, ImportedTexture, Instance};
use super::materials::common::ColorDesc;
use super::materials::{dielectric, imported_key, lambertian, pbr, MaterialDesc};
use super::mesh::{check, generate_tangents, obj_colors, read_obj, MeshData, MAX_MESH_FILE_BYTES};
use super::textures::{ImageData, MAX_TEXELS};

/// An OBJ file with the materials of its .mtl, as an imported scene: one mesh per object
/// of the file (each has one material), placed where the file puts it, and the materials
/// mapped onto wgtrace's (`mtl_material`), their textures read relative to the OBJ file.
/// A file without materials is refused: the scene must then name one. Names begin with
/// `prefix`.
pub fn load_obj_scene(
    path: &Path,
    prefix: &str,
    colors: ColorSpace,
) -> Result<ImportedScene, String> {
    let bytes = std::fs::metadata(path).map_err(|e| e.to_string())?.len();
    if bytes > MAX_MESH_FILE_BYTES {
        return Err(format!(
            "is {bytes} bytes, more than the {MAX_MESH_FILE_BYTES} read for a mesh"
        ));
    }
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, materials) = read_obj(path, &options)?;
    let materials = materials.map_err(|e| format!("its .mtl file: {e}"))?;
    if materials.is_empty() {
        return Err(
            "has no materials (no mtllib, or an empty .mtl): give the object a `material`".into(),
        );
    }
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut out = ImportedScene::default();
    let mut textures = MtlTextures {
        dir,
        prefix,
        out: Vec::new(),
        images: HashMap::new(),
        texels: 0,
    };
    for m in &materials {
        let desc = mtl_material(m, &mut textures, &mut out.warnings)
            .map_err(|e| format!("material \"{}\": {e}", m.name))?;
        out.materials
            .push((format!("{prefix}{} (mtl)", m.name), desc));
    }
    out.textures = textures.out;
    let mut default_material = None;
    for model in &models {
        let m = &model.mesh;
        if m.indices.is_empty() {
            continue;
        }
        let mut mesh = MeshData {
            positions: m.positions.chunks_exact(3).map(Vec3::from_slice).collect(),
            normals: m.normals.chunks_exact(3).map(Vec3::from_slice).collect(),
            uvs: m.texcoords.chunks_exact(2).map(Vec2::from_slice).collect(),
            colors: obj_colors(m, colors),
            triangles: m
                .indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect(),
            ..Default::default()
        };
        let material = match m.material_id.filter(|&id| id < materials.len()) {
            Some(id) => id,
            None => *default_material.get_or_insert_with(|| {
                out.warnings.push(format!(
                    "object \"{}\" names no material of the .mtl: a grey Lambertian one",
                    model.name
                ));
                out.materials.push((
                    format!("{prefix}default material"),
                    MaterialDesc::Lambertian(lambertian::Desc {
                        albedo: ColorDesc::Rgb([0.8; 3]),
                        emission: ColorDesc::Rgb([0.0; 3]),
                        two_sided: false,
                        opacity: None,
                        bump: None,
                        bump_scale: 1.0,
                        normal_map: None,
                        one_sided: false,
                    }),
                ));
                out.materials.len() - 1
            }),
        };
        mesh = check(mesh).map_err(|e| format!("object \"{}\" {e}", model.name))?;
        if out.materials[material].1.normal_map().is_some() {
            generate_tangents(&mut mesh);
        }
        out.meshes.push(mesh);
        out.instances.push(Instance {
            mesh: out.meshes.len() - 1,
            material,
            transform: Affine3A::IDENTITY,
        });
    }
    if out.instances.is_empty() {
        return Err("has no faces".into());
    }
    Ok(out)
}

/// The images a .mtl names, each read once per colour space, within the texel cap.
struct MtlTextures<'a> {
    dir: &'a Path,
    prefix: &'a str,
    out: Vec<ImportedTexture>,
    images: HashMap<(String, bool), Arc<ImageData>>,
    texels: u64,
}

impl MtlTextures<'_> {
    /// The texture of a `map_*` statement (its options, e.g. `-bm 0.5`, apart), and the
    /// value of its `-bm` option.
    fn texture(
        &mut self,
        statement: &str,
        srgb: bool,
        factor: [f32; 3],
    ) -> Result<(String, f32), String> {
        let (file, bump) = map_statement(statement);
        let name = format!("{}{file}#{}", self.prefix, self.out.len());
        let full = self.dir.join(&file);
        let image = match self.images.get(&(file.clone(), srgb)) {
            Some(image) => image.clone(),
            None => {
                let image = super::textures::load_image(&full, srgb)
                    .map_err(|e| format!("{}: {e}", full.display()))?;
                self.texels += image.texel_count();
                if self.texels > MAX_TEXELS {
                    return Err(format!(
                        "{}: brings the file's texels past the {MAX_TEXELS} accepted",
                        full.display()
                    ));
                }
                let image = Arc::new(image);
                self.images.insert((file.clone(), srgb), image.clone());
                image
            }
        };
        self.out.push(ImportedTexture {
            name: name.clone(),
            desc: TextureDesc::Image {
                path: file,
                wrap: Wrap::default(),
                filter: Filter::Bilinear,
                uv_set: 0,
                factor,
                color_space: if srgb {
                    ColorSpace::Srgb
                } else {
                    ColorSpace::Linear
                },
                transform: None,
            },
            image,
        });
        Ok((name, bump))
    }
}

/// The file name of a .mtl `map_*` statement and its `-bm` value (1 without one): the
/// options (a dash, then their numbers or on/off words) come before the name, which may
/// hold spaces.
fn map_statement(s: &str) -> (String, f32) {
    let words: Vec<&str> = s.split_whitespace().collect();
    let mut i = 0;
    let mut bump = 1.0;
    while i < words.len() && words[i].starts_with('-') && words[i].len() > 1 {
        let option = words[i];
        i += 1;
        // an option's arguments: the numbers (and on/off, or a channel letter) after it
        while i + 1 < words.len()
            && (words[i].parse::<f32>().is_ok()
                || matches!(words[i], "on" | "off" | "r" | "g" | "b" | "m" | "l" | "z"))
        {
            if option == "-bm" {
                bump = words[i].parse().unwrap_or(1.0);
            }
            i += 1;
        }
    }
    (words[i.min(words.len())..].join(" "), bump)
}

/// A .mtl material on wgtrace's (documented in docs/scene-format.md): illum 4, 6, 7 or 9
/// (refraction) onto `dielectric`, any other onto `pbr` (each module maps its own), then
/// the same checks as a scene file's materials, their problems named by the statement.
fn mtl_material(
    m: &tobj::Material,
    textures: &mut MtlTextures,
    warnings: &mut Vec<String>,
) -> Result<MaterialDesc, String> {
    let (desc, keys) = if matches!(m.illumination_model, Some(4 | 6 | 7 | 9)) {
        (
            MaterialDesc::Dielectric(dielectric::from_mtl(m)?),
            dielectric::MTL_KEYS,
        )
    } else {
        let mut image = |statement: &str, srgb: bool, factor: [f32; 3]| {
            textures.texture(statement, srgb, factor)
        };
        (
            MaterialDesc::Pbr(pbr::from_mtl(m, &mut image, warnings)?),
            pbr::MTL_KEYS,
        )
    };
    let names: Vec<String> = textures.out.iter().map(|t| t.name.clone()).collect();
    let named = |field: &str| imported_key("", keys, field);
    match desc.check(&named, &names).into_iter().next() {
        Some((key, message)) => Err(format!("{key}: {message}")),
        None => Ok(desc),
    }
}
