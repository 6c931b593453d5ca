//! Mirrors `shaders/primitives/box.wgsl`.

use glam::{Vec2, Vec3};

use super::common::ShapeTest;
use crate::cpu::bindings::Bindings;
use crate::cpu::geometry::{argmax3, argmin3, blank_surface, safe_inverse};
use crate::cpu::sampling::max_abs;
use crate::cpu::types::{Candidate, Ray, Surface, FAR};
use crate::scene::primitives::r#box::Params;

impl ShapeTest for Params {
    /// Slab method. Returns (t, axis of the face, 0); t = FAR on a miss.
    fn intersect(&self, ray: &Ray, t_max: f32) -> Vec3 {
        let inv = safe_inverse(ray.dir);
        let t0 = (self.lo - ray.origin) * inv;
        let t1 = (self.hi - ray.origin) * inv;
        let t_min = t0.min(t1);
        let t_max3 = t0.max(t1);
        let t_near = t_min.x.max(t_min.y.max(t_min.z));
        let t_far = t_max3.x.min(t_max3.y.min(t_max3.z));
        if t_near <= t_far {
            if t_near > 0.0 && t_near < t_max {
                return Vec3::new(t_near, argmax3(t_min) as f32, 0.0);
            }
            if t_far > 0.0 && t_far < t_max {
                return Vec3::new(t_far, argmin3(t_max3) as f32, 0.0);
            }
        }
        Vec3::new(FAR, 0.0, 0.0)
    }

    fn surface(&self, _b: &Bindings, ray: &Ray, cand: &Candidate) -> Surface {
        let mut s = blank_surface();
        let (lo, hi) = (self.lo, self.hi);
        let axis = cand.u as usize;
        let mut q = ray.origin + cand.t * ray.dir;
        let upper = q[axis] > 0.5 * (lo[axis] + hi[axis]);
        q[axis] = if upper { hi[axis] } else { lo[axis] };
        let mut n = Vec3::ZERO;
        n[axis] = if upper { 1.0 } else { -1.0 };
        let i = (axis + 1) % 3;
        let j = (axis + 2) % 3;
        s.p = q;
        s.ng = n;
        s.ns = n;
        s.uv = Vec2::new(
            (q[i] - lo[i]) / (hi[i] - lo[i]),
            (q[j] - lo[j]) / (hi[j] - lo[j]),
        );
        s.err = max_abs(lo).max(max_abs(hi)) * (1.0 / 1048576.0);
        s
    }

    fn uv_derivatives(&self, _b: &Bindings, _s: &Surface, cand: &Candidate) -> [Vec3; 2] {
        let axis = cand.u as usize;
        let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut d = [Vec3::ZERO; 2];
        d[0][i] = self.hi[i] - self.lo[i];
        d[1][j] = self.hi[j] - self.lo[j];
        d
    }
}
