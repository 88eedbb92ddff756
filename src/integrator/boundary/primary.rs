//! The primary boundary term (docs/theory.md §4; supplemental §2 with `x_S = c` the camera
//! centre): silhouettes of shapes seen from the camera, for both integrators.
//!
//! # The integral, in film space
//!
//! Pixel `j` is `I_j = ∫ d²u w_j(u) L(u)` over the film (pixels), `w_j` the pixel filter centred on the
//! pixel ("fixed" normalisation), `L(u)` the radiance seen along the camera ray through `u`. `L` jumps
//! across the image `Γ` of every silhouette curve `{φ = 0, ψ = 0}` (`ψ = ∇φ·(c − x)`) whose points are
//! visible from `c`: on one side the occluder `M` near `x_B`, on the other the background `x_D` (the
//! first hit beyond `x_B` on the continued ray, or the environment).
//!
//! **Which jump.** The interior estimator ([`crate::integrator::diff::interior`]) takes the first vertex by area
//! with attached points `x + V n` and their moving projections. On `M`'s side that already moves the
//! occluder's region of the film with the surface: at the silhouette the ray is tangent, a normal
//! displacement `V n` moves the projected contour exactly as the silhouette moves, and the sliding of the
//! contour over `M` (along the ray) has film-area weight `J_film ∝ |n·q| = 0`. So the occluder side needs
//! no boundary term (the sphere test checks this: the interior alone is `+ρL ∮ w v dℓ`). What the
//! interior misses is the background's region shrinking: in `x_D`'s own parametrisation its visibility
//! jumps from 1 to 0 across `Γ`. With the convention of [`super::boundary_velocity`] (`v > 0` grows the
//! blocked side, `Δ` = blocked minus clear, as the secondary term's `Δf = −f G L_e`):
//!
//! ```text
//!   ∂I_j ⊃ ∫_Γ w_j(u) Δ v dℓ_img,   Δ = 0 − L_background(x_D)                                   (1)
//! ```
//!
//! `v` the normal velocity (pixels per unit parameter) of `Γ` along the image normal `n_img` pointing to
//! the background side, **relative to the background's own parametrisation**: relative to the moving
//! projection of the attached `x_D` on a finite surface, relative to the moving projection of the fixed
//! direction for a background at infinity (the interior projects an escaping camera ray's direction with
//! the lifted camera frame, so a camera rotation moves the environment on the film). For the
//! sphere of radius `r` in a constant environment `L` the sum of both terms is the closed form
//! `−(1−ρ)L dR/dr ∮ w_j dℓ` (`R` the projected radius).
//!
//! # Sampling
//!
//! `x_B` is sampled on the extracted 3D silhouette curve ([`SilhouetteCurve::sample`]) with density
//! `p` per unit length `dℓ` of the true curve, after choosing one of the `K` shapes with a non-empty curve
//! uniformly. Only the shapes whose term can be non-zero are among the `K` ([`super::motion`]): with
//! the camera fixed, a fixed shape's `v` is exactly zero unless a moving shape or emitter can be seen
//! next to it. Its image is `u_B = P(x_B)` (`P` = [`crate::camera::CameraFrame::project`]); with `T` the
//! unit curve tangent and `P'` the 2×3 Jacobian of the projection,
//!
//! ```text
//!   dℓ_img = |P'(x_B) T| dℓ,   P'_u = f (r z − f̂ (q·r)) / z²,  P'_v = −f (up z − f̂ (q·up)) / z²
//! ```
//!
//! (`q = x_B − c`, `z = q·f̂`, `r`, `up`, `f̂` the camera axes, `f` the focal length in pixels). The image
//! tangent is `t = P'T`; `n_img ⊥ t`. So one sample contributes, to every pixel whose filter covers `u_B`,
//!
//! ```text
//!   w_j(u_B) · (−L_bg) · v · |P'T| · K / p                                                           (2)
//! ```
//!
//! averaged over the `N` samples of the whole image (own random stream [`PRIMARY_STREAM`]).
//!
//! # Pixel normalisation (supplemental §3; docs/theory.md §6)
//!
//! With `differentiable` normalisation pixel `j` is `F_j / W_j`, `W_j = ∫ w_j J_film J₁ dA` the filter's
//! own integral over the first vertices, `F_j`'s integrand with `L ≡ 1` (1 at the primal). Its visibility
//! jumps across the same curves `Γ` and splits the same way: the occluder's side is the interior's
//! ([`crate::integrator::diff::interior`] estimates `W` with the moving filter), the background's is
//!
//! ```text
//!   ∂W_j ⊃ ∫_Γ w_j(u) (−1) v dℓ_img                                                                  (3)
//! ```
//!
//! sampled with the same points as (2) ([`PrimaryTerm::coverage`]). The pixel's derivative
//! `∂F_j − I_j ∂W_j` turns the jump `−L_bg` into `I_j − L_bg` ([`PrimaryTerm::combine`]). Without (3)
//! the `differentiable` derivative is biased by `I_j ∮ w_j v dℓ` (the sphere test measures it).
//!
//! # The image-space velocity `v` by AD
//!
//! Let the parameters move with the background point held: the ray from the lifted eye `c(π)` is
//! `x(π) = c(π) + |c x_B| d̂(π)` at the depth of `x_B`, with `d̂` the unit direction towards the attached
//! `x_D(π)` ([`crate::integrator::attach::SceneAttach`]), or for a background at infinity the fixed direction `d̂` through the film
//! point `u`, `r (u_x − c_x) − up (u_y − c_y) + f̂ f` normalised, in the primal camera frame. The tangency
//! residual `h(π) = φ_π(x(π))` (shape parameters lifted too) is 0 at the primal. Moving `u` by `δ n_img`
//! (or the film point of `x_D` by `δ n_img`: the same change of direction) changes it by
//! `∇φ(x_B)·∂x/∂u n_img δ = |c x_B| ∇φ·(I − d̂d̂ᵀ) m / |d| δ`, `m = r n_x − up n_y`
//! (the ray is tangent at `x_B`, so to first order the minimum of `φ` along the ray stays at `x_B`'s
//! depth). Hence `v = −∂πh / rate`, `rate = |c x_B| ∇φ·(I − d̂d̂ᵀ) m / |d|`, and `n_img` is oriented so
//! that `rate > 0` (towards growing `φ`: the background side). This is [`super::boundary_velocity`]'s
//! construction with `x_S = c` moving with the camera and the far end replaced by the background point (or direction).
//!
//! # The background radiance
//!
//! A detached `f32` estimate (its derivative is second order in (1)): one camera path ([`trace_path`](crate::integrator::path::trace_path)
//! with the scene's `max_scatter`: the integrator's own estimator) along the ray from `c` towards
//! `x_B + δ n_B`, `δ` = 1/50 of a pixel at `x_B`'s distance (at least `4 eps`); its first vertex is
//! `x_D`. `x_B` must be visible: that ray must not hit anything before `x_B`'s depth (less a margin),
//! else the sample contributes 0. Points of the curve where the view ray is not a silhouette direction (`κ_n ≤ 0`:
//! the ray enters the solid on both sides) contribute 0.
//!
//! **Path integrator.** Nothing above depends on what follows `x_D`: (1) is the jump of the camera
//! segment's visibility, `L_background` is the whole radiance leaving `x_D` towards `c` with `x_D` the
//! first of at most `max_depth` scattering vertices (exactly the primal's paths with `x₁ = x_D`), and the
//! occluder side is the interior's moving filter whatever the rest of the path. Visibility jumps of the
//! later segments are the secondary term's.
//!
//! **Scope.** Both integrators; shapes with finite bounds and curved surfaces (planes and sharp boxes
//! have no smooth silhouettes), the outlines of finite emitters seen directly
//! ([`super::emitter_edges`]: rectangle edges, sphere silhouettes) and the crease edges of sharp boxes
//! and cylinders and of hard CSG ([`super::crease_edges`]); the kinds in view share the samples equally
//! ([`PrimarySources`]). Not included: the creases of hard CSG between unbounded children beyond
//! the scene's crease region (listed by [`crate::scene::Scene::unsampled_creases`]), the film edges.

