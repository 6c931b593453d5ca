//! A glTF 2.0 file opened: its size, its GLB header, the crate's validation and the
//! extensions it requires, its buffers (each as long as it says, every view within its
//! buffer); then its scene read by the [`Loader`].

use std::collections::HashMap;
use std::path::Path;

use gltf::json::validation::Validate;

use super::error::{GltfError, Result};
use super::loader::Loader;
use super::meshopt;
use crate::scene::imported::ImportedScene;
use crate::scene::mesh::MAX_MESH_FILE_BYTES;

/// The extensions wgtrace reads; a file that requires another one is refused.
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "EXT_meshopt_compression",
    "KHR_lights_punctual",
    "KHR_materials_clearcoat",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_pbrSpecularGlossiness",
    "KHR_materials_sheen",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_mesh_quantization",
    "KHR_texture_transform",
];

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
        uv_sets: Vec::new(),
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

/// The document, checked by the crate's validation and for its required extensions, and
/// its buffers, each as long as it says and every buffer view within its buffer; with the
/// warnings about extensions it uses that wgtrace ignores.
pub(super) fn open(data: &[u8], dir: &Path) -> Result<(gltf::Document, Vec<Vec<u8>>, Vec<String>)> {
    check_glb_header(data)?;
    let gltf = gltf::Gltf::from_slice_without_validation(data)
        .map_err(|e| GltfError::new("", format!("is not glTF 2.0: {e}")))?;
    let mut warnings = Vec::new();
    let root = gltf.document.as_json();
    for (i, ext) in root.extensions_required.iter().enumerate() {
        if ext == "KHR_draco_mesh_compression" {
            return Err(GltfError::new(
                format!("extensionsRequired[{i}]"),
                "the file's meshes are Draco-compressed (KHR_draco_mesh_compression), \
                 which wgtrace does not decode (no maintained Rust decoder exists); \
                 decompress it first, e.g. with glTF-Transform, which decodes Draco on \
                 reading: `npx @gltf-transform/cli copy model.glb plain.glb` (its `meshopt` \
                 command instead writes EXT_meshopt_compression, which wgtrace reads), or \
                 re-export it from Blender without compression",
            ));
        }
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
        // a fallback buffer of EXT_meshopt_compression: its views are decoded into it
        if meshopt::is_fallback(&buffer) && !matches!(buffer.source(), gltf::buffer::Source::Uri(_))
        {
            buffers.push(meshopt::fallback_bytes(&buffer)?);
            continue;
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
    meshopt::decode_views(&doc, &mut buffers)?;
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

/// Refuses a URI whose %-escapes do not decode to UTF-8 (the crate would panic on it).
pub(super) fn check_uri(uri: &str, key: &str) -> Result<()> {
    if !uri.starts_with("data:") && urlencoding::decode(uri).is_err() {
        return Err(GltfError::new(
            key,
            format!("\"{uri}\" does not decode to UTF-8"),
        ));
    }
    Ok(())
}

/// A buffer or image source that could not be read, with the URI it names.
pub(super) fn source_error(e: gltf::Error, source: &gltf::buffer::Source) -> String {
    match *source {
        gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
            format!("its data URI cannot be decoded: {e}")
        }
        gltf::buffer::Source::Uri(uri) => format!("\"{uri}\" cannot be read: {e}"),
        gltf::buffer::Source::Bin => format!("the GLB file has no binary chunk: {e}"),
    }
}
