//! The crease edges of primitives in closed form (docs/theory.md §7): a sharp box's twelve edges and a
//! sharp cylinder's two rims, wherever they sit in an SDF tree (under transforms, inside CSG), as curves
//! in the tree's coordinates together with the two faces that meet there.
//!
//! Each face is a function `F(x)` whose zero set is the face's plane (or the cylinder's side or cap)
//! near the edge: for a box face along axis `i` on side `s`, `F = s (x_i − c_i) − h_i`; for a cylinder
//! with axis `a`, `F = ρ − R` on its side and `F = s (x − c)·a − H` on its caps. The edge is
//! `{F_a = 0, F_b = 0}`; [`Sdf::face_value`] evaluates either function generically, through the
//! transforms above the primitive, so that the edge's motion under any parameter follows by AD.
//!
//! An edge of a primitive inside a CSG tree is on the tree's surface only where the other children leave
//! it there (a box edge inside a union's other child, or cut away by an intersection, is not): the
//! caller checks `φ ≈ 0` at each point it uses. Inside a subtracted child of a difference the solid lies
//! outside the primitive: the edge is concave and the surface's normal is `−∇F`
//! ([`CreaseEdge::inverted`]). Creases where two CSG children cross are listed with them as the
//! chords of their extracted curves ([`super::CrossingCrease`], faces [`Face::Child`]).

use super::creases::crossing_pairs;
use super::{CrossingCrease, Sdf, Similarity};
use crate::math::implicit_curve::CurveOptions;
use crate::math::{Aabb, Vec3};
use crate::scalar::Scalar;

/// One face of a primitive next to a crease edge.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Face {
    /// The box face `s (x_axis − c_axis) − h_axis = 0`, `positive` for `s = +1`.
    BoxSide {
        /// Axis index (0, 1, 2).
        axis: usize,
        /// Whether the face is on the positive side.
        positive: bool,
    },
    /// The cylinder's side `ρ − R = 0`.
    CylinderSide,
    /// A cylinder cap `s (x − c)·a − H = 0`, `positive` for `s = +1`.
    CylinderCap {
        /// Whether the cap is on the positive side of the axis.
        positive: bool,
    },
    /// Child `index` of a hard CSG node, `F = φ_child` (or `−φ_child` when `negated`): a face of the
    /// crease where two children cross ([`super::CrossingCrease`]).
    Child {
        /// Index of the child.
        index: usize,
        /// Whether `F = −φ_child`.
        negated: bool,
    },
}

/// The shape of a crease edge, in the coordinates of the tree it was listed from.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum EdgeCurve {
    /// The straight edge from `a` to `b`.
    Segment {
        /// First end.
        a: glam::Vec3,
        /// Second end.
        b: glam::Vec3,
    },
    /// A chord between two points of a crease not known in closed form (where two CSG children
    /// cross, [`super::CrossingCrease`]): samples on it are projected onto the crease
    /// ([`Sdf::crease_point`]).
    Chord {
        /// First end (on the crease).
        a: glam::Vec3,
        /// Second end (on the crease).
        b: glam::Vec3,
    },
    /// The circle `centre + radius (cos θ e1 + sin θ e2)`, `e1 ⊥ e2` unit vectors.
    Circle {
        /// Centre.
        centre: glam::Vec3,
        /// Radius.
        radius: f32,
        /// First in-plane axis.
        e1: glam::Vec3,
        /// Second in-plane axis.
        e2: glam::Vec3,
    },
}

impl EdgeCurve {
    /// Length (scene units).
    pub fn length(&self) -> f32 {
        match self {
            EdgeCurve::Segment { a, b } | EdgeCurve::Chord { a, b } => (*b - *a).length(),
            EdgeCurve::Circle { radius, .. } => std::f32::consts::TAU * radius,
        }
    }

