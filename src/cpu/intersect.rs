//! Mirrors `shaders/shared/intersect.wgsl`: the same functions, in the same order, with the
//! same operations, so both backends find the same hits.

use glam::{Vec2, Vec3, Vec4};

use super::bindings::Bindings;
use super::sampling::{max_abs, onb_tangents, PI};
use super::types::{xyz, Candidate, Hit, Ray, FAR, NO_HIT};
use crate::scene::records::{
    BvhNode, Primitive, ATTRIBUTE_ENTRIES, BVH_NODE_BITS, BVH_SLAB_ERROR, BVH_STACK_SIZE, PRIM_BOX,
    PRIM_CYLINDER, PRIM_DISK, PRIM_FLAG_ATTRIBUTES, PRIM_FLAG_CAPS, PRIM_FLAG_COLORS,
    PRIM_FLAG_SHADING_NORMALS, PRIM_FLAG_TANGENTS, PRIM_FLAG_TRANSFORM, PRIM_FLAG_UV1, PRIM_PLANE,
    PRIM_SPHERE, PRIM_TRIANGLE, TANGENT_ENTRIES, UV1_ENTRIES,
};

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

/// Triangle, watertight (Woop, Benthin and Wald 2013): edge functions in the ray's sheared
/// frame, zero counting as inside. Returns (t, b1, b2); t = FAR on a miss. Both sides are hit.
pub fn intersect_triangle(v0: Vec3, v1: Vec3, v2: Vec3, ray: &Ray, t_max: f32) -> Vec3 {
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
    let (a, b, c) = (v0 - ray.origin, v1 - ray.origin, v2 - ray.origin);
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

/// Plane through `point` with unit normal n; a ray parallel to it is a miss, t is finite.
pub fn intersect_plane(point: Vec3, n: Vec3, ray: &Ray, t_max: f32) -> f32 {
    let denom = ray.dir.dot(n);
    let num = -(ray.origin - point).dot(n);
    if num * denom > 0.0 && num.abs() < t_max * denom.abs() {
        return num / denom;
    }
    FAR
}

/// Disk: the plane of unit normal n through `center`, within `radius` of the center.
pub fn intersect_disk(center: Vec3, n: Vec3, radius: f32, ray: &Ray, t_max: f32) -> f32 {
    let t = intersect_plane(center, n, ray, t_max);
    if t < FAR {
        let q = ray.origin + t * ray.dir - center;
        if q.dot(q) <= radius * radius {
            return t;
        }
    }
    FAR
}

/// 1 / d with zero and tiny components first replaced by +-1e-30 (zero taken as +).
pub fn safe_inverse(d: Vec3) -> Vec3 {
    let tiny = Vec3::select(d.cmplt(Vec3::ZERO), Vec3::splat(-1e-30), Vec3::splat(1e-30));
    Vec3::ONE / Vec3::select(d.abs().cmplt(Vec3::splat(1e-30)), tiny, d)
}

/// Index of the largest component (the first of equals).
pub fn argmax3(v: Vec3) -> u32 {
    if v.x >= v.y && v.x >= v.z {
        return 0;
    }
    if v.y >= v.z {
        1
    } else {
        2
    }
}

/// Index of the smallest component (the first of equals).
pub fn argmin3(v: Vec3) -> u32 {
    if v.x <= v.y && v.x <= v.z {
        return 0;
    }
    if v.y <= v.z {
        1
    } else {
        2
    }
}

/// Axis-aligned box, slab method. Returns (t, axis of the face); t = FAR on a miss.
pub fn intersect_box(lo: Vec3, hi: Vec3, ray: &Ray, t_max: f32) -> Vec2 {
    let inv = safe_inverse(ray.dir);
    let t0 = (lo - ray.origin) * inv;
    let t1 = (hi - ray.origin) * inv;
    let t_min = t0.min(t1);
    let t_max3 = t0.max(t1);
    let t_near = t_min.x.max(t_min.y.max(t_min.z));
    let t_far = t_max3.x.min(t_max3.y.min(t_max3.z));
    if t_near <= t_far {
        if t_near > 0.0 && t_near < t_max {
            return Vec2::new(t_near, argmax3(t_min) as f32);
        }
        if t_far > 0.0 && t_far < t_max {
            return Vec2::new(t_far, argmin3(t_max3) as f32);
        }
    }
    Vec2::new(FAR, 0.0)
}

/// Finite cylinder from `base` to `top`, stable quadratic for the side, optional caps.
/// Returns (t, part): 0 side, 1 base cap, 2 top cap; t = FAR on a miss.
pub fn intersect_cylinder(
    base: Vec3,
    top: Vec3,
    radius: f32,
    caps: bool,
    ray: &Ray,
    t_max: f32,
) -> Vec2 {
    let axis = top - base;
    let h = axis.length();
    let ax = axis / h;
    let oc = ray.origin - base;
    let o_ax = oc.dot(ax);
    let d_ax = ray.dir.dot(ax);
    let op = oc - o_ax * ax;
    let dp = ray.dir - d_ax * ax;
    let mut best = Vec2::new(FAR, 0.0);
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
                    best = Vec2::new(t0, 0.0);
                    t_lim = t0;
                } else if t1 > 0.0 && t1 < t_lim && s1 >= 0.0 && s1 <= h {
                    best = Vec2::new(t1, 0.0);
                    t_lim = t1;
                }
            }
        }
    }
    if caps {
        let t_base = intersect_disk(base, ax, radius, ray, t_lim);
        if t_base < t_lim {
            best = Vec2::new(t_base, 1.0);
            t_lim = t_base;
        }
        let t_top = intersect_disk(top, ax, radius, ray, t_lim);
        if t_top < t_lim {
            best = Vec2::new(t_top, 2.0);
        }
    }
    best
}

