//! The silhouette curve inside the certified boxes, as a polyline of curve points, and sampling on it with an
//! exact density.
//!
//! Seen from the camera centre `c`, the silhouette is `{φ = 0, ψ = 0}` with `ψ(x) = ∇φ(x)·(c − x)` (docs/theory.md §4.2,
//! supplemental §2); its gradients are `∇φ` and `∇ψ = H(c − x) − ∇φ`, `H` the Hessian of `φ`. Where they are
//! independent the curve is smooth with unit tangent `T = ∇φ × ∇ψ / |∇φ × ∇ψ|`.
//!
//! **Extraction and sampling** are those of any curve `{f = 0, g = 0}` ([`crate::math::implicit_curve`], whose
//! module notes state the cases and the density), with `f = φ`, `g = ψ` and boxes culled by
//! [`classify_box`](crate::integrator::silhouette_boxes::classify_box): [`silhouette_boxes`](crate::integrator::silhouette_boxes::silhouette_boxes) gives boxes certified to hold every curve point.
//!
//! **Frame.** The curve is extracted and sampled in the shape's own frame, its `translate` removed
//! ([`SilhouetteCurve::origin`]): there the coordinates have the magnitude of the shape, and `φ`, `ψ`
//! and Newton's steps the float resolution of its size, wherever the shape is placed. In world
//! coordinates 1,000 radii from the origin their rounding noise left the curve open (see
//! `tests/silhouette_curve.rs`). Parameters that place a shape inside its SDF (a sphere's `center`)
//! do not benefit.
//!
//! **Density.** A sample's density per unit length of the true curve is `|T·t| / L`, `t` the direction of
//! the polyline segment it came from and `L` the polyline's total length ([`CurveSample::pdf`]).
//!
//! **Seen along a direction** ([`View::Along`], a sun's shadow edges): `ψ(x) = ∇φ(x)·(−ω)`,
//! `∇ψ = −Hω`; everything else is the same ([`extract_silhouette_in`]).

use crate::error::Result;
use crate::integrator::silhouette_boxes::{BoxClass, classify_box_in, silhouette_boxes_in};
use crate::math::Aabb;
use crate::math::implicit_curve::{CurveFunctions, Polyline, extract_polyline, project_from_chord};
use crate::scalar::Param3;
use crate::scene::Shape;
use crate::sdf::Sdf;
use glam::Vec3;

pub use crate::integrator::silhouette_boxes::View;
pub use crate::math::implicit_curve::{CurveOptions, ExtractStats};

/// The extracted silhouette: a polyline whose vertices lie on the curve.
#[derive(Clone, Debug, PartialEq)]
pub struct SilhouetteCurve {
    /// Where the curve is the silhouette seen from (in world space): the camera centre, a light.
    pub view: View,
    /// The curve: vertices on `{φ = 0, ψ = 0}` up to the Newton tolerance, relative to `origin` (the
    /// frame the curve is extracted and sampled in, at the float resolution of the shape's own size;
    /// world positions: [`SilhouetteCurve::world_points`]), and the extraction's counters.
    pub polyline: Polyline,
    /// The shape's translation when the curve was extracted: the origin of the frame it was extracted
    /// and is sampled in ([`extract_silhouette`]).
    pub origin: Vec3,
}

/// A point sampled on the silhouette curve.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct CurveSample {
    /// The curve point.
    pub x: Vec3,
    /// Unit tangent `∇φ × ∇ψ / |∇φ × ∇ψ|` of the curve at `x`.
    pub tangent: Vec3,
    /// Density per unit length of the true curve, `|T·t| / L` (see the module notes).
    pub pdf: f64,
    /// Index of the polyline segment the sample came from.
    pub segment: usize,
}

/// `φ`, `ψ` and their gradients at `x` (world space, translation included).
pub fn silhouette_functions(shape: &Shape, eye: Vec3, x: Vec3) -> (f32, f32, Vec3, Vec3) {
    silhouette_functions_in(shape, View::Point(eye), x)
}

/// [`silhouette_functions`] for any [`View`].
pub fn silhouette_functions_in(shape: &Shape, view: View, x: Vec3) -> (f32, f32, Vec3, Vec3) {
    let t = shape.translate.value();
    functions_in_frame(&shape.sdf, view.relative_to(t), x - t)
}

/// [`silhouette_functions_in`] in the shape's own frame (its translation removed from the view and
/// `x`).
fn functions_in_frame(sdf: &Sdf, view: View, x: Vec3) -> (f32, f32, Vec3, Vec3) {
    let (phi, g, h) = sdf.hessian(x);
    let v = view.towards(x);
    let grad_psi = match view {
        View::Point(_) => h * v - g,
        View::Along(_) => h * v,
    };
    (phi, g.dot(v), g, grad_psi)
}

