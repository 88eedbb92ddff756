//! Where a whole line crosses a surface, in closed form, for the nodes that have one: spheres, planes,
//! boxes and cylinders (exactly where the line crosses a flat face or a straight side) and similarity
//! transforms of these.
//!
//! The tracer ([`crate::trace::first_crossing`]) takes these instead of marching when they are certain,
//! and marches otherwise; the surface is still the SDF's zero set, and derivatives still come from the
//! SDF. The formulas:
//! - **sphere**: the roots of `|f + t d|² = r²`, `f = o − c`, in the form that keeps its precision for
//!   far and grazing rays (Haines et al., "Precision improvements for ray/sphere intersection", *Ray
//!   Tracing Gems*, 2019, ch. 7), for a direction of any length `a = |d|²` (a unit vector in `f32` is
//!   one only to rounding, which far along a grazing ray moves the roots by more than the tolerance):
//!   `b = −f·d`, `h² = (r² − |f + (b/a) d|²)/a`, `q = b/a + sign(b) h`, roots `c/(a q)` and `q` with
//!   `c = |f|² − r²`;
//! - **plane**: `t = (offset − n·o)/(n·d)`;
//! - **box**: the slab test of the sharp box with the outer extents. A rounded box lies inside it and
//!   touches it exactly on the flat part of each face, so a crossing of the sharp box there is a crossing
//!   of the rounded one; a crossing on a rounded edge or corner is reported as *inexact* (the tracer then
//!   marches);
//! - **cylinder** (axis `a`, radius `R`, half height `H`): the line between the caps' planes
//!   (`|h| ≤ H`, `h = (o − c)·a + t d·a`) and within the infinite cylinder `ρ ≤ R` (the sphere's
//!   roots above for the line's part across the axis, `f − (f·a) a + t (d − (d·a) a)`, of any length),
//!   intersected. As for the box, a rounded cylinder lies inside the sharp one and touches it exactly on
//!   the flat part of the caps (`ρ ≤ R − rounding`) and the straight part of the side
//!   (`|h| ≤ H − rounding`); a crossing elsewhere is inexact;
//! - **transform** `x = T + s R p`: the line mapped into the child's frame (`o' = R⁻¹(o − T)/s`,
//!   `d' = R⁻¹ d / s`: the same parameter `t`; [`super::Similarity::to_child_ray`]).

use super::Sdf;
use crate::math::Ray;

/// The crossings of a whole line `o + t d` (`t ∈ ℝ`) with a surface.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct LineCrossings {
    /// Crossing parameters in increasing order; the first `count` are used.
    pub t: [f32; 2],
    /// Number of crossings (0, 1 or 2).
    pub count: usize,
    /// Whether each crossing is exact. A box's crossing on a rounded edge or corner is not: its parameter
    /// is the sharp box's, before the true crossing.
    pub exact: [bool; 2],
    /// Whether the line is inside the solid before its first crossing (`t → −∞`): true for a half-space
    /// the line leaves, false for bounded shapes.
    pub inside_before: bool,
}

impl LineCrossings {
    /// No crossing; `inside_before` says on which side the whole line lies.
    fn none(inside_before: bool) -> Self {
        Self {
            t: [0.0; 2],
            count: 0,
            exact: [true; 2],
            inside_before,
        }
    }

    /// Crossings `t0 ≤ t1` of a bounded solid.
    fn pair(t0: f32, t1: f32, exact: [bool; 2]) -> Self {
        Self {
            t: [t0, t1],
            count: 2,
            exact,
            inside_before: false,
        }
    }
}

impl Sdf {
    /// The crossings of the whole line `ray.o + t ray.d` with the surface `φ = 0`, in closed form, or
    /// `None` for nodes without one (CSG, grids, tori, capsules) or when the arithmetic is
    /// not finite. See the `line_crossings` module docs for the formulas.
    pub fn line_crossings(&self, ray: &Ray) -> Option<LineCrossings> {
        let (o, d) = (ray.o, ray.d);
        let crossings = match self {
            Sdf::Sphere { center, radius } => {
                match ball_roots(o - center.value(), d, radius.value)? {
                    Some((near, far)) => LineCrossings::pair(near, far, [true; 2]),
                    None => LineCrossings::none(false),
                }
            }
            Sdf::Plane { normal, offset } => {
                let (height, slope) = (normal.dot(o) - offset.value, normal.dot(d));
                let t = -height / slope;
                if t.is_finite() {
                    LineCrossings {
                        t: [t, t],
                        count: 1,
                        exact: [true; 2],
                        inside_before: slope > 0.0,
                    }
                } else {
                    LineCrossings::none(height < 0.0)
                }
            }
            Sdf::Box {
                center,
                half_size,
                rounding,
            } => box_crossings(o - center.value(), d, half_size.value(), rounding.value)?,
            Sdf::Transform { .. } => {
                let (frame, child) = self.frame()?;
                child.line_crossings(&frame.to_child_ray(ray))?
            }
            Sdf::Cylinder {
                center,
                axis,
                radius,
                half_height,
                rounding,
            } => cylinder_crossings(
                o - center.value(),
                d,
                *axis,
                [radius.value, half_height.value],
                rounding.value,
            )?,
            Sdf::Named { child, .. } => child.line_crossings(ray)?,
            _ => return None,
        };
        let finite = crossings.t[..crossings.count].iter().all(|t| t.is_finite());
        finite.then_some(crossings)
    }
}

