//! The one generic boundary of the renderer: a project-owned [`Scalar`] trait.
//!
//! The same shading code runs with `f32` (the image), with forward-mode dual numbers (derivative images)
//! and, later, with a reverse-mode tape type. num-dual's types do not implement `num_traits::Float`, so the
//! trait is our own and small: arithmetic, a handful of elementary functions, `constant`, `primal`,
//! `detach`, [`Scalar::lift`], which turns a scene parameter into the scalar type, and
//! [`Scalar::lattice_sum`], the one operation through which a grid's values enter.
//!
//! Conventions (as in num-dual): comparisons look at the primal value only. A branch taken on a primal
//! value loses the derivative of the branch condition; where that matters a boundary term recovers it.

mod directions;
mod dual;
mod dual_array;
mod grad;
pub mod interval;
mod lattice;
mod reverse;
pub mod rules;

pub(crate) use directions::dispatch_directions;
pub use directions::{Directions, finite_directions};
pub use dual::{Dual2Vec3, DualVec3};
pub use dual_array::{Dual4, Dual8, DualN};
pub use grad::Grad;
pub use lattice::{
    BlockValues, GridValues, LatticeJet, LatticeTaps, lattice_sum_f32, lattice_sum_nested,
};
pub use num_dual::Dual32;
pub use reverse::{MAX_GRADIENT_ENTRY, Mark, Recording, Rev};

use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// Which derivative direction a scene parameter feeds, if any.
///
/// `None` means the parameter is a constant for the current pass. For a one-direction dual, slot 0 is the
/// seeded direction; for a multi-direction dual, slot `k` is the `k`-th direction; for the reverse-mode
/// [`Rev`], the slot is the parameter's gradient entry (a grid's values take a block of entries).
pub type Slot = Option<u32>;

