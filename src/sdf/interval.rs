//! Interval arithmetic over boxes: certified enclosures of `φ(B)` and `∇φ(B)` for culling.
//!
//! [`Interval`] is a closed interval of reals held in `f64` with outward rounding (every endpoint computed by
//! a rounded operation is stepped one ulp outward, two for the transcendental functions, whose libm results
//! are within one ulp), so an enclosure holds the exact real value of the node formulas evaluated at the
//! `f32` parameters. [`IntervalGrad`] is forward-mode AD on intervals with the three spatial directions: its
//! value and its derivatives are intervals, so one pass over a box gives enclosures of `φ(B)` and of every
//! component of `∇φ(B)`.
//!
//! Both implement [`Scalar`], so the generic [`Sdf::eval`] runs on them unchanged. What makes that sound:
//! - `abs`, `max`, `min`, `clamp` and `safe_sqrt` are overridden by true interval operations. Where the
//!   branch of a piecewise function is ambiguous over the box, the value is the union of both branches' and
//!   the derivative the hull of both branches' derivatives (a superset of the Clarke generalised gradient,
//!   so it holds every gradient where one exists).
//! - `primal()` returns the midpoint. It is only used for branching, and the node code that branches on a
//!   value that depends on the point has been made sound: the smooth minimum (its early exit outside the
//!   blend) and grids (which cell, inside the grid box or not: a box can span several cells and faces)
//!   hand interval types to dedicated enclosures here (`smin_dispatch`, `grid_dispatch`; a `TypeId` test
//!   that folds to a constant, so `f32` and the duals run exactly the code they ran before). The other
//!   primal branches in `src/sdf` test parameters only (the capsule's `|b − a|² > 0`, a transform's angle
//!   and scale), which are exact constants here.
//! - `detach` keeps the interval (the default would collapse it to the midpoint).
//!
//! Grids: over a box spanning several cells the spline is enclosed by its control points (B-splines are
//! convex combinations of them; the partial `∂_a φ` likewise of the differences `(c_{i+1} − c_i)/h_a`,
//! see `grid.rs`): loose, a few cells wide. A box touching at most 3 cells per axis is also bounded cell by
//! cell by the Bernstein coefficients of each cell's tricubic over the part of the box in it (blossoming;
//! computed in `f64` with a rigorous rounding margin), which converge as `O(w²)` in the box width `w`; the
//! pieces are hulled and intersected with the control-point bound.
//!
//! Singular derivatives become unbounded rather than wrong: `safe_sqrt` of an interval touching 0 has a
//! derivative enclosure `[0, ∞)·x'`, e.g. the gradient of `|p − c|` over a box holding `c`.

use super::{GridData, Sdf};
use crate::math::{Aabb, Vec3};
use crate::scalar::{Scalar, Slot};
use std::any::{Any, TypeId};
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

// ---------------------------------------------------------------------------------------------------------
// Rounding

/// Lower end of a rounded result: one ulp down, except for an exact zero (a sum, quotient or square root
/// that is 0 is exact; products guard their own zeros) and NaN, which widens to `−∞`.
#[inline(always)]
fn dn(x: f64) -> f64 {
    if x == 0.0 {
        0.0
    } else if x.is_nan() {
        f64::NEG_INFINITY
    } else {
        x.next_down()
    }
}

/// Upper end of a rounded result (see [`dn`]).
#[inline(always)]
fn up(x: f64) -> f64 {
    if x == 0.0 {
        0.0
    } else if x.is_nan() {
        f64::INFINITY
    } else {
        x.next_up()
    }
}

/// Two ulps down, for libm results (within one ulp of the exact value).
#[inline(always)]
fn dn2(x: f64) -> f64 {
    if x.is_nan() {
        f64::NEG_INFINITY
    } else {
        x.next_down().next_down()
    }
}

/// Two ulps up, for libm results.
#[inline(always)]
fn up2(x: f64) -> f64 {
    if x.is_nan() {
        f64::INFINITY
    } else {
        x.next_up().next_up()
    }
}

/// Bounds of the product of two endpoints: `0 · x = 0` exactly (also for infinite `x`, the convention of
/// interval arithmetic), otherwise the rounded product widened one ulp (which also covers underflow).
#[inline(always)]
fn emul(a: f64, b: f64) -> (f64, f64) {
    if a == 0.0 || b == 0.0 {
        (0.0, 0.0)
    } else {
        let p = a * b;
        if p.is_nan() {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            (p.next_down(), p.next_up())
        }
    }
}

// ---------------------------------------------------------------------------------------------------------
// Interval

