//! Bounding volume hierarchy over primitive boxes: a parallel binned-SAH builder of a
//! binary tree ([`build`]), which [`collapse`] turns into the compressed 8-wide tree the
//! renderers walk ([`BvhNode`]; `intersect_scene` in `shaders/shared/intersect.wgsl` and
//! its CPU twin).
//!
//! # Layout of the binary tree ([`Node`])
//!
//! * `nodes` is in depth-first (pre-)order; `nodes[0]` is the root.
//! * Interior node (`count == 0`): its first child is `nodes[index + 1]`, its
//!   second child is `nodes[offset]`.
//! * Leaf (`count > 0`): it covers *positions* `offset .. offset + count` of
//!   [`Bvh::order`]; `order[k]` is the index of the original primitive (the
//!   index into the `boxes` slice given to [`build`]). A renderer usually
//!   permutes its primitive buffer once by `order` (`new[k] = old[order[k]]`)
//!   so that the GPU indexes primitives directly with `offset + i`.
//! * A box of a node is the exact union of the boxes of the primitives below it.
//!
//! # Depth limit
//!
//! The root has depth 0 and every leaf has depth `<= BVH_MAX_LEAF_DEPTH`
//! (`= BVH_MAX_DEPTH - 1 = 31`). Hence every interior node has depth `<= 30`.
//! A traversal that pushes the far child and descends into the near one holds
//! at most one pending entry per interior ancestor, i.e. at most
//! `leaf depth <= 31` entries; even the simpler "pop a node, push both
//! children" traversal holds at most `(interior depth) + 2 <= 32` entries (plus
//! the root pushed first, already popped by then). Both therefore fit in a
//! `BVH_MAX_DEPTH`-entry stack. [`build`] asserts the limit.

use super::records::{BvhNode, BVH_STACK_SIZE};
use glam::{DVec3, Vec3, Vec3A};
use rayon::prelude::*;

/// A node of the binary tree [`build`] makes. Interior (`count` = 0): the first child is
/// the next node and the second `nodes[offset]`. Leaf: positions `offset..offset + count`
/// of [`Bvh::order`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Node {
    pub lo: [f32; 3],
    pub offset: u32,
    pub hi: [f32; 3],
    pub count: u32,
}

/// Size of the traversal stack (`BVH_STACK_SIZE` in WGSL and the CPU twin).
pub const BVH_MAX_DEPTH: u32 = BVH_STACK_SIZE;

/// Deepest allowed leaf (root = depth 0); see the module docs for why this
/// keeps every traversal stack within [`BVH_MAX_DEPTH`] entries.
pub const BVH_MAX_LEAF_DEPTH: u32 = BVH_MAX_DEPTH - 1;

/// Leaves hold at most this many primitives, except when a node cannot be
/// split (all centroids equal) or sits at [`BVH_MAX_LEAF_DEPTH`].
/// Nodes with at most this many primitives become leaves when SAH says a leaf
/// is not more expensive than the best split.
pub const BVH_MAX_LEAF_SIZE: usize = 3;

/// SAH cost of visiting an interior node (testing the boxes of its two
/// children), relative to [`SAH_INTERSECTION_COST`].
pub const SAH_TRAVERSAL_COST: f32 = 1.0;

/// SAH cost of one ray-primitive intersection test.
pub const SAH_INTERSECTION_COST: f32 = 1.0;

/// Number of centroid bins per axis; all three axes are binned at every node.
/// Nodes with fewer than `SAH_BINS / 2` primitives use `2 n` bins.
pub const SAH_BINS: usize = 16;

/// Subtrees with at least this many primitives build their two children in
/// parallel (`rayon::join`); smaller ones are built sequentially.
const PARALLEL_MIN_PRIMS: usize = 16 * 1024;

/// Axis-aligned bounding box. An empty box has `lo = +inf`, `hi = -inf`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub lo: Vec3,
    pub hi: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::empty()
    }
}

impl Aabb {
    /// The empty box (identity of [`Aabb::union`]).
    pub const EMPTY: Aabb = Aabb {
        lo: Vec3::INFINITY,
        hi: Vec3::NEG_INFINITY,
    };

