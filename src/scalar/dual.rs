//! [`Scalar`] for num-dual's number types: `Dual32` (one derivative direction with respect to scene
//! parameters) and the spatial types used to differentiate implicit functions with respect to position
//! (`DualVec3` for gradients, `Dual2Vec3` for Hessians, hence curvature). The spatial types treat scene
//! parameters as constants.

use super::{Scalar, Slot};
use num_dual::{Dual2SVec32, Dual32, DualNum, DualSVec32};

/// First-order dual number in three spatial directions: value and gradient with respect to a point.
pub type DualVec3 = DualSVec32<3>;
/// Second-order dual number in three spatial directions: value, gradient and Hessian.
pub type Dual2Vec3 = Dual2SVec32<3>;

macro_rules! impl_scalar_for_num_dual {
    ($t:ty, $first_order:expr, $lift:expr) => {
        impl Scalar for $t {
            const FIRST_ORDER: bool = $first_order;
            #[inline]
            fn constant(v: f32) -> Self {
                <$t>::from(v)
            }
            #[inline]
            fn primal(self) -> f32 {
                self.re
            }
            #[inline]
            fn lift(value: f32, slot: Slot) -> Self {
                #[allow(clippy::redundant_closure_call)]
                ($lift)(value, slot)
            }
            #[inline]
            fn sqrt(self) -> Self {
                DualNum::sqrt(&self)
            }
            #[inline]
            fn exp(self) -> Self {
                DualNum::exp(&self)
            }
            #[inline]
            fn ln(self) -> Self {
                DualNum::ln(&self)
            }
            #[inline]
            fn sin(self) -> Self {
                DualNum::sin(&self)
            }
            #[inline]
            fn cos(self) -> Self {
                DualNum::cos(&self)
            }
            #[inline]
            fn atan2(self, x: Self) -> Self {
                // num-dual computes atan(y / x), whose derivatives are NaN at x = 0. Divide by the larger
                // of |x|, |y| instead: each branch is analytic where it is used, so derivatives of every
                // order stay exact; at the origin the result is a constant.
                let (y, xr, yr) = (self, x.re, self.re);
                if xr == 0.0 && yr == 0.0 {
                    Self::constant(yr.atan2(xr))
                } else if xr.abs() >= yr.abs() {
                    let base = DualNum::atan(&(y / x));
                    if xr > 0.0 {
                        base
                    } else if yr >= 0.0 {
                        base + std::f32::consts::PI
                    } else {
                        base - std::f32::consts::PI
                    }
                } else {
                    let half_pi = std::f32::consts::FRAC_PI_2.copysign(yr);
                    -DualNum::atan(&(x / y)) + half_pi
                }
            }
            #[inline]
            fn acos(self) -> Self {
                // At |x| >= 1 the derivative is infinite: the clamp makes it zero instead.
                if self.re >= 1.0 {
                    Self::constant(0.0)
                } else if self.re <= -1.0 {
                    Self::constant(std::f32::consts::PI)
                } else {
                    DualNum::acos(&self)
                }
            }
            #[inline]
            fn powf(self, n: f32) -> Self {
                DualNum::powf(&self, n)
            }
        }
    };
}

impl_scalar_for_num_dual!(Dual32, true, |value: f32, slot: Slot| if slot == Some(0) {
    Dual32::new(value, 1.0)
} else {
    Dual32::from(value)
});
impl_scalar_for_num_dual!(DualVec3, true, |value: f32, _slot: Slot| DualVec3::from(
    value
));
impl_scalar_for_num_dual!(Dual2Vec3, false, |value: f32, _slot: Slot| Dual2Vec3::from(
    value
));
