//! A bounding volume hierarchy over a scene's shapes, so that a ray tests the shapes whose bounds it
//! passes near rather than every shape.
//!
//! Built once per scene ([`super::Scene::new`], which every change of a parameter goes through), over the
//! bounds of the shapes with finite bounds, by binned surface-area heuristic (12 bins per axis, at most
//! [`MAX_LEAF`] shapes per leaf). Shapes with unbounded (planes) or empty bounds are kept apart and
//! tested on every ray, and so are shapes whose box is a large part of the whole scene's (a floor slab,
//! a room): in the tree they would make every node above them as large.
//!
//! # What a node test guarantees
//!
//! A shape is traced over its bounds grown by the local tolerance where the ray enters them
//! ([`super::Scene::trace_interval`]). A node is tested the same way (the same slab arithmetic, in the
//! same order), over its box grown by the tolerance where the ray *leaves* the root's box (or at the
//! ray's start if it leaves before): every shape's box lies inside the root's, so a ray enters or
//! passes a shape no later than that, and the tolerance only grows along a ray. Each step of the slab
//! test is monotone in the box and in the margin, rounding included, so the node's interval contains
//! every one of its shapes' intervals, bit for bit: culling by node never drops a shape that the
//! shape's own test would keep.
//!
//! # Four children at a time
//!
//! The walks run on a 4-wide copy of the tree ([`WideNode`]): every binary node's two children are
//! expanded, largest box first, until it has four, and the four boxes are tested in the lanes of one
//! SIMD register. Each lane does the node test's operations in the same order (a slab axis the ray
//! parallels is tested against the grown slab, as there), so a lane's interval is the binary node's,
//! bit for bit; where an axis's arithmetic gives no number (a zero times an infinite reciprocal) the
//! lane keeps the interval it had before that axis, which only widens it. Half the levels, and a
//! node's boxes in one pass.
//!
//! # Order
//!
//! The nearest-hit query visits shapes in increasing order of where their interval starts (ties by
//! shape index), from a priority queue of nodes and shapes, exactly as the brute-force query does over
//! every shape: a shape's hit is sought over its interval cut at the nearest hit so far, so the order
//! decides the intervals and, through the tracer's last step, the last bits of `t`. The same order makes
//! the result the same with and without the hierarchy, bit for bit.

use crate::math::{Aabb, Ray};
use glam::{Vec3A, Vec4};

/// Most shapes in a leaf.
pub(crate) const MAX_LEAF: usize = 2;
/// Shapes whose box has more than this fraction of the surface area of the box around every bounded
/// shape are kept out of the hierarchy (tested on every ray).
const LARGE: f32 = 0.25;
/// Deepest level split (a leaf there holds whatever is left): bounds the build's recursion.
const MAX_DEPTH: usize = 48;
/// SAH bins per axis.
const BINS: usize = 12;
/// Relative cost of a node's box test against a shape's (the shape's is a box test too, and then maybe
/// a trace).
const NODE_COST: f32 = 1.0;

/// One node: a box and either two children (`count == 0`, children `first` and `first + 1`) or a leaf
/// of `count` shapes, `order[first .. first + count]`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) struct Node {
    pub bounds: Aabb,
    pub first: u32,
    pub count: u32,
}

/// The bit of a [`WideNode`] child reference marking a leaf: the rest is the leaf's index in
/// [`Bvh::nodes`].
pub(crate) const LEAF: u32 = 1 << 30;

/// A node of the 4-wide tree the walks use: up to four children's boxes, axis by axis, one child per
/// SIMD lane.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) struct WideNode {
    /// Lane `j` of `lo[a]` and `hi[a]`: child `j`'s box on axis `a` (unused lanes: an empty box).
    pub lo: [Vec4; 3],
    pub hi: [Vec4; 3],
    /// Per lane: an inner child's index in [`Bvh::wide`], or [`LEAF`] with a leaf's in [`Bvh::nodes`].
    pub child: [u32; 4],
    /// The lanes in use (children are packed from lane 0) as a bit mask.
    pub lanes: u32,
}

