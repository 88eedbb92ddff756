//! [`DualN`]: a forward-mode dual number carrying `N` derivative directions at once in a plain array.
//!
//! One pass of the shading code with `DualN<N>` yields the image derivative with respect to up to `N`
//! scene parameters. Unlike num-dual's `DualSVec32<N>` (an `Option` of an nalgebra matrix, so every
//! operation branches on "has derivative"), the directions here are a bare `[f32; N]`: `Copy`, no
//! allocation, and loops of fixed length that the compiler unrolls and vectorises.
//!
//! Every elementary function takes its value and local derivative from [`super::rules`] and applies the
//! chain rule `eps' = d · eps` (for binary operations `eps' = ∂x · x.eps + ∂y · y.eps`).

use super::{Scalar, Slot, rules};
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// A dual number with `N` derivative directions: `re + Σ eps[k] εₖ` with `εₖ εₗ = 0`.
///
/// Comparisons (in [`Scalar::max`], [`Scalar::abs`], ...) look at `re` only, as for every [`Scalar`].
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct DualN<const N: usize> {
    /// The primal value.
    pub re: f32,
    /// The derivative in each direction.
    pub eps: [f32; N],
}

/// Four derivative directions.
pub type Dual4 = DualN<4>;
/// Eight derivative directions.
pub type Dual8 = DualN<8>;

impl<const N: usize> Default for DualN<N> {
    fn default() -> Self {
        Self::constant(0.0)
    }
}

impl<const N: usize> From<f32> for DualN<N> {
    #[inline(always)]
    fn from(re: f32) -> Self {
        Self::constant(re)
    }
}

impl<const N: usize> DualN<N> {
    /// A dual number from its parts.
    #[inline(always)]
    pub const fn new(re: f32, eps: [f32; N]) -> Self {
        Self { re, eps }
    }

    /// `re` seeded in direction `k` (`eps[k] = 1`); a constant if `k >= N`.
    #[inline(always)]
    pub fn variable(re: f32, k: usize) -> Self {
        let mut eps = [0.0; N];
        if let Some(e) = eps.get_mut(k) {
            *e = 1.0;
        }
        Self { re, eps }
    }

    /// Applies a unary rule `(value, derivative)` by the chain rule.
    #[inline(always)]
    fn chain(self, (v, d): (f32, f32)) -> Self {
        let mut eps = self.eps;
        for e in &mut eps {
            *e *= d;
        }
        Self { re: v, eps }
    }

    /// Applies a binary rule `(value, ∂/∂self, ∂/∂other)` by the chain rule.
    #[inline(always)]
    fn chain2(self, other: Self, (v, dx, dy): (f32, f32, f32)) -> Self {
        let mut eps = self.eps;
        for (e, o) in eps.iter_mut().zip(other.eps) {
            *e = dx * *e + dy * o;
        }
        Self { re: v, eps }
    }
}

impl<const N: usize> Add for DualN<N> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        let mut eps = self.eps;
        for (e, o) in eps.iter_mut().zip(o.eps) {
            *e += o;
        }
        Self {
            re: self.re + o.re,
            eps,
        }
    }
}

impl<const N: usize> Sub for DualN<N> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        let mut eps = self.eps;
        for (e, o) in eps.iter_mut().zip(o.eps) {
            *e -= o;
        }
        Self {
            re: self.re - o.re,
            eps,
        }
    }
}

impl<const N: usize> Mul for DualN<N> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        self.chain2(o, rules::mul(self.re, o.re))
    }
}

impl<const N: usize> Div for DualN<N> {
    type Output = Self;
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        self.chain2(o, rules::div(self.re, o.re))
    }
}

impl<const N: usize> Neg for DualN<N> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        let mut eps = self.eps;
        for e in &mut eps {
            *e = -*e;
        }
        Self { re: -self.re, eps }
    }
}

// Mixed operations with a constant `f32`: the constant has no derivative, so `+`/`-` leave `eps` alone and
// `*`/`/` scale it.

impl<const N: usize> Add<f32> for DualN<N> {
    type Output = Self;
    #[inline(always)]
    fn add(self, c: f32) -> Self {
        Self {
            re: self.re + c,
            eps: self.eps,
        }
    }
}

impl<const N: usize> Sub<f32> for DualN<N> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, c: f32) -> Self {
        Self {
            re: self.re - c,
            eps: self.eps,
        }
    }
}

impl<const N: usize> Mul<f32> for DualN<N> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, c: f32) -> Self {
        self.chain((self.re * c, c))
    }
}