    /// Box with the given corners (`lo <= hi` component-wise).
    pub fn new(lo: Vec3, hi: Vec3) -> Self {
        Self { lo, hi }
    }

    /// The empty box.
    pub fn empty() -> Self {
        Self::EMPTY
    }

    /// Smallest box containing all `points` (empty for no points).
    pub fn from_points(points: &[Vec3]) -> Self {
        let mut b = Self::EMPTY;
        for &p in points {
            b.grow(p);
        }
        b
    }

    /// True when the box contains no point (`lo > hi` on some axis).
    pub fn is_empty(&self) -> bool {
        self.lo.cmpgt(self.hi).any()
    }

    /// Grows the box to contain point `p`.
    pub fn grow(&mut self, p: Vec3) {
        self.lo = self.lo.min(p);
        self.hi = self.hi.max(p);
    }

    /// Smallest box containing both boxes.
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb {
            lo: self.lo.min(other.lo),
            hi: self.hi.max(other.hi),
        }
    }

    /// Center of the box.
    pub fn centroid(&self) -> Vec3 {
        (self.lo + self.hi) * 0.5
    }

    /// Edge lengths (zero for an empty box).
    pub fn extent(&self) -> Vec3 {
        (self.hi - self.lo).max(Vec3::ZERO)
    }

    /// Surface area `2 (dx dy + dy dz + dz dx)`; zero for an empty box.
    pub fn surface_area(&self) -> f32 {
        let d = self.extent();
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }

    /// True when `other` lies inside `self` (boundaries included).
    pub fn contains(&self, other: &Aabb) -> bool {
        self.lo.cmple(other.lo).all() && other.hi.cmple(self.hi).all()
    }
}

/// Result of [`build`].
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    /// Nodes in depth-first order, root first (empty for no primitives).
    pub nodes: Vec<Node>,
    /// Permutation of `0..n`: leaf position `k` holds primitive `order[k]`.
    pub order: Vec<u32>,
    /// Depth of the deepest leaf (root = 0; 0 for an empty tree).
    pub depth: u32,
}

/// Builds a BVH over primitive boxes (binned SAH, see the module docs).
///
/// Boxes should be finite with `lo <= hi`; they may be flat or points.
/// (Non-finite boxes do not make it panic or loop, but the boxes of the
/// nodes above them are then unusable.) The result is deterministic
/// (independent of thread scheduling). Empty input gives empty `nodes` and
/// `order`; one primitive gives a single leaf root.
///
/// Per node (`A` = surface area, `N` = primitive count):
/// * one primitive, depth [`BVH_MAX_LEAF_DEPTH`] or all centroids equal:
///   leaf with everything;
/// * otherwise centroids are binned into [`SAH_BINS`] bins (`2 N` when
///   `N < SAH_BINS / 2`) on each of the three axes and the bin boundary
///   minimizing `C_trav + C_isect * (A_left N_left + A_right N_right) / A_node`
///   is taken (ties, e.g. zero-area boxes: most balanced counts);
/// * nodes of at most [`BVH_MAX_LEAF_SIZE`] primitives become leaves when
///   `C_isect * N` is not above that split cost; larger nodes always split;
/// * if no bin boundary separates the centroids (only for pathologically
///   small, e.g. denormal, centroid extents) the node becomes a leaf when it
///   has at most [`BVH_MAX_LEAF_SIZE`] primitives and is otherwise cut in the
///   middle of its range.
pub fn build(boxes: &[Aabb]) -> Bvh {
    let n = boxes.len();
    if n == 0 {
        return Bvh::default();
    }
    assert!(
        n < u32::MAX as usize / 2,
        "too many primitives for a u32 BVH"
    );

    // Primitive boxes as SIMD vectors, in the order they will be partitioned.
    let mut prims: Vec<PrimRef> = boxes
        .par_iter()
        .map(|b| PrimRef {
            lo: b.lo.into(),
            hi: b.hi.into(),
        })
        .collect();
    let mut order: Vec<u32> = (0..n as u32).collect();

    // Root box and root centroid box.
    let (bounds, cbounds) = prims.par_chunks(64 * 1024).map(bounds_of).reduce(
        || (Box3A::EMPTY, Box3A::EMPTY),
        |a, b| (a.0.union(&b.0), a.1.union(&b.1)),
    );

    let mut nodes = Vec::with_capacity(2 * n - 1);
    let task = Task {
        prims: &mut prims,
        ids: &mut order,
        start: 0,
        bounds,
        cbounds,
        depth: 0,
    };
    let depth = build_subtree(task, &mut nodes);
    assert!(
        depth <= BVH_MAX_LEAF_DEPTH,
        "BVH leaf depth {depth} exceeds {BVH_MAX_LEAF_DEPTH}"
    );
    nodes.shrink_to_fit();
    Bvh {
        nodes,
        order,
        depth,
    }
}

