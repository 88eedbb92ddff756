//! The hard shadow edges of delta lights (a point light, the sun; [`crate::emitter::delta`]): their
//! part of the secondary boundary term (docs/theory.md §5.7).
//!
//! # The integral, in the light's directions
//!
//! With the `direct` integrator a point light at `y` with intensity `I` adds to pixel `j`
//!
//! ```text
//!   I_j = ∫ dA(x) W(x) f(x; ω_y, x₀) I |n·ω_y| / |y − x|² V(x, y)                                    (1)
//! ```
//!
//! `W(x) = w_j(proj x) J_film(x) V(x₀, x)` the camera factor of the first vertex (by area, as the
//! interior term takes it), `ω_y` the unit direction towards the light. Unlike an area light there is
//! no integral over the light: the visibility `V(x, y)` jumps across a curve on the receivers, the
//! shadow of the occluders' silhouettes seen from `y`. Change variables to the directions `ω` leaving
//! the light, `dω = |n·ω| dA / |y − x|²`, with `x = x(ω)` the first surface along `ω`:
//!
//! ```text
//!   I_j = ∫_{S²} dω W(x(ω)) f(x(ω); ω_y, x₀) I V(ω)                                                  (2)
//! ```
//!
//! The receiver's cosine and distance cancel. This is the primary term's form (docs/theory.md §4, the
//! film replaced by the sphere of directions at `y`): `V` jumps across the set `Γ` of directions through
//! the silhouettes `{φ = 0, ψ = 0}`, `ψ(x) = ∇φ(x)·(y − x)`, of the occluders seen from `y`
//! ([`crate::integrator::silhouette_curve`]), and the interior estimator keeps `V` at its sampled value
//! in the receiver's own parametrisation (attached `x`). The missing term (supplemental §1 eqs. 4–6)
//! is, with [`super::boundary_velocity`]'s convention (`v > 0` grows the blocked side, `Δ` = blocked
//! minus clear),
//!
//! ```text
//!   ∂I_j ⊃ ∫_Γ Δ v dℓ_ω,   Δ = 0 − W f I                                                             (3)
//! ```
//!
//! `v` the angular normal velocity of `Γ` relative to the direction of the attached receiver point
//! `x_D(π)` seen from the attached light `y(π)`. In the receiver's own terms this is the secondary
//! term's `Δf V_∂ dℓ(x_D)`: `Δf = −W f I |n_D·ω| / |y x_D|²` and `V_∂ dℓ(x_D) = v dℓ_ω |y x_D|² / |n_D·ω|`
//! (the area swept on the receiver), whose product is (3): the perspective change of measure from the
//! occluder's curve to the receiver's (docs/theory.md eq. 4.7, supplemental eq. 15 corrected) and the
//! receiver's cosine and distance cancel.
//!
//! **The sun.** Light travelling along the unit `ω` with irradiance `E` (on a surface facing it):
//! `I_j = ∫ dA(x) W f E |n·ω| V`, and with `dA⊥ = |n·ω| dA` the area across the beam,
//! `I_j = ∫ dA⊥ W f E V`: (3) holds with `E` for `I`, `Γ` the silhouettes seen along `ω`
//! (`ψ = ∇φ·(−ω)`, [`crate::integrator::silhouette_curve::View::Along`]) in the plane across the beam,
//! and `v` a linear velocity in that plane.
//!
//! # Sampling
//!
//! A boundary sample chooses one of the `K` pairs (delta light, curved shape with a non-empty
//! silhouette seen from the light) uniformly and a point `x_B` on that silhouette with density `p` per
//! unit length ([`SilhouetteCurve::sample`]), unit tangent `T`. The ray from the light through `x_B`
//! travels along `ω` (`(x_B − y)/|x_B − y|`, or the sun's direction). A displacement `dℓ T` of `x_B`
//! turns that ray by its part across `ω`:
//!
//! ```text
//!   dℓ_ω = |T − ω(ω·T)| dℓ / |y x_B|   (point),      dℓ⊥ = |T − ω(ω·T)| dℓ   (sun)                   (4)
//! ```
//!
//! so one sample contributes `−W f I · v · (dℓ_ω/dℓ) · K / p` (eqs. (3), (4)) to every pixel whose
//! filter covers the receiver's projection, averaged over the term's samples.
//!
//! # The velocity by AD
//!
//! The tangency residual on the ray from the attached light towards the attached receiver, at the
//! occluder's depth: `h(π) = φ_π(y(π) + |y x_B| (x_D(π) − y(π))/|x_D(π) − y(π)|)` for a point light,
//! `h(π) = φ_π(x_D(π) − |x_B x_D| ω(π))` for the sun ([`crate::emitter::Emitter::ray_point`]), shape
//! parameters lifted. Turning the ray by an angle `ε` towards `n_B` (the clear side) moves that point by
//! `|y x_B| ε n_B` (the ray is tangent at `x_B`: `∇φ ⊥ ω`), so `h` grows at the rate `|y x_B| |∇φ|`
//! per radian (`|∇φ|` per unit length for the sun), and
//!
//! ```text
//!   v = −∂πh / (|y x_B| |∇φ(x_B)|)   (point),        v = −∂πh / |∇φ(x_B)|   (sun)                    (5)
//! ```
//!
//! One generic evaluation serves the light's position and direction, the occluder's parameters and the
//! receiver's motion, in forward and reverse mode.
//!
//! # The sides of the edge
//!
//! Everything but `v` is a detached `f32` estimate (`Δ v` is already first order). The ray is traced
//! just outside the silhouette, through `x_B + δ n_B` with `δ` eight hit tolerances at `x_B`, so that it
//! clears the occluder near `x_B`: the light must reach that point unoccluded (else the edge casts no
//! shadow there and the sample is 0), and the first surface beyond it is the receiver `x_D`, which must
//! be a shape (emitters do not scatter; a ray that escapes or runs out of steps lights nothing). Lines
//! that are not silhouettes there (`κ_n ≤ 0` along `ω`) are rejected, as in the primary term.
//!
//! **Path integrator.** With `x_D` the `k`-th scattering vertex of a path (the light ends it, like an
//! emitter end of [`super::shadow_segment`]), `W` becomes the camera factor `W_k` of an adjoint walk
//! from `x_D` connected to the camera ([`super::subpaths`], eq. (C) there) for every `k ≤ max_depth`; it
//! includes the BSDF at `x_D` towards the light. `direct` is `k = 1`.
//!
//! **Scope.** Smooth silhouettes of curved shapes with finite bounds (the shapes the primary term
//! extracts curves for). The crease edges of sharp boxes, cylinders and hard CSG seen from a delta
//! light are [`super::delta_creases`]'s, through the same estimator ([`shadow_edge`]): a point on any
//! shadow-casting curve, the direction across the light's ray towards its clear side and the rate of
//! the occluder's residual there are all it needs.

