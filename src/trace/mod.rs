//! Sphere tracing in `f32`: first hit along a ray, and every hit along a line.
//!
//! # What counts as a hit
//!
//! A hit is a **sign change** of `φ` along the ray, located to within a tolerance. The tracer marches the
//! function `g(t) = s·φ(o + t d)`, with `s = ±1` chosen so that `g(t0) ≥ 0` (`s = −1` if the ray starts
//! inside: then the first crossing is the *exit*; on the surface, see below).
//! Each step is `g/L` (Hart 1996), `L` the Lipschitz bound of `φ`, which cannot cross the surface. Where
//! that step falls below `64 h`, `h` the resolution (the local tolerance [`TraceSettings::eps_at`] where
//! the ray is, below written `eps`), the tracer *creeps* instead: steps of the larger of `g/L` and a
//! creep step, until `g` changes sign (an overshoot into the shape is fine: it brackets the crossing).
//! The creep step aims one and a half times as far as the secant through the last two values puts the
//! crossing (plus `h`) when `g` is falling, takes the full `64 h` when `g` is rising (the ray is
//! leaving a surface), and otherwise starts at `h` and doubles on each consecutive creep step; it is
//! never more than `64 h`. The bracket is then refined with the Illinois variant of regula falsi.
//! Creeping keeps grazing rays cheap: a ray skimming a unit sphere at `eps` stays within `eps` of it
//! for `2√(2 eps)` ≈ 280 `eps`, and a ray running parallel to a wall a few `eps` from it (leaving a wall
//! of a room at a shallow angle, a line tangent along a rounded edge) would advance by those few `eps`
//! per step with `g/L` alone, and by up to `64 eps` creeping. Aiming at the secant's crossing, a ray
//! approaching a surface needs one or two creep steps instead of the six of the doubling sequence, and
//! a ray leaving one (every shadow and bounce ray) leaves the creep zone in two or three.
//!
//! # Grid shapes
//!
//! A grid shape's tracer also skips the lattice cells that certainly hold no surface and steps with the
//! Lipschitz bound of the cells around the ray rather than the grid's largest ([`EmptySpace`]; the
//! bound of a cell's neighbourhood holds within one cell of it, so a step longer than a cell takes the
//! larger of that cell and the global step).
//!
//! Where that step is shorter than a cell, the tracer also uses the slope of `g` along the ray, `s`,
//! and a bound `M` of its second derivative over the cell's neighbourhood (from the control points'
//! second differences, [`EmptySpace`]): `g(t + τ) ≥ g + sτ − ½Mτ²`, so no crossing comes before
//! the first positive root of that parabola, and the step is the larger of `g/L` and nine tenths of
//! that root, at most a cell and never beyond the grid's box. `g/L` ignores the direction: a shadow or
//! bounce ray leaving a surface at an angle `θ` grows its steps only by a factor `1 + sin θ / L` each
//! from the tolerance, about 19 evaluations to leave the cells around the surface on the race's grid
//! (31³), against about 10 with the parabola; a ray grazing the surface gets Newton-like steps
//! `g/|s|` instead of `g/L`. After such a step the next point is evaluated with its gradient (the
//! grid's value and gradient from one pass over its taps), which the next step needs; so is the point
//! where a search starts or resumes, on a grid without transforms (whose value from that pass is the
//! value's bits).
//!
//! # Closed forms
//!
//! Spheres, planes, boxes, cylinders and similarity transforms of them have their crossings with a line
//! in closed form ([`Sdf::line_crossings`]); [`first_crossing`] and [`all_crossings_checked`] take those
//! instead of marching wherever the answer is certain, with the conventions below, and fall back to
//! marching where it is not: a start on the surface (its side is the one the ray moves into, which only
//! probing decides), a chord shorter than two creep steps (a graze, which marching may skip), a crossing
//! on a box's or a cylinder's rounded edge or corner (the sharp shape's crossing: the true one lies on
//! the solid's side of it, so it also counts behind the interval's start for an entry and beyond its
//! end for an exit), or a start within a tolerance of a crossing where the closed form disagrees with
//! the sign of `φ` there (rounding). Rays towards the horizon over a plane then cost nothing instead of running out of
//! steps. [`sphere_trace`] and [`all_hits`] always march.
//!
//! # Tolerances
//!
//! Every tolerance is local: at coordinates of magnitude `m` (the largest of `|x|, |y|, |z|`) the
//! resolution is `eps(m) = max(eps₀, 16 ε m)` and a point is on the surface when `|φ| ≤ eps(m)/100`, `ε`
//! the `f32` machine epsilon: tied to the rounding of the coordinates there, whatever the distance
//! between the scene's farthest objects. `eps₀` is a floor for small
//! coordinates, `10⁻⁴` times the size of the shape being traced (its bounds' smallest extent; the scene's
//! smallest shape for unbounded ones), so tolerances scale with the scene. Along a ray the magnitude is
//! bounded by `|o| + t`. The same local value sizes the margins elsewhere: the bounds a ray is clipped
//! to (at its entry point), the offset of rays leaving a surface (four tolerances), the boundary
//! samplers' occlusion margins and the area sampler's padding.
//!
//! A camera ray also resolves its pixel: at `t` the floor is at most `spread · t`
//! ([`TraceSettings::spread`], a sixteenth of the pixel's angular size), so that at a tiny field of
//! view, where a pixel is far smaller than the shape's `eps₀`, silhouettes are still traced to a
//! fraction of a pixel (the float resolution `16 ε m` remains the limit). The primary boundary term
//! looks up the background beyond an edge with the same camera-ray tolerance.
//!
//! Consequences, by design:
//! - **Tolerance.** The returned `t` satisfies `|φ(t)| ≤ eps/100` (or the bracket has shrunk to a few
//!   ulps of `t`), so `|t − t_true| ≲ 0.01·eps / |∇φ·d|`: tight for transversal hits, looser for grazing
//!   ones.
//! - **Tangent grazes** (the ray passing within `eps` of the surface without crossing it, or touching it) are
//!   **skipped**: they are not crossings. This is what tangent lines of the boundary sampler need (a line
//!   started on the surface at its tangent point must find the *next* real crossing) and what keeps
//!   [`all_hits`] alternating between entries and exits.
//! - **Thin features**: where the ray creeps, a crossing whose chord along the ray is shorter than the
//!   current creep step (at most `64 eps`) may be stepped over: a dip of depth `≲ 512 eps²/R` into a smooth
//!   surface of radius `R` (negligible for `R ≫ eps`), a box corner clipped over less than `64 eps`, a
//!   plate thinner than that along the ray. More than `64 eps` from every surface nothing is skipped.
//! - **Budget**: at most `settings.max_steps` evaluations of `φ` per crossing searched, plus the number of
//!   `64 eps` steps that cross the rest of the interval (capped at 16 `max_steps`; nothing for an
//!   unbounded interval): a ray parallel to a surface and within `64 eps` of it advances by about that
//!   much per step, so its cost follows the shape's size in tolerances. A ray that runs out reports
//!   [`ShapeTrace::Exhausted`]: a bug to report, which the renderer counts.
//! - **Starting on the surface** (`|φ(t0)| ≤ eps/100`, e.g. at a point the tracer returned): the ray
//!   belongs to the side it moves into, found by probing `φ` at `t0 + eps, t0 + 2 eps, …` (up to `64 eps`)
//!   until `|φ|` rises above the float noise; `t0` itself is never reported. So a ray leaving a surface
//!   point outward does not see that surface again, a ray entering it reports the exit, and a tangent line
//!   started at its tangent point finds the next real crossing. A ray starting *near* (but not on) the
//!   surface takes the side given by the sign of `φ(t0)`.
//! - **After a crossing** the same probe decides the new side; if the ray is back on its original side
//!   within the probe distance, the crossing was a graze at the noise level and is dropped.