fn row(b: &Bindings, i: u32) -> Vec4 {
    Vec4::from_array(b.shape_data[i as usize])
}

/// The world-to-object transform applied to a ray (direction not normalized).
pub fn ray_to_object(b: &Bindings, data: u32, ray: &Ray) -> Ray {
    let (r0, r1, r2) = (row(b, data), row(b, data + 1), row(b, data + 2));
    let o = ray.origin.extend(1.0);
    Ray {
        origin: Vec3::new(r0.dot(o), r1.dot(o), r2.dot(o)),
        dir: Vec3::new(
            r0.truncate().dot(ray.dir),
            r1.truncate().dot(ray.dir),
            r2.truncate().dot(ray.dir),
        ),
    }
}

/// An object-space point in world space.
pub fn point_to_world(b: &Bindings, data: u32, p: Vec3) -> Vec3 {
    let o = p.extend(1.0);
    Vec3::new(
        row(b, data + 3).dot(o),
        row(b, data + 4).dot(o),
        row(b, data + 5).dot(o),
    )
}

/// An object-space normal in world space (transpose of the world-to-object linear part).
pub fn normal_to_world(b: &Bindings, data: u32, n: Vec3) -> Vec3 {
    (row(b, data).truncate() * n.x
        + row(b, data + 1).truncate() * n.y
        + row(b, data + 2).truncate() * n.z)
        .normalize()
}

/// Error bound of a point mapped to world space.
pub fn transform_error(b: &Bindings, data: u32, p: Vec3, err: f32) -> f32 {
    let mut e = 0.0f32;
    for k in 0..3 {
        let r = row(b, data + 3 + k);
        let m = r.truncate().abs();
        e = e.max((m.x + m.y + m.z) * err + (m.dot(p.abs()) + r.w.abs()) * (1.0 / 2097152.0));
    }
    e
}