use super::crease_edges::{CreaseEdges, CreasesInView};
use super::emitter_edges::EmitterOutlines;
use super::motion::Motion;
use super::segment::is_silhouette_direction;
use super::source::{BoundarySource, BoundaryTerm, Pass, Scratch, term_images};
use super::{
    attached_first_vertex, background_offset, background_radiance, finite_splat, on_film,
    projection_jacobian, splat_on_film,
};
use crate::error::Result;
use crate::film::{Image, Normalization, SampleSink};
use crate::integrator::driver::RenderStats;
use crate::integrator::options::{DiffOptions, require_continuous_filter};
use crate::integrator::path::{PathRecord, TraceCounters};
use crate::integrator::silhouette_curve::{
    CurveOptions, SilhouetteCurve, extract_silhouette, silhouette_functions,
};
use crate::math::{Ray, Vec3};
use crate::sampler::Sampler;
use crate::scalar::{Directions, dispatch_directions};
use crate::scene::{Scene, Selection};

/// The random stream of primary boundary samples (distinct from the camera's and the secondary term's).
pub const PRIMARY_STREAM: u64 = 0x9121_B0DA;

/// The primary boundary term of the derivative of `scene` with respect to the parameters of
/// `selection` for the `fixed` pixel normalisation, estimated with
/// `samples` silhouette samples for the whole image (see the [module docs](self)): the
/// [`PrimaryTerm::radiance`] part of [`render_primary_terms`]. One image per parameter, the layout of
/// [`crate::integrator::diff::DerivativeImages::interior`]; the seed is `options.render.seed`.
///
/// Errors: a selection `scene` does not have, a box pixel filter, a failed curve extraction.
pub fn render_primary(
    scene: &Scene,
    selection: &Selection,
    options: &DiffOptions,
    samples: u64,
) -> Result<Vec<Image>> {
    Ok(render_primary_terms(scene, selection, options, samples)?.radiance)
}

