//! Triangle meshes from Wavefront OBJ files, read with `tobj`, and from PLY files (ASCII
//! and binary), read with `ply-rs-bw`.

use std::path::Path;

use super::format::{ColorSpace, MESH_ATTRIBUTES};
use super::texels::srgb_to_linear;
use glam::{DVec2, DVec3, DVec4, Vec2, Vec3, Vec4};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{Property, PropertyAccess, PropertyAccessResult};

/// A triangle mesh with one index per corner; `normals` and `uvs` are empty when the file
/// has none (for any of its objects), else one per position.
#[derive(Debug, Clone, Default)]
pub struct MeshData {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub triangles: Vec<[u32; 3]>,
    /// Each triangle's corner tangents (xyz) and bitangent signs (w), for normal maps:
    /// empty, or one per triangle.
    pub tangents: Vec<[Vec4; 3]>,
    /// A second uv set per vertex (glTF's), for textures that read it: empty, or one per
    /// position.
    pub uvs1: Vec<Vec2>,
    /// Vertex colours (linear rgb, alpha) per vertex: empty, or one per position.
    pub colors: Vec<Vec4>,
    /// A colour per triangle (a PLY file's face colours): empty, or one per triangle.
    /// `adjust` gives each triangle corners of its own of that colour, once the vertex
    /// normals are made over the shared corners.
    pub face_colors: Vec<Vec4>,
}

/// Largest OBJ file read (2 GiB): the whole file is parsed in memory.
pub const MAX_MESH_FILE_BYTES: u64 = 1 << 31;

/// Most triangles of all a scene's meshes together (2^24, about 1.7 GB of records).
pub const MAX_TRIANGLES: usize = 1 << 24;

/// Reads a mesh file: PLY for a `.ply` name (any case), else OBJ. Files over
/// [`MAX_MESH_FILE_BYTES`] and meshes over [`MAX_TRIANGLES`] are refused; so are faces
/// that index no vertex and coordinates that are not finite.
pub fn load_mesh(path: &Path, colors: ColorChoice) -> Result<MeshData, String> {
    let bytes = std::fs::metadata(path).map_err(|e| e.to_string())?.len();
    if bytes > MAX_MESH_FILE_BYTES {
        return Err(format!(
            "is {bytes} bytes, more than the {MAX_MESH_FILE_BYTES} read for a mesh"
        ));
    }
    let mesh = if is_ply(path) {
        load_ply(path, colors)?
    } else {
        load_obj(path, colors.space)?
    };
    check(mesh)
}

/// Whether `path` names a Mitsuba `.serialized` mesh file (any case).
pub fn is_serialized(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("serialized"))
}

/// The mesh a scene asks for: mesh `shape_index` of a `.serialized` file, else the whole
/// OBJ or PLY file.
pub fn load_mesh_at(
    path: &Path,
    shape_index: u32,
    colors: ColorChoice,
) -> Result<MeshData, String> {
    if is_serialized(path) {
        let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
        return check(read_serialized(&bytes, shape_index)?);
    }
    if shape_index != 0 {
        return Err("`shape_index` applies to .serialized files only".into());
    }
    load_mesh(path, colors)
}

/// How a mesh object's shading normals and front side are asked for.
#[derive(Debug, Clone, Copy, Default)]
pub struct Adjust {
    /// Flat shading: the vertex normals left out (Mitsuba's `face_normals`).
    pub face_normals: bool,
    /// Smooth normals computed where the file has none (Mitsuba's default).
    pub smooth_normals: bool,
    /// The front side turned to the back: windings swapped, normals negated (Mitsuba's
    /// `flip_normals`).
    pub flip_normals: bool,
    /// The file's uvs read with v down: v' = 1 - v (how Mitsuba reads a PLY file, in
    /// wgtrace's v up; a `.serialized` file's uvs are so read already).
    pub flip_tex_coords: bool,
    /// The triangles' default uvs taken with v down too ((0, 1), (1, 1), (0, 0) over the
    /// corners: Mitsuba's barycentric uvs of a PLY or `.serialized` file without uvs).
    pub default_uvs_v_down: bool,
    /// A mesh without uvs whose material reads them gets its triangles' default uvs as
    /// corners of their own where `default_uvs_v_down` or `flip_normals` would otherwise
    /// change them: they stay as the file's winding gives them.
    pub corner_uvs: bool,
    /// The object's own placement mirrors and the file's front is its placed winding's
    /// where the mesh ends up without the file's vertex normals (Mitsuba's, whose face and
    /// smooth normals are those of the placed triangles): the front turned, as
    /// `flip_normals` turns it, to undo the flattener's mirror image of the file's front.
    pub winding_front: bool,
}

