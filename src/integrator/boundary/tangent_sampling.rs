//! The tangent angle `θ_B` of a secondary boundary sample, steered towards the emitters
//! ([`super::secondary`], supplemental §2; docs/theory.md §5.4).
//!
//! # The lines
//!
//! At a point `x_B` with unit normal `n` and an orthonormal tangent frame `(t₁, t₂)`, the angle
//! `θ ∈ [0, π)` names the **unoriented** tangent line `x_B + t ω(θ)`, `ω = cos θ t₁ + sin θ t₂`, `t ∈ ℝ`
//! (`θ` and `θ + π` are the same line: [`super::secondary`] traces it both ways). A direction `φ ∈ ℝ` of the
//! tangent plane is the line `θ = φ mod π`. Every set of lines below is an arc `{start + s : 0 ≤ s ≤ width}`
//! taken mod `π` ([`Interval`]; `0 < width ≤ π`), so an arc crossing `θ = π` needs no special case.
//!
//! **Rectangle emitter** (centre `c`, edge axes `u`, `v`, half sizes `a`, `b`): the tangent plane
//! `{x : n·(x − x_B) = 0}` cuts the rectangle (a convex polygon) in a chord `P₁P₂`, found from the signed
//! distances `s_i = n·(corner_i − x_B)` of the corners: a point on every edge whose ends have opposite signs.
//! A tangent line reaches the rectangle iff its direction points at the chord, i.e. the arc of directions
//! `φ` between `φ(P₁ − x_B)` and `φ(P₂ − x_B)` (the shorter one: the chord is a segment, it subtends at most
//! `π`, exactly `π` when `x_B` is on it). No chord (the plane misses the rectangle or touches one corner),
//! a chord seen edge-on (`x_B` on the rectangle's plane: both ends in one direction), and a tangent plane
//! parallel to the rectangle's plane give no arc. The rectangle emits on one side only: when `x_B` is
//! behind it (`N·(x_B − c) ≤ 0`) every segment `x_S x_B x_D` ending on it sees its back (`x_S`, `x_B`, `x_D`
//! are collinear with `x_B` between, so `N·(x_S − x_D)` has the sign of `N·(x_B − c)`) and carries no light:
//! no arc either.
//!
//! **Sphere emitter** (centre `C`, radius `R`): the plane cuts the sphere in a disk of centre
//! `C' = C − h n`, `h = n·(C − x_B)`, radius `r = √(R² − h²)` (none when `|h| ≥ R`). With `d = |C' − x_B|`
//! the lines through `x_B` that meet the disk are the directions within `asin(r / d)` of `C' − x_B`; all
//! lines when `d ≤ r` (`x_B` inside the disk). A point `x_B` inside the sphere itself sees only its inside,
//! which does not emit: no arc.
//!
//! These arcs are exact (every line of the arc reaches the emitter's surface when nothing is in between,
//! no other line does), which the tests check by tracing lines.
//!
//! # The mixture and its density
//!
//! One-sample MIS with the balance heuristic (Veach's thesis §9.2.4 "one-sample model"): pick strategy `i`
//! with probability `P_i`, draw `θ` from it, and weight the sample by the **mixture** density
//!
//! ```text
//!   p(θ) = P_u / π + Σ_e P_e · 1[θ ∈ arc_e] / width_e                                               (1)
//! ```
//!
//! evaluated at the drawn `θ` whichever strategy drew it (`f / p` is then unbiased for every integrand on
//! `[0, π)`; (1) is the balance heuristic's `w_i f / (P_i p_i)` summed in closed form). Strategy `u` is
//! uniform on `[0, π)`, strategy `e` uniform on emitter `e`'s arc. The probabilities depend on `x_B` only:
//!
//! - a fixed share [`UNIFORM_SHARE`] stays uniform, so `p ≥ UNIFORM_SHARE / π > 0` on all of `[0, π)`: the
//!   estimator stays unbiased for ends `x_D` that are not emitters (the lines the `path` integrator will
//!   continue) and for everything the arcs miss (occluders between, rounding at the arc ends);
//! - the rest is split among the emitters in proportion to `luminance(L_e) · width_e`, a proxy for the
//!   emitter's share of `∫ dθ` of the integrand (radiance times the set of lines that reach it). The
//!   environment is reached by every line that escapes, so its arc is all of `[0, π)` (width `π`): its
//!   share joins the uniform strategy (nothing cheaper knows which lines escape);
//! - with no arc at all (no finite emitter reachable from `x_B`'s tangent plane) the draw is uniform,
//!   `p = 1/π`.
//!
//! Consequently the density inside an arc is at most `1/π + (1 − UNIFORM_SHARE) L_e / Σ_f L_f width_f`;
//! arcs narrower than [`MIN_WIDTH`] are dropped so that `p` stays finite (their lines are still drawn by the
//! uniform strategy). One uniform number drives the whole draw (strategy choice, then its rescaled
//! remainder), so steering changes neither the number of random dimensions per sample nor, with
//! [`TangentSampling::Uniform`], the draws themselves (`θ = π u` as before).

