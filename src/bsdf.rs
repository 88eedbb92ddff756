//! Surface scattering. Directions point away from the surface; `n` is the outward unit normal.

use crate::math::Vec3;
use crate::scalar::{Param3, Scalar};

/// A BSDF.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Bsdf {
    /// Lambertian reflector, two-sided: `albedo / π` when `wi` and `wo` lie on the same side.
    Diffuse {
        /// Linear RGB albedo in `[0, 1]`.
        albedo: Param3,
    },
}

/// A direction sampled from a BSDF.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct BsdfSample {
    /// Unit incident direction (pointing away from the surface).
    pub wi: glam::Vec3,
    /// Density per steradian.
    pub pdf: f32,
}

impl Bsdf {
    /// `f(wi, wo)` (without the cosine), generic.
    pub fn eval<S: Scalar>(&self, n: Vec3<S>, wi: Vec3<S>, wo: Vec3<S>) -> Vec3<S> {
        let _ = (n, wi, wo);
        todo!("bsdf: eval")
    }
    /// Samples `wi` given `wo`.
    pub fn sample(&self, n: glam::Vec3, wo: glam::Vec3, u: glam::Vec2) -> Option<BsdfSample> {
        let _ = (n, wo, u);
        todo!("bsdf: sample")
    }
    /// Density of [`Bsdf::sample`] per steradian.
    pub fn pdf(&self, n: glam::Vec3, wo: glam::Vec3, wi: glam::Vec3) -> f32 {
        let _ = (n, wo, wi);
        todo!("bsdf: pdf")
    }
}
