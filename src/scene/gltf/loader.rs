//! The reader of one glTF file's scene: what it has read so far ([`Loader`]), and the walk
//! of the scene's node tree that places meshes, cameras and lights. Meshes, materials
//! and textures are read by the `impl Loader` blocks of `meshes.rs`, `materials.rs` and
//! `textures.rs`, accessors checked by `accessors.rs`.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use glam::{Affine3A, Mat4, Vec3};

use super::error::{GltfError, Result};
use crate::scene::format::{CameraDesc, LightDesc, Projection, SpotFalloff, UvTransformDesc};
use crate::scene::imported::{ImportedScene, NamedCamera};
use crate::scene::mesh::MAX_TRIANGLES;
use crate::scene::textures::ImageData;

/// A texture of the scene format made from one glTF texture look-up: the texture, its
/// colour space, its factor, its uv slot (0 or 1: which of its primitive's two uv sets)
/// and its transform.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct TextureKey {
    pub(super) texture: usize,
    pub(super) srgb: bool,
    pub(super) factor: [f32; 3],
    pub(super) uv_slot: u32,
    pub(super) transform: Option<UvTransformDesc>,
    /// A texture made from the glTF one's image (`Some` of the glossiness factor's bits
    /// for a roughness map from KHR_materials_pbrSpecularGlossiness).
    pub(super) derived: Option<u32>,
}

pub(super) struct Loader<'a> {
    pub(super) doc: &'a gltf::Document,
    pub(super) buffers: Vec<Vec<u8>>,
    pub(super) dir: &'a Path,
    pub(super) prefix: &'a str,
    pub(super) out: ImportedScene,
    /// (mesh, primitive) -> index in `out.meshes`.
    pub(super) mesh_ids: HashMap<(usize, usize), usize>,
    /// glTF material index (None: the default material) -> index in `out.materials`.
    pub(super) material_ids: HashMap<Option<usize>, usize>,
    pub(super) texture_keys: Vec<TextureKey>,
    /// The glTF uv sets (TEXCOORD_n) of the material being read, in slot order: a texture
    /// reading set n reads its primitive's uv slot `uv_sets.position(n)`.
    pub(super) uv_sets: Vec<u32>,
    /// (image, sRGB) -> decoded image.
    pub(super) images: HashMap<(usize, bool), Arc<ImageData>>,
    /// Total texels decoded.
    pub(super) texels: u64,
}

impl<'a> Loader<'a> {
    /// Walks the first scene's node tree (depth-first, children in order).
    pub(super) fn scene(mut self) -> Result<ImportedScene> {
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
            mirror: false,
            // glTF's znear is left out: wgtrace's glTF cameras start at the camera
            near_clip: 0.0,
            medium: None,
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
                    falloff: SpotFalloff::Gltf,
                    texture: None,
                    up: [0.0, 1.0, 0.0],
                }
            }
        });
        Ok(())
    }
}