/// The hierarchy over the shapes of a scene with finite bounds, and the shapes kept apart.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bvh {
    /// The binary tree the build makes. Node 0 is the root (absent when no shape has finite bounds).
    pub(crate) nodes: Vec<Node>,
    /// The same tree with four children per node, which the walks use (node 0 is the root, present
    /// when `nodes` has a root).
    pub(crate) wide: Vec<WideNode>,
    /// Shape indices, leaves referring to ranges of it.
    pub(crate) order: Vec<u32>,
    /// Shapes with unbounded or empty bounds, tested on every ray, in index order.
    pub(crate) apart: Vec<u32>,
    /// The bounds of every shape at build time, by index: the hierarchy is used only while the scene's
    /// shapes have exactly these ([`Bvh::fits`]).
    pub(crate) bounds: Vec<Aabb>,
}

impl Bvh {
    /// The hierarchy over shapes with bounds `bounds` (indexed as the scene's shapes).
    pub fn build(bounds: &[Aabb]) -> Self {
        let bounded = |b: &Aabb| b.is_finite() && !b.is_empty();
        let all = (bounds.iter().filter(|b| bounded(b))).fold(Aabb::EMPTY, |a, b| a.union(b));
        // A shape whose box is a large part of everything's (a floor, a room's walls) would make
        // every node above it as large: it is tested apart, on every ray.
        let large = |b: &Aabb| area(b) > LARGE * area(&all);
        let mut order = Vec::new();
        let mut apart = Vec::new();
        for (i, b) in bounds.iter().enumerate() {
            if bounded(b) && !large(b) {
                order.push(i as u32);
            } else {
                apart.push(i as u32);
            }
        }
        let mut bvh = Self {
            nodes: Vec::new(),
            wide: Vec::new(),
            order,
            apart,
            bounds: bounds.to_vec(),
        };
        if !bvh.order.is_empty() {
            let n = bvh.order.len() as u32;
            bvh.nodes.push(Node {
                bounds: Aabb::EMPTY,
                first: 0,
                count: n,
            });
            bvh.split(0, 0);
            bvh.widen(0);
        }
        bvh
    }

    /// Appends to [`Bvh::wide`] the 4-wide node of binary node `k` and, below it, its subtree's; returns
    /// its index. A leaf's wide node has the leaf as its one child.
    fn widen(&mut self, k: usize) -> u32 {
        let mut children = vec![k as u32];
        // Open the inner child with the largest box until there are four (or only leaves).
        while children.len() < 4 {
            let open = (children.iter().enumerate())
                .filter(|&(_, &c)| self.nodes[c as usize].count == 0)
                .max_by(|a, b| {
                    let area_of = |c: u32| area(&self.nodes[c as usize].bounds);
                    area_of(*a.1).total_cmp(&area_of(*b.1))
                });
            let Some((j, &c)) = open else { break };
            let first = self.nodes[c as usize].first;
            children.splice(j..=j, [first, first + 1]);
        }
        let index = self.wide.len();
        self.wide.push(WideNode {
            lo: [Vec4::INFINITY; 3],
            hi: [Vec4::NEG_INFINITY; 3],
            child: [0; 4],
            lanes: (1 << children.len()) - 1,
        });
        for (j, &c) in children.iter().enumerate() {
            let node = self.nodes[c as usize];
            let child = if node.count == 0 {
                self.widen(c as usize)
            } else {
                LEAF | c
            };
            let w = &mut self.wide[index];
            for a in 0..3 {
                w.lo[a][j] = node.bounds.min[a];
                w.hi[a][j] = node.bounds.max[a];
            }
            w.child[j] = child;
        }
        index as u32
    }

