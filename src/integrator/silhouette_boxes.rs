//! Certified culling for the primary boundary: boxes that may hold a silhouette point seen from the camera.
//!
//! Seen from the camera centre `c`, the silhouette (contour generator) of a shape is the curve
//! `{φ = 0, ψ = 0}` with `ψ(x) = ∇φ(x)·(c − x)`: surface points whose tangent plane holds the eye (docs/theory.md
//! §4.2; supplemental §2). An octree over the shape's bounds discards a box `B` when interval
//! arithmetic proves `0 ∉ φ(B)` (no surface) or `0 ∉ ψ(B)` (surface, but no silhouette), with
//! `ψ(B) ⊂ Σ_k ∇_kφ(B) · (c_k − B_k)` from [`IntervalGrad`] enclosures of the gradient
//! ([`crate::sdf::interval`]). Every silhouette point lies in a returned box; the boxes around a curve
//! number about twice as many per level, their volume about a quarter.
//!
//! The shape's rigid `translate` is honoured by evaluating through [`Shape::eval`] in world coordinates.
//!
//! **Grid shapes.** Two shortcuts, neither of which keeps a box the enclosures alone would cull: a box
//! whose lattice cells are all empty ([`crate::sdf::EmptySpace::box_cells`]: each cell's control points
//! on one side of the level) holds no surface and is culled without interval arithmetic; and the
//! enclosures of `φ` and `∇φ`, which do not depend on the view, are computed once per box for all the
//! views of the shape ([`Shape::enclosures`], [`crate::sdf::interval::EnclosureMemo`]). On a lattice-aligned
//! grid (the inverse-rendering case) the kept boxes are exactly those of the enclosures alone; under a
//! rotation the cell map may cull boxes that the enclosures (looser around a rotated box) keep, boxes
//! without surface points, so the extracted curve is the same (`tests/empty_space.rs`).
//!
//! **Seen along a direction.** A delta light's shadow edges are the silhouettes seen from its position
//! (a point light: the perspective case above) or along its direction (the sun: orthographic,
//! [`View::Along`]), where `ψ(x) = ∇φ(x)·(−ω)` with `ω` the unit direction the light travels: the same
//! curve with `c − x` replaced by the constant `−ω`, and `∇ψ = H(−ω)` without the `−∇φ` term.

use crate::error::{Error, Result};
use crate::math::implicit_curve::octree_leaves;
use crate::math::{Aabb, Vec3};
use crate::scene::Shape;
use crate::sdf::BoxCells;
use crate::sdf::interval::{Interval, IntervalGrad};

/// What interval arithmetic proves about a box.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum BoxClass {
    /// `0 ∉ φ(B)`: the box holds no surface point.
    NoSurface,
    /// `0 ∉ ψ(B)`: the box may hold surface points, but none of them is a silhouette point seen from the eye.
    NoSilhouette,
    /// Neither could be proven: the box may hold a silhouette point.
    Kept,
}

/// Where a silhouette is seen from.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum View {
    /// From a point (a camera centre, a point light): perspective.
    Point(glam::Vec3),
    /// Along a unit direction `ω` (the way the sun's light travels): orthographic.
    Along(glam::Vec3),
}

impl View {
    /// The vector `e(x)` of `ψ = ∇φ·e`: `c − x` from a point, `−ω` along a direction.
    #[inline]
    pub fn towards(self, x: glam::Vec3) -> glam::Vec3 {
        match self {
            View::Point(c) => c - x,
            View::Along(w) => -w,
        }
    }

    /// The same view in a frame whose origin is at `origin` (a point moves, a direction does not).
    pub fn relative_to(self, origin: glam::Vec3) -> View {
        match self {
            View::Point(c) => View::Point(c - origin),
            View::Along(w) => View::Along(w),
        }
    }
}