/// One primitive of type `tag` in its own space: (t, u, v) as in Candidate.
pub fn intersect_local(prim: &Primitive, tag: u32, ray: &Ray, t_max: f32) -> Vec3 {
    let (a, b) = (xyz(prim.a), xyz(prim.b));
    match tag {
        PRIM_SPHERE => Vec3::new(intersect_sphere(a, prim.a[3], ray, t_max), 0.0, 0.0),
        PRIM_TRIANGLE => intersect_triangle(a, b, xyz(prim.c), ray, t_max),
        PRIM_PLANE => Vec3::new(intersect_plane(a, b, ray, t_max), 0.0, 0.0),
        PRIM_BOX => intersect_box(a, b, ray, t_max).extend(0.0),
        PRIM_CYLINDER => {
            let caps = prim.flags & PRIM_FLAG_CAPS != 0;
            intersect_cylinder(a, b, prim.a[3], caps, ray, t_max).extend(0.0)
        }
        PRIM_DISK => Vec3::new(intersect_disk(a, b, prim.a[3], ray, t_max), 0.0, 0.0),
        _ => Vec3::new(FAR, 0.0, 0.0),
    }
}

/// Primitive i in world space; transformed primitives in object space with a unit direction.
pub fn intersect_primitive(b: &Bindings, i: u32, ray: &Ray, t_max: f32) -> Vec3 {
    let prim = &b.primitives[i as usize];
    intersect_record(b, prim, prim.tag, ray, t_max)
}

/// intersect_primitive for a record already fetched, of type `tag` (the shader's per-type
/// loops pass a literal; the CPU's single loop visits the same indices in the same order
/// through intersect_primitive).
pub fn intersect_record(b: &Bindings, prim: &Primitive, tag: u32, ray: &Ray, t_max: f32) -> Vec3 {
    if prim.flags & PRIM_FLAG_TRANSFORM == 0 {
        return intersect_local(prim, tag, ray, t_max);
    }
    let r = ray_to_object(b, prim.data, ray);
    let scale = r.dir.length();
    let t_lim = t_max.min(FAR / scale.max(1.0)) * scale;
    let local = Ray {
        origin: r.origin,
        dir: r.dir / scale,
    };
    let h = intersect_local(prim, tag, &local, t_lim);
    if h.x < FAR {
        return Vec3::new(h.x / scale, h.y, h.z);
    }
    h
}

/// intersect_primitive for a primitive of the BVH (the shader skips the tag's switch
/// when they are all untransformed triangles: the same test).
pub fn intersect_bounded(b: &Bindings, i: u32, ray: &Ray, t_max: f32) -> Vec3 {
    intersect_primitive(b, i, ray, t_max)
}

/// The closer of the closest hit so far and hit h = (t, u, v) of primitive i.
pub fn closer_hit(best: Candidate, i: u32, h: Vec3) -> Candidate {
    if h.x < best.t {
        return Candidate {
            t: h.x,
            prim: i,
            u: h.y,
            v: h.z,
        };
    }
    best
}

/// Primitive i tested against the closest hit so far; the closer of the two.
pub fn closer(b: &Bindings, best: Candidate, i: u32, ray: &Ray) -> Candidate {
    closer_hit(best, i, intersect_primitive(b, i, ray, best.t))
}

/// The walk's order among a node's children: a child node hit is marked in bit 24 + (slot
/// ^ bvh_order) of the hit mask and the highest bit is taken first, so a ray whose
/// direction has the signs of octant o (bit 0: x < 0, bit 1: y, bit 2: z) takes slot o
/// first, where `bvh::collapse` puts the child such rays enter first.
pub fn bvh_order(inv_dir: Vec3) -> u32 {
    let octant = (inv_dir.x < 0.0) as u32
        | ((inv_dir.y < 0.0) as u32) << 1
        | ((inv_dir.z < 0.0) as u32) << 2;
    octant ^ 7
}

/// Four bytes of a word, from the low one, as numbers.
pub fn bvh_bytes(w: u32) -> Vec4 {
    Vec4::new(
        (w & 255) as f32,
        (w >> 8 & 255) as f32,
        (w >> 16 & 255) as f32,
        (w >> 24) as f32,
    )
}

/// min and max of numbers that are not NaN, as the shader's selects.
pub fn min4(a: Vec4, b: Vec4) -> Vec4 {
    Vec4::select(a.cmplt(b), a, b)
}

pub fn max4(a: Vec4, b: Vec4) -> Vec4 {
    Vec4::select(a.cmpgt(b), a, b)
}

