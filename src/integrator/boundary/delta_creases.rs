//! The hard shadow edges that the crease edges of sharp occluders (boxes, cylinders' rims, hard CSG)
//! cast from delta lights (a point light, the sun): the crease counterpart of
//! [`super::delta_shadows`] (read its module docs first), with the edge geometry of
//! [`super::crease_segment`] and the edges of [`super::crease_edges`].
//!
//! # The integral
//!
//! Eq. (3) of [`super::delta_shadows`], `∂I_j ⊃ ∫_Γ Δ v dℓ_ω` with `Δ = −W f I`, over the directions `Γ`
//! leaving the light (the plane across the beam for the sun) through the crease edges that the light's
//! rays pass with the edge's two faces on opposite sides ([`super::crease_segment`], "When the segment
//! is a boundary": `(∇F_a·ω)(∇F_b·ω) < 0`, never on a concave edge). These are the curves the camera's
//! crease term ([`super::crease_edges`]) samples, seen from the light: perspective from a point
//! light's position, orthographic along the sun's direction.
//!
//! # Sampling
//!
//! A sample chooses one of the `K` delta lights uniformly and a point `x_B` uniformly on the total
//! length `Λ` of the scene's crease edges, whole ([`CreaseEdges::all`], the list the area lights'
//! crease shadows use, [`super::crease_shadows`]; its [`EdgePoint::weight`] is `1/p`), and contributes
//! eq. (4) of [`super::delta_shadows`]'s `−W f I · v · (dℓ_ω/dℓ) · K / p` through the same estimator
//! ([`super::delta_shadows::shadow_edge`]). Edge points that are not on the shape's surface (inside
//! another CSG child, or cut away) or where the ray is not a boundary contribute 0.
//!
//! # The velocity by AD
//!
//! The clearing vector `c = ∇F_a/|∇F_a·ω| + ∇F_b/|∇F_b·ω|` of the line through `x_B` (eq. (B1) of
//! [`super::crease_segment`]) is orthogonal to `ω` and to the edge, so it is the normal of `Γ` (the image
//! of the edge from the light) at `ω`, pointing to the clear side, and the residual
//! `h(π) = F_a(p)/|∇F_a·ω| + F_b(p)/|∇F_b·ω|` at the point `p(π)` of the ray from the attached light
//! towards the attached receiver at `x_B`'s depth (shape parameters lifted) is, to first order, `c`
//! applied to the offset of that ray from the moved edge. Turning the ray by an angle `ε` towards `c`
//! moves `p` by `|y x_B| ε ĉ` (point light) and `h` by `|y x_B| |c| ε`: `v = −∂πh / (|y x_B| |c|)`, and
//! for the sun `v = −∂πh / |c|` — eq. (5) of [`super::delta_shadows`] with `|c|` for `|∇φ|` and `ĉ` for
//! `n_B` (the ray is traced through `x_B + δ ĉ`, which clears the wedge of solid at the edge).

use super::crease_edges::{CreaseEdges, EdgePoint, face_gradient};
use super::crease_segment::{clearing, clearing_residual};
use super::delta_shadows::{ShadowEdgePoint, shadow_edge};
use super::source::{BoundarySource, Pass, Scratch};
use crate::film::SampleSink;
use crate::integrator::path::TraceCounters;
use crate::sampler::Sampler;
use crate::scalar::Directions;
use crate::scene::Scene;

/// The random stream of the delta lights' crease shadow samples.
pub const DELTA_CREASE_STREAM: u64 = 0xDE17_C2EA;

/// The delta lights and the crease edges whose shadows they cast, prepared once per render.
#[derive(Clone, Debug, Default)]
pub struct DeltaCreases {
    /// Indices of the delta lights among the scene's emitters, chosen uniformly.
    lights: Vec<usize>,
    /// Every crease edge of the scene, whole (none without delta lights).
    edges: CreaseEdges,
}

impl DeltaCreases {
    /// The delta lights of `scene` and its crease edges `edges` ([`CreaseEdges::all`]; kept only when
    /// the scene has a delta light).
    pub fn of(scene: &Scene, edges: &CreaseEdges) -> Self {
        let lights: Vec<usize> = (scene.emitters.iter().enumerate())
            .filter(|(_, e)| e.emitter.is_delta())
            .map(|(i, _)| i)
            .collect();
        let edges = if lights.is_empty() {
            CreaseEdges::default()
        } else {
            edges.clone()
        };
        Self { lights, edges }
    }

    /// Whether the scene has no delta light or no crease edge.
    pub fn is_empty(&self) -> bool {
        self.lights.is_empty() || self.edges.is_empty()
    }
}

impl<S: Directions> BoundarySource<S> for DeltaCreases {
    fn stage(&self) -> &'static str {
        "secondary (delta light crease edges)"
    }

    fn stream(&self) -> u64 {
        DELTA_CREASE_STREAM
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
        let scene = pass.scene;
        let k = self.lights.len();
        let pick = ((sampler.next_1d() * k as f32) as usize).min(k - 1);
        let light = self.lights[pick];
        let Some((pt, m, edge)) = self.edges.sample_on_surface(scene, sampler) else {
            return;
        };
        // A concave edge blocks every line through it on both sides.
        if edge.inverted {
            return;
        }
        let EdgePoint {
            x: x_b,
            tangent,
            weight,
            ..
        } = pt;
        let shape = &scene.shapes[m];
        let Some(omega) = scene.emitters[light].emitter.delta_travel(x_b) else {
            return;
        };
        let grads = [0, 1].map(|f| face_gradient(shape, edge, f, x_b));
        let side = grads[0].dot(omega) * grads[1].dot(omega);
        // The faces must lie on opposite sides of the light's ray (NaN: no).
        if side.is_nan() || side >= 0.0 {
            return;
        }
        let c = clearing(grads, omega);
        let steepness = c.length();
        if !(steepness > 0.0 && steepness.is_finite() && weight.is_finite()) {
            return;
        }
        let point = ShadowEdgePoint {
            light,
            x_b,
            clear: c / steepness,
            steepness,
            omega,
            tangent,
            choices: k as f32,
            pdf: 1.0 / weight,
        };
        let residual = |p| clearing_residual(shape, edge, grads, omega, p);
        shadow_edge(pass, &point, residual, scratch, counters, sink);
    }
}