/// Both parts of the primary boundary term, from one set of silhouette samples: the radiance jump
/// (`Δ = −L_bg`, eq. (2)) and the jump of the pixel filter's own integral `W` (`Δ = −1`, eq. (3)).
#[derive(Clone, Debug, PartialEq)]
pub struct PrimaryTerm {
    /// `radiance[k]`: the primary term of `∂F` for slot `k` (the whole term with `fixed` normalisation).
    pub radiance: Vec<Image>,
    /// `coverage[k]`: `W`'s primary term for slot `k`, the same value in the three channels.
    pub coverage: Vec<Image>,
    /// Counts of the traced rays.
    pub stats: RenderStats,
}

impl PrimaryTerm {
    /// The primary term of each pixel's derivative under `normalization`: `radiance` (`fixed`), or
    /// `radiance − I ⊙ coverage` (`differentiable`, eq. (3)), `image` the rendered pixels `I`.
    pub fn combine(&self, image: &Image, normalization: Normalization) -> Vec<Image> {
        self.radiance
            .iter()
            .zip(&self.coverage)
            .map(|(r, c)| {
                let mut out = r.clone();
                for ((o, cv), i) in out.rgb.iter_mut().zip(&c.rgb).zip(&image.rgb) {
                    *o = normalization.derivative(*o, *cv, *i);
                }
                out
            })
            .collect()
    }
}

/// [`PrimaryTerm`] with the parameters of `selection`; `samples` boundary samples for the whole
/// image, shared by shape silhouettes, emitter outlines and crease edges ([`PrimarySources`]), in
/// passes of the widest dual number the selection needs. Errors as [`render_primary`].
pub fn render_primary_terms(
    scene: &Scene,
    selection: &Selection,
    options: &DiffOptions,
    samples: u64,
) -> Result<PrimaryTerm> {
    primary_terms(&selection.apply(scene)?, selection.len(), options, samples)
}

/// [`render_primary_terms`] of a scene with its selection applied, slots `0..count`.
pub(crate) fn primary_terms(
    scene: &Scene,
    count: usize,
    options: &DiffOptions,
    samples: u64,
) -> Result<PrimaryTerm> {
    require_continuous_filter(scene, "the primary boundary term")?;
    if count == 0 {
        return Ok(PrimaryTerm {
            radiance: Vec::new(),
            coverage: Vec::new(),
            stats: RenderStats::default(),
        });
    }
    let sources = PrimarySources::of(scene)?;
    let (radiance, coverage, stats) = dispatch_directions!(
        count,
        term_images(scene, count, options, samples, &sources, true)
    );
    Ok(PrimaryTerm {
        radiance,
        coverage,
        stats,
    })
}

