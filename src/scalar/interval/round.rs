//! Outward rounding of `f64` results: every endpoint computed by a rounded operation is stepped one ulp
//! outward (two for libm's transcendental functions, which are within one ulp of the exact value), so an
//! enclosure holds the exact real result.

/// Lower end of a rounded result: one ulp down, except for an exact zero (a sum, quotient or square root
/// that is 0 is exact; products guard their own zeros) and NaN, which widens to `−∞`.
#[inline(always)]
pub(crate) fn dn(x: f64) -> f64 {
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
pub(crate) fn up(x: f64) -> f64 {
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
pub(super) fn dn2(x: f64) -> f64 {
    if x.is_nan() {
        f64::NEG_INFINITY
    } else {
        x.next_down().next_down()
    }
}

/// Two ulps up, for libm results.
#[inline(always)]
pub(super) fn up2(x: f64) -> f64 {
    if x.is_nan() {
        f64::INFINITY
    } else {
        x.next_up().next_up()
    }
}

/// Bounds of the product of two endpoints: `0 · x = 0` exactly (also for infinite `x`, the convention of
/// interval arithmetic), otherwise the rounded product widened one ulp (which also covers underflow).
#[inline(always)]
pub(super) fn emul(a: f64, b: f64) -> (f64, f64) {
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
