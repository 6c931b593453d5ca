//! Mirrors `shaders/primitives/plane.wgsl`.

use glam::{Vec2, Vec3};

use super::common::ShapeTest;
use crate::cpu::bindings::Bindings;
use crate::cpu::geometry::{blank_surface, intersect_plane};
use crate::cpu::sampling::{max_abs, onb_tangents};
use crate::cpu::types::{Candidate, Ray, Surface};
use crate::scene::primitives::plane::Params;

impl ShapeTest for Params {
    fn intersect(&self, ray: &Ray, t_max: f32) -> Vec3 {
        Vec3::new(
            intersect_plane(self.point, self.normal, ray, t_max),
            0.0,
            0.0,
        )
    }

    fn surface(&self, _b: &Bindings, ray: &Ray, cand: &Candidate) -> Surface {
        let mut s = blank_surface();
        let n = self.normal;
        let q = ray.origin + cand.t * ray.dir - self.point;
        let qp = q - q.dot(n) * n;
        s.p = self.point + qp;
        s.ng = n;
        s.ns = n;
        let tb = onb_tangents(n);
        s.uv = self.uv_scale * Vec2::new(qp.dot(tb[0]), qp.dot(tb[1]));
        s.err = (max_abs(self.point) + max_abs(qp)) * (1.0 / 1048576.0);
        s
    }

    fn uv_derivatives(&self, _b: &Bindings, _s: &Surface, _cand: &Candidate) -> [Vec3; 2] {
        let tb = onb_tangents(self.normal);
        [tb[0] / self.uv_scale, tb[1] / self.uv_scale]
    }
}
