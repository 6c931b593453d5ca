// Ray-primitive intersection: one function per primitive type, the object-space wrapper for
// transformed primitives, the closest-hit search (planes, then the BVH), and surface_at (hit
// point, normals, uv, error bound). Every intersection function returns FAR for a miss.
#import shared/bindings
#import shared/sampling
#import shared/types

// Sphere, numerically stable form (Ray Tracing Gems, chapter 7). `dir` is unit length.
// Returns the nearest root in (0, t_max), else FAR.
fn intersect_sphere(center: vec3<f32>, radius: f32, ray: Ray, t_max: f32) -> f32 {
    let f = ray.origin - center;
    let b = dot(f, ray.dir);
    let perp = f - b * ray.dir;
    let r2 = radius * radius;
    let disc = r2 - dot(perp, perp);
    let c = dot(f, f) - r2;
    // No early return: llvmpipe runs both sides of every branch under a mask, and a
    // masked return costs more than a select; with the triangle's, 10% fewer instructions
    // in the Cornell box's bounce loop. A value of a missed case (the sqrt of disc < 0, a
    // division by q = 0) is never picked.
    let q = -b - select(-1.0, 1.0, b >= 0.0) * sqrt(disc);
    let t0 = min(c / q, q);
    let t1 = max(c / q, q);
    let t = select(select(FAR, t1, t1 > 0.0 && t1 < t_max), t0, t0 > 0.0 && t0 < t_max);
    return select(FAR, t, disc >= 0.0 && q != 0.0);
}

// Triangle, watertight (Woop, Benthin and Wald, "Watertight Ray/Triangle Intersection",
// JCGT 2013): the vertices are moved into the ray's frame (origin at 0, the dominant axis
// of the direction as z, sheared so that the ray runs along +z) and the 2D edge functions
// U, V, W of the point (0, 0) decide the hit. An edge shared by two triangles gives both the
// same value with opposite signs, and a zero counts as inside, so no ray slips between
// them, whatever the rounding. Returns (t, b1, b2): distance and the barycentric weights of
// v1 and v2; t = FAR on a miss or outside (0, t_max). Both sides are hit.
fn intersect_triangle(v0: vec3<f32>, v1: vec3<f32>, v2: vec3<f32>, ray: Ray, t_max: f32) -> vec3<f32> {
    let d = ray.dir;
    let kz = argmax3(abs(d));
    var kx = (kz + 1u) % 3u;
    var ky = (kx + 1u) % 3u;
    if (d[kz] < 0.0) {
        let k = kx;
        kx = ky;
        ky = k;
    }
    let sz = 1.0 / d[kz];
    let sx = d[kx] * sz;
    let sy = d[ky] * sz;
    let a = v0 - ray.origin;
    let b = v1 - ray.origin;
    let c = v2 - ray.origin;
    let ax = a[kx] - sx * a[kz];
    let ay = a[ky] - sy * a[kz];
    let bx = b[kx] - sx * b[kz];
    let by = b[ky] - sy * b[kz];
    let cx = c[kx] - sx * c[kz];
    let cy = c[ky] - sy * c[kz];
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    // no early return (see intersect_sphere); a division by det = 0 is never picked
    let outside = (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0);
    let det = u + v + w;
    let t = (u * (sz * a[kz]) + v * (sz * b[kz]) + w * (sz * c[kz])) / det;
    let hit = !outside && det != 0.0 && t > 0.0 && t < t_max;
    return select(vec3<f32>(FAR, 0.0, 0.0), vec3<f32>(t, v / det, w / det), hit);
}

// Plane through `point` with unit normal n: t = -((o - point) . n) / (d . n). The sign and
// range are tested before dividing (num * denom > 0, |num| < t_max |denom|), so a ray
// parallel to the plane (d . n = 0) is a miss and t is always finite.
fn intersect_plane(point: vec3<f32>, n: vec3<f32>, ray: Ray, t_max: f32) -> f32 {
    let denom = dot(ray.dir, n);
    let num = -dot(ray.origin - point, n);
    if (num * denom > 0.0 && abs(num) < t_max * abs(denom)) {
        return num / denom;
    }
    return FAR;
}

// Disk: the plane of unit normal n through `center`, within `radius` of the center.
fn intersect_disk(center: vec3<f32>, n: vec3<f32>, radius: f32, ray: Ray, t_max: f32) -> f32 {
    let t = intersect_plane(center, n, ray, t_max);
    if (t < FAR) {
        let q = ray.origin + t * ray.dir - center;
        if (dot(q, q) <= radius * radius) {
            return t;
        }
    }
    return FAR;
}

// 1 / d, with zero and tiny components first replaced by +-1e-30 (sign kept, zero taken as
// +), so that slab distances are finite and never 0 * inf = NaN.
fn safe_inverse(d: vec3<f32>) -> vec3<f32> {
    let tiny = select(vec3<f32>(1e-30), vec3<f32>(-1e-30), d < vec3<f32>(0.0));
    return 1.0 / select(d, tiny, abs(d) < vec3<f32>(1e-30));
}

// Index of the largest component (the first of equals).
fn argmax3(v: vec3<f32>) -> u32 {
    if (v.x >= v.y && v.x >= v.z) {
        return 0u;
    }
    return select(2u, 1u, v.y >= v.z);
}

// Index of the smallest component (the first of equals).
fn argmin3(v: vec3<f32>) -> u32 {
    if (v.x <= v.y && v.x <= v.z) {
        return 0u;
    }
    return select(2u, 1u, v.y <= v.z);
}

