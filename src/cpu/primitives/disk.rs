//! Mirrors `shaders/primitives/disk.wgsl`.

use glam::{Vec2, Vec3};

use super::common::ShapeTest;
use crate::cpu::bindings::Bindings;
use crate::cpu::geometry::{angle_uv, area_pdf, blank_surface, intersect_disk};
use crate::cpu::sampling::{max_abs, onb_tangents, sample_disk, PI};
use crate::cpu::types::{Candidate, LightPoint, Ray, Surface, FAR};
use crate::scene::primitives::disk::Params;

impl ShapeTest for Params {
    fn intersect(&self, ray: &Ray, t_max: f32) -> Vec3 {
        let t = intersect_disk(self.center, self.normal, self.radius, ray, t_max);
        Vec3::new(t, 0.0, 0.0)
    }

    fn surface(&self, _b: &Bindings, ray: &Ray, cand: &Candidate) -> Surface {
        let mut s = blank_surface();
        let n = self.normal;
        let q = ray.origin + cand.t * ray.dir - self.center;
        let qp = q - q.dot(n) * n;
        s.p = self.center + qp;
        s.ng = n;
        s.ns = n;
        s.uv = Vec2::new(angle_uv(qp, n), qp.length() / self.radius);
        s.err = (max_abs(self.center) + self.radius) * (1.0 / 1048576.0);
        s
    }

    fn uv_derivatives(&self, _b: &Bindings, s: &Surface, _cand: &Candidate) -> [Vec3; 2] {
        let qp = s.p - self.center;
        let len = qp.length().max(1e-12);
        let tb = onb_tangents(self.normal);
        let c = qp / len;
        let around = c.dot(tb[0]) * tb[1] - c.dot(tb[1]) * tb[0];
        [2.0 * PI * len * around, c * self.radius]
    }

    /// Uniform by area: rho = R sqrt(xi1), theta = 2 pi xi2.
    fn light_sample(&self, area: f32, from: Vec3, u: [f32; 2]) -> LightPoint {
        let d = sample_disk(u) * self.radius;
        let tb = onb_tangents(self.normal);
        let x = self.center + d.x * tb[0] + d.y * tb[1];
        LightPoint {
            x,
            pdf: area_pdf(from, x, self.normal, area),
            uv: Vec2::ZERO,
        }
    }

    fn light_pdf(&self, area: f32, from: Vec3, x: Vec3) -> f32 {
        area_pdf(from, x, self.normal, area)
    }

    fn light_distance(&self, from: Vec3, d: Vec3) -> f32 {
        intersect_disk(
            self.center,
            self.normal,
            self.radius,
            &Ray {
                origin: from,
                dir: d,
            },
            FAR,
        )
    }
}
