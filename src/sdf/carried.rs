//! Known motions of nodes: where a point of a node's surface is carried when the selected parameters
//! change, for the velocity fields of docs/theory.md §8.
//!
//! The normal field `x = p + V n` is exact for every parameter, but its area factor `∂πJ = κV` is
//! heavy-tailed where the curvature is large (a thin torus, a small rounding radius). A node whose
//! parameters move it in a known way carries each point of its surface along that motion instead:
//! a translation or rotation rigidly (no change of area), a torus's major radius by shifting points
//! radially (area change `1/ρ`, bounded), a sphere's or capsule's radius along the normal. The carried
//! position `X(q; π)` is written once, generic over the scalar type, so that the spatial gradient dual
//! ([`crate::scalar::Grad`]) gives its Jacobian `∂X/∂q` and hence the surface divergence of the motion
//! ([`crate::integrator::attach`]).
//!
//! A motion is known for primitives, similarity transforms and names over them, and for any subtree
//! whose parameters are not selected (it stays in place). CSG with a moving child is not: the parts of
//! its surface move differently and meet along creases or blends, where a carried field would tear;
//! such trees keep the normal field ([`Sdf::carried`] returns `None`).

use super::{Sdf, Similarity};
use crate::math::Vec3;
use crate::scalar::{Param, Param3, Scalar};

impl Sdf {
    /// Whether a geometric parameter of this node or of a node below it is selected (slot or grid
    /// direction): whether the node's surface moves in the current pass.
    pub fn moves(&self) -> bool {
        let mut any = false;
        self.visit_params("", &mut |_, p: &Param| any |= p.slot.is_some());
        any || self.grid_values_selected()
    }

    /// The position `X(q; π)` to which the node's motion carries a point `q` of its surface (node
    /// coordinates, parameters lifted into `S`), or `None` where no motion is known (see the
    /// module docs of `sdf::carried`). At the primal `X(q) = q` up to rounding; a surface point is carried onto
    /// the moved surface to first order (`∂π φ(X(q; π); π) = 0`).
    pub fn carried<S: Scalar>(&self, q: Vec3<S>) -> Option<Vec3<S>> {
        if !self.moves() {
            return Some(q);
        }
        match self {
            Sdf::Sphere { center, radius } => {
                let c = center.value();
                Some(center.get::<S>() + (q - Vec3::constant(c)) * scale_of::<S>(radius))
            }
            Sdf::Torus {
                center,
                axis,
                major_radius,
                minor_radius,
            } => {
                // The tube's centre circle moves with the centre and the major radius; the point keeps
                // its place on the tube's cross-section, scaled with the minor radius.
                let w = q - Vec3::constant(center.value());
                let h = w.dot_f32(*axis);
                let radial = w - Vec3::constant(*axis) * h;
                let out = radial.normalize_or_zero();
                let ring = out * S::constant(major_radius.value);
                Some(
                    center.get::<S>()
                        + out * major_radius.get::<S>()
                        + (w - ring) * scale_of::<S>(minor_radius),
                )
            }
            Sdf::Primitive(primitive) => primitive.carried(q),
            Sdf::Box {
                center,
                half_size,
                rounding,
            } => rigid_centre(
                q,
                center,
                &[&half_size.c[0], &half_size.c[1], &half_size.c[2], rounding],
            ),
            Sdf::Cylinder {
                center,
                radius,
                half_height,
                rounding,
                ..
            } => rigid_centre(q, center, &[radius, half_height, rounding]),
            Sdf::Plane { normal, offset } => {
                Some(q + Vec3::constant(*normal) * (offset.get::<S>() - offset.value))
            }
            Sdf::Transform {
                translate,
                axis,
                angle,
                scale,
                ..
            } => {
                // Into the child's frame with the primal transform, carried there, and back out with
                // the lifted one.
                let (primal, child) = self.frame()?;
                let moved = child.carried(primal.constant::<S>().to_child_point(q))?;
                Some(
                    Similarity::<S>::lifted(translate, *axis, angle, scale).from_child_point(moved),
                )
            }
            Sdf::Named { child, .. } => child.carried(q),
            Sdf::Union(_)
            | Sdf::Intersection(_)
            | Sdf::Difference(_)
            | Sdf::SmoothUnion { .. }
            | Sdf::Grid { .. } => None,
        }
    }

    /// An upper bound of the magnitude of the total curvature `κ` of the node's surface (1/length;
    /// infinite where none is known: creases, grids), which decides where a carried motion pays
    /// ([`crate::integrator::attach`]).
    pub fn curvature_bound(&self) -> f32 {
        let inv = |r: f32| if r > 0.0 { 1.0 / r } else { f32::INFINITY };
        match self {
            Sdf::Sphere { radius, .. } => 2.0 * inv(radius.value),
            Sdf::Primitive(primitive) => primitive.curvature_bound(),
            Sdf::Torus {
                major_radius,
                minor_radius,
                ..
            } => inv(minor_radius.value) + inv(major_radius.value - minor_radius.value),
            Sdf::Box { rounding, .. } | Sdf::Cylinder { rounding, .. } => 2.0 * inv(rounding.value),
            Sdf::Plane { .. } => 0.0,
            Sdf::Union(children) | Sdf::Intersection(children) | Sdf::Difference(children) => {
                (children.iter()).fold(0.0, |k, c| k.max(c.curvature_bound()))
            }
            // The blend of the cubic smooth minimum bends with radius of order k.
            Sdf::SmoothUnion { children, k } => {
                (children.iter()).fold(2.0 * inv(k.value), |b, c| b.max(c.curvature_bound()))
            }
            Sdf::Transform { scale, child, .. } => child.curvature_bound() * inv(scale.value),
            Sdf::Grid { .. } => f32::INFINITY,
            Sdf::Named { child, .. } => child.curvature_bound(),
        }
    }
}

/// `r_S / r`: 1 with the derivative of the relative change of `r`.
fn scale_of<S: Scalar>(r: &Param) -> S {
    r.get::<S>() / r.value
}

/// A node moved rigidly with its centre, when none of its `sizes` is selected.
fn rigid_centre<S: Scalar>(q: Vec3<S>, center: &Param3, sizes: &[&Param]) -> Option<Vec3<S>> {
    (sizes.iter().all(|p| p.slot.is_none()))
        .then(|| q - Vec3::constant(center.value()) + center.get::<S>())
}