/// Which of four children a ray enters before t_max: their planes' bytes on the near
/// and the far side of each axis, the slab distance of a step per axis and of the
/// node's origin, less (near) or plus (far) its error bound.
pub fn bvh_slabs(
    near: [u32; 3],
    far: [u32; 3],
    step_t: Vec3,
    near_t: Vec3,
    far_t: Vec3,
    t_max: f32,
) -> [bool; 4] {
    let plane = |w: u32, a: usize, t0: Vec3| bvh_bytes(w) * step_t[a] + Vec4::splat(t0[a]);
    let t_near = max4(
        max4(plane(near[0], 0, near_t), plane(near[1], 1, near_t)),
        max4(plane(near[2], 2, near_t), Vec4::ZERO),
    );
    let t_far = min4(
        min4(plane(far[0], 0, far_t), plane(far[1], 1, far_t)),
        plane(far[2], 2, far_t),
    );
    (t_near.cmple(t_far) & t_near.cmplt(Vec4::splat(t_max))).into()
}

/// The bits four children mark in the hit mask when hit (`BvhNode`'s meta bytes): a
/// node's moved by the walk's order, a leaf's its primitives.
pub fn bvh_child_bits(bytes: u32, inner: u32, order: u32) -> [u32; 4] {
    let mut bits = [0; 4];
    for (i, b) in bits.iter_mut().enumerate() {
        let mut m = bytes >> (8 * i) & 255;
        m ^= (inner >> i & 1) * order;
        *b = (m >> 5) << (m & 31);
    }
    bits
}

/// Node n's children that a ray enters before t_max, as the walk's next two groups:
/// (first child node, hit child nodes' bits | imask, first primitive, hit primitives'
/// bits). The quantized boxes' slab distances are (origin - ray origin) / d + q step / d
/// per axis; widened by BVH_SLAB_ERROR of the magnitudes that form them, they bound the
/// exact ones whatever cancels.
pub fn bvh_node_hits(n: &BvhNode, origin: Vec3, inv_dir: Vec3, order: u32, t_max: f32) -> [u32; 4] {
    let step = Vec3::new(
        f32::from_bits((n.scale & 255) << 23),
        f32::from_bits((n.scale >> 8 & 255) << 23),
        f32::from_bits((n.scale >> 16 & 255) << 23),
    );
    let rel = Vec3::from(n.origin) - origin;
    let origin_t = rel * inv_dir;
    let step_t = (step * inv_dir)
        .max(Vec3::splat(-f32::MAX))
        .min(Vec3::splat(f32::MAX));
    let err =
        ((rel.abs() + 256.0 * step) * inv_dir.abs()).min(Vec3::splat(f32::MAX)) * BVH_SLAB_ERROR;
    let near_t = origin_t - err;
    let far_t = origin_t + err;
    let lo = [[n.q0[0], n.q0[1]], [n.q0[2], n.q0[3]], [n.q1[0], n.q1[1]]];
    let hi = [[n.q1[2], n.q1[3]], [n.q2[0], n.q2[1]], [n.q2[2], n.q2[3]]];
    let imask = n.scale >> 24;
    let mut hits = 0;
    for (h, meta) in [n.meta0, n.meta1].into_iter().enumerate() {
        let side = |a: usize, near: bool| {
            if (inv_dir[a] < 0.0) == near {
                hi[a][h]
            } else {
                lo[a][h]
            }
        };
        let near = [side(0, true), side(1, true), side(2, true)];
        let far = [side(0, false), side(1, false), side(2, false)];
        let hit = bvh_slabs(near, far, step_t, near_t, far_t, t_max);
        let bits = bvh_child_bits(meta, imask >> (4 * h), order);
        for i in 0..4 {
            if hit[i] {
                hits |= bits[i];
            }
        }
    }
    [
        n.child,
        (hits & BVH_NODE_BITS) | imask,
        n.prim,
        hits & !BVH_NODE_BITS,
    ]
}