/// `shape` with its translation removed, and that translation: the frame the curve is extracted in.
/// Coordinates there are relative to the shape, so a shape placed far from the origin by `translate`
/// keeps the float resolution of its own size (in world coordinates `φ`, `ψ` and Newton's steps
/// would carry the rounding of the coordinates' magnitude, which 1,000 radii away leaves the curve
/// open).
fn own_frame(shape: &Shape) -> (Shape, Vec3) {
    let mut local = shape.clone();
    local.translate = Param3::new([0.0; 3]);
    local.bounds = shape.sdf.bounds();
    (local, shape.translate.value())
}

/// The silhouette's pair `(φ, ψ)` seen from `eye`, in the shape's own frame (see [`own_frame`]).
struct SilhouetteFunctions<'a> {
    sdf: &'a Sdf,
    view: View,
    /// The shape in its own frame, whose boxes [`classify_box`] culls; `None` when only projecting
    /// (sampling never culls).
    cull: Option<&'a Shape>,
}

impl CurveFunctions for SilhouetteFunctions<'_> {
    fn eval(&self, x: Vec3) -> (f32, f32, Vec3, Vec3) {
        functions_in_frame(self.sdf, self.view, x)
    }

    fn values(&self, p: Vec3) -> (f32, f32) {
        (
            self.sdf.eval_f32(p),
            self.sdf.gradient(p).dot(self.view.towards(p)),
        )
    }

    fn may_hold(&self, b: &Aabb) -> bool {
        (self.cull).is_none_or(|shape| classify_box_in(shape, self.view, b) == BoxClass::Kept)
    }

    /// `|φ| ≤ 1e-5·scale`, `|ψ| ≤ 1e-5·max(|∇φ||e(x)|, |∇ψ|)·scale`, `scale = max(1, |x|)` (`e = c −
    /// x`, or the unit `−ω` along a direction); typically the residuals are at their rounding floor,
    /// ~1e-7. The `|∇ψ|` bound is a distance to the curve: where the curvature radius `ρ` is small
    /// `ψ`'s rounding floor grows as `|e| ε |x|/ρ` (the normal of a torus of minor radius 1e-3 at
    /// unit distance carries 1e-4 of rounding) while `|∇ψ| ≈ |e|/ρ` grows with it.
    fn converged(&self, x: Vec3, phi: f32, psi: f32, gphi: Vec3, gpsi: Vec3) -> bool {
        let scale = x.length().max(1.0);
        let psi_scale = (gphi.length() * self.view.towards(x).length()).max(gpsi.length());
        phi.abs() <= 1e-5 * scale && psi.abs() <= 1e-5 * scale * psi_scale
    }
}

/// Extracts the silhouette of `shape` seen from `eye` (see the module notes), in the shape's own frame
/// (its translation removed): `points` are relative to `origin`.
pub fn extract_silhouette(
    shape: &Shape,
    eye: Vec3,
    options: &CurveOptions,
) -> Result<SilhouetteCurve> {
    extract_silhouette_in(shape, View::Point(eye), options)
}

/// [`extract_silhouette`] for any [`View`]: from a point or along a direction.
pub fn extract_silhouette_in(
    shape: &Shape,
    view: View,
    options: &CurveOptions,
) -> Result<SilhouetteCurve> {
    let (own, origin) = own_frame(shape);
    let (shape, local) = (&own, view.relative_to(origin));
    let boxes = silhouette_boxes_in(shape, local, options.max_depth, 0.0)?;
    let polyline = extract_polyline(
        &SilhouetteFunctions {
            sdf: &shape.sdf,
            view: local,
            cull: Some(shape),
        },
        &boxes,
        options,
    );
    Ok(SilhouetteCurve {
        view,
        polyline,
        origin,
    })
}

impl SilhouetteCurve {
    /// The vertices in world space (`points` moved by `origin`, rounded to the world's resolution).
    pub fn world_points(&self) -> impl Iterator<Item = Vec3> + '_ {
        self.polyline.points.iter().map(|&p| p + self.origin)
    }

    /// Total length `L` of the polyline.
    pub fn polyline_length(&self) -> f64 {
        self.polyline.length()
    }

    /// Number of segments at each vertex.
    pub fn degrees(&self) -> Vec<u32> {
        self.polyline.degrees()
    }

    /// Samples a point on the curve from two uniform numbers (`u[0]` picks the segment by length, `u[1]` the
    /// position along it), with its density per unit length of the true curve (module notes). `None` when the
    /// curve is empty or the projection onto the curve fails (a rare loss, not re-weighted). `shape` is
    /// the one the curve was extracted from; the projection works in the extraction's frame
    /// ([`SilhouetteCurve::origin`]) and the sample is returned in world space.
    pub fn sample(&self, shape: &Shape, u: [f32; 2]) -> Option<CurveSample> {
        let total = self.polyline_length();
        let (i, chord) = self.polyline.segment_at(u[0])?;
        // In the frame the curve was extracted in (see `own_frame`).
        let fns = SilhouetteFunctions {
            sdf: &shape.sdf,
            view: self.view.relative_to(self.origin),
            cull: None,
        };
        let p = project_from_chord(&fns, chord, u[1])?;
        Some(CurveSample {
            x: p.x + self.origin,
            tangent: p.tangent,
            pdf: p.cosine as f64 / total,
            segment: i,
        })
    }
}
