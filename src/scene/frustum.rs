//! The shapes a pixel's camera rays can meet, found once per pixel and shared by its samples.
//!
//! Every camera ray of a pixel leaves the eye through a film point within the pixel filter's support
//! around the pixel's centre, so it lies in the pyramid with apex at the eye spanned by that square
//! ([`PixelFrustum`]). A walk of the scene's hierarchy for a run of [`SEGMENT`] pixels of a row
//! collects the shapes whose boxes may meet the run's pyramid; each pixel keeps those that may meet
//! its own, and each of its samples' camera rays is traced against those alone
//! ([`super::Scene::intersect_among`]), in the same order and over the same intervals as
//! [`super::Scene::intersect_resolving`]'s walk would trace them, so its hit is the same, bit for bit.
//!
//! The culling must never drop a shape a ray's own test would keep. A ray tests a shape's box grown by
//! the local tolerance where it enters it ([`super::Scene::trace_interval`]; for a ray passing beside
//! the box, where it first leaves one of the box's slabs: at most √3 times as far as the box's
//! farthest point from the eye). The tolerance grows at most linearly with the distance, so twice
//! the tolerance at the farthest point bounds it; the pyramid test grows each box by that, plus 64 ulps
//! of the coordinates' magnitude there, which exceeds the rounding of the rays' directions (they may
//! leave the exact pyramid by a few ulps of their length: more than a pixel at a tiny field of view),
//! of the rays' box tests and of the plane test itself. A node's box holds its shapes' boxes and its
//! farthest point is at least as far, so culling a node culls none of its shapes that the shapes' own
//! tests would keep. Four boxes are tested at once, in the lanes of one SIMD register.

use super::Scene;
use super::bvh::LEAF;
use super::shape_list::{ShapeList, set_lanes};
use crate::camera::CameraFrame;
use crate::math::Aabb;
use glam::{Vec3, Vec4};

/// Samples per pixel from which the pixel's shapes are gathered first: at one, gathering them costs
/// more than the camera ray saves (`examples/camera_culling`, camera rays alone, gathered / walked:
/// 1.1–1.4 at 1 sample, 0.85–0.90 at 2, 0.70–0.86 at 4, at 10, 100 and 1,000 balls).
pub const MIN_SAMPLES: u32 = 2;

/// Pixels of a row whose shapes one walk of the hierarchy gathers.
pub const SEGMENT: u32 = 8;

/// The pyramid, apex at the eye, holding every camera ray through a rectangle of the film: its four
/// side planes and the plane facing the view direction, as inward normals through the eye.
#[derive(Copy, Clone, Debug)]
pub struct PixelFrustum {
    /// The eye.
    origin: Vec3,
    /// Largest coordinate magnitude of the eye (where the rays' tolerances start).
    origin_magnitude: f32,
    /// Inward normals: `n · (p − origin) ≥ 0` for every point `p` of the pyramid.
    planes: [Vec3; 5],
}

impl PixelFrustum {
    /// The pyramid of the film rectangle `[x0, x1] × [y0, y1]` (pixels from the top-left corner) seen
    /// from `frame`'s eye; `None` for a degenerate camera (no positive, finite focal length).
    pub fn new(frame: &CameraFrame<f32>, x0: f32, x1: f32, y0: f32, y1: f32) -> Option<Self> {
        let focal = frame.focal;
        if !(focal > 0.0 && focal.is_finite()) {
            return None;
        }
        let (right, up, forward) = (
            Vec3::from(frame.right),
            Vec3::from(frame.up),
            Vec3::from(frame.forward),
        );
        let (cx, cy) = frame.center;
        // A ray through film point (cx + a, cy + b) has direction a·right − b·up + focal·forward.
        let (a0, a1) = (x0 - cx, x1 - cx);
        let (b0, b1) = (y0 - cy, y1 - cy);
        let origin = Vec3::from(frame.origin);
        Some(Self {
            origin,
            origin_magnitude: origin.abs().max_element(),
            planes: [
                focal * right - a0 * forward,
                a1 * forward - focal * right,
                -focal * up - b0 * forward,
                b1 * forward + focal * up,
                forward,
            ],
        })
    }

    /// The pyramid of the camera rays of pixels `x0 ..= x1` of row `y`: the filter's support (`radius`
    /// pixels) around their centres, widened by a thousandth of a pixel.
    pub fn of_pixels(
        frame: &CameraFrame<f32>,
        radius: f32,
        x0: u32,
        x1: u32,
        y: u32,
    ) -> Option<Self> {
        let r = radius + 1e-3;
        let cy = y as f32 + 0.5;
        Self::new(
            frame,
            x0 as f32 + 0.5 - r,
            x1 as f32 + 0.5 + r,
            cy - r,
            cy + r,
        )
    }

