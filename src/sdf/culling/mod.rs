//! Culling a CSG node's children: a small bounding volume hierarchy over the children of a hard union, a
//! smooth union or a difference, so that evaluating the node at a point evaluates the children near it
//! only.
//!
//! # What may be skipped, exactly
//!
//! A child's *culling box* ([`Sdf::cull_bounds`]) is a box `B` such that at every point `p` outside it
//! `φ(p) ≥ dist(p, B)`: the distance to the box is a lower bound of the field there. It exists for
//! exact distances (spheres, boxes, tori, cylinders: their surface lies in their box), grids (outside
//! the grid box `φ = φ(face) + dist`, and the grid box is grown by how far the face values go below the
//! level), unions (`min φ_i ≥ min dist(p, B_i) ≥ dist(p, ∪B_i)`), intersections (`max φ_i ≥ φ_j`: any
//! one child's box, the smallest), differences (`φ ≥ φ_0`: the first child's box), smooth unions (the
//! union's box grown by the most the folded smooth minimum lowers the minimum, `(n − 1) k/6`: a box
//! grown by `g` per axis holds the Euclidean `g`-neighbourhood of the box) and similarity transforms
//! (`φ = s φ_c(T⁻¹p)` and the box of the mapped corners holds `T(B_c)`). Planes and the primitives kept in
//! files of their own have none: they are always evaluated.
//!
//! A hard union's value is the first child (in order) reaching the minimum; a child is skipped when the
//! point lies outside its culling box by more than the best value found so far, so its value is strictly
//! above the result and could not have been it. A difference `max(φ_0, −φ_1, …)` skips a subtracted
//! child when `−dist(p, B_i)` is below the best: `−φ_i ≤ −dist < best`. In both the result is the value
//! of the same child as the plain fold's, bit for bit, with its derivatives (every point scalar type
//! branches on primal values; the interval types, which take hulls, are never culled). The boxes are
//! grown by a margin (1e-4 of their size and position, and the distance shrunk by 1e-5 relatively) so
//! that rounding in a child's evaluation cannot cross the bound.
//!
//! The field of the faces ([`Sdf::eval_faces`]) is never culled: a sharp primitive's face field is
//! below its distance outside its edges, so its box bounds nothing there.
//!
//! A smooth union folds the cubic smooth minimum left over its children, `d_i = smin(d_{i−1}, φ_i)`,
//! which is not associative: its value depends on the children's order, so the culling must keep the
//! fold's. With blend `k > 0`, `smin(d, φ)` is exactly `min(d, φ)` where `|φ − d| ≥ k`, and the running
//! value only falls with `i`. So a child whose box bound lies `k` above the running value is skipped,
//! and a child whose value lies `k` below it *resets* the fold (the running value becomes that child's
//! value, whatever came before). The running value never lies more than `k` below the least child value
//! so far, so a reset can be proved from the values of a point's near children and the box bounds of
//! the others, without the far children's values ([`smooth`]). The result is the plain fold's, bit for
//! bit.
//!
//! Intersections are evaluated in full: a box bounds a field from below, never from above (a maximum
//! needs the latter).

use super::Sdf;
use crate::math::{Aabb, Vec3};
use crate::scalar::Scalar;
use std::sync::Arc;

mod smooth;

pub(super) use smooth::smooth_union;

/// A hard union, a smooth union or a difference with more children than this gets a hierarchy over
/// them.
pub const CULL_MIN_CHILDREN: usize = 8;

/// Leaves hold at most this many children.
const LEAF_SIZE: usize = 4;

/// The children of a CSG node, with the hierarchy over them when there are enough of them.
///
/// Dereferences to the list. Any mutable access drops the hierarchy (its boxes could go stale);
/// [`Sdf::refreshed`] builds it again. Equality and `Debug` see the list only.
#[derive(Clone)]
pub struct Children {
    list: Vec<Sdf>,
    bvh: Option<Arc<ChildBvh>>,
    /// Whether a hierarchy is wanted (see [`Sdf::set_culling`]).
    cull: bool,
}