/// A mesh's normals and windings as `a` asks.
pub fn adjust(mesh: &mut MeshData, a: Adjust) {
    let face_normals = a.face_normals;
    let flip_normals =
        a.flip_normals ^ (a.winding_front && (face_normals || mesh.normals.is_empty()));
    if face_normals {
        mesh.normals.clear();
        mesh.tangents.clear();
    } else if a.smooth_normals && mesh.normals.is_empty() {
        mesh.normals = angle_weighted_normals(&mesh.positions, &mesh.triangles);
    }
    // uvs after the smooth normals (corners of their own would flatten those) and before
    // the windings turn (the default uvs follow the file's winding)
    if !mesh.uvs.is_empty() {
        if a.flip_tex_coords {
            for uv in &mut mesh.uvs {
                uv.y = 1.0 - uv.y;
            }
        }
    } else if a.corner_uvs && (a.default_uvs_v_down || flip_normals) {
        let v = |v: f32| if a.default_uvs_v_down { 1.0 - v } else { v };
        let corners = [
            Vec2::new(0.0, v(0.0)),
            Vec2::new(1.0, v(0.0)),
            Vec2::new(0.0, v(1.0)),
        ];
        *mesh = unwelded(mesh);
        mesh.uvs = (0..mesh.triangles.len()).flat_map(|_| corners).collect();
    }
    if flip_normals {
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
        for n in &mut mesh.normals {
            *n = -*n;
        }
        for t in &mut mesh.tangents {
            t.swap(1, 2);
        }
    }
    // face colours: each triangle gets corners of its own, of its face's colour, so that
    // the colour is constant over it as the renderer interpolates corners
    if !mesh.face_colors.is_empty() {
        let colors = std::mem::take(&mut mesh.face_colors);
        *mesh = unwelded(mesh);
        mesh.colors = colors.iter().flat_map(|&c| [c; 3]).collect();
    }
}

/// Vertex normals as the mean of the unit normals of the faces around each vertex,
/// weighted by each face's angle at the vertex (Thürmer and Wüthrich 1998, as Mitsuba
/// computes them); a vertex whose faces cancel keeps the first face's normal.
pub fn angle_weighted_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut sums = vec![Vec3::ZERO; positions.len()];
    let mut first = vec![Vec3::ZERO; positions.len()];
    for t in triangles {
        let p = t.map(|i| positions[i as usize]);
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        let Some(n) = n.try_normalize() else {
            continue;
        };
        for k in 0..3 {
            let (a, b) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            let angle = a.angle_between(b);
            let i = t[k] as usize;
            sums[i] += n * angle;
            if first[i] == Vec3::ZERO {
                first[i] = n;
            }
        }
    }
    sums.iter()
        .zip(&first)
        .map(|(s, f)| s.try_normalize().unwrap_or(*f))
        .collect()
}

