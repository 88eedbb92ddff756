//! The primary boundary term along the edges of finite emitters seen directly (the rest of the primary
//! term, silhouettes of shapes, is [`super::primary`]; read its module docs first).
//!
//! # The jump
//!
//! A finite emitter seen by the camera is an occluder like any shape: across the image of its outline
//! the radiance jumps from the emitter's own side (its radiance, or 0 for a one-sided rectangle seen from
//! behind: [`crate::emitter::Emitter::intersect`] blocks rays on both sides,
//! [`crate::emitter::Emitter::emitted`] is 0 on the back) to the background. The outline is
//! - a **rectangle**'s four edges (the image of a planar convex polygon is the convex polygon of the
//!   images of its corners, so every edge is on the boundary unless the rectangle is seen edge-on);
//! - a **sphere**'s silhouette circle from the eye `c`: centre `o − (r²/d) ŵ`, radius `r √(1 − r²/d²)`
//!   (`o` the sphere's centre, `d = |o − c|`, `ŵ = (o − c)/d`).
//!
//! The emitter's own side is the interior term's, as for a shape silhouette: the interior attaches the
//! first vertex on the emitter rigidly ([`crate::integrator::attach`]: a rectangle point keeps its
//! relative coordinates, a sphere point its direction from the centre), so the emitter's region of the
//! film moves with its attached points through the moving pixel filter. On the sphere the visible cap's
//! sliding over the surface costs nothing (its edge has `J_film ∝ |n·q| = 0`). What is left is the
//! background's side, in the background's own parametrisation: eq. (1) of [`super::primary`] with
//!
//! ```text
//!   Δ = 0 − L_bg(x_D)   (radiance),      Δ = −1   (W, the coverage part, eq. (3) there).
//! ```
//!
//! # The velocity, by AD
//!
//! Let `x(π)` be the attached outline point (a rectangle edge point stays on its edge; a sphere point
//! at the silhouette moves to a point of the moved sphere within `O(π²)` of the moved silhouette, and
//! the projection folds there, so its image is within `O(π²)` of the moved outline's image). The normal
//! velocity of the outline's image relative to the background is
//!
//! ```text
//!   v = (∂π P_π(x(π)) − ∂π u_D(π)) · n_img                                                          (1)
//! ```
//!
//! `P_π` the projection with the lifted camera frame, `n_img` the image normal oriented towards the
//! background, `u_D` the background's film point as the interior moves it: the projection of the
//! attached `x_D` for a finite background, the projection of the fixed direction of the ray for a
//! background at infinity (the interior projects an escaping camera ray's direction with the lifted
//! frame, [`crate::integrator::diff`]). `v > 0` grows the emitter's side, the convention of
//! [`super::boundary_velocity`].
//!
//! `n_img`: with `T` the unit tangent of the outline and `m` its outward direction (in the rectangle's
//! plane, perpendicular to the edge; the sphere's normal at the silhouette point), the image tangent is
//! `P'T` and `n_img ⊥ P'T` points to the side of `P'm`, the image of a step off the emitter. Edge-on
//! edges (`P'm·n_img ≈ 0`) have an image of zero area on one side and are skipped.
//!
//! # Sampling
//!
//! Outline points are uniform on the total length `Λ` of the outlines in view (density `1/Λ` per unit
//! length): rectangle edges clipped to the view frustum grown by the filter radius (one pixel more), and
//! sphere circles whole unless the sphere is outside the frustum. A sample at `x_B` contributes to every
//! pixel whose filter covers `u_B = P(x_B)`
//!
//! ```text
//!   w_j(u_B) · Δ · v · |P'T| · Λ                                                                     (2)
//! ```
//!
//! averaged over the `N` samples of its own random stream ([`EDGE_STREAM`]). `x_B` must be visible
//! from the eye and the background is found as for silhouettes: one camera path (the `direct`
//! estimator, [`trace_path`](crate::integrator::path::trace_path)) through the film point `u_B + ε n_img`, `ε` = 1/50 pixel, must not hit
//! anything before `x_B`'s depth (less a margin); its first vertex is `x_D`, its detached contribution
//! `L_bg`.
//!
//! [`super::primary::render_primary_terms`] shares the primary term's samples equally between the kinds
//! of curves in view ([`super::primary::PrimarySources`]).

use super::frustum::Frustum;
use super::source::{BoundarySource, Pass, Scratch};
use super::{
    BACKGROUND_OFFSET_PIXELS, attached_first_vertex, background_offset, background_radiance,
    film_velocity, finite_splat, on_film, projection_jacobian, splat_on_film,
};
use crate::emitter::Outline;
use crate::film::SampleSink;
use crate::integrator::path::{PathRecord, TraceCounters, VertexKind};
use crate::math::Vec3;
use crate::sampler::Sampler;
use crate::scalar::Directions;
use crate::scene::Scene;

