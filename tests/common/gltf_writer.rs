//! A small glTF 2.0 writer for tests and generated gallery assets: one binary buffer, JSON built
//! with `serde_json`, written as `.gltf` + `.bin`, as a `.gltf` with the buffer embedded as a
//! base64 data URI, or as a GLB. Everything is produced procedurally; nothing is validated beyond
//! what the helpers compute (POSITION min/max, buffer length, 4-byte alignment of buffer views).
//!
//! Conventions of the geometry helpers: counter-clockwise winding seen from the side the normal
//! points to (glTF front faces), Y up, and glTF texture coordinates: uv `(0, 0)` is the image's
//! top-left corner, `v` grows downwards.
#![allow(dead_code)]

use std::io::Cursor;
use std::path::{Path, PathBuf};

use base64::Engine as _;
use serde_json::{json, Value};

/// `componentType` of 32-bit floats.
pub const FLOAT: u32 = 5126;
/// `componentType` of unsigned 16-bit integers.
pub const UNSIGNED_SHORT: u32 = 5123;
/// `componentType` of unsigned 32-bit integers.
pub const UNSIGNED_INT: u32 = 5125;
/// Sampler filter `LINEAR`.
pub const LINEAR: u32 = 9729;
/// Sampler filter `LINEAR_MIPMAP_LINEAR`.
pub const LINEAR_MIPMAP_LINEAR: u32 = 9987;
/// Sampler wrap mode `REPEAT`.
pub const REPEAT: u32 = 10497;
/// bufferView `target` of vertex attributes.
pub const ARRAY_BUFFER: u32 = 34962;
/// bufferView `target` of indices.
pub const ELEMENT_ARRAY_BUFFER: u32 = 34963;

const KHR_LIGHTS: &str = "KHR_lights_punctual";

/// A glTF document under construction: the root JSON object (without `buffers`, which the
/// output functions add) and the bytes of buffer 0.
#[derive(Clone)]
pub struct GltfWriter {
    /// The root object; edit it freely (e.g. to add names or extensions).
    pub json: Value,
    /// The contents of buffer 0.
    pub bin: Vec<u8>,
    /// Buffers after buffer 0, as given (e.g. EXT_meshopt_compression's fallback).
    pub more_buffers: Vec<Value>,
}

impl Default for GltfWriter {
    fn default() -> Self {
        Self::new()
    }
}

impl GltfWriter {
    /// An empty document with `asset.version` "2.0" and generator "wgtrace tests".
    pub fn new() -> Self {
        GltfWriter {
            json: json!({ "asset": { "version": "2.0", "generator": "wgtrace tests" } }),
            bin: Vec::new(),
            more_buffers: Vec::new(),
        }
    }

    /// Appends `value` to the root array `key` (created if absent) and returns its index.
    pub fn push(&mut self, key: &str, value: Value) -> usize {
        push_to(&mut self.json, key, value)
    }