/// A closed interval `[lo, hi]` of reals (`lo ≤ hi`; infinite ends allowed), with outward-rounded arithmetic.
///
/// As a [`Scalar`] it stands for "some value in the interval": operations return enclosures of every
/// result, `primal()` is the midpoint (used only for branching, see the module notes).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Interval {
    /// Lower end.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
}

impl Interval {
    /// The whole real line.
    pub const ENTIRE: Self = Self {
        lo: f64::NEG_INFINITY,
        hi: f64::INFINITY,
    };
    /// `[0, 0]`.
    pub const ZERO: Self = Self { lo: 0.0, hi: 0.0 };

    /// `[lo, hi]` (the ends are taken as given; swap them yourself if needed). NaN ends widen to infinite.
    #[inline]
    pub fn new(lo: f64, hi: f64) -> Self {
        Self {
            lo: if lo.is_nan() { f64::NEG_INFINITY } else { lo },
            hi: if hi.is_nan() { f64::INFINITY } else { hi },
        }
    }
    /// The single point `v`.
    #[inline]
    pub fn point(v: f64) -> Self {
        Self::new(v, v)
    }
    /// True if `v` lies in the interval.
    #[inline]
    pub fn contains(&self, v: f64) -> bool {
        self.lo <= v && v <= self.hi
    }
    /// True if 0 lies in the interval.
    #[inline]
    pub fn contains_zero(&self) -> bool {
        self.contains(0.0)
    }
    /// `hi − lo` (rounded up).
    #[inline]
    pub fn width(&self) -> f64 {
        up(self.hi - self.lo)
    }
    /// Midpoint; a finite end if the other is infinite, 0 for the whole line.
    #[inline]
    pub fn mid(&self) -> f64 {
        match (self.lo.is_finite(), self.hi.is_finite()) {
            (true, true) => 0.5 * self.lo + 0.5 * self.hi,
            (true, false) => self.lo,
            (false, true) => self.hi,
            (false, false) => 0.0,
        }
    }
    /// Smallest interval holding both.
    #[inline]
    pub fn hull(self, o: Self) -> Self {
        Self {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
        }
    }
    /// The common part of two enclosures of the same quantity. Two sound enclosures always meet; if rounding
    /// of different formulas makes them miss by a hair, the hull is returned (never lose a value).
    #[inline]
    pub fn intersect(self, o: Self) -> Self {
        let r = Self {
            lo: self.lo.max(o.lo),
            hi: self.hi.min(o.hi),
        };
        if r.lo <= r.hi { r } else { self.hull(o) }
    }
    /// Grown on both sides by `rel · max(|lo|, |hi|) + abs`.
    #[inline]
    pub fn inflate(self, rel: f64, abs: f64) -> Self {
        let m = rel * self.lo.abs().max(self.hi.abs()) + abs;
        Self::new(dn(self.lo - m), up(self.hi + m))
    }
    /// The interval `[min, max]` of an `f32` box's axis.
    #[inline]
    pub fn from_f32(lo: f32, hi: f32) -> Self {
        Self::new(lo as f64, hi as f64)
    }
    /// `{x² : x ∈ self}` (tighter than `self * self`, which treats the factors as independent).
    #[inline]
    pub fn square(self) -> Self {
        let a = if self.lo >= 0.0 {
            self
        } else if self.hi <= 0.0 {
            -self
        } else {
            let m = (-self.lo).max(self.hi);
            return Self::new(0.0, emul(m, m).1);
        };
        Self::new(emul(a.lo, a.lo).0.max(0.0), emul(a.hi, a.hi).1)
    }
    /// `{|x| : x ∈ self}`.
    #[inline]
    pub fn iabs(self) -> Self {
        if self.lo >= 0.0 {
            self
        } else if self.hi <= 0.0 {
            -self
        } else {
            Self::new(0.0, (-self.lo).max(self.hi))
        }
    }
    /// `{max(x, y)}` over independent `x ∈ self`, `y ∈ o`.
    #[inline]
    pub fn imax(self, o: Self) -> Self {
        Self::new(self.lo.max(o.lo), self.hi.max(o.hi))
    }
    /// `{min(x, y)}` over independent `x ∈ self`, `y ∈ o`.
    #[inline]
    pub fn imin(self, o: Self) -> Self {
        Self::new(self.lo.min(o.lo), self.hi.min(o.hi))
    }
    /// `{√x : x ∈ self, x ≥ 0}` (negative parts are outside the domain and dropped; `[0, 0]` if none is left).
    #[inline]
    pub fn isqrt(self) -> Self {
        let lo = self.lo.max(0.0);
        let hi = self.hi.max(0.0);
        Self::new(dn(lo.sqrt()).max(0.0), up(hi.sqrt()))
    }
    /// `{sin x}`.
    pub fn isin(self) -> Self {
        periodic(self, f64::sin, FRAC_PI_2, -FRAC_PI_2)
    }
    /// `{cos x}`.
    pub fn icos(self) -> Self {
        periodic(self, f64::cos, 0.0, PI)
    }
    /// `{eˣ}`.
    pub fn iexp(self) -> Self {
        Self::new(dn2(self.lo.exp()).max(0.0), up2(self.hi.exp()))
    }
    /// `{ln x : x > 0}` (`−∞` where the interval reaches 0 or below).
    pub fn iln(self) -> Self {
        let lo = if self.lo <= 0.0 {
            f64::NEG_INFINITY
        } else {
            dn2(self.lo.ln())
        };
        let hi = if self.hi <= 0.0 {
            f64::NEG_INFINITY
        } else {
            up2(self.hi.ln())
        };
        Self::new(lo, hi)
    }
    /// `{atan2(y, x)}` for `y ∈ self`, `x ∈ x`: the extreme angles of a box that neither holds the origin
    /// nor meets the branch cut (the negative x axis) are at its corners (the angle subtended by a convex set
    /// away from the origin); otherwise `[−π, π]`.
    pub fn iatan2(self, x: Self) -> Self {
        let full = Self::new(-PI.next_up(), PI.next_up());
        let straddles_y = self.lo <= 0.0 && self.hi >= 0.0;
        if straddles_y && x.lo <= 0.0 {
            return full;
        }
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for y in [self.lo, self.hi] {
            for xx in [x.lo, x.hi] {
                let a = y.atan2(xx);
                lo = lo.min(a);
                hi = hi.max(a);
            }
        }
        Self::new(dn2(lo), up2(hi)).intersect(full)
    }
    /// `{acos x}` with `x` clamped to `[−1, 1]` (as every [`Scalar::acos`]).
    pub fn iacos(self) -> Self {
        let lo = self.lo.clamp(-1.0, 1.0);
        let hi = self.hi.clamp(-1.0, 1.0);
        Self::new(dn2(hi.acos()).max(0.0), up2(lo.acos()))
    }
    /// `{xⁿ}` for a constant `n`: monotone on `x ≥ 0`; an interval reaching below 0 gives the whole line
    /// unless `n = 0` (the `f32` `powf` of a negative base is NaN for a non-integer `n`).
    pub fn ipowf(self, n: f32) -> Self {
        let n = n as f64;
        if n == 0.0 {
            return Self::point(1.0);
        }
        if self.lo < 0.0 {
            return Self::ENTIRE;
        }
        let a = self.lo.powf(n);
        let b = self.hi.powf(n);
        Self::new(dn2(a.min(b)).max(0.0), up2(a.max(b)))
    }
}