    /// Whether the hierarchy was built for shapes with exactly these bounds (same count, same boxes).
    pub fn fits<'a>(&self, mut bounds: impl ExactSizeIterator<Item = &'a Aabb>) -> bool {
        bounds.len() == self.bounds.len() && self.bounds.iter().all(|b| bounds.next() == Some(b))
    }

    /// Number of shapes the hierarchy was built for.
    #[inline]
    pub fn len(&self) -> usize {
        self.bounds.len()
    }

    /// Whether it was built for no shape.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.bounds.is_empty()
    }

    /// Sets node `k` (at depth `depth`)'s box from its shapes and splits it while the surface-area
    /// heuristic gains, down to [`MAX_DEPTH`].
    fn split(&mut self, k: usize, depth: usize) {
        let Node { first, count, .. } = self.nodes[k];
        let range = first as usize..(first + count) as usize;
        let boxes = &self.bounds;
        let bounds = self.order[range.clone()]
            .iter()
            .fold(Aabb::EMPTY, |a, &i| a.union(&boxes[i as usize]));
        self.nodes[k].bounds = bounds;
        if (count as usize) <= 1 || depth >= MAX_DEPTH {
            return;
        }
        let centroid = |i: u32| boxes[i as usize].center();
        let cb = self.order[range.clone()].iter().fold(Aabb::EMPTY, |a, &i| {
            Aabb::new(a.min.min(centroid(i)), a.max.max(centroid(i)))
        });
        // The best split plane: (cost, axis, bin boundary).
        let mut best: Option<(f32, usize, usize)> = None;
        for axis in 0..3 {
            let (lo, hi) = (cb.min[axis], cb.max[axis]);
            if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
                continue;
            }
            let scale = BINS as f32 / (hi - lo);
            let bin_of = |i: u32| (((centroid(i)[axis] - lo) * scale) as usize).min(BINS - 1);
            let mut bins = [(Aabb::EMPTY, 0u32); BINS];
            for &i in &self.order[range.clone()] {
                let b = &mut bins[bin_of(i)];
                b.0 = b.0.union(&boxes[i as usize]);
                b.1 += 1;
            }
            // Sweep from the right, then from the left.
            let mut right = [(0.0f32, 0u32); BINS];
            let mut acc = (Aabb::EMPTY, 0u32);
            for s in (1..BINS).rev() {
                acc = (acc.0.union(&bins[s].0), acc.1 + bins[s].1);
                right[s] = (area(&acc.0), acc.1);
            }
            let mut acc = (Aabb::EMPTY, 0u32);
            for s in 1..BINS {
                acc = (acc.0.union(&bins[s - 1].0), acc.1 + bins[s - 1].1);
                let (ra, rn) = right[s];
                if acc.1 == 0 || rn == 0 {
                    continue;
                }
                let cost = area(&acc.0) * acc.1 as f32 + ra * rn as f32;
                if best.is_none_or(|b| cost < b.0) {
                    best = Some((cost, axis, s));
                }
            }
        }
        let leaf_cost = area(&bounds) * count as f32;
        let Some((cost, axis, s)) = best else {
            // Every centroid at one point: split in halves if the leaf is too large.
            if (count as usize) > MAX_LEAF {
                self.push_children(k, count / 2, depth);
            }
            return;
        };
        if (count as usize) <= MAX_LEAF && NODE_COST * area(&bounds) + cost >= leaf_cost {
            return;
        }
        let (lo, hi) = (cb.min[axis], cb.max[axis]);
        let scale = BINS as f32 / (hi - lo);
        let slice = &mut self.order[range];
        // Stable partition: the build does not depend on anything but the boxes and their indices.
        let (mut left, mut right): (Vec<u32>, Vec<u32>) = slice
            .iter()
            .partition(|&&i| (((centroid(i)[axis] - lo) * scale) as usize).min(BINS - 1) < s);
        let n_left = left.len() as u32;
        left.append(&mut right);
        slice.copy_from_slice(&left);
        self.push_children(k, n_left, depth);
    }

    /// Makes node `k` an inner node with children of its first `n_left` shapes and the rest.
    fn push_children(&mut self, k: usize, n_left: u32, depth: usize) {
        let Node { first, count, .. } = self.nodes[k];
        let c = self.nodes.len() as u32;
        for (f, n) in [(first, n_left), (first + n_left, count - n_left)] {
            self.nodes.push(Node {
                bounds: Aabb::EMPTY,
                first: f,
                count: n,
            });
        }
        self.nodes[k].first = c;
        self.nodes[k].count = 0;
        self.split(c as usize, depth + 1);
        self.split(c as usize + 1, depth + 1);
    }
}

