//! The silhouette curve inside the certified boxes, as a polyline of curve points, and sampling on it with an
//! exact density.
//!
//! Seen from the camera centre `c`, the silhouette is `{φ = 0, ψ = 0}` with `ψ(x) = ∇φ(x)·(c − x)` (docs/theory.md §4.2,
//! supplemental §2); its gradients are `∇φ` and `∇ψ = H(c − x) − ∇φ`, `H` the Hessian of `φ`. Where they are
//! independent the curve is smooth with unit tangent `T = ∇φ × ∇ψ / |∇φ × ∇ψ|`.
//!
//! **Extraction.** [`silhouette_boxes`] gives boxes certified to hold every curve point. In each box the curve
//! enters and leaves through the faces; on a face `x_k = const` a crossing is a root of `(φ, ψ)` in the
//! plane. A small grid on the face (`face_grid` cells a side) marks the cells whose corners see a sign change
//! of both `φ` and `ψ` (for nearly linear `φ, ψ` over a cell, a zero inside means a sign change at the
//! corners), and Newton's method on the three equations `φ = 0, ψ = 0, x_k = const` starts from their
//! centres ([`solve_on_plane`]). A face shared by two boxes is seen with the same grid from both sides, so
//! both find bit-identical crossings; vertices are nevertheless welded within `1e-4` of the box size.
//! - **Two crossings**: the curve piece in the box is the chord between them, refined `refine` times by
//!   projecting each chord midpoint onto the curve in the plane through the midpoint orthogonal to the chord.
//! - **No crossing**: the box holds no curve (interval culling could not prove it), or a whole closed
//!   component smaller than the box; that component is lost (its length is below the box's perimeter).
//!   Counted in [`ExtractStats::empty_boxes`].
//! - **One or more than two crossings** (a crossing missed by the face grid, two branches through one box,
//!   a grazing crossing): the box is split into its kept octants and each is extracted again, up to
//!   `max_split` times. A box still with ONE crossing then has its entry and exit closer than the
//!   de-duplication distance (`1e-3` of the box size, crossings closer than that are merged): the curve
//!   clips one of its edges or corners (seen on grids); the tiny piece is skipped
//!   ([`ExtractStats::touching_boxes`]), the neighbours across the edge hold the curve. A box still with
//!   more crossings is skipped and counted in [`ExtractStats::unresolved_boxes`]. Either may leave open
//!   ends in the polyline ([`ExtractStats::open_ends`]); the tests find none on their shapes.
//!
//! **Frame.** The curve is extracted and sampled in the shape's own frame, its `translate` removed
//! ([`SilhouetteCurve::origin`]): there the coordinates have the magnitude of the shape, and `φ`, `ψ`
//! and Newton's steps the float resolution of its size, wherever the shape is placed. In world
//! coordinates 1,000 radii from the origin their rounding noise left the curve open (see
//! `tests/silhouette_curve.rs`). Parameters that place a shape inside its SDF (a sphere's `center`)
//! do not benefit.
//!
//! **Sampling.** A segment `[a, b]` with direction `t` is chosen with probability proportional to its
//! length and `s` uniformly on it, then mapped to the curve point `x(s)` in the plane `(x − a)·t = s`
//! ([`solve_on_plane`]). Segment ends are curve points, so the pieces `x([0, |b − a|])` of consecutive
//! segments meet exactly and tile the extracted curve. The map's Jacobian is exact and closed-form:
//! differentiating `(x(s) − a)·t = s` along the curve gives `dσ/ds = 1/|T·t|` (σ the arc length), so the
//! density per unit length of the TRUE curve is `p(x) = |T(x)·t| / L` with `L` the polyline's total
//! length ([`CurveSample::pdf`]). It is exact as long as each plane of a segment's pencil crosses its
//! curve piece once (true once boxes are small against the curve's radius of curvature); `1/p` is then an
//! unbiased estimator of the extracted curve's true length, whereas `L` itself underestimates it by the
//! chord error `≈ Σ lᵢ³ κ²/24`, which shrinks ×4 per octree level (×4 per `refine` step).

use crate::error::Result;
use crate::integrator::silhouette_boxes::{BoxClass, classify_box, silhouette_boxes};
use crate::math::Aabb;
use crate::scalar::Param3;
use crate::scene::Shape;
use crate::sdf::Sdf;
use glam::{DMat3, DVec3, Vec3};
use rayon::prelude::*;
use std::collections::HashMap;

