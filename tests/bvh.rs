//! Tests of the BVH builder: structure, depth limit, degenerate inputs, and closest hits
//! through a generic ordered traversal (the same loop as `intersect_scene`, over a closure)
//! against brute force.
//!
//! Build times are measured by `cargo bench --bench bvh` (docs/bench/bvh.md), not here.

mod common;

use common::icosphere;
use glam::Vec3;
use wgtrace::cpu::geometry::safe_inverse as finite_inv_dir;
use wgtrace::cpu::intersect::bvh_walk;
use wgtrace::cpu::types::{Ray, FAR};
use wgtrace::scene::bvh::{
    build, collapse, Aabb, Bvh, Node as BvhNode, WideBvh, BVH_MAX_DEPTH, BVH_MAX_LEAF_DEPTH,
    BVH_MAX_LEAF_SIZE, BVH_WIDTH, WIDE_LEAF_SIZE,
};

/// Entry distance into a box (clamped to 0), or FAR: the slab test, its exit distance
/// widened by 1 + 2 gamma(3) (pbrt-v4's robust bounds test), so rounding never culls a
/// box the ray touches. The binary tree's traversal below tests its boxes with it.
fn intersect_aabb(lo: Vec3, hi: Vec3, origin: Vec3, inv_dir: Vec3, t_max: f32) -> f32 {
    let t0 = (lo - origin) * inv_dir;
    let t1 = (hi - origin) * inv_dir;
    let t_min = t0.min(t1);
    let t_far = t0.max(t1).min_element() * (1.0 + 3.0 * f32::EPSILON);
    let t_near = t_min.max_element().max(0.0);
    if t_near <= t_far && t_near < t_max {
        return t_near;
    }
    FAR
}

// ---------------------------------------------------------------- helpers

/// Small deterministic PRNG (splitmix64).
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn f(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f()
    }

    fn vec(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }

    /// Uniform direction on the unit sphere.
    fn dir(&mut self) -> Vec3 {
        loop {
            let v = self.vec(-1.0, 1.0);
            let l = v.length_squared();
            if l > 1e-4 && l <= 1.0 {
                return v / l.sqrt();
            }
        }
    }
}

fn node_box(n: &BvhNode) -> Aabb {
    Aabb::new(Vec3::from(n.lo), Vec3::from(n.hi))
}

/// Checks every structural invariant of `bvh` built over `boxes`:
/// `order` is a permutation; nodes form an exact depth-first layout (left
/// child at index + 1, right child at `offset` right after the left
/// subtree, every node reached once); leaves tile `0..n` of `order`; every
/// primitive box lies in its leaf box, leaf boxes are tight, every child box
/// lies in its parent box; leaf sizes respect the limit unless the leaf is
/// at the depth limit or its centroids are all equal; `depth` is the deepest
/// leaf and within the limit.
fn validate(bvh: &Bvh, boxes: &[Aabb]) {
    let n = boxes.len();
    assert_eq!(bvh.order.len(), n);
    let mut seen = vec![false; n];
    for &p in &bvh.order {
        assert!(!seen[p as usize], "order is not a permutation");
        seen[p as usize] = true;
    }
    if n == 0 {
        assert!(bvh.nodes.is_empty());
        assert_eq!(bvh.depth, 0);
        return;
    }

    struct Walk<'a> {
        bvh: &'a Bvh,
        boxes: &'a [Aabb],
        covered: Vec<bool>,
        max_depth: u32,
    }

    impl Walk<'_> {
        /// Validates the subtree at `i`; returns the index just past it.
        fn walk(&mut self, i: usize, depth: u32, parent: Option<Aabb>) -> usize {
            let nodes = &self.bvh.nodes;
            assert!(i < nodes.len(), "node index out of range");
            assert!(depth <= BVH_MAX_LEAF_DEPTH);
            let node = nodes[i];
            let b = node_box(&node);
            assert!(!b.is_empty());
            if let Some(p) = parent {
                assert!(p.contains(&b), "child box {b:?} not in parent {p:?}");
            }
            if node.count > 0 {
                self.max_depth = self.max_depth.max(depth);
                let range = node.offset as usize..(node.offset + node.count) as usize;
                assert!(range.end <= self.bvh.order.len());
                let mut tight = Aabb::empty();
                let first = self.boxes[self.bvh.order[range.start] as usize];
                let mut same_centroid = true;
                for k in range {
                    assert!(!self.covered[k], "order position in two leaves");
                    self.covered[k] = true;
                    let pb = self.boxes[self.bvh.order[k] as usize];
                    assert!(b.contains(&pb), "primitive {pb:?} not in leaf {b:?}");
                    tight = tight.union(&pb);
                    same_centroid &= pb.lo + pb.hi == first.lo + first.hi;
                }
                assert_eq!(tight, b, "leaf box not tight");
                assert!(
                    node.count as usize <= BVH_MAX_LEAF_SIZE
                        || depth == BVH_MAX_LEAF_DEPTH
                        || same_centroid,
                    "oversized leaf ({} prims at depth {depth})",
                    node.count
                );
                i + 1
            } else {
                let left_end = self.walk(i + 1, depth + 1, Some(b));
                assert_eq!(node.offset as usize, left_end, "not depth-first");
                self.walk(left_end, depth + 1, Some(b))
            }
        }
    }

    let mut w = Walk {
        bvh,
        boxes,
        covered: vec![false; n],
        max_depth: 0,
    };
    let end = w.walk(0, 0, None);
    assert_eq!(end, bvh.nodes.len(), "unreachable nodes");
    assert!(w.covered.iter().all(|&c| c), "order position in no leaf");
    assert_eq!(
        w.max_depth, bvh.depth,
        "depth field is not the deepest leaf"
    );
    assert!(bvh.depth <= BVH_MAX_LEAF_DEPTH);
    validate_wide(&collapse(bvh, boxes), boxes);
}