/// Range of a 2π-periodic `f` with maximum 1 at `phase_max + 2πk` and minimum −1 at `phase_min + 2πk`:
/// the endpoint values, widened to ±1 when an extremum may lie inside (tested with a slack, so rounding of
/// `2πk` can only widen).
fn periodic(x: Interval, f: fn(f64) -> f64, phase_max: f64, phase_min: f64) -> Interval {
    let unit = Interval::new(-1.0, 1.0);
    if !(x.lo.is_finite() && x.hi.is_finite()) || x.hi - x.lo >= TAU {
        return unit;
    }
    let (a, b) = (f(x.lo), f(x.hi));
    let mut lo = dn2(a.min(b));
    let mut hi = up2(a.max(b));
    let slack = 1e-12 * (1.0 + x.lo.abs().max(x.hi.abs()));
    let hits = |phase: f64| {
        let k0 = ((x.lo - phase) / TAU).floor();
        (-1..=2).any(|j| {
            let p = phase + TAU * (k0 + j as f64);
            p >= x.lo - slack && p <= x.hi + slack
        })
    };
    if hits(phase_max) {
        hi = 1.0;
    }
    if hits(phase_min) {
        lo = -1.0;
    }
    Interval::new(lo.max(-1.0), hi.min(1.0))
}

impl Neg for Interval {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Self {
            lo: -self.hi,
            hi: -self.lo,
        }
    }
}

impl Add for Interval {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        Self::new(dn(self.lo + o.lo), up(self.hi + o.hi))
    }
}

impl Sub for Interval {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        Self::new(dn(self.lo - o.hi), up(self.hi - o.lo))
    }
}

impl Mul for Interval {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        let p = [
            emul(self.lo, o.lo),
            emul(self.lo, o.hi),
            emul(self.hi, o.lo),
            emul(self.hi, o.hi),
        ];
        Self::new(
            p.iter().fold(f64::INFINITY, |m, v| m.min(v.0)),
            p.iter().fold(f64::NEG_INFINITY, |m, v| m.max(v.1)),
        )
    }
}