    /// Appends `bytes` to the buffer at a 4-byte aligned offset and a bufferView over them
    /// (with `byteStride` if given); returns the view's index.
    pub fn view(&mut self, bytes: &[u8], byte_stride: Option<usize>) -> usize {
        pad_to_4(&mut self.bin, 0);
        let mut v = json!({ "buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len() });
        if let Some(s) = byte_stride {
            v["byteStride"] = json!(s);
        }
        self.bin.extend_from_slice(bytes);
        self.push("bufferViews", v)
    }

    /// [`GltfWriter::view`] with `target` set (vertex or index data).
    fn view_for(&mut self, bytes: &[u8], target: u32) -> usize {
        let v = self.view(bytes, None);
        self.json["bufferViews"][v]["target"] = json!(target);
        v
    }

    /// A raw accessor over `view` (`ty` is "SCALAR", "VEC3", ...); returns its index.
    pub fn accessor(
        &mut self,
        view: usize,
        byte_offset: usize,
        component_type: u32,
        count: usize,
        ty: &str,
        min_max: Option<(Vec<f32>, Vec<f32>)>,
    ) -> usize {
        let mut a = json!({ "bufferView": view, "byteOffset": byte_offset,
            "componentType": component_type, "count": count, "type": ty });
        if let Some((min, max)) = min_max {
            a["min"] = json!(min);
            a["max"] = json!(max);
        }
        self.push("accessors", a)
    }

    fn floats<const N: usize>(&mut self, v: &[[f32; N]], ty: &str, min_max: bool) -> usize {
        let bytes: Vec<u8> = v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        let mm = (min_max && !v.is_empty()).then(|| {
            let (mut lo, mut hi) = (vec![f32::INFINITY; N], vec![f32::NEG_INFINITY; N]);
            for p in v {
                for k in 0..N {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            (lo, hi)
        });
        let view = self.view_for(&bytes, ARRAY_BUFFER);
        self.accessor(view, 0, FLOAT, v.len(), ty, mm)
    }

    /// A VEC3 float accessor with min/max (as the spec requires for POSITION).
    pub fn positions(&mut self, p: &[[f32; 3]]) -> usize {
        self.floats(p, "VEC3", true)
    }

    /// A VEC3 float accessor (normals, colours).
    pub fn vec3(&mut self, v: &[[f32; 3]]) -> usize {
        self.floats(v, "VEC3", false)
    }

    /// A VEC2 float accessor (texture coordinates).
    pub fn vec2(&mut self, v: &[[f32; 2]]) -> usize {
        self.floats(v, "VEC2", false)
    }

    /// A VEC4 float accessor (tangents, colours).
    pub fn vec4(&mut self, v: &[[f32; 4]]) -> usize {
        self.floats(v, "VEC4", false)
    }

    /// A SCALAR unsigned-int index accessor.
    pub fn indices_u32(&mut self, i: &[u32]) -> usize {
        let bytes: Vec<u8> = i.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view_for(&bytes, ELEMENT_ARRAY_BUFFER);
        self.accessor(view, 0, UNSIGNED_INT, i.len(), "SCALAR", None)
    }

    /// A SCALAR unsigned-short index accessor.
    pub fn indices_u16(&mut self, i: &[u16]) -> usize {
        let bytes: Vec<u8> = i.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view_for(&bytes, ELEMENT_ARRAY_BUFFER);
        self.accessor(view, 0, UNSIGNED_SHORT, i.len(), "SCALAR", None)
    }

    /// A triangle-list primitive (`mode` 4) with `attributes` (semantic, accessor index).
    pub fn primitive(
        attributes: &[(&str, usize)],
        indices: Option<usize>,
        material: Option<usize>,
    ) -> Value {
        let attrs: serde_json::Map<String, Value> = attributes
            .iter()
            .map(|(k, a)| (k.to_string(), json!(a)))
            .collect();
        let mut p = json!({ "attributes": attrs, "mode": 4 });
        if let Some(i) = indices {
            p["indices"] = json!(i);
        }
        if let Some(m) = material {
            p["material"] = json!(m);
        }
        p
    }

    /// A mesh of `primitives`; returns its index.
    pub fn mesh(&mut self, primitives: Vec<Value>) -> usize {
        self.push("meshes", json!({ "primitives": primitives }))
    }

    /// Adds a material object as given; returns its index.
    pub fn material(&mut self, m: Value) -> usize {
        self.push("materials", m)
    }

    /// Adds a node object as given; returns its index.
    pub fn node(&mut self, n: Value) -> usize {
        self.push("nodes", n)
    }

    /// Adds a camera object as given; returns its index.
    pub fn camera(&mut self, c: Value) -> usize {
        self.push("cameras", c)
    }

    /// Adds a scene with root `nodes`; the first scene added becomes the default (`scene`).
    pub fn scene(&mut self, nodes: &[usize]) -> usize {
        let s = self.push("scenes", json!({ "nodes": nodes }));
        if self.json.get("scene").is_none() {
            self.json["scene"] = json!(0);
        }
        s
    }

    /// Adds a KHR_lights_punctual light (and the extension to `extensionsUsed`); returns its
    /// index. A node uses it with [`light_ref`].
    pub fn light(&mut self, l: Value) -> usize {
        self.use_extension(KHR_LIGHTS, false);
        let ext = &mut self.json["extensions"][KHR_LIGHTS];
        push_to(ext, "lights", l)
    }

    /// Lists `name` in `extensionsUsed` (and in `extensionsRequired` if `required`), once.
    pub fn use_extension(&mut self, name: &str, required: bool) {
        let keys: &[&str] = if required {
            &["extensionsUsed", "extensionsRequired"]
        } else {
            &["extensionsUsed"]
        };
        for key in keys {
            let listed = self.json[*key]
                .as_array()
                .is_some_and(|a| a.contains(&json!(name)));
            if !listed {
                self.push(key, json!(name));
            }
        }
    }

    /// A texture over `source`, with `sampler` (reused if an identical one exists).
    fn texture(&mut self, source: usize, sampler: Option<Value>) -> usize {
        let mut t = json!({ "source": source });
        if let Some(s) = sampler {
            let existing = self.json["samplers"]
                .as_array()
                .and_then(|a| a.iter().position(|x| *x == s));
            t["sampler"] = json!(existing.unwrap_or_else(|| self.push("samplers", s)));
        }
        self.push("textures", t)
    }

    /// Encodes `img` as PNG into a buffer view and adds an image (`image/png`) and a texture
    /// (with `sampler`, see [`sampler`]); returns the texture's index. Fails only where the PNG
    /// encoder does (e.g. an empty image).
    pub fn png_texture(
        &mut self,
        img: &image::RgbaImage,
        sampler: Option<Value>,
    ) -> image::ImageResult<usize> {
        let mut png = Vec::new();
        img.write_to(&mut Cursor::new(&mut png), image::ImageFormat::Png)?;
        let view = self.view(&png, None);
        let source = self.push(
            "images",
            json!({ "bufferView": view, "mimeType": "image/png" }),
        );
        Ok(self.texture(source, sampler))
    }

    /// Adds an image referring to the external file `uri` (which the caller writes; `uri` is
    /// used as given, so percent-encode it) and a texture over it; returns the texture's index.
    pub fn png_texture_uri(&mut self, uri: &str, sampler: Option<Value>) -> usize {
        let source = self.push("images", json!({ "uri": uri }));
        self.texture(source, sampler)
    }

    /// The root object with `buffers` set: buffer 0 of the buffer's real length, with `uri` if
    /// given (none for GLB); no buffer at all while the buffer is empty.
    fn root(&self, buffer_uri: Option<&str>) -> Value {
        let mut root = self.json.clone();
        if !self.bin.is_empty() {
            let mut b = json!({ "byteLength": self.bin.len() });
            if let Some(uri) = buffer_uri {
                b["uri"] = json!(uri);
            }
            let mut all = vec![b];
            all.extend(self.more_buffers.iter().cloned());
            root["buffers"] = json!(all);
        }
        root
    }

    /// The document as pretty-printed glTF JSON, buffer 0 with `uri` if given.
    pub fn gltf_json_string(&self, buffer_uri: Option<&str>) -> String {
        serde_json::to_string_pretty(&self.root(buffer_uri)).expect("a JSON value serializes")
    }

    /// Writes `dir/stem.gltf` and `dir/stem.bin` (buffer uri "stem.bin", percent-encoded);
    /// returns the path of the `.gltf`.
    pub fn to_gltf_external(&self, dir: &Path, stem: &str) -> std::io::Result<PathBuf> {
        let bin_name = format!("{stem}.bin");
        std::fs::write(dir.join(&bin_name), &self.bin)?;
        let path = dir.join(format!("{stem}.gltf"));
        std::fs::write(
            &path,
            self.gltf_json_string(Some(&percent_encode(&bin_name))),
        )?;
        Ok(path)
    }

    /// Writes a single `.gltf` with the buffer as a base64 `data:` URI.
    pub fn to_gltf_embedded(&self, path: &Path) -> std::io::Result<()> {
        let b64 = base64::engine::general_purpose::STANDARD.encode(&self.bin);
        let uri = format!("data:application/octet-stream;base64,{b64}");
        std::fs::write(path, self.gltf_json_string(Some(&uri)))
    }

    /// The document as GLB bytes: 12-byte header ("glTF", version 2, total length), a JSON
    /// chunk padded with spaces and, if the buffer is not empty, a BIN chunk padded with zeros.
    pub fn glb_bytes(&self) -> Vec<u8> {
        let mut js = serde_json::to_vec(&self.root(None)).expect("a JSON value serializes");
        pad_to_4(&mut js, b' ');
        let mut bin = self.bin.clone();
        pad_to_4(&mut bin, 0);
        let mut chunks = vec![(0x4E4F_534Au32, js)];
        if !bin.is_empty() {
            chunks.push((0x004E_4942, bin));
        }
        let total = 12 + chunks.iter().map(|(_, c)| 8 + c.len()).sum::<usize>();
        let mut out = Vec::with_capacity(total);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        for (ty, c) in chunks {
            out.extend_from_slice(&(c.len() as u32).to_le_bytes());
            out.extend_from_slice(&ty.to_le_bytes());
            out.extend_from_slice(&c);
        }
        out
    }

    /// Writes the document as a GLB file.
    pub fn to_glb(&self, path: &Path) -> std::io::Result<()> {
        std::fs::write(path, self.glb_bytes())
    }

    /// The primitive of `m` (POSITION, NORMAL if any, TEXCOORD_0 if `with_uvs` and any, u32
    /// indices if any), its accessors added; add e.g. TANGENT to it before [`GltfWriter::mesh`].
    pub fn primitive_from_arrays(
        &mut self,
        m: &MeshArrays,
        material: Option<usize>,
        with_uvs: bool,
    ) -> Value {
        let mut attrs = vec![("POSITION", self.positions(&m.positions))];
        if !m.normals.is_empty() {
            attrs.push(("NORMAL", self.vec3(&m.normals)));
        }
        if with_uvs && !m.uvs.is_empty() {
            attrs.push(("TEXCOORD_0", self.vec2(&m.uvs)));
        }
        let indices = (!m.indices.is_empty()).then(|| self.indices_u32(&m.indices));
        Self::primitive(&attrs, indices, material)
    }

    /// A mesh of the one primitive [`GltfWriter::primitive_from_arrays`] makes; returns its index.
    pub fn add_mesh_arrays(
        &mut self,
        m: &MeshArrays,
        material: Option<usize>,
        with_uvs: bool,
    ) -> usize {
        let p = self.primitive_from_arrays(m, material, with_uvs);
        self.mesh(vec![p])
    }
}

/// `{ "extensions": { "KHR_lights_punctual": { "light": light } } }`, to merge into a node.
pub fn light_ref(light: usize) -> Value {
    json!({ "extensions": { KHR_LIGHTS: { "light": light } } })
}

/// A sampler object: linear filtering (mipmapped minification) and repeat wrapping.
pub fn sampler() -> Value {
    json!({ "magFilter": LINEAR, "minFilter": LINEAR_MIPMAP_LINEAR, "wrapS": REPEAT, "wrapT": REPEAT })
}

fn push_to(obj: &mut Value, key: &str, value: Value) -> usize {
    if !obj[key].is_array() {
        obj[key] = json!([]);
    }
    let a = obj[key].as_array_mut().expect("just made an array");
    a.push(value);
    a.len() - 1
}

fn pad_to_4(v: &mut Vec<u8>, byte: u8) {
    while !v.len().is_multiple_of(4) {
        v.push(byte);
    }
}

/// Percent-encodes everything but RFC 3986's unreserved characters.
fn percent_encode(s: &str) -> String {
    s.bytes()
        .map(|b| match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'.' | b'_' | b'~' => {
                (b as char).to_string()
            }
            _ => format!("%{b:02X}"),
        })
        .collect()
}

/// Indexed triangle-mesh arrays, one normal and uv per position.
#[derive(Clone, Debug, Default)]
pub struct MeshArrays {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals.
    pub normals: Vec<[f32; 3]>,
    /// Texture coordinates (glTF convention: v = 0 at the image's top).
    pub uvs: Vec<[f32; 2]>,
    /// Triangle list, counter-clockwise seen from the front.
    pub indices: Vec<u32>,
}

impl MeshArrays {
    /// Appends `other`, offsetting its indices.
    pub fn append(&mut self, other: &MeshArrays) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.uvs.extend_from_slice(&other.uvs);
        self.indices.extend(other.indices.iter().map(|i| i + base));
    }
}

/// A latitude/longitude sphere: `stacks` rings from the north pole (+Y, v = 0) to the south
/// pole (v = 1) and `slices` segments around (at least 2 and 3), seam vertices duplicated so
/// uvs do not wrap. `u = j / slices` grows to the right seen from outside (not mirrored): the
/// point at (u, v) is `center + radius * (-sin(pi v) cos(2 pi u), cos(pi v), sin(pi v) sin(2 pi u))`,
/// so the seam is at -X, u = 0.25 faces +Z, and dP/du points along `(sin 2 pi u, 0, cos 2 pi u)`.
/// The degenerate half of each pole quad is left out: `2 * slices * (stacks - 1)` triangles.
pub fn uv_sphere(center: [f32; 3], radius: f32, stacks: u32, slices: u32) -> MeshArrays {
    let (stacks, slices) = (stacks.max(2), slices.max(3));
    let mut m = MeshArrays::default();
    for i in 0..=stacks {
        let v = i as f32 / stacks as f32;
        let (st, ct) = (std::f32::consts::PI * v).sin_cos();
        for j in 0..=slices {
            let u = j as f32 / slices as f32;
            let (sp, cp) = (std::f32::consts::TAU * u).sin_cos();
            let n = [-st * cp, ct, st * sp];
            m.positions
                .push([0, 1, 2].map(|k| center[k] + radius * n[k]));
            m.normals.push(n);
            m.uvs.push([u, v]);
        }
    }
    let row = slices + 1;
    for i in 0..stacks {
        for j in 0..slices {
            let (a, b) = (i * row + j, (i + 1) * row + j);
            let (c, d) = (b + 1, a + 1);
            // a and d are the north pole on the first ring, b and c the south pole on the last
            if i != stacks - 1 {
                m.indices.extend([a, b, c]);
            }
            if i != 0 {
                m.indices.extend([a, c, d]);
            }
        }
    }
    m
}

/// The parallelogram `center ± half_u ± half_v`, facing `half_u x half_v`, uv (0, 0) at
/// `center - half_u + half_v` (top-left: `half_v` points up in the image).
pub fn quad(center: [f32; 3], half_u: [f32; 3], half_v: [f32; 3]) -> MeshArrays {
    let n = normalize(cross(half_u, half_v));
    let corner = |su: f32, sv: f32| [0, 1, 2].map(|k| center[k] + su * half_u[k] + sv * half_v[k]);
    MeshArrays {
        positions: vec![
            corner(-1.0, 1.0),
            corner(-1.0, -1.0),
            corner(1.0, -1.0),
            corner(1.0, 1.0),
        ],
        normals: vec![n; 4],
        uvs: vec![[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]],
        indices: vec![0, 1, 2, 0, 2, 3],
    }
}

/// An axis-aligned box of six outward-facing quads (24 vertices), each face's uv covering the
/// whole image.
pub fn cuboid(center: [f32; 3], half: [f32; 3]) -> MeshArrays {
    let [x, y, z] = half;
    // (outward axis, half_u, half_v) so that half_u x half_v points outward
    let faces = [
        ([x, 0.0, 0.0], [0.0, 0.0, -z], [0.0, y, 0.0]),
        ([-x, 0.0, 0.0], [0.0, 0.0, z], [0.0, y, 0.0]),
        ([0.0, y, 0.0], [x, 0.0, 0.0], [0.0, 0.0, -z]),
        ([0.0, -y, 0.0], [x, 0.0, 0.0], [0.0, 0.0, z]),
        ([0.0, 0.0, z], [x, 0.0, 0.0], [0.0, y, 0.0]),
        ([0.0, 0.0, -z], [-x, 0.0, 0.0], [0.0, y, 0.0]),
    ];
    let mut m = MeshArrays::default();
    for (off, hu, hv) in faces {
        m.append(&quad([0, 1, 2].map(|k| center[k] + off[k]), hu, hv));
    }
    m
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn normalize(a: [f32; 3]) -> [f32; 3] {
    let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    if l > 0.0 {
        a.map(|c| c / l)
    } else {
        [0.0, 0.0, 1.0]
    }
}
