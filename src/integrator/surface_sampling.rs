//! Area sampling of an implicit surface with an exact density, as Zhou et al. (2024) do it (docs/theory.md §5.3,
//! secondary boundary): lines through the shape's bounding box along a coordinate axis, **every** crossing
//! with the surface kept, the three axes combined by multiple importance sampling.
//!
//! # One line
//!
//! Let `B` be the shape's world bounding box ([`Shape::bounds`]) with edge lengths `e`, and `F_a` its face
//! perpendicular to axis `a`, of area `A_a = e_b e_c` (`b, c` the other two axes). A line is drawn by
//! 1. choosing an axis `a` with probability `c_a = A_a / Σ_b A_b` (one number `u_axis`);
//! 2. choosing `q` uniformly on `F_a`, density `1 / A_a` (two numbers `u_face`);
//! 3. tracing the line `ℓ_q = {q + t e_a}` across the box and keeping every crossing `x` of the surface
//!    ([`crate::trace::all_crossings_skipping`]: a grid shape skips the cells that hold no surface).
//!
//! # Density of a hit
//!
//! The orthogonal projection `π_a : S → F_a` has area Jacobian `|n(x)·e_a|`, so (area formula) for any `g`
//!
//! ```text
//! ∫_{F_a} Σ_{x ∈ S ∩ ℓ_q} g(x) dq = ∫_S g(x) |n(x)·e_a| dA(x).                                  (1)
//! ```
//!
//! A hit of an axis-`a` line therefore has area density `p_a(x) = |n(x)·e_a| / A_a`, in the sense that
//! the *expected number* of axis-`a` hits in a surface patch `dA` is `p_a(x) dA`. Over the three axes
//! (one-sample MIS model) the combined density is
//!
//! ```text
//! p(x) = Σ_a c_a p_a(x) = Σ_a |n_a(x)| / Σ_a A_a = |n(x)|₁ / (A_x + A_y + A_z),               (2)
//! ```
//!
//! (axes with a face of zero area are never chosen and drop out of both sums). Since `|n| = 1`,
//! `|n|₁ ≥ 1`, so `p ≥ 1/ΣA` everywhere on the surface: no normal is perpendicular to all three axes.
//! Choosing `c_a ∝ A_a` is what makes (2) independent of the box's aspect ratio and keeps the weights
//! `1/p` within a factor `√3` of each other; uniform `c_a` would weight thin boxes badly.
//!
//! # The estimator (several hits per line)
//!
//! A line has any number of hits (zero if it misses, two for a convex shape, more for a torus), and its
//! estimate of `∫_S f dA` is the **sum over its hits**
//!
//! ```text
//! ⟨I⟩ = Σ_{x ∈ S ∩ ℓ_q} f(x) / p(x),                                                          (3)
//! ```
//!
//! `p` from (2) at each hit, whatever axis the line had. This is the balance heuristic: the axis-`a`
//! estimate `f / (c_a p_a)` times the weight `c_a p_a / Σ_b c_b p_b`. It is unbiased by (1):
//! `E⟨I⟩ = Σ_a c_a ∫_{F_a} (1/A_a) Σ_{x ∈ ℓ_q} f/p dq = ∫_S f Σ_a c_a p_a / p dA = ∫_S f dA`.
//! The expected number of hits per line is `∫_S |n|₁ dA / ΣA` (not 1: `π/2` for a sphere); `p` is a
//! density of hits, not a probability density of "the" sample. Average (3) over lines, not over hits.
//!
//! # Exactness and tolerances
//!
//! `p` is exact given the normal `n(x)` at the hit; the only approximations are the tracer's (the hit
//! satisfies `|φ| ≤ eps/100`, [`crate::trace`]) and its skipping of tangent grazes and of crossings
//! shorter than its creep step (measure-zero sets of lines as `eps → 0`). A line whose tracing runs out
//! of steps is reported ([`LineSample::exhausted`]); its hits up to that point are kept, the rest are
//! missing (a bias the caller should count). The budget per crossing is raised to `2 · length / eps`
//! (see `line_settings` in the source) so that, in practice, no line runs out: lines parallel to
//! flat faces need up to `length / eps` steps.
//!
//! Unbounded shapes (planes, or anything whose [`Shape::bounds`] is infinite) cannot be sampled this way
//! (no finite face to draw `q` on): [`sample_surface`] returns [`Error::Unsupported`] and
//! [`surface_pdf`] returns 0. So does a box with no face of positive area (bounds collapsed to a segment
//! or a point, or empty).

use crate::error::{Error, Result};
use crate::math::{Aabb, Ray};
use crate::scene::Shape;
use crate::trace::{TraceSettings, all_crossings_skipping};
use glam::{Vec2, Vec3};

