//! The smooth union's culling: its fold in index order, with the children that cannot change it skipped
//! and those before a provable reset left out.
//!
//! The plain fold is `d_0 = φ_0`, `d_i = smin(d_{i−1}, φ_i)` with the cubic smooth minimum of blend `k`
//! (`csg::smin`). Two facts make it cullable exactly:
//!
//! - Where `|φ_i − d_{i−1}| ≥ k` (in floats), `smin` returns `min(d_{i−1}, φ_i)`, one of its two
//!   arguments, derivatives and all: `d_{i−1}` when the child lies `k` above (it is *skipped*), `φ_i`
//!   when it lies `k` below (it *resets* the fold: nothing before it matters).
//! - `d_i ≤ min(d_{i−1}, φ_i)`, so the running value only falls; and it never falls more than `k` below
//!   the least child value so far, `d_i > min_{j ≤ i} φ_j − k`. One `smin` lowers `min(a, b)` by
//!   `k h³/6`, `h = 1 − |a − b|/k`; if the running value lies `x ∈ [0, k)` below the least value, the
//!   next child leaves it at most `x + k (1 − x/k)³/6 < k` below (and a new least value starts it
//!   again below `k`).
//!
//! [`NearChildren`] gathers the children whose box bounds lie below `limit = best + 3.5k` at the point
//! (`best` the hard union's value there), sorts them by index, and bounds the running value from below
//! along them: past children left out (values at least `limit`) by `min(low, limit − k)` (`smin(x, φ)`
//! with `φ ≥ limit` is `x` where `x ≤ limit − k` and stays above `limit − k` from above), past a
//! gathered child by `smin(low, φ)` (`smin` grows with each argument). The first child whose value lies
//! `k` below that bound, and `k` below `limit`, resets the fold; from there the gathered children are
//! folded in order, and the others, at least `k` above the running value by then, are skipped. Where
//! no reset is proved, the children before the first gathered one lying `k` below `limit` are folded
//! in full order ([`ordered_fold`]) and the gathered ones from there on. The bounds carry margins for
//! rounding: a few ulps between the `f32` and the generic evaluation, and the plain fold's own
//! rounding, a few ulps per step over at most `n` blending steps spanning at most `n k`.

use super::super::{Sdf, csg::smin};
use super::{ChildBvh, culled_fold, lower, primal};
use crate::math::Vec3;
use crate::scalar::Scalar;

/// A smooth union over a hierarchy: `smin` folded left over the children in index order, as the plain
/// fold, skipping the children that provably leave the running value as it is, and those before a
/// child that provably resets it.
///
/// With blend `k > 0`, `smin(d, φ_i)` is exactly `min(d, φ_i)` (the same scalar, derivatives and
/// all) where `|φ_i − d| ≥ k` in floats: `d` where `φ_i ≥ d + k`, `φ_i` where `φ_i ≤ d − k`. So a
/// child whose box bound exceeds the running value by `k` (with a margin for the subtraction's
/// rounding) is skipped, and the running value only falls with the index. [`NearChildren`] finds a
/// child that resets the fold (its value at least `k` below the running value before it, which it
/// proves without computing that value) and the few children after it that may blend; where it proves
/// none, [`ordered_fold`] walks the hierarchy in index order. With `k ≤ 0` (or NaN) `smin` is `min`:
/// the hard union.
#[inline]
pub(in crate::sdf) fn smooth_union<S: Scalar, const FACES: bool>(
    children: &[Sdf],
    bvh: &ChildBvh,
    k: S,
    p: Vec3<S>,
) -> S {
    let kp = k.primal();
    if kp.is_nan() || kp <= 0.0 {
        return culled_fold::<S, FACES, false>(children, bvh, p);
    }
    let q = primal(p);
    let Some((near, start)) = NearChildren::gather::<FACES>(children, bvh, kp, q) else {
        return ordered_fold::<S, FACES>(children, bvh, k, p, children.len());
    };
    let (indices, bounds) = (&near.index[..near.len], &near.bound[..near.len]);
    let (mut d, from) = match start {
        Start::Reset(j) => (children[indices[j] as usize].eval_as::<S, FACES>(p), j + 1),
        Start::Low(j) => (
            ordered_fold::<S, FACES>(children, bvh, k, p, indices[j] as usize),
            j,
        ),
    };
    for (&i, &bound) in indices[from..].iter().zip(&bounds[from..]) {
        d = fold_child::<S, FACES>(d, &children[i as usize], bound, k, p);
    }
    d
}

/// The running value `d` with `child` (whose box bound at the point is `bound`) folded in, or `d`
/// itself where the bound proves the child leaves it unchanged.
#[inline(always)]
fn fold_child<S: Scalar, const FACES: bool>(d: S, child: &Sdf, bound: f32, k: S, p: Vec3<S>) -> S {
    if unchanged(bound, d.primal(), k.primal()) {
        d
    } else {
        smin(d, child.eval_as::<S, FACES>(p), k)
    }
}

