//! The camera's view frustum, grown by the pixel filter's reach: which parts of curves (emitter
//! outlines, crease edges) can project onto the film.

use crate::scene::Scene;

/// The view frustum grown by the filter radius plus one pixel: half-spaces `n·(x − eye) ≥ offset`.
pub(crate) struct Frustum {
    eye: glam::Vec3,
    planes: [(glam::Vec3, f32); 5],
}

impl Frustum {
    pub(crate) fn of(scene: &Scene) -> Self {
        let frame = scene.camera.frame::<f32>();
        let (r, up, fwd): (glam::Vec3, glam::Vec3, glam::Vec3) =
            (frame.right.into(), frame.up.into(), frame.forward.into());
        let f = frame.focal;
        let (cx, cy) = frame.center;
        let grow = scene.camera.filter.radius() + 1.0;
        let (w, h) = (scene.camera.width as f32, scene.camera.height as f32);
        // x = cx + f (q·r)/z ≥ −grow  ⇔  f q·r + (cx + grow) z ≥ 0, and likewise for the other sides.
        let planes = [
            (r * f + fwd * (cx + grow), 0.0),
            (fwd * (w + grow - cx) - r * f, 0.0),
            (fwd * (cy + grow) - up * f, 0.0),
            (up * f + fwd * (h + grow - cy), 0.0),
            // In front of the eye (the projection needs z > 0).
            (fwd, 4.0 * scene.trace.eps_at_point(frame.origin.into())),
        ];
        Self {
            eye: frame.origin.into(),
            planes,
        }
    }

    /// The part of the segment `a b` inside, if any.
    pub(crate) fn clip(&self, a: glam::Vec3, b: glam::Vec3) -> Option<(glam::Vec3, glam::Vec3)> {
        let (mut t0, mut t1) = (0.0f32, 1.0f32);
        for (n, off) in self.planes {
            let (ga, gb) = (n.dot(a - self.eye) - off, n.dot(b - self.eye) - off);
            if ga < 0.0 && gb < 0.0 {
                return None;
            }
            if ga < 0.0 {
                t0 = t0.max(ga / (ga - gb));
            } else if gb < 0.0 {
                t1 = t1.min(ga / (ga - gb));
            }
        }
        (t0 < t1).then(|| (a + (b - a) * t0, a + (b - a) * t1))
    }

    /// True when the ball is entirely outside one of the planes.
    pub(crate) fn misses_ball(&self, o: glam::Vec3, r: f32) -> bool {
        self.planes.iter().any(|&(n, off)| {
            let len = n.length();
            len > 0.0 && (n.dot(o - self.eye) - off) / len < -r
        })
    }
}
