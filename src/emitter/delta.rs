//! Delta lights: a point light and a directional light (the sun), Mitsuba 3's `point` and
//! `directional` emitters.
//!
//! # Radiometry
//!
//! A point light at `y` with radiant intensity `I` (W/sr) gives a surface point `x` (unit normal `n`)
//! the irradiance `E(x) = I |n·ω| / |y − x|²`, `ω = (y − x)/|y − x|`; a sun travelling along `d`
//! with irradiance `E⊥` (W/m² on a surface facing it) gives `E(x) = E⊥ |n·ω|`, `ω = −d/|d|`. The light
//! reflected towards `wo` is `f(x; ω, wo) E(x)`: next-event estimation finds it with one deterministic
//! "sample" of density 1 (times the probability of choosing the light) and multiple importance
//! sampling weight 1, since no BSDF-sampled ray can hit a delta light (Veach 1997, §9.2.4).
//!
//! # Derivatives
//!
//! `position`, `intensity`, `direction` and `irradiance` are parameters. The arrival direction and the
//! irradiance factor are evaluated in the generic scalar ([`Emitter::delta_arrival`]): the point
//! light's attached position `y(π)` moves `ω` and `1/r²`; the sun's `d(π)` is normalised in `S`, so a
//! derivative along `d` itself (which leaves the direction unchanged) is 0. Visibility stays at its
//! sampled value; the hard shadow edge it leaves out is a secondary boundary term
//! ([`crate::integrator::boundary::delta_shadows`]).

use super::{Emitter, EmitterSample};
use crate::math::Vec3;
use crate::scalar::Scalar;

/// The parts of a delta light that shade a point: see [`Emitter::delta_arrival`].
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Arrival<S> {
    /// Unit direction from the shaded point towards the light.
    pub wi: Vec3<S>,
    /// Irradiance per unit cosine at the shaded point: `I / r²` (point), `E⊥` (sun).
    pub irradiance: Vec3<S>,
}

impl Emitter {
    /// True for delta lights (point and directional): reached by shadow rays only, never by BSDF or
    /// camera rays, invisible and non-blocking.
    pub fn is_delta(&self) -> bool {
        matches!(self, Emitter::Point { .. } | Emitter::Directional { .. })
    }

    /// A delta light's unit travel direction at its primal value, from `x`: away from a point light's
    /// position (`None` at the position itself), the sun's normalised direction (`None` for other
    /// emitters).
    pub fn delta_travel(&self, x: glam::Vec3) -> Option<glam::Vec3> {
        match self {
            Emitter::Point { position, .. } => (x - position.value()).try_normalize(),
            Emitter::Directional { direction, .. } => direction.value().try_normalize(),
            _ => None,
        }
    }

    /// The light arriving at `x` from a delta light, generic (see the module docs): the unit
    /// direction towards it and the irradiance per unit cosine. `y` is the point light's attached
    /// position (ignored for the sun). Zero for other emitters and at a point light's own position.
    pub fn delta_arrival<S: Scalar>(&self, x: Vec3<S>, y: Vec3<S>) -> Arrival<S> {
        match self {
            Emitter::Point { intensity, .. } => {
                let to = y - x;
                let r2 = to.length_squared();
                if !(r2.primal() > 0.0 && r2.primal().is_finite()) {
                    return Arrival::none();
                }
                Arrival {
                    wi: to * (S::one() / r2.sqrt()),
                    irradiance: intensity.get::<S>() * (S::one() / r2),
                }
            }
            Emitter::Directional {
                direction,
                irradiance,
            } => Arrival {
                wi: -direction.get::<S>().normalize_or_zero(),
                irradiance: irradiance.get::<S>(),
            },
            _ => Arrival::none(),
        }
    }

    /// The point of the light's ray through the attached point `x` at depth `depth`, generic: from a
    /// point light at attached position `y`, `y + depth·(x − y)/|x − y|` (`depth` from the light);
    /// along the sun's direction `ω(π)`, `x − depth·ω` (`depth` back from `x`). The shadow edge's
    /// tangency residual is the occluder's `φ` there (the secondary term of delta lights). `x` itself
    /// for other emitters.
    pub fn ray_point<S: Scalar>(&self, y: Vec3<S>, x: Vec3<S>, depth: f32) -> Vec3<S> {
        match self {
            Emitter::Point { .. } => y + (x - y).normalize_or_zero() * S::constant(depth),
            Emitter::Directional { direction, .. } => {
                x - direction.get::<S>().normalize_or_zero() * S::constant(depth)
            }
            _ => x,
        }
    }

    /// Next-event "sampling" of a delta light from `reference`: the one direction towards it, density
    /// 1 (a delta), the light's position as `p` (for the sun `reference + wi`) and `dist` (infinite for
    /// the sun); `None` at a point light's own position or for a zero direction.
    pub fn sample_delta_li(&self, reference: glam::Vec3) -> Option<EmitterSample> {
        match self {
            Emitter::Point { position, .. } => {
                let to = position.value() - reference;
                let dist = to.length();
                let wi = to.try_normalize()?;
                Some(EmitterSample {
                    wi,
                    dist,
                    p: position.value(),
                    n: -wi,
                    pdf: 1.0,
                })
            }
            Emitter::Directional { direction, .. } => {
                let wi = -direction.value().try_normalize()?;
                Some(EmitterSample {
                    wi,
                    dist: f32::INFINITY,
                    p: reference + wi,
                    n: -wi,
                    pdf: 1.0,
                })
            }
            _ => None,
        }
    }
}

impl<S: Scalar> Arrival<S> {
    fn none() -> Self {
        Self {
            wi: Vec3::zero(),
            irradiance: Vec3::zero(),
        }
    }
}