impl Div for Interval {
    type Output = Self;
    /// Quotient; a divisor holding 0 gives the whole line.
    #[inline]
    fn div(self, o: Self) -> Self {
        if o.lo <= 0.0 && o.hi >= 0.0 {
            return Self::ENTIRE;
        }
        let q = [
            self.lo / o.lo,
            self.lo / o.hi,
            self.hi / o.lo,
            self.hi / o.hi,
        ];
        if q.iter().any(|v| v.is_nan()) {
            return Self::ENTIRE;
        }
        Self::new(
            dn(q.iter().fold(f64::INFINITY, |m, &v| m.min(v))),
            up(q.iter().fold(f64::NEG_INFINITY, |m, &v| m.max(v))),
        )
    }
}

/// `+`, `−`, `×`, `÷` with an `f32` constant and the assigning forms, for any type with the
/// interval-interval operations and `constant`.
macro_rules! scalar_ops {
    ($t:ty) => {
        impl Add<f32> for $t {
            type Output = Self;
            #[inline]
            fn add(self, o: f32) -> Self {
                self + <$t as Scalar>::constant(o)
            }
        }
        impl Sub<f32> for $t {
            type Output = Self;
            #[inline]
            fn sub(self, o: f32) -> Self {
                self - <$t as Scalar>::constant(o)
            }
        }
        impl Mul<f32> for $t {
            type Output = Self;
            #[inline]
            fn mul(self, o: f32) -> Self {
                self * <$t as Scalar>::constant(o)
            }
        }
        impl Div<f32> for $t {
            type Output = Self;
            #[inline]
            fn div(self, o: f32) -> Self {
                self / <$t as Scalar>::constant(o)
            }
        }
        impl AddAssign for $t {
            #[inline]
            fn add_assign(&mut self, o: Self) {
                *self = *self + o;
            }
        }
        impl SubAssign for $t {
            #[inline]
            fn sub_assign(&mut self, o: Self) {
                *self = *self - o;
            }
        }
        impl MulAssign for $t {
            #[inline]
            fn mul_assign(&mut self, o: Self) {
                *self = *self * o;
            }
        }
        impl DivAssign for $t {
            #[inline]
            fn div_assign(&mut self, o: Self) {
                *self = *self / o;
            }
        }
    };
}

scalar_ops!(Interval);
scalar_ops!(IntervalGrad);

impl Scalar for Interval {
    #[inline]
    fn constant(v: f32) -> Self {
        Self::point(v as f64)
    }
    /// The midpoint (see the module notes: only branches read it, and those have been made sound).
    #[inline]
    fn primal(self) -> f32 {
        self.mid() as f32
    }
    #[inline]
    fn detach(self) -> Self {
        self
    }
    #[inline]
    fn lift(value: f32, _slot: Slot) -> Self {
        Self::constant(value)
    }
    /// Square root on the domain part (`x ≥ 0`) of the interval.
    #[inline]
    fn sqrt(self) -> Self {
        self.isqrt()
    }
    fn exp(self) -> Self {
        self.iexp()
    }
    fn ln(self) -> Self {
        self.iln()
    }
    fn sin(self) -> Self {
        self.isin()
    }
    fn cos(self) -> Self {
        self.icos()
    }
    fn atan2(self, x: Self) -> Self {
        self.iatan2(x)
    }
    fn acos(self) -> Self {
        self.iacos()
    }
    fn powf(self, n: f32) -> Self {
        self.ipowf(n)
    }
    #[inline]
    fn abs(self) -> Self {
        self.iabs()
    }
    #[inline]
    fn max(self, o: Self) -> Self {
        self.imax(o)
    }
    #[inline]
    fn min(self, o: Self) -> Self {
        self.imin(o)
    }
    #[inline]
    fn clamp(self, lo: f32, hi: f32) -> Self {
        self.imax(Self::constant(lo)).imin(Self::constant(hi))
    }
    #[inline]
    fn safe_sqrt(self) -> Self {
        self.isqrt()
    }
    #[inline]
    fn sqr(self) -> Self {
        self.square()
    }
}

// ---------------------------------------------------------------------------------------------------------
// IntervalGrad