/// Closest hit `(primitive, t)` over all primitives (lowest index on ties).
fn brute_force(n: usize, hit: &impl Fn(usize) -> Option<f32>) -> Option<(usize, f32)> {
    let mut best: Option<(usize, f32)> = None;
    for p in 0..n {
        match hit(p) {
            Some(t) if best.is_none_or(|(_, bt)| t < bt) => best = Some((p, t)),
            _ => {}
        }
    }
    best
}

/// Closest hit through the BVH.
fn via_bvh(
    bvh: &Bvh,
    o: Vec3,
    d: Vec3,
    hit: &impl Fn(usize) -> Option<f32>,
) -> Option<(usize, f32)> {
    let mut best = None;
    traverse(
        &bvh.nodes,
        o,
        finite_inv_dir(d),
        f32::INFINITY,
        |k, t_max| {
            let p = bvh.order[k as usize] as usize;
            let t = hit(p)?;
            if t < t_max {
                best = Some((p, t));
                Some(t)
            } else {
                None
            }
        },
    );
    best
}

/// Closest hit through the renderers' wide BVH (`cpu::intersect::bvh_walk`, the
/// walk of both backends).
fn via_wide(
    wide: &WideBvh,
    o: Vec3,
    d: Vec3,
    hit: &impl Fn(usize) -> Option<f32>,
) -> Option<(usize, f32)> {
    let mut best = None;
    let ray = Ray { origin: o, dir: d };
    bvh_walk(&wide.nodes, 0, &ray, FAR, |k, t_max| {
        let p = wide.order[k as usize] as usize;
        match hit(p) {
            Some(t) if t < t_max => {
                best = Some((p, t));
                Some(t)
            }
            _ => Some(t_max),
        }
    });
    best
}

/// Checks the wide BVH collapsed from a binary tree over `boxes`: every node reached
/// once from the root, at most [`BVH_MAX_LEAF_DEPTH`] deep (its `depth`); every
/// primitive in one leaf of at most [`WIDE_LEAF_SIZE`], a node's leaves' primitives
/// side by side from its `prim`; the meta bytes as documented; and every child's
/// quantized box, decoded in exact arithmetic, holding the boxes of the primitives
/// below it.
fn validate_wide(wide: &WideBvh, boxes: &[Aabb]) {
    let n = boxes.len();
    assert_eq!(wide.order.len(), n);
    let mut sorted = wide.order.clone();
    sorted.sort_unstable();
    assert!(
        sorted.iter().enumerate().all(|(i, &p)| p as usize == i),
        "order is not a permutation"
    );
    if n == 0 {
        assert!(wide.nodes.is_empty());
        return;
    }
    struct Walk<'a> {
        wide: &'a WideBvh,
        boxes: &'a [Aabb],
        reached: Vec<bool>,
        covered: Vec<bool>,
        depth: u32,
    }
    impl Walk<'_> {
        /// The primitive boxes below node i, their union.
        fn walk(&mut self, i: usize, depth: u32) -> Aabb {
            assert!(!self.reached[i], "node {i} reached twice");
            self.reached[i] = true;
            assert!(depth <= BVH_MAX_LEAF_DEPTH);
            self.depth = self.depth.max(depth);
            let node = self.wide.nodes[i];
            let imask = node.scale >> 24;
            let step = |a: u32| f32::from_bits((node.scale >> (8 * a) & 255) << 23) as f64;
            let words = [node.q0, node.q1, node.q2].concat();
            // plane p (lo x, y, z, hi x, y, z) of child s, in the grid
            let q = |p: usize, s: usize| (words[2 * p + s / 4] >> (8 * (s % 4)) & 255) as f64;
            let (mut rank, mut next_prim, mut all) = (0, 0, Aabb::empty());
            for s in 0..BVH_WIDTH {
                let meta = [node.meta0, node.meta1][s / 4] >> (8 * (s % 4)) & 255;
                let below = if imask >> s & 1 == 1 {
                    assert_eq!(meta, 0b0011_1000 | s as u32, "meta of a child node");
                    rank += 1;
                    self.walk((node.child + rank - 1) as usize, depth + 1)
                } else if meta == 0 {
                    continue;
                } else {
                    let (count, offset) = (meta >> 5, meta & 31);
                    assert!(
                        matches!(count, 0b001 | 0b011 | 0b111),
                        "unary count {count:b}"
                    );
                    let count = count.count_ones();
                    assert!(count <= WIDE_LEAF_SIZE);
                    assert_eq!(offset, next_prim, "leaves not side by side in slot order");
                    next_prim += count;
                    let mut b = Aabb::empty();
                    for k in node.prim + offset..node.prim + offset + count {
                        assert!(!self.covered[k as usize], "position {k} in two leaves");
                        self.covered[k as usize] = true;
                        b = b.union(&self.boxes[self.wide.order[k as usize] as usize]);
                    }
                    b
                };
                for a in 0..3 {
                    let origin = node.origin[a as usize] as f64;
                    let lo = origin + step(a) * q(a as usize, s);
                    let hi = origin + step(a) * q(3 + a as usize, s);
                    assert!(
                        lo <= below.lo[a as usize] as f64 && below.hi[a as usize] as f64 <= hi,
                        "child {s} of node {i}: axis {a} [{lo}, {hi}] does not hold [{}, {}]",
                        below.lo[a as usize],
                        below.hi[a as usize]
                    );
                }
                all = all.union(&below);
            }
            assert!(next_prim as usize <= BVH_WIDTH * WIDE_LEAF_SIZE as usize);
            all
        }
    }
    let mut w = Walk {
        wide,
        boxes,
        reached: vec![false; wide.nodes.len()],
        covered: vec![false; n],
        depth: 0,
    };
    w.walk(0, 0);
    assert!(w.reached.iter().all(|&r| r), "unreachable nodes");
    assert!(w.covered.iter().all(|&c| c), "primitive in no leaf");
    assert_eq!(w.depth, wide.depth);
}