use crate::math::Ray;
use crate::sdf::{Candidate, EmptySpace, LatticeRay, Lipschitz, Sdf};

/// Tolerances of the tracer.
///
/// The tolerance is local: at a point whose largest coordinate has magnitude `m` it is
/// [`TraceSettings::eps_at`]`(m) = max(eps, 16 ε m)` (`ε` the `f32` machine epsilon), so that it follows
/// the float resolution where the ray is and never the distance between a scene's farthest objects;
/// `eps` is a floor for coordinates near the origin, set from the size of the scene's smallest shape.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct TraceSettings {
    /// Tolerance floor in scene units: the hit tolerance where the coordinates are small (see
    /// [`TraceSettings::eps_at`]).
    ///
    /// The tolerance is also the tracer's resolution: closer than it to a surface the tracer advances by
    /// steps of it looking for the sign change; after refinement `|φ(t)|` is below
    /// [`TraceSettings::on_surface_at`] (see the [module docs](self)).
    pub eps: f32,
    /// Steps before a ray is declared exhausted, per crossing searched; the tracer adds the steps of
    /// at most `64 eps` that cross the rest of the interval, up to 16 times this (see the
    /// [module docs](self)).
    pub max_steps: u32,
    /// The detail a ray must resolve, per unit of its parameter: at `t` the tolerance floor is at most
    /// `spread · t` ([`TraceSettings::eps_along`]). A camera ray's is a fraction of its pixel's angular
    /// size, so that a narrow field of view sees its silhouettes where they are; infinite (no limit)
    /// for every other ray.
    pub spread: f32,
}

/// The local tolerance in ulps of the coordinates' magnitude (see [`TraceSettings`]).
pub const TOLERANCE_ULPS: f32 = 16.0;

impl TraceSettings {
    /// The hit tolerance where the largest coordinate has magnitude `magnitude`: `max(eps, 16 ε m)`.
    #[inline]
    pub fn eps_at(&self, magnitude: f32) -> f32 {
        self.eps
            .max(TOLERANCE_ULPS * f32::EPSILON * magnitude)
            .max(f32::MIN_POSITIVE)
    }

    /// The hit tolerance at parameter `t` of a ray whose origin's largest coordinate has magnitude
    /// `origin_magnitude` (a unit direction: the coordinates there are at most `origin_magnitude + |t|`):
    /// [`TraceSettings::eps_at`] with the floor lowered to `spread · |t|`, and never below the float
    /// resolution there.
    #[inline]
    pub fn eps_along(&self, origin_magnitude: f32, t: f32) -> f32 {
        let magnitude = origin_magnitude + t.abs();
        let footprint = self.spread * t.abs();
        if footprint < self.eps {
            footprint
                .max(TOLERANCE_ULPS * f32::EPSILON * magnitude)
                .max(f32::MIN_POSITIVE)
        } else {
            self.eps_at(magnitude)
        }
    }

    /// [`TraceSettings::eps_at`] the point `p`.
    #[inline]
    pub fn eps_at_point(&self, p: glam::Vec3) -> f32 {
        self.eps_at(p.abs().max_element())
    }