/// Half the surface area of a box (0 for an empty one).
#[inline]
fn area(b: &Aabb) -> f32 {
    if b.is_empty() {
        return 0.0;
    }
    let e = b.extent();
    e.x * e.y + e.y * e.z + e.z * e.x
}

/// A ray's slab-test data and the margin its node tests grow boxes by, computed once per query.
#[derive(Copy, Clone, Debug)]
pub(crate) struct RaySlabs {
    o: Vec3A,
    inv: Vec3A,
    parallel: glam::BVec3A,
    /// The margin: the tolerance where the ray leaves the root's box (or at its start if before).
    r: f32,
    /// `r / |d|` per axis the ray is not parallel to: how far the margin moves a slab's ends.
    grow: Vec3A,
    /// Per axis, the origin, reciprocal direction and growth in all four lanes, for the wide test.
    lanes: [AxisLanes; 3],
    /// Whether the ray parallels some axis (the wide test's general path).
    any_parallel: bool,
}

/// One axis of [`RaySlabs`] splatted across the four lanes of a wide node's test.
#[derive(Copy, Clone, Debug)]
struct AxisLanes {
    o: Vec4,
    inv: Vec4,
    grow: Vec4,
}

impl RaySlabs {
    /// The slab data of `ray`, nodes grown by `margin(t)` at the `t` where the ray leaves `root` (the
    /// box around every node) or `t_min` if before: at least the margin any shape inside gets
    /// ([`super::Scene::trace_interval`] takes it where the ray enters or passes the shape's box, no
    /// later than where it leaves the root's, and the margin only grows along a ray).
    #[inline]
    pub fn new(ray: &Ray, root: &Aabb, t_min: f32, margin: impl FnOnce(f32) -> f32) -> Self {
        let (o, d) = (Vec3A::from(ray.o), Vec3A::from(ray.d));
        let inv = d.recip();
        let parallel = d.cmpeq(Vec3A::ZERO);
        let (min, max) = (Vec3A::from(root.min), Vec3A::from(root.max));
        let hi = Vec3A::select(
            parallel,
            Vec3A::INFINITY,
            ((min - o) * inv).max((max - o) * inv),
        );
        let r = margin(hi.min_element().max(t_min));
        let grow = Vec3A::select(parallel, Vec3A::ZERO, r * inv.abs());
        let axis = |a: usize| AxisLanes {
            o: Vec4::splat(o[a]),
            inv: Vec4::splat(inv[a]),
            grow: Vec4::splat(grow[a]),
        };
        Self {
            o,
            inv,
            parallel,
            r,
            grow,
            lanes: [axis(0), axis(1), axis(2)],
            any_parallel: parallel.any(),
        }
    }

    /// The interval of the ray in `[t_min, t_max]` within `b` grown by the ray's margin: the node
    /// test (see the [module docs](self)), the same operations as [`Aabb::clip_with_margin`] with a
    /// margin at least as large as any shape inside `b` gets.
    #[inline]
    pub fn node_interval(&self, b: &Aabb, t_min: f32, t_max: f32) -> Option<(f32, f32)> {
        let (min, max) = (Vec3A::from(b.min), Vec3A::from(b.max));
        let ta = (min - self.o) * self.inv;
        let tb = (max - self.o) * self.inv;
        let lo = Vec3A::select(self.parallel, Vec3A::NEG_INFINITY, ta.min(tb));
        let hi = Vec3A::select(self.parallel, Vec3A::INFINITY, ta.max(tb));
        let r = Vec3A::splat(self.r);
        let outside = self.o.cmplt(min - r) | self.o.cmpgt(max + r);
        if (self.parallel & outside).any() {
            return None;
        }
        let t0 = t_min.max((lo - self.grow).max_element());
        let t1 = t_max.min((hi + self.grow).min_element());
        (t0 <= t1).then_some((t0, t1))
    }

