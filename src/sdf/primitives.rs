//! Primitive shapes: exact signed distances (Quílez, "distance functions", iquilezles.org) written once,
//! generic over the scalar type, plus their bounding boxes.
//!
//! Axes of revolution (torus, cylinder) need no frame: the axial coordinate is `h = q·a` and the radial
//! vector `q − h a`, so nothing has to be cached per node and the formulas stay exact for any unit `a`.

use crate::math::{Aabb, Vec3};
use crate::scalar::{Param, Param3, Scalar};

/// Sphere: `|p − c| − r`. At the centre the gradient is zero (by `safe_sqrt`), not NaN.
#[inline(always)]
pub(super) fn sphere<S: Scalar>(p: Vec3<S>, center: &Param3, radius: &Param) -> S {
    (p - center.get::<S>()).length() - radius.get::<S>()
}

/// Rounded box with outer half extents `b` and edge radius `r`: the box of half extents `b − r`
/// dilated by `r`. `q = |p − c| − b + r`; `φ = |max(q, 0)| + min(max_i q_i, 0) − r`.
///
/// With `FACES` and `r = 0` (a sharp box), the field of its faces `max_i q_i` ([`super::Sdf::eval_faces`]).
#[inline(always)]
pub(super) fn cuboid<S: Scalar, const FACES: bool>(
    p: Vec3<S>,
    center: &Param3,
    half_size: &Param3,
    rounding: &Param,
) -> S {
    let r = rounding.get::<S>();
    let q = (p - center.get::<S>()).abs() - half_size.get::<S>() + Vec3::splat(r);
    if FACES && rounding.value == 0.0 {
        return q.max_element() - r;
    }
    q.max_f32(0.0).length() + q.max_element().min(S::zero()) - r
}

/// Axial coordinate `h = q·a` and radial distance `ρ = |q − h a|` of `q` about the unit axis `a`.
#[inline(always)]
fn axial_radial<S: Scalar>(q: Vec3<S>, a: glam::Vec3) -> (S, S) {
    let h = q.dot_f32(a);
    // The radial vector, not sqrt(|q|² − h²): no cancellation near the axis.
    let radial = Vec3::new(q.x - h * a.x, q.y - h * a.y, q.z - h * a.z);
    (h, radial.length())
}

/// Torus: `sqrt((ρ − R)² + h²) − r` with `ρ`, `h` the radial and axial coordinates about `axis`.
#[inline(always)]
pub(super) fn torus<S: Scalar>(
    p: Vec3<S>,
    center: &Param3,
    axis: glam::Vec3,
    major: &Param,
    minor: &Param,
) -> S {
    let (h, rho) = axial_radial(p - center.get::<S>(), axis);
    let d = rho - major.get::<S>();
    (d * d + h * h).safe_sqrt() - minor.get::<S>()
}

/// Capped cylinder, rims rounded by `rb` with the outer radius and height kept (shrink by `rb`, dilate by
/// `rb`): `d = (ρ − R + rb, |h| − H + rb)`, `φ = min(max(d), 0) + |max(d, 0)| − rb`.
///
/// With `FACES` and `rb = 0` (sharp rims), the field of its side and caps `max(d)`
/// ([`super::Sdf::eval_faces`]).
#[inline(always)]
pub(super) fn cylinder<S: Scalar, const FACES: bool>(
    p: Vec3<S>,
    center: &Param3,
    axis: glam::Vec3,
    radius: &Param,
    half_height: &Param,
    rounding: &Param,
) -> S {
    let (h, rho) = axial_radial(p - center.get::<S>(), axis);
    let rb = rounding.get::<S>();
    let dx = rho - radius.get::<S>() + rb;
    let dy = h.abs() - half_height.get::<S>() + rb;
    if FACES && rounding.value == 0.0 {
        return dx.max(dy) - rb;
    }
    let ox = dx.max(S::zero());
    let oy = dy.max(S::zero());
    dx.max(dy).min(S::zero()) + (ox * ox + oy * oy).safe_sqrt() - rb
}

