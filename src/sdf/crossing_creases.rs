//! Creases where two children of a hard CSG node cross (docs/theory.md §7.1): the curve
//! `{φ_a = 0, φ_b = 0}` of the two children's surfaces, found as the silhouettes are found (interval-
//! culled octree, crossings on box faces, chords refined onto the curve;
//! [`crate::math::implicit_curve`]) and sampled by projecting points of its chords onto it, with the
//! exact density per unit length that projection gives.
//!
//! **Faces and orientation.** The crease's two faces are the children's signed distances with signs
//! chosen so that the solid near the crease is `{F_a < 0} ∩ {F_b < 0}` (a convex crease) or its
//! complement (a concave one, [`CreaseEdge::inverted`]): an intersection keeps both (`F = φ`, convex), a
//! difference negates the subtracted children (`F = −φ`: the solid lies outside them, convex), a hard
//! union negates both and is concave (its solid is the complement of `{−φ_a < 0} ∩ {−φ_b < 0}`). Inside a
//! subtracted child the whole picture flips once more. With these signs the crease is an edge like a
//! box's: the same estimators sample it ([`Face::Child`]).
//!
//! **Where the curve is the surface's.** With more than two children a third may cover the curve or
//! cut it away, and a CSG node above may do the same: as for the primitives' edges, the caller checks
//! `φ ≈ 0` at each point it uses.
//!
//! **Frame.** The curve is extracted in the tree's own coordinates (the shape's, its translation
//! removed), through the transforms above the node ([`Sdf::face_value`]): there the coordinates have the
//! magnitude of the shape wherever the shape is placed. The octree's root is the children's common box
//! mapped to those coordinates and padded unevenly, so that a face of a child lying in a face of the
//! common box (a box minus a ball: the crease lies in the box's faces, which bound the common box) does
//! not lie in a face of any octree box, where the crossing search on that plane would be singular.

use super::Sdf;
use super::crease_edges::{CreaseEdge, EdgeCurve, Face};
use crate::math::implicit_curve::{
    CurveFunctions, CurveOptions, Polyline, extract_polyline, octree_leaves, project_from_chord,
};
use crate::math::{Aabb, Vec3};
use crate::scalar::interval::Interval;

/// A crease where two children of a hard CSG node may cross, before extraction.
#[derive(Clone, Debug, PartialEq)]
pub struct CrossingCrease {
    /// Child indices taken at the CSG nodes from the root to the node whose children cross.
    pub path: Vec<usize>,
    /// The two children as faces ([`Face::Child`], signed as the module docs say).
    pub faces: [Face; 2],
    /// Whether the crease is concave (see [`CreaseEdge::inverted`]).
    pub inverted: bool,
    /// A box holding the whole curve, in the tree's coordinates.
    pub bounds: Aabb,
}

/// Padding of the octree's root on its low and high sides, as fractions of its size (uneven: see the
/// module docs).
const ROOT_PADDING: [f32; 2] = [0.0137, 0.0091];

impl CrossingCrease {
    /// The crease's two face functions in `sdf` (the tree this crossing was listed from).
    fn functions<'a>(&'a self, sdf: &'a Sdf) -> FacePair<'a> {
        FacePair {
            sdf,
            path: &self.path,
            faces: self.faces,
        }
    }

    /// The extracted curve as a polyline in the tree's coordinates (the module docs).
    pub fn extract(&self, sdf: &Sdf, options: &CurveOptions) -> Polyline {
        let size = self.bounds.extent().max_element();
        if !(size > 0.0 && size.is_finite()) {
            return Polyline::default();
        }
        let root = Aabb::new(
            self.bounds.min - ROOT_PADDING[0] * size,
            self.bounds.max + ROOT_PADDING[1] * size,
        );
        let fns = self.functions(sdf);
        let boxes = octree_leaves(root, options.max_depth, 0.0, |b| fns.may_hold(b));
        extract_polyline(&fns, &boxes, options)
    }

    /// The extracted curve's segments as crease edges ([`EdgeCurve::Chord`]) with this crossing's faces.
    pub fn chords(&self, sdf: &Sdf, options: &CurveOptions) -> Vec<CreaseEdge> {
        let polyline = self.extract(sdf, options);
        (polyline.segments.iter())
            .map(|s| {
                let [a, b] = polyline.segment(s);
                CreaseEdge {
                    curve: EdgeCurve::Chord { a, b },
                    path: self.path.clone(),
                    faces: self.faces,
                    inverted: self.inverted,
                }
            })
            .collect()
    }
}

