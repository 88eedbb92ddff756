//! Derivative rules written once: every elementary function as its value and its local partial
//! derivative(s) at a primal point, in `f32`.
//!
//! A forward-mode type applies a rule by the chain rule, `eps' = d · eps` ([`super::DualN`]); a reverse-mode
//! tape records the same partials and propagates `adjoint · d` backwards. Because both read the same
//! table, forward and reverse mode cannot drift apart.
//!
//! Unary rules return `(value, d value / d x)`; binary rules return `(value, ∂/∂x, ∂/∂y)`. Rules are exact
//! calculus except where a guard is documented (clamps give a zero derivative, never NaN). At a true
//! singularity (`sqrt` and `ln` at 0, `powf` with `n < 1` at 0) the partial is infinite, as in num-dual:
//! callers guard with [`super::Scalar::safe_sqrt`] or by keeping the argument away from the pole.

use std::f32::consts::PI;

/// `x · y`: partials `(y, x)`.
#[inline(always)]
pub fn mul(x: f32, y: f32) -> (f32, f32, f32) {
    (x * y, y, x)
}

/// `x / y`: partials `(1/y, -x/y²)` (quotient rule), the second written `-(x/y) · (1/y)`.
#[inline(always)]
pub fn div(x: f32, y: f32) -> (f32, f32, f32) {
    // `x / y` rather than `x * (1/y)`, so the primal agrees with `f32` to the last bit.
    let q = x / y;
    let inv = 1.0 / y;
    (q, inv, -q * inv)
}

/// `1 / x`: derivative `-1/x²`.
#[inline(always)]
pub fn recip(x: f32) -> (f32, f32) {
    let r = 1.0 / x;
    (r, -r * r)
}

/// `x²`: derivative `2x`.
#[inline(always)]
pub fn sqr(x: f32) -> (f32, f32) {
    (x * x, 2.0 * x)
}

/// `√x`: derivative `1 / (2√x)` (infinite at 0).
#[inline(always)]
pub fn sqrt(x: f32) -> (f32, f32) {
    let s = x.sqrt();
    (s, 0.5 / s)
}

/// `eˣ`: derivative `eˣ`.
#[inline(always)]
pub fn exp(x: f32) -> (f32, f32) {
    let e = x.exp();
    (e, e)
}

/// `ln x`: derivative `1/x`.
#[inline(always)]
pub fn ln(x: f32) -> (f32, f32) {
    (x.ln(), 1.0 / x)
}

/// `sin x`: derivative `cos x`.
#[inline(always)]
pub fn sin(x: f32) -> (f32, f32) {
    let (s, c) = x.sin_cos();
    (s, c)
}

/// `cos x`: derivative `-sin x`.
#[inline(always)]
pub fn cos(x: f32) -> (f32, f32) {
    let (s, c) = x.sin_cos();
    (c, -s)
}

/// `atan2(y, x)`: partials `(x/r², -y/r²)` with `r² = x² + y²`.
///
/// Guard: at the origin the angle is undefined (`f32::atan2` returns 0 there); both partials are 0 rather
/// than NaN.
#[inline(always)]
pub fn atan2(y: f32, x: f32) -> (f32, f32, f32) {
    let r2 = x * x + y * y;
    let v = y.atan2(x);
    if r2 > 0.0 {
        let inv = 1.0 / r2;
        (v, x * inv, -y * inv)
    } else {
        (v, 0.0, 0.0)
    }
}

/// `acos x` with `x` clamped to `[-1, 1]`: derivative `-1/√(1 - x²)` inside, 0 at and beyond the clamp
/// (where the true derivative is infinite), matching `Scalar::acos` of the other types.
#[inline(always)]
pub fn acos(x: f32) -> (f32, f32) {
    if x >= 1.0 {
        (0.0, 0.0)
    } else if x <= -1.0 {
        (PI, 0.0)
    } else {
        (x.acos(), -1.0 / (1.0 - x * x).sqrt())
    }
}

/// `xⁿ` for a constant `n`: derivative `n xⁿ⁻¹`.
#[inline(always)]
pub fn powf(x: f32, n: f32) -> (f32, f32) {
    (x.powf(n), n * x.powf(n - 1.0))
}