/// The BVH walk of intersect_scene and occluded_bvh, over a closure: `test(k, t)` tests
/// primitive k against the bound t and returns the new bound, or None to end the walk.
/// A walk holds two groups of a node's children hit by the ray: child nodes (the first's
/// index, their bits in the hit mask above the node's imask) and primitives (the first's
/// index, their bits). It takes the child nodes one at a time in the hit mask's order,
/// pushing the rest of their group, and tests a group of primitives as soon as it has one
/// (the shader when every lane of its subgroup has one: the same order per lane).
pub fn bvh_walk(
    nodes: &[BvhNode],
    ray: &Ray,
    t_max: f32,
    mut test: impl FnMut(u32, f32) -> Option<f32>,
) {
    let inv_dir = safe_inverse(ray.dir);
    let order = bvh_order(inv_dir);
    let mut stack = [[0u32; 2]; BVH_STACK_SIZE as usize];
    let mut sp = 0usize;
    // the root: a group of one child node, in slot 0
    let mut group = [0u32, (1 << (24 + order)) | 1];
    let mut t = t_max;
    loop {
        if group[1] & BVH_NODE_BITS == 0 {
            if sp == 0 {
                return;
            }
            sp -= 1;
            group = stack[sp];
        }
        let bit = 31 - group[1].leading_zeros();
        group[1] ^= 1 << bit;
        let slot = (bit - 24) ^ order;
        let index = group[0] + (group[1] & ((1 << slot) - 1)).count_ones();
        if group[1] & BVH_NODE_BITS != 0 {
            stack[sp] = group;
            sp += 1;
        }
        let [child, nodes_hit, prim, mut prims] =
            bvh_node_hits(&nodes[index as usize], ray.origin, inv_dir, order, t);
        group = [child, nodes_hit];
        while prims != 0 {
            let k = prim + prims.trailing_zeros();
            prims &= prims - 1;
            match test(k, t) {
                Some(bound) => t = bound,
                None => return,
            }
        }
    }
}

/// Whether anything lies along the ray before t_max (a shadow ray): the same answer as
/// `intersect_scene(b, ray, t_max).prim != NO_HIT`. With the BVH it is an any-hit search
/// (occluded_bvh); the shader's twin also searches a small scene's primitives written
/// into it for any hit.
pub fn occluded(b: &Bindings, ray: &Ray, t_max: f32) -> bool {
    if b.params.use_bvh != 0 {
        return occluded_bvh(b, ray, t_max);
    }
    intersect_scene(b, ray, t_max).prim != NO_HIT
}

/// The any-hit search of occluded over the planes and the BVH: stops at the first
/// primitive in range; boxes are culled against t_max only.
pub fn occluded_bvh(b: &Bindings, ray: &Ray, t_max: f32) -> bool {
    let p = &b.params;
    if (0..p.num_unbounded).any(|i| intersect_primitive(b, i, ray, t_max).x < t_max) {
        return true;
    }
    if p.num_primitives == p.num_unbounded {
        return false;
    }
    let mut hit = false;
    bvh_walk(b.bvh, ray, t_max, |k, t| {
        hit = intersect_bounded(b, k, ray, t).x < t;
        (!hit).then_some(t)
    });
    hit
}

/// Closest hit along the ray before t_max: planes, then the BVH in order (or every
/// primitive).
pub fn intersect_scene(b: &Bindings, ray: &Ray, t_max: f32) -> Candidate {
    let p = &b.params;
    let mut best = Candidate {
        t: t_max,
        prim: NO_HIT,
        u: 0.0,
        v: 0.0,
    };
    for i in 0..p.num_unbounded {
        best = closer(b, best, i, ray);
    }
    if p.use_bvh == 0 {
        for i in p.num_unbounded..p.num_primitives {
            best = closer(b, best, i, ray);
        }
        return best;
    }
    if p.num_primitives == p.num_unbounded {
        return best;
    }
    bvh_walk(b.bvh, ray, best.t, |k, t| {
        best = closer_hit(best, k, intersect_bounded(b, k, ray, t));
        Some(best.t)
    });
    best
}

