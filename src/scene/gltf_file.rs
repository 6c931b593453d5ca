//! glTF 2.0 files (`.gltf` with its buffers and images, or `.glb`), read with the `gltf`
//! crate into what the rest of the loader knows: meshes, placed instances of them,
//! materials and textures in the scene format's terms, cameras and lights.
//!
//! Every accessor, buffer view and image is checked before it is read, so that a file
//! that lies about its sizes is refused with the JSON path of what lies, never read out
//! of bounds; the crate's own validation (indices that name nothing, missing fields) runs
//! first. Instances are flattened: each keeps its mesh by index here, and the flattener
//! writes the mesh's triangles once per instance.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use glam::{Affine3A, Mat4, Vec2, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};
use gltf::json::validation::Validate;

use super::format::{
    AlphaMode, CameraDesc, ColorDesc, LightDesc, MaterialDesc, Projection, TextureDesc,
};
use super::format::{ColorSpace, UvTransformDesc, WrapMode};
use super::imported::{ImportedScene, ImportedTexture, Instance, NamedCamera};
use super::mesh::{self, MeshData, MAX_MESH_FILE_BYTES, MAX_TRIANGLES};
use super::textures::{self, ImageData};

/// The extensions wgtrace reads; a file that requires another one is refused.
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_texture_transform",
];

/// A problem in a glTF file: the JSON path of what is at fault (e.g.
/// `meshes[3].primitives[0].attributes.POSITION`) and what is wrong with it.
#[derive(Debug, Clone, PartialEq)]
pub struct GltfError {
    pub key: String,
    pub message: String,
}

impl GltfError {
    fn new(key: impl Into<String>, message: impl Into<String>) -> Self {
        GltfError {
            key: key.into(),
            message: message.into(),
        }
    }
}

impl std::fmt::Display for GltfError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.key.is_empty() {
            write!(f, "{}", self.message)
        } else {
            write!(f, "{}: {}", self.key, self.message)
        }
    }
}

type Result<T> = std::result::Result<T, GltfError>;

/// Reads a glTF or GLB file and its first scene (the `scene` it names, else the first).
/// Names of its materials and textures begin with `prefix`.
pub fn load_gltf(path: &Path, prefix: &str) -> Result<ImportedScene> {
    let io = |e: std::io::Error| GltfError::new("", e.to_string());
    let bytes = std::fs::metadata(path).map_err(io)?.len();
    if bytes > MAX_MESH_FILE_BYTES {
        return Err(GltfError::new(
            "",
            format!("is {bytes} bytes, more than the {MAX_MESH_FILE_BYTES} read for a glTF file"),
        ));
    }
    let data = std::fs::read(path).map_err(io)?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let (doc, buffers, warnings) = open(&data, dir)?;
    Loader {
        doc: &doc,
        buffers,
        dir,
        prefix,
        out: ImportedScene {
            warnings,
            ..Default::default()
        },
        mesh_ids: HashMap::new(),
        material_ids: HashMap::new(),
        texture_keys: Vec::new(),
        images: HashMap::new(),
        texels: 0,
    }
    .scene()
}

/// Checks a GLB header before the crate reads it: the length it declares must cover the
/// header and fit the file.
fn check_glb_header(data: &[u8]) -> Result<()> {
    if !data.starts_with(b"glTF") {
        return Ok(());
    }
    let word = |i: usize| {
        data.get(i..i + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Err(GltfError::new(
            "",
            "is a truncated GLB file (no whole header)",
        ));
    };
    if version != 2 {
        return Err(GltfError::new(
            "",
            format!("is a GLB file of version {version}; wgtrace reads version 2"),
        ));
    }
    if length < 20 || length > data.len() {
        return Err(GltfError::new(
            "",
            format!(
                "is a GLB file whose header declares {length} bytes, but it holds {} \
                 (truncated?)",
                data.len()
            ),
        ));
    }
    // every chunk's declared length within the file
    let mut at = 12;
    while at + 8 <= length {
        let chunk = word(at).unwrap_or(0);
        if chunk > length - at - 8 {
            return Err(GltfError::new(
                "",
                format!("is a GLB file whose chunk at byte {at} runs past its end (truncated?)"),
            ));
        }
        at += 8 + chunk;
    }
    Ok(())
}

/// A texture of the scene format made from one glTF texture look-up: the texture, its
/// colour space, its factor, its uv set and its transform.
#[derive(Debug, Clone, PartialEq)]
struct TextureKey {
    texture: usize,
    srgb: bool,
    factor: [f32; 3],
    uv_set: u32,
    transform: Option<UvTransformDesc>,
}

struct Loader<'a> {
    doc: &'a gltf::Document,
    buffers: Vec<Vec<u8>>,
    dir: &'a Path,
    prefix: &'a str,
    out: ImportedScene,
    /// (mesh, primitive) -> index in `out.meshes`.
    mesh_ids: HashMap<(usize, usize), usize>,
    /// glTF material index (None: the default material) -> index in `out.materials`.
    material_ids: HashMap<Option<usize>, usize>,
    texture_keys: Vec<TextureKey>,
    /// (image, sRGB) -> decoded image.
    images: HashMap<(usize, bool), Arc<ImageData>>,
    /// Total texels decoded.
    texels: u64,
}

