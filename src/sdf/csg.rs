//! Constructive solid geometry: hard union, intersection and difference (min / max), and the smooth union.
//!
//! Hard CSG branches on primal values: at the switching surface (`φ_a = φ_b`) the result has a crease
//! whose derivative the branch does not see; those creases need their own boundary terms (docs/theory.md §7,
//! "Creases"). The smooth union has none.

use super::Sdf;
use crate::math::{Aabb, Vec3};
use crate::scalar::Scalar;
use crate::scalar::interval::{Enclose, Enclosure, Interval};

/// How much [`smin`] can lower `min(a, b)`: `k/6`, reached at `a = b`.
pub(super) const SMIN_MAX_LOWERING: f32 = 1.0 / 6.0;

/// Cubic polynomial smooth minimum (Quílez, "smooth minimum", cubic variant):
/// `smin(a, b) = min(a, b) − k/6 · h³`, `h = max(k − |a − b|, 0)/k`.
///
/// Continuity: it equals `min` where `|a − b| ≥ k`. Writing `s = |a − b|`, `min = (a + b)/2 − s/2`, the
/// correction is `g(s) = s/2 + k/6 (1 − s/k)³`, with `g'(0) = 0` (so no kink at `a = b`) and
/// `g(k) = g'(k) − 1/2 = g''(k) = 0`: the result is C2 everywhere (C3 fails at `a = b` and `s = k`),
/// which the curvature needs. Its partial derivatives are `1 − (1 − s/k)²/2 ∈ [1/2, 1]` and its
/// complement, so the gradient is a convex combination of the children's gradients: the Lipschitz bound
/// of the children carries over. It is at most `k/6` below `min(a, b)` ([`SMIN_MAX_LOWERING`]).
/// With `k ≤ 0` it is the plain minimum.
#[inline(always)]
pub(super) fn smin<S: Scalar>(a: S, b: S, k: S) -> S {
    let kp = k.primal();
    let m = a.min(b);
    if kp.is_nan() || kp <= 0.0 {
        return m;
    }
    // Interval types take a tight enclosure of the same function: the branch on `s` below holds at the
    // midpoint only, and the formula's interval extension would not shrink where `a = b` in the box.
    if let Some(v) = S::enclosure(&SminEnclosure, [a, b, k]) {
        return v;
    }
    let s = (a - b).abs();
    if s.primal() >= kp {
        // Outside the blend: exactly the minimum (and its derivatives, all orders).
        return m;
    }
    let h = (k - s) / k;
    m - h * h * h * k * SMIN_MAX_LOWERING
}

/// [`smin`]'s formula for set-valued scalars ([`smin_enclosure`]); the arguments are `a`, `b` and `k`.
struct SminEnclosure;

impl Enclose<3> for SminEnclosure {
    #[inline]
    fn enclose<E: Enclosure>(&self, [a, b, k]: [E; 3]) -> E {
        smin_enclosure(a, b, k.value())
    }
}

