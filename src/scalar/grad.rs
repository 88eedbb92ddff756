//! [`Grad`]`<S>`: a first-order dual number in the three spatial directions whose coefficients are
//! themselves scalars `S`.
//!
//! Evaluating `φ` at a seeded point gives `φ` and `∇φ` as `S` values, i.e. together with their parameter
//! derivatives: the mixed partials `∂π∇φ` that move the normal of an attached vertex
//! ([`crate::integrator::attach`]). Scene parameters lift into the value (constants in space).
//!
//! Every elementary function takes its value and local derivative from [`super::rules`] evaluated in `S`
//! (so the local derivative carries its own parameter derivatives) and applies the chain rule
//! `g' = g · d` in each direction.

use super::{LatticeJet, LatticeTaps, Scalar, Slot, lattice_sum_nested, rules};
use crate::math::Vec3;
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// A first-order dual number in the three spatial directions with coefficients in `S`: `v + Σ g_i ε_i`.
/// Evaluating `φ` at a seeded point gives `φ` and `∇φ` as `S` values, i.e. with their parameter
/// derivatives (mixed partials `∂π∇φ`). Scene parameters lift into `v` (constants in space).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Grad<S> {
    /// The value.
    pub v: S,
    /// The spatial gradient.
    pub g: [S; 3],
}

impl<S: Scalar> Grad<S> {
    /// The point `p` seeded as the spatial variable: `p_i` has gradient `e_i`.
    #[inline]
    pub fn seed(p: glam::Vec3) -> Vec3<Self> {
        let (z, o) = (S::zero(), S::one());
        Vec3::new(
            Self {
                v: S::constant(p.x),
                g: [o, z, z],
            },
            Self {
                v: S::constant(p.y),
                g: [z, o, z],
            },
            Self {
                v: S::constant(p.z),
                g: [z, z, o],
            },
        )
    }

    /// Applies a unary rule `(value, derivative)` (both in `S`) by the chain rule.
    #[inline(always)]
    fn chain(self, (v, d): (S, S)) -> Self {
        Self {
            v,
            g: self.g.map(|g| g * d),
        }
    }

    /// Applies a binary rule `(value, ∂/∂self, ∂/∂other)` by the chain rule.
    #[inline(always)]
    fn chain2(self, o: Self, (v, dx, dy): (S, S, S)) -> Self {
        Self {
            v,
            g: std::array::from_fn(|i| dx * self.g[i] + dy * o.g[i]),
        }
    }
}

impl<S: Scalar> Add for Grad<S> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self {
            v: self.v + o.v,
            g: [self.g[0] + o.g[0], self.g[1] + o.g[1], self.g[2] + o.g[2]],
        }
    }
}

impl<S: Scalar> Sub for Grad<S> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self {
            v: self.v - o.v,
            g: [self.g[0] - o.g[0], self.g[1] - o.g[1], self.g[2] - o.g[2]],
        }
    }
}

impl<S: Scalar> Mul for Grad<S> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        self.chain2(o, rules::mul(self.v, o.v))
    }
}

#[allow(clippy::suspicious_arithmetic_impl)] // The factored quotient rule.
impl<S: Scalar> Div for Grad<S> {
    type Output = Self;
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        // The partials of `rules::div` are `(1/b, −(a/b)·(1/b))`; applied factored, `(a' − (a/b) b')/b`,
        // which is the order the attached normals have always been computed in (they are compared bit for
        // bit across versions).
        let (q, inv, _) = rules::div(self.v, o.v);
        Self {
            v: q,
            g: std::array::from_fn(|i| (self.g[i] - q * o.g[i]) * inv),
        }
    }
}

impl<S: Scalar> Neg for Grad<S> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self {
            v: -self.v,
            g: self.g.map(|g| -g),
        }
    }
}

impl<S: Scalar> Add<f32> for Grad<S> {
    type Output = Self;
    #[inline(always)]
    fn add(self, c: f32) -> Self {
        Self {
            v: self.v + c,
            g: self.g,
        }
    }
}

