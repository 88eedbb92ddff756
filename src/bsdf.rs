//! Surface scattering. Directions point away from the surface; `n` is the outward unit normal.

use crate::declare::{Components, Family, Field, Kind, Rule, on};
use crate::error::{Error, FieldPath};
use crate::math::sampling::{cosine_hemisphere, cosine_hemisphere_pdf};
use crate::math::{Frame, Vec3};
use crate::scalar::{Param3, Scalar};
use std::f32::consts::FRAC_1_PI;

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
    /// The broken rules of the BSDF's fields (an albedo in `[0, 1]`), named by `at`; empty when valid.
    /// The rules are the material kind's declaration ([`crate::declare::Kind`]).
    pub fn validate(&self, at: FieldPath) -> Vec<Error> {
        crate::declare::violations(self, at)
    }

    /// `f(wi, wo)` (without the cosine), generic.
    ///
    /// The side test looks at primal values only: the jump of `f` where `wi` crosses the tangent plane is
    /// a visibility-like discontinuity whose derivative belongs to the boundary terms, not to this one.
    #[inline]
    pub fn eval<S: Scalar>(&self, n: Vec3<S>, wi: Vec3<S>, wo: Vec3<S>) -> Vec3<S> {
        match self {
            Bsdf::Diffuse { albedo } => {
                let same_side = n.dot(wi).primal() * n.dot(wo).primal() > 0.0;
                if same_side {
                    albedo.get::<S>() * S::constant(FRAC_1_PI)
                } else {
                    Vec3::zero()
                }
            }
        }
    }

    /// Samples `wi` given `wo`: cosine-weighted on `wo`'s side of the surface. `None` when `wo` lies in
    /// the tangent plane (no side to scatter to).
    #[inline]
    pub fn sample(&self, n: glam::Vec3, wo: glam::Vec3, u: glam::Vec2) -> Option<BsdfSample> {
        match self {
            Bsdf::Diffuse { .. } => {
                let cos_o = n.dot(wo);
                if cos_o == 0.0 || !cos_o.is_finite() {
                    return None;
                }
                let side_n = if cos_o > 0.0 { n } else { -n };
                let local = cosine_hemisphere(u);
                let pdf = cosine_hemisphere_pdf(local.z);
                if pdf <= 0.0 {
                    return None;
                }
                let wi = Frame::from_normal(side_n).to_world(local);
                Some(BsdfSample { wi, pdf })
            }
        }
    }

    /// Density of [`Bsdf::sample`] per steradian: `|cos θi| / π` on `wo`'s side, zero on the other.
    #[inline]
    pub fn pdf(&self, n: glam::Vec3, wo: glam::Vec3, wi: glam::Vec3) -> f32 {
        match self {
            Bsdf::Diffuse { .. } => {
                let (ci, co) = (n.dot(wi), n.dot(wo));
                if ci * co > 0.0 {
                    cosine_hemisphere_pdf(ci.abs())
                } else {
                    0.0
                }
            }
        }
    }

    /// The albedo's primal value (for quick checks that a material reflects at all).
    #[inline]
    pub fn albedo(&self) -> glam::Vec3 {
        match self {
            Bsdf::Diffuse { albedo } => albedo.value(),
        }
    }
}

/// Every material kind ([`crate::declare`]), in the order the scene file's errors list them.
const KINDS: &[&Kind<Bsdf>] = &[&DIFFUSE];

impl Family for Bsdf {
    fn kinds() -> &'static [&'static Kind<Bsdf>] {
        KINDS
    }

    fn kind(&self) -> &'static Kind<Bsdf> {
        match self {
            Bsdf::Diffuse { .. } => &DIFFUSE,
        }
    }
}

/// `{"type": "diffuse", "albedo": [r, g, b]}` (each in `[0, 1]`).
const DIFFUSE: Kind<Bsdf> = Kind {
    type_name: "diffuse",
    fields: &[Field::vector(
        "albedo",
        on!(Bsdf::Diffuse { albedo } => albedo),
        Components::Rgb,
        None,
        Rule::UnitInterval,
    )],
    blank: || Bsdf::Diffuse {
        albedo: Param3::from(glam::Vec3::ZERO),
    },
    example: r#"{"type": "diffuse", "albedo": [0.6, 0.5, 0.3]}"#,
};
