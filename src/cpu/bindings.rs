//! Mirrors `shaders/shared/bindings.wgsl`: what one dispatch reads.

use crate::scene::records::{Emitter, Material, Params, Primitive};
use crate::scene::FlatScene;

/// The resources of one dispatch, borrowed from the flattened scene.
#[derive(Clone, Copy)]
pub struct Bindings<'a> {
    pub params: Params,
    pub primitives: &'a [Primitive],
    pub materials: &'a [Material],
    pub emitters: &'a [Emitter],
}

impl<'a> Bindings<'a> {
    pub fn new(scene: &'a FlatScene, params: Params) -> Self {
        Self {
            params,
            primitives: &scene.primitives,
            materials: &scene.materials,
            emitters: &scene.emitters,
        }
    }
}