/// Forward-mode AD on intervals with the three spatial directions: `v` encloses the value and `g[k]` the
/// partial derivative along axis `k` (seeded by [`IntervalGrad::seed_box`]).
///
/// Each elementary function applies the chain rule with its local derivative enclosed over the argument's
/// interval, e.g. `sin: g' = g · cos(v)`; binary rules use the operands' intervals (the quotient rule as
/// `(g_a − (a/b) g_b)/b` with the enclosure of `a/b`). Piecewise functions whose branch is ambiguous over
/// the box return the union of the branches (module notes).
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
fn hull3(a: [Interval; 3], b: [Interval; 3]) -> [Interval; 3] {
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

impl Scalar for IntervalGrad {
    #[inline]
    fn constant(v: f32) -> Self {
        Self::from_interval(Interval::constant(v))
    }
    /// The midpoint of the value (module notes).
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

// ---------------------------------------------------------------------------------------------------------
// Enclosure types

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

/// True if `S` is one of the interval types. `TypeId`s of concrete types are constants, so for `f32` and
/// the duals this folds to `false` and the callers' fast paths are untouched.
#[inline(always)]
pub(super) fn is_enclosure<S: 'static>() -> bool {
    let t = TypeId::of::<S>();
    t == TypeId::of::<Interval>() || t == TypeId::of::<IntervalGrad>()
}

/// The grid node's evaluation when `S` is an interval type ([`grid_enclosure`]), `None` for every other
/// scalar type (a compile-time constant branch, see [`is_enclosure`]).
#[inline(always)]
pub(super) fn grid_dispatch<S: Scalar>(
    data: &GridData,
    bmin: glam::Vec3,
    bmax: glam::Vec3,
    p: Vec3<S>,
) -> Option<S> {
    if !is_enclosure::<S>() {
        return None;
    }
    let mut out: Option<S> = None;
    let slot = &mut out as &mut dyn Any;
    let p = &p as &dyn Any;
    if let (Some(p), Some(o)) = (
        p.downcast_ref::<Vec3<Interval>>(),
        slot.downcast_mut::<Option<Interval>>(),
    ) {
        *o = Some(grid_enclosure(data, bmin, bmax, *p));
    } else if let (Some(p), Some(o)) = (
        p.downcast_ref::<Vec3<IntervalGrad>>(),
        slot.downcast_mut::<Option<IntervalGrad>>(),
    ) {
        *o = Some(grid_enclosure(data, bmin, bmax, *p));
    }
    out
}

/// The control point at extended lattice index `(x, y, z)` (each in `−1..=n`), in `f64`: ghost layers by
/// linear extrapolation as in `grid.rs` (exact in `f64` for `f32` samples of ordinary magnitude).
fn ext64(data: &GridData, x: isize, y: isize, z: isize) -> f64 {
    let [nx, ny, nz] = data.dims.map(|n| n as isize);
    let fold = |i: isize, n: isize| -> Option<(isize, isize)> {
        if i < 0 {
            Some((0, 1))
        } else if i >= n {
            Some((n - 1, n - 2))
        } else {
            None
        }
    };
    if let Some((a, b)) = fold(x, nx) {
        return 2.0 * ext64(data, a, y, z) - ext64(data, b, y, z);
    }
    if let Some((a, b)) = fold(y, ny) {
        return 2.0 * ext64(data, x, a, z) - ext64(data, x, b, z);
    }
    if let Some((a, b)) = fold(z, nz) {
        return 2.0 * ext64(data, x, y, a) - ext64(data, x, y, b);
    }
    data.values[((z * ny + y) * nx + x) as usize] as f64
}

/// Enclosure of a grid node over the box `p` (module notes): `φ = spline(clamp(p)) + |p − clamp(p)|`,
/// valid inside and outside the grid box, with `p − clamp(p) = max(p − bmax, 0) + min(p − bmin, 0)` (exactly
/// 0 where the box is certainly inside, so the distance term adds nothing there).
pub(super) fn grid_enclosure<E: Enclosure>(
    data: &GridData,
    bmin: glam::Vec3,
    bmax: glam::Vec3,
    p: Vec3<E>,
) -> E {
    if !data.usable() {
        return E::constant(f32::INFINITY);
    }
    let q = Vec3::new(
        p.x.clamp(bmin.x, bmax.x),
        p.y.clamp(bmin.y, bmax.y),
        p.z.clamp(bmin.z, bmax.z),
    );
    let off = |c: E, lo: f32, hi: f32| (c - hi).max(E::zero()) + (c - lo).min(E::zero());
    let d = Vec3::new(
        off(p.x, bmin.x, bmax.x),
        off(p.y, bmin.y, bmax.y),
        off(p.z, bmin.z, bmax.z),
    );
    spline_enclosure(data, bmin, bmax, q) + d.length()
}

/// Enclosure of the B-spline over the box `q` (inside the grid box): the control-point hull, intersected
/// with the per-cell Bernstein bounds when the box touches at most [`MAX_CELL_PIECES`] cells (module notes).
fn spline_enclosure<E: Enclosure>(
    data: &GridData,
    bmin: glam::Vec3,
    bmax: glam::Vec3,
    q: Vec3<E>,
) -> E {
    let ext = bmax - bmin;
    let qs = [q.x, q.y, q.z];
    // Lattice coordinate u = (q − bmin)·inv_h with the same f32 inv_h as `grid.rs`.
    let mut inv_h = [0.0f32; 3];
    let mut cells = [(0isize, 0isize); 3];
    for a in 0..3 {
        let n = data.dims[a];
        inv_h[a] = if ext[a] > 0.0 {
            (n - 1) as f32 / ext[a]
        } else {
            0.0
        };
        let u = (qs[a].value() - Interval::constant(bmin[a])) * Interval::constant(inv_h[a]);
        let cell = |x: f64| {
            if x.is_nan() {
                0
            } else {
                (x.floor().clamp(0.0, (n - 2) as f64)) as isize
            }
        };
        cells[a] = (cell(u.lo), cell(u.hi));
    }
    // Control points (and their differences) of every cell the box touches: taps i − 1 ..= i + 2.
    let lo = cells.map(|c| c.0 - 1);
    let hi = cells.map(|c| c.1 + 2);
    let size = [0, 1, 2].map(|a| (hi[a] - lo[a] + 1) as usize);
    let mut block = Vec::with_capacity(size[0] * size[1] * size[2]);
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                block.push(ext64(data, x, y, z));
            }
        }
    }
    let at = |x: usize, y: usize, z: usize| block[(z * size[1] + y) * size[0] + x];
    let (mut vmin, mut vmax) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut dmin = [f64::INFINITY; 3];
    let mut dmax = [f64::NEG_INFINITY; 3];
    for z in 0..size[2] {
        for y in 0..size[1] {
            for x in 0..size[0] {
                let c = at(x, y, z);
                vmin = vmin.min(c);
                vmax = vmax.max(c);
                let step = [(x + 1, y, z), (x, y + 1, z), (x, y, z + 1)];
                for (a, &(i, j, k)) in step.iter().enumerate() {
                    if i < size[0] && j < size[1] && k < size[2] {
                        let dlt = at(i, j, k) - c;
                        dmin[a] = dmin[a].min(dlt);
                        dmax[a] = dmax[a].max(dlt);
                    }
                }
            }
        }
    }
    // Ghost points and differences are exact in f64 up to a few ulps: grow by a relative hair.
    let value = Interval::new(vmin, vmax).inflate(1e-12, 0.0);
    let partials: [Interval; 3] = std::array::from_fn(|a| {
        Interval::new(dmin[a], dmax[a]).inflate(1e-12, 0.0) * Interval::constant(inv_h[a])
    });
    let hull = E::compose(value, partials, q);
    let pieces: isize = cells.iter().map(|c| c.1 - c.0 + 1).product();
    if pieces > MAX_CELL_PIECES {
        return hull;
    }
    // Each cell the box touches: the Bernstein form of the cell's tricubic over the part of the box in the
    // cell, whose coefficients bound the value and, differenced, the partials (convergence O(w²) in the
    // box width w, where the control-point hull stays a few cells wide).
    let mut out: Option<E> = None;
    for cz in cells[2].0..=cells[2].1 {
        for cy in cells[1].0..=cells[1].1 {
            for cx in cells[0].0..=cells[0].1 {
                let cell = [cx, cy, cz];
                let rows: [_; 3] = std::array::from_fn(|a| {
                    let t = (qs[a].value() - Interval::constant(bmin[a]))
                        * Interval::constant(inv_h[a])
                        - Interval::point(cell[a] as f64);
                    let t = t.intersect(Interval::new(0.0, 1.0));
                    bernstein_rows(t.lo, t.hi)
                });
                // The cell's 4 × 4 × 4 control values (taps i − 1 ..= i + 2, at block offset i − 1 − lo).
                let o = [0, 1, 2].map(|a| (cell[a] - 1 - lo[a]) as usize);
                let mut c = [0.0f64; 64];
                let mut cmax = 0.0f64;
                for z in 0..4 {
                    for y in 0..4 {
                        for x in 0..4 {
                            let v = at(o[0] + x, o[1] + y, o[2] + z);
                            c[(z * 4 + y) * 4 + x] = v;
                            cmax = cmax.max(v.abs());
                        }
                    }
                }
                // Rounding of the f64 transform: each coefficient is a sum of 64 products of three row
                // entries and a control value, Σ|terms| ≤ 6 max|c| (value rows are convex, derivative rows
                // sum to at most 6 in absolute value), about 25 roundings deep: error ≤ 25 · 2⁻⁵³ · 6 max|c|
                // ≈ 2e-14 max|c|. The margin is 50 times that.
                let margin = 1e-12 * cmax;
                let (m, d) = (rows.map(|r| r.0), rows.map(|r| r.1));
                let zy = apply(&apply(&c, [4, 4, 4], 2, &m[2]), [4, 4, 4], 1, &m[1]);
                let v = range(&apply(&zy, [4, 4, 4], 0, &m[0]), [4, 4, 4], margin);
                let partials: [Interval; 3] = if E::GRADIENT {
                    let zx = apply(&apply(&c, [4, 4, 4], 2, &m[2]), [4, 4, 4], 0, &m[0]);
                    let yx = apply(&apply(&c, [4, 4, 4], 1, &m[1]), [4, 4, 4], 0, &m[0]);
                    let d = [
                        range(&apply(&zy, [4, 4, 4], 0, &d[0]), [3, 4, 4], margin),
                        range(&apply(&zx, [4, 4, 4], 1, &d[1]), [4, 3, 4], margin),
                        range(&apply(&yx, [4, 4, 4], 2, &d[2]), [4, 4, 3], margin),
                    ];
                    std::array::from_fn(|a| d[a] * Interval::constant(inv_h[a]))
                } else {
                    [Interval::ZERO; 3]
                };
                let piece = E::compose(v, partials, q);
                out = Some(out.map_or(piece, |p| p.hull(piece)));
            }
        }
    }
    match out {
        Some(p) => hull.intersect(p),
        None => hull,
    }
}

