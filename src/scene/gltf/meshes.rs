//! Mesh primitives: triangles with their positions, normals, the uv set their material
//! reads and tangents (the file's, else MikkTSpace's for a normal-mapped one), each read
//! once however many nodes place it.

use glam::{Affine3A, Vec2, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};

use super::error::{GltfError, Result};
use super::loader::Loader;
use super::materials::{normal_tex_coord, uv_sets};
use crate::scene::imported::Instance;
use crate::scene::mesh::{self, MeshData};

impl Loader<'_> {
    pub(super) fn mesh(&mut self, mesh: &gltf::Mesh, transform: Affine3A) -> Result<()> {
        for prim in mesh.primitives() {
            let key = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
            use gltf::mesh::Mode;
            if !matches!(
                prim.mode(),
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                self.out.warnings.push(format!(
                    "{key}: mode {:?} is left out (wgtrace renders triangles)",
                    prim.mode()
                ));
                continue;
            }
            let id = match self.mesh_ids.get(&(mesh.index(), prim.index())) {
                Some(&id) => id,
                None => {
                    // a primitive has the uv sets its material's textures read, in slot
                    // order (TEXCOORD_0 when they read none)
                    let (sets, _) = uv_sets(&prim.material());
                    let data = self.primitive(&prim, &key, &sets)?;
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

    /// A triangle primitive's vertices, normals, vertex colours and the uv sets `sets`
    /// (those its material's textures read: slot 0's, then slot 1's), indexed or not.
    fn primitive(&self, prim: &gltf::Primitive, key: &str, sets: &[u32]) -> Result<MeshData> {
        use gltf::Semantic;
        let attr = |name: &str| format!("{key}.attributes.{name}");
        let slots: Vec<u32> = if sets.is_empty() {
            vec![0]
        } else {
            sets.to_vec()
        };
        let positions = prim.get(&Semantic::Positions).ok_or_else(|| {
            GltfError::new(attr("POSITION"), "is missing (a primitive needs positions)")
        })?;
        // floats, or the integer types KHR_mesh_quantization allows (dequantized when read)
        let (f, i8, u8, i16, u16) = (
            DataType::F32,
            DataType::I8,
            DataType::U8,
            DataType::I16,
            DataType::U16,
        );
        let n = self.check_accessor(
            &positions,
            &attr("POSITION"),
            &[Dimensions::Vec3],
            &[f, i8, u8, i16, u16],
        )?;
        // normals and tangents: floats or normalized signed integers
        let unit = |a: &gltf::Accessor, name: &str| {
            if a.data_type() != f && !a.normalized() {
                return Err(GltfError::new(
                    attr(name),
                    format!(
                        "is {:?} that is not normalized (KHR_mesh_quantization requires it)",
                        a.data_type()
                    ),
                ));
            }
            Ok(())
        };
        let normals = prim.get(&Semantic::Normals);
        if let Some(a) = &normals {
            self.check_count(a, n, &attr("NORMAL"), &[Dimensions::Vec3], &[f, i8, i16])?;
            unit(a, "NORMAL")?;
        }
        let uv_types = [f, i8, u8, i16, u16];
        for &set in &slots {
            if let Some(a) = prim.get(&Semantic::TexCoords(set)) {
                let name = attr(&format!("TEXCOORD_{set}"));
                self.check_count(&a, n, &name, &[Dimensions::Vec2], &uv_types)?;
            }
        }
        let colors = prim.get(&Semantic::Colors(0));
        if let Some(a) = &colors {
            let dims = [Dimensions::Vec3, Dimensions::Vec4];
            let types = [DataType::F32, DataType::U8, DataType::U16];
            self.check_count(a, n, &attr("COLOR_0"), &dims, &types)?;
            if a.data_type() != DataType::F32 && !a.normalized() {
                return Err(GltfError::new(
                    attr("COLOR_0"),
                    "is an integer accessor that is not normalized (glTF requires it)",
                ));
            }
        }
        let tangents = prim.get(&Semantic::Tangents);
        if let Some(a) = &tangents {
            self.check_count(a, n, &attr("TANGENT"), &[Dimensions::Vec4], &[f, i8, i16])?;
            unit(a, "TANGENT")?;
        }
        if let Some(a) = prim.indices() {
            let types = [DataType::U8, DataType::U16, DataType::U32];
            self.check_accessor(&a, &format!("{key}.indices"), &[Dimensions::Scalar], &types)?;
        }
        let reader = prim.reader(|b| self.buffers.get(b.index()).map(Vec::as_slice));
        let unreadable = |what: String| {
            GltfError::new(
                what,
                "cannot be read (its sparse data points outside its buffer view?)",
            )
        };
        let mut mesh = MeshData {
            positions: self
                .read_floats::<3>(&positions, &attr("POSITION"))?
                .into_iter()
                .map(Vec3::from)
                .collect(),
            ..Default::default()
        };
        if let Some(a) = &normals {
            mesh.normals = self
                .read_floats::<3>(a, &attr("NORMAL"))?
                .into_iter()
                .map(Vec3::from)
                .collect();
        }
        for (slot, &set) in slots.iter().enumerate() {
            let Some(a) = prim.get(&Semantic::TexCoords(set)) else {
                continue;
            };
            let uvs = self
                .read_floats::<2>(&a, &attr(&format!("TEXCOORD_{set}")))?
                .into_iter()
                // glTF's v runs down the image, wgtrace's up
                .map(|[u, v]| Vec2::new(u, 1.0 - v))
                .collect();
            if slot == 0 {
                mesh.uvs = uvs;
            } else {
                mesh.uvs1 = uvs;
            }
        }
        if colors.is_some() {
            mesh.colors = reader
                .read_colors(0)
                .ok_or_else(|| unreadable(attr("COLOR_0")))?
                .into_rgba_f32()
                .map(Vec4::from)
                .collect();
        }
        let indices: Vec<u32> = match reader.read_indices() {
            Some(i) => i.into_u32().collect(),
            None if prim.indices().is_some() => {
                return Err(unreadable(format!("{key}.indices")));
            }
            None => (0..n as u32).collect(),
        };
        mesh.triangles = triangles(prim.mode(), &indices)
            .map_err(|e| GltfError::new(format!("{key}.indices"), e))?;
        let mut mesh = mesh::check(mesh).map_err(|e| GltfError::new(key, e))?;
        if prim.material().normal_texture().is_some() && !mesh.uvs.is_empty() {
            if let Some(a) = &tangents {
                let t: Vec<Vec4> = self
                    .read_floats::<4>(a, &attr("TANGENT"))?
                    .into_iter()
                    .map(Vec4::from)
                    .collect();
                mesh.tangents = mesh
                    .triangles
                    .iter()
                    .map(|tri| tri.map(|i| t[i as usize]))
                    .collect();
            } else {
                // glTF: a normal-mapped mesh without tangents gets MikkTSpace's, over the
                // uv set its normal texture reads
                let normal_slot = prim
                    .material()
                    .normal_texture()
                    .is_some_and(|n| sets.get(1) == Some(&normal_tex_coord(&n)));
                if normal_slot && !mesh.uvs1.is_empty() {
                    std::mem::swap(&mut mesh.uvs, &mut mesh.uvs1);
                    mesh::generate_tangents(&mut mesh);
                    std::mem::swap(&mut mesh.uvs, &mut mesh.uvs1);
                } else {
                    mesh::generate_tangents(&mut mesh);
                }
            }
        }
        Ok(mesh)
    }
}

/// The triangles of a primitive's vertex list in `mode`, as glTF 2.0 (3.7.2.1) numbers
/// them: a list three by three; a strip's triangle i of vertices i, i + 1 + i % 2,
/// i + 2 - i % 2 (every other one turned, so all wind alike); a fan's of i + 1, i + 2 and
/// 0. A strip's or fan's triangles that repeat a vertex (a strip's restarts) are left out.
pub fn triangles(
    mode: gltf::mesh::Mode,
    indices: &[u32],
) -> std::result::Result<Vec<[u32; 3]>, String> {
    use gltf::mesh::Mode;
    let n = indices.len();
    let tris: Vec<[u32; 3]> = match mode {
        Mode::Triangles => {
            if !n.is_multiple_of(3) {
                return Err(format!("has {n} entries, not a multiple of 3"));
            }
            return Ok(indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect());
        }
        Mode::TriangleStrip => (0..n.saturating_sub(2))
            .map(|i| {
                let odd = i % 2;
                [indices[i], indices[i + 1 + odd], indices[i + 2 - odd]]
            })
            .collect(),
        _ => (0..n.saturating_sub(2))
            .map(|i| [indices[i + 1], indices[i + 2], indices[0]])
            .collect(),
    };
    Ok(tris
        .into_iter()
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect())
}