/// Extraction settings.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct CurveOptions {
    /// Depth of the culling octree ([`silhouette_boxes`]).
    pub max_depth: u32,
    /// Cells per side of the grid that looks for crossings on each box face.
    pub face_grid: usize,
    /// Midpoint refinements of each box's chord (`2^refine` segments per box).
    pub refine: u32,
    /// How many times a box with other than 0 or 2 crossings is split into octants before giving up.
    pub max_split: u32,
}

impl Default for CurveOptions {
    fn default() -> Self {
        Self {
            max_depth: 6,
            face_grid: 4,
            refine: 1,
            max_split: 2,
        }
    }
}

/// What happened during extraction.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ExtractStats {
    /// Leaf boxes returned by the culling.
    pub boxes: usize,
    /// Boxes (or split octants) with two crossings: one curve piece each.
    pub resolved_boxes: usize,
    /// Boxes with no crossing (skipped).
    pub empty_boxes: usize,
    /// Boxes with a single crossing even after `max_split` splits: the curve clips an edge or a corner,
    /// entering and leaving within the de-duplication distance (`1e-3` of the box size); skipped.
    pub touching_boxes: usize,
    /// Boxes with more than two crossings even after `max_split` splits (skipped).
    pub unresolved_boxes: usize,
    /// Polyline vertices with one segment (the curve has a gap there).
    pub open_ends: usize,
    /// Polyline vertices with more than two segments.
    pub branch_points: usize,
    /// Chord midpoints whose projection failed (the chord is kept unrefined there).
    pub failed_refinements: usize,
}

/// The extracted silhouette: a polyline whose vertices lie on the curve.
#[derive(Clone, Debug, PartialEq)]
pub struct SilhouetteCurve {
    /// The camera centre the curve is the silhouette for.
    pub eye: Vec3,
    /// Vertices, each on `{φ = 0, ψ = 0}` up to the Newton tolerance, relative to `origin` (the frame
    /// the curve is extracted and sampled in, at the float resolution of the shape's own size; world
    /// positions: [`SilhouetteCurve::world_points`]).
    pub points: Vec<Vec3>,
    /// Segments as pairs of indices into `points`.
    pub segments: Vec<[u32; 2]>,
    /// `cumulative[i]` = total length of segments `0..=i` (f64, to keep the sum exact enough).
    pub cumulative: Vec<f64>,
    /// Extraction counters.
    pub stats: ExtractStats,
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
    let t = shape.translate.value();
    functions_in_frame(&shape.sdf, eye - t, x - t)
}

