//! Mirrors `shaders/primitives/cylinder.wgsl`.

use glam::{Vec2, Vec3};

use super::common::ShapeTest;
use crate::cpu::bindings::Bindings;
use crate::cpu::geometry::{angle_uv, blank_surface, intersect_disk};
use crate::cpu::sampling::{max_abs, onb_tangents, PI};
use crate::cpu::types::{Candidate, Ray, Surface, FAR};
use crate::scene::primitives::cylinder::Params;
use crate::scene::records::PRIM_FLAG_CAPS;

impl ShapeTest for Params {
    /// Stable quadratic for the side, the caps with `PRIM_FLAG_CAPS`. Returns (t, part,
    /// 0): 0 side, 1 base cap, 2 top cap; t = FAR on a miss.
    fn intersect(&self, ray: &Ray, t_max: f32) -> Vec3 {
        let (base, top, radius) = (self.base, self.top, self.radius);
        let axis = top - base;
        let h = axis.length();
        let ax = axis / h;
        let oc = ray.origin - base;
        let o_ax = oc.dot(ax);
        let d_ax = ray.dir.dot(ax);
        let op = oc - o_ax * ax;
        let dp = ray.dir - d_ax * ax;
        let mut best = Vec3::new(FAR, 0.0, 0.0);
        let mut t_lim = t_max;
        let a = dp.dot(dp);
        if a > 1e-20 {
            let b = op.dot(dp);
            let perp = op - (b / a) * dp;
            let r2 = radius * radius;
            let disc = r2 - perp.dot(perp);
            if disc >= 0.0 {
                let c = op.dot(op) - r2;
                let q = -b - (if b >= 0.0 { 1.0 } else { -1.0 }) * (a * disc).sqrt();
                if q != 0.0 {
                    let t0 = (q / a).min(c / q);
                    let t1 = (q / a).max(c / q);
                    let s0 = o_ax + t0 * d_ax;
                    let s1 = o_ax + t1 * d_ax;
                    if t0 > 0.0 && t0 < t_lim && s0 >= 0.0 && s0 <= h {
                        best = Vec3::new(t0, 0.0, 0.0);
                        t_lim = t0;
                    } else if t1 > 0.0 && t1 < t_lim && s1 >= 0.0 && s1 <= h {
                        best = Vec3::new(t1, 0.0, 0.0);
                        t_lim = t1;
                    }
                }
            }
        }
        if self.flags & PRIM_FLAG_CAPS != 0 {
            let t_base = intersect_disk(base, ax, radius, ray, t_lim);
            if t_base < t_lim {
                best = Vec3::new(t_base, 1.0, 0.0);
                t_lim = t_base;
            }
            let t_top = intersect_disk(top, ax, radius, ray, t_lim);
            if t_top < t_lim {
                best = Vec3::new(t_top, 2.0, 0.0);
            }
        }
        best
    }

    fn surface(&self, _b: &Bindings, ray: &Ray, cand: &Candidate) -> Surface {
        let mut s = blank_surface();
        let (base, top, radius) = (self.base, self.top, self.radius);
        let axis = top - base;
        let h = axis.length();
        let ax = axis / h;
        let q = ray.origin + cand.t * ray.dir - base;
        let q_ax = q.dot(ax);
        let radial = q - q_ax * ax;
        if cand.u == 0.0 {
            let n = radial.normalize();
            let height = q_ax.clamp(0.0, h);
            s.p = base + height * ax + radius * n;
            s.ng = n;
            s.uv = Vec2::new(angle_uv(n, ax), height / h);
        } else {
            let top_cap = cand.u == 2.0;
            s.p = (if top_cap { top } else { base }) + radial;
            s.ng = if top_cap { ax } else { -ax };
            s.uv = Vec2::new(angle_uv(radial, ax), radial.length() / radius);
        }
        s.ns = s.ng;
        s.err = (max_abs(base).max(max_abs(top)) + radius) * (1.0 / 1048576.0);
        s
    }

    fn uv_derivatives(&self, _b: &Bindings, s: &Surface, cand: &Candidate) -> [Vec3; 2] {
        let axis = self.top - self.base;
        let ax = axis.normalize();
        let q = s.p - self.base;
        let radial = q - q.dot(ax) * ax;
        let len = radial.length().max(1e-12);
        let tb = onb_tangents(ax);
        let c = radial / len;
        let around = c.dot(tb[0]) * tb[1] - c.dot(tb[1]) * tb[0];
        [
            2.0 * PI * len * around,
            if cand.u == 0.0 { axis } else { c * self.radius },
        ]
    }
}
