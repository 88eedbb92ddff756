//! Enclosures over boxes kept for the boxes asked about again.
//!
//! The silhouette culling of a shape ([`crate::integrator::silhouette_boxes`]) encloses `φ` and `∇φ`
//! over octree boxes; only the last step (`ψ = ∇φ·(c − x)`) depends on the view. The six views of an
//! inverse-rendering iteration share their shape (the grid changes only between iterations), and about
//! half of the boxes one view encloses another has enclosed already (the boxes along the surface where
//! their silhouettes pass near each other, and the coarse levels). The memo keeps each box's enclosure,
//! computed once: the same numbers as computing it again, so nothing downstream changes.

use super::IntervalGrad;
use crate::math::Aabb;
use std::collections::HashMap;
use std::sync::Mutex;

/// At most this many boxes are kept (about 30 MB); past it the memo starts over (a shape that outlives
/// many views, as in a turntable of renders).
const CAPACITY: usize = 1 << 18;

/// The enclosures of one shape's `φ` and `∇φ` over boxes, keyed by the box and the shape's translation
/// (bit for bit): `None` where the plain interval or the gradient enclosure's value excludes 0 (the box
/// holds no surface), else the gradient enclosure. Derived data of the shape it is built with (like
/// [`crate::sdf::EmptySpace`]): built anew whenever the shape is, never shared with another SDF. Two
/// memos compare equal (they are caches, not part of the shape's value).
#[derive(Default)]
pub struct EnclosureMemo {
    boxes: Mutex<HashMap<[u32; 9], Option<IntervalGrad>>>,
}

impl EnclosureMemo {
    /// The entry of the box `b` seen with the shape translated by `translate`: the kept one, or
    /// `compute()` (kept for the next time). `compute` runs outside the lock; two threads asking for the
    /// same new box both compute it, with the same result.
    pub fn get_or_compute(
        &self,
        b: &Aabb,
        translate: glam::Vec3,
        compute: impl FnOnce() -> Option<IntervalGrad>,
    ) -> Option<IntervalGrad> {
        let key = [
            b.min.x,
            b.min.y,
            b.min.z,
            b.max.x,
            b.max.y,
            b.max.z,
            translate.x,
            translate.y,
            translate.z,
        ]
        .map(f32::to_bits);
        if let Some(&kept) = self.lock().get(&key) {
            return kept;
        }
        let value = compute();
        let mut boxes = self.lock();
        if boxes.len() >= CAPACITY {
            boxes.clear();
        }
        boxes.insert(key, value);
        value
    }

    /// The map, even after a panic elsewhere poisoned the lock (entries are inserted whole).
    fn lock(&self) -> std::sync::MutexGuard<'_, HashMap<[u32; 9], Option<IntervalGrad>>> {
        self.boxes.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The number of boxes kept.
    pub fn len(&self) -> usize {
        self.lock().len()
    }

    /// Whether no box is kept.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl PartialEq for EnclosureMemo {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl std::fmt::Debug for EnclosureMemo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "EnclosureMemo({} boxes)", self.len())
    }
}