/// For every ray, the BVH and the wide BVH collapsed from it find exactly the
/// brute-force closest hit (same primitive and bit-identical t; a different primitive
/// only for an exact tie). Returns the number of rays that hit something.
fn compare_rays<H>(bvh: &Bvh, boxes: &[Aabb], rays: &[(Vec3, Vec3)], hit: H) -> usize
where
    H: Fn(usize, Vec3, Vec3) -> Option<f32>,
{
    let n = boxes.len();
    let wide = collapse(bvh, boxes);
    validate_wide(&wide, boxes);
    let mut hits = 0;
    for (i, &(o, d)) in rays.iter().enumerate() {
        let h = |p: usize| hit(p, o, d);
        let expected = brute_force(n, &h);
        let got = via_bvh(bvh, o, d, &h);
        let got_wide = via_wide(&wide, o, d, &h);
        match (expected, got_wide) {
            (None, None) => {}
            (Some((ep, et)), Some((gp, gt))) => {
                assert_eq!(
                    et.to_bits(),
                    gt.to_bits(),
                    "ray {i}: wide t differs ({ep} vs {gp})"
                );
                if ep != gp {
                    assert_eq!(hit(gp, o, d), Some(et), "ray {i}: wide: not an exact tie");
                }
            }
            _ => panic!("ray {i} ({o}, {d}): brute force {expected:?}, wide bvh {got_wide:?}"),
        }
        match (expected, got) {
            (None, None) => {}
            (Some((ep, et)), Some((gp, gt))) => {
                hits += 1;
                assert_eq!(
                    et.to_bits(),
                    gt.to_bits(),
                    "ray {i}: t differs ({ep} vs {gp})"
                );
                if ep != gp {
                    assert_eq!(hit(gp, o, d), Some(et), "ray {i}: not an exact tie");
                }
            }
            _ => panic!("ray {i} ({o}, {d}): brute force {expected:?}, bvh {got:?}"),
        }
    }
    hits
}

/// Random rays: half in uniform directions, half aimed at random points of `targets`.
fn random_rays(
    rng: &mut Rng,
    count: usize,
    lo: f32,
    hi: f32,
    targets: &[Vec3],
) -> Vec<(Vec3, Vec3)> {
    (0..count)
        .map(|i| {
            let o = rng.vec(lo, hi);
            let d = if i % 2 == 0 || targets.is_empty() {
                rng.dir()
            } else {
                let t = targets[(rng.next_u64() % targets.len() as u64) as usize];
                (t + rng.vec(-0.05, 0.05) - o).normalize()
            };
            (o, d)
        })
        .collect()
}

/// Axis-aligned rays (zero direction components) and a few diagonal ones.
fn axis_rays(rng: &mut Rng, count: usize, lo: f32, hi: f32) -> Vec<(Vec3, Vec3)> {
    let dirs = [
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
        Vec3::new(1.0, 1.0, 0.0).normalize(),
        Vec3::new(0.0, -1.0, 1.0).normalize(),
        Vec3::new(-1.0, 0.0, -1.0).normalize(),
    ];
    (0..count)
        .map(|i| (rng.vec(lo, hi), dirs[i % dirs.len()]))
        .collect()
}

fn ray_sphere(c: Vec3, r: f32, o: Vec3, d: Vec3) -> Option<f32> {
    let oc = o - c;
    let a = d.dot(d);
    let b = oc.dot(d);
    let cc = oc.dot(oc) - r * r;
    let disc = b * b - a * cc;
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    let t0 = (-b - s) / a;
    if t0 > 1e-4 {
        return Some(t0);
    }
    let t1 = (-b + s) / a;
    (t1 > 1e-4).then_some(t1)
}