impl Default for Children {
    fn default() -> Self {
        Children::new(Vec::new())
    }
}

impl Children {
    /// The list with its hierarchy built (when it has more than [`CULL_MIN_CHILDREN`] children).
    pub fn new(list: Vec<Sdf>) -> Self {
        let mut c = Children {
            list,
            bvh: None,
            cull: true,
        };
        c.rebuild();
        c
    }

    /// Whether a hierarchy is in place.
    pub fn is_culled(&self) -> bool {
        self.bvh.is_some()
    }

    /// Builds the hierarchy from the children's current culling boxes (or drops it for few children).
    pub(super) fn rebuild(&mut self) {
        self.bvh = (self.cull && self.list.len() > CULL_MIN_CHILDREN)
            .then(|| Arc::new(ChildBvh::build(&self.list)));
    }

    /// The list, mutably, keeping the hierarchy: for refreshing the children themselves, which keeps
    /// their boxes, before this node's own [`Children::rebuild`].
    pub(super) fn list_for_refresh(&mut self) -> &mut Vec<Sdf> {
        &mut self.list
    }
}

impl From<Vec<Sdf>> for Children {
    fn from(list: Vec<Sdf>) -> Self {
        Children::new(list)
    }
}

impl std::ops::Deref for Children {
    type Target = Vec<Sdf>;
    fn deref(&self) -> &Vec<Sdf> {
        &self.list
    }
}

impl std::ops::DerefMut for Children {
    fn deref_mut(&mut self) -> &mut Vec<Sdf> {
        self.bvh = None;
        &mut self.list
    }
}

impl<'a> IntoIterator for &'a Children {
    type Item = &'a Sdf;
    type IntoIter = std::slice::Iter<'a, Sdf>;
    fn into_iter(self) -> Self::IntoIter {
        self.list.iter()
    }
}

impl<'a> IntoIterator for &'a mut Children {
    type Item = &'a mut Sdf;
    type IntoIter = std::slice::IterMut<'a, Sdf>;
    /// Through the mutable access: drops the hierarchy.
    fn into_iter(self) -> Self::IntoIter {
        std::ops::DerefMut::deref_mut(self).iter_mut()
    }
}

impl PartialEq for Children {
    fn eq(&self, other: &Self) -> bool {
        self.list == other.list
    }
}

impl std::fmt::Debug for Children {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.list.fmt(f)
    }
}

/// A node of [`ChildBvh`]: its box, and either two nodes or a run of [`ChildBvh::order`].
struct Node {
    min: glam::Vec3,
    max: glam::Vec3,
    /// Leaf: `(start, count)` in `order`; inner: `(left, right)` node indices, `leaf = false`.
    a: u32,
    b: u32,
    leaf: bool,
    /// The smallest child index below the node: the order in which a smooth union visits it.
    first: u32,
}

/// The hierarchy over children `1..` (the first is always evaluated first: it starts the fold).
pub(super) struct ChildBvh {
    nodes: Vec<Node>,
    /// Child indices, leaves' runs.
    order: Vec<u32>,
    /// Each child's grown culling box, by child index (infinite for those without one).
    boxes: Vec<(glam::Vec3, glam::Vec3)>,
    /// Children without a culling box (evaluated at every point), ascending.
    always: Vec<u32>,
}

/// The box grown by the rounding margin.
fn grown(b: &Aabb) -> (glam::Vec3, glam::Vec3) {
    let g = 1e-4 * (1.0 + b.magnitude());
    (b.min - glam::Vec3::splat(g), b.max + glam::Vec3::splat(g))
}

