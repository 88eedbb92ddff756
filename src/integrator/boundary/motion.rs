//! What moves with the selected parameters, and which silhouettes can therefore carry a non-zero
//! boundary term: the camera's (primary term) and the delta lights' (their hard shadows).
//!
//! **Primary term.** A boundary sample on the silhouette of shape `m` contributes `−L_bg v`,
//! `v = −∂πh / rate`, `h = φ_m(c + |c x_B| d̂)` with `c` the lifted eye and `d̂` the direction towards
//! the attached background point `x_D` (or the fixed direction for a background at infinity; see
//! [`super::primary`]). `∂πh` has three sources only: `φ_m`'s own parameters (the shape moves), the
//! camera's (`c`, and the frame that places a background at infinity), and the attached `x_D`, which
//! moves only on a shape or finite emitter whose geometry is selected
//! ([`crate::integrator::attach::SceneAttach`]: every other vertex is attached as a constant). When
//! none of them is selected, every dual part of `h` is exactly zero, so is `v`, and the whole
//! silhouette adds exactly nothing: its extraction and its share of the samples are saved.
//!
//! `x_D` is the first thing the camera ray through `x_B + δ n_B` meets (`δ` 1/50 of a pixel, or a few
//! hit tolerances), so its image is within a pixel of `m`'s image. [`Motion::primary_keeps`] keeps `m`
//! when the camera moves, when `m` moves, or when the image box of a moving shape's or finite
//! emitter's bounds overlaps that of `m`'s. Each world box is grown by [`WORLD_MARGIN_TOLERANCES`] hit
//! tolerances (the offset `δ`, hits reported within a tolerance of the surface), each image box by
//! [`FILM_MARGIN_PIXELS`]; a box with a corner not in front of the eye covers the whole film. Point
//! lights and the sun are never `x_D` (no ray meets them), so their motion keeps nothing here.
//!
//! **Hard shadows of delta lights** ([`super::delta_shadows`]). A sample on the silhouette of `m` seen
//! from light `y` has `h = φ_m(y + |y x_B| (x_D − y)/|x_D − y|)` (point light) or
//! `h = φ_m(x_D − |x_B x_D| ω)` (sun), `x_D` the attached receiver, the first shape along the light's
//! ray through `x_B` offset by a few hit tolerances to its clear side. Only `m`'s, the light's and the
//! receiver's parameters can move it; the camera's cannot (the camera factor is a detached estimate).
//! [`Motion::delta_shadow_keeps`] keeps the pair when `m` moves, the light moves, or the light's cone
//! (the sun's beam) around a moving shape's grown bounds meets the one around `m`'s: only then can a
//! moving shape be the receiver.

use crate::camera::CameraFrame;
use crate::emitter::Emitter;
use crate::integrator::attach::geometry_selected;
use crate::math::{Aabb, Vec3};
use crate::scene::Scene;

/// How far the image box of a shape's bounds is grown, in pixels, on every side: with both boxes
/// grown, one pixel between them, fifty times the background ray's offset (1/50 of a pixel).
const FILM_MARGIN_PIXELS: f32 = 0.5;

/// How far the world bounds are grown before they are projected or turned into cones, in hit
/// tolerances at their largest coordinate (and the eye's or light's): beyond the offsets of the rays
/// traced past the silhouettes (at most eight tolerances) and the tolerance of the hits.
const WORLD_MARGIN_TOLERANCES: f32 = 64.0;

/// An axis-aligned box on the film, pixels; `None` in [`Motion`] stands for the whole film plane.
#[derive(Copy, Clone, Debug, PartialEq)]
struct FilmBox {
    min: (f32, f32),
    max: (f32, f32),
}

impl FilmBox {
    fn overlaps(&self, o: &FilmBox) -> bool {
        self.min.0 <= o.max.0
            && o.min.0 <= self.max.0
            && self.min.1 <= o.max.1
            && o.min.1 <= self.max.1
    }
}