/// Möller-Trumbore.
fn ray_triangle(v: &[Vec3; 3], o: Vec3, d: Vec3) -> Option<f32> {
    let e1 = v[1] - v[0];
    let e2 = v[2] - v[0];
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - v[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let w = d.dot(q) * inv;
    if w < 0.0 || u + w > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > 1e-4).then_some(t)
}

/// Box primitive hit by the same slab test (entry distance, 0 when inside).
fn ray_box(b: &Aabb, o: Vec3, d: Vec3) -> Option<f32> {
    let t = intersect_aabb(b.lo, b.hi, o, finite_inv_dir(d), f32::INFINITY);
    (t != FAR).then_some(t)
}

fn tri_box(v: &[Vec3; 3]) -> Aabb {
    Aabb::from_points(v)
}

fn random_spheres(rng: &mut Rng, n: usize, extent: f32) -> Vec<(Vec3, f32)> {
    (0..n)
        .map(|_| (rng.vec(-extent, extent), rng.range(0.01, 0.5)))
        .collect()
}

fn sphere_boxes(spheres: &[(Vec3, f32)]) -> Vec<Aabb> {
    spheres
        .iter()
        .map(|&(c, r)| Aabb::new(c - Vec3::splat(r), c + Vec3::splat(r)))
        .collect()
}

/// Small random triangles (edge up to `size`) in a cube of half-width `extent`.
fn random_triangles(rng: &mut Rng, n: usize, extent: f32, size: f32) -> Vec<[Vec3; 3]> {
    (0..n)
        .map(|_| {
            let a = rng.vec(-extent, extent);
            [a, a + rng.vec(-size, size), a + rng.vec(-size, size)]
        })
        .collect()
}

// ---------------------------------------------------------------- (1) structure

#[test]
fn structure_random_boxes() {
    let mut rng = Rng(1);
    for &n in &[3usize, 5, 17, 100, 1000, 50_000] {
        let spheres = random_spheres(&mut rng, n, 20.0);
        let boxes = sphere_boxes(&spheres);
        let bvh = build(&boxes);
        validate(&bvh, &boxes);
    }
}

#[test]
fn structure_parallel_build_is_deterministic() {
    // Large enough for the rayon::join path; must equal a second build.
    let mut rng = Rng(2);
    let tris = random_triangles(&mut rng, 200_000, 50.0, 0.5);
    let boxes: Vec<Aabb> = tris.iter().map(tri_box).collect();
    let a = build(&boxes);
    validate(&a, &boxes);
    let b = build(&boxes);
    assert_eq!(a.nodes, b.nodes);
    assert_eq!(a.order, b.order);
    assert_eq!(a.depth, b.depth);
}

#[test]
fn structure_icosphere() {
    let tris = icosphere(5, 3.0);
    let boxes: Vec<Aabb> = tris.iter().map(tri_box).collect();
    let bvh = build(&boxes);
    validate(&bvh, &boxes);
}

// ---------------------------------------------------------------- (2) traversal == brute force

#[test]
fn traversal_spheres_matches_brute_force() {
    let mut rng = Rng(3);
    let spheres = random_spheres(&mut rng, 3000, 10.0);
    let boxes = sphere_boxes(&spheres);
    let bvh = build(&boxes);
    validate(&bvh, &boxes);
    let centers: Vec<Vec3> = spheres.iter().map(|s| s.0).collect();
    let rays = random_rays(&mut rng, 10_000, -14.0, 14.0, &centers);
    let hits = compare_rays(&bvh, &boxes, &rays, |p, o, d| {
        ray_sphere(spheres[p].0, spheres[p].1, o, d)
    });
    assert!(hits > 5000, "too few hits to be meaningful: {hits}");
}

#[test]
fn traversal_boxes_matches_brute_force() {
    let mut rng = Rng(4);
    let boxes: Vec<Aabb> = (0..3000)
        .map(|_| {
            let c = rng.vec(-10.0, 10.0);
            let h = rng.vec(0.0, 0.6);
            Aabb::new(c - h, c + h)
        })
        .collect();
    let bvh = build(&boxes);
    validate(&bvh, &boxes);
    let centers: Vec<Vec3> = boxes.iter().map(Aabb::centroid).collect();
    let mut rays = random_rays(&mut rng, 10_000, -14.0, 14.0, &centers);
    rays.extend(axis_rays(&mut rng, 2000, -11.0, 11.0));
    let hits = compare_rays(&bvh, &boxes, &rays, |p, o, d| ray_box(&boxes[p], o, d));
    assert!(hits > 5000, "too few hits: {hits}");
}

#[test]
fn traversal_triangles_matches_brute_force() {
    let mut rng = Rng(5);
    let mut tris = random_triangles(&mut rng, 3000, 10.0, 1.0);
    tris.extend(icosphere(4, 4.0)); // 5120 triangles, overlapping the soup
    let boxes: Vec<Aabb> = tris.iter().map(tri_box).collect();
    let bvh = build(&boxes);
    validate(&bvh, &boxes);
    let centers: Vec<Vec3> = tris.iter().map(|t| (t[0] + t[1] + t[2]) / 3.0).collect();
    let mut rays = random_rays(&mut rng, 10_000, -13.0, 13.0, &centers);
    rays.extend(axis_rays(&mut rng, 2000, -11.0, 11.0));
    let hits = compare_rays(&bvh, &boxes, &rays, |p, o, d| ray_triangle(&tris[p], o, d));
    assert!(hits > 5000, "too few hits: {hits}");
}