/// A lower bound of the field of a child with grown culling box `[min, max]` at `p`: the distance to the
/// box (shrunk by 1e-5 relatively) outside it, `−∞` inside (no bound there).
#[inline(always)]
fn lower(min: glam::Vec3, max: glam::Vec3, p: glam::Vec3) -> f32 {
    let e = (min - p).max(p - max);
    if e.cmple(glam::Vec3::ZERO).all() {
        return f32::NEG_INFINITY;
    }
    e.max(glam::Vec3::ZERO).length() * (1.0 - 1e-5)
}

impl ChildBvh {
    fn build(children: &[Sdf]) -> Self {
        let mut boxes = Vec::with_capacity(children.len());
        let mut always = Vec::new();
        let mut order = Vec::new();
        for (i, c) in children.iter().enumerate() {
            match c.cull_bounds() {
                Some(b) if !b.is_empty() && b.is_finite() => {
                    boxes.push(grown(&b));
                    order.push(i as u32);
                }
                _ => {
                    // An infinite box bounds nothing: the smooth union never skips it.
                    boxes.push((glam::Vec3::NEG_INFINITY, glam::Vec3::INFINITY));
                    always.push(i as u32)
                }
            }
        }
        // The first child starts every fold: it is in no list.
        order.retain(|&i| i != 0);
        always.retain(|&i| i != 0);
        let mut bvh = ChildBvh {
            nodes: Vec::new(),
            order: Vec::new(),
            boxes,
            always,
        };
        if !order.is_empty() {
            let n = order.len();
            bvh.split(&mut order, 0, n);
        }
        bvh.order = order;
        bvh
    }

    /// Builds the node over `order[start..start + count]` (median split of the centres along the
    /// widest axis); returns its index.
    fn split(&mut self, order: &mut [u32], start: usize, count: usize) -> u32 {
        let run = &mut order[start..start + count];
        let (mut min, mut max) = (glam::Vec3::INFINITY, glam::Vec3::NEG_INFINITY);
        let (mut cmin, mut cmax) = (glam::Vec3::INFINITY, glam::Vec3::NEG_INFINITY);
        for &i in run.iter() {
            let (a, b) = self.boxes[i as usize];
            min = min.min(a);
            max = max.max(b);
            let c = (a + b) * 0.5;
            cmin = cmin.min(c);
            cmax = cmax.max(c);
        }
        let id = self.nodes.len() as u32;
        self.nodes.push(Node {
            min,
            max,
            a: start as u32,
            b: count as u32,
            leaf: true,
            first: run.iter().copied().min().unwrap_or(u32::MAX),
        });
        if count <= LEAF_SIZE {
            return id;
        }
        let axis = (cmax - cmin).max_position();
        let half = count / 2;
        let boxes = &self.boxes;
        let centre = |i: &u32| {
            let (a, b) = boxes[*i as usize];
            a[axis] + b[axis]
        };
        run.select_nth_unstable_by(half, |x, y| centre(x).total_cmp(&centre(y)));
        let left = self.split(order, start, half);
        let right = self.split(order, start + half, count - half);
        let node = &mut self.nodes[id as usize];
        (node.a, node.b, node.leaf) = (left, right, false);
        id
    }