/// Box with SIMD corners used by the builder.
#[derive(Clone, Copy, Debug)]
struct Box3A {
    lo: Vec3A,
    hi: Vec3A,
}

impl Box3A {
    const EMPTY: Box3A = Box3A {
        lo: Vec3A::INFINITY,
        hi: Vec3A::NEG_INFINITY,
    };

    #[inline(always)]
    fn grow(&mut self, lo: Vec3A, hi: Vec3A) {
        self.lo = self.lo.min(lo);
        self.hi = self.hi.max(hi);
    }

    #[inline(always)]
    fn union(&self, other: &Box3A) -> Box3A {
        Box3A {
            lo: self.lo.min(other.lo),
            hi: self.hi.max(other.hi),
        }
    }

    /// Half the surface area (the SAH only needs ratios); 0 when empty.
    #[inline(always)]
    fn half_area(&self) -> f32 {
        let d = (self.hi - self.lo).max(Vec3A::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

/// A primitive box; `lo + hi` (twice the centroid) is the binning key.
#[derive(Clone, Copy, Debug)]
struct PrimRef {
    lo: Vec3A,
    hi: Vec3A,
}

impl PrimRef {
    /// Twice the centroid (the factor 2 cancels out in the bin grid).
    #[inline(always)]
    fn centroid2(&self) -> Vec3A {
        self.lo + self.hi
    }
}

/// Box of the primitives and box of their (doubled) centroids.
fn bounds_of(prims: &[PrimRef]) -> (Box3A, Box3A) {
    let mut b = Box3A::EMPTY;
    let mut c = Box3A::EMPTY;
    for p in prims {
        b.grow(p.lo, p.hi);
        let c2 = p.centroid2();
        c.grow(c2, c2);
    }
    (b, c)
}

/// Maps a doubled centroid to bin coordinates on the three axes.
#[derive(Clone, Copy, Debug)]
struct BinGrid {
    origin: Vec3A,
    /// `bins / extent`, or 0 on axes that cannot be split (zero or
    /// denormal-small centroid extent): everything lands in bin 0 there.
    scale: Vec3A,
    /// Number of bins used (`<= SAH_BINS`).
    bins: usize,
}

impl BinGrid {
    fn new(cbounds: &Box3A, prims: usize) -> Self {
        let bins = (2 * prims).clamp(2, SAH_BINS);
        let extent = cbounds.hi - cbounds.lo;
        let scale = Vec3A::splat(bins as f32) / extent;
        let usable = extent.cmpgt(Vec3A::ZERO) & scale.is_finite_mask();
        Self {
            origin: cbounds.lo,
            scale: Vec3A::select(usable, scale, Vec3A::ZERO),
            bins,
        }
    }

    /// Continuous bin coordinates of a primitive. Binning and partitioning
    /// both go through this exact expression, so they always agree.
    #[inline(always)]
    fn coords(&self, p: &PrimRef) -> Vec3A {
        (p.centroid2() - self.origin) * self.scale
    }

    /// Bin index of one coordinate (float-to-int casts saturate; clamp the top).
    #[inline(always)]
    fn bin(&self, coord: f32) -> usize {
        (coord as usize).min(self.bins - 1)
    }
}

/// A candidate split: primitives whose bin on `axis` is `< bin` go left.
#[derive(Clone, Copy, Debug)]
struct Split {
    axis: usize,
    bin: usize,
    /// `A_left N_left + A_right N_right` with half areas.
    cost: f32,
    /// `|N_left - N_right|`, the tie breaker.
    imbalance: u32,
}

/// Bins the primitives on all three axes and returns the bin boundary with
/// the lowest SAH cost, or `None` when no boundary leaves both sides non-empty.
fn find_split(prims: &[PrimRef], grid: &BinGrid) -> Option<Split> {
    // Per axis and bin: box of the primitives and their number.
    let mut boxes = [[Box3A::EMPTY; SAH_BINS]; 3];
    let mut counts = [[0u32; SAH_BINS]; 3];
    for p in prims {
        let c = grid.coords(p);
        for axis in 0..3 {
            let b = grid.bin(c[axis]);
            boxes[axis][b].grow(p.lo, p.hi);
            counts[axis][b] += 1;
        }
    }

    let mut best: Option<Split> = None;
    for axis in 0..3 {
        if grid.scale[axis] == 0.0 {
            continue;
        }
        // Right-to-left sweep: area and count of bins `i..` for every boundary i.
        let mut right_area = [0.0f32; SAH_BINS];
        let mut right_count = [0u32; SAH_BINS];
        let mut acc = Box3A::EMPTY;
        let mut count = 0;
        for i in (1..grid.bins).rev() {
            acc = acc.union(&boxes[axis][i]);
            count += counts[axis][i];
            right_area[i] = acc.half_area();
            right_count[i] = count;
        }
        // Left-to-right sweep: bins `..i` against the precomputed right side.
        let mut acc = Box3A::EMPTY;
        let mut count = 0;
        for i in 1..grid.bins {
            acc = acc.union(&boxes[axis][i - 1]);
            count += counts[axis][i - 1];
            let rc = right_count[i];
            if count == 0 || rc == 0 {
                continue;
            }
            let cost = acc.half_area() * count as f32 + right_area[i] * rc as f32;
            let imbalance = count.abs_diff(rc);
            let better = match best {
                None => true,
                Some(b) => cost < b.cost || (cost == b.cost && imbalance < b.imbalance),
            };
            if better {
                best = Some(Split {
                    axis,
                    bin: i,
                    cost,
                    imbalance,
                });
            }
        }
    }
    best
}

/// Primitive range of one subtree plus what is known about it.
struct Task<'a> {
    prims: &'a mut [PrimRef],
    /// Original primitive indices, permuted in lockstep with `prims`.
    ids: &'a mut [u32],
    /// Position of `prims[0]` in the final `order`.
    start: u32,
    bounds: Box3A,
    cbounds: Box3A,
    depth: u32,
}

/// Moves the primitives whose bin on `axis` is below `bin` to the front of
/// the range (`ids` follows). Returns the number moved and the boxes/centroid
/// boxes of both sides, computed in the same pass.
///
/// Branch-free Lomuto partition: `prims[..i]` go left and `prims[i..k]` go
/// right; element `k` is always swapped with `i` (a no-op exchange of two
/// right-side elements when it goes right) and `i` advances when it goes
/// left. Random left/right outcomes thus cost no branch mispredictions.
fn partition(
    prims: &mut [PrimRef],
    ids: &mut [u32],
    grid: &BinGrid,
    axis: usize,
    bin: usize,
) -> (usize, [(Box3A, Box3A); 2]) {
    // sides[0] = left, sides[1] = right: (box, centroid box).
    let mut sides = [(Box3A::EMPTY, Box3A::EMPTY); 2];
    let mut i = 0;
    for k in 0..prims.len() {
        let p = prims[k];
        let left = grid.bin(grid.coords(&p)[axis]) < bin;
        let side = &mut sides[usize::from(!left)];
        side.0.grow(p.lo, p.hi);
        let c2 = p.centroid2();
        side.1.grow(c2, c2);
        prims.swap(i, k);
        ids.swap(i, k);
        i += usize::from(left);
    }
    (i, sides)
}

/// Decides whether `task` becomes a leaf (`None`) or splits into two
/// non-empty tasks (left first), partitioning its range in place.
fn split_task(task: Task<'_>) -> Option<(Task<'_>, Task<'_>)> {
    let n = task.prims.len();
    if n <= 1 || task.depth >= BVH_MAX_LEAF_DEPTH || task.cbounds.lo == task.cbounds.hi {
        return None;
    }
    let grid = BinGrid::new(&task.cbounds, n);
    let mut cut = None;
    let best = find_split(task.prims, &grid);
    if best.is_none() && n <= BVH_MAX_LEAF_SIZE {
        return None;
    }
    if let Some(split) = best {
        // SAH termination, both costs multiplied by the node's half area.
        let area = task.bounds.half_area();
        let leaf_cost = SAH_INTERSECTION_COST * n as f32 * area;
        let split_cost = SAH_TRAVERSAL_COST * area + SAH_INTERSECTION_COST * split.cost;
        if n <= BVH_MAX_LEAF_SIZE && leaf_cost <= split_cost {
            return None;
        }
        let (mid, sides) = partition(task.prims, task.ids, &grid, split.axis, split.bin);
        if mid > 0 && mid < n {
            cut = Some((mid, sides));
        }
    }
    // Fallback (no usable bin boundary): cut the range in the middle.
    let (mid, [left, right]) = cut.unwrap_or_else(|| {
        let mid = n / 2;
        (
            mid,
            [bounds_of(&task.prims[..mid]), bounds_of(&task.prims[mid..])],
        )
    });

    let (lp, rp) = task.prims.split_at_mut(mid);
    let (li, ri) = task.ids.split_at_mut(mid);
    Some((
        Task {
            prims: lp,
            ids: li,
            start: task.start,
            bounds: left.0,
            cbounds: left.1,
            depth: task.depth + 1,
        },
        Task {
            prims: rp,
            ids: ri,
            start: task.start + mid as u32,
            bounds: right.0,
            cbounds: right.1,
            depth: task.depth + 1,
        },
    ))
}

/// Appends the subtree of `task` to `nodes` in depth-first order and returns
/// its deepest leaf depth. Interior offsets are indices into `nodes`.
///
/// Large subtrees build their left child into `nodes` and, concurrently, the
/// right child into a fresh vector whose interior offsets are then rebased
/// while it is appended, which keeps the global depth-first layout.
fn build_subtree(task: Task<'_>, nodes: &mut Vec<Node>) -> u32 {
    let depth = task.depth;
    let index = nodes.len();
    // Written as a leaf; turned into an interior node below if it splits.
    nodes.push(Node {
        lo: task.bounds.lo.to_array(),
        offset: task.start,
        hi: task.bounds.hi.to_array(),
        count: task.prims.len() as u32,
    });
    let Some((left, right)) = split_task(task) else {
        return depth;
    };
    nodes[index].count = 0;

    if left.prims.len() + right.prims.len() >= PARALLEL_MIN_PRIMS {
        let (left_depth, (right_nodes, right_depth)) = rayon::join(
            || build_subtree(left, nodes),
            || {
                let mut sub = Vec::with_capacity(2 * right.prims.len());
                let d = build_subtree(right, &mut sub);
                (sub, d)
            },
        );
        let base = nodes.len() as u32;
        nodes[index].offset = base;
        nodes.extend(right_nodes.into_iter().map(|mut node| {
            if node.count == 0 {
                node.offset += base;
            }
            node
        }));
        left_depth.max(right_depth)
    } else {
        let left_depth = build_subtree(left, nodes);
        nodes[index].offset = nodes.len() as u32;
        left_depth.max(build_subtree(right, nodes))
    }
}

/// Children of a node of the renderers' BVH ([`BvhNode`]).
pub const BVH_WIDTH: usize = 8;

/// Most primitives in a leaf of the renderers' BVH: a child's meta byte counts them in
/// unary in 3 bits.
pub const WIDE_LEAF_SIZE: u32 = 3;
const _: () = assert!(BVH_MAX_LEAF_SIZE == WIDE_LEAF_SIZE as usize);

/// Result of [`collapse`]: the tree the renderers walk.
#[derive(Clone, Debug, Default)]
pub struct WideBvh {
    /// The root first; the child nodes of a node follow one another (empty for no
    /// primitives).
    pub nodes: Vec<BvhNode>,
    /// Permutation of `0..n`: primitive position `k` holds primitive `order[k]`. The
    /// primitives of a node's leaf children follow one another from its `prim`.
    pub order: Vec<u32>,
    /// Depth of the deepest node (root = 0), at most [`BVH_MAX_LEAF_DEPTH`]: a walk holds
    /// at most one stack entry per ancestor of the node it visits.
    pub depth: u32,
}

/// Turns the binary tree `tree` over `boxes` into the renderers' compressed 8-wide tree.
///
/// Each node takes the two children of its binary node and then, seven times at most,
/// replaces the child of the largest surface area that holds more than
/// [`WIDE_LEAF_SIZE`] primitives by its two children (a binary leaf of more is halved at
/// a multiple of [`WIDE_LEAF_SIZE`]); a child of at most [`WIDE_LEAF_SIZE`] primitives
/// becomes a leaf. Should that make the tree deeper than [`BVH_MAX_LEAF_DEPTH`] (a
/// binary tree at its depth limit with huge leaves), it is collapsed again taking the
/// tallest child first, which takes at least three binary levels per node.
///
/// A child's slot is chosen for the order of the walk: a ray whose direction has the
/// signs of octant `o` (bit 0: x < 0, bit 1: y, bit 2: z) visits slot `o` first, then
/// `o ^ 1`, `o ^ 2`, ... (`bvh_node_hits`), so slot `o` gets the child nearest to where
/// such rays enter the node (the smallest dot product of its centroid with the octant's
/// direction, assigned greedily). The child boxes are quantized outwards in exact
/// arithmetic, so each holds its primitives' boxes.
pub fn collapse(tree: &Bvh, boxes: &[Aabb]) -> WideBvh {
    if tree.nodes.is_empty() {
        return WideBvh::default();
    }
    // (first position, count, height) of every binary node; children follow their parent
    let mut spans = vec![(0u32, 0u32, 0u32); tree.nodes.len()];
    for i in (0..tree.nodes.len()).rev() {
        let n = &tree.nodes[i];
        spans[i] = if n.count > 0 {
            (n.offset, n.count, run_height(n.count))
        } else {
            let (l, r) = (spans[i + 1], spans[n.offset as usize]);
            (l.0, l.1 + r.1, 1 + l.2.max(r.2))
        };
    }
    let mut wide = WideBvh::default();
    for by_height in [false, true] {
        let mut c = Collapse {
            tree,
            boxes,
            spans: &spans,
            by_height,
            nodes: vec![BvhNode::default()],
            order: Vec::with_capacity(tree.order.len()),
            depth: 0,
        };
        c.node(0, c.part(0), 0);
        wide = WideBvh {
            nodes: c.nodes,
            order: c.order,
            depth: c.depth,
        };
        if wide.depth <= BVH_MAX_LEAF_DEPTH {
            break;
        }
    }
    debug_assert!(wide.depth <= BVH_MAX_LEAF_DEPTH);
    wide
}

/// Binary levels a run of `count` primitives takes to reach leaves of at most
/// [`WIDE_LEAF_SIZE`]: ceil(log2(ceil(count / WIDE_LEAF_SIZE))).
fn run_height(count: u32) -> u32 {
    let leaves = count.div_ceil(WIDE_LEAF_SIZE);
    32 - leaves.saturating_sub(1).leading_zeros()
}

/// A binary node's subtree, or a run of a binary leaf's primitives, being collapsed.
#[derive(Clone, Copy, Debug)]
struct Part {
    /// The binary node, or [`RUN`].
    node: u32,
    /// Its primitives: positions `start..start + count` of the binary tree's order.
    start: u32,
    count: u32,
    bounds: Aabb,
    /// Binary levels below it (for a run, [`run_height`]).
    height: u32,
}

/// [`Part::node`] of a run of primitives.
const RUN: u32 = u32::MAX;

struct Collapse<'a> {
    tree: &'a Bvh,
    boxes: &'a [Aabb],
    spans: &'a [(u32, u32, u32)],
    by_height: bool,
    nodes: Vec<BvhNode>,
    order: Vec<u32>,
    depth: u32,
}

impl Collapse<'_> {
    fn part(&self, node: u32) -> Part {
        let n = &self.tree.nodes[node as usize];
        let (start, count, height) = self.spans[node as usize];
        Part {
            node,
            start,
            count,
            bounds: Aabb::new(n.lo.into(), n.hi.into()),
            height,
        }
    }