use crate::emitter::{Emitter, Geometry};
use crate::scene::Scene;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// Share of the uniform strategy in the mixture (1); it bounds the weight `1 / p` of any line by
/// `π / UNIFORM_SHARE`. Measured on the floor-shadow scene of `tests/secondary_boundary.rs` (relative L2
/// after a 5×5 blur against a 600k-sample reference, 40k samples, three parameters): 0.1 scored 3–8%
/// lower than 0.25 and 0.5 15–35% higher. 0.25 is kept rather than 0.1 because lines ending on
/// non-emitters (which the `path` integrator will continue) and emitters behind occluders are drawn by
/// the uniform strategy alone.
pub const UNIFORM_SHARE: f32 = 0.25;

/// Arcs narrower than this (radians) are left to the uniform strategy: it keeps (1) finite.
pub const MIN_WIDTH: f32 = 1e-5;

/// How the secondary boundary term draws `θ_B`.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum TangentSampling {
    /// Uniform on `[0, π)` (density `1/π`), for comparisons.
    Uniform,
    /// The mixture (1) of the [module docs](self).
    #[default]
    Steered,
}

/// An arc of unoriented tangent lines: `θ = (start + s) mod π`, `0 ≤ s ≤ width`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Interval {
    /// First angle, in `[0, π)`.
    pub start: f32,
    /// Length of the arc, in `(0, π]`.
    pub width: f32,
}

impl Interval {
    /// All lines.
    pub const FULL: Interval = Interval {
        start: 0.0,
        width: PI,
    };

    /// The arc of directions from `a` to `b` (2D, in the tangent frame), the shorter way round; `None` if
    /// it is narrower than [`MIN_WIDTH`] or a direction is undefined.
    fn between(a: Vec2, b: Vec2) -> Option<Interval> {
        if a == Vec2::ZERO || b == Vec2::ZERO {
            return None;
        }
        let delta = a.perp_dot(b).atan2(a.dot(b));
        let first = if delta >= 0.0 { a } else { b };
        Self::new(first.y.atan2(first.x), delta.abs())
    }

    /// The arc starting at direction `start` (any angle) of length `width` (clamped to `π`); `None` if
    /// narrower than [`MIN_WIDTH`] or not finite.
    fn new(start: f32, width: f32) -> Option<Interval> {
        if !(width >= MIN_WIDTH && start.is_finite()) {
            return None;
        }
        if width >= PI {
            return Some(Self::FULL);
        }
        Some(Interval {
            start: wrap(start),
            width,
        })
    }

    /// Whether the line `theta ∈ [0, π)` is in the arc (ends included).
    #[inline]
    pub fn contains(&self, theta: f32) -> bool {
        let mut d = theta - self.start;
        if d < 0.0 {
            d += PI;
        }
        d <= self.width
    }

    /// The line at fraction `u ∈ [0, 1)` of the arc, in `[0, π)`.
    #[inline]
    pub fn at(&self, u: f32) -> f32 {
        wrap(self.start + u * self.width)
    }
}

/// `theta mod π` in `[0, π)` (rounding can make `rem_euclid` return `π` itself: that is the line `0`).
#[inline]
fn wrap(theta: f32) -> f32 {
    let t = theta.rem_euclid(PI);
    if t >= PI { 0.0 } else { t }
}

/// Relative luminance (Rec. 709) of a radiance: the weight of an emitter in the mixture.
fn luminance(rgb: Vec3) -> f32 {
    let l = rgb.dot(Vec3::new(0.2126, 0.7152, 0.0722));
    if l.is_finite() { l.max(0.0) } else { 0.0 }
}

