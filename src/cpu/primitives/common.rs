//! What every primitive file of the CPU backend implements.

use glam::{Vec2, Vec3};

use crate::cpu::bindings::Bindings;
use crate::cpu::types::{Candidate, LightPoint, Ray, Surface, FAR};

/// A primitive type's functions (its WGSL file's `NAME_...`), on its view. The light
/// ones only for the types that can be lights (`PrimitiveKind::light`); the dispatch
/// never calls the others'.
pub trait ShapeTest {
    /// (t, u, v) as in `Candidate`, t = FAR on a miss; `ray.dir` is unit length.
    fn intersect(&self, ray: &Ray, t_max: f32) -> Vec3;

    /// Hit point, normals, uv and error bound of a candidate, in the shape's own space.
    fn surface(&self, b: &Bindings, ray: &Ray, cand: &Candidate) -> Surface;

    /// The derivatives of the point along the first uv set.
    fn uv_derivatives(&self, b: &Bindings, s: &Surface, cand: &Candidate) -> [Vec3; 2];

    /// A point on the light seen from `from`, with its solid-angle pdf.
    fn light_sample(&self, _area: f32, _from: Vec3, _u: [f32; 2]) -> LightPoint {
        LightPoint {
            x: Vec3::ZERO,
            pdf: 0.0,
            uv: Vec2::ZERO,
        }
    }

    /// The solid-angle pdf of `light_sample` toward x.
    fn light_pdf(&self, _area: f32, _from: Vec3, _x: Vec3) -> f32 {
        0.0
    }

    /// Where the ray from `from` along unit d meets the light as its sampling sees it.
    fn light_distance(&self, _from: Vec3, _d: Vec3) -> f32 {
        FAR
    }
}
