//! What moves with the selected parameters, and which silhouettes seen from the camera can therefore
//! carry a non-zero primary term.
//!
//! A primary boundary sample on the silhouette of shape `m` contributes `−L_bg v`, `v = −∂πh / rate`,
//! `h = φ_m(c + |c x_B| d̂)` with `c` the lifted eye and `d̂` the direction towards the attached
//! background point `x_D` (or the fixed direction for a background at infinity; see
//! [`super::primary`]). `∂πh` has three sources only: `φ_m`'s own parameters (the shape moves), the
//! camera's (`c`, and the frame that places a background at infinity), and the attached `x_D`, which
//! moves only on a shape or emitter whose geometry is selected ([`crate::integrator::attach::SceneAttach`]:
//! every other vertex is attached as a constant). When none of them is selected, every dual part of `h`
//! is exactly zero, so is `v`, and the whole silhouette adds exactly nothing: its extraction and its
//! share of the samples are saved.
//!
//! `x_D` is the first thing a camera ray just outside `m`'s silhouette meets, so it lies on something
//! whose image overlaps `m`'s image. [`Motion::primary_keeps`] keeps `m` when the camera moves, when
//! `m` moves, when a moving emitter exists (conservatively, wherever it is), or when the image box of a
//! moving shape's bounds overlaps that of `m`'s (a box that reaches behind the eye covers the whole
//! film).

use crate::camera::CameraFrame;
use crate::emitter::Emitter;
use crate::integrator::attach::geometry_selected;
use crate::math::{Aabb, Vec3};
use crate::scene::Scene;

/// How far the image box of a shape's bounds is grown, in pixels: beyond the background ray's offset
/// (1/50 of a pixel) and rounding.
const FILM_MARGIN_PIXELS: f32 = 2.0;

/// An axis-aligned box on the film, pixels; `None` in [`Motion`] stands for the whole film plane.
#[derive(Copy, Clone, Debug, PartialEq)]
struct FilmBox {
    min: (f32, f32),
    max: (f32, f32),
}

impl FilmBox {
    fn overlaps(&self, o: &FilmBox) -> bool {
        self.min.0 <= o.max.0 && o.min.0 <= self.max.0 && self.min.1 <= o.max.1 && o.min.1 <= self.max.1
    }
}

/// The film box of `b` seen through `frame`, grown by [`FILM_MARGIN_PIXELS`]; `None` (the whole film
/// plane) for an unbounded box or one with a corner not in front of the eye.
fn film_box(frame: &CameraFrame<f32>, b: &Aabb) -> Option<FilmBox> {
    if !b.is_finite() {
        return None;
    }
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
    /// Per emitter: whether its position or size has a selected parameter.
    pub emitters: Vec<bool>,
    /// Film boxes of the moving shapes (`None`: the whole film).
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
        let emitters = scene
            .emitters
            .iter()
            .map(|e| e.emitter.geometry_selected())
            .collect();
        let frame = c.frame::<f32>();
        let moving_boxes = (scene.shapes.iter().zip(&shapes))
            .filter(|(_, m)| **m)
            .map(|(s, _)| film_box(&frame, &s.bounds))
            .collect();
        let moving_bounds = (scene.shapes.iter().zip(&shapes))
            .filter(|(_, m)| **m)
            .map(|(s, _)| s.bounds)
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
    /// camera moves, `m` moves, an emitter moves, or a moving shape can be seen next to `m` on the film
    /// (module docs). Where this is `false` every sample of that silhouette is exactly zero.
    pub fn primary_keeps(&self, scene: &Scene, m: usize) -> bool {
        if self.camera || self.shapes[m] || self.emitters.iter().any(|&e| e) {
            return true;
        }
        if self.moving_boxes.is_empty() {
            return false;
        }
        let Some(own) = film_box(&scene.camera.frame::<f32>(), &scene.shapes[m].bounds) else {
            return true;
        };
        self.moving_boxes
            .iter()
            .any(|b| b.is_none_or(|b| b.overlaps(&own)))
    }

    /// Whether the hard shadow of shape `m`'s silhouette seen from delta light `light` (a point light
    /// or the sun, [`super::delta_shadows`]) can carry a non-zero term: `m` moves, the light's position
    /// (direction) is selected, or a moving shape can be the receiver, the first surface beyond the
    /// silhouette seen from the light (the light's cone, or the sun's beam, around a moving shape's
    /// bounds meets the one around `m`'s). The term's `v` depends on nothing else: where this is
    /// `false` every sample is exactly zero. `true` for any other kind of light.
    pub fn delta_shadow_keeps(&self, scene: &Scene, light: usize, m: usize) -> bool {
        let sel = |p: &crate::scalar::Param| p.slot.is_some();
        let own = scene.shapes[m].bounds;
        if self.shapes[m] {
            return true;
        }
        let light = &scene.emitters[light].emitter;
        match light {
            Emitter::Point { position, .. } => {
                let y = position.value();
                position.c.iter().any(sel)
                    || (self.moving_bounds.iter()).any(|b| cones_meet(y, b, &own))
            }
            Emitter::Directional { direction, .. } => {
                if direction.c.iter().any(sel) {
                    return true;
                }
                let Some(w) = light.delta_travel(glam::Vec3::ZERO) else {
                    return true;
                };
                (self.moving_bounds.iter()).any(|b| beams_meet(w, b, &own))
            }
            _ => true,
        }
    }
}

/// Angular slack of [`cones_meet`] (radians) and relative slack of [`beams_meet`]: beyond the
/// offset of the ray past the silhouette (a few hit tolerances) and rounding.
const VIEW_SLACK: f32 = 1e-3;

/// Whether the cones from `y` around the bounding spheres of boxes `a` and `b` meet (true for a box
/// not finite or reaching `y`).
fn cones_meet(y: glam::Vec3, a: &Aabb, b: &Aabb) -> bool {
    let cone = |b: &Aabb| -> Option<(glam::Vec3, f32)> {
        if !b.is_finite() {
            return None;
        }
        let (c, r) = (b.center(), 0.5 * b.extent().length());
        let d = (c - y).length();
        if !(d > r * (1.0 + VIEW_SLACK)) {
            return None;
        }
        Some(((c - y) / d, (r / d).asin()))
    };
    let (Some((da, ha)), Some((db, hb))) = (cone(a), cone(b)) else {
        return true;
    };
    da.dot(db).clamp(-1.0, 1.0).acos() <= ha + hb + VIEW_SLACK
}

/// Whether the beams along unit `w` around the bounding spheres of boxes `a` and `b` meet (true for a
/// box not finite).
fn beams_meet(w: glam::Vec3, a: &Aabb, b: &Aabb) -> bool {
    if !(a.is_finite() && b.is_finite()) {
        return true;
    }
    let across = |v: glam::Vec3| v - w * w.dot(v);
    let (ra, rb) = (0.5 * a.extent().length(), 0.5 * b.extent().length());
    across(a.center() - b.center()).length() <= (ra + rb) * (1.0 + VIEW_SLACK)
}