    fn run(&self, start: u32, count: u32) -> Part {
        let mut bounds = Aabb::EMPTY;
        for k in start..start + count {
            bounds = bounds.union(&self.boxes[self.tree.order[k as usize] as usize]);
        }
        Part {
            node: RUN,
            start,
            count,
            bounds,
            height: run_height(count),
        }
    }

    /// The two halves of a part of more than [`WIDE_LEAF_SIZE`] primitives: a binary
    /// node's children, else its run cut at a multiple of [`WIDE_LEAF_SIZE`].
    fn split(&self, p: &Part) -> (Part, Part) {
        if p.node != RUN {
            let n = &self.tree.nodes[p.node as usize];
            if n.count == 0 {
                return (self.part(p.node + 1), self.part(n.offset));
            }
        }
        let half = p.count.div_ceil(WIDE_LEAF_SIZE) / 2 * WIDE_LEAF_SIZE;
        (
            self.run(p.start, half),
            self.run(p.start + half, p.count - half),
        )
    }

    /// Writes node `index`, over `part`, and the nodes below it.
    fn node(&mut self, index: usize, part: Part, depth: u32) {
        self.depth = self.depth.max(depth);
        let mut kids = if part.count > WIDE_LEAF_SIZE {
            let (a, b) = self.split(&part);
            vec![a, b]
        } else {
            vec![part]
        };
        let key = |p: &Part| {
            let area = p.bounds.surface_area();
            if self.by_height {
                (p.height as f32, area)
            } else {
                (area, 0.0)
            }
        };
        while kids.len() < BVH_WIDTH {
            let Some(j) = (0..kids.len())
                .filter(|&j| kids[j].count > WIDE_LEAF_SIZE)
                .max_by(|&a, &b| {
                    key(&kids[a])
                        .partial_cmp(&key(&kids[b]))
                        .unwrap_or(std::cmp::Ordering::Equal)
                })
            else {
                break;
            };
            let (a, b) = self.split(&kids[j]);
            kids[j] = a;
            kids.push(b);
        }
        let bounds = kids.iter().fold(Aabb::EMPTY, |b, k| b.union(&k.bounds));
        let slots = assign_slots(bounds.centroid(), &kids);
        let grid = Grid::new(&bounds);

        let child = self.nodes.len() as u32;
        let inner = kids.iter().filter(|k| k.count > WIDE_LEAF_SIZE).count();
        self.nodes
            .resize(self.nodes.len() + inner, BvhNode::default());
        let prim = self.order.len() as u32;
        let (mut imask, mut meta, mut q) = (0u32, [0u32; BVH_WIDTH], [[0u32; BVH_WIDTH]; 6]);
        let mut below = Vec::with_capacity(inner);
        for (s, kid) in slots.iter().enumerate() {
            let Some(k) = kid.map(|c| kids[c]) else {
                continue;
            };
            for a in 0..3 {
                q[a][s] = grid.quantize(k.bounds.lo[a], a, false);
                q[3 + a][s] = grid.quantize(k.bounds.hi[a], a, true);
            }
            if k.count > WIDE_LEAF_SIZE {
                imask |= 1 << s;
                meta[s] = (1 << 5) | (24 + s as u32);
                below.push((child as usize + below.len(), k));
            } else {
                meta[s] = (((1 << k.count) - 1) << 5) | (self.order.len() as u32 - prim);
                let order = &self.tree.order[k.start as usize..(k.start + k.count) as usize];
                self.order.extend_from_slice(order);
            }
        }
        // four bytes of children 4 h .. 4 h + 3 in a word, from the low byte
        let pack =
            |v: &[u32; BVH_WIDTH], h: usize| (0..4).fold(0, |w, i| w | v[4 * h + i] << (8 * i));
        let both = |v: &[u32; BVH_WIDTH]| [pack(v, 0), pack(v, 1)];
        let [x0, x1] = both(&q[0]);
        let [y0, y1] = both(&q[1]);
        let [z0, z1] = both(&q[2]);
        let [hx0, hx1] = both(&q[3]);
        let [hy0, hy1] = both(&q[4]);
        let [hz0, hz1] = both(&q[5]);
        self.nodes[index] = BvhNode {
            origin: bounds.lo.to_array(),
            scale: grid.exponents[0]
                | grid.exponents[1] << 8
                | grid.exponents[2] << 16
                | imask << 24,
            child,
            prim,
            meta0: pack(&meta, 0),
            meta1: pack(&meta, 1),
            q0: [x0, x1, y0, y1],
            q1: [z0, z1, hx0, hx1],
            q2: [hy0, hy1, hz0, hz1],
        };
        for (i, k) in below {
            self.node(i, k, depth + 1);
        }
    }
}