use super::motion::Motion;
use super::segment::is_silhouette_direction;
use super::shadow_segment::subpath_sampler;
use super::source::{BoundarySource, BoundaryTerm, Pass, Scratch};
use super::subpaths::camera_side;
use super::{finite_splat, splat_on_film};
use crate::emitter::Emitter;
use crate::film::SampleSink;
use crate::integrator::path::{TraceCounters, occluded};
use crate::integrator::silhouette_curve::{
    CurveOptions, SilhouetteCurve, View, extract_silhouette_in, silhouette_functions_in,
};
use crate::math::{Ray, Vec3};
use crate::sampler::Sampler;
use crate::scalar::Directions;
use crate::scene::{Intersection, Scene, Surface};

/// The random stream of delta-light shadow-edge samples.
pub const DELTA_SHADOW_STREAM: u64 = 0xDE17_A5AD;

/// How far outside the silhouette the ray through it is traced, in hit tolerances at `x_B`.
const OFFSET_TOLERANCES: f32 = 8.0;

/// The silhouettes of the curved shapes seen from each delta light, prepared once per render: the
/// samples of eq. (3).
#[derive(Clone, Debug, Default)]
pub struct DeltaShadows {
    /// `(light, shape, silhouette seen from the light)`, non-empty curves only, chosen uniformly.
    curves: Vec<(usize, usize, SilhouetteCurve)>,
}

impl DeltaShadows {
    /// The silhouettes of `scene`'s curved shapes with finite bounds seen from its delta lights (none
    /// without delta lights), `scene` with its selection applied, for the pairs whose term can be
    /// non-zero ([`super::motion::Motion::delta_shadow_keeps`]): the others add exactly nothing, and
    /// are neither extracted nor sampled.
    pub fn of(scene: &Scene) -> Self {
        let motion = Motion::of(scene);
        Self::extract(scene, |e, m| motion.delta_shadow_keeps(scene, e, m))
    }

    /// The silhouettes seen from the delta lights of every curved shape with finite bounds, whatever
    /// the selected parameters move (what [`DeltaShadows::of`] prunes from).
    pub fn unpruned(scene: &Scene) -> Self {
        Self::extract(scene, |_, _| true)
    }