impl<S: Scalar> Sub<f32> for Grad<S> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, c: f32) -> Self {
        Self {
            v: self.v - c,
            g: self.g,
        }
    }
}

impl<S: Scalar> Mul<f32> for Grad<S> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, c: f32) -> Self {
        Self {
            v: self.v * c,
            g: self.g.map(|g| g * c),
        }
    }
}

impl<S: Scalar> Div<f32> for Grad<S> {
    type Output = Self;
    #[inline(always)]
    fn div(self, c: f32) -> Self {
        Self {
            v: self.v / c,
            g: self.g.map(|g| g / c),
        }
    }
}

macro_rules! assign_ops {
    ($($tr:ident $f:ident $op:tt),*) => {$(
        impl<S: Scalar> $tr for Grad<S> {
            #[inline(always)]
            fn $f(&mut self, o: Self) {
                *self = *self $op o;
            }
        }
    )*};
}
assign_ops!(AddAssign add_assign +, SubAssign sub_assign -, MulAssign mul_assign *, DivAssign div_assign /);

// `recip` and `sqr` keep the trait defaults (`1 / x` and `x · x` through the quotient and product rules):
// the rule-table versions round differently in `S`.
impl<S: Scalar> Scalar for Grad<S> {
    const POINT: bool = S::POINT;
    #[inline(always)]
    fn constant(v: f32) -> Self {
        Self {
            v: S::constant(v),
            g: [S::zero(); 3],
        }
    }
    #[inline(always)]
    fn spatial_only(self) -> bool {
        self.v.is_constant() && self.g.iter().all(|g| g.is_constant())
    }
    #[inline(always)]
    fn primal(self) -> f32 {
        self.v.primal()
    }
    #[inline(always)]
    fn lift(value: f32, slot: Slot) -> Self {
        Self {
            v: S::lift(value, slot),
            g: [S::zero(); 3],
        }
    }
    #[inline]
    fn sqrt(self) -> Self {
        self.chain(rules::sqrt(self.v))
    }
    #[inline]
    fn exp(self) -> Self {
        self.chain(rules::exp(self.v))
    }
    #[inline]
    fn ln(self) -> Self {
        self.chain(rules::ln(self.v))
    }
    #[inline]
    fn sin(self) -> Self {
        self.chain(rules::sin(self.v))
    }
    #[inline]
    fn cos(self) -> Self {
        self.chain(rules::cos(self.v))
    }
    #[inline]
    fn atan2(self, x: Self) -> Self {
        self.chain2(x, rules::atan2(self.v, x.v))
    }
    #[inline]
    fn acos(self) -> Self {
        self.chain(rules::acos(self.v))
    }
    #[inline]
    fn powf(self, n: f32) -> Self {
        self.chain(rules::powf(self.v, n))
    }