/// Whether the ray touches box b at a distance in [0, FAR), in f64 (29 more bits than
/// the walk's arithmetic: its rounding is far below the walk's error bound).
fn touches_f64(b: &Aabb, o: Vec3, d: Vec3) -> bool {
    let (mut near, mut far) = (0.0f64, f32::MAX as f64);
    for a in 0..3 {
        let (o, d) = (o[a] as f64, d[a] as f64);
        let (lo, hi) = (b.lo[a] as f64, b.hi[a] as f64);
        if d == 0.0 {
            if o < lo || o > hi {
                return false;
            }
            continue;
        }
        let (t0, t1) = ((lo - o) / d, (hi - o) / d);
        near = near.max(t0.min(t1));
        far = far.min(t0.max(t1));
    }
    near <= far
}

/// The walk never culls a box a ray touches, however it grazes it: rays through the
/// corners, edges and faces of boxes whose planes lie on the nodes' grids (so the
/// quantized boxes are exact, with no slack), from near and far, along and across the
/// axes. Each must be offered every primitive whose box it touches (in f64).
#[test]
fn traversal_never_culls_a_grazed_box() {
    let mut rng = Rng(11);
    let grid = |rng: &mut Rng| (rng.range(-32.0, 32.0) * 8.0).round() / 8.0;
    let boxes: Vec<Aabb> = (0..2000)
        .map(|_| {
            let lo = Vec3::new(grid(&mut rng), grid(&mut rng), grid(&mut rng));
            let size = Vec3::new(
                rng.range(0.0, 2.0),
                rng.range(0.0, 2.0),
                rng.range(0.0, 2.0),
            );
            let size = (size * 8.0).round() / 8.0;
            Aabb::new(lo, lo + size)
        })
        .collect();
    let bvh = build(&boxes);
    let wide = collapse(&bvh, &boxes);
    validate_wide(&wide, &boxes);
    let mut culled = 0;
    let mut touched = 0;
    for i in 0..20_000 {
        let b = boxes[rng.next_u64() as usize % boxes.len()];
        // a corner, an edge or a face point
        let pick = |rng: &mut Rng, a: usize| match rng.next_u64() % 3 {
            0 => b.lo[a],
            1 => b.hi[a],
            _ => rng.range(b.lo[a], b.hi[a]),
        };
        let p = Vec3::new(pick(&mut rng, 0), pick(&mut rng, 1), pick(&mut rng, 2));
        let d = match i % 3 {
            0 => rng.dir(),
            1 => Vec3::new(
                rng.range(-1.0, 1.0),
                1e-3 * rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            )
            .normalize(),
            _ => [
                Vec3::X,
                Vec3::NEG_Y,
                Vec3::Z,
                Vec3::new(1.0, 1.0, 0.0).normalize(),
            ][i % 4],
        };
        let dist = [0.0, 0.5, 100.0, 1e5][(i / 3) % 4];
        let o = p - d * dist;
        let mut offered = vec![false; boxes.len()];
        bvh_walk(&wide.nodes, 0, &Ray { origin: o, dir: d }, FAR, |k, t| {
            offered[wide.order[k as usize] as usize] = true;
            Some(t)
        });
        for (j, bj) in boxes.iter().enumerate() {
            if touches_f64(bj, o, d) {
                touched += 1;
                if !offered[j] {
                    culled += 1;
                }
            }
        }
    }
    assert!(touched > 20_000, "too few boxes touched: {touched}");
    assert_eq!(culled, 0, "{culled} of {touched} touched boxes culled");
}

#[test]
fn traversal_respects_t_max_and_origin_inside() {
    let mut rng = Rng(6);
    let spheres = random_spheres(&mut rng, 500, 5.0);
    let boxes = sphere_boxes(&spheres);
    let bvh = build(&boxes);
    // Rays starting inside the scene, with a finite t_max.
    for _ in 0..2000 {
        let o = rng.vec(-5.0, 5.0);
        let d = rng.dir();
        let t_max = rng.range(0.5, 4.0);
        let h = |p: usize| ray_sphere(spheres[p].0, spheres[p].1, o, d).filter(|&t| t < t_max);
        let expected = brute_force(spheres.len(), &h);
        let mut got = None;
        traverse(&bvh.nodes, o, finite_inv_dir(d), t_max, |k, tm| {
            assert!(tm <= t_max);
            let p = bvh.order[k as usize] as usize;
            let t = ray_sphere(spheres[p].0, spheres[p].1, o, d).filter(|&t| t < tm)?;
            got = Some((p, t));
            Some(t)
        });
        assert_eq!(expected, got);
    }
}