impl<const N: usize> Div<f32> for DualN<N> {
    type Output = Self;
    #[inline(always)]
    fn div(self, c: f32) -> Self {
        self.chain((self.re / c, 1.0 / c))
    }
}

impl<const N: usize> Add<DualN<N>> for f32 {
    type Output = DualN<N>;
    #[inline(always)]
    fn add(self, d: DualN<N>) -> DualN<N> {
        DualN {
            re: self + d.re,
            eps: d.eps,
        }
    }
}

impl<const N: usize> Sub<DualN<N>> for f32 {
    type Output = DualN<N>;
    #[inline(always)]
    fn sub(self, d: DualN<N>) -> DualN<N> {
        -d + self
    }
}

impl<const N: usize> Mul<DualN<N>> for f32 {
    type Output = DualN<N>;
    #[inline(always)]
    fn mul(self, d: DualN<N>) -> DualN<N> {
        d * self
    }
}

impl<const N: usize> Div<DualN<N>> for f32 {
    type Output = DualN<N>;
    #[inline(always)]
    fn div(self, d: DualN<N>) -> DualN<N> {
        // c / y: the constant numerator drops the first partial of the quotient rule.
        let (v, _, dy) = rules::div(self, d.re);
        d.chain((v, dy))
    }
}

macro_rules! assign_ops {
    ($($tr:ident $m:ident $op:tt),*) => {$(
        impl<const N: usize> $tr for DualN<N> {
            #[inline(always)]
            fn $m(&mut self, o: Self) {
                *self = *self $op o;
            }
        }
        impl<const N: usize> $tr<f32> for DualN<N> {
            #[inline(always)]
            fn $m(&mut self, c: f32) {
                *self = *self $op c;
            }
        }
    )*};
}

assign_ops!(AddAssign add_assign +, SubAssign sub_assign -, MulAssign mul_assign *, DivAssign div_assign /);

impl<const N: usize> Scalar for DualN<N> {
    const FIRST_ORDER: bool = true;
    #[inline(always)]
    fn constant(v: f32) -> Self {
        Self {
            re: v,
            eps: [0.0; N],
        }
    }
    #[inline(always)]
    fn is_constant(self) -> bool {
        self.eps.iter().all(|&e| e == 0.0)
    }
    #[inline(always)]
    fn primal(self) -> f32 {
        self.re
    }
    /// Slot `k < N` seeds direction `k`; a slot beyond `N` or `None` is a constant (that parameter is
    /// differentiated in another pass).
    #[inline(always)]
    fn lift(value: f32, slot: Slot) -> Self {
        match slot {
            Some(k) => Self::variable(value, k as usize),
            None => Self::constant(value),
        }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        self.chain(rules::sqrt(self.re))
    }
    #[inline(always)]
    fn exp(self) -> Self {
        self.chain(rules::exp(self.re))
    }
    #[inline(always)]
    fn ln(self) -> Self {
        self.chain(rules::ln(self.re))
    }
    #[inline(always)]
    fn sin(self) -> Self {
        self.chain(rules::sin(self.re))
    }
    #[inline(always)]
    fn cos(self) -> Self {
        self.chain(rules::cos(self.re))
    }
    #[inline(always)]
    fn atan2(self, x: Self) -> Self {
        self.chain2(x, rules::atan2(self.re, x.re))
    }
    #[inline(always)]
    fn acos(self) -> Self {
        self.chain(rules::acos(self.re))
    }
    #[inline(always)]
    fn powf(self, n: f32) -> Self {
        self.chain(rules::powf(self.re, n))
    }
    #[inline(always)]
    fn recip(self) -> Self {
        self.chain(rules::recip(self.re))
    }
    #[inline(always)]
    fn sqr(self) -> Self {
        self.chain(rules::sqr(self.re))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lift_seeds_its_slot_only_when_in_range() {
        assert_eq!(Dual4::lift(2.0, Some(2)).eps, [0.0, 0.0, 1.0, 0.0]);
        assert_eq!(Dual4::lift(2.0, Some(4)).eps, [0.0; 4]);
        assert_eq!(Dual4::lift(2.0, None).eps, [0.0; 4]);
        assert_eq!(DualN::<0>::lift(2.0, Some(0)).re, 2.0);
    }

    #[test]
    fn product_rule_in_two_directions() {
        let x = Dual4::lift(3.0, Some(0));
        let y = Dual4::lift(-2.0, Some(1));
        let p = x * y + x * 4.0;
        assert_eq!(p.re, 6.0);
        assert_eq!(p.eps, [2.0, 3.0, 0.0, 0.0]);
    }
}