    /// The point at fraction `u ∈ [0, 1)` of the length, and the unit tangent there (of the chord, for a
    /// [`EdgeCurve::Chord`]).
    pub fn at(&self, u: f32) -> (glam::Vec3, glam::Vec3) {
        match *self {
            EdgeCurve::Segment { a, b } | EdgeCurve::Chord { a, b } => {
                (a + (b - a) * u, (b - a).normalize_or_zero())
            }
            EdgeCurve::Circle {
                centre,
                radius,
                e1,
                e2,
            } => {
                let (s, c) = (std::f32::consts::TAU * u).sin_cos();
                (centre + (e1 * c + e2 * s) * radius, e2 * c - e1 * s)
            }
        }
    }
}

/// A crease edge of a primitive: its curve and the two faces meeting there, each reached from the
/// tree's root by `path` (the child taken at each CSG node on the way).
#[derive(Clone, Debug, PartialEq)]
pub struct CreaseEdge {
    /// The edge, in the tree's coordinates.
    pub curve: EdgeCurve,
    /// Child indices taken at the CSG nodes from the root to the primitive.
    pub path: Vec<usize>,
    /// The two faces meeting at the edge.
    pub faces: [Face; 2],
    /// Whether the tree's solid lies outside the primitive here (an odd number of subtracted
    /// [`Sdf::Difference`] children on the way): the surface's outward normal is then `−∇F` and the
    /// edge is concave (no line passes it clear on both sides).
    pub inverted: bool,
}

/// The similarities of the transforms above a node, outermost first: `x ↦ t + s R x` applied
/// innermost first.
#[derive(Clone, Debug, Default)]
struct Placement(Vec<Similarity>);

impl Placement {
    fn point(&self, p: glam::Vec3) -> glam::Vec3 {
        (self.0.iter().rev()).fold(p, |p, frame| frame.from_child_point(p.into()).into())
    }

    fn vector(&self, v: glam::Vec3) -> glam::Vec3 {
        (self.0.iter().rev()).fold(v, |v, frame| frame.from_child_vector(v.into()).into())
    }

    fn scale(&self) -> f32 {
        self.0.iter().map(Similarity::scale).product()
    }

    /// The box holding the finite box `b` (a node's coordinates) in the tree's coordinates.
    fn bounds(&self, b: &Aabb) -> Aabb {
        (b.corners().into_iter())
            .map(|c| self.point(c))
            .fold(Aabb::EMPTY, |b, p| b.union(&Aabb::new(p, p)))
    }
}

impl Sdf {
    /// The crease edges of the sharp boxes and cylinders in this tree (see the module docs of `sdf::crease_edges`), and
    /// the chords of the curves where hard CSG children cross ([`super::CrossingCrease::chords`], with
    /// the default extraction settings), in this node's coordinates. Empty when there are none. Creases
    /// between unbounded children that nothing in the tree bounds are left out: see
    /// [`Sdf::crease_edges_within`].
    pub fn crease_edges(&self) -> Vec<CreaseEdge> {
        self.crease_edges_within(&Aabb::INFINITE)
    }

    /// [`Sdf::crease_edges`], with the creases between unbounded children (two planes) that nothing in
    /// the tree bounds extracted within `region` (this node's coordinates; a finite box, or
    /// [`Aabb::INFINITE`] to leave them out).
    pub fn crease_edges_within(&self, region: &Aabb) -> Vec<CreaseEdge> {
        let found = self.find_creases(region);
        let mut edges = found.edges;
        for crossing in &found.crossings {
            edges.extend(crossing.chords(self, &CurveOptions::default()));
        }
        edges
    }

    /// Whether this tree has crease edges ([`Sdf::crease_edges`] not empty, or only curves too small
    /// for extraction to find, or creases between unbounded children), without extracting the crossings.
    pub fn has_crease_edges(&self) -> bool {
        let found = self.find_creases(&Aabb::INFINITE);
        !(found.edges.is_empty() && found.crossings.is_empty() && found.unbounded == 0)
    }

