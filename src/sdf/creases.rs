//! Which nodes have crease edges (docs/theory.md §7): curves where the surface normal jumps. A
//! crease seen from the camera or from a light is a boundary curve of its own (its image moves with the
//! parameters, and the visibility jumps across it), which the silhouette-based boundary terms do not
//! sample. The edges of sharp primitives and the crossings of hard CSG children with bounded common
//! boxes have their own estimators ([`Sdf::crease_edges`]); a crease no finite box in the tree holds
//! (hard CSG of unbounded children, [`Sdf::unsampled_creases`]) is sampled within a region the caller
//! chooses, who must say that the terms beyond it are missing rather than drop them silently.
//!
//! - **Primitives**: a box or a cylinder with `rounding = 0` has sharp edges (the box's twelve edges, the
//!   cylinder's two rims). Spheres, tori, capsules and planes have none (the capsule is C1 where its
//!   cylinder meets its caps, with no normal jump); grids are C2.
//! - **Hard CSG** (`min`/`max`): where two children's surfaces cross, the active child switches and the
//!   normal jumps. Children whose surfaces cannot meet make no crease: [`surfaces_may_meet`] proves it
//!   with interval enclosures of both `φ` over the common part of their boxes, subdivided
//!   ([`MEET_DEPTH`] levels). It is conservative: surfaces that touch (or nearly touch, within the
//!   enclosures' looseness) count as crossing, and a crease of a child that another child hides (a sharp
//!   box intersected away) is still reported. A smooth union with `k ≤ 0` is a hard union.
//! - Transforms, names and smooth unions keep their children's creases.

use super::Sdf;
use crate::math::Aabb;

/// Subdivision levels of [`surfaces_may_meet`]: boxes `1/64` of the common box's size. Only boxes that
/// hold both surfaces are split, a band around their crossing curve: a few thousand enclosures at most.
const MEET_DEPTH: u32 = 6;

impl Sdf {
    /// Why the surface `φ = 0` of this node may have crease edges (normal discontinuities), e.g. `"sharp
    /// box (rounding 0)"`, or `None` if it has none. Several reasons are joined by `"; "`.
    ///
    /// Exact for primitives (a box or cylinder with `rounding = 0`); conservative for hard CSG (union,
    /// intersection, difference, and the smooth union with `k ≤ 0`): a crease is reported when two
    /// children's surfaces may cross, which [`surfaces_may_meet`] disproves with interval enclosures
    /// (touching surfaces count as crossing; a child's crease hidden by another child is still
    /// reported). Transforms, names (prefixed `"name: "`) and smooth unions keep their children's
    /// creases.
    pub fn creases(&self) -> Option<String> {
        self.crease_reasons()
    }

    /// The crease curves of this node that no finite box in the tree holds: the creases where two
    /// unbounded children of hard CSG cross (two planes) and no bounded child or ancestor cuts them
    /// ([`Sdf::unbounded_crossings`]). The estimators sample them only within a region the caller
    /// gives ([`Sdf::crease_edges_within`]); the edges of sharp boxes, the rims of sharp cylinders and
    /// bounded crossings are sampled whole. `None` when there are none.
    pub fn unsampled_creases(&self) -> Option<String> {
        (self.unbounded_crossings() > 0).then(|| {
            "hard CSG of unbounded children (planes) whose crease no bounded child cuts".into()
        })
    }

    /// All reasons.
    fn crease_reasons(&self) -> Option<String> {
        let mut reasons = Vec::new();
        self.collect_creases(&mut reasons);
        reasons.dedup();
        (!reasons.is_empty()).then(|| reasons.join("; "))
    }