/// A hit in a primitive's own space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Surface {
    pub p: Vec3,
    pub ng: Vec3,
    pub ns: Vec3,
    pub uv: Vec2,
    pub err: f32,
    pub tangent: Vec4,
    /// A triangle's second uv set (`PRIM_FLAG_UV1`) and vertex colour
    /// (`PRIM_FLAG_COLORS`).
    pub uv1: Vec2,
    pub color: Vec4,
}

/// Angle of q about the unit axis n, as a fraction in [0, 1].
pub fn angle_uv(q: Vec3, n: Vec3) -> f32 {
    let tb = onb_tangents(n);
    q.dot(tb[1]).atan2(q.dot(tb[0])) * (0.5 / PI) + 0.5
}

/// Hit point, normals, uv and error bound in the primitive's own space.
pub fn surface_local(b: &Bindings, prim: &Primitive, ray: &Ray, cand: &Candidate) -> Surface {
    let mut s = Surface {
        p: Vec3::ZERO,
        ng: Vec3::Z,
        ns: Vec3::Z,
        uv: Vec2::ZERO,
        err: 0.0,
        tangent: Vec4::ZERO,
        uv1: Vec2::ZERO,
        color: Vec4::ONE,
    };
    match prim.tag {
        PRIM_SPHERE => {
            let center = xyz(prim.a);
            let radius = prim.a[3];
            let n = (ray.origin + cand.t * ray.dir - center).normalize();
            s.p = center + radius * n;
            s.ng = n;
            s.ns = n;
            s.uv = Vec2::new(
                (-n.z).atan2(n.x) * (0.5 / PI) + 0.5,
                (-n.y).clamp(-1.0, 1.0).acos() / PI,
            );
            s.err = (max_abs(center) + radius) * (1.0 / 1048576.0);
        }
        PRIM_TRIANGLE => {
            let (v0, v1, v2) = (xyz(prim.a), xyz(prim.b), xyz(prim.c));
            let w = Vec3::new(1.0 - cand.u - cand.v, cand.u, cand.v);
            s.p = w.x * v0 + w.y * v1 + w.z * v2;
            s.ng = (v1 - v0).cross(v2 - v0).normalize();
            s.ns = s.ng;
            s.uv = Vec2::new(cand.u, cand.v);
            s.err = max_abs(v0).max(max_abs(v1).max(max_abs(v2))) * (1.0 / 2097152.0);
            if prim.flags & PRIM_FLAG_ATTRIBUTES != 0 {
                let (a0, a1) = (row(b, prim.data), row(b, prim.data + 1));
                let (a2, a3) = (row(b, prim.data + 2), row(b, prim.data + 3));
                s.uv = w.x * Vec2::new(a0.w, a3.x)
                    + w.y * Vec2::new(a1.w, a3.y)
                    + w.z * Vec2::new(a2.w, a3.z);
                if prim.flags & PRIM_FLAG_SHADING_NORMALS != 0 {
                    let n = w.x * a0.truncate() + w.y * a1.truncate() + w.z * a2.truncate();
                    let len = n.length();
                    if len > 0.0 {
                        let sign = if n.dot(s.ng) >= 0.0 { 1.0 } else { -1.0 };
                        s.ns = n * (sign / len);
                    }
                }
                if prim.flags & PRIM_FLAG_TANGENTS != 0 {
                    let (t0, t1) = (row(b, prim.data + 4), row(b, prim.data + 5));
                    let t2 = row(b, prim.data + 6);
                    let t = w.x * t0.truncate() + w.y * t1.truncate() + w.z * t2.truncate();
                    // normals turned to ng's side turn the bitangent with them
                    let nv = w.x * a0.truncate() + w.y * a1.truncate() + w.z * a2.truncate();
                    let turned = prim.flags & PRIM_FLAG_SHADING_NORMALS != 0 && nv.dot(s.ng) < 0.0;
                    s.tangent = t.extend(if turned { -t0.w } else { t0.w });
                }
                // the second uv set and the vertex colours follow the tangents
                let mut extra = prim.data
                    + ATTRIBUTE_ENTRIES
                    + if prim.flags & PRIM_FLAG_TANGENTS != 0 {
                        TANGENT_ENTRIES
                    } else {
                        0
                    };
                if prim.flags & PRIM_FLAG_UV1 != 0 {
                    let (u01, u2) = (row(b, extra), row(b, extra + 1));
                    let (a, c, e) = (
                        Vec2::new(u01.x, u01.y),
                        Vec2::new(u01.z, u01.w),
                        Vec2::new(u2.x, u2.y),
                    );
                    s.uv1 = w.x * a + w.y * c + w.z * e;
                    extra += UV1_ENTRIES;
                }
                if prim.flags & PRIM_FLAG_COLORS != 0 {
                    s.color =
                        w.x * row(b, extra) + w.y * row(b, extra + 1) + w.z * row(b, extra + 2);
                }
            }
        }
        PRIM_PLANE => {
            let point = xyz(prim.a);
            let n = xyz(prim.b);
            let q = ray.origin + cand.t * ray.dir - point;
            let qp = q - q.dot(n) * n;
            s.p = point + qp;
            s.ng = n;
            s.ns = n;
            let tb = onb_tangents(n);
            s.uv = prim.a[3] * Vec2::new(qp.dot(tb[0]), qp.dot(tb[1]));
            s.err = (max_abs(point) + max_abs(qp)) * (1.0 / 1048576.0);
        }
        PRIM_BOX => {
            let lo = xyz(prim.a);
            let hi = xyz(prim.b);
            let axis = cand.u as usize;
            let mut p = ray.origin + cand.t * ray.dir;
            let upper = p[axis] > 0.5 * (lo[axis] + hi[axis]);
            p[axis] = if upper { hi[axis] } else { lo[axis] };
            let mut n = Vec3::ZERO;
            n[axis] = if upper { 1.0 } else { -1.0 };
            let i = (axis + 1) % 3;
            let j = (axis + 2) % 3;
            s.p = p;
            s.ng = n;
            s.ns = n;
            s.uv = Vec2::new(
                (p[i] - lo[i]) / (hi[i] - lo[i]),
                (p[j] - lo[j]) / (hi[j] - lo[j]),
            );
            s.err = max_abs(lo).max(max_abs(hi)) * (1.0 / 1048576.0);
        }
        PRIM_CYLINDER => {
            let base = xyz(prim.a);
            let top = xyz(prim.b);
            let radius = prim.a[3];
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
        }
        PRIM_DISK => {
            let center = xyz(prim.a);
            let radius = prim.a[3];
            let n = xyz(prim.b);
            let q = ray.origin + cand.t * ray.dir - center;
            let qp = q - q.dot(n) * n;
            s.p = center + qp;
            s.ng = n;
            s.ns = n;
            s.uv = Vec2::new(angle_uv(qp, n), qp.length() / radius);
            s.err = (max_abs(center) + radius) * (1.0 / 1048576.0);
        }
        _ => {}
    }
    s
}