/// Apply the rows `m` (each over 4 inputs) along `axis` of the 4 × 4 × 4 array `c` (x fastest; `dims` its
/// used extent): the result has `m.len()` entries along `axis`, same layout.
fn apply(c: &[f64; 64], dims: [usize; 3], axis: usize, m: &[[f64; 4]]) -> [f64; 64] {
    let stride = [1, 4, 16];
    let mut out_dims = dims;
    out_dims[axis] = m.len();
    let mut out = [0.0; 64];
    for z in 0..out_dims[2] {
        for y in 0..out_dims[1] {
            for x in 0..out_dims[0] {
                let mut idx = [x, y, z];
                let row = &m[idx[axis]];
                idx[axis] = 0;
                let b = idx[0] + 4 * idx[1] + 16 * idx[2];
                let s = stride[axis];
                out[x + 4 * y + 16 * z] = row[0] * c[b]
                    + row[1] * c[b + s]
                    + row[2] * c[b + 2 * s]
                    + row[3] * c[b + 3 * s];
            }
        }
    }
    out
}

/// `[min − margin, max + margin]` over the used extent `dims` of a 4 × 4 × 4 array (x fastest).
fn range(c: &[f64; 64], dims: [usize; 3], margin: f64) -> Interval {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let v = c[x + 4 * y + 16 * z];
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
    }
    Interval::new(dn(lo - margin), up(hi + margin))
}