    /// [`RaySlabs::node_interval`] of a wide node's four children at once: the lanes kept (a bit mask
    /// of [`WideNode::lanes`]) and each lane's interval (see the [module docs](self)).
    #[inline]
    pub fn wide_interval(&self, n: &WideNode, t_min: f32, t_max: f32) -> (u32, Vec4, Vec4) {
        if self.any_parallel {
            return self.wide_interval_parallel(n, t_min, t_max);
        }
        // The three axes unrolled, branch-free: most rays parallel no axis.
        let (t0, t1) = self.axis_slabs(n, 0, Vec4::splat(t_min), Vec4::splat(t_max));
        let (t0, t1) = self.axis_slabs(n, 1, t0, t1);
        let (t0, t1) = self.axis_slabs(n, 2, t0, t1);
        (n.lanes & !t0.cmpgt(t1).bitmask(), t0, t1)
    }

    /// The lanes' intervals `[t0, t1]` cut by node `n`'s slabs on axis `a` (one the ray does not
    /// parallel), grown by the margin.
    #[inline(always)]
    fn axis_slabs(&self, n: &WideNode, a: usize, t0: Vec4, t1: Vec4) -> (Vec4, Vec4) {
        let l = &self.lanes[a];
        let ta = (n.lo[a] - l.o) * l.inv;
        let tb = (n.hi[a] - l.o) * l.inv;
        // `x.max(t0)` keeps `t0` where `x` is NaN (SSE's max returns its second operand then).
        ((ta.min(tb) - l.grow).max(t0), (ta.max(tb) + l.grow).min(t1))
    }

    /// [`RaySlabs::wide_interval`] for a ray parallel to some axis: that axis's slabs are tested
    /// against the ray's origin instead.
    #[cold]
    fn wide_interval_parallel(&self, n: &WideNode, t_min: f32, t_max: f32) -> (u32, Vec4, Vec4) {
        let mut t0 = Vec4::splat(t_min);
        let mut t1 = Vec4::splat(t_max);
        let mut keep = n.lanes;
        for a in 0..3 {
            if self.parallel.test(a) {
                let (o, r) = (self.lanes[a].o, Vec4::splat(self.r));
                let outside = o.cmplt(n.lo[a] - r) | o.cmpgt(n.hi[a] + r);
                keep &= !outside.bitmask();
                continue;
            }
            (t0, t1) = self.axis_slabs(n, a, t0, t1);
        }
        (keep & !t0.cmpgt(t1).bitmask(), t0, t1)
    }
}

/// An entry of the nearest-hit query's priority queue: a node or a shape, keyed by where its interval
/// starts; nodes before shapes at equal starts, shapes by index.
#[derive(Copy, Clone, Debug)]
pub(crate) struct Entry {
    pub t0: f32,
    pub t1: f32,
    /// `index` for a node, `SHAPE | index` for a shape.
    pub tag: u32,
}

/// The bit of [`Entry::tag`] marking a shape.
pub(crate) const SHAPE: u32 = 1 << 31;

impl Entry {
    #[inline]
    pub fn before(&self, o: &Self) -> bool {
        match self.t0.total_cmp(&o.t0) {
            std::cmp::Ordering::Less => true,
            std::cmp::Ordering::Greater => false,
            std::cmp::Ordering::Equal => self.tag < o.tag,
        }
    }
}

/// A binary min-heap of [`Entry`]s on a reusable vector.
#[derive(Debug, Default)]
pub(crate) struct Queue {
    heap: Vec<Entry>,
}

impl Queue {
    #[inline]
    pub fn clear(&mut self) {
        self.heap.clear();
    }

    /// Whether `e` comes before every queued entry (it would be popped next).
    #[inline]
    pub fn comes_first(&self, e: &Entry) -> bool {
        self.heap.first().is_none_or(|top| e.before(top))
    }

    #[inline]
    pub fn push(&mut self, e: Entry) {
        let h = &mut self.heap;
        h.push(e);
        let mut k = h.len() - 1;
        while k > 0 {
            let parent = (k - 1) / 2;
            if !h[k].before(&h[parent]) {
                break;
            }
            h.swap(k, parent);
            k = parent;
        }
    }

