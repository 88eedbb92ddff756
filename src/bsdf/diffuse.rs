//! The Lambertian reflector: `f = albedo / π` on both sides (a surface seen from behind reflects as
//! from the front), sampled with the cosine-weighted hemisphere on `wo`'s side.

use super::{Bsdf, BsdfSample};
use crate::declare::{Components, Field, Kind, Rule, on};
use crate::math::sampling::{cosine_hemisphere, cosine_hemisphere_pdf};
use crate::math::{Frame, Vec3};
use crate::scalar::{Param3, Scalar};
use std::f32::consts::FRAC_1_PI;

/// `albedo / π` when `wi` and `wo` lie on the same side of the surface, zero otherwise.
#[inline]
pub fn eval<S: Scalar>(albedo: &Param3, n: Vec3<S>, wi: Vec3<S>, wo: Vec3<S>) -> Vec3<S> {
    eval_with(albedo.get::<S>(), n, wi, wo)
}

/// [`eval`] with the albedo given as a value (a constant's or a texture's).
#[inline]
pub fn eval_with<S: Scalar>(albedo: Vec3<S>, n: Vec3<S>, wi: Vec3<S>, wo: Vec3<S>) -> Vec3<S> {
    let same_side = n.dot(wi).primal() * n.dot(wo).primal() > 0.0;
    if same_side {
        albedo * S::constant(FRAC_1_PI)
    } else {
        Vec3::zero()
    }
}

/// Cosine-weighted on `wo`'s side of the surface; `None` when `wo` lies in the tangent plane (no side
/// to scatter to).
#[inline]
pub fn sample(n: glam::Vec3, wo: glam::Vec3, u: glam::Vec2) -> Option<BsdfSample> {
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

/// `|cos θi| / π` on `wo`'s side, zero on the other.
#[inline]
pub fn pdf(n: glam::Vec3, wo: glam::Vec3, wi: glam::Vec3) -> f32 {
    let (ci, co) = (n.dot(wi), n.dot(wo));
    if ci * co > 0.0 {
        cosine_hemisphere_pdf(ci.abs())
    } else {
        0.0
    }
}

/// `{"type": "diffuse", "albedo": [r, g, b]}` (each in `[0, 1]`).
pub(super) const DIFFUSE: Kind<Bsdf> = Kind {
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
