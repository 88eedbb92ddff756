//! Checks that catch an image that will come out black or without a shape before anything is
//! rendered: a rectangle light whose emitting side faces nothing the camera sees, and a shape whose
//! bounds lie wholly outside the camera's view.
//!
//! Both are conservative (a warning is certain, silence is not): a shape is outside the view only
//! when its whole box is beyond one side of the view's pyramid; a rectangle lights nothing only when
//! the camera is behind it and, for the `direct` integrator, no first hit of a grid of camera rays
//! lies in front of it (only those points are lit), or, for the `path` integrator, no shape's box
//! reaches in front of it (light could bounce from there into the view; an unbounded shape always
//! might).

use super::{IntegratorKind, Intersection, Scene};
use crate::emitter::Emitter;

/// Camera rays per image side that look for points a rectangle light could reach.
const PROBES: u32 = 48;
/// Pixels beyond the image's edge that still count as in view (the pixel filter's reach).
const MARGIN: f32 = 2.0;

impl Scene {
    /// What cannot show in the image, one line each (see the module's documentation): shapes outside
    /// the camera's view, rectangle emitters that light nothing the camera sees. Empty for a scene
    /// whose every part can show.
    pub fn reach_warnings(&self) -> Vec<String> {
        let words = ["the camera's view", "the camera", "the camera"];
        self.reach_warnings_from(std::slice::from_ref(self), words)
    }

    /// [`Scene::reach_warnings`] for several views of this scene (e.g. an optimisation's), each
    /// `views[k]` this scene with another camera: shapes outside every view, rectangle emitters that
    /// light nothing any view sees.
    pub fn reach_warnings_in_views(&self, views: &[Scene]) -> Vec<String> {
        match views {
            [one] => one.reach_warnings(),
            _ => self.reach_warnings_from(views, ["every view", "any view", "every camera"]),
        }
    }

    /// The warnings of [`Scene::reach_warnings`] over `views` (this scene with other cameras), naming
    /// them with `[in_view, sees, cameras]`: "the camera's view", "the camera", "the camera" for one.
    fn reach_warnings_from(&self, views: &[Scene], words: [&str; 3]) -> Vec<String> {
        let [in_view, sees, cameras] = words;
        let mut lines = Vec::new();
        for shape in &self.shapes {
            if views.iter().all(|v| v.outside_view(shape.bounds)) {
                lines.push(format!(
                    "shape {:?} lies outside {in_view} (it can still cast shadows and reflect \
                     light into it)",
                    shape.name
                ));
            }
        }
        for named in &self.emitters {
            if let Emitter::Rectangle { center, normal, .. } = &named.emitter
                && !(views.iter()).any(|v| v.lit_from((center.value(), *normal)))
            {
                lines.push(format!(
                    "emitter {:?} lights nothing {sees} sees (its emitting side, along its normal \
                     {:?}, faces away from {cameras} and from {})",
                    named.name,
                    normal.to_array(),
                    match self.integrator {
                        IntegratorKind::Direct => "every surface in view",
                        IntegratorKind::Path { .. } => "every shape",
                    }
                ));
            }
        }
        lines
    }

    /// Whether the box lies wholly beyond one side of the camera's view pyramid.
    fn outside_view(&self, bounds: crate::math::Aabb) -> bool {
        if !bounds.is_finite() || bounds.is_empty() {
            return false;
        }
        let frame = self.camera.frame::<f32>();
        let (origin, right, up, forward): (glam::Vec3, glam::Vec3, glam::Vec3, glam::Vec3) = (
            frame.origin.into(),
            frame.right.into(),
            frame.up.into(),
            frame.forward.into(),
        );
        if frame.focal <= 0.0 {
            return false;
        }
        // Half the film's extent per unit depth, with the margin.
        let tx = (0.5 * self.camera.width as f32 + MARGIN) / frame.focal;
        let ty = (0.5 * self.camera.height as f32 + MARGIN) / frame.focal;
        let local: Vec<glam::Vec3> = (bounds.corners().iter())
            .map(|p| {
                let q = *p - origin;
                glam::Vec3::new(q.dot(right), q.dot(up), q.dot(forward))
            })
            .collect();
        let beyond = |side: &dyn Fn(glam::Vec3) -> bool| local.iter().all(|&c| side(c));
        beyond(&|c| c.z <= 0.0)
            || beyond(&|c| c.x > tx * c.z)
            || beyond(&|c| c.x < -tx * c.z)
            || beyond(&|c| c.y > ty * c.z)
            || beyond(&|c| c.y < -ty * c.z)
    }

    /// Whether a one-sided emitter in the plane through `center` with unit `normal` can light
    /// something the camera sees.
    fn lit_from(&self, (center, normal): (glam::Vec3, glam::Vec3)) -> bool {
        let in_front = |p: glam::Vec3| normal.dot(p - center) > 0.0;
        if in_front(self.camera.origin.value()) {
            return true;
        }
        match self.integrator {
            IntegratorKind::Path { max_depth } if max_depth > 1 => (self.shapes.iter())
                .any(|s| !s.bounds.is_finite() || s.bounds.corners().iter().any(|&p| in_front(p))),
            _ => {
                let frame = self.camera.frame::<f32>();
                let (w, h) = (self.camera.width as f32, self.camera.height as f32);
                (0..PROBES * PROBES).any(|k| {
                    let (i, j) = ((k % PROBES) as f32 + 0.5, (k / PROBES) as f32 + 0.5);
                    let film = glam::Vec2::new(i * w / PROBES as f32, j * h / PROBES as f32);
                    let ray = frame.generate_ray(film);
                    match self.intersect(&ray, f32::INFINITY) {
                        Intersection::Hit(hit) => in_front(hit.p),
                        _ => false,
                    }
                })
            }
        }
    }
}