    /// Pushes this node's crease reasons.
    fn collect_creases(&self, out: &mut Vec<String>) {
        let mut push = |s: String| {
            if !out.contains(&s) {
                out.push(s);
            }
        };
        match self {
            Sdf::Box { rounding, .. } if rounding.value <= 0.0 => {
                push("sharp box (rounding 0)".into());
            }
            Sdf::Cylinder { rounding, .. } if rounding.value <= 0.0 => {
                push("cylinder with sharp rims (rounding 0)".into());
            }
            Sdf::Union(children) => hard_csg(children, "union", out),
            Sdf::Intersection(children) => hard_csg(children, "intersection", out),
            Sdf::Difference(children) => hard_csg(children, "difference", out),
            Sdf::SmoothUnion { children, k } if k.value <= 0.0 => {
                hard_csg(children, "smooth union with k = 0, i.e.", out);
            }
            Sdf::SmoothUnion { children, .. } => {
                for c in children {
                    c.collect_creases(out);
                }
            }
            Sdf::Transform { child, .. } => child.collect_creases(out),
            Sdf::Named { name, child } => {
                let mut inner = Vec::new();
                child.collect_creases(&mut inner);
                for r in inner {
                    let r = format!("{name}: {r}");
                    if !out.contains(&r) {
                        out.push(r);
                    }
                }
            }
            _ => {}
        }
    }
}

/// The children's own creases, then one reason for the node if two children's surfaces may cross.
fn hard_csg(children: &[Sdf], op: &str, out: &mut Vec<String>) {
    for c in children {
        c.collect_creases(out);
    }
    let r = format!("hard {op} of children whose surfaces cross");
    if !crossing_pairs(children).is_empty() && !out.contains(&r) {
        out.push(r);
    }
}

/// The pairs `(i, j)`, `i < j`, of children whose surfaces may cross ([`surfaces_may_meet`]), with their
/// common box (unbounded for two unbounded children).
pub(super) fn crossing_pairs(children: &[Sdf]) -> Vec<(usize, usize, Aabb)> {
    let mut pairs = Vec::new();
    for i in 0..children.len() {
        for j in i + 1..children.len() {
            if surfaces_may_meet(&children[i], &children[j]) {
                let common = children[i].bounds().intersection(&children[j].bounds());
                pairs.push((i, j, common));
            }
        }
    }
    pairs
}

/// Whether the surfaces `φ_a = 0` and `φ_b = 0` (same coordinates) may have a common point: `false` is
/// certain (interval enclosures over boxes holding both surfaces' candidates), `true` may be a false
/// alarm (surfaces closer than the finest box, or unbounded boxes, which are not subdivided).
pub fn surfaces_may_meet(a: &Sdf, b: &Sdf) -> bool {
    let common = a.bounds().intersection(&b.bounds());
    if common.is_empty() {
        return false;
    }
    if !common.is_finite() {
        // Two unbounded children (planes): a crossing unless the enclosure over the whole space
        // excludes zero, which it cannot be relied on to do.
        return true;
    }
    meet_in(a, b, &common, MEET_DEPTH)
}