/// The arc of tangent lines at `x_B` (tangent plane normal `n`, frame `t1`, `t2`) that reach a finite
/// emitter of geometry `g`; see [`emitter_interval`].
fn interval(g: &Geometry, x_b: Vec3, t1: Vec3, t2: Vec3, n: Vec3) -> Option<Interval> {
    let local = |p: Vec3| {
        let q = p - x_b;
        Vec2::new(q.dot(t1), q.dot(t2))
    };
    match *g {
        Geometry::Rectangle {
            center,
            normal,
            u,
            v,
            size,
        } => {
            let half = [0.5 * size[0], 0.5 * size[1]];
            // Behind the emitting side, or a tangent plane parallel to the rectangle: no light.
            let front = normal.dot(x_b - center);
            if !(front > 0.0 && front.is_finite()) || normal.cross(n).length_squared() < 1e-10 {
                return None;
            }
            let (a, b) = (u * half[0], v * half[1]);
            let corners = [
                center - a - b,
                center + a - b,
                center + a + b,
                center - a + b,
            ];
            let s = corners.map(|p| n.dot(p - x_b));
            let mut points = [Vec2::ZERO; 4];
            let mut count = 0;
            for i in 0..4 {
                let j = (i + 1) % 4;
                if s[i] == 0.0 {
                    points[count] = local(corners[i]);
                    count += 1;
                } else if s[j] != 0.0 && (s[i] < 0.0) != (s[j] < 0.0) {
                    let t = s[i] / (s[i] - s[j]);
                    points[count] = local(corners[i] + (corners[j] - corners[i]) * t);
                    count += 1;
                }
            }
            // The chord's ends are the pair of points farthest apart in angle (more than two points
            // only when corners lie on the plane: duplicates of the ends).
            let mut best: Option<Interval> = None;
            for i in 0..count {
                for j in i + 1..count {
                    if let Some(arc) = Interval::between(points[i], points[j])
                        && best.is_none_or(|b| arc.width > b.width)
                    {
                        best = Some(arc);
                    }
                }
            }
            best
        }
        Geometry::Sphere { center, radius } => {
            let q = center - x_b;
            if q.length_squared() <= radius * radius {
                return None;
            }
            let h = n.dot(q);
            let r2 = radius * radius - h * h;
            if !(r2 > 0.0 && r2.is_finite()) {
                return None;
            }
            let c = local(center);
            let d2 = c.length_squared();
            if d2 <= r2 {
                return Some(Interval::FULL);
            }
            let half = (r2 / d2).sqrt().min(1.0).asin();
            Interval::new(c.y.atan2(c.x) - half, 2.0 * half)
        }
    }
}

/// The scene's emitters as seen by the tangent sampler (built once per pass).
#[derive(Clone, Debug)]
pub struct TangentSampler {
    /// Finite emitters with their luminance (empty for [`TangentSampling::Uniform`]).
    targets: Vec<(Geometry, f32)>,
    /// `luminance · π` of the environment's mean radiance (0 without one).
    environment: f32,
}

impl TangentSampler {
    /// The sampler for `scene`'s emitters.
    pub fn new(scene: &Scene, mode: TangentSampling) -> Self {
        Self::from_emitters(scene.emitters.iter().map(|e| &e.emitter), mode)
    }

    /// The sampler for a list of emitters.
    pub fn from_emitters<'a>(
        emitters: impl IntoIterator<Item = &'a Emitter>,
        mode: TangentSampling,
    ) -> Self {
        let mut targets = Vec::new();
        let mut environment = 0.0;
        if mode == TangentSampling::Steered {
            // Delta lights are at no point a tangent line could reach.
            for emitter in emitters.into_iter().filter(|e| !e.is_delta()) {
                let l = luminance(emitter.mean_radiance());
                match emitter.geometry() {
                    Some(g) if l > 0.0 => targets.push((g, l)),
                    Some(_) => {}
                    None => environment += l * PI,
                }
            }
        }
        Self {
            targets,
            environment,
        }
    }

    /// The mixture (1) at `x_B` with unit normal `n` and tangent frame `(t1, t2)` (orthonormal, `t1 × t2`
    /// along `n` or not: only the plane matters).
    pub fn distribution(&self, x_b: Vec3, t1: Vec3, t2: Vec3, n: Vec3) -> TangentDistribution {
        let mut arcs = Vec::new();
        let mut total = 0.0f32;
        for (target, l) in &self.targets {
            if let Some(arc) = interval(target, x_b, t1, t2, n) {
                let w = l * arc.width;
                if w > 0.0 && w.is_finite() {
                    total += w;
                    arcs.push((arc, w));
                }
            }
        }
        if arcs.is_empty() || !(total > 0.0 && total.is_finite()) {
            return TangentDistribution::uniform();
        }
        let rest = 1.0 - UNIFORM_SHARE;
        let norm = rest / (total + self.environment);
        let uniform = UNIFORM_SHARE + self.environment * norm;
        TangentDistribution {
            uniform,
            arcs: arcs.into_iter().map(|(arc, w)| (arc, w * norm)).collect(),
        }
    }
}