    /// `|φ|` below which a point of magnitude `magnitude` counts as on the surface (the refinement
    /// target): a hundredth of [`TraceSettings::eps_at`].
    #[inline]
    pub fn on_surface_at(&self, magnitude: f32) -> f32 {
        REFINE_FRACTION * self.eps_at(magnitude)
    }
}

impl Default for TraceSettings {
    fn default() -> Self {
        Self {
            eps: 1e-4,
            max_steps: 2048,
            spread: f32::INFINITY,
        }
    }
}

/// Result of tracing one implicit surface over a parameter interval.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum ShapeTrace {
    /// First crossing of the surface at parameter `t`.
    Hit(f32),
    /// No crossing in the interval.
    Miss,
    /// Ran out of steps before deciding; `t` is where it stopped.
    Exhausted(f32),
}

/// Largest creep step, in units of `eps`. A creep step can only miss a crossing whose chord along the ray
/// is shorter than the step: on a smooth surface of radius `R` that is a dip of depth `≲ (32 eps)² / 2R`
/// below the surface, below `eps` whenever `R ≳ 500 eps`.
pub(crate) const MAX_CREEP: f32 = 64.0;
/// How far past the secant's estimate of the crossing a step in the creep zone aims, as a multiple of
/// the estimate (plus one tolerance): far enough that an estimate a little short still brackets the
/// crossing, close enough that refinement starts from a narrow bracket.
const AIM_PAST: f32 = 1.5;
/// Cap of the interval-dependent part of the step budget ([`Marcher::budget`]), in units of
/// `max_steps`: bounds the work on a pathological interval (a tolerance floor far below the shape's
/// size).
const MAX_EXTRA_BUDGET: f32 = 16.0;
/// Refinement target: `|φ|` at the returned `t`, as a fraction of `eps`.
const REFINE_FRACTION: f32 = 0.01;
/// Refinement iterations (Illinois converges superlinearly: 4 to 8 are typical).
const REFINE_ITERATIONS: u32 = 40;

/// No cell of an [`EmptySpace`] known: look it up at the next step.
const NO_CELL: Candidate = Candidate {
    t: f32::NEG_INFINITY,
    until: f32::NEG_INFINITY,
    inv_lipschitz: [0.0; 2],
    curvature_radius: 0.0,
};

/// The side of the surface a ray is on at some `t`, and where marching may resume from.
#[derive(Copy, Clone, Debug)]
struct Side {
    /// `+1` outside, `−1` inside.
    sign: f32,
    /// Parameter to resume from.
    t: f32,
    /// `sign · φ` there (`≥ 0`).
    g: f32,
    /// The slope `∇φ · d` there, when the evaluation gave it ([`Marcher::phi_for_steps`]).
    slope: Option<f32>,
}

/// Outcome of one crossing search.
#[derive(Copy, Clone, Debug)]
enum Crossing {
    /// Root estimate `t`, and the far side of the surface to continue from.
    Hit {
        t: f32,
        next: Side,
    },
    Miss,
    Exhausted(f32),
}

/// The inverse of a usable Lipschitz bound. A non-positive or non-finite bound is a caller bug; in release
/// builds it falls back to 1 (exact for true distance functions) rather than looping or producing NaN.
#[inline]
fn inverse_lipschitz(lipschitz: f32) -> f32 {
    debug_assert!(
        lipschitz.is_finite() && lipschitz > 0.0,
        "Lipschitz bound must be finite and positive, got {lipschitz}"
    );
    if lipschitz.is_finite() && lipschitz > 0.0 {
        1.0 / lipschitz
    } else {
        1.0
    }
}

/// Smallest step that still moves `t` in `f32` (a few ulps), so a far ray cannot stall.
#[inline]
fn min_progress(t: f32) -> f32 {
    t.abs() * (4.0 * f32::EPSILON) + f32::MIN_POSITIVE
}

/// One tracing job: the function along the ray, the interval end and the step budget.
struct Marcher<'a> {
    sdf: &'a Sdf,
    ray: &'a Ray,
    /// The shape's certified empty cells, and the ray in their lattice coordinates: marching skips them.
    space: Option<(&'a EmptySpace, LatticeRay)>,
    /// The straddling cell where marching starts, when the caller's query of `space` found it: the
    /// first search takes it instead of asking again ([`NO_CELL`] otherwise).
    seed: Candidate,
    /// Inverse Lipschitz bounds outside and inside.
    inv_l: [f32; 2],
    t1: f32,
    settings: TraceSettings,
    /// Largest coordinate magnitude of the ray's origin: with `|t|` (the direction is a unit vector) a
    /// bound of the coordinates' magnitude along the ray, where the local tolerance is taken.
    origin_magnitude: f32,
    steps_left: u32,
    /// Evaluations spent refining brackets (not charged to the step budget; kept for tests).
    refine_evals: u32,
    /// Whether the field's value with its slope ([`Sdf::value_and_gradient`]) is its value bit for
    /// bit ([`Sdf::value_and_gradient_is_exact`]).
    exact_jet: bool,
}

impl<'a> Marcher<'a> {
    fn new(
        sdf: &'a Sdf,
        lipschitz: Lipschitz,
        ray: &'a Ray,
        t1: f32,
        settings: &TraceSettings,
    ) -> Self {
        let settings = TraceSettings {
            eps: if settings.eps > 0.0 {
                settings.eps
            } else {
                0.0
            },
            ..*settings
        };
        Self {
            sdf,
            ray,
            space: None,
            seed: NO_CELL,
            inv_l: [lipschitz.outside, lipschitz.inside].map(inverse_lipschitz),
            t1,
            settings,
            origin_magnitude: ray.o.abs().max_element(),
            steps_left: settings.max_steps,
            refine_evals: 0,
            exact_jet: sdf.value_and_gradient_is_exact(),
        }
    }