#[test]
fn intersect_aabb_basics() {
    let lo = Vec3::splat(-1.0);
    let hi = Vec3::splat(1.0);
    let inv = finite_inv_dir(Vec3::X);
    assert_eq!(inv, Vec3::new(1.0, 1e30, 1e30));
    assert_eq!(
        finite_inv_dir(Vec3::new(-0.0, -1e-31, 2.0)),
        Vec3::new(1e30, -1e30, 0.5)
    );
    // Entry distance, origin inside (0), behind, beyond t_max, parallel miss.
    assert_eq!(
        intersect_aabb(lo, hi, Vec3::new(-3.0, 0.0, 0.0), inv, FAR),
        2.0
    );
    assert_eq!(intersect_aabb(lo, hi, Vec3::ZERO, inv, FAR), 0.0);
    assert_eq!(
        intersect_aabb(lo, hi, Vec3::new(3.0, 0.0, 0.0), inv, FAR),
        FAR
    );
    assert_eq!(
        intersect_aabb(lo, hi, Vec3::new(-3.0, 0.0, 0.0), inv, 2.0),
        FAR
    );
    assert_eq!(
        intersect_aabb(lo, hi, Vec3::new(-3.0, 2.0, 0.0), inv, FAR),
        FAR
    );
    // Ray in the plane of the lo face with a zero component: hit.
    assert_eq!(
        intersect_aabb(lo, hi, Vec3::new(-3.0, -1.0, 0.0), inv, FAR),
        2.0
    );
    // Flat box (zero extent on z) hit head-on along z: no NaN.
    let (flo, fhi) = (Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 1.0, 1.0));
    let t = intersect_aabb(
        flo,
        fhi,
        Vec3::new(0.5, 0.5, -1.0),
        finite_inv_dir(Vec3::Z),
        FAR,
    );
    assert_eq!(t, 2.0);
}

// ---------------------------------------------------------------- (3) degenerate inputs

#[test]
fn degenerate_empty() {
    let bvh = build(&[]);
    assert!(bvh.nodes.is_empty() && bvh.order.is_empty());
    assert_eq!(bvh.depth, 0);
    let mut called = false;
    traverse(&bvh.nodes, Vec3::ZERO, Vec3::ONE, FAR, |_, _| {
        called = true;
        None
    });
    assert!(!called);
}

#[test]
fn degenerate_one_and_two() {
    let one = [Aabb::new(Vec3::ZERO, Vec3::ONE)];
    let bvh = build(&one);
    validate(&bvh, &one);
    assert_eq!(bvh.nodes.len(), 1);
    assert_eq!(bvh.nodes[0].count, 1);
    assert_eq!(bvh.nodes[0].offset, 0);
    assert_eq!(bvh.order, vec![0]);
    assert_eq!(bvh.depth, 0);

    let spheres = [
        (Vec3::new(-2.0, 0.0, 0.0), 0.5),
        (Vec3::new(2.0, 0.3, 0.0), 0.7),
    ];
    let two = sphere_boxes(&spheres);
    let bvh = build(&two);
    validate(&bvh, &two);
    assert_eq!(bvh.nodes.len(), 3, "two far-apart spheres should split");
    let mut rng = Rng(7);
    let centers = [spheres[0].0, spheres[1].0];
    let mut rays = random_rays(&mut rng, 2000, -4.0, 4.0, &centers);
    rays.extend(axis_rays(&mut rng, 500, -3.0, 3.0));
    compare_rays(&bvh, &two, &rays, |p, o, d| {
        ray_sphere(spheres[p].0, spheres[p].1, o, d)
    });
}

#[test]
fn degenerate_identical_boxes() {
    let b = Aabb::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(1.5, 2.5, 3.5));
    let boxes = vec![b; 10_000];
    let bvh = build(&boxes);
    validate(&bvh, &boxes);
    assert_eq!(bvh.nodes.len(), 1, "identical centroids -> one leaf");
    assert_eq!(bvh.nodes[0].count, 10_000);
    let rays = [(Vec3::ZERO, (b.centroid()).normalize())];
    compare_rays(&bvh, &boxes, &rays, |p, o, d| ray_box(&boxes[p], o, d));
}

#[test]
fn degenerate_same_centroid_different_sizes() {
    // Nested boxes around one centre: centroids equal, extents differ.
    let boxes: Vec<Aabb> = (1..=50)
        .map(|i| Aabb::new(Vec3::splat(-(i as f32)), Vec3::splat(i as f32)))
        .collect();
    let bvh = build(&boxes);
    validate(&bvh, &boxes);
    assert_eq!(bvh.nodes.len(), 1);
}