// Axis-aligned box, slab method: per axis the distances to its two planes; the ray is inside
// between t_near = max of the per-axis minima and t_far = min of the maxima. Returns
// (t, axis of the face): t_near when the box is ahead, t_far when the ray starts inside.
fn intersect_box(lo: vec3<f32>, hi: vec3<f32>, ray: Ray, t_max: f32) -> vec2<f32> {
    let inv = safe_inverse(ray.dir);
    let t0 = (lo - ray.origin) * inv;
    let t1 = (hi - ray.origin) * inv;
    let t_min = min(t0, t1);
    let t_max3 = max(t0, t1);
    let t_near = max(t_min.x, max(t_min.y, t_min.z));
    let t_far = min(t_max3.x, min(t_max3.y, t_max3.z));
    if (t_near <= t_far) {
        if (t_near > 0.0 && t_near < t_max) {
            return vec2<f32>(t_near, f32(argmax3(t_min)));
        }
        if (t_far > 0.0 && t_far < t_max) {
            return vec2<f32>(t_far, f32(argmin3(t_max3)));
        }
    }
    return vec2<f32>(FAR, 0.0);
}

// Finite cylinder from `base` to `top`. The side: a t^2 + 2 b t + c = 0 for the squared
// distance to the axis of the ray's components across the axis, in the stable form (the
// discriminant b^2 - a c = a (r^2 - |op - (b / a) dp|^2), the larger-magnitude root first),
// each root kept only within the height. With caps, the two end disks too.
// Returns (t, part): part 0 = side, 1 = base cap, 2 = top cap.
fn intersect_cylinder(base: vec3<f32>, top: vec3<f32>, radius: f32, caps: bool, ray: Ray, t_max: f32) -> vec2<f32> {
    let axis = top - base;
    let h = length(axis);
    let ax = axis / h;
    let oc = ray.origin - base;
    let o_ax = dot(oc, ax);
    let d_ax = dot(ray.dir, ax);
    let op = oc - o_ax * ax;
    let dp = ray.dir - d_ax * ax;
    var best = vec2<f32>(FAR, 0.0);
    var t_lim = t_max;
    let a = dot(dp, dp);
    // a = 0: the ray runs along the axis and only the caps can be hit.
    if (a > 1e-20) {
        let b = dot(op, dp);
        let perp = op - (b / a) * dp;
        let r2 = radius * radius;
        let disc = r2 - dot(perp, perp);
        if (disc >= 0.0) {
            let c = dot(op, op) - r2;
            let q = -b - select(-1.0, 1.0, b >= 0.0) * sqrt(a * disc);
            if (q != 0.0) {
                let t0 = min(q / a, c / q);
                let t1 = max(q / a, c / q);
                let s0 = o_ax + t0 * d_ax;
                let s1 = o_ax + t1 * d_ax;
                if (t0 > 0.0 && t0 < t_lim && s0 >= 0.0 && s0 <= h) {
                    best = vec2<f32>(t0, 0.0);
                    t_lim = t0;
                } else if (t1 > 0.0 && t1 < t_lim && s1 >= 0.0 && s1 <= h) {
                    best = vec2<f32>(t1, 0.0);
                    t_lim = t1;
                }
            }
        }
    }
    if (caps) {
        let t_base = intersect_disk(base, ax, radius, ray, t_lim);
        if (t_base < t_lim) {
            best = vec2<f32>(t_base, 1.0);
            t_lim = t_base;
        }
        let t_top = intersect_disk(top, ax, radius, ray, t_lim);
        if (t_top < t_lim) {
            best = vec2<f32>(t_top, 2.0);
        }
    }
    return best;
}

// The world-to-object transform of a primitive applied to a ray: the origin by the affine
// map, the direction by its linear part (not normalized).
fn ray_to_object(data: u32, ray: Ray) -> Ray {
    let r0 = shape_data[data];
    let r1 = shape_data[data + 1u];
    let r2 = shape_data[data + 2u];
    let o = vec4<f32>(ray.origin, 1.0);
    return Ray(vec3<f32>(dot(r0, o), dot(r1, o), dot(r2, o)),
        vec3<f32>(dot(r0.xyz, ray.dir), dot(r1.xyz, ray.dir), dot(r2.xyz, ray.dir)));
}

// An object-space point in world space (the object-to-world rows).
fn point_to_world(data: u32, p: vec3<f32>) -> vec3<f32> {
    let o = vec4<f32>(p, 1.0);
    return vec3<f32>(dot(shape_data[data + 3u], o), dot(shape_data[data + 4u], o),
        dot(shape_data[data + 5u], o));
}

// An object-space normal in world space: the transpose of the world-to-object linear part
// (the inverse transpose of object-to-world), normalized.
fn normal_to_world(data: u32, n: vec3<f32>) -> vec3<f32> {
    return normalize(shape_data[data].xyz * n.x + shape_data[data + 1u].xyz * n.y
        + shape_data[data + 2u].xyz * n.z);
}

// Error bound of a point mapped to world space: the object-space bound through the matrix,
// plus the rounding of the matrix product (a few ulps of the magnitudes summed).
fn transform_error(data: u32, p: vec3<f32>, err: f32) -> f32 {
    var e = 0.0;
    for (var k = 0u; k < 3u; k++) {
        let row = shape_data[data + 3u + k];
        let m = abs(row.xyz);
        e = max(e, (m.x + m.y + m.z) * err + (dot(m, abs(p)) + abs(row.w)) * (1.0 / 2097152.0));
    }
    return e;
}