/// Classify the world-space box `b` for the silhouette of `shape` seen from `eye`.
pub fn classify_box(shape: &Shape, eye: glam::Vec3, b: &Aabb) -> BoxClass {
    classify_box_in(shape, View::Point(eye), b)
}

/// [`classify_box`] for any [`View`].
pub fn classify_box_in(shape: &Shape, view: View, b: &Aabb) -> BoxClass {
    let t = shape.translate.value();
    // A grid shape's map of straddling cells settles the boxes in empty cells without interval
    // arithmetic (the spline there is a convex combination of control points all on one side of the
    // level); where interval arithmetic would not discard them too, they still hold no surface.
    if let Some(space) = shape.empty_space.as_deref()
        && space.box_cells(&Aabb::new(b.min - t, b.max - t)) == BoxCells::Empty
    {
        return BoxClass::NoSurface;
    }
    let surface = || surface_enclosure(shape, b);
    let phi = match shape.enclosures.as_deref() {
        Some(memo) => memo.get_or_compute(b, t, surface),
        None => surface(),
    };
    let Some(phi) = phi else {
        return BoxClass::NoSurface;
    };
    let psi = (0..3).fold(Interval::ZERO, |acc, k| {
        let to_eye = match view {
            View::Point(eye) => {
                Interval::point(eye[k] as f64) - Interval::from_f32(b.min[k], b.max[k])
            }
            View::Along(w) => Interval::point(-w[k] as f64),
        };
        acc + phi.g[k] * to_eye
    });
    if !psi.contains_zero() {
        return BoxClass::NoSilhouette;
    }
    BoxClass::Kept
}

/// The enclosure of `φ` and `∇φ` over `b` (world space) when the box may hold surface points, `None`
/// when interval arithmetic proves `0 ∉ φ(B)`: what [`classify_box_in`] needs of the shape, whatever
/// the view.
fn surface_enclosure(shape: &Shape, b: &Aabb) -> Option<IntervalGrad> {
    // The plain interval first: a quarter of the cost, and it settles most of the empty space.
    let x = Vec3::new(
        Interval::from_f32(b.min.x, b.max.x),
        Interval::from_f32(b.min.y, b.max.y),
        Interval::from_f32(b.min.z, b.max.z),
    );
    if !shape.eval(x).contains_zero() {
        return None;
    }
    let phi = shape.eval(IntervalGrad::seed_box(b));
    phi.v.contains_zero().then_some(phi)
}

/// The leaves of an octree over `shape.bounds` that may hold a point of the silhouette seen from `eye`.
///
/// A box is split into its eight octants until depth `max_depth` or until its longest edge is at most
/// `min_size`; a box is dropped as soon as [`classify_box`] proves it holds no silhouette point. Every point
/// of `{φ = 0, ψ = 0}` inside the bounds lies in one of the returned boxes (closed boxes: a point on a shared
/// face may be in either). Levels are processed in parallel; the order of the result is deterministic.
///
/// Errors if the shape is unbounded (e.g. a plane): the octree needs a finite root.
pub fn silhouette_boxes(
    shape: &Shape,
    eye: glam::Vec3,
    max_depth: u32,
    min_size: f32,
) -> Result<Vec<Aabb>> {
    silhouette_boxes_in(shape, View::Point(eye), max_depth, min_size)
}

/// [`silhouette_boxes`] for any [`View`].
pub fn silhouette_boxes_in(
    shape: &Shape,
    view: View,
    max_depth: u32,
    min_size: f32,
) -> Result<Vec<Aabb>> {
    let root = shape.bounds;
    if root.is_empty() {
        return Ok(Vec::new());
    }
    if !root.is_finite() {
        return Err(Error::Unsupported(format!(
            "silhouette boxes of shape '{}': unbounded shapes (planes) have no finite octree root",
            shape.name
        )));
    }
    Ok(octree_leaves(root, max_depth, min_size, |b| {
        classify_box_in(shape, view, b) == BoxClass::Kept
    }))
}