/// The document, checked by the crate's validation and for its required extensions, and
/// its buffers, each as long as it says and every buffer view within its buffer; with the
/// warnings about extensions it uses that wgtrace ignores.
fn open(data: &[u8], dir: &Path) -> Result<(gltf::Document, Vec<Vec<u8>>, Vec<String>)> {
    check_glb_header(data)?;
    let gltf = gltf::Gltf::from_slice_without_validation(data)
        .map_err(|e| GltfError::new("", format!("is not glTF 2.0: {e}")))?;
    let mut warnings = Vec::new();
    let root = gltf.document.as_json();
    for (i, ext) in root.extensions_required.iter().enumerate() {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            return Err(GltfError::new(
                format!("extensionsRequired[{i}]"),
                format!(
                    "the file requires the extension {ext}, which wgtrace cannot honour \
                     (it reads {})",
                    SUPPORTED_EXTENSIONS.join(", ")
                ),
            ));
        }
    }
    for ext in &root.extensions_used {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            warnings.push(format!(
                "the file uses the extension {ext}, which wgtrace ignores"
            ));
        }
    }
    // the crate's validation reads POSITION's accessor unchecked: check it first
    for (mi, m) in root.meshes.iter().enumerate() {
        for (pi, p) in m.primitives.iter().enumerate() {
            let position = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
            if let Some(a) = p.attributes.get(&position) {
                if a.value() >= root.accessors.len() {
                    return Err(GltfError::new(
                        format!("meshes[{mi}].primitives[{pi}].attributes.POSITION"),
                        format!(
                            "names accessors[{}], but the file has {} accessors",
                            a.value(),
                            root.accessors.len()
                        ),
                    ));
                }
            }
        }
    }
    // an image's source() unwraps these
    for (i, img) in root.images.iter().enumerate() {
        if img.buffer_view.is_some() && img.mime_type.is_none() {
            return Err(GltfError::new(
                format!("images[{i}].mimeType"),
                "is missing (an image in a bufferView must give its mimeType)",
            ));
        }
        if img.buffer_view.is_none() && img.uri.is_none() {
            return Err(GltfError::new(
                format!("images[{i}]"),
                "has neither a uri nor a bufferView",
            ));
        }
    }
    let mut problems = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| {
        let path = path().to_string();
        // required extensions are checked above against wgtrace's own list
        if !path.starts_with("extensionsRequired") {
            problems.push(GltfError::new(path, error.to_string()));
        }
    });
    if let Some(p) = problems.into_iter().next() {
        return Err(p);
    }
    let mut blob = gltf.blob;
    let doc = gltf.document;
    let mut buffers = Vec::new();
    for buffer in doc.buffers() {
        let key = format!("buffers[{}]", buffer.index());
        if let gltf::buffer::Source::Uri(uri) = buffer.source() {
            check_uri(uri, &format!("{key}.uri"))?;
        }
        let data = gltf::buffer::Data::from_source_and_blob(buffer.source(), Some(dir), &mut blob)
            .map_err(|e| GltfError::new(key.clone(), source_error(e, &buffer.source())))?;
        if data.len() < buffer.length() {
            return Err(GltfError::new(
                format!("{key}.byteLength"),
                format!(
                    "is {}, but the buffer holds {} bytes",
                    buffer.length(),
                    data.len()
                ),
            ));
        }
        buffers.push(data.0);
    }
    for view in doc.views() {
        let len = buffers[view.buffer().index()].len() as u128;
        // u128: a byteOffset near 2^64 must not wrap past the check
        let end = view.offset() as u128 + view.length() as u128;
        if end > len {
            return Err(GltfError::new(
                format!("bufferViews[{}]", view.index()),
                format!(
                    "ends at byte {end}, past the end of buffers[{}] ({len} bytes)",
                    view.buffer().index()
                ),
            ));
        }
    }
    Ok((doc, buffers, warnings))
}

impl<'a> Loader<'a> {
    /// Walks the first scene's node tree (depth-first, children in order).
    fn scene(mut self) -> Result<ImportedScene> {
        let scene = self
            .doc
            .default_scene()
            .or_else(|| self.doc.scenes().next())
            .ok_or_else(|| GltfError::new("scenes", "the file has no scene"))?;
        let mut seen = vec![false; self.doc.nodes().len()];
        let mut stack: Vec<(gltf::Node, Mat4)> = scene
            .nodes()
            .map(|n| (n, Mat4::IDENTITY))
            .collect::<Vec<_>>();
        stack.reverse();
        let nodes: Vec<(gltf::Node, Mat4)> = {
            let mut order = Vec::new();
            while let Some((node, parent)) = stack.pop() {
                let key = format!("nodes[{}]", node.index());
                if std::mem::replace(&mut seen[node.index()], true) {
                    return Err(GltfError::new(
                        key,
                        "is reached twice from the scene (the node hierarchy must be a tree)",
                    ));
                }
                let local = Mat4::from_cols_array_2d(&node.transform().matrix());
                if !local.is_finite() {
                    return Err(GltfError::new(key, "has a transform that is not finite"));
                }
                let world = parent * local;
                let mut children: Vec<_> = node.children().map(|c| (c, world)).collect();
                children.reverse();
                stack.extend(children);
                order.push((node, world));
            }
            order
        };
        for (node, world) in &nodes {
            let transform = Affine3A::from_mat4(*world);
            if let Some(mesh) = node.mesh() {
                self.mesh(&mesh, transform)?;
            }
            if let Some(camera) = node.camera() {
                self.camera(&camera, node, transform)?;
            }
            if let Some(light) = node.light() {
                self.light(&light, transform)?;
            }
            if node.skin().is_some() || node.weights().is_some() {
                self.out.warnings.push(format!(
                    "nodes[{}]: skins and morph targets are left out (the rest pose renders)",
                    node.index()
                ));
            }
        }
        let total = self.out.instanced_triangles();
        if total > MAX_TRIANGLES as u64 {
            return Err(GltfError::new(
                "",
                format!(
                    "its scene places {total} triangles (instances counted each), more than \
                     the {MAX_TRIANGLES} a scene may hold"
                ),
            ));
        }
        Ok(self.out)
    }