/// Half-space: `n·p − offset`.
#[inline(always)]
pub(super) fn plane<S: Scalar>(p: Vec3<S>, normal: glam::Vec3, offset: &Param) -> S {
    p.dot_f32(normal) - offset.get::<S>()
}

/// `sqrt(1 − a_i²)` per component: the half extent along world axis `i` of a unit circle about `a`.
fn circle_extent(a: glam::Vec3) -> glam::Vec3 {
    (glam::Vec3::ONE - a * a)
        .max(glam::Vec3::ZERO)
        .map(f32::sqrt)
}

/// Box of a sphere.
pub(super) fn sphere_bounds(center: &Param3, radius: &Param) -> Aabb {
    Aabb::around(center.value(), glam::Vec3::splat(radius.value.abs()))
}

/// Box of a (rounded) box: rounding keeps the outer extents.
pub(super) fn cuboid_bounds(center: &Param3, half_size: &Param3) -> Aabb {
    Aabb::around(center.value(), half_size.value().abs())
}

/// Box of a torus: the centre circle (radius `R`, half extent `R sqrt(1 − a_i²)` along axis `i`) grown by
/// the tube radius.
pub(super) fn torus_bounds(
    center: &Param3,
    axis: glam::Vec3,
    major: &Param,
    minor: &Param,
) -> Aabb {
    let r = circle_extent(axis) * major.value.abs() + glam::Vec3::splat(minor.value.abs());
    Aabb::around(center.value(), r)
}

/// Box of a capped cylinder: the axis segment plus the rim disk.
pub(super) fn cylinder_bounds(
    center: &Param3,
    axis: glam::Vec3,
    radius: &Param,
    half_height: &Param,
) -> Aabb {
    let r = axis.abs() * half_height.value.abs() + circle_extent(axis) * radius.value.abs();
    Aabb::around(center.value(), r)
}

/// The declarations of the primitives' fields ([`crate::declare`]).
pub(super) mod kinds {
    use crate::declare::{Components::Xyz, Field, Kind, Rule, on};
    use crate::scalar::Param3;
    use crate::sdf::Sdf;

    fn zero3() -> Param3 {
        Param3::from(glam::Vec3::ZERO)
    }

    /// `{"type": "sphere", "center": [x, y, z], "radius": r}`.
    pub(in crate::sdf) const SPHERE: Kind<Sdf> = Kind {
        type_name: "sphere",
        fields: &[
            Field::point("center", on!(Sdf::Sphere { center, .. } => center)),
            Field::number(
                "radius",
                on!(Sdf::Sphere { radius, .. } => radius),
                None,
                Rule::Positive,
            ),
        ],
        blank: || Sdf::sphere(zero3(), 0.0),
        example: r#"{"type": "sphere", "center": [0, 0.5, 0], "radius": 0.5}"#,
    };

    /// `{"type": "box", "center", "half_size", "rounding" (default 0, at most the smallest half size)}`.
    pub(in crate::sdf) const BOX: Kind<Sdf> = Kind {
        type_name: "box",
        fields: &[
            Field::point("center", on!(Sdf::Box { center, .. } => center)),
            Field::vector(
                "half_size",
                on!(Sdf::Box { half_size, .. } => half_size),
                Xyz,
                None,
                Rule::Positive,
            ),
            Field::number(
                "rounding",
                on!(Sdf::Box { rounding, .. } => rounding),
                Some(0.0),
                Rule::Relation {
                    ok: |n, v| (0.0..=box_rounding_limit(n)).contains(&v),
                    text: |n| format!("must be in [0, {}]", box_rounding_limit(n)),
                },
            ),
        ],
        blank: || Sdf::cuboid(zero3(), zero3(), 0.0),
        example: r#"{"type": "box", "center": [0, 0.4, 0], "half_size": [0.4, 0.3, 0.5], "rounding": 0.05}"#,
    };

