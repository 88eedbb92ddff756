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
#[inline(always)]
pub(super) fn cuboid<S: Scalar>(
    p: Vec3<S>,
    center: &Param3,
    half_size: &Param3,
    rounding: &Param,
) -> S {
    let r = rounding.get::<S>();
    let q = (p - center.get::<S>()).abs() - half_size.get::<S>() + Vec3::splat(r);
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
#[inline(always)]
pub(super) fn cylinder<S: Scalar>(
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
    let ox = dx.max(S::zero());
    let oy = dy.max(S::zero());
    dx.max(dy).min(S::zero()) + (ox * ox + oy * oy).safe_sqrt() - rb
}

/// Capsule: distance to the segment `a`–`b` minus `r`; the projection parameter is clamped to `[0, 1]`
/// (a degenerate segment `a = b` is a sphere).
#[inline(always)]
pub(super) fn capsule<S: Scalar>(p: Vec3<S>, a: &Param3, b: &Param3, radius: &Param) -> S {
    let a = a.get::<S>();
    let pa = p - a;
    let ba = b.get::<S>() - a;
    let bb = ba.length_squared();
    let t = if bb.primal() > 0.0 {
        (pa.dot(ba) / bb).clamp(0.0, 1.0)
    } else {
        S::zero()
    };
    (pa - ba * t).length() - radius.get::<S>()
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

/// Box of a capsule: the segment's box grown by the radius.
pub(super) fn capsule_bounds(a: &Param3, b: &Param3, radius: &Param) -> Aabb {
    let (a, b) = (a.value(), b.value());
    Aabb::new(a.min(b), a.max(b)).expanded(radius.value.abs())
}