    /// The local tolerance at parameter `t` ([`TraceSettings::eps_at`]).
    #[inline]
    fn eps(&self, t: f32) -> f32 {
        self.settings.eps_along(self.origin_magnitude, t)
    }

    /// `|φ|` below which the point at `t` counts as on the surface.
    #[inline]
    fn on_surface(&self, t: f32) -> f32 {
        REFINE_FRACTION * self.eps(t)
    }

    /// The step budget of a crossing search from `t`: `max_steps`, plus the largest creep steps it takes
    /// to cross what is left of the interval. A ray running parallel to a surface a few tolerances
    /// from it (a line tangent along a rounded edge, a ray skimming a wall) advances by at most one such
    /// step at a time, so its cost grows with the interval's length in tolerances, not with the scene's
    /// complexity. An unbounded interval adds nothing.
    fn budget(&self, t: f32) -> u32 {
        let crossing = (self.t1 - t) / (MAX_CREEP * self.eps(t));
        let extra = if crossing.is_finite() && crossing > 0.0 {
            crossing.min(MAX_EXTRA_BUDGET * self.settings.max_steps as f32) as u32
        } else {
            0
        };
        self.settings.max_steps.saturating_add(extra)
    }

    #[inline]
    fn phi(&mut self, t: f32) -> f32 {
        self.steps_left = self.steps_left.saturating_sub(1);
        self.sdf.eval_f32(self.ray.at(t))
    }

    /// `φ` at `t` with its slope `∇φ · d` along the ray where the field has a grid's fast jet there
    /// (one evaluation of the spline's taps for both); `None` for the slope elsewhere.
    #[inline]
    fn phi_slope(&mut self, t: f32) -> (f32, Option<f32>) {
        match self.sdf.value_and_gradient(self.ray.at(t)) {
            Some((phi, gradient)) => {
                self.steps_left = self.steps_left.saturating_sub(1);
                (phi, Some(gradient.dot(self.ray.d)))
            }
            None => (self.phi(t), None),
        }
    }

    /// `φ` at `t`, with its slope along the ray where the second-order steps may need it next (a grid
    /// with its empty-space map) and one pass over the grid's taps gives both, the value bit for bit
    /// [`Marcher::phi`]'s: where a search starts or resumes (the first step there takes the slope).
    #[inline]
    fn phi_for_steps(&mut self, t: f32) -> (f32, Option<f32>) {
        if self.exact_jet && self.space.is_some() {
            self.phi_slope(t)
        } else {
            (self.phi(t), None)
        }
    }

    /// The side the ray is on at `t` (where `φ = phi`, with its slope `slope` if known). On the
    /// surface (`|φ| ≤ eps/100`, e.g. a point the tracer returned) the side is the one the ray moves
    /// into: probes at `t + eps, t + 2 eps, …` up to `64 eps` until `|φ|` exceeds the on-surface
    /// level, and marching resumes from that probe. This is what makes a tangent line started at its
    /// tangent point skip it: there `φ ≈ δ²κ/2` is below the float noise for the first few probes.
    fn side(&mut self, t: f32, phi: f32, slope: Option<f32>) -> Side {
        let sign_of = |v: f32| if v < 0.0 { -1.0 } else { 1.0 };
        let (eps, on_surface) = (self.eps(t), self.on_surface(t));
        if phi.abs() > on_surface {
            let sign = sign_of(phi);
            return Side {
                sign,
                t,
                g: sign * phi,
                slope,
            };
        }
        let mut delta = eps;
        let mut last = Side {
            sign: sign_of(phi),
            t,
            g: phi.abs(),
            slope,
        };
        while delta <= MAX_CREEP * eps && last.t < self.t1 {
            let tp = (t + delta.max(min_progress(t))).min(self.t1);
            let (p, slope) = self.phi_for_steps(tp);
            let sign = sign_of(p);
            last = Side {
                sign,
                t: tp,
                g: sign * p,
                slope,
            };
            if p.abs() > on_surface {
                break;
            }
            delta *= 2.0;
        }
        last
    }

