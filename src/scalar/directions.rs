//! Forward-mode number types whose derivative directions can be read back, one `f32` each.

use super::{Dual32, DualN, Rev, Scalar};

/// A forward-mode scalar type whose derivative directions can be read back.
pub trait Directions: Scalar {
    /// Number of directions carried.
    const COUNT: usize;
    /// Derivative in direction `k < COUNT`.
    fn direction(&self, k: usize) -> f32;
}

/// A plain number carries no direction.
impl Directions for f32 {
    const COUNT: usize = 0;
    #[inline(always)]
    fn direction(&self, _k: usize) -> f32 {
        0.0
    }
}

impl<const N: usize> Directions for DualN<N> {
    const COUNT: usize = N;
    #[inline(always)]
    fn direction(&self, k: usize) -> f32 {
        self.eps[k]
    }
}

/// A reverse-mode number has no forward directions to read: its derivatives are checked when the tape
/// is swept, so the per-direction finiteness checks of the estimators pass it through.
impl Directions for Rev {
    const COUNT: usize = 0;
    #[inline(always)]
    fn direction(&self, _k: usize) -> f32 {
        0.0
    }
}

impl Directions for Dual32 {
    const COUNT: usize = 1;
    #[inline(always)]
    fn direction(&self, _k: usize) -> f32 {
        self.eps
    }
}

/// All directions `0..width` of `v` are finite.
#[inline]
pub fn finite_directions<S: Directions>(v: S, width: usize) -> bool {
    (0..width).all(|k| v.direction(k).is_finite())
}

/// Calls `$f::<S>(args)` with the narrowest `DualN` that holds `$count` directions (several passes of
/// eight beyond eight): one dispatch for the interior and both boundary terms.
macro_rules! dispatch_directions {
    ($count:expr, $f:ident($($arg:expr),* $(,)?)) => {
        match $count {
            0 | 1 => $f::<crate::scalar::DualN<1>>($($arg),*),
            2 => $f::<crate::scalar::DualN<2>>($($arg),*),
            3 | 4 => $f::<crate::scalar::DualN<4>>($($arg),*),
            _ => $f::<crate::scalar::DualN<8>>($($arg),*),
        }
    };
}
pub(crate) use dispatch_directions;
