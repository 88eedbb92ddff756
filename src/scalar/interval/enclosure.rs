//! What code specialised to interval types needs on top of [`Scalar`]: the [`Enclosure`] operations, and
//! [`Enclose`], a formula with a dedicated enclosure that [`Scalar::enclosure`] runs for set-valued types.

use super::gradient::hull3;
use super::{Interval, IntervalGrad};
use crate::math::Vec3;
use crate::scalar::Scalar;

/// What the grid path needs from an interval scalar on top of [`Scalar`]: implemented by [`Interval`] and
/// [`IntervalGrad`].
pub trait Enclosure: Scalar {
    /// True if the type carries derivatives (so the grid path computes partial enclosures).
    const GRADIENT: bool;
    /// The enclosure of the value.
    fn value(self) -> Interval;
    /// Component-wise [`Interval::intersect`] of two enclosures of the same quantity.
    fn intersect(self, o: Self) -> Self;
    /// Every interval grown by `rel · magnitude + abs` ([`Interval::inflate`]).
    fn inflate(self, rel: f64, abs: f64) -> Self;
    /// The enclosure of `f(q)` from an enclosure `value` of `f` and `partials[a]` of `∂f/∂q_a` over the
    /// range of `q`: the derivative follows `q`'s by the chain rule, `Σ_a ∂f/∂q_a · q_a'`.
    fn compose(value: Interval, partials: [Interval; 3], q: Vec3<Self>) -> Self;
    /// An `f64` constant (kept in `f64`: [`Scalar::constant`] takes an `f32`).
    fn from_f64(v: f64) -> Self;
    /// Component-wise [`Interval::hull`].
    fn hull(self, o: Self) -> Self;
    /// The same number known to lie in `range` as well: the value is intersected, the derivatives kept (they
    /// enclose the derivative over a larger set, hence over the smaller one).
    fn restrict(self, range: Interval) -> Self;
}

impl Enclosure for Interval {
    const GRADIENT: bool = false;
    #[inline]
    fn value(self) -> Interval {
        self
    }
    #[inline]
    fn intersect(self, o: Self) -> Self {
        Interval::intersect(self, o)
    }
    #[inline]
    fn inflate(self, rel: f64, abs: f64) -> Self {
        Interval::inflate(self, rel, abs)
    }
    #[inline]
    fn compose(value: Interval, _partials: [Interval; 3], _q: Vec3<Self>) -> Self {
        value
    }
    #[inline]
    fn from_f64(v: f64) -> Self {
        Interval::point(v)
    }
    #[inline]
    fn hull(self, o: Self) -> Self {
        Interval::hull(self, o)
    }
    #[inline]
    fn restrict(self, range: Interval) -> Self {
        Interval::intersect(self, range)
    }
}

impl Enclosure for IntervalGrad {
    const GRADIENT: bool = true;
    #[inline]
    fn value(self) -> Interval {
        self.v
    }
    fn intersect(self, o: Self) -> Self {
        Self {
            v: self.v.intersect(o.v),
            g: std::array::from_fn(|k| self.g[k].intersect(o.g[k])),
        }
    }
    fn inflate(self, rel: f64, abs: f64) -> Self {
        Self {
            v: self.v.inflate(rel, abs),
            g: self.g.map(|g| g.inflate(rel, abs)),
        }
    }
    fn compose(value: Interval, partials: [Interval; 3], q: Vec3<Self>) -> Self {
        let qs = [q.x, q.y, q.z];
        Self {
            v: value,
            g: std::array::from_fn(|k| {
                (0..3).fold(Interval::ZERO, |acc, a| acc + partials[a] * qs[a].g[k])
            }),
        }
    }
    #[inline]
    fn from_f64(v: f64) -> Self {
        Self::from_interval(Interval::point(v))
    }
    fn hull(self, o: Self) -> Self {
        Self {
            v: self.v.hull(o.v),
            g: hull3(self.g, o.g),
        }
    }
    #[inline]
    fn restrict(self, range: Interval) -> Self {
        Self {
            v: self.v.intersect(range),
            g: self.g,
        }
    }
}

/// A formula of `N` scalars with a dedicated enclosure for set-valued types.
///
/// Generic code branches on [`Scalar::primal`]; for an interval that is the midpoint, and a branch taken
/// there need not hold over the whole set (the smooth minimum's exit outside the blend, a grid's choice of
/// cell). Such code asks [`Scalar::enclosure`] first: the interval types answer with [`Enclose::enclose`],
/// the point types with `None`, and then run the point formula.
pub trait Enclose<const N: usize> {
    /// An enclosure of the formula over every point of the sets `args`.
    fn enclose<E: Enclosure>(&self, args: [E; N]) -> E;
}