/// Mesh `index` of a Mitsuba `.serialized` file: a little-endian header (0x041C and the
/// version, 3 or 4), then each mesh as its own zlib stream (flags; version 4's name;
/// vertex and triangle counts as u64; positions, then normals, uvs and colours as the
/// flags say, in f32 or f64; u32 indices, u64 past 2^32 vertices), and at the end each
/// mesh's offset (u64 in version 4, u32 in 3) and the mesh count (u32). Uvs are stored
/// with v down, as Mitsuba renders them: they are read as 1 - v.
pub fn read_serialized(bytes: &[u8], index: u32) -> Result<MeshData, String> {
    use std::io::Read;
    const HAS_NORMALS: u32 = 0x0001;
    const HAS_UVS: u32 = 0x0002;
    const HAS_COLORS: u32 = 0x0008;
    const FACE_NORMALS: u32 = 0x0010;
    const SINGLE: u32 = 0x1000;
    const DOUBLE: u32 = 0x2000;
    let u16_at = |o: usize| {
        bytes
            .get(o..o + 2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
    };
    let u32_at = |o: usize| {
        bytes
            .get(o..o + 4)
            .map(|b| u32::from_le_bytes(b.try_into().unwrap()))
    };
    let u64_at = |o: usize| {
        bytes
            .get(o..o + 8)
            .map(|b| u64::from_le_bytes(b.try_into().unwrap()))
    };
    if u16_at(0) != Some(0x041C) {
        return Err(
            "is not a Mitsuba .serialized file (its first two bytes are not 0x041C)".into(),
        );
    }
    let version = u16_at(2).unwrap_or(0);
    if version != 3 && version != 4 {
        return Err(format!(
            "is .serialized version {version}; versions 3 and 4 are read"
        ));
    }
    let cut = || "is cut short".to_string();
    let count = u32_at(bytes.len().saturating_sub(4)).ok_or_else(cut)?;
    if index >= count {
        return Err(format!(
            "has {count} meshes; shape_index {index} is past them"
        ));
    }
    let table = bytes.len() - 4;
    let offset = if version == 4 {
        u64_at(table - 8 * (count - index) as usize).ok_or_else(cut)?
    } else {
        u64::from(u32_at(table - 4 * (count - index) as usize).ok_or_else(cut)?)
    };
    let start = usize::try_from(offset).map_err(|_| cut())?;
    if u16_at(start) != Some(0x041C) {
        return Err(format!(
            "mesh {index}: its offset {start} holds no mesh header"
        ));
    }
    let stream = bytes.get(start + 4..).ok_or_else(cut)?;
    let mut z = flate2::read::ZlibDecoder::new(stream);
    let mut read = |n: usize| -> Result<Vec<u8>, String> {
        let mut buf = vec![0; n];
        z.read_exact(&mut buf)
            .map_err(|e| format!("mesh {index}: cannot be decompressed: {e}"))?;
        Ok(buf)
    };
    let flags = u32::from_le_bytes(read(4)?.try_into().unwrap());
    if version == 4 {
        // the shape's name, up to a NUL
        while read(1)?[0] != 0 {}
    }
    let vertices = u64::from_le_bytes(read(8)?.try_into().unwrap());
    let triangles = u64::from_le_bytes(read(8)?.try_into().unwrap());
    if triangles > MAX_TRIANGLES as u64 || vertices > 3 * MAX_TRIANGLES as u64 {
        return Err(format!(
            "mesh {index} has {triangles} triangles and {vertices} vertices, more than a scene may hold"
        ));
    }
    let (n, t) = (vertices as usize, triangles as usize);
    let double = match flags & (SINGLE | DOUBLE) {
        SINGLE => false,
        DOUBLE => true,
        _ => return Err(format!("mesh {index}: flags {flags:#x} give no precision")),
    };
    let mut floats = |k: usize| -> Result<Vec<f32>, String> {
        Ok(if double {
            read(8 * k)?
                .chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().unwrap()) as f32)
                .collect()
        } else {
            read(4 * k)?
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
                .collect()
        })
    };
    let positions: Vec<Vec3> = floats(3 * n)?
        .chunks_exact(3)
        .map(Vec3::from_slice)
        .collect();
    let mut normals: Vec<Vec3> = if flags & HAS_NORMALS != 0 {
        floats(3 * n)?
            .chunks_exact(3)
            .map(Vec3::from_slice)
            .collect()
    } else {
        Vec::new()
    };
    let uvs: Vec<Vec2> = if flags & HAS_UVS != 0 {
        floats(2 * n)?
            .chunks_exact(2)
            .map(|c| Vec2::new(c[0], 1.0 - c[1]))
            .collect()
    } else {
        Vec::new()
    };
    let colors: Vec<Vec4> = if flags & HAS_COLORS != 0 {
        floats(3 * n)?
            .chunks_exact(3)
            .map(|c| Vec4::new(c[0], c[1], c[2], 1.0))
            .collect()
    } else {
        Vec::new()
    };
    let wide = vertices > u64::from(u32::MAX);
    let indices: Vec<u32> = if wide {
        read(8 * 3 * t)?
            .chunks_exact(8)
            .map(|c| u64::from_le_bytes(c.try_into().unwrap()).min(u64::from(u32::MAX)) as u32)
            .collect()
    } else {
        read(4 * 3 * t)?
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect()
    };
    if flags & FACE_NORMALS != 0 {
        normals.clear();
    }
    Ok(MeshData {
        positions,
        normals,
        uvs,
        triangles: indices
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect(),
        colors,
        ..Default::default()
    })
}

/// One mesh for [`write_serialized`]: positions, triangles, uvs (v as stored; may be empty).
pub type SerializedMesh = (Vec<[f32; 3]>, Vec<[u32; 3]>, Vec<[f32; 2]>);

/// A `.serialized` file of `meshes` in version 4, single precision: what tests write.
pub fn write_serialized(meshes: &[SerializedMesh]) -> Vec<u8> {
    use std::io::Write;
    let mut out = Vec::new();
    let mut offsets = Vec::new();
    for (positions, triangles, uvs) in meshes {
        offsets.push(out.len() as u64);
        let mut raw = Vec::new();
        let flags = 0x1000u32 | if uvs.is_empty() { 0 } else { 0x0002 };
        raw.extend_from_slice(&flags.to_le_bytes());
        raw.extend_from_slice(b"mesh\0");
        raw.extend_from_slice(&(positions.len() as u64).to_le_bytes());
        raw.extend_from_slice(&(triangles.len() as u64).to_le_bytes());
        for x in positions.iter().flatten().chain(uvs.iter().flatten()) {
            raw.extend_from_slice(&x.to_le_bytes());
        }
        for i in triangles.iter().flatten() {
            raw.extend_from_slice(&i.to_le_bytes());
        }
        // each mesh starts with the header
        out.extend_from_slice(&0x041Cu16.to_le_bytes());
        out.extend_from_slice(&4u16.to_le_bytes());
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(&raw).expect("writing to memory");
        out.extend_from_slice(&z.finish().expect("writing to memory"));
    }
    for o in &offsets {
        out.extend_from_slice(&o.to_le_bytes());
    }
    out.extend_from_slice(&(meshes.len() as u32).to_le_bytes());
    out
}

/// An OBJ file's models and its .mtl's materials (or why they could not be read).
pub type ObjFile = (
    Vec<tobj::Model>,
    Result<Vec<tobj::Material>, tobj::LoadError>,
);