    /// Visits the children that may matter: `visit(i, bound)` (the child's box bound, `−∞` where none
    /// is known) is called for every always-evaluated child, then for the children whose bound passes
    /// `keep(bound)` (asked again with the latest state before each evaluation, so that it tightens as
    /// values come in).
    #[inline]
    fn visit(
        &self,
        p: glam::Vec3,
        mut keep: impl FnMut(f32) -> bool,
        mut visit: impl FnMut(usize, f32),
    ) {
        for &i in &self.always {
            visit(i as usize, f32::NEG_INFINITY);
        }
        let Some(root) = self.nodes.first() else {
            return;
        };
        // Nodes with their box bounds, computed once, when the parent orders its two.
        let mut stack = [(0u32, 0.0f32); 64];
        stack[0].1 = lower(root.min, root.max, p);
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let (id, bound) = stack[top];
            if !keep(bound) {
                continue;
            }
            let node = &self.nodes[id as usize];
            if node.leaf {
                for &i in &self.order[node.a as usize..(node.a + node.b) as usize] {
                    let (a, b) = self.boxes[i as usize];
                    let bound = lower(a, b, p);
                    if keep(bound) {
                        visit(i as usize, bound);
                    }
                }
            } else {
                // Nearer child last, so popped first: the best value tightens sooner.
                let (l, r) = (&self.nodes[node.a as usize], &self.nodes[node.b as usize]);
                let (dl, dr) = (lower(l.min, l.max, p), lower(r.min, r.max, p));
                let (near, far) = if dl <= dr {
                    ((node.a, dl), (node.b, dr))
                } else {
                    ((node.b, dr), (node.a, dl))
                };
                if top + 2 > stack.len() {
                    // Deeper than any balanced tree of a CSG node: visit everything below instead.
                    self.visit_all(id, &mut visit);
                    continue;
                }
                stack[top] = far;
                stack[top + 1] = near;
                top += 2;
            }
        }
    }

    fn visit_all(&self, node: u32, visit: &mut impl FnMut(usize, f32)) {
        let n = &self.nodes[node as usize];
        if n.leaf {
            for &i in &self.order[n.a as usize..(n.a + n.b) as usize] {
                visit(i as usize, f32::NEG_INFINITY);
            }
        } else {
            self.visit_all(n.a, visit);
            self.visit_all(n.b, visit);
        }
    }
}

/// The primal point of a generic point.
#[inline(always)]
fn primal<S: Scalar>(p: Vec3<S>) -> glam::Vec3 {
    glam::Vec3::new(p.x.primal(), p.y.primal(), p.z.primal())
}

/// A hard union over a hierarchy: the plain fold's result (the first child reaching the minimum).
#[inline]
pub(super) fn union<S: Scalar, const FACES: bool>(
    children: &[Sdf],
    bvh: &ChildBvh,
    p: Vec3<S>,
) -> S {
    culled_fold::<S, FACES, false>(children, bvh, p)
}

/// A difference over a hierarchy of its subtracted children: the plain fold's result (the first term
/// of `φ_0, −φ_1, …` reaching the maximum).
#[inline]
pub(super) fn difference<S: Scalar, const FACES: bool>(
    children: &[Sdf],
    bvh: &ChildBvh,
    p: Vec3<S>,
) -> S {
    culled_fold::<S, FACES, true>(children, bvh, p)
}

/// The minimum of `φ_0, φ_1, …` (`SUBTRACT` false) or the maximum of `φ_0, −φ_1, …` (true), the
/// first term reaching it on ties, visiting only the children whose box may hold a better value. Both
/// compare keys that are minimised: the term, or its negation for the maximum (exact in floats), so
/// that a child's box lower bound `b` may improve on the best key `k` only if `b ≤ k`.
#[inline(always)]
fn culled_fold<S: Scalar, const FACES: bool, const SUBTRACT: bool>(
    children: &[Sdf],
    bvh: &ChildBvh,
    p: Vec3<S>,
) -> S {
    let mut best = children[0].eval_as::<S, FACES>(p);
    if best.primal().is_nan() {
        // The fold keeps a NaN first value.
        return best;
    }
    let key = |v: f32| if SUBTRACT { -v } else { v };
    let mut best_index = 0;
    let q = primal(p);
    let best_key = std::cell::Cell::new(key(best.primal()));
    bvh.visit(
        q,
        |bound| bound.partial_cmp(&best_key.get()) != Some(std::cmp::Ordering::Greater),
        |i, _| {
            let child = children[i].eval_as::<S, FACES>(p);
            let v = if SUBTRACT { -child } else { child };
            let (vk, bk) = (key(v.primal()), key(best.primal()));
            if vk < bk || (vk == bk && i < best_index) {
                best = v;
                best_index = i;
                best_key.set(vk);
            }
        },
    );
    best
}