/// The derivatives of the point along the first uv set of a surface point `s` of a
/// primitive, in its own space (intersect.wgsl's `surface_uv_derivatives`).
pub fn surface_uv_derivatives(
    b: &Bindings,
    prim: &Primitive,
    s: &Surface,
    cand: &Candidate,
) -> [Vec3; 2] {
    let mut d = onb_tangents(s.ng);
    match prim.tag {
        PRIM_SPHERE => {
            let r = prim.a[3];
            let n = s.ng;
            let rho = (n.x * n.x + n.z * n.z).sqrt().max(1e-6);
            d[0] = 2.0 * PI * r * Vec3::new(n.z, 0.0, -n.x);
            d[1] = PI * r * Vec3::new(-n.y * n.x / rho, rho, -n.y * n.z / rho);
        }
        PRIM_TRIANGLE => {
            let (mut uv0, mut uv1, mut uv2) = (Vec2::ZERO, Vec2::X, Vec2::Y);
            if prim.flags & PRIM_FLAG_ATTRIBUTES != 0 {
                let a3 = row(b, prim.data + 3);
                uv0 = Vec2::new(row(b, prim.data).w, a3.x);
                uv1 = Vec2::new(row(b, prim.data + 1).w, a3.y);
                uv2 = Vec2::new(row(b, prim.data + 2).w, a3.z);
            }
            let (duv02, duv12) = (uv0 - uv2, uv1 - uv2);
            let (dp02, dp12) = (xyz(prim.a) - xyz(prim.c), xyz(prim.b) - xyz(prim.c));
            let det = duv02.x * duv12.y - duv02.y * duv12.x;
            if det.abs() > 1e-12 {
                d[0] = (duv12.y * dp02 - duv02.y * dp12) / det;
                d[1] = (duv02.x * dp12 - duv12.x * dp02) / det;
            }
        }
        PRIM_PLANE => {
            let tb = onb_tangents(xyz(prim.b));
            d[0] = tb[0] / prim.a[3];
            d[1] = tb[1] / prim.a[3];
        }
        PRIM_BOX => {
            let axis = cand.u as usize;
            let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
            d = [Vec3::ZERO; 2];
            d[0][i] = prim.b[i] - prim.a[i];
            d[1][j] = prim.b[j] - prim.a[j];
        }
        PRIM_CYLINDER => {
            let axis = xyz(prim.b) - xyz(prim.a);
            let ax = axis.normalize();
            let q = s.p - xyz(prim.a);
            let radial = q - q.dot(ax) * ax;
            let len = radial.length().max(1e-12);
            let tb = onb_tangents(ax);
            let c = radial / len;
            let around = c.dot(tb[0]) * tb[1] - c.dot(tb[1]) * tb[0];
            d[0] = 2.0 * PI * len * around;
            d[1] = if cand.u == 0.0 { axis } else { c * prim.a[3] };
        }
        PRIM_DISK => {
            let n = xyz(prim.b);
            let qp = s.p - xyz(prim.a);
            let len = qp.length().max(1e-12);
            let tb = onb_tangents(n);
            let c = qp / len;
            let around = c.dot(tb[0]) * tb[1] - c.dot(tb[1]) * tb[0];
            d[0] = 2.0 * PI * len * around;
            d[1] = c * prim.a[3];
        }
        _ => {}
    }
    d
}