// One primitive in its own space: (t, u, v) as in Candidate.
fn intersect_local(prim: Primitive, tag: u32, ray: Ray, t_max: f32) -> vec3<f32> {
    switch tag {
#ifdef HAS_SPHERE
        case PRIM_SPHERE: {
            return vec3<f32>(intersect_sphere(prim.a.xyz, prim.a.w, ray, t_max), 0.0, 0.0);
        }
#endif
#ifdef HAS_TRIANGLE
        case PRIM_TRIANGLE: {
            return intersect_triangle(prim.a.xyz, prim.b.xyz, prim.c.xyz, ray, t_max);
        }
#endif
#ifdef HAS_PLANE
        case PRIM_PLANE: {
            return vec3<f32>(intersect_plane(prim.a.xyz, prim.b.xyz, ray, t_max), 0.0, 0.0);
        }
#endif
#ifdef HAS_BOX
        case PRIM_BOX: {
            return vec3<f32>(intersect_box(prim.a.xyz, prim.b.xyz, ray, t_max), 0.0);
        }
#endif
#ifdef HAS_CYLINDER
        case PRIM_CYLINDER: {
            let caps = (prim.flags & PRIM_FLAG_CAPS) != 0u;
            return vec3<f32>(intersect_cylinder(prim.a.xyz, prim.b.xyz, prim.a.w, caps, ray, t_max), 0.0);
        }
#endif
#ifdef HAS_DISK
        case PRIM_DISK: {
            return vec3<f32>(intersect_disk(prim.a.xyz, prim.b.xyz, prim.a.w, ray, t_max), 0.0, 0.0);
        }
#endif
        default: {
            return vec3<f32>(FAR, 0.0, 0.0);
        }
    }
}

// Primitive i in world space. A transformed primitive is intersected in object space with
// the direction normalized (the sphere test needs unit length); t is mapped back by the
// direction's length.
fn intersect_primitive(i: u32, ray: Ray, t_max: f32) -> vec3<f32> {
    let prim = primitive_record(i);
    return intersect_record(prim, prim.tag, ray, t_max);
}

// intersect_primitive for a record already fetched, of type `tag`: a literal lets the
// compiler drop the other types' cases (the per-type loops of intersect_scene).
fn intersect_record(prim: Primitive, tag: u32, ray: Ray, t_max: f32) -> vec3<f32> {
#ifndef HAS_TRANSFORMS
    return intersect_local(prim, tag, ray, t_max);
#else
    if ((prim.flags & PRIM_FLAG_TRANSFORM) == 0u) {
        return intersect_local(prim, tag, ray, t_max);
    }
    let r = ray_to_object(prim.data, ray);
    let scale = length(r.dir);
    let t_lim = min(t_max, FAR / max(scale, 1.0)) * scale;
    let h = intersect_local(prim, tag, Ray(r.origin, r.dir / scale), t_lim);
    if (h.x < FAR) {
        return vec3<f32>(h.x / scale, h.y, h.z);
    }
    return h;
#endif
}

// The traversal stacks: entry k of the invocation of local index stack_lane is
// bvh_stack[k * BVH_STACK_LANES + stack_lane], the lanes' entries side by side (16 KiB, the
// workgroup memory every device has). In workgroup memory rather than an array of each
// invocation: llvmpipe writes a private array for all 8 lanes of a batch, reading back what
// the lanes that do not push keep, and writes workgroup memory lane by lane for those that
// do (nefertiti's bounce loop: 9363 JIT instructions with private stacks, 5152 with these).
// Each entry point sets stack_lane from its local_invocation_index first.
var<private> stack_lane: u32;

#ifdef HAS_LANE_STATS
// --tune lane-stats (gpu::plan::LANE_STATS): per kind of step (x: a turn of the bounce
// loop, y: a BVH node step, z: a primitive test of the BVH walk), the steps this
// invocation took part in, and its share of the steps of its subgroup, subgroup size /
// active lanes at each; summed, their ratio is the share of live lanes. The entry point
// sets lane_subgroup_size.
var<private> lane_steps: vec3<f32>;
var<private> lane_shares: vec3<f32>;
var<private> lane_subgroup_size: u32;

fn count_lanes(kind: u32) {
    let lanes = subgroupAdd(1u);
    let step = select(vec3<f32>(0.0), vec3<f32>(1.0), vec3<u32>(0u, 1u, 2u) == vec3<u32>(kind));
    lane_steps += step;
    lane_shares += step * (f32(lane_subgroup_size) / f32(lanes));
}
#endif
#ifdef HAS_BVH
var<workgroup> bvh_stack: array<vec2<u32>, BVH_STACK_SIZE * BVH_STACK_LANES>;
#endif

// intersect_primitive for a primitive of the BVH. When all of them are untransformed
// triangles (BOUNDED_TRIANGLES_ONLY) the tag is not read: the test needs neither the
// record's first texel nor a switch.
fn intersect_bounded(i: u32, ray: Ray, t_max: f32) -> vec3<f32> {
#ifdef BOUNDED_TRIANGLES_ONLY
    return intersect_record(primitive_record(i), PRIM_TRIANGLE, ray, t_max);
#else
    return intersect_primitive(i, ray, t_max);
#endif
}

// The closer of the closest hit so far and hit h = (t, u, v) of primitive i.
fn closer_hit(best: Candidate, i: u32, h: vec3<f32>) -> Candidate {
    if (h.x < best.t) {
        return Candidate(h.x, i, h.y, h.z);
    }
    return best;
}

// Primitive i tested against the closest hit so far; the closer of the two.
fn closer(best: Candidate, i: u32, ray: Ray) -> Candidate {
    return closer_hit(best, i, intersect_primitive(i, ray, best.t));
}