/// Everything the primary term samples, found once per render: shape silhouettes, emitter outlines and
/// crease edges in view, which share its samples equally (those with nothing in view take no share).
#[derive(Clone, Debug)]
pub struct PrimarySources {
    /// The silhouette curves of shapes.
    pub silhouettes: Silhouettes,
    /// The outlines of emitters in view.
    pub outlines: EmitterOutlines,
    /// The crease edges in view.
    pub creases: CreasesInView,
}

impl PrimarySources {
    /// The curves of `scene` seen from its camera. Errors: a failed silhouette extraction.
    pub fn of(scene: &Scene) -> Result<Self> {
        Ok(Self {
            silhouettes: Silhouettes::of(scene)?,
            outlines: EmitterOutlines::seen_from(scene),
            creases: CreasesInView(CreaseEdges::seen_from(scene)),
        })
    }
}

impl BoundaryTerm for PrimarySources {
    fn sources<S: Directions>(&self) -> Vec<&dyn BoundarySource<S>> {
        vec![&self.silhouettes, &self.outlines, &self.creases]
    }
}

/// The silhouette curves seen from the camera centre of the shapes with finite bounds and curved
/// surfaces ([`crate::sdf::Sdf::is_piecewise_flat`]; non-empty curves only) whose primary term can be
/// non-zero with the selected parameters ([`super::motion`]), per shape index: eq. (2)'s samples.
#[derive(Clone, Debug, Default)]
pub struct Silhouettes(pub Vec<(usize, SilhouetteCurve)>);

impl Silhouettes {
    /// The silhouettes seen from the camera of `scene`'s shapes (its selection applied) whose term can
    /// be non-zero ([`super::motion::Motion::primary_keeps`]): the others add exactly nothing, and are
    /// neither extracted nor sampled. Errors: a failed extraction.
    pub fn of(scene: &Scene) -> Result<Self> {
        let motion = Motion::of(scene);
        Self::extract(scene, |m| motion.primary_keeps(scene, m))
    }

    /// The silhouettes seen from the camera of every shape of `scene` with finite bounds and curved
    /// surfaces, whatever the selected parameters move (what [`Silhouettes::of`] prunes from).
    pub fn unpruned(scene: &Scene) -> Result<Self> {
        Self::extract(scene, |_| true)
    }

    /// The silhouettes of the curved, bounded shapes `m` with `keep(m)`.
    fn extract(scene: &Scene, keep: impl Fn(usize) -> bool) -> Result<Self> {
        let eye: glam::Vec3 = scene.camera.frame::<f32>().origin.into();
        let mut curves = Vec::new();
        for (i, shape) in scene.shapes.iter().enumerate() {
            let b = shape.bounds;
            if !b.is_finite() || b.is_empty() || shape.sdf.is_piecewise_flat() || !keep(i) {
                continue;
            }
            let curve = extract_silhouette(shape, eye, &CurveOptions::default())?;
            if curve.polyline_length() > 0.0 {
                curves.push((i, curve));
            }
        }
        Ok(Self(curves))
    }
}

impl BoundaryTerm for Silhouettes {
    fn sources<S: Directions>(&self) -> Vec<&dyn BoundarySource<S>> {
        vec![self]
    }
}

impl<S: Directions> BoundarySource<S> for Silhouettes {
    fn stage(&self) -> &'static str {
        "primary"
    }

    fn stream(&self) -> u64 {
        PRIMARY_STREAM
    }

    fn takes_share(&self) -> bool {
        !self.0.is_empty()
    }

    fn sample(
        &self,
        pass: &Pass,
        sampler: &mut Sampler,
        scratch: &mut Scratch,
        counters: &mut TraceCounters,
        sink: &mut dyn SampleSink<S>,
    ) {
        sample(pass, &self.0, sampler, &mut scratch.record, sink, counters);
    }
}