/// A real number that may carry derivatives.
///
/// All methods branch on primal values only. Singular operations (`sqrt` at 0, division by 0) are the
/// caller's to guard; see [`Scalar::safe_sqrt`].
pub trait Scalar:
    Copy
    + Debug
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Add<f32, Output = Self>
    + Sub<f32, Output = Self>
    + Mul<f32, Output = Self>
    + Div<f32, Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + DivAssign
{
    /// Whether this is a point type (one value and its derivatives), whose `min`/`max` pick one
    /// argument by primal value; `false` for the interval types, which take hulls. Code that skips work
    /// by comparing primal values (the CSG culling) does so for point types only.
    const POINT: bool = true;
    /// A constant (all derivatives zero).
    fn constant(v: f32) -> Self;
    /// The value without derivatives.
    fn primal(self) -> f32;
    /// The same value with all derivatives dropped.
    #[inline]
    fn detach(self) -> Self {
        Self::constant(self.primal())
    }
    /// A scene parameter with value `value` lifted into this type: seeded in direction `slot` if the
    /// type differentiates with respect to scene parameters, a constant otherwise.
    fn lift(value: f32, slot: Slot) -> Self;

    /// Square root. Its derivative is infinite at 0: use [`Scalar::safe_sqrt`] where 0 can occur.
    fn sqrt(self) -> Self;
    /// Natural exponential.
    fn exp(self) -> Self;
    /// Natural logarithm.
    fn ln(self) -> Self;
    /// Sine (radians).
    fn sin(self) -> Self;
    /// Cosine (radians).
    fn cos(self) -> Self;
    /// Arc tangent of `self / x` in `(-π, π]`.
    fn atan2(self, x: Self) -> Self;
    /// Arc cosine; the argument is clamped to `[-1, 1]` and the derivative is zero at the clamp.
    fn acos(self) -> Self;
    /// `self` raised to a constant power.
    fn powf(self, n: f32) -> Self;

    /// Zero.
    #[inline]
    fn zero() -> Self {
        Self::constant(0.0)
    }
    /// One.
    #[inline]
    fn one() -> Self {
        Self::constant(1.0)
    }
    /// `1 / self`.
    #[inline]
    fn recip(self) -> Self {
        Self::one() / self
    }
    /// Absolute value (derivative sign chosen by the primal; 0 at 0 takes the positive branch).
    #[inline]
    fn abs(self) -> Self {
        if self.primal() < 0.0 { -self } else { self }
    }
    /// The larger of the two by primal value (ties keep `self`).
    #[inline]
    fn max(self, other: Self) -> Self {
        if other.primal() > self.primal() {
            other
        } else {
            self
        }
    }
    /// The smaller of the two by primal value (ties keep `self`).
    #[inline]
    fn min(self, other: Self) -> Self {
        if other.primal() < self.primal() {
            other
        } else {
            self
        }
    }
    /// Clamp by primal value; outside the range the derivative is zero.
    #[inline]
    fn clamp(self, lo: f32, hi: f32) -> Self {
        let v = self.primal();
        if v < lo {
            Self::constant(lo)
        } else if v > hi {
            Self::constant(hi)
        } else {
            self
        }
    }
    /// `sqrt(max(self, 0))` whose derivative is zero (not infinite or NaN) where the primal is `<= 0`.
    #[inline]
    fn safe_sqrt(self) -> Self {
        if self.primal() <= 0.0 {
            Self::zero()
        } else {
            self.sqrt()
        }
    }
    /// `self * self`.
    #[inline]
    fn sqr(self) -> Self {
        self * self
    }

    /// Whether this number is known to carry no derivative; `false` where that is not known (always
    /// safe). Generic code asks it before taking shortcuts that hold for constants only.
    #[inline(always)]
    fn is_constant(self) -> bool {
        false
    }

    /// Whether this is a coordinate of a point seeded in space only: a [`Grad`] whose value and spatial
    /// gradient are constants, so that a smooth function of it is exactly its value plus its slope
    /// times `self − primal` (first order in space, no parameter derivative, no mixed partial).
    /// `false` for every other type.
    #[inline(always)]
    fn spatial_only(self) -> bool {
        false
    }

    /// The value itself if this is `f32`, the tracer's type, which takes vectorised fast paths that
    /// give the same bits as the generic code; `None` for the derivative and interval types.
    #[inline(always)]
    fn as_f32(self) -> Option<f32> {
        None
    }

    /// A grid's B-spline at one point: the separable sum of [`lattice_sum_nested`] over the values of
    /// a lattice of `dims = [nx, ny, nz]` (x fastest). `block` is the gradient entry of `values[0]` when
    /// the values are differentiated in reverse mode ([`BlockValues::block`]); other types ignore it.
    #[inline(always)]
    fn lattice_sum(
        taps: &LatticeTaps<Self>,
        values: &[f32],
        dims: [usize; 3],
        block: Slot,
    ) -> Self {
        let _ = block;
        lattice_sum_nested(taps, values, dims[0], dims[1])
    }

    /// A lookup at a point fixed in everything but space, in a block differentiated in reverse mode:
    /// the value and the spatial gradient `[v, g_x, g_y, g_z]` that `Grad<Self>`'s
    /// [`Scalar::lattice_sum`] would give for constant weights `taps` whose derivative along axis
    /// `a` is `deriv[a]` for axis `a`'s own weights and 0 for the others', with the same primal bits
    /// and the same derivatives; `None` to let it take its generic path (the default, and for any
    /// type but [`Rev`], which computes the four sums in one pass). `sums` are those four sums'
    /// values where the caller has them already (a grid's `f32` jet), so they are not summed again.
    #[inline(always)]
    fn lattice_sum_with_gradient(
        taps: &LatticeTaps<f32>,
        deriv: &[[f32; 4]; 3],
        values: &[f32],
        dims: [usize; 3],
        block: Slot,
        sums: Option<[f32; 4]>,
    ) -> Option<[Self; 4]> {
        let _ = (taps, deriv, values, dims, block, sums);
        None
    }

    /// Whether this type carries first derivatives only (no second-order parts), so that a smooth
    /// function of it is exactly its value plus its slope times its change ([`Scalar::affine`]).
    const FIRST_ORDER: bool = false;

    /// Whether every operation on this type is recorded (a reverse-mode tape node), so that fusing a
    /// computation into one [`Scalar::affine`] number, its partials taken in `f32`, saves work; for
    /// the forward-mode types it would only change their derivatives' rounding.
    const RECORDED: bool = false;

    /// The number with primal `value` whose derivative is `Σ c · (the derivative of x)` over `terms`:
    /// a smooth function's first-order expansion around the primals of its arguments, with its value
    /// given rather than recomputed. Exact for [`Scalar::FIRST_ORDER`] types; [`Rev`] records it as
    /// one node.
    #[inline(always)]
    fn affine(value: f32, terms: &[(Self, f32)]) -> Self {
        terms.iter().fold(Self::constant(value), |acc, &(x, c)| {
            acc + (x - x.primal()) * c
        })
    }

    /// A grid's spline at a point `q` whose coordinates carry derivatives, built by the chain rule from
    /// the spline's `f32` jet at the primal point (`jet`, called only by types that use it); `None`
    /// (the default) lets the lookup evaluate the basis in this type's own arithmetic. [`Grad`] over a
    /// first-order type implements it.
    #[inline(always)]
    fn lattice_jet<'a>(q: [Self; 3], jet: impl FnOnce() -> Option<LatticeJet<'a>>) -> Option<Self> {
        let _ = (q, jet);
        None
    }

    /// The derivative part of a lookup in a parameter block differentiated in reverse mode: a number
    /// whose primal is 0 and whose derivative with respect to value `i` of the block whose first
    /// gradient entry is `first` is `w` for each `(i, w)` of `terms` (a texture's trilinear weights).
    /// [`Rev`] records it as one tape node; the other types, which never carry a reverse-mode block,
    /// return zero (as [`Scalar::lattice_sum`] ignores its block).
    #[inline(always)]
    fn block_terms(first: u32, terms: &[(usize, f32)]) -> Self {
        let _ = (first, terms);
        Self::zero()
    }

    /// `formula`'s dedicated enclosure of its value over the sets `args` if this is a set-valued type
    /// (an [`interval::Enclosure`]); `None` for the point types, which evaluate the formula itself.
    ///
    /// Generic code asks this before branching on a primal value that varies over a set (see
    /// [`interval::Enclose`]). The default is a constant `None`, so the point types run exactly the code
    /// they would without the question.
    #[inline(always)]
    fn enclosure<F: interval::Enclose<N>, const N: usize>(
        formula: &F,
        args: [Self; N],
    ) -> Option<Self> {
        let _ = (formula, args);
        None
    }
}