/// [`silhouette_functions`] in the shape's own frame (its translation removed from `eye` and `x`).
fn functions_in_frame(sdf: &Sdf, eye: Vec3, x: Vec3) -> (f32, f32, Vec3, Vec3) {
    let (phi, g, h) = sdf.hessian(x);
    let v = eye - x;
    (phi, g.dot(v), g, h * v - g)
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

/// The curve point on the plane `n·x = c` near `x0` by Newton's method on `(φ, ψ, n·x − c)`.
///
/// Each step solves the 3×3 system with rows `∇φ, ∇ψ, n` (f64 solve of f32 evaluations). Fails when the
/// system is singular (the curve is tangent to the plane or `∇φ ∥ ∇ψ`), when an iterate leaves the ball
/// of radius `reach` around `x0` (so a root of another branch is not taken), or when the residuals are
/// not below the tolerance once the Newton step has reached the f32 resolution of `x` (or, for `x` near the
/// origin, that of `scale` and stopped shrinking) (`|φ| ≤ 1e-5·scale`, `|ψ| ≤ 1e-5·|∇φ||c − x|·scale`,
/// `scale = max(1, |x|)`; typically they are at their rounding floor, ~1e-7).
pub fn solve_on_plane(
    shape: &Shape,
    eye: Vec3,
    x0: Vec3,
    n: Vec3,
    c: f32,
    reach: f32,
) -> Option<Vec3> {
    let t = shape.translate.value();
    solve_in_frame(&shape.sdf, eye - t, x0 - t, n, c - n.dot(t), reach).map(|x| x + t)
}

/// [`solve_on_plane`] in the shape's own frame (its translation removed from `eye`, `x0` and `c`).
fn solve_in_frame(sdf: &Sdf, eye: Vec3, x0: Vec3, n: Vec3, c: f32, reach: f32) -> Option<Vec3> {
    let nd = n.as_dvec3();
    let mut x = x0.as_dvec3();
    // Start on the plane: the other two equations are then solved within it.
    x += nd * ((c as f64 - nd.dot(x)) / nd.length_squared());
    let mut prev = f64::INFINITY;
    for _ in 0..24 {
        let xf = x.as_vec3();
        let (phi, psi, gphi, gpsi) = functions_in_frame(sdf, eye, xf);
        let j = DMat3::from_cols(gphi.as_dvec3(), gpsi.as_dvec3(), nd).transpose();
        let det = j.determinant();
        let norm = gphi.length() as f64 * gpsi.length() as f64 * nd.length();
        if !det.is_finite() || det.abs() <= 1e-9 * norm {
            return None;
        }
        let f = DVec3::new(phi as f64, psi as f64, nd.dot(x) - c as f64);
        let step = j.inverse() * f;
        if !step.is_finite() {
            return None;
        }
        // Stop once the step is at the f32 resolution of x, or below that of the unit (the rounding floor
        // of φ and ψ for shapes of unit size) and no longer converging: the residuals are then at their
        // rounding floor. Stopping at the unit's resolution alone is too early on a small curve (a sphere
        // of radius 0.02: a step of 3e-7 left |ψ| = 5e-5, above the tolerance, and lost the crossing).
        let scale = xf.length().max(1.0);
        let len = step.length();
        let eps = 4.0 * f32::EPSILON as f64;
        if len <= eps * xf.length() as f64 || (len <= eps * scale as f64 && len > 0.5 * prev) {
            let ok = phi.abs() <= 1e-5 * scale
                && psi.abs() <= 1e-5 * scale * gphi.length() * (eye - xf).length();
            return ok.then_some(xf);
        }
        prev = len;
        x -= step;
        if (x - x0.as_dvec3()).length() > reach as f64 {
            return None;
        }
    }
    None
}

/// Extracts the silhouette of `shape` seen from `eye` (see the module notes), in the shape's own frame
/// (its translation removed): `points` are relative to `origin`.
pub fn extract_silhouette(
    shape: &Shape,
    eye: Vec3,
    options: &CurveOptions,
) -> Result<SilhouetteCurve> {
    let world_eye = eye;
    let (own, origin) = own_frame(shape);
    let (shape, eye) = (&own, eye - origin);
    let boxes = silhouette_boxes(shape, eye, options.max_depth, 0.0)?;
    let mut stats = ExtractStats {
        boxes: boxes.len(),
        ..Default::default()
    };
    let per_box: Vec<(Vec<[Vec3; 2]>, ExtractStats)> = boxes
        .par_iter()
        .map(|b| {
            let mut st = ExtractStats::default();
            let mut chords = Vec::new();
            box_chords(
                shape,
                eye,
                b,
                options,
                options.max_split,
                &mut chords,
                &mut st,
            );
            let mut pieces = Vec::new();
            for [a, e] in chords {
                refine_chord(shape, eye, a, e, options.refine, &mut pieces, &mut st);
            }
            (pieces, st)
        })
        .collect();
    let weld = boxes
        .first()
        .map_or(1e-6, |b| 1e-4 * b.extent().max_element());
    let mut welder = Welder::new(weld);
    let mut segments = Vec::new();
    // A curve piece lying exactly in a face shared by two boxes (a sphere's silhouette circle seen along
    // an axis, in a dyadic plane of the octree) is extracted by both: keep each welded segment once, or
    // the sampled length, and every estimate built on it, would double there.
    let mut seen = std::collections::HashSet::new();
    for (pieces, st) in per_box {
        stats.resolved_boxes += st.resolved_boxes;
        stats.empty_boxes += st.empty_boxes;
        stats.unresolved_boxes += st.unresolved_boxes;
        stats.touching_boxes += st.touching_boxes;
        stats.failed_refinements += st.failed_refinements;
        for [a, e] in pieces {
            let (i, j) = (welder.index(a), welder.index(e));
            if i != j && seen.insert((i.min(j), i.max(j))) {
                segments.push([i, j]);
            }
        }
    }
    let points = welder.points;
    let mut degree = vec![0u32; points.len()];
    for s in &segments {
        degree[s[0] as usize] += 1;
        degree[s[1] as usize] += 1;
    }
    stats.open_ends = degree.iter().filter(|&&d| d == 1).count();
    stats.branch_points = degree.iter().filter(|&&d| d > 2).count();
    let mut total = 0.0f64;
    let cumulative = segments
        .iter()
        .map(|s| {
            total += (points[s[1] as usize] - points[s[0] as usize])
                .as_dvec3()
                .length();
            total
        })
        .collect();
    Ok(SilhouetteCurve {
        eye: world_eye,
        points,
        segments,
        cumulative,
        stats,
        origin,
    })
}

impl SilhouetteCurve {
    /// The vertices in world space (`points` moved by `origin`, rounded to the world's resolution).
    pub fn world_points(&self) -> impl Iterator<Item = Vec3> + '_ {
        self.points.iter().map(|&p| p + self.origin)
    }

    /// Total length `L` of the polyline.
    pub fn polyline_length(&self) -> f64 {
        self.cumulative.last().copied().unwrap_or(0.0)
    }

    /// Number of segments at each vertex.
    pub fn degrees(&self) -> Vec<u32> {
        let mut degree = vec![0u32; self.points.len()];
        for s in &self.segments {
            degree[s[0] as usize] += 1;
            degree[s[1] as usize] += 1;
        }
        degree
    }

    /// Samples a point on the curve from two uniform numbers (`u[0]` picks the segment by length, `u[1]` the
    /// position along it), with its density per unit length of the true curve (module notes). `None` when the
    /// curve is empty or the projection onto the curve fails (a rare loss, not re-weighted). `shape` is
    /// the one the curve was extracted from; the projection works in the extraction's frame
    /// ([`SilhouetteCurve::origin`]) and the sample is returned in world space.
    pub fn sample(&self, shape: &Shape, u: [f32; 2]) -> Option<CurveSample> {
        let total = self.polyline_length();
        if total <= 0.0 {
            return None;
        }
        let target = (u[0] as f64).clamp(0.0, 1.0) * total;
        let i = self
            .cumulative
            .partition_point(|&c| c < target)
            .min(self.segments.len() - 1);
        let [ia, ib] = self.segments[i];
        // In the frame the curve was extracted in (see `own_frame`).
        let (a, b) = (self.points[ia as usize], self.points[ib as usize]);
        let eye = self.eye - self.origin;
        let len = (b - a).length();
        let t = (b - a) / len;
        let x0 = a + t * (u[1].clamp(0.0, 1.0) * len);
        let x = solve_in_frame(&shape.sdf, eye, x0, t, t.dot(x0), len)?;
        let (_, _, gphi, gpsi) = functions_in_frame(&shape.sdf, eye, x);
        let tangent = gphi.cross(gpsi).try_normalize()?;
        Some(CurveSample {
            x: x + self.origin,
            tangent,
            pdf: (tangent.dot(t) as f64).abs() / total,
            segment: i,
        })
    }
}