/// Whether `smin(d, φ)` is provably `d` for every `φ ≥ bound`: `bound > d + k (1 + 1e-5) + 1e-5 |d|`
/// makes the rounded `φ − d` at least `k`. False where `d` is NaN.
#[inline(always)]
fn unchanged(bound: f32, d: f32, k: f32) -> bool {
    bound > d + k + 1e-5 * (d.abs() + k)
}

/// Where the fold over [`NearChildren`] starts, as a position in the list.
enum Start {
    /// The child there resets the fold: its value is the running value after it.
    Reset(usize),
    /// No reset is proved; from the child there on (the first whose value lies `k` below the list's
    /// reach) the children left out change nothing, so the fold of the children before it, done in
    /// full order, and then the list's from there give the fold.
    Low(usize),
}

/// How many children [`NearChildren`] holds; with more near a point the walk in index order decides.
const NEAR_MAX: usize = 128;

/// The children of a smooth union whose box bounds lie below `limit = best + 3.5k` at a point (`best`
/// the least of the children's values there, the hard union's), in index order, and where the fold
/// over them starts (the proof in the module notes): every child left out has a value of at least
/// `limit`.
struct NearChildren {
    index: [u32; NEAR_MAX],
    /// The child's box bound at the point (`−∞` where it has none).
    bound: [f32; NEAR_MAX],
    /// The child's value in `f32` where the gathering computed it, else NaN.
    value: [f32; NEAR_MAX],
    len: usize,
}

impl NearChildren {
    /// The near children of the smooth union with blend `k > 0` at `q` and where the fold starts:
    /// at the first child that provably resets it, else after the children before the first whose
    /// value lies `k` below `limit`. `None` where there are too many, or a value is NaN.
    fn gather<const FACES: bool>(
        children: &[Sdf],
        bvh: &ChildBvh,
        k: f32,
        q: glam::Vec3,
    ) -> Option<(Self, Start)> {
        let eval = |i: usize| children[i].eval_as::<f32, FACES>(q.into());
        let mut near = NearChildren {
            index: [0; NEAR_MAX],
            bound: [0.0; NEAR_MAX],
            value: [f32::NAN; NEAR_MAX],
            len: 0,
        };
        let first = eval(0);
        if first.is_nan() {
            return None;
        }
        let (a, b) = bvh.boxes[0];
        near.push(0, lower(a, b, q), first);
        let reach = 3.5 * k;
        let best = std::cell::Cell::new(first);
        let mut fits = true;
        // Near first, as the hard union's walk: the least value tightens the reach as it comes in.
        bvh.visit(
            q,
            |bound| bound < best.get() + reach,
            |i, bound| {
                let value = if bound <= best.get() {
                    let v = eval(i);
                    best.set(best.get().min(v));
                    v
                } else {
                    f32::NAN
                };
                fits &= near.push(i as u32, bound, value);
            },
        );
        let limit = best.get() + reach;
        if !fits || !limit.is_finite() {
            return None;
        }
        // Keep those within the final reach (the walk's earlier, wider reach let more in), in order.
        let mut kept = 0;
        for j in 0..near.len {
            if near.bound[j] < limit {
                near.move_entry(j, kept);
                kept += 1;
            }
        }
        near.len = kept;
        near.sort();
        let n = children.len() as f32;
        // A lower bound of the running value before the child at `j` (none before child 0).
        let mut low = f32::INFINITY;
        let mut previous = None;
        let mut first_low = None;
        for j in 0..near.len {
            let i = near.index[j];
            if previous.map_or(i > 0, |p| i > p + 1) {
                // Children left out lie at `limit` or above: past them the running value is at
                // least `min(low, limit − k)`.
                low = low.min(limit - k);
            }
            let mut v = near.value[j];
            if v.is_nan() {
                v = eval(i as usize);
            }
            if v.is_nan() {
                return None;
            }
            // Rounding: a few ulps between the `f32` and the generic evaluation; and the plain
            // fold's own and this bound's: one `smin` errs by at most about `ε (|d| + 2.2 k)` (`ε` half
            // an ulp, 6e-8), at most `n` blending steps matter, over values within `|v| + (n + 4.5) k`
            // of zero (the blends descend by less than `k` each to `low`, itself below `v + 3.5 k`),
            // and each step passes earlier errors on at most unchanged (partials in [0, 1]).
            let ulps = 1e-5 * (v.abs() + low.abs().min(f32::MAX) + k);
            let chain = n * 2.5e-7 * (v.abs() + (n + 1.0) * k);
            if v + k + ulps < limit {
                let resets = low == f32::INFINITY || low - ulps - chain >= v + k;
                if resets {
                    return Some((near, Start::Reset(j)));
                }
                first_low.get_or_insert(j);
            }
            low = if low == f32::INFINITY {
                v
            } else {
                smin(low, v, k)
            };
            previous = Some(i);
        }
        first_low.map(|j| (near, Start::Low(j)))
    }

    /// Adds a child; false (nothing added) when full.
    fn push(&mut self, index: u32, bound: f32, value: f32) -> bool {
        if self.len == NEAR_MAX {
            return false;
        }
        let at = self.len;
        (self.index[at], self.bound[at], self.value[at]) = (index, bound, value);
        self.len += 1;
        true
    }

