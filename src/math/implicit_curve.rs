//! Curves where two implicit functions vanish together, `{f = 0, g = 0}`, extracted as polylines whose
//! vertices lie on the curve, and points projected onto them with an exact density per unit length.
//!
//! Two curves of this kind are sampled: the silhouette seen from an eye (`f = φ`, `g = ∇φ·(c − x)`,
//! [`crate::integrator::silhouette_curve`], docs/theory.md §4.2) and the crease where two children of a hard CSG
//! node cross (`f`, `g` the children's signed distances, docs/theory.md §7.1). The functions come
//! through [`CurveFunctions`]; where their gradients are independent the curve is smooth with unit
//! tangent `T = ∇f × ∇g / |∇f × ∇g|`.
//!
//! **Extraction.** An octree over a root box keeps the boxes that interval arithmetic cannot prove free
//! of the curve ([`CurveFunctions::may_hold`]); every curve point lies in a kept leaf. In each leaf the
//! curve enters and leaves through the faces; on a face `x_k = const` a crossing is a root of `(f, g)` in
//! the plane. A small grid on the face (`face_grid` cells a side) marks the cells whose corners see a sign
//! change of both `f` and `g` (for nearly linear `f, g` over a cell, a zero inside means a sign change at
//! the corners), and Newton's method on the three equations `f = 0, g = 0, x_k = const` starts from their
//! centres ([`solve_on_plane`]). A feature thinner than a cell (a tube 1/45 of a pixel across) hides
//! `f`'s zeros between the corners: a cell where `g` changes sign and the distance `f` is within the
//! cell's diagonal of 0 at a corner (and half of it at the centre) is split in four, recursively, until
//! its cells see `f` change sign ([`cell_crossings`]). A face shared by two boxes is seen with the same grid from both sides, so
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
//!   more crossings holds two branches closer than itself (the two sides of a thin tube stay together
//!   through any split): its crossings are paired along the curve's tangents
//!   ([`ExtractStats::paired_boxes`]), or, when they do not pair up, the box is skipped and counted in
//!   [`ExtractStats::unresolved_boxes`]. Skipped boxes may leave open ends in the polyline
//!   ([`ExtractStats::open_ends`]); the tests find none or a few on their shapes.
//!
//! **Sampling.** A segment `[a, b]` with direction `t` is chosen with probability proportional to its
//! length and `s` uniformly on it, then mapped to the curve point `x(s)` in the plane `(x − a)·t = s`
//! ([`solve_on_plane`]). Segment ends are curve points, so the pieces `x([0, |b − a|])` of consecutive
//! segments meet exactly and tile the extracted curve. The map's Jacobian is exact and closed-form:
//! differentiating `(x(s) − a)·t = s` along the curve gives `dσ/ds = 1/|T·t|` (σ the arc length), so the
//! density per unit length of the TRUE curve is `p(x) = |T(x)·t| / L` with `L` the polyline's total
//! length. It is exact as long as each plane of a segment's pencil crosses its curve piece once (true
//! once boxes are small against the curve's radius of curvature); `1/p` is then an unbiased estimator of
//! the extracted curve's true length, whereas `L` itself underestimates it by the chord error
//! `≈ Σ lᵢ³ κ²/24`, which shrinks ×4 per octree level (×4 per `refine` step).

use crate::math::Aabb;
use glam::{DMat3, DVec3, Vec3};
use rayon::prelude::*;
use std::collections::HashMap;

/// The two functions whose common zero set is the curve, in the frame the curve is extracted in.
pub trait CurveFunctions: Sync {
    /// `f`, `g` and their gradients at `x`.
    fn eval(&self, x: Vec3) -> (f32, f32, Vec3, Vec3);
    /// `f` and `g` at a node of a face grid (may be computed more cheaply than [`Self::eval`]).
    fn values(&self, x: Vec3) -> (f32, f32);
    /// False only when the box `b` provably holds no point of the curve.
    fn may_hold(&self, b: &Aabb) -> bool;
    /// Whether the residuals `(f, g)` at `x` (gradients `gf`, `gg`) are at the solve's tolerance once
    /// Newton's step has reached the float resolution of `x`.
    fn converged(&self, x: Vec3, f: f32, g: f32, gf: Vec3, gg: Vec3) -> bool;
}