/// Shading record of a candidate hit, in world space.
pub fn surface_at(b: &Bindings, ray: &Ray, cand: &Candidate) -> Hit {
    let prim = &b.primitives[cand.prim as usize];
    // the uv derivatives, where a bump map may need them (as HAS_BUMP: every hit, since
    // a blend's part may be the bumped one)
    let bumped = b.has_bump;
    let mut dp = [Vec3::ZERO; 2];
    let s = if prim.flags & PRIM_FLAG_TRANSFORM != 0 {
        let r = ray_to_object(b, prim.data, ray);
        let scale = r.dir.length();
        let local = Candidate {
            t: cand.t * scale,
            ..*cand
        };
        let local_ray = Ray {
            origin: r.origin,
            dir: r.dir / scale,
        };
        let mut s = surface_local(b, prim, &local_ray, &local);
        if bumped {
            // tangent vectors go to world space by the object-to-world matrix itself
            let o = point_to_world(b, prim.data, Vec3::ZERO);
            dp = surface_uv_derivatives(b, prim, &s, &local)
                .map(|v| point_to_world(b, prim.data, v) - o);
        }
        let p_obj = s.p;
        s.p = point_to_world(b, prim.data, p_obj);
        s.ng = normal_to_world(b, prim.data, s.ng);
        s.ns = s.ng;
        s.err = transform_error(b, prim.data, p_obj, s.err);
        s
    } else {
        let s = surface_local(b, prim, ray, cand);
        if bumped {
            dp = surface_uv_derivatives(b, prim, &s, cand);
        }
        s
    };
    let uv1 = if prim.flags & PRIM_FLAG_UV1 != 0 {
        s.uv1
    } else {
        s.uv
    };
    Hit {
        p: s.p,
        ng: s.ng,
        ns: s.ns,
        uv: s.uv.extend(uv1.x).extend(uv1.y),
        front_face: ray.dir.dot(s.ng) < 0.0,
        material: prim.material,
        err: s.err,
        tangent: s.tangent,
        color: s.color,
        dpdu: dp[0],
        dpdv: dp[1],
    }
}