/// Rows of the linear maps from the four control values `d_0..d_3` of one uniform cubic B-spline segment
/// (taps `i − 1 ..= i + 2`, segment `t ∈ [0, 1]`) to the Bernstein coefficients over `[t0, t1]` of the
/// segment (4 rows) and of its derivative `d/dt` (3 rows), by blossoming (de Boor's algorithm with distinct
/// arguments; Ramshaw, "Blossoms are polar forms", 1989): `b_m = P(t0^{3−m}, t1^m)` and
/// `b'_m = 3 (P(t0^{2−m}, t1^m, 1) − P(t0^{2−m}, t1^m, 0))`. For `t0, t1 ∈ [0, 1]` every de Boor weight
/// lies in `[0, 1]`: value rows are convex (entries ≥ 0, sum 1), derivative rows sum to at most 6 in
/// absolute value (the rounding margin in `spline_enclosure` relies on it).
#[allow(clippy::type_complexity)]
fn bernstein_rows(t0: f64, t1: f64) -> ([[f64; 4]; 4], [[f64; 4]; 3]) {
    // The segment's knots are −2 … 3 and d_j is the blossom P(j − 2, j − 1, j).
    type Lin = [f64; 4];
    let comb = |wa: f64, a: &Lin, wb: f64, b: &Lin, div: f64| -> Lin {
        std::array::from_fn(|k| (wa * a[k] + wb * b[k]) / div)
    };
    // (P(s1, s2, 0), P(s1, s2, 1)) as rows over d_0..d_3.
    let two = |s1: f64, s2: f64| -> (Lin, Lin) {
        let d: [Lin; 4] = std::array::from_fn(|j| {
            let mut e = [0.0; 4];
            e[j] = 1.0;
            e
        });
        let d1: [Lin; 3] = std::array::from_fn(|i| {
            let j = (i + 1) as f64;
            comb(j - s1, &d[i], s1 - (j - 3.0), &d[i + 1], 3.0)
        });
        let d2: [Lin; 2] = std::array::from_fn(|i| {
            let j = (i + 2) as f64;
            comb(j - 1.0 - s2, &d1[i], s2 - (j - 3.0), &d1[i + 1], 2.0)
        });
        (d2[0], d2[1])
    };
    let eval3 = |s1: f64, s2: f64, s3: f64| -> Lin {
        let (p0, p1) = two(s1, s2);
        std::array::from_fn(|k| (1.0 - s3) * p0[k] + s3 * p1[k])
    };
    let deriv = |s1: f64, s2: f64| -> Lin {
        let (p0, p1) = two(s1, s2);
        std::array::from_fn(|k| 3.0 * (p1[k] - p0[k]))
    };
    (
        [
            eval3(t0, t0, t0),
            eval3(t0, t0, t1),
            eval3(t0, t1, t1),
            eval3(t1, t1, t1),
        ],
        [deriv(t0, t0), deriv(t0, t1), deriv(t1, t1)],
    )
}