    fn mesh(&mut self, mesh: &gltf::Mesh, transform: Affine3A) -> Result<()> {
        for prim in mesh.primitives() {
            let key = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
            if prim.mode() != gltf::mesh::Mode::Triangles {
                self.out.warnings.push(format!(
                    "{key}: mode {:?} is left out (wgtrace renders triangles)",
                    prim.mode()
                ));
                continue;
            }
            let id = match self.mesh_ids.get(&(mesh.index(), prim.index())) {
                Some(&id) => id,
                None => {
                    // each primitive has one uv set: the one its material's textures read
                    // (a material that reads two gets the first, with a note)
                    let sets = uv_sets(&prim.material());
                    let uv_set = sets.first().copied().unwrap_or(0);
                    if sets.iter().any(|&s| s != uv_set) {
                        self.out.warnings.push(format!(
                            "{key}: its material's textures read TEXCOORD_{uv_set} and \
                             another set; wgtrace gives a primitive one: TEXCOORD_{uv_set}"
                        ));
                    }
                    let data = self.primitive(&prim, &key, uv_set)?;
                    self.out.meshes.push(data);
                    let id = self.out.meshes.len() - 1;
                    self.mesh_ids.insert((mesh.index(), prim.index()), id);
                    id
                }
            };
            let material = self.material(prim.material().index())?;
            self.out.instances.push(Instance {
                mesh: id,
                material,
                transform,
            });
        }
        Ok(())
    }

