//! What a file brings besides its triangles, in the scene format's terms: meshes, placed
//! instances of them, materials and textures, cameras and lights. glTF files
//! (`gltf`) and OBJ files with their .mtl (`mesh`) are read into it; the flattener
//! writes each instance's triangles under its own transform and appends the materials and
//! textures after the scene file's own.

use std::sync::Arc;

use glam::{Affine3A, Vec3};

use super::bvh::Aabb;
use super::format::{CameraDesc, LightDesc, TextureDesc};
use super::materials::MaterialDesc;
use super::mesh::MeshData;
use super::textures::ImageData;

/// One placement of a mesh: `mesh` and `material` index [`ImportedScene::meshes`] and
/// [`ImportedScene::materials`].
#[derive(Debug, Clone)]
pub struct Instance {
    pub mesh: usize,
    pub material: usize,
    pub transform: Affine3A,
}

/// A camera placed by its node: `name` is the camera's name, else its node's, else
/// `cameras[i]`.
#[derive(Debug, Clone)]
pub struct NamedCamera {
    pub name: String,
    pub node_name: Option<String>,
    pub desc: CameraDesc,
}

/// A texture as the scene format describes it, with its decoded image.
#[derive(Debug, Clone)]
pub struct ImportedTexture {
    pub name: String,
    pub desc: TextureDesc,
    /// Shared by every texture of the file that looks the same image up (in the same
    /// colour space): its texels are written once.
    pub image: Arc<ImageData>,
}

/// What an imported file's scene brings. Texture and material names begin with the prefix
/// the loader was given, so that several files and a scene file's own names never
/// collide.
#[derive(Debug, Clone, Default)]
pub struct ImportedScene {
    /// One per mesh primitive that is used.
    pub meshes: Vec<MeshData>,
    pub instances: Vec<Instance>,
    pub materials: Vec<(String, MaterialDesc)>,
    pub textures: Vec<ImportedTexture>,
    /// In the order of the scene's nodes.
    pub cameras: Vec<NamedCamera>,
    /// KHR_lights_punctual lights, placed.
    pub lights: Vec<LightDesc>,
    /// What was left out or approximated, one line each.
    pub warnings: Vec<String>,
}

impl ImportedScene {
    /// Texels of its images, each shared image counted once.
    pub fn unique_texels(&self) -> u64 {
        let mut seen = std::collections::HashSet::new();
        self.textures
            .iter()
            .filter(|t| seen.insert(Arc::as_ptr(&t.image)))
            .map(|t| t.image.texel_count())
            .sum()
    }

    /// Triangles over all instances: what the flattened scene holds.
    pub fn instanced_triangles(&self) -> u64 {
        self.instances
            .iter()
            .map(|i| self.meshes[i.mesh].triangles.len() as u64)
            .sum()
    }

    /// The placed meshes' bounds (empty without any).
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::empty();
        for inst in &self.instances {
            let local = Aabb::from_points(&self.meshes[inst.mesh].positions);
            for k in 0..8 {
                let corner = Vec3::new(
                    if k & 1 == 0 { local.lo.x } else { local.hi.x },
                    if k & 2 == 0 { local.lo.y } else { local.hi.y },
                    if k & 4 == 0 { local.lo.z } else { local.hi.z },
                );
                b.grow(inst.transform.transform_point3(corner));
            }
        }
        b
    }

    /// Whether a material of an instance emits light.
    pub fn emits(&self) -> bool {
        self.instances
            .iter()
            .any(|i| self.materials[i.material].1.emits())
    }
}