#[test]
fn degenerate_flat_boxes() {
    // Rectangles in the plane z = 0 (zero extent on z).
    let mut rng = Rng(8);
    let rects: Vec<Aabb> = (0..3000)
        .map(|_| {
            let c = Vec3::new(rng.range(-10.0, 10.0), rng.range(-10.0, 10.0), 0.0);
            let h = Vec3::new(rng.range(0.0, 0.4), rng.range(0.0, 0.4), 0.0);
            Aabb::new(c - h, c + h)
        })
        .collect();
    let bvh = build(&rects);
    validate(&bvh, &rects);
    let hit_rect = |p: usize, o: Vec3, d: Vec3| -> Option<f32> {
        if d.z == 0.0 {
            return None;
        }
        let t = -o.z / d.z;
        let q = o + d * t;
        let r = &rects[p];
        (t > 0.0 && q.x >= r.lo.x && q.x <= r.hi.x && q.y >= r.lo.y && q.y <= r.hi.y).then_some(t)
    };
    let mut rays = Vec::new();
    for i in 0..4000 {
        let o = Vec3::new(
            rng.range(-11.0, 11.0),
            rng.range(-11.0, 11.0),
            rng.range(-5.0, 5.0),
        );
        let d = match i % 4 {
            // Straight down/up: zero x and y components.
            0 => Vec3::new(0.0, 0.0, -o.z.signum()),
            // Zero x component only.
            1 => Vec3::new(0.0, rng.range(-1.0, 1.0), -o.z).normalize(),
            // Parallel to the plane: must miss everything.
            2 => Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 0.0).normalize(),
            _ => rng.dir(),
        };
        rays.push((o, d));
    }
    let hits = compare_rays(&bvh, &rects, &rays, hit_rect);
    assert!(hits > 500, "too few hits: {hits}");
}

#[test]
fn degenerate_points_on_a_line() {
    // Zero-volume, zero-area boxes: all SAH costs are 0, ties must balance.
    let mut rng = Rng(9);
    let boxes: Vec<Aabb> = (0..10_000)
        .map(|_| {
            let p = Vec3::new(rng.range(-100.0, 100.0), 1.0, 2.0);
            Aabb::new(p, p)
        })
        .collect();
    let bvh = build(&boxes);
    validate(&bvh, &boxes);
    assert!(
        bvh.depth <= 20,
        "unbalanced tree over points: depth {}",
        bvh.depth
    );
    let rays = axis_rays(&mut rng, 500, -100.0, 100.0);
    compare_rays(&bvh, &boxes, &rays, |p, o, d| ray_box(&boxes[p], o, d));
}

#[test]
fn degenerate_tiny_extent() {
    // Centroids differing by denormal-sized amounts.
    let boxes: Vec<Aabb> = (0..100)
        .map(|i| {
            let p = Vec3::new(i as f32 * 1e-44, 0.0, 0.0);
            Aabb::new(p, p + Vec3::splat(1e-45))
        })
        .collect();
    let bvh = build(&boxes);
    validate(&bvh, &boxes);
}

#[test]
fn degenerate_non_finite_boxes_do_not_panic() {
    // Not supported input, but the builder must terminate without panicking.
    let mut rng = Rng(11);
    let mut boxes: Vec<Aabb> = (0..5000)
        .map(|_| {
            let c = rng.vec(-10.0, 10.0);
            Aabb::new(c, c + Vec3::splat(0.1))
        })
        .collect();
    boxes[10].lo.x = f32::NAN;
    boxes[20].hi = Vec3::INFINITY;
    boxes[30].lo = Vec3::NEG_INFINITY;
    boxes[40] = Aabb::empty();
    let bvh = build(&boxes);
    let mut seen = vec![false; boxes.len()];
    for &p in &bvh.order {
        assert!(!std::mem::replace(&mut seen[p as usize], true));
    }
    assert!(seen.iter().all(|&s| s));
    assert!(bvh.depth <= BVH_MAX_LEAF_DEPTH);
    let wide = collapse(&bvh, &boxes);
    let mut seen = vec![false; boxes.len()];
    for &p in &wide.order {
        assert!(!std::mem::replace(&mut seen[p as usize], true));
    }
    assert!(seen.iter().all(|&s| s));
    assert!(wide.depth <= BVH_MAX_LEAF_DEPTH);
}

// ---------------------------------------------------------------- (4) depth limit

/// Boxes at `base^i` along x (i = 0..count): SAH keeps cutting off the
/// few largest boxes, so the tree is very unbalanced.
fn exponential_boxes(base: f32, count: i32) -> Vec<Aabb> {
    (0..count)
        .map(|i| {
            let x = base.powi(i);
            Aabb::new(Vec3::new(x, 0.0, 0.0), Vec3::new(x * 1.25, 1.0, 1.0))
        })
        .collect()
}

/// Boxes `[x, 1.25x] x [0, x] x [0, x]` with `x = 2^e`, `e = lo..=hi`: the
/// SAH cost of a node is dominated by its largest boxes, so every split
/// cuts off only the top centroid bin (about 4 boxes) and the centroid range
/// shrinks by only 16x per level. Spanning 2^130 this needs about 33 levels,
/// more than the limit.
fn scaled_exponential_boxes(lo: i32, hi: i32) -> Vec<Aabb> {
    (lo..=hi)
        .map(|e| {
            let x = 2f32.powi(e);
            Aabb::new(Vec3::new(x, 0.0, 0.0), Vec3::new(1.25 * x, x, x))
        })
        .collect()
}