/// `b` grown by [`WORLD_MARGIN_TOLERANCES`] hit tolerances of `scene` at the largest magnitude of its
/// corners and of `viewer` (the eye or the light).
fn grown(scene: &Scene, b: &Aabb, viewer: glam::Vec3) -> Aabb {
    let magnitude = b
        .min
        .abs()
        .max(b.max.abs())
        .max_element()
        .max(viewer.abs().max_element());
    b.expanded(WORLD_MARGIN_TOLERANCES * scene.trace.eps_at(magnitude))
}

/// The film box of `b` (grown, [`grown`]) seen through `frame`, grown by [`FILM_MARGIN_PIXELS`];
/// `None` (the whole film plane) for an unbounded box or one with a corner not in front of the eye.
fn film_box(scene: &Scene, frame: &CameraFrame<f32>, b: &Aabb) -> Option<FilmBox> {
    if !b.is_finite() {
        return None;
    }
    let b = grown(scene, b, frame.origin.into());
    let mut out = FilmBox {
        min: (f32::INFINITY, f32::INFINITY),
        max: (f32::NEG_INFINITY, f32::NEG_INFINITY),
    };
    for c in b.corners() {
        let (x, y) = frame.project(Vec3::constant(c))?;
        if !(x.is_finite() && y.is_finite()) {
            return None;
        }
        out.min = (out.min.0.min(x), out.min.1.min(y));
        out.max = (out.max.0.max(x), out.max.1.max(y));
    }
    let m = FILM_MARGIN_PIXELS;
    out.min = (out.min.0 - m, out.min.1 - m);
    out.max = (out.max.0 + m, out.max.1 + m);
    Some(out)
}

/// Which parts of a scene (with its selection applied) move with the selected parameters: see the
/// [module docs](self).
#[derive(Clone, Debug)]
pub struct Motion {
    /// Whether a camera parameter is selected.
    pub camera: bool,
    /// Per shape: whether its geometry (SDF or translation) has a selected parameter.
    pub shapes: Vec<bool>,
    /// Per emitter: whether its position, size or direction has a selected parameter.
    pub emitters: Vec<bool>,
    /// Film boxes of the moving shapes and finite emitters (`None`: the whole film).
    moving_boxes: Vec<Option<FilmBox>>,
    /// World bounds of the moving shapes.
    moving_bounds: Vec<Aabb>,
}

impl Motion {
    /// What moves in `scene` with its selected parameters.
    pub fn of(scene: &Scene) -> Self {
        let c = &scene.camera;
        let camera = [&c.origin, &c.target, &c.up]
            .into_iter()
            .flat_map(|v| v.c.iter())
            .chain(std::iter::once(&c.fov_y))
            .any(|p| p.slot.is_some());
        let shapes: Vec<bool> = scene.shapes.iter().map(geometry_selected).collect();
        let emitters: Vec<bool> = (scene.emitters.iter())
            .map(|e| delta_light_selected(&e.emitter) || e.emitter.geometry_selected())
            .collect();
        let frame = c.frame::<f32>();
        let moving_bounds: Vec<Aabb> = (scene.shapes.iter().zip(&shapes))
            .filter(|(_, m)| **m)
            .map(|(s, _)| s.bounds)
            .collect();
        // Finite emitters are what camera rays can meet; a moving one without bounds (none today)
        // would cover the whole film.
        let moving_emitters = (scene.emitters.iter().zip(&emitters))
            .filter(|(e, m)| **m && !e.emitter.is_infinite() && !e.emitter.is_delta())
            .map(|(e, _)| {
                e.emitter
                    .bounds()
                    .unwrap_or(Aabb::new(glam::Vec3::NEG_INFINITY, glam::Vec3::INFINITY))
            });
        let moving_boxes = (moving_bounds.iter().copied())
            .chain(moving_emitters)
            .map(|b| film_box(scene, &frame, &b))
            .collect();
        Self {
            camera,
            shapes,
            emitters,
            moving_boxes,
            moving_bounds,
        }
    }