    /// The largest rounding of a box: its smallest half size (0 if one is negative, which is reported
    /// on its own).
    fn box_rounding_limit(n: &Sdf) -> f32 {
        match n {
            Sdf::Box { half_size, .. } => half_size.value().min_element().max(0.0),
            _ => unreachable!("a box's rule"),
        }
    }

    /// `{"type": "torus", "center", "axis", "major_radius" (> minor_radius), "minor_radius" (> 0)}`.
    pub(in crate::sdf) const TORUS: Kind<Sdf> = Kind {
        type_name: "torus",
        fields: &[
            Field::point("center", on!(Sdf::Torus { center, .. } => center)),
            Field::direction("axis", on!(Sdf::Torus { axis, .. } => axis)),
            Field::number(
                "major_radius",
                on!(Sdf::Torus { major_radius, .. } => major_radius),
                None,
                Rule::Relation {
                    ok: |n, v| v > torus_minor(n),
                    text: |n| format!("must be > minor_radius ({})", torus_minor(n)),
                },
            ),
            Field::number(
                "minor_radius",
                on!(Sdf::Torus { minor_radius, .. } => minor_radius),
                None,
                Rule::Positive,
            ),
        ],
        blank: || Sdf::torus(zero3(), glam::Vec3::Y, 0.0, 0.0),
        example: r#"{"type": "torus", "center": [0, 0.3, 0], "axis": [0, 1, 0], "major_radius": 0.6, "minor_radius": 0.2}"#,
    };

    fn torus_minor(n: &Sdf) -> f32 {
        match n {
            Sdf::Torus { minor_radius, .. } => minor_radius.value,
            _ => unreachable!("a torus's rule"),
        }
    }

    /// `{"type": "cylinder", "center", "axis", "radius", "half_height", "rounding" (default 0, at most
    /// the radius and the half height)}`.
    pub(in crate::sdf) const CYLINDER: Kind<Sdf> = Kind {
        type_name: "cylinder",
        fields: &[
            Field::point("center", on!(Sdf::Cylinder { center, .. } => center)),
            Field::direction("axis", on!(Sdf::Cylinder { axis, .. } => axis)),
            Field::number(
                "radius",
                on!(Sdf::Cylinder { radius, .. } => radius),
                None,
                Rule::Positive,
            ),
            Field::number(
                "half_height",
                on!(Sdf::Cylinder { half_height, .. } => half_height),
                None,
                Rule::Positive,
            ),
            Field::number(
                "rounding",
                on!(Sdf::Cylinder { rounding, .. } => rounding),
                Some(0.0),
                Rule::Relation {
                    ok: |n, v| (0.0..=cylinder_rounding_limit(n)).contains(&v),
                    text: |n| format!("must be in [0, {}]", cylinder_rounding_limit(n)),
                },
            ),
        ],
        blank: || Sdf::cylinder(zero3(), glam::Vec3::Y, 0.0, 0.0, 0.0),
        example: r#"{"type": "cylinder", "center": [0, 0.5, 0], "axis": [0, 1, 0], "radius": 0.4, "half_height": 0.5, "rounding": 0.1}"#,
    };

    /// The largest rounding of a cylinder: the smaller of its radius and half height (0 if negative).
    fn cylinder_rounding_limit(n: &Sdf) -> f32 {
        match n {
            Sdf::Cylinder {
                radius,
                half_height,
                ..
            } => radius.value.min(half_height.value).max(0.0),
            _ => unreachable!("a cylinder's rule"),
        }
    }

    /// `{"type": "plane", "normal", "offset"}`: the half-space `normal · p <= offset`.
    pub(in crate::sdf) const PLANE: Kind<Sdf> = Kind {
        type_name: "plane",
        fields: &[
            Field::direction("normal", on!(Sdf::Plane { normal, .. } => normal)),
            Field::number(
                "offset",
                on!(Sdf::Plane { offset, .. } => offset),
                None,
                Rule::Any,
            ),
        ],
        blank: || Sdf::plane(glam::Vec3::Y, 0.0),
        example: r#"{"type": "plane", "normal": [0, 1, 0], "offset": 0}"#,
    };
}
