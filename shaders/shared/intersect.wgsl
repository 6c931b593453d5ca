// Ray-scene intersection: the object-space wrapper for transformed primitives, the
// closest-hit search (the unbounded primitives, then the BVH or the per-type loops), and
// surface_at (hit point, normals, uv, error bound). Each primitive type's own functions
// are its file's (shaders/primitives/NAME.wgsl), reached through the dispatch
// gpu::codegen::primitives writes from the type list: intersect_local, surface_local,
// surface_uv_derivatives, intersect_each_type. Every intersection returns FAR for a miss.
#import shared/bindings
#import shared/geometry
#import shared/sampling
#import shared/types
#import generated/primitives

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
#ifndef REGISTER_STACK
var<workgroup> bvh_stack: array<vec2<u32>, BVH_STACK_SIZE * BVH_STACK_LANES>;
#endif
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

#ifdef HAS_INSTANCES
// intersect_bounded for a record already fetched (the walk reads its tag first, for
// instances).
fn intersect_bounded_record(prim: Primitive, ray: Ray, t_max: f32) -> vec3<f32> {
#ifdef BOUNDED_TRIANGLES_ONLY
    return intersect_record(prim, PRIM_TRIANGLE, ray, t_max);
#else
    return intersect_record(prim, prim.tag, ray, t_max);
#endif
}
#endif

// The closer of the closest hit so far and hit h = (t, u, v) of primitive i.
fn closer_hit(best: Candidate, i: u32, h: vec3<f32>) -> Candidate {
    if (h.x < best.t) {
#ifdef HAS_INSTANCES
        return Candidate(h.x, i, h.y, h.z, NO_HIT);
#else
        return Candidate(h.x, i, h.y, h.z);
#endif
    }
    return best;
}

#ifdef HAS_INSTANCES
// closer_hit for primitive i of a group, hit through instance inst (NO_HIT: a primitive
// of the scene's own).
fn closer_hit_in(best: Candidate, i: u32, h: vec3<f32>, inst: u32) -> Candidate {
    if (h.x < best.t) {
        return Candidate(h.x, i, h.y, h.z, inst);
    }
    return best;
}

// The no-hit candidate of a search before t_max.
fn no_candidate(t_max: f32) -> Candidate {
    return Candidate(t_max, NO_HIT, 0.0, 0.0, NO_HIT);
}
#endif

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
#ifdef REGISTER_STACK
// The walk's stack in registers (gpu::plan::REGISTER_STACK, for trees of depth at most
// BVH_REGISTER_STACK): e0 is the top; a push moves every entry one down, a pop one up.
// llvmpipe blends the 8 entries under the lanes' mask, where a store to workgroup memory
// and a load from it are each a scalar loop over the lanes.
struct WalkStack {
    e0: vec2<u32>,
    e1: vec2<u32>,
    e2: vec2<u32>,
    e3: vec2<u32>,
    e4: vec2<u32>,
    e5: vec2<u32>,
    e6: vec2<u32>,
    e7: vec2<u32>,
    size: u32,
}

fn walk_push(s: ptr<function, WalkStack>, group: vec2<u32>) {
    (*s).e7 = (*s).e6;
    (*s).e6 = (*s).e5;
    (*s).e5 = (*s).e4;
    (*s).e4 = (*s).e3;
    (*s).e3 = (*s).e2;
    (*s).e2 = (*s).e1;
    (*s).e1 = (*s).e0;
    (*s).e0 = group;
    (*s).size += 1u;
}

fn walk_pop(s: ptr<function, WalkStack>) -> vec2<u32> {
    let group = (*s).e0;
    (*s).e0 = (*s).e1;
    (*s).e1 = (*s).e2;
    (*s).e2 = (*s).e3;
    (*s).e3 = (*s).e4;
    (*s).e4 = (*s).e5;
    (*s).e5 = (*s).e6;
    (*s).e6 = (*s).e7;
    (*s).size -= 1u;
    return group;
}