    /// Per lane, whether a ray of the pyramid may meet the box `[lo, hi]` grown by the tracer's
    /// tolerance (floor `eps`, module notes): `false` only where none can. A lane with an empty or
    /// non-finite box (no number in its arithmetic) is not met.
    #[inline]
    fn may_meet_lanes(&self, lo: [Vec4; 3], hi: [Vec4; 3], eps: f32) -> u32 {
        let o = self.origin.to_array();
        let centre: [Vec4; 3] = std::array::from_fn(|a| 0.5 * (lo[a] + hi[a]) - Vec4::splat(o[a]));
        let half: [Vec4; 3] = std::array::from_fn(|a| 0.5 * (hi[a] - lo[a]));
        let far: [Vec4; 3] = std::array::from_fn(|a| centre[a].abs() + half[a]);
        let farthest = (far[0] * far[0] + far[1] * far[1] + far[2] * far[2]).sqrt();
        let magnitude = Vec4::splat(self.origin_magnitude) + farthest;
        // Twice the tolerance `max(eps, 16 ε m)` there, and 64 ulps of the magnitude.
        let grow = Vec4::splat(2.0 * eps).max(magnitude * (32.0 * f32::EPSILON))
            + magnitude * (64.0 * f32::EPSILON);
        let half: [Vec4; 3] = std::array::from_fn(|a| half[a] + grow);
        let mut keep = lo[0].cmple(hi[0]) & lo[1].cmple(hi[1]) & lo[2].cmple(hi[2]);
        for n in &self.planes {
            let v = centre[0] * n.x
                + centre[1] * n.y
                + centre[2] * n.z
                + half[0] * n.x.abs()
                + half[1] * n.y.abs()
                + half[2] * n.z.abs();
            // Also false for a NaN lane.
            keep &= v.cmpge(Vec4::ZERO);
        }
        keep.bitmask()
    }

    /// Whether a ray of the pyramid may meet the box `b` grown by the tracer's tolerance (floor `eps`,
    /// module notes): `false` only when none can; an empty or non-finite box is not met.
    #[inline]
    pub fn may_meet(&self, b: &Aabb, eps: f32) -> bool {
        let lanes = |v: Vec3| v.to_array().map(Vec4::splat);
        self.may_meet_lanes(lanes(b.min), lanes(b.max), eps) & 1 != 0
    }
}

impl Scene {
    /// Appends to `out` every shape of the hierarchy (not those it keeps apart) whose box a ray of
    /// `frustum` may meet; `false` when the queries do not use a hierarchy. `stack` is scratch.
    pub fn shapes_in_frustum(
        &self,
        frustum: &PixelFrustum,
        stack: &mut Vec<u32>,
        out: &mut Vec<u32>,
    ) -> bool {
        let Some(bvh) = self.hierarchy() else {
            return false;
        };
        if bvh.wide.is_empty() {
            return true;
        }
        let eps = self.trace.eps;
        stack.clear();
        stack.push(0);
        while let Some(k) = stack.pop() {
            let node = &bvh.wide[k as usize];
            for j in set_lanes(node.lanes & frustum.may_meet_lanes(node.lo, node.hi, eps)) {
                let child = node.child[j];
                if child & LEAF == 0 {
                    stack.push(child);
                    continue;
                }
                let leaf = bvh.nodes[(child & !LEAF) as usize];
                let range = leaf.first as usize..(leaf.first + leaf.count) as usize;
                out.extend(
                    (bvh.order[range].iter())
                        .filter(|&&i| frustum.may_meet(&self.shapes[i as usize].bounds, eps)),
                );
            }
        }
        true
    }
}

/// The shapes the camera rays of the pixel being rendered can meet, gathered by runs of [`SEGMENT`]
/// pixels ([`Scene::shapes_in_frustum`]) and kept from pixel to pixel, so that a thread allocates once.
#[derive(Clone, Debug, Default)]
pub struct PixelShapes {
    /// The run of pixels (row, first pixel) whose shapes `run` holds.
    key: Option<(u32, u32)>,
    /// The run's shapes in the hierarchy, in increasing index order.
    run: ShapeList,
    /// The pixel's: those of the run its own pyramid may meet, and the shapes kept apart, in
    /// increasing index order.
    shapes: ShapeList,
    /// Scratch: shapes' indices, and the walk's stack.
    indices: Vec<u32>,
    stack: Vec<u32>,
}

impl PixelShapes {
    /// The only shapes pixel `(x, y)`'s camera rays can meet, in increasing index order, for a render
    /// at `spp` samples per pixel; `None` (trace them against every shape) when the scene has no
    /// hierarchy, the camera is degenerate or `spp` is below [`MIN_SAMPLES`].
    pub fn gather(
        &mut self,
        scene: &Scene,
        frame: &CameraFrame<f32>,
        x: u32,
        y: u32,
        spp: u32,
    ) -> Option<&ShapeList> {
        if spp < MIN_SAMPLES {
            return None;
        }
        let bvh = scene.hierarchy()?;
        let radius = scene.camera.filter.radius();
        let eps = scene.trace.eps;
        let first = x - x % SEGMENT;
        if self.key != Some((y, first)) {
            self.key = None;
            self.indices.clear();
            let last = (first + SEGMENT - 1).min(scene.camera.width.max(1) - 1);
            let run = PixelFrustum::of_pixels(frame, radius, first, last, y)?;
            scene.shapes_in_frustum(&run, &mut self.stack, &mut self.indices);
            self.indices.sort_unstable();
            self.run.set(scene, self.indices.iter().copied());
            self.key = Some((y, first));
        }
        let pixel = PixelFrustum::of_pixels(frame, radius, x, x, y)?;
        self.indices.clear();
        for (four, [lo, hi]) in self.run.fours() {
            let lanes = pixel.may_meet_lanes(*lo, *hi, eps);
            self.indices.extend(set_lanes(lanes).map(|j| four[j]));
        }
        if !bvh.apart.is_empty() {
            self.indices.extend_from_slice(&bvh.apart);
            self.indices.sort_unstable();
        }
        self.shapes.set(scene, self.indices.iter().copied());
        Some(&self.shapes)
    }
}