/// An OBJ file and its .mtl through tobj. The .mtl is read here and its colour
/// statements (`Ka`, `Kd`, `Ks`, `Ke`, `Tf`) written out to three numbers first: the
/// format allows one (g = b = r), and tobj panics on fewer than three.
pub fn read_obj(path: &Path, options: &tobj::LoadOptions) -> Result<ObjFile, String> {
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut reader = std::io::BufReader::new(file);
    let result = tobj::load_obj_buf(&mut reader, options, |mtl| {
        let text = std::fs::read(dir.join(mtl)).map_err(|_| tobj::LoadError::OpenFileFailed)?;
        let text = String::from_utf8_lossy(&text);
        let mut fixed = String::with_capacity(text.len());
        for line in text.lines() {
            let mut words = line.split_whitespace();
            let colour = matches!(words.next(), Some("Ka" | "Kd" | "Ks" | "Ke" | "Tf"));
            let values: Vec<&str> = words.collect();
            match values.len() {
                0 if colour => return Err(tobj::LoadError::MaterialParseError),
                1 | 2 if colour => {
                    let key = line.split_whitespace().next().unwrap_or("");
                    let v = values[0];
                    fixed.push_str(&format!("{key} {v} {v} {v}\n"));
                }
                _ => {
                    fixed.push_str(line);
                    fixed.push('\n');
                }
            }
        }
        tobj::load_mtl_buf(&mut fixed.as_bytes())
    });
    result.map_err(|e| e.to_string())
}

/// Whether `path` names a PLY file (`.ply`, any case).
pub fn is_ply(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ply"))
}

/// A vertex colour of an OBJ or PLY file as the renderer's: by default such colours are
/// display colours (as MeshLab and Blender write them), so rgb is decoded from sRGB;
/// `ColorSpace::Linear` takes them as they are (Mitsuba's reading). Alpha is linear.
pub fn file_color(c: [f64; 4], space: ColorSpace) -> Vec4 {
    let lin = |x: f64| match space {
        ColorSpace::Srgb => srgb_to_linear(x as f32),
        ColorSpace::Linear => x as f32,
    };
    Vec4::new(lin(c[0]), lin(c[1]), lin(c[2]), c[3] as f32)
}

/// The vertex colours of an OBJ model (tobj's, rgb per vertex) as the renderer's
/// ([`file_color`]); none when the model has none.
pub fn obj_colors(m: &tobj::Mesh, space: ColorSpace) -> Vec<Vec4> {
    m.vertex_color
        .chunks_exact(3)
        .map(|c| file_color([c[0].into(), c[1].into(), c[2].into(), 1.0], space))
        .collect()
}

/// Which of a mesh file's colours the mesh keeps, and how it reads them.
#[derive(Clone, Copy, Debug, Default)]
pub struct ColorChoice<'a> {
    /// How the colours become linear ones (`color_space`).
    pub space: ColorSpace,
    /// The mesh attribute its material reads, if any: `face_color` keeps a PLY file's face
    /// colours even where it has vertex colours; a named one (`vertex_NAME`, `face_NAME`)
    /// becomes the mesh's colours in their place.
    pub attribute: Option<&'a str>,
}

/// Every object of an OBJ file as one mesh (polygons are triangulated).
fn load_obj(path: &Path, colors: ColorSpace) -> Result<MeshData, String> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) = read_obj(path, &options)?;
    let with_normals = models.iter().all(|m| !m.mesh.normals.is_empty());
    let with_uvs = models.iter().all(|m| !m.mesh.texcoords.is_empty());
    let with_colors = models.iter().all(|m| !m.mesh.vertex_color.is_empty());
    let mut mesh = MeshData::default();
    for model in &models {
        let m = &model.mesh;
        let base = mesh.positions.len() as u32;
        mesh.positions
            .extend(m.positions.chunks_exact(3).map(Vec3::from_slice));
        if with_normals {
            mesh.normals
                .extend(m.normals.chunks_exact(3).map(Vec3::from_slice));
        }
        if with_uvs {
            mesh.uvs
                .extend(m.texcoords.chunks_exact(2).map(Vec2::from_slice));
        }
        if with_colors {
            mesh.colors.extend(obj_colors(m, colors));
        }
        mesh.triangles.extend(
            m.indices
                .chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
    }
    Ok(mesh)
}

/// A PLY `vertex` element: position, and the normal and texture coordinates when the file
/// declares them (any scalar type), and the colour (`red`, `green`, `blue`, `alpha`:
/// integers scaled to [0, 1] by their type's largest value, floats as they are).
struct PlyVertex {
    p: [f64; 3],
    n: [f64; 3],
    uv: [f64; 2],
    c: [f64; 4],
}

impl Default for PlyVertex {
    fn default() -> Self {
        PlyVertex {
            p: [0.0; 3],
            n: [0.0; 3],
            uv: [0.0; 2],
            c: [1.0; 4],
        }
    }
}

impl PropertyAccess for PlyVertex {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        if let Some(result) = ply_color(name, &property, &mut self.c) {
            return result;
        }
        let Some(value) = ply_scalar(&property) else {
            return PropertyAccessResult::Ignored;
        };
        let slot = match name {
            "x" => &mut self.p[0],
            "y" => &mut self.p[1],
            "z" => &mut self.p[2],
            "nx" => &mut self.n[0],
            "ny" => &mut self.n[1],
            "nz" => &mut self.n[2],
            _ => match PLY_UV.iter().position(|names| names.contains(&name)) {
                Some(k) => &mut self.uv[k],
                None => return PropertyAccessResult::Ignored,
            },
        };
        *slot = value;
        PropertyAccessResult::Set
    }
}