    /// The silhouettes of the pairs `(light e, shape m)` with `keep(e, m)`.
    fn extract(scene: &Scene, keep: impl Fn(usize, usize) -> bool) -> Self {
        let mut curves = Vec::new();
        for (e, light) in scene.emitters.iter().enumerate() {
            let view = match &light.emitter {
                Emitter::Point { position, .. } => View::Point(position.value()),
                sun @ Emitter::Directional { .. } => match sun.delta_travel(glam::Vec3::ZERO) {
                    Some(w) => View::Along(w),
                    None => continue,
                },
                _ => continue,
            };
            for (i, shape) in scene.shapes.iter().enumerate() {
                let b = shape.bounds;
                if !b.is_finite() || b.is_empty() || shape.sdf.is_piecewise_flat() || !keep(e, i) {
                    continue;
                }
                // Extraction fails only for unbounded shapes, excluded above.
                if let Ok(curve) = extract_silhouette_in(shape, view, &CurveOptions::default())
                    && curve.polyline_length() > 0.0
                {
                    curves.push((e, i, curve));
                }
            }
        }
        Self { curves }
    }

    /// Whether the scene has a delta light with an occluder's silhouette in its view.
    pub fn is_empty(&self) -> bool {
        self.curves.is_empty()
    }

    /// The `(light, shape)` index pairs whose silhouettes are held, in sampling order.
    pub fn pairs(&self) -> Vec<(usize, usize)> {
        self.curves.iter().map(|(e, m, _)| (*e, *m)).collect()
    }

    /// The silhouettes of the pairs `(light, shape)` with `keep(light, shape)` only.
    pub fn only(&self, keep: impl Fn(usize, usize) -> bool) -> Self {
        let curves = (self.curves.iter())
            .filter(|(e, m, _)| keep(*e, *m))
            .cloned()
            .collect();
        Self { curves }
    }
}

impl BoundaryTerm for DeltaShadows {
    fn sources<S: Directions>(&self) -> Vec<&dyn BoundarySource<S>> {
        vec![self]
    }
}

impl<S: Directions> BoundarySource<S> for DeltaShadows {
    fn stage(&self) -> &'static str {
        "secondary"
    }

    fn stream(&self) -> u64 {
        DELTA_SHADOW_STREAM
    }

    fn takes_share(&self) -> bool {
        !self.curves.is_empty()
    }

    fn sample(
        &self,
        pass: &Pass,
        sampler: &mut Sampler,
        scratch: &mut Scratch,
        counters: &mut TraceCounters,
        sink: &mut dyn SampleSink<S>,
    ) {
        self.sample_edge(pass, sampler, scratch, counters, sink);
    }
}

impl DeltaShadows {
    /// One sample of eq. (3): pushes its weighted contributions (not yet divided by the sample count).
    fn sample_edge<S: Directions>(
        &self,
        pass: &Pass,
        sampler: &mut Sampler,
        scratch: &mut Scratch,
        counters: &mut TraceCounters,
        sink: &mut dyn SampleSink<S>,
    ) {
        let scene = pass.scene;
        let k = self.curves.len();
        let pick = ((sampler.next_1d() * k as f32) as usize).min(k - 1);
        let (e, m, curve) = (
            &self.curves[pick].0,
            self.curves[pick].1,
            &self.curves[pick].2,
        );
        let emitter = &scene.emitters[*e].emitter;
        let shape = &scene.shapes[m];
        let u = sampler.next_2d();
        let Some(cs) = curve.sample(shape, [u.x, u.y]) else {
            return;
        };
        if !(cs.pdf > 0.0 && cs.pdf.is_finite()) {
            return;
        }
        let x_b = cs.x;
        let Some(omega) = emitter.delta_travel(x_b) else {
            return;
        };
        if !is_silhouette_direction(shape, x_b, omega) {
            return;
        }
        let (_, _, grad, _) = silhouette_functions_in(shape, curve.view, x_b);
        let grad_len = grad.length();
        if !(grad_len > 0.0 && grad_len.is_finite()) {
            return;
        }
        let point = ShadowEdgePoint {
            light: *e,
            x_b,
            clear: grad / grad_len,
            steepness: grad_len,
            omega,
            tangent: cs.tangent,
            choices: k as f32,
            pdf: cs.pdf as f32,
        };
        shadow_edge(
            pass,
            &point,
            |p| Some(shape.eval(p)),
            scratch,
            counters,
            sink,
        );
    }
}

/// A point `x_B` of a delta light's shadow-casting curve (a silhouette seen from the light, or a crease
/// edge passed by the light's ray, [`super::delta_creases`]) and what eqs. (3)–(5) need of it.
pub(crate) struct ShadowEdgePoint {
    /// Index of the delta light among the scene's emitters.
    pub light: usize,
    /// The point.
    pub x_b: glam::Vec3,
    /// Unit direction across the light's ray at `x_B` towards the side where the ray clears the
    /// occluder (`n_B` for a silhouette).
    pub clear: glam::Vec3,
    /// The rate of the occluder's residual `h` per unit of displacement of the ray towards `clear`
    /// (`|∇φ|` for a silhouette).
    pub steepness: f32,
    /// The light's unit travel direction at `x_B`.
    pub omega: glam::Vec3,
    /// Unit tangent of the curve at `x_B`.
    pub tangent: glam::Vec3,
    /// `K` of eq. (4)'s weight: the number of equally likely choices made before drawing `x_B`.
    pub choices: f32,
    /// `p`: the density of `x_B` per unit length of the curve.
    pub pdf: f32,
}