/// A point drawn on a surface by [`sample_surface`].
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct SurfaceSample {
    /// The point, in world coordinates.
    pub p: Vec3,
    /// Outward unit normal there ([`Shape::normal`]).
    pub n: Vec3,
    /// Combined area density of the point, eq. (2) of the [module docs](self), per unit area (always > 0).
    pub pdf: f32,
}

/// What happened on one line of [`sample_surface`].
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct LineSample {
    /// The axis the line ran along (0, 1, 2 for x, y, z).
    pub axis: usize,
    /// The line, in world coordinates: `o` on the padded box face, `d = e_axis`.
    pub ray: Ray,
    /// `Some(t)` if tracing ran out of steps at `ray.at(t)`: hits beyond `t` are missing.
    pub exhausted: Option<f32>,
}

/// The faces of a shape's bounding box and the axis probabilities.
#[derive(Copy, Clone, Debug)]
struct Faces {
    bounds: Aabb,
    /// Face areas `A_a` (0 for a degenerate face).
    area: [f32; 3],
    /// `Σ A_a > 0`.
    total: f32,
}

impl Faces {
    /// `None` for infinite, empty or collapsed boxes (no face of positive, finite area).
    fn of(bounds: Aabb) -> Option<Self> {
        if !bounds.is_finite() || bounds.is_empty() {
            return None;
        }
        let e = bounds.extent();
        let area = [e.y * e.z, e.z * e.x, e.x * e.y];
        let total: f32 = area.iter().sum();
        (total > 0.0 && total.is_finite()).then_some(Self {
            bounds,
            area,
            total,
        })
    }

    /// The axis `a` with probability `A_a / ΣA` (inverse CDF; never an axis of zero area).
    fn pick(&self, u: f32) -> usize {
        let target = u * self.total;
        let mut acc = 0.0;
        let mut last = 0;
        for (a, &area) in self.area.iter().enumerate() {
            if area > 0.0 {
                acc += area;
                last = a;
                if target < acc {
                    return a;
                }
            }
        }
        // Only reached through rounding of the sum with `u` close to 1.
        last
    }

    /// Eq. (2): `Σ_{a : A_a > 0} |n_a| / ΣA` for a unit normal `n`.
    fn pdf(&self, n: Vec3) -> f32 {
        let a = n.abs();
        let sum: f32 = (0..3).filter(|&i| self.area[i] > 0.0).map(|i| a[i]).sum();
        sum / self.total
    }

    /// Distance the line starts before (and ends after) the box, so that it starts strictly outside the
    /// surface even when the surface touches the box (a sharp box): a few tracer tolerances, and enough
    /// ulps of the coordinates to move the start at all.
    fn pad(&self, eps: f32) -> f32 {
        4.0 * eps.max(0.0) + 1e-5 * (self.bounds.magnitude() + self.bounds.extent().max_element())
    }
}

/// `settings` with a step budget that lets a line always reach its end.
///
/// Axis-aligned lines run parallel to flat faces (boxes, cylinder caps, planes inside CSG) at every
/// depth `δ`, and sphere tracing along such a line takes `length/δ` steps: with the renderer's budget
/// (512) about 0.5% of the lines through a box ran out of steps and lost their later hits, a 0.3% bias
/// of the area. Every marching step advances at least `eps` (steps below `eps` are rounded up to the
/// creep step), so `length/eps` steps cross the whole line; the budget doubles that for the probes after
/// crossings and grazes (up to 7 each). Only a line lying in the surface to within float noise over a
/// long stretch (a measure-zero set) can still run out, and is reported. The average cost stays small:
/// only lines hugging a face need many steps (`length/δ` at depth `δ`, `ln(extent/eps)` on average).
fn line_settings(settings: &TraceSettings, length: f32) -> TraceSettings {
    let eps = settings.eps.max(f32::MIN_POSITIVE);
    // `as u32` saturates (an absurdly small `eps` gives `u32::MAX`, which still terminates).
    let needed = (2.0 * length / eps).ceil() as u32;
    TraceSettings {
        max_steps: settings.max_steps.max(needed.saturating_add(64)),
        ..*settings
    }
}

fn unsupported(shape: &Shape) -> Error {
    Error::Unsupported(format!(
        "shape '{}': area sampling needs finite bounds with a face of positive area, got {:?} .. {:?}",
        shape.name, shape.bounds.min, shape.bounds.max
    ))
}