/// A colour property (`red`, `green`, `blue`, `alpha`) of a PLY vertex or face into `c`
/// (`ply_unit`'s scaling); None for any other property.
fn ply_color(name: &str, property: &Property, c: &mut [f64; 4]) -> Option<PropertyAccessResult> {
    let k = ["red", "green", "blue", "alpha"]
        .iter()
        .position(|&n| n == name)
        .or_else(|| ["r", "g", "b", "a"].iter().position(|&n| n == name))?;
    Some(match ply_unit(property) {
        Some(v) => {
            c[k] = v;
            PropertyAccessResult::Set
        }
        None => PropertyAccessResult::Ignored,
    })
}

/// The names PLY writers give the texture coordinates u and v.
const PLY_UV: [[&str; 4]; 2] = [
    ["u", "s", "texture_u", "texture_s"],
    ["v", "t", "texture_v", "texture_t"],
];

/// A PLY `face` element: its vertex indices (`vertex_indices` or `vertex_index`, a list of
/// any integer type), and its colour (`red`, `green`, `blue`, `alpha`, as a vertex's).
struct PlyFace {
    indices: Vec<i64>,
    c: [f64; 4],
}

impl Default for PlyFace {
    fn default() -> Self {
        PlyFace {
            indices: Vec::new(),
            c: [1.0; 4],
        }
    }
}

impl PropertyAccess for PlyFace {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        if let Some(result) = ply_color(name, &property, &mut self.c) {
            return result;
        }
        if name != "vertex_indices" && name != "vertex_index" {
            return PropertyAccessResult::Ignored;
        }
        let list: Vec<i64> = match property {
            Property::ListChar(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUChar(v) => v.into_iter().map(i64::from).collect(),
            Property::ListShort(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUShort(v) => v.into_iter().map(i64::from).collect(),
            Property::ListInt(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUInt(v) => v.into_iter().map(i64::from).collect(),
            _ => return PropertyAccessResult::UnsupportedType,
        };
        self.indices = list;
        PropertyAccessResult::Set
    }
}

/// Any other PLY element, read past.
struct PlySkip;

impl PropertyAccess for PlySkip {
    fn new() -> Self {
        PlySkip
    }
}

/// A colour channel in [0, 1]: an unsigned integer over its type's largest value, a float
/// as it is.
fn ply_unit(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::UChar(v) => f64::from(v) / 255.0,
        Property::UShort(v) => f64::from(v) / 65535.0,
        Property::UInt(v) => f64::from(v) / f64::from(u32::MAX),
        Property::Float(v) => v.into(),
        Property::Double(v) => v,
        _ => return None,
    })
}

fn ply_scalar(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Char(v) => v.into(),
        Property::UChar(v) => v.into(),
        Property::Short(v) => v.into(),
        Property::UShort(v) => v.into(),
        Property::Int(v) => v.into(),
        Property::UInt(v) => v.into(),
        Property::Float(v) => v.into(),
        Property::Double(v) => v,
        _ => return None,
    })
}