/// The random stream of emitter-outline samples (distinct from the silhouettes' and the camera's).
pub const EDGE_STREAM: u64 = 0xED6E_0F11;

/// One piece of an emitter's outline seen from the eye.
#[derive(Copy, Clone, Debug, PartialEq)]
enum Piece {
    /// A straight part of a rectangle's edge from `a` to `b`, `outward` (unit) pointing off the emitter
    /// in its plane, `normal` the rectangle's.
    Segment {
        emitter: usize,
        a: glam::Vec3,
        b: glam::Vec3,
        outward: glam::Vec3,
        normal: glam::Vec3,
    },
    /// A sphere's silhouette circle: `centre + radius (cos θ e1 + sin θ e2)`.
    Circle {
        emitter: usize,
        centre: glam::Vec3,
        radius: f32,
        e1: glam::Vec3,
        e2: glam::Vec3,
        sphere_centre: glam::Vec3,
    },
}

impl Piece {
    fn length(&self) -> f32 {
        match self {
            Piece::Segment { a, b, .. } => (*b - *a).length(),
            Piece::Circle { radius, .. } => std::f32::consts::TAU * radius,
        }
    }
}

/// A point of an outline: position, unit tangent, unit outward direction, emitter index.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct OutlinePoint {
    /// The point.
    pub x: glam::Vec3,
    /// Unit tangent of the outline.
    pub tangent: glam::Vec3,
    /// Unit direction off the emitter (in a rectangle's plane; a sphere's normal).
    pub outward: glam::Vec3,
    /// Unit normal of the emitter at the point (a rectangle's normal; a sphere's, as `outward`).
    pub normal: glam::Vec3,
    /// Index of the emitter in [`Scene::emitters`].
    pub emitter: usize,
}

/// The outlines of the finite emitters in view from the camera centre, for uniform sampling by length.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EmitterOutlines {
    pieces: Vec<Piece>,
    /// Cumulative lengths (`cumulative[i]` = total length of pieces `0..=i`).
    cumulative: Vec<f32>,
}

impl EmitterOutlines {
    /// The outlines of `scene`'s finite emitters seen from its camera centre (see the
    /// [module docs](self)); empty when no finite emitter is in view.
    pub fn seen_from(scene: &Scene) -> Self {
        let frustum = Frustum::of(scene);
        let eye: glam::Vec3 = scene.camera.frame::<f32>().origin.into();
        let mut pieces = Vec::new();
        for &e in &scene.finite_emitters {
            match scene.emitters[e].emitter.outline(eye) {
                Some(Outline::Edges { normal, edges }) => {
                    for (a, b, outward) in edges {
                        if let Some((a, b)) = frustum.clip(a, b)
                            && (b - a).length() > 0.0
                        {
                            pieces.push(Piece::Segment {
                                emitter: e,
                                a,
                                b,
                                outward,
                                normal,
                            });
                        }
                    }
                }
                Some(Outline::Circle {
                    centre,
                    radius,
                    e1,
                    e2,
                    sphere_centre,
                    sphere_radius,
                }) if !frustum.misses_ball(sphere_centre, sphere_radius) => {
                    pieces.push(Piece::Circle {
                        emitter: e,
                        centre,
                        radius,
                        e1,
                        e2,
                        sphere_centre,
                    });
                }
                Some(Outline::Circle { .. }) | None => {}
            }
        }
        pieces.retain(|p| p.length() > 0.0 && p.length().is_finite());
        let mut total = 0.0;
        let cumulative = pieces
            .iter()
            .map(|p| {
                total += p.length();
                total
            })
            .collect();
        Self { pieces, cumulative }
    }

    /// True when no outline is in view.
    pub fn is_empty(&self) -> bool {
        self.pieces.is_empty()
    }

    /// Total length `Λ` of the outlines (scene units); the sampling density is `1/Λ` per unit length.
    pub fn total_length(&self) -> f32 {
        self.cumulative.last().copied().unwrap_or(0.0)
    }

    /// A point uniform on the total length from two uniform numbers in `[0, 1)`; `None` when empty.
    pub fn sample(&self, u: [f32; 2]) -> Option<OutlinePoint> {
        // Pieces have finite positive lengths, so a non-empty total is positive.
        if self.pieces.is_empty() {
            return None;
        }
        let total = self.total_length();
        let target = u[0] * total;
        let i = self
            .cumulative
            .partition_point(|&c| c <= target)
            .min(self.pieces.len() - 1);
        Some(match self.pieces[i] {
            Piece::Segment {
                emitter,
                a,
                b,
                outward,
                normal,
            } => {
                let ab = b - a;
                OutlinePoint {
                    x: a + ab * u[1],
                    tangent: ab.normalize(),
                    outward,
                    normal,
                    emitter,
                }
            }
            Piece::Circle {
                emitter,
                centre,
                radius,
                e1,
                e2,
                sphere_centre,
            } => {
                let (s, c) = (std::f32::consts::TAU * u[1]).sin_cos();
                let x = centre + (e1 * c + e2 * s) * radius;
                let outward = (x - sphere_centre).normalize_or_zero();
                OutlinePoint {
                    x,
                    tangent: e2 * c - e1 * s,
                    outward,
                    normal: outward,
                    emitter,
                }
            }
        })
    }
}

