//! Derivative rules written once: every elementary function as its value and its local partial
//! derivative(s) at a point.
//!
//! The rules are generic over the number `T` the point is given in. A forward-mode type over `f32`
//! evaluates them in `f32` and applies the chain rule `eps' = d · eps` ([`super::DualN`]); a type whose
//! coefficients are themselves differentiable evaluates them in that coefficient type, so the local
//! derivative carries its own parameter derivatives ([`super::Grad`]`<S>` with `T = S`, which is how
//! mixed partials `∂π∇φ` arise); a reverse-mode tape records the same partials and propagates
//! `adjoint · d` backwards. Because all of them read the same table, they cannot drift apart.
//!
//! Unary rules return `(value, d value / d x)`; binary rules return `(value, ∂/∂x, ∂/∂y)`. Rules are exact
//! calculus except where a guard is documented (clamps give a zero derivative, never NaN). At a true
//! singularity (`sqrt` and `ln` at 0, `powf` with `n < 1` at 0) the partial is infinite, as in num-dual:
//! callers guard with [`super::Scalar::safe_sqrt`] or by keeping the argument away from the pole.
//!
//! Guards branch on the primal value, like every [`Scalar`]. The order of the floating-point operations is
//! part of the contract: images and derivative images are compared bit for bit across versions, so a
//! rewrite must keep it (e.g. `1/(2√x)` and `0.5/√x` are the same `f32` for every input, but not the same
//! dual number).

use super::Scalar;

/// `x · y`: partials `(y, x)`.
#[inline(always)]
pub fn mul<T: Scalar>(x: T, y: T) -> (T, T, T) {
    (x * y, y, x)
}

/// `x / y`: partials `(1/y, -x/y²)` (quotient rule), the second written `-(x/y) · (1/y)`.
#[inline(always)]
pub fn div<T: Scalar>(x: T, y: T) -> (T, T, T) {
    // `x / y` rather than `x * (1/y)`, so the primal agrees with `f32` to the last bit.
    let q = x / y;
    let inv = y.recip();
    (q, inv, -q * inv)
}

/// `1 / x`: derivative `-1/x²`.
#[inline(always)]
pub fn recip<T: Scalar>(x: T) -> (T, T) {
    let r = x.recip();
    (r, -r * r)
}

/// `x²`: derivative `2x`.
#[inline(always)]
pub fn sqr<T: Scalar>(x: T) -> (T, T) {
    (x * x, x * 2.0)
}

/// `√x`: derivative `1 / (2√x)` (infinite at 0).
#[inline(always)]
pub fn sqrt<T: Scalar>(x: T) -> (T, T) {
    let s = x.sqrt();
    (s, (s * 2.0).recip())
}

/// `eˣ`: derivative `eˣ`.
#[inline(always)]
pub fn exp<T: Scalar>(x: T) -> (T, T) {
    let e = x.exp();
    (e, e)
}

/// `ln x`: derivative `1/x`.
#[inline(always)]
pub fn ln<T: Scalar>(x: T) -> (T, T) {
    (x.ln(), x.recip())
}

/// `sin x`: derivative `cos x`.
#[inline(always)]
pub fn sin<T: Scalar>(x: T) -> (T, T) {
    (x.sin(), x.cos())
}

/// `cos x`: derivative `-sin x`.
#[inline(always)]
pub fn cos<T: Scalar>(x: T) -> (T, T) {
    (x.cos(), -x.sin())
}

/// `atan2(y, x)`: partials `(x/r², -y/r²)` with `r² = x² + y²`.
///
/// Guard: at the origin the angle is undefined (`f32::atan2` returns 0 there); both partials are 0 rather
/// than NaN.
#[inline(always)]
pub fn atan2<T: Scalar>(y: T, x: T) -> (T, T, T) {
    let r2 = x * x + y * y;
    let v = y.atan2(x);
    if r2.primal() > 0.0 {
        let inv = r2.recip();
        (v, x * inv, -y * inv)
    } else {
        (v, T::zero(), T::zero())
    }
}

/// `acos x` with `x` clamped to `[-1, 1]`: derivative `-1/√(1 - x²)` inside, 0 at and beyond the clamp
/// (where the true derivative is infinite), matching `Scalar::acos` of the other types.
#[inline(always)]
pub fn acos<T: Scalar>(x: T) -> (T, T) {
    let p = x.primal();
    if p >= 1.0 || p <= -1.0 {
        // `T::acos` clamps: exactly 0 or π (in `f32`), with `T`'s own zero derivative.
        (x.acos(), T::zero())
    } else {
        (x.acos(), -((-(x * x) + 1.0).sqrt().recip()))
    }
}

/// `xⁿ` for a constant `n`: derivative `n xⁿ⁻¹`.
#[inline(always)]
pub fn powf<T: Scalar>(x: T, n: f32) -> (T, T) {
    (x.powf(n), x.powf(n - 1.0) * n)
}