// The walk's order among a node's children: a child node hit is marked in bit 24 + (slot ^
// bvh_order) of the hit mask and the highest bit is taken first, so a ray whose direction
// has the signs of octant o (bit 0: x < 0, bit 1: y, bit 2: z) takes slot o first, where
// scene::bvh::collapse puts the child such rays enter first.
fn bvh_order(inv_dir: vec3<f32>) -> u32 {
    let neg = select(vec3<u32>(0u), vec3<u32>(1u, 2u, 4u), inv_dir < vec3<f32>(0.0));
    return (neg.x | neg.y | neg.z) ^ 7u;
}

// Four bytes of a word, from the low one, as numbers.
fn bvh_bytes(w: u32) -> vec4<f32> {
    return vec4<f32>((vec4<u32>(w) >> vec4<u32>(0u, 8u, 16u, 24u)) & vec4<u32>(255u));
}

// min and max of numbers that are not NaN: selects (llvmpipe's min and max also handle
// NaN operands, one more instruction each)
fn min4(a: vec4<f32>, b: vec4<f32>) -> vec4<f32> {
    return select(b, a, a < b);
}

fn max4(a: vec4<f32>, b: vec4<f32>) -> vec4<f32> {
    return select(b, a, a > b);
}

// Which of four children a ray enters before t_max: their planes' bytes on the near and
// the far side of each axis, the slab distance of a step per axis and of the node's
// origin, less (near) or plus (far) its error bound.
fn bvh_slabs(near: vec3<u32>, far: vec3<u32>, step_t: vec3<f32>, near_t: vec3<f32>, far_t: vec3<f32>, t_max: f32) -> vec4<bool> {
    let t_near = max4(
        max4(bvh_bytes(near.x) * step_t.x + near_t.x, bvh_bytes(near.y) * step_t.y + near_t.y),
        max4(bvh_bytes(near.z) * step_t.z + near_t.z, vec4<f32>(0.0)),
    );
    let t_far = min4(
        min4(bvh_bytes(far.x) * step_t.x + far_t.x, bvh_bytes(far.y) * step_t.y + far_t.y),
        bvh_bytes(far.z) * step_t.z + far_t.z,
    );
    return (t_near <= t_far) & (t_near < vec4<f32>(t_max));
}

// The bits four children mark in the hit mask when hit (BvhNode's meta bytes): a node's
// moved by the walk's order, a leaf's its primitives.
fn bvh_child_bits(bytes: u32, inner: u32, order: u32) -> vec4<u32> {
    var m = (vec4<u32>(bytes) >> vec4<u32>(0u, 8u, 16u, 24u)) & vec4<u32>(255u);
    m ^= ((vec4<u32>(inner) >> vec4<u32>(0u, 1u, 2u, 3u)) & vec4<u32>(1u)) * order;
    return (m >> vec4<u32>(5u)) << (m & vec4<u32>(31u));
}

#ifdef HAS_BVH
// The walk's next node: the highest node bit of the group (which must hold one) is taken
// from it and the rest of the group pushed (bvh_stack at sp) if it holds more.
fn bvh_take(group: ptr<function, vec2<u32>>, sp: ptr<function, u32>, order: u32) -> u32 {
    let bit = firstLeadingBit((*group).y);
    (*group).y ^= 1u << bit;
    let slot = (bit - 24u) ^ order;
    let index = (*group).x + countOneBits((*group).y & ((1u << slot) - 1u));
    if (((*group).y & BVH_NODE_BITS) != 0u) {
        bvh_stack[*sp] = *group;
        *sp += BVH_STACK_LANES;
    }
    return index;
}
#endif

// Node n's children that a ray enters before t_max, as the walk's next two groups: (first
// child node, hit child nodes' bits | imask, first primitive, hit primitives' bits). The
// quantized boxes' slab distances are (origin - ray origin) / d + q step / d per axis;
// widened by BVH_SLAB_ERROR of the magnitudes that form them, they bound the exact ones
// whatever cancels.
fn bvh_node_hits(n: BvhNode, origin: vec3<f32>, inv_dir: vec3<f32>, order: u32, t_max: f32) -> vec4<u32> {
    let step = bitcast<vec3<f32>>(((vec3<u32>(n.scale) >> vec3<u32>(0u, 8u, 16u)) & vec3<u32>(255u)) << vec3<u32>(23u));
    let rel = n.origin - origin;
    let origin_t = rel * inv_dir;
    let step_t = min(max(step * inv_dir, vec3<f32>(-FAR)), vec3<f32>(FAR));
    let err = min((abs(rel) + 256.0 * step) * abs(inv_dir), vec3<f32>(FAR)) * BVH_SLAB_ERROR;
    let near_t = origin_t - err;
    let far_t = origin_t + err;
    let neg = inv_dir < vec3<f32>(0.0);
    // the planes' words: lo x, y, z in q0.xy, q0.zw, q1.xy, hi in q1.zw, q2.xy, q2.zw
    let lo0 = vec3<u32>(n.q0.x, n.q0.z, n.q1.x);
    let lo1 = vec3<u32>(n.q0.y, n.q0.w, n.q1.y);
    let hi0 = vec3<u32>(n.q1.z, n.q2.x, n.q2.z);
    let hi1 = vec3<u32>(n.q1.w, n.q2.y, n.q2.w);
    let imask = n.scale >> 24u;
    let hit0 = bvh_slabs(select(lo0, hi0, neg), select(hi0, lo0, neg), step_t, near_t, far_t, t_max);
    let hit1 = bvh_slabs(select(lo1, hi1, neg), select(hi1, lo1, neg), step_t, near_t, far_t, t_max);
    let b0 = select(vec4<u32>(0u), bvh_child_bits(n.meta0, imask, order), hit0);
    let b1 = select(vec4<u32>(0u), bvh_child_bits(n.meta1, imask >> 4u, order), hit1);
    let b = b0 | b1;
    let hits = b.x | b.y | b.z | b.w;
    return vec4<u32>(n.child, (hits & BVH_NODE_BITS) | imask, n.prim, hits & ~BVH_NODE_BITS);
}