#[test]
fn depth_limit_adversarial() {
    let cases = [
        // Positions stay below ~2e18 so that rays from 1e19 away stay exact
        // (a zero direction component acts like 1e-30: drift of t * 1e-30).
        ("2^i", exponential_boxes(2.0, 61), false),
        ("1.2^i", exponential_boxes(1.2, 230), false),
        ("scaled 2^i", scaled_exponential_boxes(-70, 60), true),
        (
            "scaled 2^i (short)",
            scaled_exponential_boxes(-60, 55),
            true,
        ),
    ];
    for (name, boxes, expect_limit) in cases {
        assert!(boxes.iter().all(|b| b.lo.is_finite() && b.hi.is_finite()));
        let bvh = build(&boxes);
        validate(&bvh, &boxes);
        println!("{name}: depth {}, nodes {}", bvh.depth, bvh.nodes.len());
        if expect_limit {
            assert_eq!(bvh.depth, BVH_MAX_LEAF_DEPTH, "{name}: limit not reached");
            let deep = bvh
                .nodes
                .iter()
                .filter(|n| n.count as usize > BVH_MAX_LEAF_SIZE);
            assert!(
                deep.count() > 0,
                "{name}: expected an oversized leaf at the limit"
            );
        }
        // The ray along +x on the y = z = 0 faces enters every box, so the
        // deepest paths are walked with the fixed BVH_MAX_DEPTH-entry stack.
        let far = 1e19;
        let rays = [
            (Vec3::new(-1.0, 0.0, 0.0), Vec3::X),
            (Vec3::new(-far, 0.5, 0.5), Vec3::X),
            (Vec3::new(far, 0.5, 0.5), Vec3::NEG_X),
            (Vec3::new(-1.0, 0.25, 0.75), Vec3::X),
            (
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 1e-30, 1e-30).normalize(),
            ),
            (Vec3::new(-1.0, -1.0, -1.0), Vec3::ONE.normalize()),
        ];
        compare_rays(&bvh, &boxes, &rays, |p, o, d| ray_box(&boxes[p], o, d));
        // A closure that never reports a hit must be offered every primitive.
        let mut tested = 0;
        traverse(
            &bvh.nodes,
            rays[0].0,
            finite_inv_dir(rays[0].1),
            FAR,
            |_, _| {
                tested += 1;
                None
            },
        );
        assert_eq!(tested, boxes.len(), "{name}: not every leaf visited");
    }
    assert_eq!(BVH_MAX_LEAF_DEPTH, BVH_MAX_DEPTH - 1);
}

/// Ordered closest-hit traversal over a closure `hit(position in order, t_max)`.
/// Ordered closest-hit traversal: calls `hit(prim_index, t_max) -> Option<f32>`
/// (a hit closer than t_max) for each primitive of each visited leaf, visits
/// the nearer child first, skips nodes whose entry distance is >= the closest
/// hit so far. Returns nothing; the closure records the best hit.
///
/// `prim_index` is the *position in `Bvh::order`* (`offset + i` of the
/// leaf), not the original primitive index: use `order[prim_index]` or a
/// primitive buffer already permuted by `order`. `t_max` passed to `hit` is
/// the closest hit so far (initially the `t_max` argument); a returned value
/// that is not below it is ignored.
///
/// Mirrors the WGSL loop: a fixed stack of far children (with their entry
/// distances), at most `BVH_MAX_LEAF_DEPTH` entries deep (see module docs).
fn traverse(
    nodes: &[BvhNode],
    origin: Vec3,
    inv_dir: Vec3,
    t_max: f32,
    mut hit: impl FnMut(u32, f32) -> Option<f32>,
) {
    if nodes.is_empty() {
        return;
    }
    let mut closest = t_max;
    let root = nodes[0];
    if intersect_aabb(
        Vec3::from(root.lo),
        Vec3::from(root.hi),
        origin,
        inv_dir,
        closest,
    ) == FAR
    {
        return;
    }

    let mut stack_node = [0u32; BVH_MAX_DEPTH as usize];
    let mut stack_t = [0.0f32; BVH_MAX_DEPTH as usize];
    let mut sp = 0usize;
    let mut current = 0u32;
    loop {
        let node = nodes[current as usize];
        let mut descend = false;
        if node.count > 0 {
            // Leaf: test its primitives, shrinking the search interval.
            for i in 0..node.count {
                if let Some(t) = hit(node.offset + i, closest) {
                    closest = closest.min(t);
                }
            }
        } else {
            // Interior: test both children, go to the nearer, push the farther.
            let left = current + 1;
            let right = node.offset;
            let l = nodes[left as usize];
            let r = nodes[right as usize];
            let t_left =
                intersect_aabb(Vec3::from(l.lo), Vec3::from(l.hi), origin, inv_dir, closest);
            let t_right =
                intersect_aabb(Vec3::from(r.lo), Vec3::from(r.hi), origin, inv_dir, closest);
            if t_left != FAR && t_right != FAR {
                let (near, far, t_far) = if t_right < t_left {
                    (right, left, t_left)
                } else {
                    (left, right, t_right)
                };
                stack_node[sp] = far;
                stack_t[sp] = t_far;
                sp += 1;
                current = near;
                descend = true;
            } else if t_left != FAR {
                current = left;
                descend = true;
            } else if t_right != FAR {
                current = right;
                descend = true;
            }
        }
        if !descend {
            // Pop the next pending node still entered before the closest hit.
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                if stack_t[sp] < closest {
                    current = stack_node[sp];
                    break;
                }
            }
        }
    }
}