/// The slot of each child (`slots[s]` = index into `kids`): greedily, the pairs of child
/// and octant in increasing order of the dot product of the child's centroid (about
/// `center`) with the octant's direction.
fn assign_slots(center: Vec3, kids: &[Part]) -> [Option<usize>; BVH_WIDTH] {
    let octant = |s: usize| {
        let sign = |bit: usize| if s & bit != 0 { -1.0 } else { 1.0 };
        Vec3::new(sign(1), sign(2), sign(4))
    };
    let mut pairs = Vec::with_capacity(kids.len() * BVH_WIDTH);
    for (c, k) in kids.iter().enumerate() {
        let d = k.bounds.centroid() - center;
        for s in 0..BVH_WIDTH {
            pairs.push((d.dot(octant(s)), c, s));
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut slots = [None; BVH_WIDTH];
    let mut placed = [false; BVH_WIDTH];
    for (_, c, s) in pairs {
        if slots[s].is_none() && !placed[c] {
            slots[s] = Some(c);
            placed[c] = true;
        }
    }
    slots
}

/// A node's quantization grid: per axis, the node's lower corner and a power-of-two step
/// such that 255 steps span the node.
struct Grid {
    origin: DVec3,
    step: DVec3,
    /// The steps as biased exponents (`f32::from_bits(e << 23)`), 1 to 254.
    exponents: [u32; 3],
}

impl Grid {
    fn new(bounds: &Aabb) -> Self {
        let origin = bounds.lo.as_dvec3();
        let extent = bounds.hi.as_dvec3() - origin;
        let mut step = DVec3::ZERO;
        let mut exponents = [0; 3];
        for a in 0..3 {
            // the smallest power of two (a normal f32) with 255 of them spanning the node
            let mut k = if extent[a] > 0.0 {
                ((extent[a] / 255.0).log2().ceil() as i32).clamp(-126, 127)
            } else {
                -126
            };
            while k < 127 && 255.0 * 2f64.powi(k) < extent[a] {
                k += 1;
            }
            while k > -126 && 255.0 * 2f64.powi(k - 1) >= extent[a] {
                k -= 1;
            }
            step[a] = 2f64.powi(k);
            exponents[a] = (k + 127) as u32;
        }
        Self {
            origin,
            step,
            exponents,
        }
    }

    /// Plane `v` on axis `a` in steps of the grid, rounded down (`up`: up), so that
    /// `origin + step q` lies on its outer side in exact arithmetic (f64 holds these
    /// sums of an f32 and a power of two times a byte exactly).
    fn quantize(&self, v: f32, a: usize, up: bool) -> u32 {
        let v = v as f64;
        let x = (v - self.origin[a]) / self.step[a];
        let mut q = if up { x.ceil() } else { x.floor() }.clamp(0.0, 255.0);
        let plane = |q: f64| self.origin[a] + self.step[a] * q;
        if up {
            while q < 255.0 && plane(q) < v {
                q += 1.0;
            }
        } else {
            while q > 0.0 && plane(q) > v {
                q -= 1.0;
            }
        }
        q as u32
    }
}
