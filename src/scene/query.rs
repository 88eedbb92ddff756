//! Ray queries against a scene's shapes: the nearest hit and whether anything lies within a distance,
//! through the scene's [`Bvh`] or, for few shapes, shape by shape.

use super::bvh::{Entry, LEAF, Queue, RaySlabs, SHAPE};
use super::shape_list::{ShapeList, set_lanes};
use super::{Bvh, Hit, Intersection, Scene, Surface};
use crate::math::Ray;
use crate::trace::{ShapeTrace, TraceSettings};
use std::cell::RefCell;
use std::sync::Arc;

/// The nearest surface found so far by [`Scene::intersect`].
#[derive(Clone, Copy)]
pub(super) struct Nearest {
    pub(super) t: f32,
    pub(super) surface: Option<Surface>,
    /// Normal of an emitter hit (shape normals are computed once, for the final hit only).
    normal: glam::Vec3,
    exhausted: bool,
}

/// Scenes with at most this many shapes sort their intervals on the stack when not using the hierarchy.
const MAX_SORTED_SHAPES: usize = 16;

/// Scenes with more shapes than this use the hierarchy: below, testing every shape's bounds costs no
/// more than walking a tree (and gives the same results).
const MIN_BVH_SHAPES: usize = 4;

/// Most levels of a hierarchy's any-hit walk kept on the stack; deeper walks spill to the heap.
const STACK: usize = 64;

thread_local! {
    /// The nearest-hit query's priority queue, reused from ray to ray on each thread.
    static QUEUE: RefCell<Queue> = RefCell::new(Queue::default());
}

impl Scene {
    /// Rebuilds [`Scene::bvh`] from the shapes' current bounds: needed only after changing
    /// [`Scene::shapes`] in place (every other change of the scene rebuilds it).
    pub fn refresh_bvh(&mut self) {
        let bounds: Vec<_> = self.shapes.iter().map(|s| s.bounds).collect();
        if !self.bvh.fits(bounds.iter()) {
            self.bvh = Arc::new(Bvh::build(&bounds));
        }
    }

    /// The hierarchy, when the queries use it: switched on, built for as many shapes as the scene has,
    /// and more than a few of them.
    #[inline]
    pub(super) fn hierarchy(&self) -> Option<&Bvh> {
        let n = self.shapes.len();
        (self.use_bvh && n > MIN_BVH_SHAPES && self.bvh.len() == n).then_some(&*self.bvh)
    }

    /// The first surface hit by `ray` in `(0, t_max)`, resolving `spread`, skipping shape `leaving`.
    ///
    /// Shapes are traced in the order the ray enters their grown bounds (ties by index), each over its
    /// interval cut at the nearest hit so far, so that a near hit cuts the intervals of the shapes behind
    /// it (most of a floor's pixels never march through the object above it); the hierarchy visits
    /// them in the same order ([`super::bvh`]), so the result is the same with it or without.
    pub(super) fn nearest(
        &self,
        ray: &Ray,
        t_max: f32,
        spread: f32,
        leaving: Option<usize>,
    ) -> Intersection {
        let mut nearest = self.nearest_emitter(ray, t_max);
        match self.hierarchy() {
            Some(bvh) => self.nearest_in(bvh, ray, spread, leaving, &mut nearest),
            None => {
                let t_max = nearest.t;
                let intervals = (self.shapes.iter().enumerate())
                    .filter(|&(i, _)| Some(i) != leaving)
                    .filter_map(|(i, shape)| {
                        let (t0, t1) = self.trace_interval(shape, ray, t_max)?;
                        Some((t0, t1, i))
                    });
                self.nearest_each(ray, spread, intervals, self.shapes.len(), &mut nearest);
            }
        }
        self.nearest_hit(ray, nearest)
    }

    /// The first hit of a camera ray with footprint growth `spread`: [`Scene::intersect_among`] the
    /// pixel's `shapes` when they are known ([`super::frustum::PixelShapes`]), else
    /// [`Scene::intersect_resolving`].
    #[inline]
    pub fn intersect_camera(
        &self,
        ray: &Ray,
        spread: f32,
        shapes: Option<&ShapeList>,
    ) -> Intersection {
        match shapes {
            Some(list) => self.intersect_among(ray, f32::INFINITY, spread, list),
            None => self.intersect_resolving(ray, f32::INFINITY, spread),
        }
    }

