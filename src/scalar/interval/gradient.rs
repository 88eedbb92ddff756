//! [`IntervalGrad`]: forward-mode AD on intervals with the three spatial directions.

use super::{Enclose, Interval, Scalar, Slot};
use crate::math::{Aabb, Vec3};
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// Forward-mode AD on intervals with the three spatial directions: `v` encloses the value and `g[k]` the
/// partial derivative along axis `k` (seeded by [`IntervalGrad::seed_box`]).
///
/// Each elementary function applies the chain rule with its local derivative enclosed over the argument's
/// interval, e.g. `sin: g' = g · cos(v)`; binary rules use the operands' intervals (the quotient rule as
/// `(g_a − (a/b) g_b)/b` with the enclosure of `a/b`). Piecewise functions whose branch is ambiguous over
/// the box return the union of the branches (notes of the [`interval`](super) module).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct IntervalGrad {
    /// Enclosure of the value.
    pub v: Interval,
    /// Enclosures of `∂/∂x`, `∂/∂y`, `∂/∂z`.
    pub g: [Interval; 3],
}

/// `g[k] · f` for each direction.
#[inline(always)]
fn scale(g: [Interval; 3], f: Interval) -> [Interval; 3] {
    [g[0] * f, g[1] * f, g[2] * f]
}

/// Component-wise hull.
#[inline(always)]
pub(super) fn hull3(a: [Interval; 3], b: [Interval; 3]) -> [Interval; 3] {
    [a[0].hull(b[0]), a[1].hull(b[1]), a[2].hull(b[2])]
}

impl IntervalGrad {
    /// A value without derivative.
    #[inline]
    pub fn from_interval(v: Interval) -> Self {
        Self {
            v,
            g: [Interval::ZERO; 3],
        }
    }
    /// The point of a box as AD variables: coordinate `k` ranges over the box's axis `k` with derivative
    /// `e_k`, so that evaluating `φ` on it gives enclosures of `φ(B)` and `∇φ(B)`.
    pub fn seed_box(b: &Aabb) -> Vec3<Self> {
        let c = |k: usize| {
            let mut g = [Interval::ZERO; 3];
            g[k] = Interval::point(1.0);
            Self {
                v: Interval::from_f32(b.min[k], b.max[k]),
                g,
            }
        };
        Vec3::new(c(0), c(1), c(2))
    }
    /// The gradient enclosures as a vector of intervals.
    pub fn gradient(&self) -> Vec3<Interval> {
        Vec3::new(self.g[0], self.g[1], self.g[2])
    }
    #[inline]
    fn chain(self, v: Interval, d: Interval) -> Self {
        Self {
            v,
            g: scale(self.g, d),
        }
    }
}

impl Neg for IntervalGrad {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self {
            v: -self.v,
            g: [-self.g[0], -self.g[1], -self.g[2]],
        }
    }
}

impl Add for IntervalGrad {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        Self {
            v: self.v + o.v,
            g: [self.g[0] + o.g[0], self.g[1] + o.g[1], self.g[2] + o.g[2]],
        }
    }
}

impl Sub for IntervalGrad {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        Self {
            v: self.v - o.v,
            g: [self.g[0] - o.g[0], self.g[1] - o.g[1], self.g[2] - o.g[2]],
        }
    }
}

// The product and quotient rules use `+` and `−` by design.
#[allow(clippy::suspicious_arithmetic_impl)]
impl Mul for IntervalGrad {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        Self {
            v: self.v * o.v,
            g: std::array::from_fn(|k| self.g[k] * o.v + self.v * o.g[k]),
        }
    }
}

// The product and quotient rules use `+` and `−` by design.
#[allow(clippy::suspicious_arithmetic_impl)]
impl Div for IntervalGrad {
    type Output = Self;
    #[inline]
    fn div(self, o: Self) -> Self {
        let q = self.v / o.v;
        Self {
            v: q,
            g: std::array::from_fn(|k| (self.g[k] - q * o.g[k]) / o.v),
        }
    }
}

scalar_ops!(IntervalGrad);