/// The mixture (1) at one `x_B`: the uniform strategy and one arc per reachable emitter.
#[derive(Clone, Debug, PartialEq)]
pub struct TangentDistribution {
    /// Probability of the uniform strategy (environment included).
    uniform: f32,
    /// The arcs with their strategy probabilities (`uniform + Σ = 1` up to rounding).
    arcs: Vec<(Interval, f32)>,
}

impl TangentDistribution {
    /// Uniform on `[0, π)`.
    pub fn uniform() -> Self {
        Self {
            uniform: 1.0,
            arcs: Vec::new(),
        }
    }

    /// The arcs of the emitter strategies with their probabilities.
    pub fn arcs(&self) -> &[(Interval, f32)] {
        &self.arcs
    }

    /// Probability of the uniform strategy.
    pub fn uniform_probability(&self) -> f32 {
        self.uniform
    }

    /// A line `θ ∈ [0, π)` from one uniform number `u ∈ [0, 1)`: the strategy, then `u` rescaled within it.
    pub fn sample(&self, u: f32) -> f32 {
        if u < self.uniform || self.arcs.is_empty() {
            return wrap(PI * (u / self.uniform).min(1.0));
        }
        let mut lo = self.uniform;
        for (k, (arc, p)) in self.arcs.iter().enumerate() {
            // The last strategy takes whatever rounding left over.
            if u < lo + p || k + 1 == self.arcs.len() {
                let v = ((u - lo) / p).clamp(0.0, 1.0);
                return arc.at(v);
            }
            lo += p;
        }
        unreachable!("the last arc takes every remaining u")
    }

    /// The mixture density (1) at `theta ∈ [0, π)`, per radian; at least `UNIFORM_SHARE / π` (or `1/π`),
    /// always finite.
    pub fn pdf(&self, theta: f32) -> f32 {
        let mut p = self.uniform / PI;
        for (arc, q) in &self.arcs {
            if arc.contains(theta) {
                p += q / arc.width;
            }
        }
        p
    }
}

/// The arc of tangent lines at `x_B` that reach `emitter` (see the [module docs](self)); `None` for the
/// environment, for an emitter no line reaches with light, and for arcs narrower than [`MIN_WIDTH`].
pub fn emitter_interval(
    emitter: &Emitter,
    x_b: Vec3,
    t1: Vec3,
    t2: Vec3,
    n: Vec3,
) -> Option<Interval> {
    interval(&emitter.geometry()?, x_b, t1, t2, n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_mode_draws_pi_u() {
        let d = TangentDistribution::uniform();
        for u in [0.0f32, 0.1, 0.5, 0.999_999_9] {
            assert_eq!(d.sample(u), PI * u);
            assert_eq!(d.pdf(d.sample(u)), 1.0 / PI);
        }
    }

    #[test]
    fn arcs_wrap_around_pi() {
        let arc = Interval::new(-0.2, 0.5).unwrap();
        assert!((arc.start - (PI - 0.2)).abs() < 1e-6);
        assert!(arc.contains(0.1) && arc.contains(PI - 0.1) && !arc.contains(0.4));
        assert!(arc.contains(arc.at(0.0)) && arc.contains(arc.at(0.999)));
        assert_eq!(Interval::new(1.0, 4.0), Some(Interval::FULL));
        assert_eq!(Interval::new(1.0, 0.0), None);
        assert_eq!(Interval::new(f32::NAN, 1.0), None);
        assert_eq!(Interval::new(1.0, f32::NAN), None);
    }
}