// Closest hit along the ray before t_max (FAR: anywhere; a shadow ray's length: whether
// anything lies in between): every unbounded primitive (planes), then the BVH in order
// (nearer child first, a far child pushed with its entry distance and skipped when the
// closest hit is already nearer), or every bounded primitive when use_bvh = 0. A shader
// holds the BVH walk (HAS_BVH), the plain loop (HAS_PRIMITIVE_LOOP), or both; or, for a
// small scene, the search over its primitives written in as constants (BAKED_PRIMITIVES).
fn intersect_scene(ray: Ray, t_max: f32) -> Candidate {
#ifdef BAKED_PRIMITIVES
    // a small scene's records are constants of its shader (gpu::codegen::baked_primitives)
    return intersect_baked(ray, t_max);
#else
    var best = Candidate(t_max, NO_HIT, 0.0, 0.0);
#ifdef HAS_PLANE
    // (the unbounded primitives are planes; without them llvmpipe would still run this
    // loop's body once, masked off)
    for (var i = 0u; i < params.num_unbounded; i++) {
        best = closer(best, i, ray);
    }
#endif
#ifdef HAS_PRIMITIVE_LOOP
    if (params.use_bvh == 0u) {
        // Without the BVH the bounded primitives are sorted by type (scene::flatten), and
        // each type present gets a loop whose body holds only its own test: llvmpipe runs
        // every case of a switch under a mask. The loops visit the indices in order, as
        // the CPU's single loop does. Each record is fetched once, for its tag and its test.
        var i = params.num_unbounded;
#ifdef HAS_SPHERE
        for (; i < params.num_primitives; i++) {
            let prim = primitive_record(i);
            if (prim.tag != PRIM_SPHERE) {
                break;
            }
            best = closer_hit(best, i, intersect_record(prim, PRIM_SPHERE, ray, best.t));
        }
#endif
#ifdef HAS_TRIANGLE
        for (; i < params.num_primitives; i++) {
            let prim = primitive_record(i);
            if (prim.tag != PRIM_TRIANGLE) {
                break;
            }
            best = closer_hit(best, i, intersect_record(prim, PRIM_TRIANGLE, ray, best.t));
        }
#endif
#ifdef HAS_BOX
        for (; i < params.num_primitives; i++) {
            let prim = primitive_record(i);
            if (prim.tag != PRIM_BOX) {
                break;
            }
            best = closer_hit(best, i, intersect_record(prim, PRIM_BOX, ray, best.t));
        }
#endif
#ifdef HAS_CYLINDER
        for (; i < params.num_primitives; i++) {
            let prim = primitive_record(i);
            if (prim.tag != PRIM_CYLINDER) {
                break;
            }
            best = closer_hit(best, i, intersect_record(prim, PRIM_CYLINDER, ray, best.t));
        }
#endif
#ifdef HAS_DISK
        for (; i < params.num_primitives; i++) {
            let prim = primitive_record(i);
            if (prim.tag != PRIM_DISK) {
                break;
            }
            best = closer_hit(best, i, intersect_record(prim, PRIM_DISK, ray, best.t));
        }
#endif
        return best;
    }
#endif
#ifdef HAS_BVH
    best = bvh_walk(ray, best, false);
#endif
    return best;
#endif
}

// Whether anything lies along the ray before t_max (a shadow ray): the same answer as
// intersect_scene(ray, t_max).prim != NO_HIT. With the BVH it is an any-hit search: a
// lane stops at the first primitive in range, and boxes are culled against t_max only.
fn occluded(ray: Ray, t_max: f32) -> bool {
#ifdef BAKED_PRIMITIVES
    return occluded_baked(ray, t_max);
#else
#ifdef HAS_BVH
#ifndef HAS_PRIMITIVE_LOOP
    // Without the plain loop the BVH is always on, and the closest-hit walk is not
    // written in a second time: llvmpipe would run it, masked off, on every shadow ray
    // (one pass of its loop body: 881 instructions of the 14349 of nefertiti's bounce).
    return occluded_bvh(ray, t_max);
#else
    if (params.use_bvh != 0u) {
        return occluded_bvh(ray, t_max);
    }
    return intersect_scene(ray, t_max).prim != NO_HIT;
#endif
#else
    return intersect_scene(ray, t_max).prim != NO_HIT;
#endif
#endif
}

#ifdef HAS_BVH
// The any-hit search of occluded over the planes and the BVH.
fn occluded_bvh(ray: Ray, t_max: f32) -> bool {
#ifdef HAS_PLANE
    for (var i = 0u; i < params.num_unbounded; i++) {
        if (intersect_primitive(i, ray, t_max).x < t_max) {
            return true;
        }
    }
#endif
    return bvh_walk(ray, Candidate(t_max, NO_HIT, 0.0, 0.0), true).prim != NO_HIT;
}