fn meet_in(a: &Sdf, b: &Sdf, bx: &Aabb, depth: u32) -> bool {
    if !a.enclose(bx).contains_zero() || !b.enclose(bx).contains_zero() {
        return false;
    }
    if depth == 0 {
        return true;
    }
    let c = bx.center();
    (0..8).any(|i| {
        let pick = |bit: u32, lo: f32, mid: f32, hi: f32| {
            if i & bit == 0 { (lo, mid) } else { (mid, hi) }
        };
        let (x0, x1) = pick(1, bx.min.x, c.x, bx.max.x);
        let (y0, y1) = pick(2, bx.min.y, c.y, bx.max.y);
        let (z0, z1) = pick(4, bx.min.z, c.z, bx.max.z);
        meet_in(
            a,
            b,
            &Aabb::new(glam::Vec3::new(x0, y0, z0), glam::Vec3::new(x1, y1, z1)),
            depth - 1,
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sharp_box(c: [f32; 3], h: f32) -> Sdf {
        Sdf::Box {
            center: c.into(),
            half_size: [h; 3].into(),
            rounding: 0.0.into(),
        }
    }

    #[test]
    fn primitives() {
        assert_eq!(Sdf::sphere([0.0; 3], 1.0).creases(), None);
        assert_eq!(
            sharp_box([0.0; 3], 1.0).creases().as_deref(),
            Some("sharp box (rounding 0)")
        );
        let rounded = Sdf::Box {
            center: [0.0; 3].into(),
            half_size: [1.0; 3].into(),
            rounding: 0.1.into(),
        };
        assert_eq!(rounded.creases(), None);
        let cyl = |r: f32| Sdf::Cylinder {
            center: [0.0; 3].into(),
            axis: glam::Vec3::Y,
            radius: 1.0.into(),
            half_height: 1.0.into(),
            rounding: r.into(),
        };
        assert!(cyl(0.0).creases().unwrap().contains("cylinder"));
        assert_eq!(cyl(0.2).creases(), None);
        let plane = Sdf::Plane {
            normal: glam::Vec3::Y,
            offset: 0.0.into(),
        };
        assert_eq!(plane.creases(), None);
    }

    #[test]
    fn hard_csg_creases_only_where_surfaces_cross() {
        let (a, b) = (
            Sdf::sphere([0.0; 3], 1.0),
            Sdf::sphere([1.5, 0.0, 0.0], 1.0),
        );
        let far = Sdf::sphere([5.0, 0.0, 0.0], 1.0);
        let crossing = Sdf::union(vec![a.clone(), b.clone()]).creases().unwrap();
        assert!(crossing.contains("hard union"), "{crossing}");
        assert_eq!(Sdf::union(vec![a.clone(), far.clone()]).creases(), None);
        // Boxes overlap but the surfaces do not cross: a small sphere deep inside a big one.
        let inner = Sdf::sphere([0.1, 0.0, 0.0], 0.3);
        assert_eq!(Sdf::union(vec![a.clone(), inner.clone()]).creases(), None);
        assert_eq!(Sdf::intersection(vec![a.clone(), inner]).creases(), None);
        assert!(
            Sdf::difference(vec![a.clone(), b.clone()])
                .creases()
                .unwrap()
                .contains("hard difference")
        );
        // A sphere resting above a floor plane (no contact) versus sunk into it.
        let floor = Sdf::Plane {
            normal: glam::Vec3::Y,
            offset: (-1.2f32).into(),
        };
        assert_eq!(Sdf::union(vec![a.clone(), floor.clone()]).creases(), None);
        let sunk = Sdf::Plane {
            normal: glam::Vec3::Y,
            offset: (-0.5f32).into(),
        };
        assert!(Sdf::union(vec![a.clone(), sunk]).creases().is_some());
        // k = 0 smooth union is a hard union; k > 0 has no crease of its own.
        assert!(
            Sdf::smooth_union(vec![a.clone(), b.clone()], 0.0)
                .creases()
                .is_some()
        );
        assert_eq!(
            Sdf::smooth_union(vec![a.clone(), b.clone()], 0.3).creases(),
            None
        );
    }

    #[test]
    fn reasons_pass_through_transforms_names_and_smooth_unions() {
        let boxed = Sdf::named(
            "lid",
            Sdf::transform(
                sharp_box([0.0; 3], 0.5),
                [1.0, 0.0, 0.0],
                glam::Vec3::Z,
                30.0,
                2.0,
            ),
        );
        let s = Sdf::smooth_union(vec![Sdf::sphere([9.0, 0.0, 0.0], 1.0), boxed], 0.3)
            .creases()
            .unwrap();
        assert_eq!(s, "lid: sharp box (rounding 0)");
        // Several reasons, each once.
        let two = Sdf::union(vec![
            sharp_box([0.0; 3], 1.0),
            sharp_box([1.5, 0.0, 0.0], 1.0),
            sharp_box([9.0, 0.0, 0.0], 1.0),
        ])
        .creases()
        .unwrap();
        assert_eq!(
            two,
            "sharp box (rounding 0); hard union of children whose surfaces cross"
        );
    }
}