    /// The creases where two children of a hard CSG node cross, in this node's coordinates, before
    /// extraction (those between unbounded children as [`Sdf::crease_edges_within`] bounds them).
    pub fn crossing_creases_within(&self, region: &Aabb) -> Vec<CrossingCrease> {
        self.find_creases(region).crossings
    }

    /// The creases where two children of a hard CSG node cross, in this node's coordinates, before
    /// extraction (without those between unbounded children that nothing in the tree bounds).
    pub fn crossing_creases(&self) -> Vec<CrossingCrease> {
        self.crossing_creases_within(&Aabb::INFINITE)
    }

    /// The number of pairs of crossing children whose crease nothing in the tree bounds (two planes
    /// not cut by a bounded sibling or ancestor): [`Sdf::crease_edges_within`] needs a region for them.
    pub fn unbounded_crossings(&self) -> usize {
        self.find_creases(&Aabb::INFINITE).unbounded
    }

    /// The primitives' edges in closed form and the CSG crossings still to be extracted.
    fn find_creases(&self, region: &Aabb) -> Found {
        let mut out = Found::default();
        let mut walk = Walk {
            region: *region,
            ..Walk::default()
        };
        collect(self, &mut walk, &mut out);
        out
    }

    /// The face function `F(p)` of `face` of the primitive reached by `path` (see [`CreaseEdge`]), at
    /// `p` in this node's coordinates, generic (lifted parameters); `None` when `path` or `face` does
    /// not name a box or cylinder face of this tree.
    pub fn face_value<S: Scalar>(&self, path: &[usize], face: Face, p: Vec3<S>) -> Option<S> {
        match (self, face) {
            (Sdf::Named { child, .. }, _) => child.face_value(path, face, p),
            (
                Sdf::Transform {
                    translate,
                    axis,
                    angle,
                    scale,
                    child,
                    ..
                },
                _,
            ) => {
                let frame = Similarity::<S>::lifted(translate, *axis, angle, scale);
                // The zero set is what matters: the child's value is not rescaled.
                child.face_value(path, face, frame.to_child_point(p))
            }
            (
                Sdf::Union(children)
                | Sdf::Intersection(children)
                | Sdf::Difference(children)
                | Sdf::SmoothUnion { children, .. },
                Face::Child { index, negated },
            ) if path.is_empty() => {
                let v = children.get(index)?.eval(p);
                Some(if negated { -v } else { v })
            }
            (
                Sdf::Union(children)
                | Sdf::Intersection(children)
                | Sdf::Difference(children)
                | Sdf::SmoothUnion { children, .. },
                _,
            ) => {
                let (&first, rest) = path.split_first()?;
                children.get(first)?.face_value(rest, face, p)
            }
            (
                Sdf::Box {
                    center, half_size, ..
                },
                Face::BoxSide { axis, positive },
            ) if path.is_empty() && axis < 3 => {
                let d = p - center.get::<S>();
                let h = half_size.get::<S>();
                let (x, h) = match axis {
                    0 => (d.x, h.x),
                    1 => (d.y, h.y),
                    _ => (d.z, h.z),
                };
                Some(if positive { x } else { -x } - h)
            }
            (
                Sdf::Cylinder {
                    center,
                    axis,
                    radius,
                    half_height,
                    ..
                },
                _,
            ) if path.is_empty() => {
                let q = p - center.get::<S>();
                let h = q.dot_f32(*axis);
                match face {
                    Face::CylinderSide => {
                        let radial =
                            Vec3::new(q.x - h * axis.x, q.y - h * axis.y, q.z - h * axis.z);
                        Some(radial.length() - radius.get::<S>())
                    }
                    Face::CylinderCap { positive } => {
                        Some(if positive { h } else { -h } - half_height.get::<S>())
                    }
                    Face::BoxSide { .. } | Face::Child { .. } => None,
                }
            }
            _ => None,
        }
    }
}

