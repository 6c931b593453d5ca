//! Mirrors `shaders/shared/intersect.wgsl`: the same functions, in the same order, with the
//! same operations, so both backends find the same hits. Each primitive type's own
//! functions are its file's under `cpu/primitives/`.

use glam::{Vec3, Vec4};

use super::bindings::Bindings;
use super::geometry::safe_inverse;
use super::primitives::{intersect_local, surface_local, surface_uv_derivatives};
use super::types::{Candidate, Hit, Ray, FAR, NO_HIT};
use crate::scene::records::{
    BvhNode, Primitive, BVH_NODE_BITS, BVH_SLAB_ERROR, BVH_STACK_SIZE, PRIM_FLAG_TRANSFORM,
    PRIM_FLAG_UV1, PRIM_INSTANCE,
};

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
    closer_hit_in(best, i, h, NO_HIT)
}

/// closer_hit for primitive i of a group, hit through instance inst (NO_HIT: a primitive
/// of the scene's own).
pub fn closer_hit_in(best: Candidate, i: u32, h: Vec3, inst: u32) -> Candidate {
    if h.x < best.t {
        return Candidate {
            t: h.x,
            prim: i,
            u: h.y,
            v: h.z,
            inst,
        };
    }
    best
}

/// The no-hit candidate of a search before t_max.
pub fn no_candidate(t_max: f32) -> Candidate {
    Candidate {
        t: t_max,
        prim: NO_HIT,
        u: 0.0,
        v: 0.0,
        inst: NO_HIT,
    }
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
/// (the shader when every lane of its subgroup has one: the same order per lane). `root`
/// is the index of the root node: 0 for the scene's BVH, a group's for an instance's.
pub fn bvh_walk(
    nodes: &[BvhNode],
    root: u32,
    ray: &Ray,
    t_max: f32,
    mut test: impl FnMut(u32, f32) -> Option<f32>,
) {
    let inv_dir = safe_inverse(ray.dir);
    let order = bvh_order(inv_dir);
    let mut stack = [[0u32; 2]; BVH_STACK_SIZE as usize];
    let mut sp = 0usize;
    // the root: a group of one child node, in slot 0
    let mut group = [root, (1 << (24 + order)) | 1];
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
    let mut best = no_candidate(t_max);
    bvh_walk(b.bvh, 0, ray, t_max, |k, _| {
        best = walk_test(b, best, k, ray, true);
        (best.prim == NO_HIT).then_some(best.t)
    });
    best.prim != NO_HIT
}

/// A primitive k the scene's BVH walk reaches, against the closest hit so far: tested, or,
/// when it is an instance, its group's BVH walked in the group's space (the ray with a unit
/// direction, distances times its length there) from the group's root, the shader's walk
/// into an instance; with any_hit the group's walk ends at its first hit.
pub fn walk_test(b: &Bindings, best: Candidate, k: u32, ray: &Ray, any_hit: bool) -> Candidate {
    let prim = &b.primitives[k as usize];
    if prim.tag != PRIM_INSTANCE {
        return closer_hit(best, k, intersect_bounded(b, k, ray, best.t));
    }
    let r = ray_to_object(b, prim.data, ray);
    let scale = r.dir.length();
    let local = Ray {
        origin: r.origin,
        dir: r.dir / scale,
    };
    let mut inner = Candidate {
        // below FAR, which a miss returns
        t: (best.t * scale).min(FAR),
        ..best
    };
    bvh_walk(b.bvh, prim.a[0].to_bits(), &local, inner.t, |j, t| {
        inner = closer_hit_in(inner, j, intersect_bounded(b, j, &local, t), k);
        (!(any_hit && inner.inst == k)).then_some(inner.t)
    });
    if inner.inst == k {
        Candidate {
            t: inner.t / scale,
            ..inner
        }
    } else {
        best
    }
}

/// Closest hit along the ray before t_max: planes, then the BVH in order (or every
/// primitive).
pub fn intersect_scene(b: &Bindings, ray: &Ray, t_max: f32) -> Candidate {
    let p = &b.params;
    let mut best = no_candidate(t_max);
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
    bvh_walk(b.bvh, 0, ray, best.t, |k, _| {
        best = walk_test(b, best, k, ray, false);
        Some(best.t)
    });
    best
}

/// Shading record of a candidate hit, in world space: a hit through an instance is the
/// group primitive's in the group's space (the ray there with a unit direction, as the
/// walk had it), placed by the instance's transform.
pub fn surface_at(b: &Bindings, ray: &Ray, cand: &Candidate) -> Hit {
    if cand.inst == NO_HIT {
        return surface_own(b, ray, cand);
    }
    let data = b.primitives[cand.inst as usize].data;
    let r = ray_to_object(b, data, ray);
    let scale = r.dir.length();
    let local_ray = Ray {
        origin: r.origin,
        dir: r.dir / scale,
    };
    let local = Candidate {
        t: cand.t * scale,
        inst: NO_HIT,
        ..*cand
    };
    let mut h = surface_own(b, &local_ray, &local);
    let p_obj = h.p;
    h.p = point_to_world(b, data, p_obj);
    h.ng = normal_to_world(b, data, h.ng);
    h.ns = normal_to_world(b, data, h.ns);
    h.unmapped = h.ns;
    h.err = transform_error(b, data, p_obj, h.err);
    h.front_face = ray.dir.dot(h.ng) < 0.0;
    // tangent vectors by the object-to-world matrix itself; a mirror flips the
    // bitangent's handedness
    let origin = point_to_world(b, data, Vec3::ZERO);
    let rows = [0, 1, 2].map(|k| row(b, data + k).truncate());
    let linear_det = rows[0].cross(rows[1]).dot(rows[2]);
    let w = if linear_det < 0.0 {
        -h.tangent.w
    } else {
        h.tangent.w
    };
    h.tangent = (point_to_world(b, data, h.tangent.truncate()) - origin).extend(w);
    h.dpdu = point_to_world(b, data, h.dpdu) - origin;
    h.dpdv = point_to_world(b, data, h.dpdv) - origin;
    h
}

/// surface_at for a hit on a primitive of its own space (the scene's, or a group's in the
/// group's space).
pub fn surface_own(b: &Bindings, ray: &Ray, cand: &Candidate) -> Hit {
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
        unmapped: s.ns,
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