// The BVH walk of intersect_scene and occluded_bvh (the CPU's bvh_walk): the closest hit
// nearer than start's, or, with any_hit (a constant at each call, which the compiler
// folds), the first one found, the walk ending there (a shadow ray's). The walk's two
// groups (bvh_node_hits): child nodes still to visit (a stack entry) and primitives to
// test; sp indexes bvh_stack (the entries of this lane are BVH_STACK_LANES apart); the
// root is a group of one child node, in slot 0. Boxes are culled against the closest hit
// so far (an any-hit walk ends at its first, so it culls against t_max only).
fn bvh_walk(ray: Ray, start: Candidate, any_hit: bool) -> Candidate {
    var best = start;
    if (params.num_primitives == params.num_unbounded) {
        return best;
    }
    let inv_dir = safe_inverse(ray.dir);
    let order = bvh_order(inv_dir);
    var sp = stack_lane;
    var group = vec2<u32>(0u, (1u << (24u + order)) | 1u);
    var prims = vec2<u32>(0u, 0u);
    var live = true;
    loop {
        // Nodes until the lane has primitives to test (tested after the loop, when every
        // lane of the subgroup has some) or none is left.
        loop {
            if ((group.y & BVH_NODE_BITS) == 0u) {
                if (sp == stack_lane) {
                    live = false;
                    break;
                }
                sp -= BVH_STACK_LANES;
                group = bvh_stack[sp];
            }
#ifdef HAS_LANE_STATS
            count_lanes(1u);
#endif
            let index = bvh_take(&group, &sp, order);
            let h = bvh_node_hits(bvh_node(index), ray.origin, inv_dir, order, best.t);
            group = h.xy;
            prims = h.zw;
            if (prims.y != 0u) {
                break;
            }
        }
        loop {
            if (prims.y == 0u) {
                break;
            }
#ifdef HAS_LANE_STATS
            count_lanes(2u);
#endif
            let k = prims.x + firstTrailingBit(prims.y);
            prims.y &= prims.y - 1u;
            best = closer_hit(best, k, intersect_bounded(k, ray, best.t));
            if (any_hit && best.prim != NO_HIT) {
                live = false;
                break;
            }
        }
        if (!live) {
            break;
        }
    }
    return best;
}
#endif

// A hit in a primitive's own space.
struct Surface {
    p: vec3<f32>,
    ng: vec3<f32>,
    ns: vec3<f32>,
    uv: vec2<f32>,
    err: f32,
    tangent: vec4<f32>,
    // a triangle's second uv set (PRIM_FLAG_UV1) and vertex colour (PRIM_FLAG_COLORS)
    uv1: vec2<f32>,
    color: vec4<f32>,
}

// Angle of q about the unit axis n, in the onb_tangents frame, as a fraction in [0, 1].
fn angle_uv(q: vec3<f32>, n: vec3<f32>) -> f32 {
    let tb = onb_tangents(n);
    return atan2(dot(q, tb[1]), dot(q, tb[0])) * (0.5 / PI) + 0.5;
}