    /// [`Scene::intersect_resolving`] for a ray that can meet no shape but `shapes`, e.g. a camera
    /// ray with its pixel's shapes ([`super::frustum::PixelShapes`]): the same intersection, bit for
    /// bit, when every other shape's interval along the ray is empty. The list's boxes are tested
    /// four at a time first ([`ShapeList`]).
    pub fn intersect_among(
        &self,
        ray: &Ray,
        t_max: f32,
        spread: f32,
        shapes: &ShapeList,
    ) -> Intersection {
        let mut nearest = self.nearest_emitter(ray, t_max);
        let intervals = shapes.intervals(self, ray, nearest.t);
        self.nearest_each(ray, spread, intervals, shapes.len(), &mut nearest);
        self.nearest_hit(ray, nearest)
    }

    /// The nearest finite emitter `ray` meets in `(0, t_max)`: where [`Scene::nearest`] starts.
    #[inline]
    pub(super) fn nearest_emitter(&self, ray: &Ray, t_max: f32) -> Nearest {
        let mut nearest = Nearest {
            t: t_max,
            surface: None,
            normal: glam::Vec3::ZERO,
            exhausted: false,
        };
        for &i in &self.finite_emitters {
            if let Some((t, n)) = self.emitters[i].emitter.intersect(ray, nearest.t) {
                nearest = Nearest {
                    t,
                    surface: Some(Surface::Emitter(i)),
                    normal: n,
                    ..nearest
                };
            }
        }
        nearest
    }

    /// The intersection of the nearest surface found, with its normal.
    #[inline]
    pub(super) fn nearest_hit(&self, ray: &Ray, nearest: Nearest) -> Intersection {
        match nearest.surface {
            Some(surface) => {
                let p = ray.at(nearest.t);
                let n = match surface {
                    Surface::Shape(i) => self.shapes[i].normal(p),
                    Surface::Emitter(_) => nearest.normal,
                };
                Intersection::Hit(Hit {
                    t: nearest.t,
                    p,
                    n,
                    surface,
                })
            }
            None if nearest.exhausted => Intersection::Exhausted,
            None => Intersection::Miss,
        }
    }