    /// Marches `g = sign·φ` from `from` to the first sign change in `[from.t, t1]` that the ray does not
    /// immediately undo (a graze), and refines it.
    fn next_crossing(&mut self, mut from: Side) -> Crossing {
        let sign = from.sign;
        // Marching on one side needs only that side's bound.
        let inv_l = self.inv_l[usize::from(sign < 0.0)];
        let (mut t, mut g) = (from.t, from.g);
        // The doubling creep step inside the zone `g/L < MAX_CREEP · eps` (when the secant says neither
        // approaching nor leaving): starts at `eps`, doubles on each consecutive creep step up to
        // `MAX_CREEP · eps`, resets when the ray leaves the zone.
        let mut creep = self.eps(t);
        // The previous sample on this side, for the secant's estimate of where the surface is.
        let mut previous: Option<(f32, f32)> = None;
        // The straddling cell of `space` the ray is in, until it leaves it: the seed if the search
        // starts where it was found (the query there would find it again).
        let seed = std::mem::replace(&mut self.seed, NO_CELL);
        let mut cell = if seed.t == t { seed } else { NO_CELL };
        let side = usize::from(sign < 0.0);
        // The slope of `g` along the ray at `t`, when the evaluation there gave it.
        let mut slope: Option<f32> = from.slope.map(|s| sign * s);
        loop {
            // Also stops on a NaN parameter.
            if t.partial_cmp(&self.t1) != Some(std::cmp::Ordering::Less) {
                return Crossing::Miss;
            }
            if self.steps_left == 0 {
                return Crossing::Exhausted(t);
            }
            if let Some((space, lattice_ray)) = &self.space
                && t >= cell.until
            {
                // Out of the surface's cells the ray jumps to the next cell that can hold it.
                let Some(found) = space.first_candidate_lattice(lattice_ray, t, self.t1) else {
                    return Crossing::Miss;
                };
                cell = found;
                if found.t > t {
                    let (phi_next, slope_next) = self.phi_for_steps(found.t);
                    let g_next = sign * phi_next;
                    if g_next > 0.0 {
                        (t, g) = (found.t, g_next);
                        slope = slope_next.map(|s| sign * s);
                        previous = None;
                        creep = self.eps(t);
                        continue;
                    }
                    cell = NO_CELL;
                }
            }
            let mut safe = self.safe_step(g, inv_l, cell.inv_lipschitz[side]);
            // Where the Lipschitz step is short, the second-order bound may reach further; the point
            // after such a step is evaluated with its slope, which the next step will likely need.
            let mut curved = false;
            if let Some((space, lattice_ray)) = &self.space
                && cell.curvature_radius > 0.0
                && safe < space.cell_size
            {
                curved = true;
                let reach = space.cell_size.min(lattice_ray.exit() - t);
                let s = match slope {
                    Some(s) => s,
                    None => sign * self.sdf.gradient(self.ray.at(t)).dot(self.ray.d),
                };
                safe = safe.max(self.curved_step(s, g, cell.curvature_radius, reach));
            }
            let eps = self.eps(t);
            let step = if safe >= MAX_CREEP * eps {
                creep = eps;
                safe
            } else {
                let s = match previous {
                    // Approaching the surface: aim past the secant's root (an overshoot brackets the
                    // crossing for refinement) instead of creeping up to it from `eps`.
                    Some((tp, gp)) if gp > g => {
                        let root = g * (t - tp) / (gp - g);
                        (AIM_PAST * root + eps).min(MAX_CREEP * eps).max(creep)
                    }
                    // Moving away from it (leaving a surface): nothing nearer to resolve than what
                    // the largest creep step may skip anyway.
                    Some((_, gp)) if g > gp => MAX_CREEP * eps,
                    _ => creep,
                };
                creep = (2.0 * creep).min(MAX_CREEP * eps);
                s.max(safe)
            }
            .max(min_progress(t));
            let t_next = (t + step).min(self.t1);
            let (phi_next, slope_next) = if curved {
                self.phi_slope(t_next)
            } else {
                (self.phi(t_next), None)
            };
            let g_next = sign * phi_next;
            if g_next.is_nan() {
                return Crossing::Miss;
            }
            if g_next > 0.0 {
                slope = slope_next.map(|s| sign * s);
                previous = Some((t, g));
                t = t_next;
                g = g_next;
                continue;
            }
            let (hit, beyond, g_beyond) = self.refine(sign, t, g, t_next, g_next);
            let next = self.side(beyond, sign * g_beyond, None);
            // A crossing right at `t1` cannot be probed beyond: keep it.
            let undecided_at_end = next.t >= self.t1 && next.g <= self.on_surface(next.t);
            if next.sign != sign || undecided_at_end {
                return Crossing::Hit { t: hit, next };
            }
            // Back on the starting side within the probe distance: a graze at the float-noise level.
            from = next;
            t = from.t;
            g = from.g;
            slope = from.slope.map(|s| sign * s);
            creep = self.eps(t);
            previous = None;
        }
    }

    /// Illinois (modified regula falsi) on the bracket `[a, b]`, `g(a) > 0 ≥ g(b)`, until `|g| ≤ eps/100`
    /// at an end or the bracket is a few ulps wide. Returns the end with the smaller `|g|` as the hit, and
    /// the inside end `b` with its `g`.
    fn refine(&mut self, sign: f32, mut a: f32, ga: f32, mut b: f32, gb: f32) -> (f32, f32, f32) {
        // True values at the ends, and the weights Illinois uses for the secant (halved on the end that
        // is kept twice in a row, which restores superlinear convergence).
        let (mut ga, mut gb) = (ga, gb);
        let (mut wa, mut wb) = (ga, gb);
        let mut side = 0i8;
        let on_surface = self.on_surface(b);
        for _ in 0..REFINE_ITERATIONS {
            if ga.abs() <= on_surface || gb.abs() <= on_surface || b - a <= 2.0 * min_progress(b) {
                break;
            }
            // Root of the secant through (a, wa) and (b, wb): m = b − wb (b − a) / (wb − wa). With
            // wa > 0 ≥ wb the denominator wa − wb is positive unless both underflow; bisect then.
            let denom = wa - wb;
            let mut m = if denom > 0.0 {
                b + wb * (b - a) / denom
            } else {
                0.5 * (a + b)
            };
            if !(m > a && m < b) {
                m = 0.5 * (a + b);
            }
            // Refinement is not charged to the step budget: it is bounded by REFINE_ITERATIONS.
            self.refine_evals += 1;
            let gm = sign * self.sdf.eval_f32(self.ray.at(m));
            if gm > 0.0 {
                a = m;
                ga = gm;
                wa = gm;
                if side == 1 {
                    wb *= 0.5;
                }
                side = 1;
            } else {
                b = m;
                gb = gm;
                wb = gm;
                if side == -1 {
                    wa *= 0.5;
                }
                side = -1;
            }
        }
        let t = if ga.abs() < gb.abs() { a } else { b };
        (t, b, gb)
    }