/// The hierarchy of `children` if it may be used for the scalar type `S` (point types only).
#[inline(always)]
pub(super) fn hierarchy<S: Scalar>(children: &Children) -> Option<&ChildBvh> {
    if S::POINT {
        children.bvh.as_deref()
    } else {
        None
    }
}

/// Rebuilds every hierarchy under `sdf`, children first (their culling boxes do not depend on their own
/// hierarchies, but the walk must not go through the mutable access that drops them).
pub(super) fn refresh(sdf: &mut Sdf) {
    match sdf {
        Sdf::Union(c) | Sdf::Intersection(c) | Sdf::Difference(c) => {
            c.list_for_refresh().iter_mut().for_each(refresh);
            c.rebuild();
        }
        Sdf::SmoothUnion { children, .. } => {
            children.list_for_refresh().iter_mut().for_each(refresh);
            children.rebuild();
        }
        Sdf::Transform { child, .. } | Sdf::Named { child, .. } => refresh(child),
        _ => {}
    }
}

impl Sdf {
    /// Turns the culling of every CSG node under this one on (the default; hierarchies built) or off
    /// (every child evaluated everywhere, also after [`Sdf::refreshed`]): for comparisons and benches.
    pub fn set_culling(&mut self, on: bool) {
        match self {
            Sdf::Union(c) | Sdf::Intersection(c) | Sdf::Difference(c) => {
                c.list.iter_mut().for_each(|s| s.set_culling(on));
                c.cull = on;
                c.rebuild();
            }
            Sdf::SmoothUnion { children: c, .. } => {
                c.list.iter_mut().for_each(|s| s.set_culling(on));
                c.cull = on;
                c.rebuild();
            }
            Sdf::Transform { child, .. } | Sdf::Named { child, .. } => child.set_culling(on),
            _ => {}
        }
    }

    /// A box `B` such that `φ(p) ≥ dist(p, B)` at every point outside it (see the culling notes in the
    /// source): what lets a hard union or a difference skip this node where it cannot matter. `None`
    /// where no such box is known (planes, the primitives in files of their own, CSG over them).
    pub fn cull_bounds(&self) -> Option<Aabb> {
        match self {
            Sdf::Sphere { .. } | Sdf::Box { .. } | Sdf::Torus { .. } | Sdf::Cylinder { .. } => {
                Some(self.bounds())
            }
            Sdf::Primitive(_) | Sdf::Plane { .. } => None,
            Sdf::Union(children) => children
                .iter()
                .try_fold(Aabb::EMPTY, |b, c| Some(b.union(&c.cull_bounds()?))),
            Sdf::Intersection(children) => children
                .iter()
                .filter_map(Sdf::cull_bounds)
                .min_by(|a, b| volume(a).total_cmp(&volume(b))),
            Sdf::Difference(children) => children.first().and_then(Sdf::cull_bounds),
            Sdf::SmoothUnion { children, k } => {
                let b = children
                    .iter()
                    .try_fold(Aabb::EMPTY, |b, c| Some(b.union(&c.cull_bounds()?)))?;
                let n = children.len().max(1) as f32;
                let grow = (n - 1.0) * k.value.max(0.0) * super::csg::SMIN_MAX_LOWERING;
                Some(if b.is_empty() { b } else { b.expanded(grow) })
            }
            Sdf::Transform { .. } => {
                let (frame, child) = self.frame()?;
                Some(frame.from_child_box(&child.cull_bounds()?))
            }
            Sdf::Grid {
                data,
                bbox_min,
                bbox_max,
                level,
                ..
            } => Some(super::grid::cull_bounds(
                data,
                *bbox_min,
                *bbox_max,
                level.value,
            )),
            Sdf::Named { child, .. } => child.cull_bounds(),
        }
    }
}

/// A box's volume (infinite boxes compare last).
fn volume(b: &Aabb) -> f32 {
    let e = b.extent();
    if b.is_empty() { 0.0 } else { e.x * e.y * e.z }
}