// The walk's next node: the highest node bit of the group (which must hold one) is taken
// from it and the rest of the group pushed if it holds more.
fn bvh_take(group: ptr<function, vec2<u32>>, stack: ptr<function, WalkStack>, order: u32) -> u32 {
#else
// The walk's next node: the highest node bit of the group (which must hold one) is taken
// from it and the rest of the group pushed (bvh_stack at sp) if it holds more.
fn bvh_take(group: ptr<function, vec2<u32>>, sp: ptr<function, u32>, order: u32) -> u32 {
#endif
    let bit = firstLeadingBit((*group).y);
    (*group).y ^= 1u << bit;
    let slot = (bit - 24u) ^ order;
    let index = (*group).x + countOneBits((*group).y & ((1u << slot) - 1u));
    if (((*group).y & BVH_NODE_BITS) != 0u) {
#ifdef REGISTER_STACK
        walk_push(stack, *group);
#else
        bvh_stack[*sp] = *group;
        *sp += BVH_STACK_LANES;
#endif
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
#ifdef HAS_INSTANCES
    var best = no_candidate(t_max);
#else
    var best = Candidate(t_max, NO_HIT, 0.0, 0.0);
#endif
#ifdef HAS_UNBOUNDED
    // (without unbounded primitives llvmpipe would still run this loop's body once,
    // masked off)
    for (var i = 0u; i < params.num_unbounded; i++) {
        best = closer(best, i, ray);
    }
#endif
#ifdef HAS_PRIMITIVE_LOOP
    if (params.use_bvh == 0u) {
        // Without the BVH the bounded primitives are sorted by type
        // (scene::primitives::sort_for_loops), and each type present gets a loop whose
        // body holds only its own test (intersect_each_type, written from the type list in
        // the same order): llvmpipe runs every case of a switch under a mask.
        best = intersect_each_type(ray, best);
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
#ifdef HAS_UNBOUNDED
    for (var i = 0u; i < params.num_unbounded; i++) {
        if (intersect_primitive(i, ray, t_max).x < t_max) {
            return true;
        }
    }
#endif
#ifdef HAS_INSTANCES
    return bvh_walk(ray, no_candidate(t_max), true).prim != NO_HIT;
#else
    return bvh_walk(ray, Candidate(t_max, NO_HIT, 0.0, 0.0), true).prim != NO_HIT;
#endif
}

// The BVH walk of intersect_scene and occluded_bvh (the CPU's bvh_walk): the closest hit
// nearer than start's, or, with any_hit (a constant at each call, which the compiler
// folds), the first one found, the walk ending there (a shadow ray's). The walk's two
// groups (bvh_node_hits): child nodes still to visit (a stack entry) and primitives to
// test; sp indexes bvh_stack (the entries of this lane are BVH_STACK_LANES apart; with
// REGISTER_STACK it is the WalkStack itself); the
// root is a group of one child node, in slot 0. Boxes are culled against the closest hit
// so far (an any-hit walk ends at its first, so it culls against t_max only).
// With instances (HAS_INSTANCES), a primitive of the walk may be an instance: the
// primitive loop stops there, and the walk pushes the node's child nodes still to visit,
// keeps the leaf's other primitives and the ray, and goes on at the root of the
// instance's group, with the ray in the group's space (a unit direction; distances,
// best.t among them, times inst_scale, at most FAR) and the stack above the entries it had
// (inst_sp; NO_HIT outside an instance); when the group's walk has no node left, it takes
// the ray and the rest of the leaf back. Both happen once per turn of the outer loop, not
// in the node and primitive loops (llvmpipe would run them, masked, on every step). One
// loop, one stack: a lane in an instance and one outside it step together (flatten checks
// that both BVHs' depths fit the stack).
#ifdef HAS_INSTANCES
fn bvh_walk(world_ray: Ray, start: Candidate, any_hit: bool) -> Candidate {
    var best = start;
    if (params.num_primitives == params.num_unbounded) {
        return best;
    }
    var ray = world_ray;
    var inv_dir = safe_inverse(ray.dir);
    var order = bvh_order(inv_dir);
    var inst = NO_HIT;
    var inst_sp = NO_HIT;
    var inst_scale = 1.0;
    var inst_prims = vec2<u32>(0u, 0u);
    var world_t = 0.0;
    // the instance the primitive loop stopped at (NO_HIT: none), its transform's and its
    // group's root's indices
    var entering = NO_HIT;
    var entering_data = 0u;
    var entering_root = 0u;
#else
fn bvh_walk(ray: Ray, start: Candidate, any_hit: bool) -> Candidate {
    var best = start;
    if (params.num_primitives == params.num_unbounded) {
        return best;
    }
    let inv_dir = safe_inverse(ray.dir);
    let order = bvh_order(inv_dir);
#endif
#ifdef REGISTER_STACK
    var sp: WalkStack;
#else
    var sp = stack_lane;
#endif
    var group = vec2<u32>(0u, (1u << (24u + order)) | 1u);
    var prims = vec2<u32>(0u, 0u);
    var live = true;
    loop {
#ifdef HAS_INSTANCES
        // (the rest of a leaf after an instance is tested before any node)
        if (prims.y == 0u) {
#endif
        // Nodes until the lane has primitives to test (tested after the loop, when every
        // lane of the subgroup has some) or none is left.
        loop {
            if ((group.y & BVH_NODE_BITS) == 0u) {
#ifdef HAS_INSTANCES
                if (sp == inst_sp) {
                    // the group's walk is over (left below)
                    break;
                }
#endif
#ifdef REGISTER_STACK
                if (sp.size == 0u) {
                    live = false;
                    break;
                }
                group = walk_pop(&sp);
#else
                if (sp == stack_lane) {
                    live = false;
                    break;
                }
                sp -= BVH_STACK_LANES;
                group = bvh_stack[sp];
#endif
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
#ifdef HAS_INSTANCES
        }
#endif
        loop {
            if (prims.y == 0u) {
                break;
            }
#ifdef HAS_LANE_STATS
            count_lanes(2u);
#endif
            let k = prims.x + firstTrailingBit(prims.y);
            prims.y &= prims.y - 1u;
#ifdef HAS_INSTANCES
            let prim = primitive_record(k);
            if (prim.tag == PRIM_INSTANCE) {
                // entered below
                entering = k;
                entering_data = prim.data;
                entering_root = bitcast<u32>(prim.a.x);
                break;
            }
            best = closer_hit_in(best, k, intersect_bounded_record(prim, ray, best.t), inst);
#else
            best = closer_hit(best, k, intersect_bounded(k, ray, best.t));
#endif
            if (any_hit && best.prim != NO_HIT) {
                live = false;
                break;
            }
        }
        if (!live) {
            break;
        }
#ifdef HAS_INSTANCES
        if (entering != NO_HIT) {
            // into the instance's group: the node's child nodes still to visit go on the
            // stack, under the group's entries
            if ((group.y & BVH_NODE_BITS) != 0u) {
                bvh_stack[sp] = group;
                sp += BVH_STACK_LANES;
            }
            inst = entering;
            entering = NO_HIT;
            inst_sp = sp;
            inst_prims = prims;
            prims.y = 0u;
            world_t = best.t;
            let r = ray_to_object(entering_data, world_ray);
            inst_scale = length(r.dir);
            ray = Ray(r.origin, r.dir / inst_scale);
            // below FAR, which a miss returns
            best.t = min(best.t * inst_scale, FAR);
            inv_dir = safe_inverse(ray.dir);
            order = bvh_order(inv_dir);
            group = vec2<u32>(entering_root, (1u << (24u + order)) | 1u);
        } else if (sp == inst_sp && (group.y & BVH_NODE_BITS) == 0u) {
            // the group's walk is over: the scene's ray, and the rest of its leaf
            ray = world_ray;
            best.t = select(world_t, best.t / inst_scale, best.inst == inst);
            inv_dir = safe_inverse(ray.dir);
            order = bvh_order(inv_dir);
            inst = NO_HIT;
            inst_sp = NO_HIT;
            prims = inst_prims;
        }
#endif
    }
    return best;
}
#endif

#ifdef HAS_INSTANCES
// Shading record of a candidate hit, in world space: a hit through an instance is the
// group primitive's in the group's space (the ray there with a unit direction, as the
// walk had it), placed by the instance's transform.
fn surface_at(ray: Ray, cand: Candidate) -> Hit {
    if (cand.inst == NO_HIT) {
        return surface_own(ray, cand);
    }
    let data = primitive_record(cand.inst).data;
    let r = ray_to_object(data, ray);
    let scale = length(r.dir);
    var h = surface_own(Ray(r.origin, r.dir / scale), Candidate(cand.t * scale, cand.prim, cand.u, cand.v, NO_HIT));
    let p_obj = h.p;
    h.p = point_to_world(data, p_obj);
    h.ng = normal_to_world(data, h.ng);
    h.ns = normal_to_world(data, h.ns);
    h.unmapped = h.ns;
    h.err = transform_error(data, p_obj, h.err);
    h.front_face = dot(ray.dir, h.ng) < 0.0;
    // tangent vectors by the object-to-world matrix itself; a mirror flips the
    // bitangent's handedness
    let origin = point_to_world(data, vec3<f32>(0.0));
    let linear_det = dot(cross(shape_data[data].xyz, shape_data[data + 1u].xyz), shape_data[data + 2u].xyz);
    h.tangent = vec4<f32>(point_to_world(data, h.tangent.xyz) - origin, select(h.tangent.w, -h.tangent.w, linear_det < 0.0));
#ifdef HAS_BUMP
    h.dpdu = point_to_world(data, h.dpdu) - origin;
    h.dpdv = point_to_world(data, h.dpdv) - origin;
#endif
    return h;
}

// surface_at for a hit on a primitive of its own space (the scene's, or a group's in the
// group's space).
fn surface_own(ray: Ray, cand: Candidate) -> Hit {
#else
// Shading record of a candidate hit, in world space.
fn surface_at(ray: Ray, cand: Candidate) -> Hit {
#endif
    let prim = primitive_record(cand.prim);
    var s: Surface;
#ifdef HAS_BUMP
    var dp: array<vec3<f32>, 2>;
#endif
#ifdef HAS_TRANSFORMS
    if ((prim.flags & PRIM_FLAG_TRANSFORM) != 0u) {
        let r = ray_to_object(prim.data, ray);
        let scale = length(r.dir);
#ifdef HAS_INSTANCES
        let local = Candidate(cand.t * scale, cand.prim, cand.u, cand.v, NO_HIT);
#else
        let local = Candidate(cand.t * scale, cand.prim, cand.u, cand.v);
#endif
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
    return Hit(s.p, s.ng, s.ns, s.ns, vec4<f32>(s.uv, uv1), dot(ray.dir, s.ng) < 0.0, prim.material, s.err, s.tangent, s.color, dp[0], dp[1]);
#else
    return Hit(s.p, s.ng, s.ns, s.ns, vec4<f32>(s.uv, uv1), dot(ray.dir, s.ng) < 0.0, prim.material, s.err, s.tangent, s.color);
#endif
}