impl Sdf {
    /// `∇F` of [`Sdf::face_value`] at `p` (this node's coordinates, `f32`, by forward-mode AD); zero
    /// when the face does not evaluate.
    pub fn face_gradient(&self, path: &[usize], face: Face, p: glam::Vec3) -> glam::Vec3 {
        super::gradient_by_ad(p, |q| self.face_value(path, face, q))
    }
}

/// Where [`collect`] is in the tree: the CSG children taken, the transforms above, whether the
/// solid is inverted (inside a subtracted child), the box the CSG nodes above leave the surface in
/// (`clip`, the intersection of their bounds), and the region given for unbounded creases, both in the
/// tree's coordinates.
struct Walk {
    path: Vec<usize>,
    place: Placement,
    inverted: bool,
    clip: Aabb,
    region: Aabb,
}

impl Default for Walk {
    fn default() -> Self {
        Self {
            path: Vec::new(),
            place: Placement::default(),
            inverted: false,
            clip: Aabb::INFINITE,
            region: Aabb::INFINITE,
        }
    }
}

/// What [`collect`] finds.
#[derive(Default)]
struct Found {
    edges: Vec<CreaseEdge>,
    crossings: Vec<CrossingCrease>,
    /// Pairs of crossing children whose crease neither the tree nor the region bounds (not listed).
    unbounded: usize,
}

fn collect(node: &Sdf, walk: &mut Walk, out: &mut Found) {
    match node {
        Sdf::Named { child, .. } => collect(child, walk, out),
        Sdf::Transform { .. } if let Some((frame, child)) = node.frame() => {
            walk.place.0.push(frame);
            collect(child, walk, out);
            walk.place.0.pop();
        }
        Sdf::Union(children)
        | Sdf::Intersection(children)
        | Sdf::Difference(children)
        | Sdf::SmoothUnion { children, .. } => {
            let subtracts = matches!(node, Sdf::Difference(_));
            // The node's surface lies in its bounds: a bounded child of an intersection (a ball)
            // bounds the crease of two planes beside it, and those of the CSG nodes below.
            let above = walk.clip;
            let bounds = node.bounds();
            if bounds.is_finite() {
                walk.clip = walk.clip.intersection(&walk.place.bounds(&bounds));
            }
            push_crossings(node, walk, out);
            for (i, c) in children.iter().enumerate() {
                let flip = subtracts && i > 0;
                walk.path.push(i);
                walk.inverted ^= flip;
                collect(c, walk, out);
                walk.inverted ^= flip;
                walk.path.pop();
            }
            walk.clip = above;
        }
        Sdf::Box {
            center,
            half_size,
            rounding,
        } if rounding.value <= 0.0 => {
            let (c, h) = (center.value(), half_size.value());
            for k in 0..3 {
                // The edges along axis k: the faces of the other two axes meet there.
                let (i, j) = ((k + 1) % 3, (k + 2) % 3);
                for (si, sj) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
                    let mut mid = c;
                    mid[i] += si * h[i];
                    mid[j] += sj * h[j];
                    let mut along = glam::Vec3::ZERO;
                    along[k] = h[k];
                    out.edges.push(CreaseEdge {
                        curve: EdgeCurve::Segment {
                            a: walk.place.point(mid - along),
                            b: walk.place.point(mid + along),
                        },
                        path: walk.path.clone(),
                        inverted: walk.inverted,
                        faces: [
                            Face::BoxSide {
                                axis: i,
                                positive: si > 0.0,
                            },
                            Face::BoxSide {
                                axis: j,
                                positive: sj > 0.0,
                            },
                        ],
                    });
                }
            }
        }
        Sdf::Cylinder {
            center,
            axis,
            radius,
            half_height,
            rounding,
        } if rounding.value <= 0.0 => {
            let e1 = axis.any_orthonormal_vector();
            let e2 = axis.cross(e1);
            for positive in [true, false] {
                let s = if positive { 1.0 } else { -1.0 };
                let centre = center.value() + *axis * (s * half_height.value);
                out.edges.push(CreaseEdge {
                    curve: EdgeCurve::Circle {
                        centre: walk.place.point(centre),
                        radius: radius.value * walk.place.scale(),
                        e1: walk.place.vector(e1).normalize_or_zero(),
                        e2: walk.place.vector(e2).normalize_or_zero(),
                    },
                    path: walk.path.clone(),
                    inverted: walk.inverted,
                    faces: [Face::CylinderSide, Face::CylinderCap { positive }],
                });
            }
        }
        _ => {}
    }
}

