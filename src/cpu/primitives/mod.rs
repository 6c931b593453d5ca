//! Mirrors the dispatch `gpu::codegen::primitives` writes (`generated/primitives`): a
//! primitive's test, surface and uv derivatives by its type, and a light's sampling by
//! its primitive's type. One file per primitive beside this one mirrors
//! `shaders/primitives/NAME.wgsl`, implementing [`ShapeTest`] (in `common`, which the
//! type files import, never this one) on the type's view; the dispatch below is written
//! from the type list (`scene::primitives::for_each_primitive!`).

pub mod r#box;
pub mod common;
pub mod cylinder;
pub mod disk;
pub mod plane;
pub mod sphere;
pub mod triangle;

use glam::{Vec2, Vec3};

pub use common::ShapeTest;

use super::bindings::Bindings;
use super::geometry::{blank_surface, emitter_shape};
use super::sampling::onb_tangents;
use super::types::{Candidate, LightPoint, Ray, Surface, FAR};
use crate::scene::primitives::{for_each_primitive, PrimitiveKind};
use crate::scene::records::{Emitter, Primitive};

macro_rules! dispatch {
    ($( $(#[$doc:meta])* $kind:ident = $tag:literal, $module:ident, $name:literal, $define:literal; )*) => {
        /// One primitive of type `tag` in its own space: (t, u, v) as in Candidate.
        pub fn intersect_local(prim: &Primitive, tag: u32, ray: &Ray, t_max: f32) -> Vec3 {
            match PrimitiveKind::from_tag(tag) {
                $( Some(PrimitiveKind::$kind) => {
                    crate::scene::primitives::$module::Params::read(prim).intersect(ray, t_max)
                } )*
                None => Vec3::new(FAR, 0.0, 0.0),
            }
        }

        /// Hit point, normals, uv and error bound in the primitive's own space.
        pub fn surface_local(b: &Bindings, prim: &Primitive, ray: &Ray, cand: &Candidate) -> Surface {
            match PrimitiveKind::from_tag(prim.tag) {
                $( Some(PrimitiveKind::$kind) => {
                    crate::scene::primitives::$module::Params::read(prim).surface(b, ray, cand)
                } )*
                None => blank_surface(),
            }
        }

        /// The derivatives of the point along the first uv set of a surface point `s` of
        /// a primitive, in its own space.
        pub fn surface_uv_derivatives(
            b: &Bindings,
            prim: &Primitive,
            s: &Surface,
            cand: &Candidate,
        ) -> [Vec3; 2] {
            match PrimitiveKind::from_tag(prim.tag) {
                $( Some(PrimitiveKind::$kind) => {
                    crate::scene::primitives::$module::Params::read(prim)
                        .uv_derivatives(b, s, cand)
                } )*
                None => onb_tangents(s.ng),
            }
        }

        /// A point on light e seen from `from`, by its primitive type.
        pub fn shape_light_sample(e: &Emitter, from: Vec3, u: [f32; 2]) -> LightPoint {
            let shape = emitter_shape(e);
            match PrimitiveKind::from_tag(e.kind) {
                $( Some(k @ PrimitiveKind::$kind) if k.light() => {
                    crate::scene::primitives::$module::Params::read(&shape)
                        .light_sample(e.area, from, u)
                } )*
                _ => LightPoint { x: Vec3::ZERO, pdf: 0.0, uv: Vec2::ZERO },
            }
        }

        /// The solid-angle pdf of `shape_light_sample` toward x on light e.
        pub fn shape_light_pdf(e: &Emitter, from: Vec3, x: Vec3) -> f32 {
            let shape = emitter_shape(e);
            match PrimitiveKind::from_tag(e.kind) {
                $( Some(k @ PrimitiveKind::$kind) if k.light() => {
                    crate::scene::primitives::$module::Params::read(&shape)
                        .light_pdf(e.area, from, x)
                } )*
                _ => 0.0,
            }
        }

        /// Where the ray from `from` along unit d meets light e as its sampling sees it.
        pub fn shape_light_distance(e: &Emitter, from: Vec3, d: Vec3) -> f32 {
            let shape = emitter_shape(e);
            match PrimitiveKind::from_tag(e.kind) {
                $( Some(k @ PrimitiveKind::$kind) if k.light() => {
                    crate::scene::primitives::$module::Params::read(&shape)
                        .light_distance(from, d)
                } )*
                _ => FAR,
            }
        }
    };
}

for_each_primitive!(dispatch);