    /// Whether the primary term of shape `m`'s silhouette (seen from the camera) can be non-zero: the
    /// camera moves, `m` moves, or a moving shape or finite emitter can be seen next to `m` on the
    /// film (module docs). Where this is `false` every sample of that silhouette is exactly zero.
    pub fn primary_keeps(&self, scene: &Scene, m: usize) -> bool {
        if self.camera || self.shapes[m] {
            return true;
        }
        if self.moving_boxes.is_empty() {
            return false;
        }
        let frame = scene.camera.frame::<f32>();
        let Some(own) = film_box(scene, &frame, &scene.shapes[m].bounds) else {
            return true;
        };
        self.moving_boxes
            .iter()
            .any(|b| b.is_none_or(|b| b.overlaps(&own)))
    }

    /// Whether the hard shadow of shape `m`'s silhouette seen from delta light `light` (a point light
    /// or the sun, [`super::delta_shadows`]) can carry a non-zero term: `m` moves, the light's position
    /// (direction) is selected, or a moving shape can be the receiver (module docs). Where this is
    /// `false` every sample is exactly zero. `true` for any other kind of light.
    pub fn delta_shadow_keeps(&self, scene: &Scene, light: usize, m: usize) -> bool {
        if self.shapes[m] || self.emitters[light] {
            return true;
        }
        let emitter = &scene.emitters[light].emitter;
        let own = scene.shapes[m].bounds;
        match emitter {
            Emitter::Point { position, .. } => {
                let y = position.value();
                let own = grown(scene, &own, y);
                (self.moving_bounds.iter()).any(|b| cones_meet(y, &grown(scene, b, y), &own))
            }
            Emitter::Directional { .. } => {
                let Some(w) = emitter.delta_travel(glam::Vec3::ZERO) else {
                    return true;
                };
                let origin = glam::Vec3::ZERO;
                let own = grown(scene, &own, origin);
                (self.moving_bounds.iter()).any(|b| beams_meet(w, &grown(scene, b, origin), &own))
            }
            _ => true,
        }
    }
}

/// Whether a delta light's position (a point light) or direction (the sun) is selected.
fn delta_light_selected(e: &Emitter) -> bool {
    let sel = |p: &crate::scalar::Param| p.slot.is_some();
    match e {
        Emitter::Point { position, .. } => position.c.iter().any(sel),
        Emitter::Directional { direction, .. } => direction.c.iter().any(sel),
        _ => false,
    }
}

/// Whether the cones from `y` around the bounding spheres of boxes `a` and `b` meet (true for a box
/// not finite or whose bounding sphere reaches `y`).
fn cones_meet(y: glam::Vec3, a: &Aabb, b: &Aabb) -> bool {
    let cone = |b: &Aabb| -> Option<(glam::Vec3, f32)> {
        if !b.is_finite() {
            return None;
        }
        let (c, r) = (b.center(), 0.5 * b.extent().length());
        let d = (c - y).length();
        if d.is_nan() || d <= r {
            return None;
        }
        Some(((c - y) / d, (r / d).asin()))
    };
    let (Some((da, ha)), Some((db, hb))) = (cone(a), cone(b)) else {
        return true;
    };
    // The angle by atan2 (acos loses half the digits near 0); the slack covers rounding, far below
    // the boxes' growth.
    da.cross(db).length().atan2(da.dot(db)) <= ha + hb + 1e-5
}

/// Whether the beams along unit `w` around the bounding spheres of boxes `a` and `b` meet (true for a
/// box not finite).
fn beams_meet(w: glam::Vec3, a: &Aabb, b: &Aabb) -> bool {
    if !(a.is_finite() && b.is_finite()) {
        return true;
    }
    let across = |v: glam::Vec3| v - w * w.dot(v);
    let (ra, rb) = (0.5 * a.extent().length(), 0.5 * b.extent().length());
    across(a.center() - b.center()).length() <= (ra + rb) * (1.0 + 1e-5)
}