    /// The step that cannot cross the surface from a point where `sign·φ = g`: `g/L` with the global
    /// bound (`inv_l = 1/L`), or with the bound of the grid cells around the point (`local`, 0 when
    /// unknown), which holds within one cell of it: the local step if it stays within that reach,
    /// else at least the reach itself.
    #[inline]
    fn safe_step(&self, g: f32, inv_l: f32, local: f32) -> f32 {
        let global = g * inv_l;
        match &self.space {
            Some((space, _)) if local > 0.0 => {
                let near = g * local;
                if near <= space.cell_size {
                    near.max(global)
                } else {
                    global.max(space.cell_size)
                }
            }
            _ => global,
        }
    }

    /// The step that cannot cross the surface from a point where `sign·φ = g > 0` by the second-order
    /// bound `g(t + τ) ≥ g + s τ − ½ M τ²` (`s` the slope of `sign·φ` along the ray, `M = 1/radius`
    /// bounding its second derivative within `reach`): nine tenths of the bound's first root, at most
    /// `reach`. Where the ray leaves the surface or grazes it, this is far longer than `g/L`, which
    /// ignores the direction: a ray leaving a surface at an angle would otherwise crawl out by steps
    /// growing geometrically from the tolerance.
    fn curved_step(&self, s: f32, g: f32, radius: f32, reach: f32) -> f32 {
        if !(reach > 0.0 && g > 0.0) {
            return 0.0;
        }
        let m = self.ray.d.length_squared() / radius;
        let root = (s * s + 2.0 * m * g).sqrt();
        // The first positive root of g + sτ − ½mτ², in the form without cancellation for each sign
        // of `s` (a linear bound where m = 0).
        let tau = if s < 0.0 {
            2.0 * g / (root - s)
        } else if m > 0.0 {
            (s + root) / m
        } else {
            f32::INFINITY
        };
        // Also 0 for a NaN slope.
        if tau > 0.0 {
            (0.9 * tau).min(reach)
        } else {
            0.0
        }
    }

    /// The first crossing in `[t0, t1]`, as [`sphere_trace`] reports it.
    fn first(&mut self, t0: f32) -> ShapeTrace {
        let Some(side) = self.start(t0) else {
            return ShapeTrace::Miss;
        };
        match self.next_crossing(side) {
            Crossing::Hit { t, .. } => ShapeTrace::Hit(t),
            Crossing::Miss => ShapeTrace::Miss,
            Crossing::Exhausted(t) => ShapeTrace::Exhausted(t),
        }
    }

    /// Every crossing in `[t0, t1]` in order, and where the budget ran out if it did, as
    /// [`all_hits_checked`] reports them (the budget is per crossing searched).
    fn all(&mut self, t0: f32) -> (Vec<f32>, Option<f32>) {
        let mut hits = Vec::new();
        let Some(mut side) = self.start(t0) else {
            return (hits, None);
        };
        loop {
            match self.next_crossing(side) {
                Crossing::Hit { t, next } => {
                    hits.push(t);
                    side = next;
                    self.steps_left = self.budget(side.t);
                }
                Crossing::Miss => return (hits, None),
                Crossing::Exhausted(at) => return (hits, Some(at)),
            }
        }
    }

    /// The side at `t0`, or `None` for an empty interval or a NaN value.
    fn start(&mut self, t0: f32) -> Option<Side> {
        // Rejects NaN bounds too.
        if !matches!(
            t0.partial_cmp(&self.t1),
            Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal)
        ) {
            return None;
        }
        self.steps_left = self.budget(t0);
        let (phi, slope) = self.phi_for_steps(t0);
        if phi.is_nan() {
            return None;
        }
        Some(self.side(t0, phi, slope))
    }
}

/// The crossings of `sdf` along `ray` in `(t0, t1]` from [`Sdf::line_crossings`], or `None` where the
/// marcher must decide: no closed form, a start on the surface (`|φ(t0)|` at most the on-surface level:
/// its side is the one the ray moves into, which the marcher probes), a chord shorter than two creep
/// steps (a graze, which the marcher may skip), a crossing on a rounded edge within `(t0, t1]` (or an
/// entry there behind `t0`, or an exit there beyond `t1`: the true crossing may lie on the other side
/// of the interval's end), or a start within a tolerance of a crossing where the closed form disagrees
/// with the sign of `φ(t0)`. With `first_only`, only the first crossing is wanted.
fn closed_form(
    sdf: &Sdf,
    ray: &Ray,
    t0: f32,
    t1: f32,
    settings: &TraceSettings,
    first_only: bool,
) -> Option<([f32; 2], usize)> {
    if t0.is_nan() || t1.is_nan() || t0 > t1 {
        return None;
    }
    let line = sdf.line_crossings(ray)?;
    let t = &line.t[..line.count];
    // The common miss of a bounded shape: nothing to check.
    if t.is_empty() {
        return Some(([0.0; 2], 0));
    }
    let origin_magnitude = ray.o.abs().max_element();
    if let [a, b] = *t {
        let eps = settings.eps_along(origin_magnitude, a.abs().max(b.abs()));
        if b - a < 2.0 * MAX_CREEP * eps {
            return None;
        }
    }
    // Only a start within a tolerance of a crossing can be on the surface or on the other side of it
    // by rounding: only then is `φ(t0)` needed (elsewhere the crossings' parity gives the side).
    let behind = t.iter().filter(|&&t| t <= t0).count();
    let eps0 = settings.eps_along(origin_magnitude, t0);
    if t.iter().any(|&t| (t - t0).abs() <= eps0) {
        let phi0 = sdf.eval_f32(ray.at(t0));
        if phi0.is_nan() || phi0.abs() <= REFINE_FRACTION * eps0 {
            return None;
        }
        if (phi0 < 0.0) != (line.inside_before ^ (behind % 2 == 1)) {
            return None;
        }
    }
    // An inexact crossing (on a rounded edge) is the sharp shape's: the true one lies on the solid's
    // side of it, later for an entry and earlier for an exit. So an inexact entry behind `t0` may still
    // be ahead (the ray may start outside), and an inexact exit beyond `t1` may still be within reach:
    // only the marcher can tell.
    let uncertain =
        |k: usize, exit: bool| !line.exact[k] && exit == (line.inside_before ^ (k % 2 == 1));
    if (0..behind).any(|k| uncertain(k, false)) {
        return None;
    }
    let mut found = ([0.0; 2], 0);
    for (k, &t) in t.iter().enumerate().skip(behind) {
        if t > t1 {
            if uncertain(k, true) {
                return None;
            }
            break;
        }
        if !line.exact[k] {
            return None;
        }
        found.0[found.1] = t;
        found.1 += 1;
        if first_only {
            break;
        }
    }
    Some(found)
}

