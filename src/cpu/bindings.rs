//! Mirrors `shaders/shared/bindings.wgsl`: what one dispatch reads.

use crate::scene::flat::FlatScene;
use crate::scene::records::{BvhNode, Emitter, Material, Params, Primitive, Texture};
use crate::scene::texels::Texels;

/// The resources of one dispatch, borrowed from the flattened scene.
#[derive(Clone, Copy)]
pub struct Bindings<'a> {
    pub params: Params,
    pub primitives: &'a [Primitive],
    pub materials: &'a [Material],
    pub emitters: &'a [Emitter],
    pub bvh: &'a [BvhNode],
    pub shape_data: &'a [[f32; 4]],
    pub textures: &'a [Texture],
    /// The image texel banks (`scene::texels`): what the GPU binds as array textures.
    pub texels: &'a Texels,
    /// The Perlin tables and the image background's distribution.
    pub tables: &'a [[f32; 4]],
    /// A material has alpha (mask or blend): rays pass through transparent surfaces (the
    /// shader's HAS_ALPHA).
    pub has_alpha: bool,
    /// A material has a bump map: hits carry their uv derivatives (the shader's HAS_BUMP,
    /// which computes them for every hit, so that a blend's bumped part has them too).
    pub has_bump: bool,
    /// A path can enter a medium (the shader's HAS_MEDIA).
    pub has_media: bool,
}

impl<'a> Bindings<'a> {
    pub fn new(scene: &'a FlatScene, params: Params) -> Self {
        Self {
            params,
            primitives: &scene.primitives,
            materials: &scene.materials,
            emitters: &scene.emitters,
            bvh: &scene.bvh,
            shape_data: &scene.shape_data,
            textures: &scene.textures,
            texels: &scene.texels,
            tables: &scene.tables,
            has_bump: scene
                .materials
                .iter()
                .any(crate::scene::materials::reads_uv_derivatives),
            has_media: scene.has_media(),
            has_alpha: scene.materials.iter().any(|m| {
                m.flags
                    & (crate::scene::records::MAT_FLAG_ALPHA_MASK
                        | crate::scene::records::MAT_FLAG_ALPHA_BLEND)
                    != 0
            }),
        }
    }
}