/// Draws one line through `shape`'s bounding box (axis from `u_axis`, point on the face from `u_face`,
/// both uniform in `[0, 1)`) and writes **every** surface point it crosses into `out` (cleared first), in
/// order along the line, with its combined density. See the [module docs](self) for the density and for
/// the estimator `Σ_{hits} f(x)/pdf` that these samples serve.
///
/// Hits where the normal is not finite are dropped (a zero gradient: a measure-zero set). Errors with
/// [`Error::Unsupported`] if the shape's bounds are infinite (planes) or have no face of positive area.
pub fn sample_surface(
    shape: &Shape,
    settings: &TraceSettings,
    u_axis: f32,
    u_face: Vec2,
    out: &mut Vec<SurfaceSample>,
) -> Result<LineSample> {
    out.clear();
    let faces = Faces::of(shape.bounds).ok_or_else(|| unsupported(shape))?;
    let a = faces.pick(u_axis);
    let (b, c) = ((a + 1) % 3, (a + 2) % 3);
    let (min, ext) = (faces.bounds.min, faces.bounds.extent());
    let pad = faces.pad(settings.eps_at(faces.bounds.magnitude()));
    let mut o = min;
    o[a] -= pad;
    // `u < 1` keeps `q` on the half-open face; clamping guards rounding at the upper edge.
    o[b] = (min[b] + u_face.x * ext[b]).min(faces.bounds.max[b]);
    o[c] = (min[c] + u_face.y * ext[c]).min(faces.bounds.max[c]);
    let ray = Ray::new(o, Vec3::AXES[a]);
    let length = ext[a] + 2.0 * pad;
    let (ts, exhausted) = all_crossings_skipping(
        &shape.sdf,
        shape.lipschitz,
        shape.empty_space.as_deref(),
        &shape.local_ray(&ray),
        0.0,
        length,
        &line_settings(settings, length),
    );
    out.extend(ts.into_iter().filter_map(|t| {
        let p = ray.at(t);
        let n = shape.normal(p);
        let pdf = faces.pdf(n);
        (n.is_finite() && pdf > 0.0 && pdf.is_finite()).then_some(SurfaceSample { p, n, pdf })
    }));
    Ok(LineSample {
        axis: a,
        ray,
        exhausted,
    })
}

/// The combined area density (eq. (2) of the [module docs](self)) with which [`sample_surface`] produces
/// the surface point `p` of `shape` with unit normal `n`.
///
/// It depends on `p` only through the box: 0 for points outside the bounds grown by 0.1% of their
/// largest edge (the sampler cannot produce them; the slack covers the tracer's tolerance at surfaces
/// touching the box), and 0 for shapes [`sample_surface`] refuses. `n` must be a unit vector (as
/// [`Shape::normal`] returns; it is not renormalised, so that the value reproduces a sample's `pdf`
/// exactly); a non-finite `n` gives 0.
pub fn surface_pdf(shape: &Shape, p: Vec3, n: Vec3) -> f32 {
    let Some(faces) = Faces::of(shape.bounds) else {
        return 0.0;
    };
    let slack = 1e-3 * faces.bounds.extent().max_element();
    if !faces.bounds.expanded(slack).contains(p) || !n.is_finite() {
        return 0.0;
    }
    faces.pdf(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn faces(e: Vec3) -> Faces {
        Faces::of(Aabb::new(Vec3::ZERO, e)).unwrap()
    }

    #[test]
    fn axis_choice_follows_face_areas() {
        // Areas 6, 3, 2 of total 11.
        let f = faces(Vec3::new(1.0, 2.0, 3.0));
        let n = 11_000;
        let mut count = [0usize; 3];
        for i in 0..n {
            count[f.pick((i as f32 + 0.5) / n as f32)] += 1;
        }
        assert_eq!(count, [6000, 3000, 2000]);
        assert_eq!(f.pick(0.0), 0);
        assert_eq!(f.pick(0.999_999_94), 2);
    }

    #[test]
    fn flat_box_uses_its_only_face() {
        let f = faces(Vec3::new(2.0, 3.0, 0.0));
        assert_eq!(f.area, [0.0, 0.0, 6.0]);
        for u in [0.0, 0.3, 0.999_999_94] {
            assert_eq!(f.pick(u), 2);
        }
        assert_eq!(f.pdf(Vec3::Z), 1.0 / 6.0);
        assert_eq!(f.pdf(Vec3::X), 0.0);
        assert!(Faces::of(Aabb::new(Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0))).is_none());
        assert!(Faces::of(Aabb::INFINITE).is_none());
        assert!(Faces::of(Aabb::EMPTY).is_none());
    }

    #[test]
    fn density_is_bounded_below() {
        let f = faces(Vec3::new(1.0, 2.0, 3.0));
        for n in [Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE.normalize()] {
            let p = f.pdf(n);
            assert!(
                p >= 1.0 / 11.0 - 1e-7 && p <= 3f32.sqrt() / 11.0 + 1e-7,
                "{p}"
            );
        }
    }
}
