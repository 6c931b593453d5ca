//! Triangle meshes from Wavefront OBJ files, read with `tobj`.

use std::path::Path;

use glam::{Vec2, Vec3};

/// A triangle mesh with one index per corner; `normals` and `uvs` are empty when the file
/// has none (for any of its objects), else one per position.
#[derive(Debug, Clone, Default)]
pub struct MeshData {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub triangles: Vec<[u32; 3]>,
}

/// Largest OBJ file read (2 GiB): the whole file is parsed in memory.
pub const MAX_MESH_FILE_BYTES: u64 = 1 << 31;

/// Most triangles of all a scene's meshes together (2^24, about 1.7 GB of records).
pub const MAX_TRIANGLES: usize = 1 << 24;

/// Reads every object of an OBJ file into one mesh (polygons are triangulated). Files
/// over [`MAX_MESH_FILE_BYTES`] and meshes over [`MAX_TRIANGLES`] are refused.
pub fn load_obj(path: &Path) -> Result<MeshData, String> {
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
    let (models, _materials) = tobj::load_obj(path, &options).map_err(|e| e.to_string())?;
    let with_normals = models.iter().all(|m| !m.mesh.normals.is_empty());
    let with_uvs = models.iter().all(|m| !m.mesh.texcoords.is_empty());
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
        mesh.triangles.extend(
            m.indices
                .chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
    }
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
    if (with_normals && mesh.normals.len() != n) || (with_uvs && mesh.uvs.len() != n) {
        return Err("has normals or texture coordinates that do not match its positions".into());
    }
    if mesh.triangles.iter().flatten().any(|&i| i as usize >= n) {
        return Err("has a face index beyond its vertex list".into());
    }
    if !mesh.positions.iter().all(|p| p.is_finite())
        || !mesh.normals.iter().all(|p| p.is_finite())
        || !mesh.uvs.iter().all(|p| p.is_finite())
    {
        return Err("has a non-finite coordinate".into());
    }
    Ok(mesh)
}
