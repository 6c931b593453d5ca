//! Mesh primitives: triangles with their positions, normals, the uv set their material
//! reads and tangents (the file's, else MikkTSpace's for a normal-mapped one), each read
//! once however many nodes place it.

use glam::{Affine3A, Vec2, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};

use super::error::{GltfError, Result};
use super::loader::Loader;
use crate::scene::imported::Instance;
use crate::scene::mesh::{self, MeshData};

impl Loader<'_> {
    pub(super) fn mesh(&mut self, mesh: &gltf::Mesh, transform: Affine3A) -> Result<()> {
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