impl Sdf {
    /// The point of `edge` (listed from this tree) at fraction `u ∈ [0, 1)` of its curve, its unit
    /// tangent, and its density per unit length relative to the uniform density on the curve's length
    /// (`EdgeCurve::length`): 1 for a segment or a circle, `|T·t|` for a chord whose point is projected
    /// onto the crease in the plane orthogonal to the chord ([`crate::math::implicit_curve`]). `None`
    /// when the projection fails.
    pub fn crease_point(&self, edge: &CreaseEdge, u: f32) -> Option<(glam::Vec3, glam::Vec3, f32)> {
        match edge.curve {
            EdgeCurve::Chord { a, b } => {
                let fns = FacePair {
                    sdf: self,
                    path: &edge.path,
                    faces: edge.faces,
                };
                let p = project_from_chord(&fns, [a, b], u)?;
                Some((p.x, p.tangent, p.cosine))
            }
            _ => {
                let (x, t) = edge.curve.at(u);
                Some((x, t, 1.0))
            }
        }
    }
}

/// The two face functions of a crease, in the tree's coordinates.
struct FacePair<'a> {
    sdf: &'a Sdf,
    path: &'a [usize],
    faces: [Face; 2],
}

impl FacePair<'_> {
    fn value(&self, face: usize, x: glam::Vec3) -> f32 {
        (self
            .sdf
            .face_value(self.path, self.faces[face], Vec3::from(x)))
        .unwrap_or(f32::NAN)
    }
}

impl CurveFunctions for FacePair<'_> {
    fn eval(&self, x: glam::Vec3) -> (f32, f32, glam::Vec3, glam::Vec3) {
        let [ga, gb] = [0, 1].map(|f| self.sdf.face_gradient(self.path, self.faces[f], x));
        (self.value(0, x), self.value(1, x), ga, gb)
    }

    fn values(&self, x: glam::Vec3) -> (f32, f32) {
        (self.value(0, x), self.value(1, x))
    }

    fn may_hold(&self, b: &Aabb) -> bool {
        let x = Vec3::new(
            Interval::from_f32(b.min.x, b.max.x),
            Interval::from_f32(b.min.y, b.max.y),
            Interval::from_f32(b.min.z, b.max.z),
        );
        self.faces.iter().all(|&face| {
            (self.sdf.face_value(self.path, face, x)).is_none_or(|v| v.contains_zero())
        })
    }

    /// `|F| ≤ 1e-5·max(1, |x|)·|∇F|` for both faces: a distance to each face at the solve's tolerance
    /// (the faces' values are not rescaled by the transforms above them).
    fn converged(&self, x: glam::Vec3, fa: f32, fb: f32, ga: glam::Vec3, gb: glam::Vec3) -> bool {
        let tol = 1e-5 * x.length().max(1.0);
        fa.abs() <= tol * ga.length() && fb.abs() <= tol * gb.length()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two unit spheres `d` apart: their intersection (a lens) creases along a circle of radius
    /// `√(1 − d²/4)` in the plane between them; sampled lengths `1/p` average to its length.
    #[test]
    fn a_lens_creases_along_a_circle() {
        let d = 1.2f32;
        let lens = Sdf::transform(
            Sdf::intersection(vec![
                Sdf::sphere([0.0; 3], 1.0),
                Sdf::sphere([d, 0.0, 0.0], 1.0),
            ]),
            [0.3, -0.2, 0.1],
            glam::Vec3::new(1.0, 1.0, 0.0).normalize(),
            40.0,
            1.5,
        );
        let crossings = lens.crossing_creases();
        assert_eq!(crossings.len(), 1);
        assert!(!crossings[0].inverted);
        let radius = 1.5 * (1.0 - d * d / 4.0).sqrt();
        let exact = std::f64::consts::TAU * radius as f64;
        let polyline = crossings[0].extract(&lens, &CurveOptions::default());
        assert_eq!(polyline.stats.open_ends, 0, "{:?}", polyline.stats);
        let chord_error = (polyline.length() - exact) / exact;
        assert!((-1e-3..=0.0).contains(&chord_error), "{chord_error}");
        let edges = crossings[0].chords(&lens, &CurveOptions::default());
        let total: f64 = edges.iter().map(|e| e.curve.length() as f64).sum();
        let n = 4096;
        let mut estimate = 0.0;
        for i in 0..n {
            // Chords by length, then a point on each.
            let target = (i as f64 + 0.5) / n as f64 * total;
            let mut acc = 0.0;
            let e = (edges.iter())
                .find(|e| {
                    acc += e.curve.length() as f64;
                    acc >= target
                })
                .unwrap_or(edges.last().unwrap());
            let (x, tangent, cosine) = lens.crease_point(e, 0.37).unwrap();
            for face in e.faces {
                let f: f32 = lens.face_value(&e.path, face, Vec3::from(x)).unwrap();
                assert!(f.abs() < 1e-5, "{face:?}: {f}");
            }
            assert!(tangent.is_normalized());
            estimate += total / cosine as f64 / n as f64;
        }
        assert!(
            ((estimate - exact) / exact).abs() < 2e-4,
            "{estimate} vs {exact}"
        );
    }
}