/// Enclosure of the cubic smooth minimum [`smin`] with blend `k > 0` (a constant).
///
/// With `d = a − b`, `smin = min(a, b) − c k h³`, `h = max(1 − |d|/k, 0)`, `c` = `SMIN_MAX_LOWERING`, is
/// `(a + b)/2 − g(|d|)` with `g(x) = x/2 + c k max(1 − x/k, 0)³`, increasing on `x ≥ 0`, and
/// `∇smin = (∇a + ∇b)/2 − G(d)(∇a − ∇b)` with `G(d) = sign(d) g'(|d|)`, `g'(x) = 1/2 − 3c max(1 − x/k, 0)²`,
/// increasing in `d` (up to a jump of `|1/2 − 3c|` ≈ 1e-8 at 0 from the rounded `c`, covered by a
/// margin). Both monotone factors are enclosed exactly from the ends of `d`, so the enclosure shrinks with
/// the box even where `a = b` inside it (the naive extension hulls both branches of `|d|` and `min` there).
fn smin_enclosure<E: Enclosure>(a: E, b: E, k: Interval) -> E {
    let c = Interval::point(SMIN_MAX_LOWERING as f64);
    let half = Interval::point(0.5);
    let one = Interval::point(1.0);
    // (1 − x/k)₊ for a point x ≥ 0.
    let rest = |x: f64| (one - Interval::point(x) / k).imax(Interval::ZERO);
    let g = |x: f64| {
        let r = rest(x);
        Interval::point(x) * half + c * k * r * r * r
    };
    let gp = |x: f64| {
        let r = rest(x);
        half - Interval::point(3.0) * c * r.square()
    };
    let d = a - b;
    let dv = d.value();
    // Certainly outside the blend: exactly one child (no dependency between a + b and |d| to pay for).
    if dv.lo >= k.hi {
        return b;
    }
    if dv.hi <= -k.hi {
        return a;
    }
    let xlo = if dv.lo <= 0.0 && dv.hi >= 0.0 {
        0.0
    } else {
        dv.lo.abs().min(dv.hi.abs())
    };
    let xhi = dv.lo.abs().max(dv.hi.abs());
    let g_range = Interval::new(g(xlo).lo, g(xhi).hi);
    // G is odd and increasing: its range over [d.lo, d.hi] is [G(d.lo), G(d.hi)].
    let big_g = |x: f64| {
        let v = gp(x.abs());
        if x < 0.0 { -v } else { v }
    };
    let jump = (half - Interval::point(3.0) * c).iabs().hi;
    let g_slope = Interval::new(big_g(dv.lo).lo, big_g(dv.hi).hi).inflate(0.0, jump);
    let blend = E::compose(
        g_range,
        [g_slope, Interval::ZERO, Interval::ZERO],
        Vec3::new(d, E::zero(), E::zero()),
    );
    // The formula of `smin`, extended naturally, is sometimes tighter in value (one child dominating):
    // both enclose the same function.
    let kk = E::from_f64(k.mid());
    let h = (kk - d.abs()).max(E::zero()) / kk;
    let naive = a.min(b) - h * h * h * kk * SMIN_MAX_LOWERING;
    ((a + b) * 0.5 - blend).intersect(naive)
}

/// Union: the minimum of the children (`+∞`, the empty set, for no child).
#[inline(always)]
pub(super) fn union<S: Scalar, const FACES: bool>(children: &[Sdf], p: Vec3<S>) -> S {
    let mut it = children.iter();
    let Some(first) = it.next() else {
        return S::constant(f32::INFINITY);
    };
    let mut d = first.eval_as::<S, FACES>(p);
    for c in it {
        d = d.min(c.eval_as::<S, FACES>(p));
    }
    d
}

/// Intersection: the maximum of the children (`−∞`, the whole space, for no child).
#[inline(always)]
pub(super) fn intersection<S: Scalar, const FACES: bool>(children: &[Sdf], p: Vec3<S>) -> S {
    let mut it = children.iter();
    let Some(first) = it.next() else {
        return S::constant(f32::NEG_INFINITY);
    };
    let mut d = first.eval_as::<S, FACES>(p);
    for c in it {
        d = d.max(c.eval_as::<S, FACES>(p));
    }
    d
}

/// Difference: `max(φ_0, −φ_1, −φ_2, …)` (`+∞` for no child).
#[inline(always)]
pub(super) fn difference<S: Scalar, const FACES: bool>(children: &[Sdf], p: Vec3<S>) -> S {
    let mut it = children.iter();
    let Some(first) = it.next() else {
        return S::constant(f32::INFINITY);
    };
    let mut d = first.eval_as::<S, FACES>(p);
    for c in it {
        d = d.max(-c.eval_as::<S, FACES>(p));
    }
    d
}

/// Smooth union: [`smin`] folded left over the children (`+∞` for no child).
#[inline(always)]
pub(super) fn smooth_union<S: Scalar, const FACES: bool>(children: &[Sdf], k: S, p: Vec3<S>) -> S {
    let mut it = children.iter();
    let Some(first) = it.next() else {
        return S::constant(f32::INFINITY);
    };
    let mut d = first.eval_as::<S, FACES>(p);
    for c in it {
        d = smin(d, c.eval_as::<S, FACES>(p), k);
    }
    d
}

/// Box of a union: the union of the children's boxes.
pub(super) fn union_bounds(children: &[Sdf]) -> Aabb {
    children
        .iter()
        .fold(Aabb::EMPTY, |b, c| b.union(&c.bounds()))
}

