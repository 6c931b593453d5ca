//! Mirrors `shaders/primitives/triangle.wgsl`.

use glam::{Vec2, Vec3, Vec4};

use super::common::ShapeTest;
use crate::cpu::bindings::Bindings;
use crate::cpu::geometry::{area_pdf, argmax3, blank_surface};
use crate::cpu::sampling::{max_abs, onb_tangents};
use crate::cpu::types::{Candidate, LightPoint, Ray, Surface, FAR};
use crate::scene::primitives::triangle::Params;
use crate::scene::records::{
    ATTRIBUTE_ENTRIES, PRIM_FLAG_ATTRIBUTES, PRIM_FLAG_COLORS, PRIM_FLAG_SHADING_NORMALS,
    PRIM_FLAG_TANGENTS, PRIM_FLAG_UV1, TANGENT_ENTRIES, UV1_ENTRIES,
};

fn row(b: &Bindings, i: u32) -> Vec4 {
    Vec4::from_array(b.shape_data[i as usize])
}

impl ShapeTest for Params {
    /// Watertight (Woop, Benthin and Wald 2013): edge functions in the ray's sheared
    /// frame, zero counting as inside. Returns (t, b1, b2); t = FAR on a miss. Both sides
    /// are hit.
    fn intersect(&self, ray: &Ray, t_max: f32) -> Vec3 {
        let miss = Vec3::new(FAR, 0.0, 0.0);
        let d = ray.dir;
        let kz = argmax3(d.abs()) as usize;
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let sz = 1.0 / d[kz];
        let sx = d[kx] * sz;
        let sy = d[ky] * sz;
        let (a, b, c) = (
            self.v0 - ray.origin,
            self.v1 - ray.origin,
            self.v2 - ray.origin,
        );
        let ax = a[kx] - sx * a[kz];
        let ay = a[ky] - sy * a[kz];
        let bx = b[kx] - sx * b[kz];
        let by = b[ky] - sy * b[kz];
        let cx = c[kx] - sx * c[kz];
        let cy = c[ky] - sy * c[kz];
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return miss;
        }
        let det = u + v + w;
        if det == 0.0 {
            return miss;
        }
        let t = (u * (sz * a[kz]) + v * (sz * b[kz]) + w * (sz * c[kz])) / det;
        // Written as in WGSL, so a NaN takes the same branch on both backends.
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        if !(t > 0.0) || t >= t_max {
            return miss;
        }
        Vec3::new(t, v / det, w / det)
    }

    fn surface(&self, b: &Bindings, _ray: &Ray, cand: &Candidate) -> Surface {
        let mut s = blank_surface();
        let (v0, v1, v2) = (self.v0, self.v1, self.v2);
        let (flags, data) = (self.flags, self.data);
        let w = Vec3::new(1.0 - cand.u - cand.v, cand.u, cand.v);
        s.p = w.x * v0 + w.y * v1 + w.z * v2;
        s.ng = (v1 - v0).cross(v2 - v0).normalize();
        s.ns = s.ng;
        s.uv = Vec2::new(cand.u, cand.v);
        s.err = max_abs(v0).max(max_abs(v1).max(max_abs(v2))) * (1.0 / 2097152.0);
        if flags & PRIM_FLAG_ATTRIBUTES != 0 {
            let (a0, a1) = (row(b, data), row(b, data + 1));
            let (a2, a3) = (row(b, data + 2), row(b, data + 3));
            s.uv = w.x * Vec2::new(a0.w, a3.x)
                + w.y * Vec2::new(a1.w, a3.y)
                + w.z * Vec2::new(a2.w, a3.z);
            if flags & PRIM_FLAG_SHADING_NORMALS != 0 {
                let n = w.x * a0.truncate() + w.y * a1.truncate() + w.z * a2.truncate();
                let len = n.length();
                if len > 0.0 {
                    let sign = if n.dot(s.ng) >= 0.0 { 1.0 } else { -1.0 };
                    s.ns = n * (sign / len);
                }
            }
            if flags & PRIM_FLAG_TANGENTS != 0 {
                let (t0, t1) = (row(b, data + 4), row(b, data + 5));
                let t2 = row(b, data + 6);
                let t = w.x * t0.truncate() + w.y * t1.truncate() + w.z * t2.truncate();
                // normals turned to ng's side turn the bitangent with them
                let nv = w.x * a0.truncate() + w.y * a1.truncate() + w.z * a2.truncate();
                let turned = flags & PRIM_FLAG_SHADING_NORMALS != 0 && nv.dot(s.ng) < 0.0;
                s.tangent = t.extend(if turned { -t0.w } else { t0.w });
            }
            // the second uv set and the vertex colours follow the tangents
            let mut extra = data
                + ATTRIBUTE_ENTRIES
                + if flags & PRIM_FLAG_TANGENTS != 0 {
                    TANGENT_ENTRIES
                } else {
                    0
                };
            if flags & PRIM_FLAG_UV1 != 0 {
                let (u01, u2) = (row(b, extra), row(b, extra + 1));
                let (a, c, e) = (
                    Vec2::new(u01.x, u01.y),
                    Vec2::new(u01.z, u01.w),
                    Vec2::new(u2.x, u2.y),
                );
                s.uv1 = w.x * a + w.y * c + w.z * e;
                extra += UV1_ENTRIES;
            }
            if flags & PRIM_FLAG_COLORS != 0 {
                s.color = w.x * row(b, extra) + w.y * row(b, extra + 1) + w.z * row(b, extra + 2);
            }
        }
        s
    }

    fn uv_derivatives(&self, b: &Bindings, s: &Surface, _cand: &Candidate) -> [Vec3; 2] {
        let mut d = onb_tangents(s.ng);
        let (mut uv0, mut uv1, mut uv2) = (Vec2::ZERO, Vec2::X, Vec2::Y);
        if self.flags & PRIM_FLAG_ATTRIBUTES != 0 {
            let a3 = row(b, self.data + 3);
            uv0 = Vec2::new(row(b, self.data).w, a3.x);
            uv1 = Vec2::new(row(b, self.data + 1).w, a3.y);
            uv2 = Vec2::new(row(b, self.data + 2).w, a3.z);
        }
        let (duv02, duv12) = (uv0 - uv2, uv1 - uv2);
        let (dp02, dp12) = (self.v0 - self.v2, self.v1 - self.v2);
        let det = duv02.x * duv12.y - duv02.y * duv12.x;
        if det.abs() > 1e-12 {
            d[0] = (duv12.y * dp02 - duv02.y * dp12) / det;
            d[1] = (duv02.x * dp12 - duv12.x * dp02) / det;
        }
        d
    }

    /// Uniform by area; uv the barycentrics of v1 and v2.
    fn light_sample(&self, area: f32, from: Vec3, u: [f32; 2]) -> LightPoint {
        let su = u[0].sqrt();
        let wa = 1.0 - su;
        let wb = u[1] * su;
        let x = wa * self.v0 + wb * self.v1 + (1.0 - wa - wb) * self.v2;
        let n = (self.v1 - self.v0).cross(self.v2 - self.v0).normalize();
        LightPoint {
            x,
            pdf: area_pdf(from, x, n, area),
            uv: Vec2::new(wb, 1.0 - wa - wb),
        }
    }

    fn light_pdf(&self, area: f32, from: Vec3, x: Vec3) -> f32 {
        let n = (self.v1 - self.v0).cross(self.v2 - self.v0).normalize();
        area_pdf(from, x, n, area)
    }

    fn light_distance(&self, from: Vec3, d: Vec3) -> f32 {
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