/// One sample of eq. (3) at `point`, the occluder's residual `residual(p)` with lifted parameters at
/// the world point `p` (module docs, "The velocity by AD": 0 on the curve at the primal, growing
/// towards the clear side at the rate [`ShadowEdgePoint::steepness`]): traces the ray past `x_B` from
/// the light to the receiver and pushes the weighted contributions (not yet divided by the sample
/// count).
pub(crate) fn shadow_edge<S: Directions>(
    pass: &Pass,
    point: &ShadowEdgePoint,
    residual: impl Fn(Vec3<S>) -> Option<S>,
    scratch: &mut Scratch,
    counters: &mut TraceCounters,
    sink: &mut dyn SampleSink<S>,
) {
    let (scene, attach) = (pass.scene, &pass.attach);
    let e = point.light;
    let emitter = &scene.emitters[e].emitter;
    let (x_b, omega) = (point.x_b, point.omega);
    // The light's position (a point light) and the distance from it to x_B, eqs. (4), (5).
    let light = match emitter {
        Emitter::Point { position, .. } => {
            let y = position.value();
            Some((y, x_b.distance(y)))
        }
        _ => None,
    };
    let magnitude = light.map_or(0.0, |(y, _)| y.abs().max_element());
    let eps = scene.trace.eps_at(x_b.abs().max_element().max(magnitude));
    let x_off = x_b + point.clear * (OFFSET_TOLERANCES * eps);
    // The light must reach x_B's clear side: the ray from the light through it, up to it.
    let (dir, lit) = match light {
        Some((y, _)) => {
            let to = x_off - y;
            let Some(d) = to.try_normalize() else {
                return;
            };
            let blocked = occluded(scene, &Ray::new(y, d), to.length(), None, None, counters);
            (d, !blocked)
        }
        None => {
            let blocked = occluded(
                scene,
                &Ray::new(x_off, -omega),
                f32::INFINITY,
                None,
                None,
                counters,
            );
            (omega, !blocked)
        }
    };
    if !lit {
        return;
    }
    // The receiver: the first surface beyond x_B.
    let (d_idx, x_d, n_d) = match scene.intersect(&Ray::new(x_off, dir), f32::INFINITY) {
        Intersection::Hit(h) => match h.surface {
            Surface::Shape(d) => (d, h.p, h.n),
            Surface::Emitter(_) => return,
        },
        Intersection::Miss => return,
        Intersection::Exhausted => {
            counters.exhausted += 1;
            return;
        }
    };
    let frame = scene.camera.frame::<f32>();
    let mut walk = subpath_sampler(x_b, x_d);
    let depth = scene.integrator.max_scatter();
    let cams = &mut scratch.cams;
    camera_side(
        scene, &frame, d_idx, x_d, n_d, -dir, depth, &mut walk, cams, counters,
    );
    if cams.is_empty() {
        return;
    }
    // Eqs. (4), (5): the measure change and the rate of h, per unit length of the curve.
    let across = (point.tangent - omega * omega.dot(point.tangent)).length();
    let (measure, rate, depth_b) = match light {
        Some((_, dist)) => (across / dist, dist * point.steepness, dist),
        None => (across, point.steepness, x_d.distance(x_off)),
    };
    let weight = measure * point.choices / point.pdf;
    if !(weight.is_finite() && rate > 0.0 && rate.is_finite()) {
        return;
    }
    let y_s = match light {
        Some((y, _)) => attach.emitter_vertex::<S>(e, y, -dir).x,
        None => Vec3::zero(),
    };
    let xd_s = attach.shape_vertex::<S>(d_idx, x_d, n_d).x;
    let Some(h) = residual(emitter.ray_point(y_s, xd_s, depth_b)) else {
        return;
    };
    let v = -(h - h.detach()) / rate;
    let power = emitter.mean_radiance();
    for cam in cams.iter() {
        // Δ = −W f I on the clear side (eq. (3)).
        let scale = -(cam.f * power) * (weight * cam.j_film);
        if scale == glam::Vec3::ZERO || !scale.is_finite() {
            continue;
        }
        let value = Vec3::<S>::constant(scale) * v;
        if finite_splat(&value, S::zero()) {
            splat_on_film(scene, (cam.film.x, cam.film.y), value, S::zero(), sink);
        }
    }
}
