//! Generic geometry helpers shared by the primal integrators and, later, the interior derivative.

use crate::math::Vec3;
use crate::scalar::Scalar;

/// The geometry term `G(x, y) = |n_x · ω| |n_y · ω| / d²`, `ω = (y − x)/d`, `d = |y − x|` (Veach 1997,
/// eq. 8.3, with absolute cosines because surfaces here are two-sided).
///
/// Written as `|n_x · Δ| |n_y · Δ| / d⁴` with `Δ = y − x`, so no square root (and no infinite derivative)
/// appears. Zero, with zero derivative, when the points coincide; zero when a normal is zero.
#[inline]
pub fn geometry_term<S: Scalar>(x: Vec3<S>, nx: Vec3<S>, y: Vec3<S>, ny: Vec3<S>) -> S {
    let delta = y - x;
    let d2 = delta.length_squared();
    if d2.primal().is_nan() || d2.primal() <= 0.0 {
        return S::zero();
    }
    let cx = nx.dot(delta).abs();
    let cy = ny.dot(delta).abs();
    cx * cy / (d2 * d2)
}

/// `|n · ω|` for a point `x` with normal `n` looking towards a direction `w` at infinity.
#[inline]
pub fn abs_cos<S: Scalar>(n: Vec3<S>, w: Vec3<S>) -> S {
    n.dot(w).abs()
}

/// Unit direction from `from` to `to`, or zero (with zero derivative) when they coincide.
#[inline]
pub fn direction<S: Scalar>(from: Vec3<S>, to: Vec3<S>) -> Vec3<S> {
    (to - from).normalize_or_zero()
}
