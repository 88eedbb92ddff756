//! The capsule: points within `radius` of the segment `a`–`b`. Everything about it is here (its
//! distance, bounds, known motion, curvature bound and scene-file declaration); it is registered with
//! one line in the sdf module's list of primitives ([`super::Primitive`]).

use super::primitive::SdfPrimitive;
use super::{Primitive, Sdf};
use crate::declare::{Field, Kind, Rule, on};
use crate::math::{Aabb, Vec3};
use crate::scalar::{Param, Param3, Scalar};

/// Points within `radius` of the segment `a`–`b` (a sphere when `a = b`).
#[derive(Clone, Debug, PartialEq)]
pub struct Capsule {
    /// First end of the segment.
    pub a: Param3,
    /// Second end of the segment.
    pub b: Param3,
    /// Radius (> 0).
    pub radius: Param,
}

impl SdfPrimitive for Capsule {
    /// Distance to the segment minus the radius; the projection parameter is clamped to `[0, 1]` (a
    /// degenerate segment `a = b` is a sphere).
    #[inline(always)]
    fn eval<S: Scalar>(&self, p: Vec3<S>) -> S {
        let a = self.a.get::<S>();
        let pa = p - a;
        let ba = self.b.get::<S>() - a;
        let bb = ba.length_squared();
        let t = if bb.primal() > 0.0 {
            (pa.dot(ba) / bb).clamp(0.0, 1.0)
        } else {
            S::zero()
        };
        (pa - ba * t).length() - self.radius.get::<S>()
    }

    /// The segment's box grown by the radius.
    fn bounds(&self) -> Aabb {
        let (a, b) = (self.a.value(), self.b.value());
        Aabb::new(a.min(b), a.max(b)).expanded(self.radius.value.abs())
    }

    fn is_convex(&self) -> bool {
        true
    }

    /// The nearest point of the segment moves with its ends at the same segment parameter; the offset
    /// from it scales with the radius.
    fn carried<S: Scalar>(&self, q: Vec3<S>) -> Option<Vec3<S>> {
        let (a0, b0) = (self.a.value(), self.b.value());
        let ba = b0 - a0;
        let bb = ba.length_squared();
        let t = if bb > 0.0 {
            ((q - Vec3::constant(a0)).dot_f32(ba) / bb).clamp(0.0, 1.0)
        } else {
            S::zero()
        };
        let (a_s, b_s) = (self.a.get::<S>(), self.b.get::<S>());
        let axis_point = a_s + (b_s - a_s) * t;
        let rest = Vec3::constant(a0) + Vec3::constant(ba) * t;
        Some(axis_point + (q - rest) * (self.radius.get::<S>() / self.radius.value))
    }

    /// A sphere's: its caps are half spheres and its side a cylinder (curvature `1/r`).
    fn curvature_bound(&self) -> f32 {
        let r = self.radius.value;
        2.0 * if r > 0.0 { 1.0 / r } else { f32::INFINITY }
    }
}

impl Sdf {
    /// A capsule around the segment `a`–`b`.
    pub fn capsule(a: impl Into<Param3>, b: impl Into<Param3>, radius: impl Into<Param>) -> Self {
        Sdf::Primitive(Primitive::Capsule(Capsule {
            a: a.into(),
            b: b.into(),
            radius: radius.into(),
        }))
    }
}

/// `{"type": "capsule", "a": [x, y, z], "b": [x, y, z], "radius": r}`.
pub(super) const KIND: Kind<Sdf> = Kind {
    type_name: "capsule",
    fields: &[
        Field::point("a", on!(Sdf::Primitive(Primitive::Capsule(Capsule { a, .. })) => a)),
        Field::point("b", on!(Sdf::Primitive(Primitive::Capsule(Capsule { b, .. })) => b)),
        Field::number(
            "radius",
            on!(Sdf::Primitive(Primitive::Capsule(Capsule { radius, .. })) => radius),
            None,
            Rule::Positive,
        ),
    ],
    blank: || {
        let zero = Param3::from(glam::Vec3::ZERO);
        Sdf::capsule(zero, zero, 0.0)
    },
    example: r#"{"type": "capsule", "a": [-0.5, 0.3, 0], "b": [0.5, 0.3, 0], "radius": 0.3}"#,
};
