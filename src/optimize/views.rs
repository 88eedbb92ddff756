//! The cameras an optimisation renders from.

use crate::error::Result;
use crate::scene::Scene;

/// A camera pose: the scene's camera with another origin, target, up and field of view (same film).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct View {
    /// Eye position.
    pub origin: glam::Vec3,
    /// The point looked at.
    pub target: glam::Vec3,
    /// Up direction.
    pub up: glam::Vec3,
    /// Vertical field of view in degrees.
    pub fov_y: f32,
}

impl View {
    /// The pose of `camera`.
    pub fn of(camera: &crate::camera::Camera) -> Self {
        Self {
            origin: camera.origin.value(),
            target: camera.target.value(),
            up: camera.up.value(),
            fov_y: camera.fov_y.value,
        }
    }

    /// `scene` seen from this view (its camera's film, filter and selection kept). Errors: an invalid
    /// camera (e.g. `up` parallel to the view direction, a field of view outside `(0, 180)`).
    pub fn apply(&self, scene: &Scene) -> Result<Scene> {
        let mut camera = scene.camera.clone();
        for (p, v) in [
            (&mut camera.origin, self.origin),
            (&mut camera.target, self.target),
            (&mut camera.up, self.up),
        ] {
            for (c, x) in p.c.iter_mut().zip(v.to_array()) {
                c.value = x;
            }
        }
        camera.fov_y.value = self.fov_y;
        camera.validate()?;
        Ok(scene.with_camera(camera))
    }
}

/// `count` views evenly spaced on a horizontal circle of radius `radius` at height `height` above
/// `look_at`, all looking at `look_at` with `+y` up; the first at azimuth 0 (on `+z`).
pub fn orbit(count: usize, radius: f32, height: f32, look_at: glam::Vec3, fov_y: f32) -> Vec<View> {
    (0..count)
        .map(|k| {
            let a = std::f32::consts::TAU * k as f32 / count as f32;
            View {
                origin: look_at + glam::Vec3::new(radius * a.sin(), height, radius * a.cos()),
                target: look_at,
                up: glam::Vec3::Y,
                fov_y,
            }
        })
        .collect()
}