impl<S: Directions> BoundarySource<S> for EmitterOutlines {
    fn stage(&self) -> &'static str {
        "primary (emitter outlines)"
    }

    fn stream(&self) -> u64 {
        EDGE_STREAM
    }

    fn takes_share(&self) -> bool {
        !self.is_empty()
    }

    fn sample(
        &self,
        pass: &Pass,
        sampler: &mut Sampler,
        scratch: &mut Scratch,
        counters: &mut TraceCounters,
        sink: &mut dyn SampleSink<S>,
    ) {
        sample(pass, self, sampler, &mut scratch.record, sink, counters);
    }
}

/// One sample of eq. (2): pushes `(pixel, radiance, coverage)` splats (not yet divided by `N`).
fn sample<S: Directions>(
    pass: &Pass,
    outlines: &EmitterOutlines,
    sampler: &mut Sampler,
    record: &mut PathRecord,
    splats: &mut dyn SampleSink<S>,
    counters: &mut TraceCounters,
) {
    let (scene, attach) = (pass.scene, &pass.attach);
    let (u0, u1) = (sampler.next_1d(), sampler.next_1d());
    let Some(pt) = outlines.sample([u0, u1]) else {
        return;
    };
    let frame = scene.camera.frame::<f32>();
    let eye: glam::Vec3 = frame.origin.into();
    let x_b = pt.x;
    let q = x_b - eye;
    let dist = q.length();
    if !(dist > 0.0 && dist.is_finite()) {
        return;
    }
    let Some((px, py)) = frame.project(Vec3::constant(x_b)) else {
        return;
    };
    if !on_film(scene, px, py) {
        return;
    }
    // P' (2×3) at x_B, the image tangent P'T (its length is dℓ_img/dℓ) and the image of a step off
    // the emitter P'm, which orients n_img.
    let Some((du, dv)) = projection_jacobian(&frame, q) else {
        return;
    };
    let image = |a: glam::Vec3| glam::Vec2::new(du.dot(a), dv.dot(a));
    let t_img = image(pt.tangent);
    let len_img = t_img.length();
    if !(len_img > 0.0 && len_img.is_finite()) {
        return;
    }
    let mut n_img = glam::Vec2::new(-t_img.y, t_img.x) / len_img;
    let off = image(pt.outward).dot(n_img);
    // Edge-on: the outward step hardly moves the image (relative to the tangent's scale).
    if off.is_nan() || off.abs() <= 1e-4 * len_img {
        return;
    }
    if off < 0.0 {
        n_img = -n_img;
    }
    // The background side: the camera ray through u_B + ε n_img, visible up to x_B's depth.
    let off = BACKGROUND_OFFSET_PIXELS;
    let ray = frame.generate_ray(glam::Vec2::new(px + off * n_img.x, py + off * n_img.y));
    let delta = background_offset(scene, dist, frame.focal);
    let Some(l_bg) =
        background_radiance(scene, &frame, ray, dist, delta, sampler, record, counters)
    else {
        return;
    };
    // The ray must have passed the emitter (it starts ε pixels off its outline).
    if let Some(first) = record.vertices.first()
        && first.kind == VertexKind::Emitter(pt.emitter)
    {
        return;
    }
    // Eq. (1): the outline point's film velocity relative to the background's.
    let fs = scene.camera.frame::<S>();
    let Some((ex, ey)) = film_velocity(
        &fs,
        attach.emitter_vertex::<S>(pt.emitter, x_b, pt.normal).x,
    ) else {
        return;
    };
    // At infinity (or nothing): the fixed direction projected with the lifted frame.
    let x_d = attached_first_vertex::<S>(attach, record)
        .unwrap_or_else(|| fs.origin + Vec3::constant(ray.d));
    let background = film_velocity(&fs, x_d);
    let Some((bx, by)) = background else {
        return;
    };
    let v = (ex - bx) * n_img.x + (ey - by) * n_img.y;
    let measure = len_img * outlines.total_length();
    let scale = -l_bg * measure;
    if !(scale.is_finite() && measure.is_finite()) {
        return;
    }
    let value = Vec3::<S>::constant(scale) * v;
    let cover = v * S::constant(-measure);
    if finite_splat(&value, cover) {
        splat_on_film(scene, (px, py), value, cover, splats);
    }
}
