//! Interval enclosures of `φ(B)` and `∇φ(B)` over boxes, for culling.
//!
//! The number types live in [`crate::scalar::interval`] (re-exported here); [`Sdf::eval`] runs on them
//! unchanged. The node formulas that branch on a value depending on the point have dedicated enclosures,
//! reached through [`Scalar::enclosure`](crate::scalar::Scalar::enclosure) (point types get `None` and run
//! the formula itself): the smooth minimum (its early exit outside the blend; in `sdf/csg.rs`) and grids
//! (which cell, inside the grid box or not: a box can span several cells and faces; `grid.rs` here). The other
//! primal branches in `src/sdf` test parameters only (the capsule's `|b − a|² > 0`, a transform's angle
//! and scale), which are exact constants here.

use super::Sdf;
use crate::math::{Aabb, Vec3};

mod grid;
mod memo;

pub use crate::scalar::interval::{Enclosure, Interval, IntervalGrad};
pub(super) use grid::GridEnclosure;
pub use memo::EnclosureMemo;

impl Sdf {
    /// Enclosure of `φ(B)` over the box `b` (the node's own coordinates).
    pub fn enclose(&self, b: &Aabb) -> Interval {
        self.eval(Vec3::new(
            Interval::from_f32(b.min.x, b.max.x),
            Interval::from_f32(b.min.y, b.max.y),
            Interval::from_f32(b.min.z, b.max.z),
        ))
    }

    /// Enclosures of `φ(B)` and `∇φ(B)` over the box `b` (the node's own coordinates).
    pub fn enclose_gradient(&self, b: &Aabb) -> IntervalGrad {
        self.eval(IntervalGrad::seed_box(b))
    }
}