/// A PLY file's `vertex` and `face` elements as one mesh, its polygons split into fans of
/// triangles; normals and uvs when the vertex element declares all of their components.
fn load_ply(path: &Path, colors: ColorChoice) -> Result<MeshData, String> {
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut reader = Reader::new(std::io::BufReader::new(file));
    // the parser's message on one line: it spans several, with the offending text quoted
    let bad = |e: ply_rs_bw::parser::ParseError| {
        let words: Vec<String> = e
            .to_string()
            .split_whitespace()
            .map(str::to_string)
            .collect();
        format!("is not a PLY file wgtrace reads: {}", words.join(" "))
    };
    let header = Parser::<PlySkip>::new()
        .read_header(&mut reader)
        .map_err(bad)?;
    let declares = |element: &str, names: &[&str]| {
        header
            .elements
            .get(element)
            .is_some_and(|e| names.iter().all(|n| e.properties.contains_key(*n)))
    };
    for (element, names) in [("vertex", &["x", "y", "z"][..]), ("face", &[][..])] {
        if !declares(element, names) {
            return Err(format!(
                "has no {element} element{}",
                if names.is_empty() {
                    String::new()
                } else {
                    format!(" with properties {}", names.join(", "))
                }
            ));
        }
    }
    // the counts are capped before anything is read (a face becomes at least one
    // triangle; a mesh cannot need more than three vertices a triangle), and the
    // properties read as numbers must be scalars
    let count = |element: &str| header.elements.get(element).map_or(0, |e| e.count);
    if count("face") > MAX_TRIANGLES || count("vertex") > 3 * MAX_TRIANGLES {
        return Err(format!(
            "declares {} vertices and {} faces, more than the {MAX_TRIANGLES} triangles a scene may hold",
            count("vertex"),
            count("face")
        ));
    }
    let numeric = ["x", "y", "z", "nx", "ny", "nz"]
        .into_iter()
        .chain(PLY_UV.into_iter().flatten());
    for name in numeric {
        if let Some(p) = header.elements["vertex"].properties.get(name) {
            if !matches!(p.data_type, ply_rs_bw::ply::PropertyType::Scalar(_)) {
                return Err(format!("has a vertex property {name} that is a list"));
            }
        }
    }
    let normals = declares("vertex", &["nx", "ny", "nz"]);
    let uv_names = PLY_UV.map(|names| names.iter().any(|n| declares("vertex", &[n])));
    let uvs = uv_names[0] && uv_names[1];
    let rgb = |element: &str| {
        declares(element, &["red", "green", "blue"]) || declares(element, &["r", "g", "b"])
    };
    let vertex_colors = rgb("vertex");
    // a named attribute and its element: one not among the colours every reader knows,
    // or one of those where the file names its colours as Mitsuba writes them (`color_0`,
    // `color_1`, `color_2`), not `red`, `green`, `blue`
    let colour_names = colors
        .attribute
        .is_some_and(|a| MESH_ATTRIBUTES.contains(&a));
    let named = colors
        .attribute
        .and_then(|a| a.split_once('_'))
        .filter(|&(element, _)| !colour_names || !rgb(element));
    // its element and columns among that element's scalar properties (a file without the
    // colours a material reads is white, as any mesh without them)
    let kept = match named {
        Some((element, attribute)) => {
            match attribute_columns(&header.elements[element], element, attribute) {
                Ok(columns) => Some((element, columns)),
                Err(_) if colour_names => None,
                Err(e) => return Err(e),
            }
        }
        None => None,
    };
    let columns_of = |element: &str| {
        kept.as_ref()
            .filter(|(e, _)| *e == element)
            .map(|(_, c)| c.as_slice())
    };
    let mut vertices: Vec<PlyVertex> = Vec::new();
    let mut faces: Vec<PlyFace> = Vec::new();
    let mut values = Vec::new();
    for (name, def) in &header.elements {
        match name.as_str() {
            // (one element at most has values kept)
            "vertex" => {
                let read = read_element(&mut reader, def, &header, columns_of("vertex"));
                let kept_values;
                (vertices, kept_values) = read.map_err(bad)?;
                values.extend(kept_values);
            }
            "face" => {
                let read = read_element(&mut reader, def, &header, columns_of("face"));
                let kept_values;
                (faces, kept_values) = read.map_err(bad)?;
                values.extend(kept_values);
            }
            _ => {
                Parser::<PlySkip>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(bad)?;
            }
        }
    }
    let mut mesh = MeshData {
        positions: vertices
            .iter()
            .map(|v| DVec3::from(v.p).as_vec3())
            .collect(),
        ..Default::default()
    };
    if normals {
        mesh.normals = vertices
            .iter()
            .map(|v| DVec3::from(v.n).as_vec3())
            .collect();
    }
    if uvs {
        mesh.uvs = vertices
            .iter()
            .map(|v| DVec2::from(v.uv).as_vec2())
            .collect();
    }
    if vertex_colors {
        mesh.colors = vertices
            .iter()
            .map(|v| file_color(v.c, colors.space))
            .collect();
    }
    let n = mesh.positions.len() as i64;
    for (k, face) in faces.iter().enumerate() {
        if let Some(&i) = face.indices.iter().find(|&&i| i < 0 || i >= n) {
            return Err(format!(
                "face {k} has vertex index {i}, outside its {n} vertices"
            ));
        }
        let f = &face.indices;
        if mesh.triangles.len() + f.len().saturating_sub(2) > MAX_TRIANGLES {
            return Err(format!(
                "has more than the {MAX_TRIANGLES} triangles a scene may hold"
            ));
        }
        for j in 1..f.len().saturating_sub(1) {
            mesh.triangles
                .push([f[0] as u32, f[j] as u32, f[j + 1] as u32]);
        }
    }
    // face colours (Mitsuba's `face_color`), where there are no vertex colours or the
    // mesh asks for them: one per triangle of the face's fan, which `adjust` gives the
    // triangle's corners
    let faces_read = colors.attribute == Some("face_color");
    let fan = |colours: &mut dyn Iterator<Item = Vec4>| -> Vec<Vec4> {
        faces
            .iter()
            .zip(colours)
            .flat_map(|(f, c)| std::iter::repeat_n(c, f.indices.len().saturating_sub(2)))
            .collect()
    };
    if (faces_read || !vertex_colors) && rgb("face") {
        mesh.colors.clear();
        mesh.face_colors = fan(&mut faces.iter().map(|f| file_color(f.c, colors.space)));
    }
    // a named attribute as the mesh's colours: one channel as grey, three as rgb, each
    // as it is (integers over their type's largest value)
    if let Some((element, columns)) = &kept {
        let colour = |v: &[f64]| match *v {
            [w] => DVec4::new(w, w, w, 1.0).as_vec4(),
            [r, g, b] => DVec4::new(r, g, b, 1.0).as_vec4(),
            _ => unreachable!("attribute_columns gives one or three"),
        };
        let per_element = values.chunks_exact(columns.len());
        mesh.colors.clear();
        mesh.face_colors.clear();
        if *element == "vertex" {
            mesh.colors = per_element.map(colour).collect();
        } else {
            mesh.face_colors = fan(&mut per_element.map(colour));
        }
    }
    Ok(mesh)
}