/// First zero crossing of `sdf` along `ray` in `[t0, t1]`, with the conventions of [`sphere_trace`]:
/// from the closed form where the surface has one and the answer is certain (spheres, planes, the flat
/// faces of boxes and cylinders, the straight sides of cylinders, transforms of these:
/// [`Sdf::line_crossings`]), by sphere tracing otherwise.
pub fn first_crossing(
    sdf: &Sdf,
    lipschitz: impl Into<Lipschitz>,
    ray: &Ray,
    t0: f32,
    t1: f32,
    settings: &TraceSettings,
) -> ShapeTrace {
    first_crossing_skipping(sdf, lipschitz, None, ray, t0, t1, settings)
}

/// [`first_crossing`], skipping the cells of `space` that certainly hold no surface (a grid shape's
/// [`EmptySpace`], `ray` in the shape's frame).
pub fn first_crossing_skipping(
    sdf: &Sdf,
    lipschitz: impl Into<Lipschitz>,
    space: Option<&EmptySpace>,
    ray: &Ray,
    t0: f32,
    t1: f32,
    settings: &TraceSettings,
) -> ShapeTrace {
    // The ray in the lattice's coordinates, once for the first skip and the marcher's.
    let space = space.map(|s| (s, s.lattice_ray(ray)));
    let seed = match &space {
        Some((space, lattice_ray)) => match space.first_candidate_lattice(lattice_ray, t0, t1) {
            Some(found) => found,
            None => return ShapeTrace::Miss,
        },
        // No cell known: only the parameter is used.
        None => Candidate { t: t0, ..NO_CELL },
    };
    let t0 = seed.t;
    match closed_form(sdf, ray, t0, t1, settings, true) {
        Some((_, 0)) => ShapeTrace::Miss,
        Some((t, _)) => ShapeTrace::Hit(t[0]),
        None => {
            let mut m = Marcher::new(sdf, lipschitz.into(), ray, t1, settings);
            m.space = space;
            m.seed = seed;
            m.first(t0)
        }
    }
}

/// Every zero crossing of `sdf` along `ray` in `[t0, t1]`, with the conventions of
/// [`all_hits_checked`]: from the closed form where it is certain (see [`first_crossing`]), by sphere
/// tracing otherwise.
pub fn all_crossings_checked(
    sdf: &Sdf,
    lipschitz: impl Into<Lipschitz>,
    ray: &Ray,
    t0: f32,
    t1: f32,
    settings: &TraceSettings,
) -> (Vec<f32>, Option<f32>) {
    all_crossings_skipping(sdf, lipschitz, None, ray, t0, t1, settings)
}

/// [`all_crossings_checked`], skipping the cells of `space` that certainly hold no surface (a grid
/// shape's [`EmptySpace`], `ray` in the shape's frame), on either side of the surface.
pub fn all_crossings_skipping(
    sdf: &Sdf,
    lipschitz: impl Into<Lipschitz>,
    space: Option<&EmptySpace>,
    ray: &Ray,
    t0: f32,
    t1: f32,
    settings: &TraceSettings,
) -> (Vec<f32>, Option<f32>) {
    match closed_form(sdf, ray, t0, t1, settings, false) {
        Some((t, count)) => (t[..count].to_vec(), None),
        None => {
            let mut m = Marcher::new(sdf, lipschitz.into(), ray, t1, settings);
            m.space = space.map(|s| (s, s.lattice_ray(ray)));
            m.all(t0)
        }
    }
}

/// First zero crossing of `sdf` (Lipschitz bound `lipschitz`) along `ray` in `[t0, t1]`.
///
/// If the ray starts inside (`φ(o + t0 d) < 0`) the first crossing is where it leaves the shape; if it
/// starts on the surface, the side is the one it moves into and `t0` itself is not reported. Tangent
/// grazes are not crossings. See the [module docs](self) for the tolerance and the step budget.
pub fn sphere_trace(
    sdf: &Sdf,
    lipschitz: impl Into<Lipschitz>,
    ray: &Ray,
    t0: f32,
    t1: f32,
    settings: &TraceSettings,
) -> ShapeTrace {
    Marcher::new(sdf, lipschitz.into(), ray, t1, settings).first(t0)
}