impl Scalar for f32 {
    #[inline(always)]
    fn constant(v: f32) -> Self {
        v
    }
    #[inline(always)]
    fn is_constant(self) -> bool {
        true
    }
    #[inline(always)]
    fn as_f32(self) -> Option<f32> {
        Some(self)
    }
    #[inline(always)]
    fn lattice_sum(
        taps: &LatticeTaps<Self>,
        values: &[f32],
        dims: [usize; 3],
        _block: Slot,
    ) -> Self {
        lattice_sum_f32(taps, values, dims[0], dims[1])
    }
    #[inline(always)]
    fn primal(self) -> f32 {
        self
    }
    #[inline(always)]
    fn lift(value: f32, _slot: Slot) -> Self {
        value
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    #[inline(always)]
    fn exp(self) -> Self {
        f32::exp(self)
    }
    #[inline(always)]
    fn ln(self) -> Self {
        f32::ln(self)
    }
    #[inline(always)]
    fn sin(self) -> Self {
        f32::sin(self)
    }
    #[inline(always)]
    fn cos(self) -> Self {
        f32::cos(self)
    }
    #[inline(always)]
    fn atan2(self, x: Self) -> Self {
        f32::atan2(self, x)
    }
    #[inline(always)]
    fn acos(self) -> Self {
        f32::acos(self.clamp(-1.0, 1.0))
    }
    #[inline(always)]
    fn powf(self, n: f32) -> Self {
        f32::powf(self, n)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32::abs(self)
    }
    #[inline(always)]
    fn max(self, other: Self) -> Self {
        if other > self { other } else { self }
    }
    #[inline(always)]
    fn min(self, other: Self) -> Self {
        if other < self { other } else { self }
    }
}

/// A scene parameter stored in `f32` together with the derivative slot it feeds in the current pass.
///
/// Rendering types hold `Param`s for every differentiable number; [`Param::get`] lifts it into any
/// [`Scalar`]. With `f32` this is a plain load.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Param {
    /// The value, in the units of the field it stands for.
    pub value: f32,
    /// The derivative direction this parameter seeds, if any.
    pub slot: Slot,
}

impl Param {
    /// A parameter that is not differentiated.
    #[inline]
    pub const fn new(value: f32) -> Self {
        Self { value, slot: None }
    }
    /// The parameter lifted into `S`.
    #[inline(always)]
    pub fn get<S: Scalar>(&self) -> S {
        S::lift(self.value, self.slot)
    }
}

impl From<f32> for Param {
    fn from(value: f32) -> Self {
        Self::new(value)
    }
}

/// Three parameters: a point, a vector or a linear RGB colour.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Param3 {
    /// The components (`x, y, z` or `r, g, b`).
    pub c: [Param; 3],
}

impl Param3 {
    /// Three undifferentiated parameters.
    #[inline]
    pub const fn new(v: [f32; 3]) -> Self {
        Self {
            c: [Param::new(v[0]), Param::new(v[1]), Param::new(v[2])],
        }
    }
    /// The primal values as a glam vector.
    #[inline(always)]
    pub fn value(&self) -> glam::Vec3 {
        glam::Vec3::new(self.c[0].value, self.c[1].value, self.c[2].value)
    }
    /// The parameters lifted into `S`.
    #[inline(always)]
    pub fn get<S: Scalar>(&self) -> crate::math::Vec3<S> {
        crate::math::Vec3::new(self.c[0].get(), self.c[1].get(), self.c[2].get())
    }
}

impl From<glam::Vec3> for Param3 {
    fn from(v: glam::Vec3) -> Self {
        Self::new(v.to_array())
    }
}

impl From<[f32; 3]> for Param3 {
    fn from(v: [f32; 3]) -> Self {
        Self::new(v)
    }
}

#[cfg(test)]
mod tests;
