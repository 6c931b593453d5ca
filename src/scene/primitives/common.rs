//! What every primitive module answers, through its record view (`Params`).

use glam::{Mat3, Vec3};

use crate::scene::bvh::Aabb;

/// A primitive type's host geometry, on its record view.
pub trait Shape: Sized {
    /// Whether it has bounds: a BVH leaf; else it is tested on its own before the BVH.
    const BOUNDED: bool = true;
    /// Whether it can be sampled as a light (its WGSL file has the `NAME_light_*`
    /// functions, and [`Shape::light`] answers).
    const LIGHT: bool = false;
    /// Whether its code reads `shape_data` beyond a transform.
    const SHAPE_DATA: bool = false;

    /// Object-space bounds (bounded types only).
    fn bounds(&self) -> Aabb;

    /// Surface area in its own space.
    fn area(&self) -> f32;

    /// Whether its values make a shape: sizes above 0, unit normals (the caller checks
    /// that they are finite).
    fn usable(&self) -> bool {
        true
    }

    /// Its geometry as a light's, in world space under a similarity: linear part `m`,
    /// translation `t`, scale `s` (types with [`Shape::LIGHT`] only).
    fn light(&self, _m: Mat3, _t: Vec3, _s: f32) -> Option<Self> {
        None
    }
}

/// Half-extent along each world axis of a disk of radius r with unit normal n.
pub fn disk_extent(n: Vec3, r: f32) -> Vec3 {
    r * (Vec3::ONE - n * n).max(Vec3::ZERO).powf(0.5)
}

/// Whether n has unit length, to within what a normal read back from f32 keeps.
pub fn unit(n: Vec3) -> bool {
    (n.length() - 1.0).abs() < 1e-3
}