/// A PLY element's records as `T` reads them and, where `columns` names some of its scalar
/// properties (a named attribute's; see [`attribute_columns`]), their values, record after
/// record.
fn read_element<T: PropertyAccess>(
    reader: &mut Reader<std::io::BufReader<std::fs::File>>,
    def: &ply_rs_bw::ply::ElementDef,
    header: &ply_rs_bw::ply::Header,
    columns: Option<&[usize]>,
) -> Result<(Vec<T>, Vec<f64>), ply_rs_bw::parser::ParseError> {
    let Some(columns) = columns else {
        let records = Parser::<T>::new().read_payload_for_element(reader, def, header)?;
        return Ok((records, Vec::new()));
    };
    let records = Parser::<WithValues<T>>::new().read_payload_for_element(reader, def, header)?;
    let mut values = Vec::with_capacity(records.len() * columns.len());
    let mut out = Vec::with_capacity(records.len());
    for r in records {
        values.extend(columns.iter().map(|&k| r.values[k]));
        out.push(r.inner);
    }
    Ok((out, values))
}

/// A PLY record as `T` reads it, with the value of each of its scalar properties kept
/// ([`ply_value`]), in the order the parser gives them: the header's.
struct WithValues<T> {
    inner: T,
    values: Vec<f64>,
}

impl<T: PropertyAccess> PropertyAccess for WithValues<T> {
    fn new() -> Self {
        WithValues {
            inner: T::new(),
            values: Vec::new(),
        }
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        if let Some(v) = ply_value(&property) {
            self.values.push(v);
        }
        self.inner.set_property(name, property)
    }
}

/// A scalar property's value as an attribute's: an integer over its type's largest value,
/// as wgtrace reads integer colours (Mitsuba 3.9.1 takes integer attributes as they are,
/// warning that they should lie in [0, 1]), a float as it is; None for a list.
fn ply_value(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Char(v) => f64::from(v) / f64::from(i8::MAX),
        Property::Short(v) => f64::from(v) / f64::from(i16::MAX),
        Property::Int(v) => f64::from(v) / f64::from(i32::MAX),
        _ => return ply_unit(p),
    })
}

