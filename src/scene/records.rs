//! `#[repr(C)]` records shared with WGSL: the contract both backends read.
//!
//! Each struct mirrors the struct of the same name in `shaders/shared/types.wgsl`.
//! `tests/layout.rs` compares every size and field offset below with naga's layout of the
//! shader, so a change on one side that is not made on the other fails the tests.

use bytemuck::{Pod, Zeroable};

/// Primitive tags: the cases of the `switch` in `intersect.wgsl`.
pub const PRIM_SPHERE: u32 = 0;
pub const PRIM_TRIANGLE: u32 = 1;

/// Material tags: the cases of the `switch` in `materials.wgsl`.
pub const MAT_LAMBERTIAN: u32 = 0;
pub const MAT_EMISSIVE: u32 = 1;

/// Material flag: emits from both sides.
pub const MAT_FLAG_TWO_SIDED: u32 = 1;

/// Primitive index reported for a ray that hits nothing.
pub const NO_HIT: u32 = u32::MAX;
/// Largest finite f32: "no intersection" without relying on infinities.
pub const FAR: f32 = f32::MAX;

/// A tagged primitive. Sphere: `a` = (center, radius). Triangle: vertices `a`, `b`, `c`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Primitive {
    pub tag: u32,
    pub material: u32,
    pub flags: u32,
    pub pad: u32,
    pub a: [f32; 4],
    pub b: [f32; 4],
    pub c: [f32; 4],
}

/// A tagged material. `emission` is the radiance leaving the front side (both sides with
/// [`MAT_FLAG_TWO_SIDED`]); `params` holds per-type scalars.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Material {
    pub tag: u32,
    pub flags: u32,
    pub pad0: u32,
    pub pad1: u32,
    pub albedo: [f32; 4],
    pub emission: [f32; 4],
    pub params: [f32; 4],
}

/// One entry of the emitter list: an emissive primitive, its area and emitted power.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Emitter {
    pub primitive: u32,
    pub material: u32,
    pub area: f32,
    pub power: f32,
}

/// Per-dispatch constants (a uniform buffer): camera, image, pass and tile.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Params {
    /// Camera position; `.w` = lens radius.
    pub cam_origin: [f32; 4],
    /// Unit right vector; `.w` = half width of the focus plane.
    pub cam_right: [f32; 4],
    /// Unit up vector; `.w` = half height of the focus plane.
    pub cam_up: [f32; 4],
    /// Unit forward vector; `.w` = focus distance.
    pub cam_forward: [f32; 4],
    /// Radiance of rays that leave the scene.
    pub background: [f32; 4],
    pub width: u32,
    pub height: u32,
    pub max_depth: u32,
    pub seed: u32,
    pub sample_index: u32,
    pub num_primitives: u32,
    pub num_emitters: u32,
    pub tile_x: u32,
    pub tile_y: u32,
    pub tile_width: u32,
    pub tile_height: u32,
    pub pad: u32,
}

/// Size and field offsets of one record, for the layout test against naga.
#[derive(Debug)]
pub struct RecordLayout {
    pub name: &'static str,
    pub size: usize,
    pub fields: Vec<(&'static str, usize)>,
}

macro_rules! layout {
    ($ty:ident { $($field:ident),* $(,)? }) => {
        RecordLayout {
            name: stringify!($ty),
            size: core::mem::size_of::<$ty>(),
            fields: vec![$((stringify!($field), core::mem::offset_of!($ty, $field))),*],
        }
    };
}

/// Every record shared with WGSL, with every field. A field added to a struct here must be
/// added to this list (the test also checks the field count against the shader).
pub fn record_layouts() -> Vec<RecordLayout> {
    vec![
        layout!(Primitive {
            tag,
            material,
            flags,
            pad,
            a,
            b,
            c
        }),
        layout!(Material {
            tag,
            flags,
            pad0,
            pad1,
            albedo,
            emission,
            params
        }),
        layout!(Emitter {
            primitive,
            material,
            area,
            power
        }),
        layout!(Params {
            cam_origin,
            cam_right,
            cam_up,
            cam_forward,
            background,
            width,
            height,
            max_depth,
            seed,
            sample_index,
            num_primitives,
            num_emitters,
            tile_x,
            tile_y,
            tile_width,
            tile_height,
            pad
        }),
    ]
}