    /// A triangle primitive's vertices, normals and uv set `uv_set` (the one its
    /// material's textures read), indexed or not.
    fn primitive(&self, prim: &gltf::Primitive, key: &str, uv_set: u32) -> Result<MeshData> {
        use gltf::Semantic;
        let uv_name = format!("TEXCOORD_{uv_set}");
        let attr = |name: &str| format!("{key}.attributes.{name}");
        let positions = prim.get(&Semantic::Positions).ok_or_else(|| {
            GltfError::new(attr("POSITION"), "is missing (a primitive needs positions)")
        })?;
        let n = self.check_accessor(
            &positions,
            &attr("POSITION"),
            Dimensions::Vec3,
            &[DataType::F32],
        )?;
        if let Some(a) = prim.get(&Semantic::Normals) {
            self.check_count(&a, n, &attr("NORMAL"), Dimensions::Vec3, &[DataType::F32])?;
        }
        let uv_types = [DataType::F32, DataType::U8, DataType::U16];
        if let Some(a) = prim.get(&Semantic::TexCoords(uv_set)) {
            self.check_count(&a, n, &attr(&uv_name), Dimensions::Vec2, &uv_types)?;
        }
        let tangents = prim.get(&Semantic::Tangents);
        if let Some(a) = &tangents {
            self.check_count(a, n, &attr("TANGENT"), Dimensions::Vec4, &[DataType::F32])?;
        }
        if let Some(a) = prim.indices() {
            let types = [DataType::U8, DataType::U16, DataType::U32];
            self.check_accessor(&a, &format!("{key}.indices"), Dimensions::Scalar, &types)?;
        }
        let reader = prim.reader(|b| self.buffers.get(b.index()).map(Vec::as_slice));
        let unreadable = |what: String| {
            GltfError::new(
                what,
                "cannot be read (its sparse data points outside its buffer view?)",
            )
        };
        let mut mesh = MeshData {
            positions: reader
                .read_positions()
                .ok_or_else(|| unreadable(attr("POSITION")))?
                .map(Vec3::from)
                .collect(),
            ..Default::default()
        };
        if prim.get(&Semantic::Normals).is_some() {
            mesh.normals = reader
                .read_normals()
                .ok_or_else(|| unreadable(attr("NORMAL")))?
                .map(Vec3::from)
                .collect();
        }
        if prim.get(&Semantic::TexCoords(uv_set)).is_some() {
            mesh.uvs = reader
                .read_tex_coords(uv_set)
                .ok_or_else(|| unreadable(attr(&uv_name)))?
                .into_f32()
                // glTF's v runs down the image, wgtrace's up
                .map(|[u, v]| Vec2::new(u, 1.0 - v))
                .collect();
        }
        let indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None if prim.indices().is_some() => {
                return Err(unreadable(format!("{key}.indices")));
            }
            None => (0..n as u32).collect(),
        };
        if !indices.len().is_multiple_of(3) {
            return Err(GltfError::new(
                format!("{key}.indices"),
                format!("has {} entries, not a multiple of 3", indices.len()),
            ));
        }
        mesh.triangles = indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        let mut mesh = mesh::check(mesh).map_err(|e| GltfError::new(key, e))?;
        if prim.material().normal_texture().is_some() && !mesh.uvs.is_empty() {
            if tangents.is_some() {
                let t: Vec<Vec4> = reader
                    .read_tangents()
                    .ok_or_else(|| unreadable(attr("TANGENT")))?
                    .map(Vec4::from)
                    .collect();
                if !t.iter().all(|t| t.is_finite()) {
                    return Err(GltfError::new(attr("TANGENT"), "has a non-finite value"));
                }
                mesh.tangents = mesh
                    .triangles
                    .iter()
                    .map(|tri| tri.map(|i| t[i as usize]))
                    .collect();
            } else {
                // glTF: a normal-mapped mesh without tangents gets MikkTSpace's
                mesh::generate_tangents(&mut mesh);
            }
        }
        Ok(mesh)
    }

    /// `check_accessor` for an attribute that must have one entry per vertex.
    fn check_count(
        &self,
        a: &gltf::Accessor,
        n: usize,
        key: &str,
        dims: Dimensions,
        types: &[DataType],
    ) -> Result<()> {
        let count = self.check_accessor(a, key, dims, types)?;
        if count != n {
            return Err(GltfError::new(
                key,
                format!("has {count} entries, but POSITION has {n}"),
            ));
        }
        Ok(())
    }

    /// Checks an accessor of `dims` and one of `types` before it is read: its count, and
    /// that every byte it (and its sparse part) reads lies in its buffer view. Returns its
    /// count.
    fn check_accessor(
        &self,
        a: &gltf::Accessor,
        key: &str,
        dims: Dimensions,
        types: &[DataType],
    ) -> Result<usize> {
        let at = |what: &str| format!("{key} (accessors[{}]{what})", a.index());
        let count = a.count();
        let max = 3 * MAX_TRIANGLES;
        if count == 0 || count > max {
            return Err(GltfError::new(
                at(".count"),
                format!("is {count}; wgtrace reads 1 to {max}"),
            ));
        }
        if a.dimensions() != dims || !types.contains(&a.data_type()) {
            return Err(GltfError::new(
                at(""),
                format!(
                    "is {:?} of {:?}; expected {dims:?} of {types:?}",
                    a.dimensions(),
                    a.data_type()
                ),
            ));
        }
        let size = a.size();
        match a.view() {
            Some(view) => {
                self.check_view(&view, a.offset(), count, size, view.stride(), &at(""))?
            }
            None if a.sparse().is_none() => {
                return Err(GltfError::new(
                    at(""),
                    "has neither a bufferView nor sparse data",
                ));
            }
            None => {}
        }
        if let Some(s) = a.sparse() {
            if s.count() == 0 || s.count() > count {
                return Err(GltfError::new(
                    at(".sparse.count"),
                    format!("is {}; it must be 1 to the accessor's {count}", s.count()),
                ));
            }
            let index_size = match s.indices().index_type() {
                gltf::accessor::sparse::IndexType::U8 => 1,
                gltf::accessor::sparse::IndexType::U16 => 2,
                gltf::accessor::sparse::IndexType::U32 => 4,
            };
            let i = s.indices();
            self.check_view(
                &i.view(),
                i.offset(),
                s.count(),
                index_size,
                None,
                &at(".sparse.indices"),
            )?;
            let v = s.values();
            self.check_view(
                &v.view(),
                v.offset(),
                s.count(),
                size,
                None,
                &at(".sparse.values"),
            )?;
        }
        Ok(count)
    }

    /// That `count` elements of `size` bytes, `stride` apart (tightly packed without one),
    /// from `offset` lie within `view`.
    fn check_view(
        &self,
        view: &gltf::buffer::View,
        offset: usize,
        count: usize,
        size: usize,
        stride: Option<usize>,
        key: &str,
    ) -> Result<()> {
        let stride = stride.unwrap_or(size) as u128;
        if stride < size as u128 {
            return Err(GltfError::new(
                format!("bufferViews[{}].byteStride", view.index()),
                format!("is {stride}, less than the {size}-byte elements read through it"),
            ));
        }
        // count >= 1 (checked by the callers); u128 never wraps here
        let end = offset as u128 + stride * (count as u128 - 1) + size as u128;
        if end > view.length() as u128 {
            return Err(GltfError::new(
                key,
                format!(
                    "reads up to byte {end} of bufferViews[{}], which has {} bytes",
                    view.index(),
                    view.length()
                ),
            ));
        }
        Ok(())
    }

    /// The scene-format material of glTF material `index` (None: glTF's default
    /// material), made once.
    fn material(&mut self, index: Option<usize>) -> Result<usize> {
        if let Some(&id) = self.material_ids.get(&index) {
            return Ok(id);
        }
        let (name, desc) = match index {
            None => (
                format!("{}default material", self.prefix),
                MaterialDesc::Pbr {
                    base_color: ColorDesc::Rgb([1.0; 3]),
                    metallic: 1.0,
                    roughness: 1.0,
                    ior: 1.5,
                    specular: 1.0,
                    specular_color: ColorDesc::Rgb([1.0; 3]),
                    metallic_roughness: None,
                    specular_texture: None,
                    normal_map: None,
                    normal_scale: 1.0,
                    alpha: 1.0,
                    alpha_mode: AlphaMode::Opaque,
                    alpha_cutoff: 0.5,
                    emission: ColorDesc::Rgb([0.0; 3]),
                    two_sided: false,
                },
            ),
            Some(i) => {
                let m = self.doc.materials().nth(i).expect("validated index");
                let name = match m.name() {
                    Some(n) => format!("{}materials[{i}] ({n})", self.prefix),
                    None => format!("{}materials[{i}]", self.prefix),
                };
                (name, self.material_desc(&m)?)
            }
        };
        self.out.materials.push((name, desc));
        let id = self.out.materials.len() - 1;
        self.material_ids.insert(index, id);
        Ok(id)
    }

    fn material_desc(&mut self, m: &gltf::Material) -> Result<MaterialDesc> {
        let key = format!("materials[{}]", m.index().expect("not the default"));
        let pbr = m.pbr_metallic_roughness();
        let unit = |what: &str, x: f32| -> Result<f32> {
            if (0.0..=1.0).contains(&x) {
                Ok(x)
            } else {
                Err(GltfError::new(
                    format!("{key}.{what}"),
                    format!("must be in [0, 1], got {x}"),
                ))
            }
        };
        let factor4 = pbr.base_color_factor();
        for (c, x) in factor4.iter().enumerate() {
            unit(&format!("pbrMetallicRoughness.baseColorFactor[{c}]"), *x)?;
        }
        let base_factor = [factor4[0], factor4[1], factor4[2]];
        let metallic = unit("pbrMetallicRoughness.metallicFactor", pbr.metallic_factor())?;
        let roughness = unit(
            "pbrMetallicRoughness.roughnessFactor",
            pbr.roughness_factor(),
        )?;
        let base_color = self.color(
            pbr.base_color_texture(),
            base_factor,
            &key,
            "pbrMetallicRoughness.baseColorTexture",
        )?;
        let strength = m.emissive_strength().unwrap_or(1.0);
        if !(strength >= 0.0 && strength.is_finite()) {
            return Err(GltfError::new(
                format!("{key}.extensions.KHR_materials_emissive_strength.emissiveStrength"),
                format!("must be >= 0, got {strength}"),
            ));
        }
        let emissive = m.emissive_factor();
        for (c, x) in emissive.iter().enumerate() {
            unit(&format!("emissiveFactor[{c}]"), *x)?;
        }
        // an emissive texture times 0 (glTF's default emissiveFactor) emits nothing: no
        // texture, so that the material is not taken for a light
        let emission = self.color(
            m.emissive_texture()
                .filter(|_| emissive != [0.0; 3] && strength > 0.0),
            emissive.map(|c| c * strength),
            &key,
            "emissiveTexture",
        )?;
        let ior = m.ior().unwrap_or(1.5);
        if !(ior >= 1.0 && ior.is_finite()) {
            return Err(GltfError::new(
                format!("{key}.extensions.KHR_materials_ior.ior"),
                format!("must be >= 1, got {ior}"),
            ));
        }
        let two_sided = m.double_sided();
        let metallic_roughness = match pbr.metallic_roughness_texture() {
            Some(info) => Some(self.texture(
                &info,
                false,
                [1.0; 3],
                &format!("{key}.pbrMetallicRoughness.metallicRoughnessTexture"),
            )?),
            None => None,
        };
        let (normal_map, normal_scale) = match m.normal_texture() {
            Some(n) => {
                let scale = n.scale();
                if !scale.is_finite() {
                    return Err(GltfError::new(
                        format!("{key}.normalTexture.scale"),
                        format!("must be finite, got {scale}"),
                    ));
                }
                (
                    Some(self.normal_texture(&n, &format!("{key}.normalTexture"))?),
                    scale,
                )
            }
            None => (None, 1.0),
        };
        let alpha_cutoff = m.alpha_cutoff().unwrap_or(0.5);
        if !(0.0..=1.0).contains(&alpha_cutoff) {
            return Err(GltfError::new(
                format!("{key}.alphaCutoff"),
                format!("must be in [0, 1], got {alpha_cutoff}"),
            ));
        }
        let alpha_mode = match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
            gltf::material::AlphaMode::Mask => AlphaMode::Mask,
            gltf::material::AlphaMode::Blend => AlphaMode::Blend,
        };
        if let Some(t) = m.transmission() {
            let factor = unit(
                "extensions.KHR_materials_transmission.transmissionFactor",
                t.transmission_factor(),
            )?;
            if factor > 0.0 {
                return self.transmissive(m, &key, factor, base_color, ior, emission);
            }
        }
        let (mut specular, mut specular_color) = (1.0, ColorDesc::Rgb([1.0; 3]));
        let mut specular_texture = None;
        if let Some(s) = m.specular() {
            let sk = "extensions.KHR_materials_specular";
            specular = unit(&format!("{sk}.specularFactor"), s.specular_factor())?;
            let f = s.specular_color_factor();
            if !f.iter().all(|c| *c >= 0.0 && c.is_finite()) {
                return Err(GltfError::new(
                    format!("{key}.{sk}.specularColorFactor"),
                    format!("must be >= 0, got {f:?}"),
                ));
            }
            specular_color = self.color(
                s.specular_color_texture(),
                f,
                &key,
                &format!("{sk}.specularColorTexture"),
            )?;
            if let Some(info) = s.specular_texture() {
                // its alpha channel (linear) scales specularFactor
                let k = format!("{key}.{sk}.specularTexture");
                specular_texture = Some(self.texture(&info, false, [1.0; 3], &k)?);
            }
        }
        Ok(MaterialDesc::Pbr {
            base_color,
            metallic,
            roughness,
            ior,
            specular,
            specular_color,
            metallic_roughness,
            specular_texture,
            normal_map,
            normal_scale,
            alpha: factor4[3],
            alpha_mode,
            alpha_cutoff,
            emission,
            two_sided,
        })
    }

    /// KHR_materials_transmission onto wgtrace's dielectric: smooth glass of the
    /// material's ior, tinted by the base colour, absorbing inside as KHR_materials_volume
    /// says (sigma_a = -ln(attenuationColor) / attenuationDistance).
    fn transmissive(
        &mut self,
        m: &gltf::Material,
        key: &str,
        factor: f32,
        tint: ColorDesc,
        ior: f32,
        emission: ColorDesc,
    ) -> Result<MaterialDesc> {
        if factor < 1.0 {
            self.out.warnings.push(format!(
                "{key}: transmissionFactor {factor} is rendered as 1 (wgtrace's glass transmits all it does not reflect)"
            ));
        }
        if m.pbr_metallic_roughness().roughness_factor() > 0.0 {
            self.out.warnings.push(format!(
                "{key}: rough transmission is rendered as smooth glass"
            ));
        }
        let mut absorption = [0.0; 3];
        if let Some(v) = m.volume() {
            let d = v.attenuation_distance();
            let c = v.attenuation_color();
            if d.is_nan() || d <= 0.0 {
                return Err(GltfError::new(
                    format!("{key}.extensions.KHR_materials_volume.attenuationDistance"),
                    format!("must be > 0, got {d}"),
                ));
            }
            if !c.iter().all(|x| (0.0..=1.0).contains(x)) {
                return Err(GltfError::new(
                    format!("{key}.extensions.KHR_materials_volume.attenuationColor"),
                    format!("must be in [0, 1], got {c:?}"),
                ));
            }
            if d.is_finite() {
                // a colour of 0 absorbs everything: a large finite coefficient
                absorption = c.map(|x| (-(x.max(1e-6)).ln() / d).min(1e6));
            }
        }
        Ok(MaterialDesc::Dielectric {
            ior,
            tint,
            absorption,
            emission,
            two_sided: m.double_sided(),
        })
    }

    /// A colour parameter: `factor`, times the texture of `info` when there is one (an
    /// sRGB texture, named and made once per texture, factor and look-up).
    fn color(
        &mut self,
        info: Option<gltf::texture::Info>,
        factor: [f32; 3],
        key: &str,
        what: &str,
    ) -> Result<ColorDesc> {
        let Some(info) = info else {
            return Ok(ColorDesc::Rgb(factor));
        };
        let name = self.texture(&info, true, factor, &format!("{key}.{what}"))?;
        Ok(ColorDesc::Texture(name))
    }

    /// The name of the scene-format texture for one look-up of a glTF texture.
    fn texture(
        &mut self,
        info: &gltf::texture::Info,
        srgb: bool,
        factor: [f32; 3],
        key: &str,
    ) -> Result<String> {
        let t = info.texture_transform();
        let transform = t
            .as_ref()
            .map(|t| UvTransformDesc::from_v_down(t.offset(), t.rotation(), t.scale()));
        if let Some(tr) = &t {
            let [a, b] = tr.offset();
            let [c, d] = tr.scale();
            if ![a, b, c, d, tr.rotation()].iter().all(|x| x.is_finite()) {
                return Err(GltfError::new(
                    format!("{key}.extensions.KHR_texture_transform"),
                    "must hold finite numbers",
                ));
            }
        }
        let uv_set = t.and_then(|t| t.tex_coord()).unwrap_or(info.tex_coord());
        self.texture_lookup(info.texture(), uv_set, transform, srgb, factor)
            .map_err(|e| GltfError::new(e.key, format!("{} (the image of {key})", e.message)))
    }

    /// A normal texture's look-up: the crate gives its KHR_texture_transform only as JSON.
    fn normal_texture(&mut self, n: &gltf::material::NormalTexture, key: &str) -> Result<String> {
        let ext = n.extension_value("KHR_texture_transform");
        let pair = |name: &str, default: [f32; 2]| -> Result<[f32; 2]> {
            match ext.and_then(|e| e.get(name)) {
                None => Ok(default),
                Some(v) => match v
                    .as_array()
                    .map(|a| a.iter().map(|x| x.as_f64()).collect::<Vec<_>>())
                {
                    Some(a) if a.len() == 2 && a.iter().all(|x| x.is_some_and(f64::is_finite)) => {
                        Ok([a[0].unwrap_or(0.0) as f32, a[1].unwrap_or(0.0) as f32])
                    }
                    _ => Err(GltfError::new(
                        format!("{key}.extensions.KHR_texture_transform.{name}"),
                        "must be two finite numbers",
                    )),
                },
            }
        };
        let transform = match ext {
            Some(e) => {
                let rotation = e
                    .get("rotation")
                    .map_or(Some(0.0), |r| r.as_f64())
                    .filter(|r| r.is_finite())
                    .ok_or_else(|| {
                        GltfError::new(
                            format!("{key}.extensions.KHR_texture_transform.rotation"),
                            "must be a finite number",
                        )
                    })? as f32;
                Some(UvTransformDesc::from_v_down(
                    pair("offset", [0.0; 2])?,
                    rotation,
                    pair("scale", [1.0; 2])?,
                ))
            }
            None => None,
        };
        let uv_set = ext
            .and_then(|e| e.get("texCoord"))
            .and_then(|c| c.as_u64())
            .map_or(n.tex_coord(), |c| c as u32);
        self.texture_lookup(n.texture(), uv_set, transform, false, [1.0; 3])
    }

    fn texture_lookup(
        &mut self,
        tex: gltf::Texture,
        uv_set: u32,
        transform: Option<UvTransformDesc>,
        srgb: bool,
        factor: [f32; 3],
    ) -> Result<String> {
        let k = TextureKey {
            texture: tex.index(),
            srgb,
            factor,
            uv_set,
            transform,
        };
        if let Some(i) = self.texture_keys.iter().position(|t| *t == k) {
            return Ok(self.out.textures[i].name.clone());
        }
        let source = tex.source();
        let image = self.image(&source, srgb)?;
        if tex.sampler().wrap_t() != tex.sampler().wrap_s() {
            self.out.warnings.push(format!(
                "samplers[{}]: wrapT {:?} differs from wrapS {:?}; wgtrace wraps both as wrapS",
                tex.sampler().index().unwrap_or(0),
                tex.sampler().wrap_t(),
                tex.sampler().wrap_s()
            ));
        }
        let wrap = match tex.sampler().wrap_s() {
            gltf::texture::WrappingMode::ClampToEdge => WrapMode::Clamp,
            gltf::texture::WrappingMode::MirroredRepeat => WrapMode::Mirror,
            gltf::texture::WrappingMode::Repeat => WrapMode::Repeat,
        };
        let name = format!(
            "{}textures[{}]#{}",
            self.prefix,
            tex.index(),
            self.texture_keys.len()
        );
        self.out.textures.push(ImportedTexture {
            name: name.clone(),
            desc: TextureDesc::Image {
                path: String::new(),
                wrap,
                factor,
                color_space: if srgb {
                    ColorSpace::Srgb
                } else {
                    ColorSpace::Linear
                },
                transform,
            },
            image,
        });
        self.texture_keys.push(k);
        Ok(name)
    }

    /// glTF image `source` decoded (sRGB or linear), once per colour space.
    fn image(&mut self, source: &gltf::Image, srgb: bool) -> Result<Arc<ImageData>> {
        if let Some(img) = self.images.get(&(source.index(), srgb)) {
            return Ok(img.clone());
        }
        let key = format!("images[{}]", source.index());
        let bytes: Vec<u8> = match source.source() {
            gltf::image::Source::View { view, .. } => {
                let b = &self.buffers[view.buffer().index()];
                b[view.offset()..view.offset() + view.length()].to_vec()
            }
            gltf::image::Source::Uri { uri, .. } => {
                check_uri(uri, &format!("{key}.uri"))?;
                let src = gltf::buffer::Source::Uri(uri);
                gltf::buffer::Data::from_source(src, Some(self.dir))
                    .map_err(|e| {
                        GltfError::new(
                            format!("{key}.uri"),
                            source_error(e, &gltf::buffer::Source::Uri(uri)),
                        )
                    })?
                    .0
            }
        };
        let img =
            textures::decode_image(&bytes, srgb).map_err(|e| GltfError::new(key.clone(), e))?;
        self.texels += img.width as u64 * img.height as u64;
        if self.texels > textures::MAX_TEXELS {
            return Err(GltfError::new(
                key,
                format!(
                    "brings the file's texels past the {} accepted",
                    textures::MAX_TEXELS
                ),
            ));
        }
        let img = Arc::new(img);
        self.images.insert((source.index(), srgb), img.clone());
        Ok(img)
    }

    fn camera(&mut self, camera: &gltf::Camera, node: &gltf::Node, m: Affine3A) -> Result<()> {
        let key = format!("cameras[{}]", camera.index());
        let from = Vec3::from(m.translation);
        let forward = m.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        let up = m.transform_vector3(Vec3::Y).normalize_or_zero();
        if forward == Vec3::ZERO || up == Vec3::ZERO || forward.cross(up).length_squared() < 1e-12 {
            return Err(GltfError::new(
                format!("nodes[{}]", node.index()),
                "places a camera under a degenerate transform",
            ));
        }
        let mut desc = CameraDesc {
            look_from: from.into(),
            look_at: (from + forward).into(),
            up: up.into(),
            vfov: 40.0,
            aperture: 0.0,
            focus_distance: None,
            projection: Projection::Perspective,
            height: None,
        };
        match camera.projection() {
            gltf::camera::Projection::Perspective(p) => {
                let yfov = p.yfov().to_degrees();
                if !(yfov > 0.0 && yfov < 180.0) {
                    return Err(GltfError::new(
                        format!("{key}.perspective.yfov"),
                        format!("must be in (0, pi), got {}", p.yfov()),
                    ));
                }
                desc.vfov = yfov;
            }
            gltf::camera::Projection::Orthographic(o) => {
                let h = 2.0 * o.ymag().abs();
                if !(h > 0.0 && h.is_finite()) {
                    return Err(GltfError::new(
                        format!("{key}.orthographic.ymag"),
                        format!("must not be 0, got {}", o.ymag()),
                    ));
                }
                desc.projection = Projection::Orthographic;
                desc.height = Some(h);
            }
        }
        let name = camera
            .name()
            .or(node.name())
            .map_or_else(|| key.clone(), str::to_string);
        self.out.cameras.push(NamedCamera {
            name,
            node_name: node.name().map(str::to_string),
            desc,
        });
        Ok(())
    }

    /// KHR_lights_punctual: intensity taken as W/sr (point, spot) or W/m^2 (directional),
    /// times the colour; `range` ignored.
    fn light(&mut self, light: &gltf::khr_lights_punctual::Light, m: Affine3A) -> Result<()> {
        use gltf::khr_lights_punctual::Kind;
        let key = format!("extensions.KHR_lights_punctual.lights[{}]", light.index());
        let i = light.intensity();
        let c = light.color();
        if !(i >= 0.0 && i.is_finite() && c.iter().all(|x| *x >= 0.0 && x.is_finite())) {
            return Err(GltfError::new(
                key,
                "needs a finite, non-negative intensity and colour",
            ));
        }
        if light.range().is_some() {
            self.out.warnings.push(format!(
                "{key}: range is ignored (the light falls off with the inverse square, unbounded)"
            ));
        }
        let power = c.map(|x| x * i);
        let position: [f32; 3] = m.translation.into();
        let direction = m.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
        if direction == Vec3::ZERO && !matches!(light.kind(), Kind::Point) {
            return Err(GltfError::new(key, "is placed by a degenerate transform"));
        }
        self.out.lights.push(match light.kind() {
            Kind::Point => LightDesc::Point {
                position,
                intensity: power,
            },
            Kind::Directional => LightDesc::Directional {
                direction: direction.into(),
                irradiance: power,
            },
            Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => {
                if !(0.0 <= inner_cone_angle && inner_cone_angle < outer_cone_angle && outer_cone_angle <= std::f32::consts::FRAC_PI_2) {
                    return Err(GltfError::new(format!("{key}.spot"), format!("needs 0 <= innerConeAngle < outerConeAngle <= pi/2, got {inner_cone_angle} and {outer_cone_angle}")));
                }
                LightDesc::Spot {
                    position,
                    direction: Some(direction.into()),
                    look_at: None,
                    intensity: power,
                    inner_angle: inner_cone_angle.to_degrees(),
                    outer_angle: outer_cone_angle.to_degrees(),
                }
            }
        });
        Ok(())
    }
}