// Hit point, normals, uv and error bound of a candidate, in the primitive's own space. The
// point is recomputed from the primitive (re-projected onto spheres, cylinders, planes and
// disks, barycentric on triangles, snapped to the face on boxes), which keeps it on the
// surface to within a few ulps of the primitive's own magnitudes whatever the distance
// travelled; err bounds that (16 ulps, 8 for triangles).
fn surface_local(prim: Primitive, ray: Ray, cand: Candidate) -> Surface {
    var s = Surface(vec3<f32>(0.0), vec3<f32>(0.0, 0.0, 1.0), vec3<f32>(0.0, 0.0, 1.0), vec2<f32>(0.0), 0.0, vec4<f32>(0.0), vec2<f32>(0.0), vec4<f32>(1.0));
    switch prim.tag {
#ifdef HAS_SPHERE
        case PRIM_SPHERE: {
            let center = prim.a.xyz;
            let radius = prim.a.w;
            let n = normalize(ray.origin + cand.t * ray.dir - center);
            s.p = center + radius * n;
            s.ng = n;
            s.ns = n;
            // longitude from atan2(-z, x), latitude from the south pole (v = 0) up
            s.uv = vec2<f32>(atan2(-n.z, n.x) * (0.5 / PI) + 0.5, acos(clamp(-n.y, -1.0, 1.0)) / PI);
            s.err = (max_abs(center) + radius) * (1.0 / 1048576.0);
        }
#endif
#ifdef HAS_TRIANGLE
        case PRIM_TRIANGLE: {
            let v0 = prim.a.xyz;
            let v1 = prim.b.xyz;
            let v2 = prim.c.xyz;
            let w = vec3<f32>(1.0 - cand.u - cand.v, cand.u, cand.v);
            s.p = w.x * v0 + w.y * v1 + w.z * v2;
            s.ng = normalize(cross(v1 - v0, v2 - v0));
            s.ns = s.ng;
            // default vertex uvs (0, 0), (1, 0), (0, 1)
            s.uv = vec2<f32>(cand.u, cand.v);
            s.err = max(max_abs(v0), max(max_abs(v1), max_abs(v2))) * (1.0 / 2097152.0);
            if ((prim.flags & PRIM_FLAG_ATTRIBUTES) != 0u) {
                let a0 = shape_data[prim.data];
                let a1 = shape_data[prim.data + 1u];
                let a2 = shape_data[prim.data + 2u];
                let a3 = shape_data[prim.data + 3u];
                s.uv = w.x * vec2<f32>(a0.w, a3.x) + w.y * vec2<f32>(a1.w, a3.y) + w.z * vec2<f32>(a2.w, a3.z);
                if ((prim.flags & PRIM_FLAG_SHADING_NORMALS) != 0u) {
                    let n = w.x * a0.xyz + w.y * a1.xyz + w.z * a2.xyz;
                    let len = length(n);
                    if (len > 0.0) {
                        // on the side of ng whatever the file's winding
                        s.ns = n * (select(-1.0, 1.0, dot(n, s.ng) >= 0.0) / len);
                    }
                }
#ifdef HAS_NORMAL_MAP
                if ((prim.flags & PRIM_FLAG_TANGENTS) != 0u) {
                    let t0 = shape_data[prim.data + 4u];
                    let t1 = shape_data[prim.data + 5u];
                    let t2 = shape_data[prim.data + 6u];
                    // normals turned to ng's side turn the bitangent with them
                    let nv = w.x * a0.xyz + w.y * a1.xyz + w.z * a2.xyz;
                    let turned = (prim.flags & PRIM_FLAG_SHADING_NORMALS) != 0u && dot(nv, s.ng) < 0.0;
                    s.tangent = vec4<f32>(w.x * t0.xyz + w.y * t1.xyz + w.z * t2.xyz, select(t0.w, -t0.w, turned));
                }
#endif
                // the second uv set and the vertex colours follow the tangents
                var extra = prim.data + ATTRIBUTE_ENTRIES + select(0u, TANGENT_ENTRIES, (prim.flags & PRIM_FLAG_TANGENTS) != 0u);
#ifdef HAS_UV1
                if ((prim.flags & PRIM_FLAG_UV1) != 0u) {
                    let u01 = shape_data[extra];
                    let u2 = shape_data[extra + 1u];
                    s.uv1 = w.x * u01.xy + w.y * u01.zw + w.z * u2.xy;
                    extra += UV1_ENTRIES;
                }
#endif
#ifdef HAS_VERTEX_COLORS
                if ((prim.flags & PRIM_FLAG_COLORS) != 0u) {
                    s.color = w.x * shape_data[extra] + w.y * shape_data[extra + 1u] + w.z * shape_data[extra + 2u];
                }
#endif
            }
        }
#endif
#ifdef HAS_PLANE
        case PRIM_PLANE: {
            let point = prim.a.xyz;
            let n = prim.b.xyz;
            let q = ray.origin + cand.t * ray.dir - point;
            let qp = q - dot(q, n) * n;
            s.p = point + qp;
            s.ng = n;
            s.ns = n;
            let tb = onb_tangents(n);
            s.uv = prim.a.w * vec2<f32>(dot(qp, tb[0]), dot(qp, tb[1]));
            s.err = (max_abs(point) + max_abs(qp)) * (1.0 / 1048576.0);
        }
#endif
#ifdef HAS_BOX
        case PRIM_BOX: {
            let lo = prim.a.xyz;
            let hi = prim.b.xyz;
            let axis = u32(cand.u);
            var p = ray.origin + cand.t * ray.dir;
            let upper = p[axis] > 0.5 * (lo[axis] + hi[axis]);
            p[axis] = select(lo[axis], hi[axis], upper);
            var n = vec3<f32>(0.0);
            n[axis] = select(-1.0, 1.0, upper);
            let i = (axis + 1u) % 3u;
            let j = (axis + 2u) % 3u;
            s.p = p;
            s.ng = n;
            s.ns = n;
            s.uv = vec2<f32>((p[i] - lo[i]) / (hi[i] - lo[i]), (p[j] - lo[j]) / (hi[j] - lo[j]));
            // the face coordinate is exact; the others only move the point along the face
            s.err = max(max_abs(lo), max_abs(hi)) * (1.0 / 1048576.0);
        }
#endif
#ifdef HAS_CYLINDER
        case PRIM_CYLINDER: {
            let base = prim.a.xyz;
            let top = prim.b.xyz;
            let radius = prim.a.w;
            let axis = top - base;
            let h = length(axis);
            let ax = axis / h;
            let q = ray.origin + cand.t * ray.dir - base;
            let q_ax = dot(q, ax);
            let radial = q - q_ax * ax;
            if (cand.u == 0.0) {
                let n = normalize(radial);
                let height = clamp(q_ax, 0.0, h);
                s.p = base + height * ax + radius * n;
                s.ng = n;
                s.uv = vec2<f32>(angle_uv(n, ax), height / h);
            } else {
                let top_cap = cand.u == 2.0;
                s.p = select(base, top, top_cap) + radial;
                s.ng = select(-ax, ax, top_cap);
                s.uv = vec2<f32>(angle_uv(radial, ax), length(radial) / radius);
            }
            s.ns = s.ng;
            s.err = (max(max_abs(base), max_abs(top)) + radius) * (1.0 / 1048576.0);
        }
#endif
#ifdef HAS_DISK
        case PRIM_DISK: {
            let center = prim.a.xyz;
            let radius = prim.a.w;
            let n = prim.b.xyz;
            let q = ray.origin + cand.t * ray.dir - center;
            let qp = q - dot(q, n) * n;
            s.p = center + qp;
            s.ng = n;
            s.ns = n;
            s.uv = vec2<f32>(angle_uv(qp, n), length(qp) / radius);
            s.err = (max_abs(center) + radius) * (1.0 / 1048576.0);
        }
#endif
        default: {}
    }
    return s;
}