    /// By the chain rule from the `f32` jet at the primal point `q̄` (`φ̄`, `ḡ`, `H̄`), exact to first
    /// order in `S`: with `δq = q − q̄` (each coordinate's value, a number in `S` of primal 0), the value
    /// is `φ̄ + ḡ · δq`, the grid's gradient `G_a = ḡ_a + Σ_b H̄_ab δq_b`, and the spatial gradient
    /// `g_k = Σ_a G_a ∂q_a/∂x_k`; the values of a reverse-mode block enter through the four lattice
    /// nodes of the value and gradient sums. Where the generic path evaluates the basis in `Grad<S>`
    /// arithmetic and sums ten lattices with moving weights, this takes seven [`Scalar::affine`]
    /// numbers (docs/theory.md (10.3)). Only for first-order `S` (a second-order `S` would lose its
    /// curvature terms).
    fn lattice_jet<'a>(q: [Self; 3], jet: impl FnOnce() -> Option<LatticeJet<'a>>) -> Option<Self> {
        if !S::FIRST_ORDER {
            return None;
        }
        let jet = jet()?;
        let (g, h) = (jet.gradient, jet.hessian);
        let lattice = match jet.block {
            Some(_) => S::lattice_sum_with_gradient(
                &jet.taps,
                &jet.deriv,
                jet.values,
                jet.dims,
                jet.block,
                Some([jet.value, g[0], g[1], g[2]]),
            )?,
            None => [S::zero(); 4],
        };
        let [q0, q1, q2] = q.map(|c| c.v);
        let v = S::affine(
            jet.value,
            &[(lattice[0], 1.0), (q0, g[0]), (q1, g[1]), (q2, g[2])],
        );
        let grid_gradient: [S; 3] = std::array::from_fn(|a| {
            S::affine(
                g[a],
                &[
                    (lattice[a + 1], 1.0),
                    (q0, h[a][0]),
                    (q1, h[a][1]),
                    (q2, h[a][2]),
                ],
            )
        });
        let gradient = std::array::from_fn(|k| {
            let j = q.map(|c| c.g[k]);
            let jp = j.map(|x| x.primal());
            S::affine(
                g[0] * jp[0] + g[1] * jp[1] + g[2] * jp[2],
                &[
                    (grid_gradient[0], jp[0]),
                    (grid_gradient[1], jp[1]),
                    (grid_gradient[2], jp[2]),
                    (j[0], g[0]),
                    (j[1], g[1]),
                    (j[2], g[2]),
                ],
            )
        });
        Some(Self { v, g: gradient })
    }

    /// With a reverse-mode block, by trilinearity: the value is `S`'s sum of the weights' values and
    /// `g_i` the sum over axes of `S`'s sums with that axis's weights replaced by their `i`-th spatial
    /// derivative, so that each is one node of `S` over the block (the value and the gradient's 3×64).
    /// Otherwise the nested sum in `Grad<S>` arithmetic.
    fn lattice_sum(
        taps: &LatticeTaps<Self>,
        values: &[f32],
        dims: [usize; 3],
        block: Slot,
    ) -> Self {
        if block.is_none() {
            return lattice_sum_nested(taps, values, dims[0], dims[1]);
        }
        if let Some((fixed, deriv)) = axis_aligned_constant(taps)
            && let Some([v, gx, gy, gz]) =
                S::lattice_sum_with_gradient(&fixed, &deriv, values, dims, block, None)
        {
            return Self { v, g: [gx, gy, gz] };
        }
        let part = |deriv: Option<(usize, usize)>| {
            let t = taps.map(|a, w| match deriv {
                Some((axis, i)) if axis == a => w.g[i],
                _ => w.v,
            });
            S::lattice_sum(&t, values, dims, block)
        };
        Self {
            v: part(None),
            g: std::array::from_fn(|i| {
                part(Some((0, i))) + part(Some((1, i))) + part(Some((2, i)))
            }),
        }
    }
}

/// The primal weights of `taps` and each axis's weights' derivative along that axis, when every
/// weight and derivative is a constant, no axis's weights move along another axis (exact zeros, as
/// for a point seeded in space only, unrotated) and no axis's own derivatives are all zero;
/// otherwise `None`.
fn axis_aligned_constant<S: Scalar>(
    taps: &LatticeTaps<Grad<S>>,
) -> Option<(LatticeTaps<f32>, [[f32; 4]; 3])> {
    let mut deriv = [[0.0f32; 4]; 3];
    for (a, weights) in taps.weight.iter().enumerate() {
        for (k, w) in weights.iter().enumerate() {
            if !w.v.is_constant() || !w.g.iter().all(|g| g.is_constant()) {
                return None;
            }
            if (0..3).any(|i| i != a && w.g[i].primal() != 0.0) {
                return None;
            }
            deriv[a][k] = w.g[a].primal();
        }
        if deriv[a].iter().all(|&d| d == 0.0) {
            return None;
        }
    }
    Some((taps.map(|_, w| w.v.primal()), deriv))
}