/// Extraction settings.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct CurveOptions {
    /// Depth of the culling octree.
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
    /// Boxes with more than two crossings even after `max_split` splits whose crossings pair up along
    /// the curve's tangents (two branches closer than the box, e.g. the sides of a thin tube).
    pub paired_boxes: usize,
    /// Boxes with more than two crossings even after `max_split` splits that do not pair up (skipped).
    pub unresolved_boxes: usize,
    /// Polyline vertices with one segment (the curve has a gap there).
    pub open_ends: usize,
    /// Polyline vertices with more than two segments.
    pub branch_points: usize,
    /// Chord midpoints whose projection failed (the chord is kept unrefined there).
    pub failed_refinements: usize,
}

/// An extracted curve: vertices on the curve and the segments between them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Polyline {
    /// Vertices, each on the curve up to the Newton tolerance.
    pub points: Vec<Vec3>,
    /// Segments as pairs of indices into `points`.
    pub segments: Vec<[u32; 2]>,
    /// `cumulative[i]` = total length of segments `0..=i` (f64, to keep the sum exact enough).
    pub cumulative: Vec<f64>,
    /// Extraction counters.
    pub stats: ExtractStats,
}

/// A point projected onto the curve from a polyline segment.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Projected {
    /// The curve point.
    pub x: Vec3,
    /// Unit tangent `∇f × ∇g / |∇f × ∇g|` at `x`.
    pub tangent: Vec3,
    /// `|T·t|`: the density per unit length of the true curve relative to the uniform density on the
    /// segment (see the module notes).
    pub cosine: f32,
}

/// The leaves of an octree over `root` that `keep` does not rule out: boxes are split into their eight
/// octants until depth `max_depth` or until their longest edge is at most `min_size`, and dropped as
/// soon as `keep` is false. Levels run in parallel; the order of the result is deterministic.
pub fn octree_leaves(
    root: Aabb,
    max_depth: u32,
    min_size: f32,
    keep: impl Fn(&Aabb) -> bool + Sync,
) -> Vec<Aabb> {
    let mut leaves = Vec::new();
    if root.is_empty() {
        return leaves;
    }
    let mut frontier = vec![root];
    for depth in 0..=max_depth {
        let kept: Vec<Aabb> = frontier.par_iter().filter(|b| keep(b)).copied().collect();
        let (leaf, inner): (Vec<Aabb>, Vec<Aabb>) = kept
            .into_iter()
            .partition(|b| depth == max_depth || b.extent().max_element() <= min_size);
        leaves.extend(leaf);
        frontier = inner.iter().flat_map(Aabb::octants).collect();
        if frontier.is_empty() {
            break;
        }
    }
    leaves
}

/// The curve point on the plane `n·x = c` near `x0` by Newton's method on `(f, g, n·x − c)`.
///
/// Each step solves the 3×3 system with rows `∇f, ∇g, n` (f64 solve of f32 evaluations). Fails when the
/// system is singular (the curve is tangent to the plane or `∇f ∥ ∇g`), when an iterate leaves the ball
/// of radius `reach` around `x0` (so a root of another branch is not taken), or when the residuals are
/// not at the tolerance ([`CurveFunctions::converged`]) once the Newton step has reached the f32
/// resolution of `x` (or, for `x` near the origin, that of the unit and stopped shrinking).
pub fn solve_on_plane(
    fns: &impl CurveFunctions,
    x0: Vec3,
    n: Vec3,
    c: f32,
    reach: f32,
) -> Option<Vec3> {
    let nd = n.as_dvec3();
    let mut x = x0.as_dvec3();
    // Start on the plane: the other two equations are then solved within it.
    x += nd * ((c as f64 - nd.dot(x)) / nd.length_squared());
    let mut prev = f64::INFINITY;
    for _ in 0..24 {
        let xf = x.as_vec3();
        let (f, g, gf, gg) = fns.eval(xf);
        let j = DMat3::from_cols(gf.as_dvec3(), gg.as_dvec3(), nd).transpose();
        let det = j.determinant();
        let norm = gf.length() as f64 * gg.length() as f64 * nd.length();
        if !det.is_finite() || det.abs() <= 1e-9 * norm {
            return None;
        }
        let r = DVec3::new(f as f64, g as f64, nd.dot(x) - c as f64);
        let step = j.inverse() * r;
        if !step.is_finite() {
            return None;
        }
        // Stop once the step is at the f32 resolution of x, or below that of the unit (the rounding floor
        // of f and g for shapes of unit size) and no longer converging: the residuals are then at their
        // rounding floor. Stopping at the unit's resolution alone is too early on a small curve (a sphere
        // of radius 0.02: a step of 3e-7 left |ψ| = 5e-5, above the tolerance, and lost the crossing).
        let scale = xf.length().max(1.0);
        let len = step.length();
        let eps = 4.0 * f32::EPSILON as f64;
        if len <= eps * xf.length() as f64 || (len <= eps * scale as f64 && len > 0.5 * prev) {
            return fns.converged(xf, f, g, gf, gg).then_some(xf);
        }
        prev = len;
        x -= step;
        if (x - x0.as_dvec3()).length() > reach as f64 {
            return None;
        }
    }
    None
}