/// One sample of eq. (2): pushes `(pixel, value)` pairs (not yet divided by the sample count).
fn sample<S: Directions>(
    pass: &Pass,
    curves: &[(usize, SilhouetteCurve)],
    sampler: &mut Sampler,
    record: &mut PathRecord,
    splats: &mut dyn SampleSink<S>,
    counters: &mut TraceCounters,
) {
    let (scene, attach) = (pass.scene, &pass.attach);
    let k = curves.len();
    let pick = ((sampler.next_1d() * k as f32) as usize).min(k - 1);
    let (m, curve) = (curves[pick].0, &curves[pick].1);
    let shape = &scene.shapes[m];
    let u = sampler.next_2d();
    let Some(cs) = curve.sample(shape, [u.x, u.y]) else {
        return;
    };
    if !(cs.pdf > 0.0 && cs.pdf.is_finite()) {
        return;
    }
    let frame = scene.camera.frame::<f32>();
    let eye: glam::Vec3 = frame.origin.into();
    let (right, up, fwd): (glam::Vec3, glam::Vec3, glam::Vec3) =
        (frame.right.into(), frame.up.into(), frame.forward.into());
    let focal = frame.focal;
    let x_b = cs.x;
    let q = x_b - eye;
    let dist = q.length();
    if !(dist > 0.0 && dist.is_finite()) {
        return;
    }
    let omega = q / dist;
    if !is_silhouette_direction(shape, x_b, omega) {
        return;
    }
    let Some((px, py)) = frame.project(Vec3::constant(x_b)) else {
        return;
    };
    if !on_film(scene, px, py) {
        return;
    }
    let (_, _, grad, _) = silhouette_functions(shape, eye, x_b);
    let Some(n_b) = grad.try_normalize() else {
        return;
    };
    // Image tangent t = P'T and its length (the measure change dℓ_img/dℓ).
    let Some((du, dv)) = projection_jacobian(&frame, q) else {
        return;
    };
    let t_img = glam::Vec2::new(du.dot(cs.tangent), dv.dot(cs.tangent));
    let len_img = t_img.length();
    if !(len_img > 0.0 && len_img.is_finite()) {
        return;
    }
    let n_img = glam::Vec2::new(-t_img.y, t_img.x) / len_img;
    // rate = ∂h/∂u along n_img (module docs).
    let (ox, oy) = (px - frame.center.0, py - frame.center.1);
    let d_raw = right * ox - up * oy + fwd * focal;
    let d_len = d_raw.length();
    let d_hat = d_raw / d_len;
    let proj = |m: glam::Vec3| m - d_hat * d_hat.dot(m);
    let mut rate = dist / d_len * grad.dot(proj(right * n_img.x - up * n_img.y));
    // Orient n_img towards growing φ (the background side): flipping it flips the rate.
    if rate < 0.0 {
        rate = -rate;
    }
    if !(rate > 0.0 && rate.is_finite()) {
        return;
    }
    // The background side: x_D and its radiance, along the ray just outside the silhouette.
    let delta = background_offset(scene, dist, focal);
    let Some(d_out) = (x_b + n_b * delta - eye).try_normalize() else {
        return;
    };
    let ray = Ray::new(eye, d_out);
    let Some(l_bg) =
        background_radiance(scene, &frame, ray, dist, delta, sampler, record, counters)
    else {
        return;
    };
    // v = −∂πh / rate, relative to the background's own parametrisation (module docs): the ray from the
    // moving eye towards the attached x_D, or along the fixed direction for a background at infinity.
    let fs = scene.camera.frame::<S>();
    let d_s = match attached_first_vertex::<S>(attach, record) {
        Some(x_d) => x_d - fs.origin,
        None => Vec3::constant(d_hat),
    }
    .normalize_or_zero();
    let h = shape.eval(fs.origin + d_s * S::constant(dist));
    let v = -(h - h.detach()) / rate;
    // Δ = blocked − clear = 0 − L_bg (module docs: the occluder's own side is the interior's), and
    // −1 for W (eq. (3)).
    let measure = len_img * k as f32 / cs.pdf as f32;
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
