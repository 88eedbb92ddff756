//! Light sources: a one-sided rectangle, a sphere and a constant environment.

use crate::math::{Ray, Vec3};
use crate::scalar::{Param, Param3, Scalar};

/// An emitter. Finite emitters are also surfaces that block light and are seen by rays.
#[derive(Clone, Debug, PartialEq)]
pub enum Emitter {
    /// One-sided rectangle emitting along `normal`, spanned by `u` and `v = normal × u`.
    Rectangle {
        /// Centre.
        center: Param3,
        /// Unit normal: the side that emits.
        normal: glam::Vec3,
        /// Unit first edge direction (orthogonal to `normal`).
        u: glam::Vec3,
        /// Edge lengths along `u` and `v`.
        size: [Param; 2],
        /// Emitted radiance (linear RGB, W·m⁻²·sr⁻¹ in scene units).
        radiance: Param3,
    },
    /// Sphere emitting outward uniformly.
    Sphere {
        /// Centre.
        center: Param3,
        /// Radius (> 0).
        radius: Param,
        /// Emitted radiance.
        radiance: Param3,
    },
    /// Constant radiance arriving from every direction at infinity.
    Constant {
        /// Radiance.
        radiance: Param3,
    },
}

/// A point sampled on an emitter for next-event estimation from a reference point.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct EmitterSample {
    /// Unit direction from the reference point towards the emitter.
    pub wi: glam::Vec3,
    /// Distance to the sampled point (`f32::INFINITY` for the environment).
    pub dist: f32,
    /// The sampled point (meaningless for the environment).
    pub p: glam::Vec3,
    /// Unit normal at the sampled point (meaningless for the environment).
    pub n: glam::Vec3,
    /// Density per steradian at the reference point.
    pub pdf: f32,
}

impl Emitter {
    /// Nearest intersection `(t, outward normal)` of `ray` with a finite emitter in `(0, t_max)`.
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<(f32, glam::Vec3)> {
        let _ = (ray, t_max);
        todo!("emitter: intersect")
    }
    /// Samples a direction towards the emitter from `reference`.
    pub fn sample_li(&self, reference: glam::Vec3, u: glam::Vec2) -> Option<EmitterSample> {
        let _ = (reference, u);
        todo!("emitter: sample_li")
    }
    /// Density per steradian of [`Emitter::sample_li`] from `reference` to the point `p` (normal `n`) it
    /// would have produced (`p` ignored for the environment, where `wi` alone matters).
    pub fn pdf_li(
        &self,
        reference: glam::Vec3,
        wi: glam::Vec3,
        p: glam::Vec3,
        n: glam::Vec3,
    ) -> f32 {
        let _ = (reference, wi, p, n);
        todo!("emitter: pdf_li")
    }
    /// Radiance leaving point `p` (normal `n`) in direction `w` (away from the emitter), generic.
    pub fn emitted<S: Scalar>(&self, p: Vec3<S>, n: Vec3<S>, w: Vec3<S>) -> Vec3<S> {
        let _ = (p, n, w);
        todo!("emitter: emitted")
    }
    /// True for emitters at infinity.
    pub fn is_infinite(&self) -> bool {
        matches!(self, Emitter::Constant { .. })
    }
}