    #[inline]
    pub fn pop(&mut self) -> Option<Entry> {
        let h = &mut self.heap;
        let last = h.pop()?;
        if h.is_empty() {
            return Some(last);
        }
        let top = std::mem::replace(&mut h[0], last);
        let n = h.len();
        let mut k = 0;
        loop {
            let (l, r) = (2 * k + 1, 2 * k + 2);
            let mut m = k;
            if l < n && h[l].before(&h[m]) {
                m = l;
            }
            if r < n && h[r].before(&h[m]) {
                m = r;
            }
            if m == k {
                break;
            }
            h.swap(k, m);
            k = m;
        }
        Some(top)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn boxes(n: usize, seed: u32) -> Vec<Aabb> {
        let mut s = seed;
        let mut u = move || {
            s = s.wrapping_mul(1664525).wrapping_add(1013904223);
            (s >> 8) as f32 / (1u32 << 24) as f32
        };
        (0..n)
            .map(|_| {
                let c = Vec3::new(u(), u(), u()) * 20.0 - 10.0;
                Aabb::around(c, Vec3::new(u(), u(), u()) * 0.5 + 0.01)
            })
            .collect()
    }

    /// A fixed sequence of numbers in [-1, 1) per seed.
    fn signed_uniform(seed: u32) -> impl FnMut() -> f32 {
        let mut s = seed;
        move || {
            s = s.wrapping_mul(1664525).wrapping_add(1013904223);
            (s >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
        }
    }

    /// The box in lane `j` of a wide node.
    fn lane_box(w: &WideNode, j: usize) -> Aabb {
        Aabb::new(
            Vec3::new(w.lo[0][j], w.lo[1][j], w.lo[2][j]),
            Vec3::new(w.hi[0][j], w.hi[1][j], w.hi[2][j]),
        )
    }

    #[test]
    fn every_finite_shape_is_in_one_leaf_inside_its_ancestors() {
        let mut b = boxes(500, 7);
        b[3] = Aabb::INFINITE;
        b[9] = Aabb::EMPTY;
        let bvh = Bvh::build(&b);
        assert_eq!(bvh.apart, vec![3, 9]);
        let mut seen = vec![0; b.len()];
        let mut stack = vec![(0usize, Aabb::INFINITE)];
        while let Some((k, parent)) = stack.pop() {
            let n = bvh.nodes[k];
            assert_eq!(
                n.bounds.union(&parent),
                parent,
                "node {k} outside its parent"
            );
            if n.count == 0 {
                stack.push((n.first as usize, n.bounds));
                stack.push((n.first as usize + 1, n.bounds));
            } else {
                assert!(n.count as usize <= MAX_LEAF);
                for &i in &bvh.order[n.first as usize..(n.first + n.count) as usize] {
                    seen[i as usize] += 1;
                    assert_eq!(b[i as usize].union(&n.bounds), n.bounds);
                }
            }
        }
        for (i, &s) in seen.iter().enumerate() {
            assert_eq!(s, if i == 3 || i == 9 { 0 } else { 1 }, "shape {i}");
        }
        assert!(bvh.fits(b.iter()));
        let mut moved = b.clone();
        moved[0].max.x += 1.0;
        assert!(!bvh.fits(moved.iter()));
        assert!(!bvh.fits(b[1..].iter()));
    }

    #[test]
    fn the_wide_tree_holds_every_leaf_once_and_its_lanes_test_as_the_binary_nodes() {
        let b = boxes(300, 5);
        let bvh = Bvh::build(&b);
        // Every binary leaf is referenced by exactly one lane, inside its wide ancestors' lanes.
        let mut leaves = vec![0; bvh.nodes.len()];
        let mut stack = vec![0u32];
        while let Some(k) = stack.pop() {
            let w = bvh.wide[k as usize];
            assert!(w.lanes != 0 && w.lanes < 16 && (w.lanes + 1).is_power_of_two());
            for j in 0..w.lanes.count_ones() as usize {
                let c = w.child[j];
                if c & LEAF != 0 {
                    let leaf = (c & !LEAF) as usize;
                    assert!(bvh.nodes[leaf].count > 0);
                    leaves[leaf] += 1;
                    assert_eq!(lane_box(&w, j), bvh.nodes[leaf].bounds);
                } else {
                    stack.push(c);
                }
            }
        }
        for (k, n) in bvh.nodes.iter().enumerate() {
            assert_eq!(leaves[k], usize::from(n.count > 0), "node {k}");
        }
        // Each lane's interval is the binary node test's, bit for bit, rays parallel to axes included.
        let root = bvh.nodes[0].bounds;
        let margin = |t: f32| 1e-3 * (1.0 + t.abs());
        let mut u = signed_uniform(17);
        let mut kept = 0;
        for k in 0..3000 {
            let w = &bvh.wide[k % bvh.wide.len()];
            // Aimed at one of the node's boxes (some rays graze or miss it), or axis-parallel.
            let j = k % w.lanes.count_ones() as usize;
            let lane = lane_box(w, j);
            let aim = lane.min.lerp(lane.max, 0.5 + 0.7 * u());
            let o = Vec3::new(u(), u(), u()) * 15.0;
            let d = match k % 5 {
                0 => Vec3::Y,
                1 => Vec3::new(0.0, u(), u()).normalize(),
                _ => (aim - o).normalize(),
            };
            let slabs = RaySlabs::new(&Ray::new(o, d), &root, 0.0, margin);
            let (lanes, t0, t1) = slabs.wide_interval(w, 0.0, 40.0);
            for j in 0..w.lanes.count_ones() as usize {
                let c = w.child[j];
                let node = if c & LEAF != 0 {
                    bvh.nodes[(c & !LEAF) as usize].bounds
                } else {
                    let v = &bvh.wide[c as usize];
                    (0..v.lanes.count_ones() as usize)
                        .fold(Aabb::EMPTY, |a, i| a.union(&lane_box(v, i)))
                };
                let want = slabs.node_interval(&node, 0.0, 40.0);
                let got = (lanes & (1 << j) != 0).then(|| (t0[j], t1[j]));
                assert_eq!(got, want, "ray {k}, lane {j}");
                kept += usize::from(got.is_some());
            }
        }
        assert!(kept > 1000, "{kept}");
    }

    #[test]
    fn the_queue_pops_in_order_of_start_then_tag() {
        let mut q = Queue::default();
        let starts = [3.0, 1.0, 2.0, 1.0, 0.5, 2.0, 1.0];
        let tags = [1, SHAPE | 4, 7, 2, SHAPE | 9, SHAPE | 1, SHAPE | 2];
        for (&t0, &tag) in starts.iter().zip(&tags) {
            q.push(Entry { t0, t1: t0, tag });
        }
        let mut got = Vec::new();
        while let Some(e) = q.pop() {
            got.push((e.t0, e.tag));
        }
        let mut want: Vec<(f32, u32)> = starts.iter().copied().zip(tags).collect();
        want.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        assert_eq!(got, want);
    }

    #[test]
    fn a_node_interval_holds_its_boxes_intervals() {
        let b = boxes(64, 3);
        let parent = b.iter().fold(Aabb::EMPTY, |a, x| a.union(x));
        let margin = |t: f32| 1e-3 * (1.0 + t.abs());
        let mut u = signed_uniform(11);
        let mut kept = 0;
        for k in 0..4000 {
            let o = Vec3::new(u(), u(), u()) * 30.0;
            let d = match k % 8 {
                0 => Vec3::X,
                1 => Vec3::NEG_Z,
                // Aimed near a box: mostly kept, some grazing.
                _ => (b[k % b.len()].center() + Vec3::new(u(), u(), u()) * 0.3 - o).normalize(),
            };
            let ray = Ray::new(o, d);
            let slabs = RaySlabs::new(&ray, &parent, 0.0, margin);
            let node = slabs.node_interval(&parent, 0.0, 50.0);
            for child in &b {
                if let Some((c0, c1)) = child.clip_with_margin(&ray, 0.0, 50.0, margin) {
                    kept += 1;
                    let (n0, n1) = node.expect("the node holds a kept child");
                    assert!(
                        n0 <= c0 && c1 <= n1,
                        "ray {k}: child ({c0}, {c1}) node ({n0}, {n1})"
                    );
                }
            }
        }
        assert!(kept > 200, "{kept}");
    }
}