    /// Copies the entry at `from` over the one at `to`.
    fn move_entry(&mut self, from: usize, to: usize) {
        self.index[to] = self.index[from];
        self.bound[to] = self.bound[from];
        self.value[to] = self.value[from];
    }

    /// Sorts the children by index (insertion sort: a few dozen, mostly in order).
    fn sort(&mut self) {
        for j in 1..self.len {
            let (i, b, v) = (self.index[j], self.bound[j], self.value[j]);
            let mut at = j;
            while at > 0 && self.index[at - 1] > i {
                self.move_entry(at - 1, at);
                at -= 1;
            }
            (self.index[at], self.bound[at], self.value[at]) = (i, b, v);
        }
    }
}

/// The smooth union's fold over the children before `end`, in index order through the hierarchy:
/// nodes and children are popped from a small heap keyed by their smallest child index, so that every
/// child comes after all lower ones have been folded or skipped, and a node whose box bound leaves the
/// running value unchanged is skipped whole (the running value only falls). Past the heap's size, the
/// remaining children in order, each by its own box.
fn ordered_fold<S: Scalar, const FACES: bool>(
    children: &[Sdf],
    bvh: &ChildBvh,
    k: S,
    p: Vec3<S>,
    end: usize,
) -> S {
    let kp = k.primal();
    let q = primal(p);
    let mut d = children[0].eval_as::<S, FACES>(p);
    let mut heap = IndexHeap::default();
    let mut ok = bvh
        .always
        .iter()
        .filter(|&&i| (i as usize) < end)
        .all(|&i| heap.push(i, CHILD | i));
    if let Some(root) = bvh.nodes.first().filter(|r| (r.first as usize) < end) {
        ok &= heap.push(root.first, 0);
    }
    // The smallest child index not yet folded or skipped, once the heap has overflowed.
    let mut rest = (!ok).then_some(1);
    while rest.is_none() {
        let Some((key, item)) = heap.pop().filter(|&(key, _)| (key as usize) < end) else {
            break;
        };
        if item & CHILD != 0 {
            let i = (item & !CHILD) as usize;
            let (a, b) = bvh.boxes[i];
            d = fold_child::<S, FACES>(d, &children[i], lower(a, b, q), k, p);
            continue;
        }
        let node = &bvh.nodes[item as usize];
        if unchanged(lower(node.min, node.max, q), d.primal(), kp) {
            continue;
        }
        let fits = if node.leaf {
            let dp = d.primal();
            bvh.order[node.a as usize..(node.a + node.b) as usize]
                .iter()
                .filter(|&&i| {
                    let (a, b) = bvh.boxes[i as usize];
                    !unchanged(lower(a, b, q), dp, kp)
                })
                .all(|&i| heap.push(i, CHILD | i))
        } else {
            let (l, r) = (&bvh.nodes[node.a as usize], &bvh.nodes[node.b as usize]);
            heap.push(l.first, node.a) && heap.push(r.first, node.b)
        };
        if !fits {
            rest = Some(key as usize);
        }
    }
    // After an overflow: every child from `rest` on in order, each skipped by its own box only.
    let from = rest.unwrap_or(end);
    for (child, &(a, b)) in children[from..end].iter().zip(&bvh.boxes[from..end]) {
        d = fold_child::<S, FACES>(d, child, lower(a, b, q), k, p);
    }
    d
}

/// Marks a heap item as a child index (else it is a node index).
const CHILD: u32 = 1 << 31;

/// A fixed-size min-heap of `(key, item)` pairs with distinct keys, on the stack.
struct IndexHeap {
    entries: [u64; 64],
    len: usize,
}

impl Default for IndexHeap {
    fn default() -> Self {
        IndexHeap {
            entries: [0; 64],
            len: 0,
        }
    }
}

impl IndexHeap {
    /// Adds an entry; false (and nothing added) when full.
    #[inline]
    fn push(&mut self, key: u32, item: u32) -> bool {
        if self.len == self.entries.len() {
            return false;
        }
        let e = (u64::from(key) << 32) | u64::from(item);
        let mut at = self.len;
        self.len += 1;
        while at > 0 {
            let up = (at - 1) / 2;
            if self.entries[up] <= e {
                break;
            }
            self.entries[at] = self.entries[up];
            at = up;
        }
        self.entries[at] = e;
        true
    }

    /// Removes and returns the entry with the smallest key.
    #[inline]
    fn pop(&mut self) -> Option<(u32, u32)> {
        if self.len == 0 {
            return None;
        }
        let top = self.entries[0];
        self.len -= 1;
        let last = self.entries[self.len];
        let mut at = 0;
        loop {
            let mut down = 2 * at + 1;
            if down >= self.len {
                break;
            }
            if down + 1 < self.len && self.entries[down + 1] < self.entries[down] {
                down += 1;
            }
            if last <= self.entries[down] {
                break;
            }
            self.entries[at] = self.entries[down];
            at = down;
        }
        self.entries[at] = last;
        Some(((top >> 32) as u32, top as u32))
    }
}