/// Most cells a box may touch for [`spline_enclosure`] to bound each cell's polynomial (3 per axis).
const MAX_CELL_PIECES: isize = 27;

/// The smooth minimum's evaluation when `S` is an interval type ([`smin_enclosure`]), `None` otherwise (a
/// compile-time constant branch, see [`is_enclosure`]).
#[inline(always)]
pub(super) fn smin_dispatch<S: Scalar>(a: S, b: S, k: S) -> Option<S> {
    if !is_enclosure::<S>() {
        return None;
    }
    let mut out: Option<S> = None;
    let slot = &mut out as &mut dyn Any;
    let args = &(a, b, k) as &dyn Any;
    if let (Some(&(a, b, k)), Some(o)) = (
        args.downcast_ref::<(Interval, Interval, Interval)>(),
        slot.downcast_mut::<Option<Interval>>(),
    ) {
        *o = Some(smin_enclosure(a, b, k.value()));
    } else if let (Some(&(a, b, k)), Some(o)) = (
        args.downcast_ref::<(IntervalGrad, IntervalGrad, IntervalGrad)>(),
        slot.downcast_mut::<Option<IntervalGrad>>(),
    ) {
        *o = Some(smin_enclosure(a, b, k.value()));
    }
    out
}

/// Enclosure of the cubic smooth minimum (`csg.rs`) with blend `k > 0` (a constant).
///
/// With `d = a − b`, `smin = min(a, b) − c k h³`, `h = max(1 − |d|/k, 0)`, `c` = `SMIN_MAX_LOWERING`, is
/// `(a + b)/2 − g(|d|)` with `g(x) = x/2 + c k max(1 − x/k, 0)³`, increasing on `x ≥ 0`, and
/// `∇smin = (∇a + ∇b)/2 − G(d)(∇a − ∇b)` with `G(d) = sign(d) g'(|d|)`, `g'(x) = 1/2 − 3c max(1 − x/k, 0)²`,
/// increasing in `d` (up to a jump of `|1/2 − 3c|` ≈ 1e-8 at 0 from the rounded `c`, covered by a
/// margin). Both monotone factors are enclosed exactly from the ends of `d`, so the enclosure shrinks with
/// the box even where `a = b` inside it (the naive extension hulls both branches of `|d|` and `min` there).
fn smin_enclosure<E: Enclosure>(a: E, b: E, k: Interval) -> E {
    let c = Interval::point(super::csg::SMIN_MAX_LOWERING as f64);
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
    // The formula of `csg.rs`, extended naturally, is sometimes tighter in value (one child dominating):
    // both enclose the same function.
    let kk = E::from_f64(k.mid());
    let h = (kk - d.abs()).max(E::zero()) / kk;
    let naive = a.min(b) - h * h * h * kk * super::csg::SMIN_MAX_LOWERING;
    ((a + b) * 0.5 - blend).intersect(naive)
}

// ---------------------------------------------------------------------------------------------------------
// Entry points

impl Sdf {
    /// Enclosure of `φ(B)` over the box `b` (the node's own coordinates).
    pub fn enclose(&self, b: &Aabb) -> Interval {
        self.eval(Vec3::new(
            Interval::from_f32(b.min.x, b.max.x),
            Interval::from_f32(b.min.y, b.max.y),
            Interval::from_f32(b.min.z, b.max.z),
        ))
    }

    /// Enclosures of `φ(B)` and `∇φ(B)` over the box `b` (the node's own coordinates).
    pub fn enclose_gradient(&self, b: &Aabb) -> IntervalGrad {
        self.eval(IntervalGrad::seed_box(b))
    }
}