/// The uv sets a material's textures read (occlusion's apart: it is not used), in the
/// order base colour, metallic-roughness, emissive, specular colour, specular, normal.
fn uv_sets(m: &gltf::Material) -> Vec<u32> {
    let set = |info: gltf::texture::Info| {
        info.texture_transform()
            .and_then(|t| t.tex_coord())
            .unwrap_or(info.tex_coord())
    };
    let pbr = m.pbr_metallic_roughness();
    let mut sets: Vec<u32> = [
        pbr.base_color_texture(),
        pbr.metallic_roughness_texture(),
        m.emissive_texture(),
        m.specular().and_then(|s| s.specular_color_texture()),
        m.specular().and_then(|s| s.specular_texture()),
    ]
    .into_iter()
    .flatten()
    .map(set)
    .collect();
    if let Some(n) = m.normal_texture() {
        let ext = n
            .extension_value("KHR_texture_transform")
            .and_then(|e| e.get("texCoord"))
            .and_then(|c| c.as_u64());
        sets.push(ext.map_or(n.tex_coord(), |c| c as u32));
    }
    sets
}

/// Refuses a URI whose %-escapes do not decode to UTF-8 (the crate would panic on it).
fn check_uri(uri: &str, key: &str) -> Result<()> {
    if !uri.starts_with("data:") && urlencoding::decode(uri).is_err() {
        return Err(GltfError::new(
            key,
            format!("\"{uri}\" does not decode to UTF-8"),
        ));
    }
    Ok(())
}

/// A buffer or image source that could not be read, with the URI it names.
fn source_error(e: gltf::Error, source: &gltf::buffer::Source) -> String {
    match *source {
        gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
            format!("its data URI cannot be decoded: {e}")
        }
        gltf::buffer::Source::Uri(uri) => format!("\"{uri}\" cannot be read: {e}"),
        gltf::buffer::Source::Bin => format!("the GLB file has no binary chunk: {e}"),
    }
}
