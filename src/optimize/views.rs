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
        self.apply_reduced(scene, 1)
    }

    /// [`View::apply`] with the film's width and height divided by `divisor` (the same field of
    /// view; `divisor` must divide both).
    pub fn apply_reduced(&self, scene: &Scene, divisor: u32) -> Result<Scene> {
        let mut camera = scene.camera.clone();
        camera.width /= divisor;
        camera.height /= divisor;
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

/// `count` views evenly spaced in azimuth on a horizontal circle of radius `radius` around `look_at`,
/// view `k` at height `heights[k mod heights.len()]` above it (one height: one ring; `[h, −h]`: views
/// alternately above and below), all looking at `look_at` with `+y` up; the first at azimuth 0 (on
/// `+z`). No views if `heights` is empty.
pub fn orbit(
    count: usize,
    radius: f32,
    heights: &[f32],
    look_at: glam::Vec3,
    fov_y: f32,
) -> Vec<View> {
    if heights.is_empty() {
        return Vec::new();
    }
    (0..count)
        .map(|k| {
            let a = std::f32::consts::TAU * k as f32 / count as f32;
            let height = heights[k % heights.len()];
            View {
                origin: look_at + glam::Vec3::new(radius * a.sin(), height, radius * a.cos()),
                target: look_at,
                up: glam::Vec3::Y,
                fov_y,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orbit_cycles_through_its_heights() {
        let look_at = glam::Vec3::new(0.5, -0.1, 2.0);
        let views = orbit(8, 4.0, &[2.0, -1.0], look_at, 30.0);
        assert_eq!(views.len(), 8);
        for (k, v) in views.iter().enumerate() {
            let offset = v.origin - look_at;
            let want = if k % 2 == 0 { 2.0 } else { -1.0 };
            assert!((offset.y - want).abs() < 1e-6, "view {k}: {offset}");
            assert!(
                (offset.x.hypot(offset.z) - 4.0).abs() < 1e-5,
                "view {k}: {offset}"
            );
            assert_eq!((v.target, v.up, v.fov_y), (look_at, glam::Vec3::Y, 30.0));
        }
        // The first on +z, the third a quarter turn on (+x).
        assert!((views[0].origin - look_at - glam::Vec3::new(0.0, 2.0, 4.0)).length() < 1e-5);
        assert!((views[2].origin - look_at - glam::Vec3::new(4.0, 2.0, 0.0)).length() < 1e-5);
        assert!(orbit(3, 1.0, &[], look_at, 30.0).is_empty());
    }
}