/// The crossings of `node`'s children if it is a hard CSG node (see [`CrossingCrease`] for the faces'
/// signs): each pair whose surfaces may meet inside a bounded common box, or, for two unbounded
/// children, inside the box the CSG nodes above leave (`walk.clip`), else inside the region given.
fn push_crossings(node: &Sdf, walk: &Walk, out: &mut Found) {
    // Locally the solid is {F_a < 0 and F_b < 0} (convex) or, inverted, its complement.
    let (children, negate, inverted): (&[Sdf], fn(usize) -> bool, bool) = match node {
        Sdf::Intersection(c) => (c.as_slice(), |_| false, false),
        Sdf::Difference(c) => (c.as_slice(), |i| i > 0, false),
        Sdf::Union(c) => (c.as_slice(), |_| true, true),
        Sdf::SmoothUnion { children, k } if k.value <= 0.0 => (children.as_slice(), |_| true, true),
        _ => return,
    };
    for (i, j, common) in crossing_pairs(children) {
        let bounds = if common.is_finite() {
            walk.place.bounds(&common)
        } else if walk.clip.is_finite() {
            walk.clip
        } else {
            let bounds = walk.region.intersection(&walk.clip);
            if !bounds.is_finite() {
                out.unbounded += 1;
                continue;
            }
            bounds
        };
        if bounds.is_empty() {
            continue;
        }
        out.crossings.push(CrossingCrease {
            path: walk.path.clone(),
            faces: [i, j].map(|index| Face::Child {
                index,
                negated: negate(index),
            }),
            inverted: walk.inverted ^ inverted,
            bounds,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sharp_box() -> Sdf {
        Sdf::Box {
            center: [0.1, -0.2, 0.3].into(),
            half_size: [0.5, 0.7, 0.9].into(),
            rounding: 0.0.into(),
        }
    }

    fn transformed(child: Sdf) -> Sdf {
        Sdf::Transform {
            translate: [1.0, 2.0, -0.5].into(),
            axis: glam::Vec3::new(1.0, 2.0, 3.0).normalize(),
            angle: 37.0.into(),
            scale: 1.7.into(),
            trig: super::super::AngleTrig::of(37.0),
            child: Box::new(child),
        }
    }

    /// Every edge point lies on both faces and on the surface, whatever the transforms above it.
    #[test]
    fn edges_lie_on_both_faces_and_the_surface() {
        let cylinder = Sdf::Cylinder {
            center: [0.0, 0.5, 0.0].into(),
            axis: glam::Vec3::new(0.3, 1.0, 0.2).normalize(),
            radius: 0.4.into(),
            half_height: 0.6.into(),
            rounding: 0.0.into(),
        };
        for (sdf, count, total) in [
            (sharp_box(), 12, 4.0 * 2.0 * (0.5 + 0.7 + 0.9)),
            (
                transformed(sharp_box()),
                12,
                1.7 * 4.0 * 2.0 * (0.5 + 0.7 + 0.9),
            ),
            (
                transformed(Sdf::union(vec![
                    Sdf::sphere([5.0, 0.0, 0.0], 0.5),
                    cylinder,
                ])),
                2,
                1.7 * 2.0 * std::f32::consts::TAU * 0.4,
            ),
        ] {
            let edges = sdf.crease_edges();
            assert_eq!(edges.len(), count);
            let length: f32 = edges.iter().map(|e| e.curve.length()).sum();
            assert!((length - total).abs() < 1e-4 * total, "{length} vs {total}");
            for e in &edges {
                for u in [0.0, 0.13, 0.5, 0.97] {
                    let (x, tangent) = e.curve.at(u);
                    assert!(sdf.eval_f32(x).abs() < 1e-5, "φ = {}", sdf.eval_f32(x));
                    for face in e.faces {
                        let f: f32 = sdf.face_value(&e.path, face, Vec3::from(x)).unwrap();
                        assert!(f.abs() < 1e-5, "{face:?}: {f}");
                        // The tangent keeps both faces at zero (to second order on a circle).
                        let ahead: f32 = sdf
                            .face_value(&e.path, face, Vec3::from(x + tangent * 1e-3))
                            .unwrap();
                        assert!(ahead.abs() < 1e-5, "{face:?} along the tangent: {ahead}");
                    }
                }
            }
        }
    }

    /// A box subtracted from a sphere leaves concave edges (inverted); subtracting twice restores them.
    /// The crossing of the ball and the box is convex (the solid lies outside the box there).
    #[test]
    fn subtracted_edges_are_inverted() {
        let ball = Sdf::sphere([0.0; 3], 1.0);
        let box_edges = |sdf: &Sdf| -> Vec<CreaseEdge> {
            let edges = sdf.crease_edges();
            edges
                .into_iter()
                .filter(|e| !matches!(e.faces[0], Face::Child { .. }))
                .collect()
        };
        let notch = Sdf::difference(vec![ball.clone(), sharp_box()]);
        let edges = box_edges(&notch);
        assert_eq!(edges.len(), 12);
        assert!(edges.iter().all(|e| e.inverted && e.path == [1]));
        let crossings = notch.crossing_creases();
        assert_eq!(crossings.len(), 1);
        assert!(!crossings[0].inverted && crossings[0].path.is_empty());
        let faces = crossings[0].faces;
        assert_eq!(
            faces,
            [
                Face::Child {
                    index: 0,
                    negated: false
                },
                Face::Child {
                    index: 1,
                    negated: true
                }
            ]
        );
        let twice = Sdf::difference(vec![ball.clone(), notch]);
        assert!(
            box_edges(&twice)
                .iter()
                .all(|e| !e.inverted && e.path == [1, 1])
        );
        // The notch's own crossing, inside the subtracted child, is concave.
        let inner = twice.crossing_creases();
        assert!(inner.iter().any(|c| c.path == [1] && c.inverted));
        let kept = Sdf::difference(vec![sharp_box(), ball.clone()]);
        assert!(
            box_edges(&kept)
                .iter()
                .all(|e| !e.inverted && e.path == [0])
        );
        // A hard union's crossing is concave, with both children negated.
        let union = Sdf::union(vec![ball, sharp_box()]);
        let c = union.crossing_creases();
        assert_eq!(c.len(), 1);
        assert!(c[0].inverted);
        assert!(
            (c[0].faces)
                .iter()
                .all(|f| matches!(f, Face::Child { negated: true, .. }))
        );
    }

    #[test]
    fn rounded_and_smooth_primitives_have_no_edges() {
        let rounded = Sdf::Box {
            center: [0.0; 3].into(),
            half_size: [1.0; 3].into(),
            rounding: 0.1.into(),
        };
        assert!(rounded.crease_edges().is_empty());
        assert!(Sdf::sphere([0.0; 3], 1.0).crease_edges().is_empty());
        assert!(
            sharp_box()
                .face_value::<f32>(&[0], Face::CylinderSide, Vec3::from(glam::Vec3::ZERO))
                .is_none()
        );
    }
}