/// Appends the chords of the curve pieces in `b` (see the module notes for the cases).
fn box_chords(
    shape: &Shape,
    eye: Vec3,
    b: &Aabb,
    options: &CurveOptions,
    splits: u32,
    out: &mut Vec<[Vec3; 2]>,
    stats: &mut ExtractStats,
) {
    let crossings = face_crossings(shape, eye, b, options.face_grid.max(1));
    match crossings.len() {
        0 => stats.empty_boxes += 1,
        2 => {
            stats.resolved_boxes += 1;
            out.push([crossings[0], crossings[1]]);
        }
        _ if splits > 0 => {
            for child in b.octants() {
                if classify_box(shape, eye, &child) == BoxClass::Kept {
                    box_chords(shape, eye, &child, options, splits - 1, out, stats);
                }
            }
        }
        // Still one crossing after the splits: entry and exit closer than the de-duplication distance, the
        // curve clips an edge or a corner of the box; its piece here is shorter than 1e-3 of the box size.
        1 => stats.touching_boxes += 1,
        _ => stats.unresolved_boxes += 1,
    }
}

/// The distinct crossings of the curve with the six faces of `b`.
fn face_crossings(shape: &Shape, eye: Vec3, b: &Aabb, grid: usize) -> Vec<Vec3> {
    let size = b.extent().max_element();
    let slack = 1e-4 * size;
    let mut found: Vec<Vec3> = Vec::new();
    for k in 0..3 {
        let (u, v) = ((k + 1) % 3, (k + 2) % 3);
        for c in [b.min[k], b.max[k]] {
            // Node values of φ and ψ on the face grid; the node coordinates depend only on the face, so a
            // face shared by two boxes gives the same crossings from both sides.
            let node = |i: usize, j: usize| {
                let mut p = Vec3::ZERO;
                p[k] = c;
                p[u] = b.min[u] + (b.max[u] - b.min[u]) * (i as f32 / grid as f32);
                p[v] = b.min[v] + (b.max[v] - b.min[v]) * (j as f32 / grid as f32);
                p
            };
            let vals: Vec<(f32, f32)> = (0..=grid)
                .flat_map(|j| (0..=grid).map(move |i| (i, j)))
                .map(|(i, j)| {
                    let p = node(i, j);
                    let phi = shape.eval_f32(p);
                    let psi = shape.gradient(p).dot(eye - p);
                    (phi, psi)
                })
                .collect();
            let at = |i: usize, j: usize| vals[j * (grid + 1) + i];
            let mut n = Vec3::ZERO;
            n[k] = 1.0;
            for j in 0..grid {
                for i in 0..grid {
                    let corners = [at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)];
                    let changes = |f: fn(&(f32, f32)) -> f32| {
                        let lo = corners.iter().map(f).fold(f32::INFINITY, f32::min);
                        let hi = corners.iter().map(f).fold(f32::NEG_INFINITY, f32::max);
                        lo <= 0.0 && hi >= 0.0
                    };
                    if !(changes(|q| q.0) && changes(|q| q.1)) {
                        continue;
                    }
                    let start = (node(i, j) + node(i + 1, j + 1)) * 0.5;
                    let Some(x) = solve_on_plane(shape, eye, start, n, c, size) else {
                        continue;
                    };
                    let inside =
                        (0..3).all(|m| x[m] >= b.min[m] - slack && x[m] <= b.max[m] + slack);
                    if inside && found.iter().all(|q| (*q - x).length() > 10.0 * slack) {
                        found.push(x);
                    }
                }
            }
        }
    }
    found
}