/// Extracts the curve inside `boxes` (leaves that hold every curve point, e.g. from [`octree_leaves`];
/// see the module notes).
pub fn extract_polyline(
    fns: &impl CurveFunctions,
    boxes: &[Aabb],
    options: &CurveOptions,
) -> Polyline {
    let mut stats = ExtractStats {
        boxes: boxes.len(),
        ..Default::default()
    };
    let per_box: Vec<(Vec<[Vec3; 2]>, ExtractStats)> = boxes
        .par_iter()
        .map(|b| {
            let mut st = ExtractStats::default();
            let mut chords = Vec::new();
            box_chords(fns, b, options, options.max_split, &mut chords, &mut st);
            let mut pieces = Vec::new();
            for [a, e] in chords {
                refine_chord(fns, a, e, options.refine, &mut pieces, &mut st);
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
        stats.paired_boxes += st.paired_boxes;
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
    let mut polyline = Polyline {
        points,
        segments,
        cumulative: Vec::new(),
        stats,
    };
    let degree = polyline.degrees();
    polyline.stats.open_ends = degree.iter().filter(|&&d| d == 1).count();
    polyline.stats.branch_points = degree.iter().filter(|&&d| d > 2).count();
    let mut total = 0.0f64;
    polyline.cumulative = (polyline.segments.iter())
        .map(|s| {
            let [a, b] = polyline.segment(s);
            total += (b - a).as_dvec3().length();
            total
        })
        .collect();
    polyline
}

impl Polyline {
    /// Total length `L` of the polyline.
    pub fn length(&self) -> f64 {
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

    /// The two end points of a segment.
    pub fn segment(&self, s: &[u32; 2]) -> [Vec3; 2] {
        [self.points[s[0] as usize], self.points[s[1] as usize]]
    }

    /// The segment at fraction `u ∈ [0, 1]` of the total length (chosen with probability proportional to
    /// its length) and its index; `None` when empty.
    pub fn segment_at(&self, u: f32) -> Option<(usize, [Vec3; 2])> {
        let total = self.length();
        if total <= 0.0 {
            return None;
        }
        let target = (u as f64).clamp(0.0, 1.0) * total;
        let i = (self.cumulative)
            .partition_point(|&c| c < target)
            .min(self.segments.len() - 1);
        Some((i, self.segment(&self.segments[i])))
    }
}

/// The curve point in the plane orthogonal to the chord `[a, b]` at fraction `u ∈ [0, 1]` of it, with its
/// tangent and `|T·t|` (module notes); `None` when the projection fails (a rare loss, not re-weighted)
/// or the chord is degenerate.
pub fn project_from_chord(
    fns: &impl CurveFunctions,
    [a, b]: [Vec3; 2],
    u: f32,
) -> Option<Projected> {
    let len = (b - a).length();
    if !(len > 0.0 && len.is_finite()) {
        return None;
    }
    let t = (b - a) / len;
    let x0 = a + t * (u.clamp(0.0, 1.0) * len);
    let x = solve_on_plane(fns, x0, t, t.dot(x0), len)?;
    let (_, _, gf, gg) = fns.eval(x);
    let tangent = gf.cross(gg).try_normalize()?;
    Some(Projected {
        x,
        tangent,
        cosine: tangent.dot(t).abs(),
    })
}

/// Appends the chords of the curve pieces in `b` (see the module notes for the cases).
fn box_chords(
    fns: &impl CurveFunctions,
    b: &Aabb,
    options: &CurveOptions,
    splits: u32,
    out: &mut Vec<[Vec3; 2]>,
    stats: &mut ExtractStats,
) {
    let crossings = face_crossings(fns, b, options.face_grid.max(1));
    match crossings.len() {
        0 => stats.empty_boxes += 1,
        2 => {
            stats.resolved_boxes += 1;
            out.push([crossings[0], crossings[1]]);
        }
        _ if splits > 0 => {
            for child in b.octants() {
                if fns.may_hold(&child) {
                    box_chords(fns, &child, options, splits - 1, out, stats);
                }
            }
        }
        // Still one crossing after the splits: entry and exit closer than the de-duplication distance, the
        // curve clips an edge or a corner of the box; its piece here is shorter than 1e-3 of the box size.
        1 => stats.touching_boxes += 1,
        _ => match pair_along_tangents(fns, &crossings) {
            Some(chords) => {
                stats.paired_boxes += 1;
                out.extend(chords);
            }
            None => stats.unresolved_boxes += 1,
        },
    }
}

/// Chords joining `crossings` (an even number, at least 4) in pairs that each lie along the curve:
/// the chord's direction within `acos 0.9` of the unit tangent at both ends, the tangents oriented
/// the same way along it. Two branches closer together than the box, such as the two sides of a
/// tube thinner than the box, cross its faces four times and stay together through any split; each
/// branch's entry and exit pair up this way, while a chord across branches runs across the tangents
/// or against one of them (the two sides of a tube are oriented oppositely). `None` when some
/// crossing finds no such partner.
fn pair_along_tangents(fns: &impl CurveFunctions, crossings: &[Vec3]) -> Option<Vec<[Vec3; 2]>> {
    if !crossings.len().is_multiple_of(2) {
        return None;
    }
    let tangents: Vec<Vec3> = crossings
        .iter()
        .map(|&x| {
            let (_, _, gf, gg) = fns.eval(x);
            gf.cross(gg).try_normalize()
        })
        .collect::<Option<_>>()?;
    let mut pairs: Vec<(f32, usize, usize)> = Vec::new();
    for i in 0..crossings.len() {
        for j in i + 1..crossings.len() {
            let Some(d) = (crossings[j] - crossings[i]).try_normalize() else {
                continue;
            };
            let (a, b) = (tangents[i].dot(d), tangents[j].dot(d));
            if a * b > 0.0 && a.abs().min(b.abs()) >= 0.9 {
                pairs.push((a.abs().min(b.abs()), i, j));
            }
        }
    }
    pairs.sort_by(|p, q| q.0.total_cmp(&p.0));
    let mut taken = vec![false; crossings.len()];
    let mut chords = Vec::new();
    for (_, i, j) in pairs {
        if !taken[i] && !taken[j] {
            taken[i] = true;
            taken[j] = true;
            chords.push([crossings[i], crossings[j]]);
        }
    }
    taken.iter().all(|&t| t).then_some(chords)
}

/// The distinct crossings of the curve with the six faces of `b`.
///
/// Each face cell is searched ([`cell_crossings`]); the node coordinates depend only on the face, so a
/// face shared by two boxes gives the same crossings from both sides.
fn face_crossings(fns: &impl CurveFunctions, b: &Aabb, grid: usize) -> Vec<Vec3> {
    let size = b.extent().max_element();
    let mut found = Crossings {
        b,
        slack: 1e-4 * size,
        reach: size,
        points: Vec::new(),
    };
    for k in 0..3 {
        let (u, v) = ((k + 1) % 3, (k + 2) % 3);
        for c in [b.min[k], b.max[k]] {
            let face = Face { k, u, v, c };
            let at = |i: usize, j: usize| {
                (
                    b.min[u] + (b.max[u] - b.min[u]) * (i as f32 / grid as f32),
                    b.min[v] + (b.max[v] - b.min[v]) * (j as f32 / grid as f32),
                )
            };
            let vals: Vec<(f32, f32)> = (0..=grid)
                .flat_map(|j| (0..=grid).map(move |i| (i, j)))
                .map(|(i, j)| fns.values(face.point(at(i, j))))
                .collect();
            let value = |i: usize, j: usize| vals[j * (grid + 1) + i];
            for j in 0..grid {
                for i in 0..grid {
                    let corners = [
                        value(i, j),
                        value(i + 1, j),
                        value(i, j + 1),
                        value(i + 1, j + 1),
                    ];
                    let cell = [at(i, j), at(i + 1, j + 1)];
                    cell_crossings(fns, &face, cell, corners, THIN_SPLITS, &mut found);
                }
            }
        }
    }
    found.points
}

/// How many times a face cell that may hide a feature thinner than itself is split in four.
const THIN_SPLITS: u32 = 6;

/// The face `x_k = c` of a box, with in-face axes `u`, `v`.
struct Face {
    k: usize,
    u: usize,
    v: usize,
    c: f32,
}

impl Face {
    /// The point of the face with in-face coordinates `(p_u, p_v)`.
    fn point(&self, (pu, pv): (f32, f32)) -> Vec3 {
        let mut p = Vec3::ZERO;
        p[self.k] = self.c;
        p[self.u] = pu;
        p[self.v] = pv;
        p
    }
}

/// Crossings found on a box's faces so far, distinct and inside the box.
struct Crossings<'a> {
    b: &'a Aabb,
    slack: f32,
    reach: f32,
    points: Vec<Vec3>,
}

impl Crossings<'_> {
    /// Keeps `x` if it lies in the box (within `slack`) and is not one already found.
    fn push(&mut self, x: Vec3) {
        let (b, slack) = (self.b, self.slack);
        let inside = (0..3).all(|m| x[m] >= b.min[m] - slack && x[m] <= b.max[m] + slack);
        if inside && self.points.iter().all(|q| (*q - x).length() > 10.0 * slack) {
            self.points.push(x);
        }
    }
}

/// Searches the face cell `[lo, hi]` (in-face coordinates; `corners`: `(f, g)` at its corners in the
/// order `lo`, `(hi_u, lo_v)`, `(lo_u, hi_v)`, `hi`) for crossings.
///
/// Newton's method starts from the cell's centre when both `f` and `g` change sign at its corners. A
/// feature thinner than the cell (the two sides of a tube 1/45 of a pixel across) holds `f`'s zeros
/// with every corner outside it; `f` being a distance (Lipschitz 1), a cell where `g` changes sign,
/// `f` is within the cell's diagonal of 0 at a corner and within half of it at the centre may hide
/// such a feature, and is split in four, up to `splits` times, until its cells see `f` change sign.
fn cell_crossings(
    fns: &impl CurveFunctions,
    face: &Face,
    [lo, hi]: [(f32, f32); 2],
    corners: [(f32, f32); 4],
    splits: u32,
    found: &mut Crossings,
) {
    let changes = |f: fn(&(f32, f32)) -> f32| {
        let lo = corners.iter().map(f).fold(f32::INFINITY, f32::min);
        let hi = corners.iter().map(f).fold(f32::NEG_INFINITY, f32::max);
        lo <= 0.0 && hi >= 0.0
    };
    if !changes(|q| q.1) {
        return;
    }
    let mid = (0.5 * (lo.0 + hi.0), 0.5 * (lo.1 + hi.1));
    if changes(|q| q.0) {
        let mut n = Vec3::ZERO;
        n[face.k] = 1.0;
        if let Some(x) = solve_on_plane(fns, face.point(mid), n, face.c, found.reach) {
            found.push(x);
        }
        return;
    }
    // A zero of the distance `f` in the cell is within the diagonal of every corner and within half
    // of it of the centre.
    let diagonal = (hi.0 - lo.0).hypot(hi.1 - lo.1);
    if splits == 0 || corners.iter().all(|q| q.0.abs() > diagonal) {
        return;
    }
    let at = |p: (f32, f32)| fns.values(face.point(p));
    let centre = at(mid);
    if centre.0.abs() > 0.5 * diagonal {
        return;
    }
    // Values at the edge midpoints; the sub-cells' corners in the same order as the cell's.
    let (bottom, top) = (at((mid.0, lo.1)), at((mid.0, hi.1)));
    let (left, right) = (at((lo.0, mid.1)), at((hi.0, mid.1)));
    let [c00, c10, c01, c11] = corners;
    let cells = [
        ([lo, mid], [c00, bottom, left, centre]),
        ([(mid.0, lo.1), (hi.0, mid.1)], [bottom, c10, centre, right]),
        ([(lo.0, mid.1), (mid.0, hi.1)], [left, centre, c01, top]),
        ([mid, hi], [centre, right, top, c11]),
    ];
    for (cell, corners) in cells {
        cell_crossings(fns, face, cell, corners, splits - 1, found);
    }
}

/// Appends the chord `[a, e]` split `levels` times at curve points (midpoints projected onto the curve).
fn refine_chord(
    fns: &impl CurveFunctions,
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
    match solve_on_plane(fns, m, t, t.dot(m), len) {
        Some(x) => {
            refine_chord(fns, a, x, levels - 1, out, stats);
            refine_chord(fns, x, e, levels - 1, out, stats);
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
