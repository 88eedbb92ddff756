//! Interval arithmetic: [`Interval`], a closed interval of reals held in `f64` with outward rounding, and
//! [`IntervalGrad`], forward-mode AD on intervals in the three spatial directions.
//!
//! An enclosure holds the exact real value of a formula evaluated at the `f32` inputs. [`IntervalGrad`]'s
//! value and derivatives are intervals, so one pass over a box gives enclosures of `φ(B)` and of every
//! component of `∇φ(B)` (`crate::sdf::interval` uses both to cull boxes).
//!
//! Both implement [`Scalar`], so generic code runs on them unchanged. What makes that sound:
//! - `abs`, `max`, `min`, `clamp` and `safe_sqrt` are overridden by true interval operations. Where the
//!   branch of a piecewise function is ambiguous over the box, the value is the union of both branches' and
//!   the derivative the hull of both branches' derivatives (a superset of the Clarke generalised gradient,
//!   so it holds every gradient where one exists).
//! - `primal()` returns the midpoint. It is only used for branching; generic code whose branch on a value
//!   that varies over the set would be unsound hands set-valued types to a dedicated enclosure through
//!   [`Scalar::enclosure`] (an [`Enclose`] formula), which the point types answer with `None`.
//! - `detach` keeps the interval (the default would collapse it to the midpoint).
//!
//! Singular derivatives become unbounded rather than wrong: `safe_sqrt` of an interval touching 0 has a
//! derivative enclosure `[0, ∞)·x'`, e.g. the gradient of `|p − c|` over a box holding `c`.

use super::{Scalar, Slot};
use round::{dn, dn2, emul, up, up2};
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

mod enclosure;
mod round;

pub use enclosure::{Enclose, Enclosure};
pub(crate) use round::{dn as round_down, up as round_up};

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

// After the macro: `gradient` uses it.
mod gradient;
pub use gradient::IntervalGrad;

impl Scalar for Interval {
    const POINT: bool = false;
    /// Always the dedicated enclosure (see [`Enclose`]).
    #[inline]
    fn enclosure<F: Enclose<N>, const N: usize>(formula: &F, args: [Self; N]) -> Option<Self> {
        Some(formula.enclose(args))
    }
    #[inline]
    fn constant(v: f32) -> Self {
        Self::point(v as f64)
    }
    /// The midpoint (see the module notes: only branches read it, and those are sound).
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