/// Appends the chord `[a, e]` split `levels` times at curve points (midpoints projected onto the curve).
fn refine_chord(
    shape: &Shape,
    eye: Vec3,
    a: Vec3,
    e: Vec3,
    levels: u32,
    out: &mut Vec<[Vec3; 2]>,
    stats: &mut ExtractStats,
) {
    let d = e - a;
    let len = d.length();
    if levels == 0 || len <= 0.0 {
        out.push([a, e]);
        return;
    }
    let t = d / len;
    let m = (a + e) * 0.5;
    match solve_on_plane(shape, eye, m, t, t.dot(m), len) {
        Some(x) => {
            refine_chord(shape, eye, a, x, levels - 1, out, stats);
            refine_chord(shape, eye, x, e, levels - 1, out, stats);
        }
        None => {
            stats.failed_refinements += 1;
            out.push([a, e]);
        }
    }
}

/// Merges points closer than `tol` (hash grid of cell `tol`, neighbours searched).
struct Welder {
    tol: f32,
    points: Vec<Vec3>,
    cells: HashMap<[i64; 3], Vec<u32>>,
}

impl Welder {
    fn new(tol: f32) -> Self {
        Self {
            tol: tol.max(1e-12),
            points: Vec::new(),
            cells: HashMap::new(),
        }
    }

    fn cell(&self, p: Vec3) -> [i64; 3] {
        let q = (p / self.tol).floor();
        [q.x as i64, q.y as i64, q.z as i64]
    }

    fn index(&mut self, p: Vec3) -> u32 {
        let c = self.cell(p);
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    if let Some(list) = self.cells.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) {
                        for &i in list {
                            if (self.points[i as usize] - p).length() <= self.tol {
                                return i;
                            }
                        }
                    }
                }
            }
        }
        let i = self.points.len() as u32;
        self.points.push(p);
        self.cells.entry(c).or_default().push(i);
        i
    }
}