/// The roots `t₀ ≤ t₁` of `|f + t d|² = r²` (`d` of any length), in the stable form of the module docs;
/// `Some(None)` where the line misses or grazes, `None` where the arithmetic is not finite.
#[inline]
fn ball_roots(f: glam::Vec3, d: glam::Vec3, r: f32) -> Option<Option<(f32, f32)>> {
    // `a = |d|²`: a direction is a unit vector only to rounding, and the tracer walks the line as
    // given, so the roots are those of `a t² − 2 b t + c` with `b = −f·d`.
    let a = d.length_squared();
    let b = -f.dot(d);
    let v = f + (b / a) * d;
    let h2 = (r - v.length()) * (r + v.length()) / a;
    if h2.is_nan() {
        return None;
    }
    if h2 <= 0.0 {
        return Some(None);
    }
    let q = b / a + h2.sqrt().copysign(b);
    let c = (f.length() - r) * (f.length() + r);
    let (near, far) = (c / (a * q), q);
    Some(Some((near.min(far), near.max(far))))
}

/// The crossings of the line `f + t d` (`f` from the centre) with the cylinder of unit axis `axis`,
/// radius and half height `[r, half]`, its rims rounded by `rounding`: the sharp cylinder's, exact where
/// the line meets a flat cap or the straight side (see the module docs).
#[inline]
fn cylinder_crossings(
    f: glam::Vec3,
    d: glam::Vec3,
    axis: glam::Vec3,
    [r, half]: [f32; 2],
    rounding: f32,
) -> Option<LineCrossings> {
    let (h0, dh) = (f.dot(axis), d.dot(axis));
    let (rf, rd) = (f - h0 * axis, d - dh * axis);
    // Between the caps' planes; 0/0 (a line in a cap's plane) is undecidable here: the tracer decides.
    let (ta, tb) = ((-half - h0) / dh, (half - h0) / dh);
    if ta.is_nan() || tb.is_nan() {
        return None;
    }
    let (cap_in, cap_out) = (ta.min(tb), ta.max(tb));
    // Within the infinite cylinder: a line parallel to the axis is inside everywhere or nowhere.
    let (side_in, side_out) = if rd == glam::Vec3::ZERO {
        if rf.length() > r {
            return Some(LineCrossings::none(false));
        }
        (f32::NEG_INFINITY, f32::INFINITY)
    } else {
        match ball_roots(rf, rd, r)? {
            Some(roots) => roots,
            None => return Some(LineCrossings::none(false)),
        }
    };
    let (t_in, t_out) = (cap_in.max(side_in), cap_out.min(side_out));
    if t_in >= t_out {
        return Some(LineCrossings::none(false));
    }
    let exact = |t: f32, on_cap: bool| {
        if on_cap {
            (rf + t * rd).length() <= r - rounding
        } else {
            (h0 + t * dh).abs() <= half - rounding
        }
    };
    let exact = [
        exact(t_in, cap_in >= side_in),
        exact(t_out, cap_out <= side_out),
    ];
    Some(LineCrossings::pair(t_in, t_out, exact))
}

/// The crossings of the line `q + t d` (in the box's frame) with the box of half extents `half`, its
/// edges rounded by `rounding`: the sharp box's slab test, exact where the line meets a flat face.
#[inline]
fn box_crossings(
    q: glam::Vec3,
    d: glam::Vec3,
    half: glam::Vec3,
    rounding: f32,
) -> Option<LineCrossings> {
    // In SIMD lanes: the same IEEE operations lane by lane as in `Vec3` (this runs for every box on
    // every ray).
    use glam::{BVec3A, Vec3A};
    let (q, d, half) = (Vec3A::from(q), Vec3A::from(d), Vec3A::from(half));
    let inv = d.recip();
    let ta = (-half - q) * inv;
    let tb = (half - q) * inv;
    // 0·∞ (a line in a face's plane) is undecidable here: the tracer decides.
    if (ta.is_nan_mask() | tb.is_nan_mask()).any() {
        return None;
    }
    let (lo, hi) = (ta.min(tb), ta.max(tb));
    let (t_in, t_out) = (lo.max_element(), hi.min_element());
    // Not NaN: the slabs were checked above.
    if t_in >= t_out {
        return Some(LineCrossings::none(false));
    }
    // Exact where the point lies within the flat part of every other axis's extent; the face's own
    // axis is the first whose slab gave the crossing.
    let inner = half - Vec3A::splat(rounding);
    let flat = |t: f32, slabs: Vec3A| {
        let face = if slabs.x == t {
            BVec3A::new(true, false, false)
        } else if slabs.y == t {
            BVec3A::new(false, true, false)
        } else if slabs.z == t {
            BVec3A::new(false, false, true)
        } else {
            BVec3A::new(true, false, false)
        };
        ((q + t * d).abs().cmple(inner) | face).all()
    };
    let exact = [flat(t_in, lo), flat(t_out, hi)];
    Some(LineCrossings::pair(t_in, t_out, exact))
}