    /// [`Scene::nearest`]'s shapes, given as their non-empty intervals `(t0, t1, index)` along the
    /// ray up to the nearest emitter hit ([`Scene::trace_interval`]; increasing indices, drawn from
    /// at most `count` shapes).
    fn nearest_each(
        &self,
        ray: &Ray,
        spread: f32,
        intervals: impl Iterator<Item = (f32, f32, usize)>,
        count: usize,
        nearest: &mut Nearest,
    ) {
        let mut trace = |sorted: &[(f32, f32, usize)]| {
            for &(t0, t1, i) in sorted {
                if t0 < nearest.t {
                    self.trace_shape(i, ray, t0, t1.min(nearest.t), spread, nearest);
                }
            }
        };
        if count <= MAX_SORTED_SHAPES {
            // Insertion sort on the stack: stable, so ties keep the index order.
            let mut sorted = [(0.0f32, 0.0f32, 0usize); MAX_SORTED_SHAPES];
            let mut count = 0;
            for (t0, t1, i) in intervals {
                let mut k = count;
                while k > 0 && sorted[k - 1].0 > t0 {
                    sorted[k] = sorted[k - 1];
                    k -= 1;
                }
                sorted[k] = (t0, t1, i);
                count += 1;
            }
            trace(&sorted[..count]);
        } else {
            let mut sorted: Vec<_> = intervals.collect();
            sorted.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.2.cmp(&b.2)));
            trace(&sorted);
        }
    }

    /// [`Scene::nearest`]'s shapes through the hierarchy: a priority queue of nodes and shapes keyed by
    /// where their intervals start, popped until the nearest start is beyond the nearest hit.
    fn nearest_in(
        &self,
        bvh: &Bvh,
        ray: &Ray,
        spread: f32,
        leaving: Option<usize>,
        nearest: &mut Nearest,
    ) {
        // Shapes' intervals are clipped at the nearest emitter hit, as [`Scene::nearest_each`] clips
        // them; nodes' at the nearest hit so far (a node beyond it holds no shape to trace).
        let t_max = nearest.t;
        let origin = ray.o.abs().max_element();
        let margin = |entry: f32| self.trace.eps_at(origin + entry);
        QUEUE.with(|queue| {
            let mut queue = queue.borrow_mut();
            queue.clear();
            let push_shape = |queue: &mut Queue, i: u32| {
                if Some(i as usize) == leaving {
                    return;
                }
                if let Some((t0, t1)) = self.trace_interval(&self.shapes[i as usize], ray, t_max) {
                    queue.push(Entry {
                        t0,
                        t1,
                        tag: SHAPE | i,
                    });
                }
            };
            for &i in &bvh.apart {
                push_shape(&mut queue, i);
            }
            let Some(root) = bvh.nodes.first() else {
                while let Some(e) = queue.pop() {
                    if e.t0.partial_cmp(&nearest.t) != Some(std::cmp::Ordering::Less) {
                        break;
                    }
                    let i = (e.tag & !SHAPE) as usize;
                    self.trace_shape(i, ray, e.t0, e.t1.min(nearest.t), spread, nearest);
                }
                return;
            };
            let slabs = RaySlabs::new(ray, &root.bounds, 0.0, margin);
            // The entry being processed: popped, or a child that would be popped next.
            let mut next = None;
            if let Some((t0, t1)) = slabs.node_interval(&root.bounds, 0.0, t_max) {
                queue.push(Entry { t0, t1, tag: 0 });
            }
            while let Some(e) = next.take().or_else(|| queue.pop()) {
                // Nothing queued starts before this, and only shapes starting before the nearest hit
                // are traced.
                if e.t0.partial_cmp(&nearest.t) != Some(std::cmp::Ordering::Less) {
                    break;
                }
                if e.tag & SHAPE != 0 {
                    let i = (e.tag & !SHAPE) as usize;
                    self.trace_shape(i, ray, e.t0, e.t1.min(nearest.t), spread, nearest);
                    continue;
                }
                if e.tag & LEAF != 0 {
                    let node = bvh.nodes[(e.tag & !LEAF) as usize];
                    let range = node.first as usize..(node.first + node.count) as usize;
                    for &i in &bvh.order[range] {
                        push_shape(&mut queue, i);
                    }
                    continue;
                }
                let node = &bvh.wide[e.tag as usize];
                let (lanes, t0, t1) = slabs.wide_interval(node, 0.0, nearest.t);
                // The first child goes on at once when it would be popped next anyway.
                let mut first: Option<Entry> = None;
                for j in set_lanes(lanes) {
                    let child = Entry {
                        t0: t0[j],
                        t1: t1[j],
                        tag: node.child[j],
                    };
                    match first {
                        Some(f) if !child.before(&f) => queue.push(child),
                        _ => {
                            if let Some(f) = first.replace(child) {
                                queue.push(f);
                            }
                        }
                    }
                }
                if let Some(f) = first {
                    if queue.comes_first(&f) {
                        next = Some(f);
                    } else {
                        queue.push(f);
                    }
                }
            }
        });
    }

    /// Traces shape `i` over `[t0, t1]` and keeps its hit if it is the nearest so far.
    #[inline]
    fn trace_shape(
        &self,
        i: usize,
        ray: &Ray,
        t0: f32,
        t1: f32,
        spread: f32,
        nearest: &mut Nearest,
    ) {
        let shape = &self.shapes[i];
        let settings = TraceSettings {
            spread,
            ..self.shape_trace(shape)
        };
        match shape.trace(ray, t0, t1, &settings) {
            ShapeTrace::Hit(t) if t < nearest.t => {
                nearest.t = t;
                nearest.surface = Some(Surface::Shape(i));
            }
            ShapeTrace::Exhausted(_) => nearest.exhausted = true,
            _ => {}
        }
    }

    /// Whether some shape other than `leaving` crosses `ray` in `(0, t_max)`, each traced over its
    /// bounds with its own tolerances, as [`Scene::intersect`] traces it (a shadow ray and a camera ray
    /// along the same line agree on what they hit). Adds to `exhausted` the traces that ran out of
    /// steps before the answer was known (they count as misses).
    pub fn shapes_block(
        &self,
        ray: &Ray,
        t_max: f32,
        leaving: Option<usize>,
        exhausted: &mut u64,
    ) -> bool {
        self.shape_blocking(ray, t_max, leaving, exhausted)
            .is_some()
    }

    /// [`Scene::shapes_block`] for a ray that follows one that `blocker` blocked (`None`: nothing did,
    /// or no ray came before), which is tested first: shadow rays from nearby points to one light
    /// tend to meet the same occluder, and when it blocks this ray too the answer is the same
    /// without walking the hierarchy (any one blocker decides it). Sets `blocker` to this ray's,
    /// when it walked. Only the count of exhausted traces can differ from [`Scene::shapes_block`]'s
    /// (the walk counts those it meets before a blocker); it is the same on every run as long as the
    /// caller's sequence of rays is. Without a hierarchy (a few shapes), the walk itself.
    pub fn shapes_block_after(
        &self,
        ray: &Ray,
        t_max: f32,
        leaving: Option<usize>,
        blocker: &mut Option<u32>,
        exhausted: &mut u64,
    ) -> bool {
        if self.hierarchy().is_none() {
            return self.shapes_block(ray, t_max, leaving, exhausted);
        }
        if let Some(i) = *blocker
            && self.shape_blocks(i as usize, ray, t_max, leaving, &mut 0)
        {
            return true;
        }
        let found = self.shape_blocking(ray, t_max, leaving, exhausted);
        *blocker = found.map(|i| i as u32);
        found.is_some()
    }

    /// Whether shape `i`, when it is not `leaving`, crosses `ray` in `(0, t_max)`, as
    /// [`Scene::shapes_block`] tests it (a trace that runs out of steps adds to `exhausted`).
    #[inline]
    fn shape_blocks(
        &self,
        i: usize,
        ray: &Ray,
        t_max: f32,
        leaving: Option<usize>,
        exhausted: &mut u64,
    ) -> bool {
        if Some(i) == leaving {
            return false;
        }
        let shape = &self.shapes[i];
        let Some((t0, t1)) = self.trace_interval(shape, ray, t_max) else {
            return false;
        };
        match shape.trace(ray, t0, t1, &self.shape_trace(shape)) {
            ShapeTrace::Hit(t) => t < t_max,
            ShapeTrace::Exhausted(_) => {
                *exhausted += 1;
                false
            }
            ShapeTrace::Miss => false,
        }
    }

    /// [`Scene::shapes_block`], saying which shape blocks the ray: the first one found (nearer
    /// boxes first), or `None`.
    fn shape_blocking(
        &self,
        ray: &Ray,
        t_max: f32,
        leaving: Option<usize>,
        exhausted: &mut u64,
    ) -> Option<usize> {
        let blocks =
            |i: usize, exhausted: &mut u64| self.shape_blocks(i, ray, t_max, leaving, exhausted);
        let Some(bvh) = self.hierarchy() else {
            return (0..self.shapes.len()).find(|&i| blocks(i, exhausted));
        };
        if let Some(&i) = bvh.apart.iter().find(|&&i| blocks(i as usize, exhausted)) {
            return Some(i as usize);
        }
        let root = bvh.nodes.first()?;
        let origin = ray.o.abs().max_element();
        let margin = |entry: f32| self.trace.eps_at(origin + entry);
        let slabs = RaySlabs::new(ray, &root.bounds, 0.0, margin);
        slabs.node_interval(&root.bounds, 0.0, t_max)?;
        // Depth first, nearer children first: an occluder near the start ends the walk early.
        let mut stack = [0u32; STACK];
        let mut spill = Vec::new();
        let mut top = 1;
        loop {
            let k = if let Some(k) = spill.pop() {
                k
            } else if top > 0 {
                top -= 1;
                stack[top]
            } else {
                return None;
            };
            if k & LEAF != 0 {
                let node = bvh.nodes[(k & !LEAF) as usize];
                let range = node.first as usize..(node.first + node.count) as usize;
                if let Some(&i) = bvh.order[range]
                    .iter()
                    .find(|&&i| blocks(i as usize, exhausted))
                {
                    return Some(i as usize);
                }
                continue;
            }
            let node = &bvh.wide[k as usize];
            let (lanes, t0, _) = slabs.wide_interval(node, 0.0, t_max);
            // The kept children, farthest first (pushed first, popped last).
            let mut kept = [(0.0f32, 0u32); 4];
            let mut n = 0;
            for j in set_lanes(lanes) {
                let mut m = n;
                while m > 0 && kept[m - 1].0 < t0[j] {
                    kept[m] = kept[m - 1];
                    m -= 1;
                }
                kept[m] = (t0[j], node.child[j]);
                n += 1;
            }
            for &(_, c) in &kept[..n] {
                if top < STACK {
                    stack[top] = c;
                    top += 1;
                } else {
                    spill.push(c);
                }
            }
        }
    }
}