/// Where a PLY element's named attribute lies among its scalar properties, as Mitsuba 3's
/// PLY reader names attributes: consecutive properties `P_x`, `P_y`, `P_z` (or `_0 _1 _2`,
/// `_1 _2 _3`; one to three of them) are the attribute `P`, and `P_r`, `P_g`, `P_b` the
/// attribute `P_color`. One channel or three are read; anything else is an error listing
/// the attributes the element has.
fn attribute_columns(
    def: &ply_rs_bw::ply::ElementDef,
    element: &str,
    attribute: &str,
) -> Result<Vec<usize>, String> {
    const SERIES: [&str; 4] = ["xyzw", "rgba", "0123", "1234"];
    let scalars: Vec<&str> = def
        .properties
        .values()
        .filter(|p| matches!(p.data_type, ply_rs_bw::ply::PropertyType::Scalar(_)))
        .map(|p| p.name.as_str())
        .collect();
    // (name, columns) of each attribute, in order
    let mut found: Vec<(String, Vec<usize>)> = Vec::new();
    let mut open: Option<(&str, usize, Vec<usize>)> = None; // (prefix, series, columns)
    let close = |open: &mut Option<(&str, usize, Vec<usize>)>, found: &mut Vec<_>| {
        if let Some((prefix, series, columns)) = open.take() {
            let suffix = if series == 1 { "_color" } else { "" };
            found.push((format!("{prefix}{suffix}"), columns));
        }
    };
    for (k, name) in scalars.iter().enumerate() {
        let split = name
            .rsplit_once('_')
            .filter(|(p, s)| !p.is_empty() && s.chars().count() == 1);
        if let (Some((prefix, s)), Some((open_prefix, series, columns))) = (split, &mut open) {
            let next = SERIES[*series].chars().nth(columns.len());
            if prefix == *open_prefix && next == s.chars().next() {
                columns.push(k);
                continue;
            }
        }
        close(&mut open, &mut found);
        if let Some((prefix, s)) = split {
            let c = s.chars().next();
            if let Some(series) = SERIES.iter().position(|x| x.chars().next() == c) {
                open = Some((prefix, series, vec![k]));
            }
        }
    }
    close(&mut open, &mut found);
    match found.iter().find(|(name, _)| name == attribute) {
        Some((_, columns)) if columns.len() == 1 || columns.len() == 3 => Ok(columns.clone()),
        Some((_, columns)) => Err(format!(
            "has the {element} attribute \"{element}_{attribute}\" with {} channels; a \
             mesh_attribute reads one (as grey) or three",
            columns.len()
        )),
        None => Err(format!(
            "has no {element} attribute \"{element}_{attribute}\" (its {element} attributes: {})",
            if found.is_empty() {
                "none".to_string()
            } else {
                found
                    .iter()
                    .map(|(n, _)| format!("{element}_{n}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            }
        )),
    }
}

/// The mesh with three corners of its own per triangle (positions, normals, uvs and vertex
/// colours copied; the per-triangle tangents and face colours kept).
fn unwelded(mesh: &MeshData) -> MeshData {
    fn copy<T: Copy>(v: &[T], triangles: &[[u32; 3]]) -> Vec<T> {
        if v.is_empty() {
            Vec::new()
        } else {
            triangles.iter().flatten().map(|&i| v[i as usize]).collect()
        }
    }
    let t = &mesh.triangles;
    MeshData {
        positions: copy(&mesh.positions, t),
        normals: copy(&mesh.normals, t),
        uvs: copy(&mesh.uvs, t),
        uvs1: copy(&mesh.uvs1, t),
        colors: copy(&mesh.colors, t),
        triangles: (0..t.len() as u32)
            .map(|k| [3 * k, 3 * k + 1, 3 * k + 2])
            .collect(),
        tangents: mesh.tangents.clone(),
        face_colors: mesh.face_colors.clone(),
    }
}

/// What every mesh file must give: faces, within the caps, indices inside the vertex list,
/// attributes that match the positions, finite coordinates.
pub fn check(mesh: MeshData) -> Result<MeshData, String> {
    if mesh.triangles.is_empty() {
        return Err("has no faces".into());
    }
    if mesh.triangles.len() > MAX_TRIANGLES {
        return Err(format!(
            "has {} triangles, more than the {MAX_TRIANGLES} a scene may hold",
            mesh.triangles.len()
        ));
    }
    let n = mesh.positions.len();
    let matches = |len: usize| len == 0 || len == n;
    if !matches(mesh.normals.len()) || !matches(mesh.uvs.len()) || !matches(mesh.uvs1.len()) {
        return Err("has normals or texture coordinates that do not match its positions".into());
    }
    if !matches(mesh.colors.len()) {
        return Err("has vertex colours that do not match its positions".into());
    }
    if !mesh.face_colors.is_empty() && mesh.face_colors.len() != mesh.triangles.len() {
        return Err("has face colours that do not match its faces".into());
    }
    if mesh.triangles.iter().flatten().any(|&i| i as usize >= n) {
        return Err("has a face index beyond its vertex list".into());
    }
    if !mesh.positions.iter().all(|p| p.is_finite())
        || !mesh.normals.iter().all(|p| p.is_finite())
        || !mesh.uvs.iter().all(|p| p.is_finite())
        || !mesh.uvs1.iter().all(|p| p.is_finite())
    {
        return Err("has a non-finite coordinate".into());
    }
    if !mesh
        .colors
        .iter()
        .chain(&mesh.face_colors)
        .all(|c| c.is_finite() && c.cmpge(Vec4::ZERO).all())
    {
        return Err("has a negative or non-finite vertex colour or attribute".into());
    }
    Ok(mesh)
}

/// The mesh's corner tangents by MikkTSpace (the `bevy_mikktspace` crate), as glTF asks
/// for a normal-mapped mesh without tangents: over its uvs (v up) and normals (each face's
/// own where the mesh has none). Without uvs there is no tangent frame: nothing is set.
pub fn generate_tangents(mesh: &mut MeshData) {
    if mesh.uvs.is_empty() {
        return;
    }
    struct Geometry<'a> {
        mesh: &'a MeshData,
        out: Vec<[Vec4; 3]>,
    }
    impl Geometry<'_> {
        fn vertex(&self, face: usize, vert: usize) -> usize {
            self.mesh.triangles[face][vert] as usize
        }
    }
    impl bevy_mikktspace::Geometry for Geometry<'_> {
        fn num_faces(&self) -> usize {
            self.mesh.triangles.len()
        }
        fn num_vertices_of_face(&self, _face: usize) -> usize {
            3
        }
        fn position(&self, face: usize, vert: usize) -> [f32; 3] {
            self.mesh.positions[self.vertex(face, vert)].into()
        }
        fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
            if self.mesh.normals.is_empty() {
                let p = self.mesh.triangles[face].map(|i| self.mesh.positions[i as usize]);
                (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero().into()
            } else {
                self.mesh.normals[self.vertex(face, vert)].into()
            }
        }
        fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
            self.mesh.uvs[self.vertex(face, vert)].into()
        }
        fn set_tangent(
            &mut self,
            tangent_space: Option<bevy_mikktspace::TangentSpace>,
            face: usize,
            vert: usize,
        ) {
            self.out[face][vert] =
                tangent_space.map_or(Vec4::ZERO, |t| Vec4::from(t.tangent_encoded()));
        }
    }
    let mut g = Geometry {
        mesh,
        out: vec![[Vec4::ZERO; 3]; mesh.triangles.len()],
    };
    // a mesh it cannot give a frame to keeps zero tangents: its normal map is not applied
    if bevy_mikktspace::generate_tangents(&mut g).is_ok() {
        let out = g.out;
        mesh.tangents = out;
    }
}