/// Box of an intersection: the intersection of the children's boxes (the whole space for no child).
pub(super) fn intersection_bounds(children: &[Sdf]) -> Aabb {
    children
        .iter()
        .fold(Aabb::INFINITE, |b, c| b.intersection(&c.bounds()))
}

/// Box of a smooth union.
///
/// Folding [`smin`] over `n` children lowers the minimum by at most `(n − 1) k/6`, so `{φ ≤ 0}` lies in
/// `∪ {φ_i ≤ (n − 1) k/6}`. For exact distances that is each child's box grown by `(n − 1) k/6`; children
/// that under-estimate the distance to their box (hard intersections, whose per-axis argument loses up to
/// `√3` after a rotation) need more, so the box grows by `max(k, √3 (n − 1) k/6)`, i.e. by `k` for up to
/// four children.
pub(super) fn smooth_union_bounds(children: &[Sdf], k: f32) -> Aabb {
    let n = children.len().max(1) as f32;
    let k = k.max(0.0);
    let grow = k.max(3f32.sqrt() * (n - 1.0) * k * SMIN_MAX_LOWERING);
    let b = union_bounds(children);
    if b.is_empty() { b } else { b.expanded(grow) }
}

/// Largest Lipschitz bound of the children (min, max, negation and [`smin`] all keep it); 1 for none.
pub(super) fn max_lipschitz(children: &[Sdf]) -> f32 {
    children.iter().map(Sdf::lipschitz).fold(1.0, f32::max)
}

/// The declarations of the CSG nodes' fields ([`crate::declare`]).
pub(super) mod kinds {
    use crate::declare::{Field, Kind, Rule, Value, on};
    use crate::sdf::Sdf;

    /// A list of children of at least one node.
    const fn children(access: crate::declare::Access<Sdf, Vec<Sdf>>) -> Field<Sdf> {
        Field {
            key: "children",
            value: Value::Children {
                access,
                count: None,
            },
        }
    }

    /// The children of the examples: two overlapping spheres.
    macro_rules! two_spheres {
        () => {
            r#"[{"type": "sphere", "center": [0, 0.5, 0], "radius": 0.5},
                {"type": "sphere", "center": [0.4, 0.5, 0.1], "radius": 0.4}]"#
        };
    }

    /// `{"type": "union", "children": [...]}`: the minimum of the children.
    pub(in crate::sdf) const UNION: Kind<Sdf> = Kind {
        type_name: "union",
        fields: &[children(on!(Sdf::Union(c) => c))],
        blank: || Sdf::union(Vec::new()),
        example: concat!(r#"{"type": "union", "children": "#, two_spheres!(), "}"),
    };

    /// `{"type": "intersection", "children": [...]}`: the maximum of the children.
    pub(in crate::sdf) const INTERSECTION: Kind<Sdf> = Kind {
        type_name: "intersection",
        fields: &[children(on!(Sdf::Intersection(c) => c))],
        blank: || Sdf::intersection(Vec::new()),
        example: concat!(
            r#"{"type": "intersection", "children": "#,
            two_spheres!(),
            "}"
        ),
    };

    /// `{"type": "difference", "children": [...]}`: the first child minus the others.
    pub(in crate::sdf) const DIFFERENCE: Kind<Sdf> = Kind {
        type_name: "difference",
        fields: &[children(on!(Sdf::Difference(c) => c))],
        blank: || Sdf::difference(Vec::new()),
        example: concat!(
            r#"{"type": "difference", "children": "#,
            two_spheres!(),
            "}"
        ),
    };

    /// `{"type": "smooth_union", "children": [...], "k": blend radius}`.
    pub(in crate::sdf) const SMOOTH_UNION: Kind<Sdf> = Kind {
        type_name: "smooth_union",
        fields: &[
            children(on!(Sdf::SmoothUnion { children, .. } => children)),
            Field::number(
                "k",
                on!(Sdf::SmoothUnion { k, .. } => k),
                None,
                Rule::Positive,
            ),
        ],
        blank: || Sdf::smooth_union(Vec::new(), 0.0),
        example: concat!(
            r#"{"type": "smooth_union", "k": 0.2, "children": "#,
            two_spheres!(),
            "}"
        ),
    };
}
