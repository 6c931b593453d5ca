//! Mirrors `shaders/shared/intersect.wgsl`.

use glam::Vec3;

use super::bindings::Bindings;
use super::sampling::max_abs;
use super::types::{xyz, Candidate, Hit, Ray, FAR, NO_HIT};
use crate::scene::records::{Primitive, PRIM_SPHERE, PRIM_TRIANGLE};

/// Sphere, numerically stable form (Ray Tracing Gems, chapter 7). `ray.dir` is unit length.
/// Returns the nearest root in (0, t_max), else FAR.
pub fn intersect_sphere(center: Vec3, radius: f32, ray: &Ray, t_max: f32) -> f32 {
    let f = ray.origin - center;
    let b = f.dot(ray.dir);
    let perp = f - b * ray.dir;
    let r2 = radius * radius;
    let disc = r2 - perp.dot(perp);
    if disc < 0.0 {
        return FAR;
    }
    let c = f.dot(f) - r2;
    let q = -b - (if b >= 0.0 { 1.0 } else { -1.0 }) * disc.sqrt();
    if q == 0.0 {
        return FAR;
    }
    let t0 = (c / q).min(q);
    let t1 = (c / q).max(q);
    if t0 > 0.0 && t0 < t_max {
        return t0;
    }
    if t1 > 0.0 && t1 < t_max {
        return t1;
    }
    FAR
}

/// Triangle (Moeller-Trumbore). Returns (t, b1, b2); t = FAR on a miss. Both sides are hit.
pub fn intersect_triangle(v0: Vec3, v1: Vec3, v2: Vec3, ray: &Ray, t_max: f32) -> Vec3 {
    let miss = Vec3::new(FAR, 0.0, 0.0);
    let e1 = v1 - v0;
    let e2 = v2 - v0;
    let pv = ray.dir.cross(e2);
    let det = e1.dot(pv);
    if det == 0.0 {
        return miss;
    }
    let inv_det = 1.0 / det;
    let tv = ray.origin - v0;
    let b1 = tv.dot(pv) * inv_det;
    // Written as in WGSL (not `contains`), so a NaN takes the same branch on both backends.
    #[allow(clippy::manual_range_contains)]
    if b1 < 0.0 || b1 > 1.0 {
        return miss;
    }
    let qv = tv.cross(e1);
    let b2 = ray.dir.dot(qv) * inv_det;
    if b2 < 0.0 || b1 + b2 > 1.0 {
        return miss;
    }
    let t = e2.dot(qv) * inv_det;
    if t <= 0.0 || t >= t_max {
        return miss;
    }
    Vec3::new(t, b1, b2)
}

/// Closest hit along the ray among all primitives.
pub fn intersect_scene(b: &Bindings, ray: &Ray) -> Candidate {
    let mut best = Candidate {
        t: FAR,
        prim: NO_HIT,
        u: 0.0,
        v: 0.0,
    };
    for (i, prim) in b.primitives[..b.params.num_primitives as usize]
        .iter()
        .enumerate()
    {
        match prim.tag {
            PRIM_SPHERE => {
                let t = intersect_sphere(xyz(prim.a), prim.a[3], ray, best.t);
                if t < best.t {
                    best = Candidate {
                        t,
                        prim: i as u32,
                        u: 0.0,
                        v: 0.0,
                    };
                }
            }
            PRIM_TRIANGLE => {
                let h = intersect_triangle(xyz(prim.a), xyz(prim.b), xyz(prim.c), ray, best.t);
                if h.x < best.t {
                    best = Candidate {
                        t: h.x,
                        prim: i as u32,
                        u: h.y,
                        v: h.z,
                    };
                }
            }
            _ => {}
        }
    }
    best
}

/// Shading record of a candidate hit, with the point recomputed from the primitive.
pub fn surface_at(b: &Bindings, ray: &Ray, cand: &Candidate) -> Hit {
    let prim: &Primitive = &b.primitives[cand.prim as usize];
    let mut p = Vec3::ZERO;
    let mut ng = Vec3::Z;
    let mut err = 0.0;
    match prim.tag {
        PRIM_SPHERE => {
            let center = xyz(prim.a);
            let radius = prim.a[3];
            ng = (ray.origin + cand.t * ray.dir - center).normalize();
            p = center + radius * ng;
            err = (max_abs(center) + radius) * (1.0 / 1048576.0);
        }
        PRIM_TRIANGLE => {
            let (v0, v1, v2) = (xyz(prim.a), xyz(prim.b), xyz(prim.c));
            p = (1.0 - cand.u - cand.v) * v0 + cand.u * v1 + cand.v * v2;
            ng = (v1 - v0).cross(v2 - v0).normalize();
            err = max_abs(v0).max(max_abs(v1).max(max_abs(v2))) * (1.0 / 2097152.0);
        }
        _ => {}
    }
    Hit {
        p,
        ng,
        front_face: ray.dir.dot(ng) < 0.0,
        material: prim.material,
        err,
    }
}