/// Every zero crossing of `sdf` along `ray` in `[t0, t1]`, in increasing order.
///
/// Crossings alternate between entries and exits (the first one is an exit if the ray starts inside).
/// Tangent grazes are skipped. If the step budget runs out, the crossings found so far are returned; use
/// [`all_hits_checked`] to learn whether that happened.
pub fn all_hits(
    sdf: &Sdf,
    lipschitz: impl Into<Lipschitz>,
    ray: &Ray,
    t0: f32,
    t1: f32,
    settings: &TraceSettings,
) -> Vec<f32> {
    all_hits_checked(sdf, lipschitz, ray, t0, t1, settings).0
}

/// As [`all_hits`], also returning `Some(t)` if the search ran out of steps at `t` (the list is then
/// complete only up to `t`). The budget `settings.max_steps` is per crossing searched.
pub fn all_hits_checked(
    sdf: &Sdf,
    lipschitz: impl Into<Lipschitz>,
    ray: &Ray,
    t0: f32,
    t1: f32,
    settings: &TraceSettings,
) -> (Vec<f32>, Option<f32>) {
    Marcher::new(sdf, lipschitz.into(), ray, t1, settings).all(t0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Regression: the secant step once had its sign flipped, which sent every iterate out of the bracket
    /// and degraded Illinois to bisection (about 7 evaluations per hit instead of 1 or 2).
    #[test]
    fn refinement_converges_superlinearly() {
        let settings = TraceSettings {
            eps: 1e-3,
            max_steps: 512,
            ..TraceSettings::default()
        };
        let plane = Sdf::plane(Vec3::Y, 0.0);
        let sphere = Sdf::sphere([0.0, 0.0, 0.0], 1.0);
        for (sdf, most) in [(&plane, 1), (&sphere, 3)] {
            for k in 0..16 {
                // Aimed at points inside the unit sphere: every ray hits both surfaces.
                let origin = Vec3::new(0.05, 3.0, -0.1);
                let target = Vec3::new(0.05 * k as f32 - 0.4, 0.0, 0.1);
                let ray = Ray::new(origin, (target - origin).normalize());
                let mut m = Marcher::new(sdf, 1.0.into(), &ray, 10.0, &settings);
                // A bracket [a, b] around the first crossing, `eps` wide, as the marcher produces it.
                let t_hit = match sphere_trace(sdf, 1.0, &ray, 0.0, 10.0, &settings) {
                    ShapeTrace::Hit(t) => t,
                    other => panic!("{other:?}"),
                };
                let (a, b) = (t_hit - 0.3e-3, t_hit + 0.7e-3);
                let (ga, gb) = (sdf.eval_f32(ray.at(a)), sdf.eval_f32(ray.at(b)));
                let (t, _, _) = m.refine(1.0, a, ga, b, gb);
                assert!(sdf.eval_f32(ray.at(t)).abs() <= 0.01 * settings.eps);
                assert!(
                    m.refine_evals <= most,
                    "{} evaluations (ray {k})",
                    m.refine_evals
                );
            }
        }
    }

    /// On a grid under names only, a search that starts or resumes takes the slope from the same
    /// pass over the taps as the value; the steps are then those of computing it afresh, bit for
    /// bit: every crossing and every budget the same, on rays from afar and rays leaving the surface
    /// (where the first step takes the slope), with and without the carried slopes.
    #[test]
    fn carried_slopes_take_the_same_steps() {
        let lobes = Sdf::union(vec![
            Sdf::sphere([-0.4, 0.0, 0.1], 0.6),
            Sdf::sphere([0.5, 0.2, 0.0], 0.45),
        ]);
        let (lo, hi) = (Vec3::new(-1.2, -1.0, -1.0), Vec3::new(1.2, 1.0, 1.0));
        let grid = crate::sdf::Sdf::named(
            "blob",
            Sdf::grid(crate::sdf::bake(&lobes, lo, hi, 25), lo, hi).expect("a valid grid"),
        );
        assert!(grid.value_and_gradient_is_exact());
        let space = EmptySpace::of(&grid).expect("the surface stays in the box");
        let lipschitz = grid.lipschitz_sided();
        let settings = TraceSettings {
            eps: 1e-4,
            ..TraceSettings::default()
        };
        let mut rng = crate::sampler::Sampler::new(3, 0, 9, 0);
        let mut direction = || {
            let u = rng.next_2d();
            let z = 1.0 - 2.0 * u.x;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = std::f32::consts::TAU * u.y;
            Vec3::new(r * phi.cos(), r * phi.sin(), z)
        };
        let trace = |ray: &Ray, carried: bool| {
            let mut m = Marcher::new(&grid, lipschitz, ray, 10.0, &settings);
            m.space = Some((&space, space.lattice_ray(ray)));
            m.exact_jet = carried;
            let (hits, out) = m.all(0.0);
            (
                hits.iter().map(|t| t.to_bits()).collect::<Vec<_>>(),
                out,
                m.steps_left,
            )
        };
        let mut leaving = 0;
        for _ in 0..3000 {
            let o = direction() * 3.0;
            let mut ray = Ray::new(o, (direction() * 0.5 - o).normalize());
            let (hits, _, _) = trace(&ray, true);
            if let Some(&t) = hits.first() {
                // From the first hit, out into the hemisphere of its normal.
                let p = ray.at(f32::from_bits(t));
                let n = grid.normal(p);
                let w = direction();
                ray = Ray::new(p, if w.dot(n) < 0.0 { -w } else { w });
                leaving += 1;
            }
            assert_eq!(trace(&ray, true), trace(&ray, false), "ray {ray:?}");
        }
        assert!(leaving > 1000, "{leaving} rays leaving the surface");
    }
}