impl Scalar for IntervalGrad {
    const POINT: bool = false;
    /// Always the dedicated enclosure (see [`Enclose`]).
    #[inline]
    fn enclosure<F: Enclose<N>, const N: usize>(formula: &F, args: [Self; N]) -> Option<Self> {
        Some(formula.enclose(args))
    }
    #[inline]
    fn constant(v: f32) -> Self {
        Self::from_interval(Interval::constant(v))
    }
    /// The midpoint of the value (notes of the [`interval`](super) module).
    #[inline]
    fn primal(self) -> f32 {
        self.v.primal()
    }
    /// The value interval without derivatives.
    #[inline]
    fn detach(self) -> Self {
        Self::from_interval(self.v)
    }
    /// Scene parameters are constants: the directions are spatial.
    #[inline]
    fn lift(value: f32, _slot: Slot) -> Self {
        Self::constant(value)
    }
    /// `√x` with derivative `x'/(2√x)`, unbounded if the interval reaches 0.
    fn sqrt(self) -> Self {
        let v = self.v.isqrt();
        self.chain(v, Interval::point(0.5) / v)
    }
    fn exp(self) -> Self {
        let v = self.v.iexp();
        self.chain(v, v)
    }
    fn ln(self) -> Self {
        let v = self.v.iln();
        self.chain(v, Interval::point(1.0) / self.v)
    }
    fn sin(self) -> Self {
        self.chain(self.v.isin(), self.v.icos())
    }
    fn cos(self) -> Self {
        self.chain(self.v.icos(), -self.v.isin())
    }
    /// Partials `(x/r², −y/r²)`, `r² = x² + y²` (unbounded if the box holds the origin).
    fn atan2(self, x: Self) -> Self {
        let r2 = self.v.square() + x.v.square();
        let dy = x.v / r2;
        let dx = -self.v / r2;
        Self {
            v: self.v.iatan2(x.v),
            g: std::array::from_fn(|k| self.g[k] * dy + x.g[k] * dx),
        }
    }
    /// Derivative `−x'/√(1 − x²)` inside `(−1, 1)`, 0 at and beyond the clamp (hulled where the interval
    /// reaches it).
    fn acos(self) -> Self {
        let inner = (Interval::point(1.0) - self.v.square()).imax(Interval::ZERO);
        let mut d = -(Interval::point(1.0) / inner.isqrt());
        if self.v.lo <= -1.0 || self.v.hi >= 1.0 {
            d = d.hull(Interval::ZERO);
        }
        self.chain(self.v.iacos(), d)
    }
    fn powf(self, n: f32) -> Self {
        let d = self.v.ipowf(n - 1.0) * Interval::point(n as f64);
        self.chain(self.v.ipowf(n), d)
    }
    #[inline]
    fn abs(self) -> Self {
        if self.v.lo > 0.0 {
            self
        } else if self.v.hi < 0.0 {
            -self
        } else {
            Self {
                v: self.v.iabs(),
                g: hull3(self.g, (-self).g),
            }
        }
    }
    #[inline]
    fn max(self, o: Self) -> Self {
        if self.v.hi < o.v.lo {
            o
        } else if o.v.hi < self.v.lo {
            self
        } else {
            Self {
                v: self.v.imax(o.v),
                g: hull3(self.g, o.g),
            }
        }
    }
    #[inline]
    fn min(self, o: Self) -> Self {
        if self.v.lo > o.v.hi {
            o
        } else if o.v.lo > self.v.hi {
            self
        } else {
            Self {
                v: self.v.imin(o.v),
                g: hull3(self.g, o.g),
            }
        }
    }
    #[inline]
    fn clamp(self, lo: f32, hi: f32) -> Self {
        self.max(Self::constant(lo)).min(Self::constant(hi))
    }
    /// `√max(x, 0)`; derivative 0 where `x ≤ 0`, so `[0, ∞)·x'` if the interval straddles 0.
    #[inline]
    fn safe_sqrt(self) -> Self {
        if self.v.hi <= 0.0 {
            Self::zero()
        } else if self.v.lo > 0.0 {
            self.sqrt()
        } else {
            self.chain(self.v.isqrt(), Interval::new(0.0, f64::INFINITY))
        }
    }
    #[inline]
    fn sqr(self) -> Self {
        self.chain(self.v.square(), self.v * Interval::point(2.0))
    }
}
