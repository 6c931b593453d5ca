//! Mirrors `shaders/primitives/sphere.wgsl`.

use glam::{Vec2, Vec3};

use super::common::ShapeTest;
use crate::cpu::bindings::Bindings;
use crate::cpu::geometry::{area_pdf, blank_surface};
use crate::cpu::sampling::{max_abs, onb_tangents, sample_sphere, PI};
use crate::cpu::types::{Candidate, LightPoint, Ray, Surface, FAR};
use crate::scene::primitives::sphere::Params;

impl ShapeTest for Params {
    /// Numerically stable form (Ray Tracing Gems, chapter 7): (t, 0, 0), the nearest root
    /// in (0, t_max), else FAR.
    fn intersect(&self, ray: &Ray, t_max: f32) -> Vec3 {
        let miss = Vec3::new(FAR, 0.0, 0.0);
        let f = ray.origin - self.center;
        let b = f.dot(ray.dir);
        let perp = f - b * ray.dir;
        let r2 = self.radius * self.radius;
        let disc = r2 - perp.dot(perp);
        if disc < 0.0 {
            return miss;
        }
        let c = f.dot(f) - r2;
        let q = -b - (if b >= 0.0 { 1.0 } else { -1.0 }) * disc.sqrt();
        if q == 0.0 {
            return miss;
        }
        let t0 = (c / q).min(q);
        let t1 = (c / q).max(q);
        if t0 > 0.0 && t0 < t_max {
            return Vec3::new(t0, 0.0, 0.0);
        }
        if t1 > 0.0 && t1 < t_max {
            return Vec3::new(t1, 0.0, 0.0);
        }
        miss
    }

    fn surface(&self, _b: &Bindings, ray: &Ray, cand: &Candidate) -> Surface {
        let mut s = blank_surface();
        let n = (ray.origin + cand.t * ray.dir - self.center).normalize();
        s.p = self.center + self.radius * n;
        s.ng = n;
        s.ns = n;
        s.uv = Vec2::new(
            (-n.z).atan2(n.x) * (0.5 / PI) + 0.5,
            (-n.y).clamp(-1.0, 1.0).acos() / PI,
        );
        s.err = (max_abs(self.center) + self.radius) * (1.0 / 1048576.0);
        s
    }

    fn uv_derivatives(&self, _b: &Bindings, s: &Surface, _cand: &Candidate) -> [Vec3; 2] {
        let n = s.ng;
        let rho = (n.x * n.x + n.z * n.z).sqrt().max(1e-6);
        [
            2.0 * PI * self.radius * Vec3::new(n.z, 0.0, -n.x),
            PI * self.radius * Vec3::new(-n.y * n.x / rho, rho, -n.y * n.z / rho),
        ]
    }

    /// Uniform in the cone the sphere subtends, or by area from inside.
    fn light_sample(&self, _area: f32, from: Vec3, u: [f32; 2]) -> LightPoint {
        let (center, r) = (self.center, self.radius);
        let oc = center - from;
        let dc2 = oc.dot(oc);
        if self.inside(from) {
            let n = sample_sphere(u);
            let x = center + r * n;
            return LightPoint {
                x,
                pdf: area_pdf(from, x, n, 4.0 * PI * r * r),
                uv: Vec2::ZERO,
            };
        }
        let sin2_max = r * r / dc2;
        let sin_max = sin2_max.sqrt();
        let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
        let mut cos_t = (cos_max - 1.0) * u[0] + 1.0;
        let mut sin2_t = 1.0 - cos_t * cos_t;
        if sin2_max < 0.000_685_23 {
            sin2_t = sin2_max * u[0];
            cos_t = (1.0 - sin2_t).sqrt();
        }
        let cos_a = sin2_t / sin_max + cos_t * (1.0 - sin2_t / sin2_max).max(0.0).sqrt();
        let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
        let phi = 2.0 * PI * u[1];
        let wc = oc / dc2.sqrt();
        let tb = onb_tangents(wc);
        let n = -(sin_a * phi.cos() * tb[0] + sin_a * phi.sin() * tb[1] + cos_a * wc);
        LightPoint {
            x: center + r * n,
            pdf: 1.0 / (2.0 * PI * cone(r, dc2)),
            uv: Vec2::ZERO,
        }
    }

    fn light_pdf(&self, area: f32, from: Vec3, x: Vec3) -> f32 {
        if self.inside(from) {
            return area_pdf(from, x, (x - self.center).normalize(), area);
        }
        let oc = self.center - from;
        1.0 / (2.0 * PI * cone(self.radius, oc.dot(oc)))
    }

    /// From inside, the far root (the way out).
    fn light_distance(&self, from: Vec3, d: Vec3) -> f32 {
        if self.inside(from) {
            let oc = from - self.center;
            let b = oc.dot(d);
            let c = oc.dot(oc) - self.radius * self.radius;
            let t = -b + (b * b - c).max(0.0).sqrt();
            return if t > 0.0 { t } else { FAR };
        }
        self.intersect(
            &Ray {
                origin: from,
                dir: d,
            },
            FAR,
        )
        .x
    }
}

/// sphere.wgsl's `sphere_inside`.
trait Inside {
    fn inside(&self, from: Vec3) -> bool;
}

impl Inside for Params {
    /// Whether `from` is inside the sphere for sampling: within radius x (1 + 1/1024),
    /// squared 1 + 1/512, so that points on the surface sample by area rather than by a
    /// degenerate cone.
    fn inside(&self, from: Vec3) -> bool {
        let v = from - self.center;
        v.dot(v) <= self.radius * self.radius * (1.0 + 1.0 / 512.0)
    }
}

/// 1 - cos(theta_max) of the cone a sphere subtends at squared distance dc2
/// (`sphere_cone`).
pub fn cone(r: f32, dc2: f32) -> f32 {
    let sin2_max = r * r / dc2;
    if sin2_max < 0.000_685_23 {
        return 0.5 * sin2_max;
    }
    1.0 - (1.0 - sin2_max).max(0.0).sqrt()
}