#ifdef HAS_BUMP
// The derivatives of the point along the first uv set of a surface point s of a
// primitive, in its own space (HAS_BUMP: what a bump map's slopes are measured against,
// as in Mitsuba and pbrt): a sphere's longitude and latitude (kept off the poles'
// singularity), a triangle's vertex uvs (its default (0, 0), (1, 0), (0, 1) without
// them; a frame of its normal where they are degenerate), a plane's scaled frame, a box
// face's extent, a cylinder's and a disk's angle and height or radius.
fn surface_uv_derivatives(prim: Primitive, s: Surface, cand: Candidate) -> array<vec3<f32>, 2> {
    var d = onb_tangents(s.ng);
    switch prim.tag {
#ifdef HAS_SPHERE
        case PRIM_SPHERE: {
            let r = prim.a.w;
            let n = s.ng;
            let rho = max(sqrt(n.x * n.x + n.z * n.z), 1e-6);
            d[0] = 2.0 * PI * r * vec3<f32>(n.z, 0.0, -n.x);
            d[1] = PI * r * vec3<f32>(-n.y * n.x / rho, rho, -n.y * n.z / rho);
        }
#endif
#ifdef HAS_TRIANGLE
        case PRIM_TRIANGLE: {
            var uv0 = vec2<f32>(0.0);
            var uv1 = vec2<f32>(1.0, 0.0);
            var uv2 = vec2<f32>(0.0, 1.0);
            if ((prim.flags & PRIM_FLAG_ATTRIBUTES) != 0u) {
                let a3 = shape_data[prim.data + 3u];
                uv0 = vec2<f32>(shape_data[prim.data].w, a3.x);
                uv1 = vec2<f32>(shape_data[prim.data + 1u].w, a3.y);
                uv2 = vec2<f32>(shape_data[prim.data + 2u].w, a3.z);
            }
            let duv02 = uv0 - uv2;
            let duv12 = uv1 - uv2;
            let dp02 = prim.a.xyz - prim.c.xyz;
            let dp12 = prim.b.xyz - prim.c.xyz;
            let det = duv02.x * duv12.y - duv02.y * duv12.x;
            if (abs(det) > 1e-12) {
                d[0] = (duv12.y * dp02 - duv02.y * dp12) / det;
                d[1] = (duv02.x * dp12 - duv12.x * dp02) / det;
            }
        }
#endif
#ifdef HAS_PLANE
        case PRIM_PLANE: {
            let tb = onb_tangents(prim.b.xyz);
            d[0] = tb[0] / prim.a.w;
            d[1] = tb[1] / prim.a.w;
        }
#endif
#ifdef HAS_BOX
        case PRIM_BOX: {
            let axis = u32(cand.u);
            let i = (axis + 1u) % 3u;
            let j = (axis + 2u) % 3u;
            d[0] = vec3<f32>(0.0);
            d[1] = vec3<f32>(0.0);
            d[0][i] = prim.b[i] - prim.a[i];
            d[1][j] = prim.b[j] - prim.a[j];
        }
#endif
#ifdef HAS_CYLINDER
        case PRIM_CYLINDER: {
            let axis = prim.b.xyz - prim.a.xyz;
            let ax = normalize(axis);
            let q = s.p - prim.a.xyz;
            let radial = q - dot(q, ax) * ax;
            let len = max(length(radial), 1e-12);
            let tb = onb_tangents(ax);
            let c = radial / len;
            // the direction of growing angle (angle_uv), times the circumference's length
            let around = dot(c, tb[0]) * tb[1] - dot(c, tb[1]) * tb[0];
            d[0] = 2.0 * PI * len * around;
            d[1] = select(c * prim.a.w, axis, cand.u == 0.0);
        }
#endif
#ifdef HAS_DISK
        case PRIM_DISK: {
            let n = prim.b.xyz;
            let qp = s.p - prim.a.xyz;
            let len = max(length(qp), 1e-12);
            let tb = onb_tangents(n);
            let c = qp / len;
            let around = dot(c, tb[0]) * tb[1] - dot(c, tb[1]) * tb[0];
            d[0] = 2.0 * PI * len * around;
            d[1] = c * prim.a.w;
        }
#endif
        default: {}
    }
    return d;
}
#endif

// Shading record of a candidate hit, in world space.
fn surface_at(ray: Ray, cand: Candidate) -> Hit {
    let prim = primitive_record(cand.prim);
    var s: Surface;
#ifdef HAS_BUMP
    var dp: array<vec3<f32>, 2>;
#endif
#ifdef HAS_TRANSFORMS
    if ((prim.flags & PRIM_FLAG_TRANSFORM) != 0u) {
        let r = ray_to_object(prim.data, ray);
        let scale = length(r.dir);
        let local = Candidate(cand.t * scale, cand.prim, cand.u, cand.v);
        s = surface_local(prim, Ray(r.origin, r.dir / scale), local);
#ifdef HAS_BUMP
        // tangent vectors go to world space by the object-to-world matrix itself
        dp = surface_uv_derivatives(prim, s, local);
        dp[0] = point_to_world(prim.data, dp[0]) - point_to_world(prim.data, vec3<f32>(0.0));
        dp[1] = point_to_world(prim.data, dp[1]) - point_to_world(prim.data, vec3<f32>(0.0));
#endif
        let p_obj = s.p;
        s.p = point_to_world(prim.data, p_obj);
        s.ng = normal_to_world(prim.data, s.ng);
        s.ns = s.ng;
        s.err = transform_error(prim.data, p_obj, s.err);
    } else {
        s = surface_local(prim, ray, cand);
#ifdef HAS_BUMP
        dp = surface_uv_derivatives(prim, s, cand);
#endif
    }
#else
    s = surface_local(prim, ray, cand);
#ifdef HAS_BUMP
    dp = surface_uv_derivatives(prim, s, cand);
#endif
#endif
#ifdef HAS_UV1
    let uv1 = select(s.uv, s.uv1, (prim.flags & PRIM_FLAG_UV1) != 0u);
#else
    let uv1 = s.uv;
#endif
#ifdef HAS_BUMP
    return Hit(s.p, s.ng, s.ns, vec4<f32>(s.uv, uv1), dot(ray.dir, s.ng) < 0.0, prim.material, s.err, s.tangent, s.color, dp[0], dp[1]);
#else
    return Hit(s.p, s.ng, s.ns, vec4<f32>(s.uv, uv1), dot(ray.dir, s.ng) < 0.0, prim.material, s.err, s.tangent, s.color);
#endif
}
