//! A list of shapes with their boxes four per SIMD lane, so that a ray clips itself against four of
//! them at once instead of shape by shape.
//!
//! [`super::Scene::trace_interval`] clips a ray against a shape's box grown by the tracer's tolerance
//! where the ray enters it ([`crate::math::Aabb::clip_with_margin`]). [`ShapeList::intervals`] does
//! the same arithmetic in the lanes of one register: the same IEEE operations on the same operands
//! in the same order, lane by lane. The shape's own test does a few of them on single numbers
//! (`f32::max`, which passes over a NaN where the register's `max` may return it, and reductions
//! across axes in another order), so the two agree wherever every value of the lane is a number, but
//! for the sign of a zero. A lane's interval is therefore taken from the register only where its
//! slab ends grown by the margin are all numbers (then so is every value before them) and it starts
//! after zero; it is dropped there when it is empty. Every other lane (a NaN somewhere, a start at
//! zero of either sign, a ray parallel to an axis) is left to the shape's own test. So the intervals
//! are the test's own, bit for bit, and a query through the list traces exactly what it traced
//! shape by shape.

use super::Scene;
use crate::math::Ray;
use crate::trace::TOLERANCE_ULPS;
use glam::{Vec3A, Vec4};

/// Shapes of a scene in increasing index order, with their boxes four per SIMD lane: what a ray
/// tests when it can meet no other shape ([`Scene::intersect_among`]).
#[derive(Clone, Debug, Default)]
pub struct ShapeList {
    indices: Vec<u32>,
    /// Per four shapes, `[lo, hi]` per axis, one shape per lane (unused lanes hold empty boxes).
    boxes: Vec<[[Vec4; 3]; 2]>,
}

impl ShapeList {
    /// The list of `scene`'s shapes `indices` (increasing).
    pub fn new(scene: &Scene, indices: &[u32]) -> Self {
        let mut list = Self::default();
        list.set(scene, indices.iter().copied());
        list
    }

    /// Makes this the list of `scene`'s shapes `indices` (increasing), keeping the allocations.
    pub fn set(&mut self, scene: &Scene, indices: impl IntoIterator<Item = u32>) {
        self.indices.clear();
        self.indices.extend(indices);
        debug_assert!(self.indices.windows(2).all(|w| w[0] < w[1]));
        self.boxes.clear();
        for four in self.indices.chunks(4) {
            let (mut lo, mut hi) = ([Vec4::INFINITY; 3], [Vec4::NEG_INFINITY; 3]);
            for (j, &i) in four.iter().enumerate() {
                let b = scene.shapes[i as usize].bounds;
                for a in 0..3 {
                    lo[a][j] = b.min[a];
                    hi[a][j] = b.max[a];
                }
            }
            self.boxes.push([lo, hi]);
        }
    }

    /// The shapes' indices, increasing.
    pub fn indices(&self) -> &[u32] {
        &self.indices
    }

    /// How many shapes the list holds.
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    /// Whether the list holds no shape.
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// The shapes (in list order) whose intervals along `ray` in `[0, t_max]` are non-empty, each
    /// with its interval: `(t0, t1, index)`, [`Scene::trace_interval`]'s bit for bit (module notes).
    pub(super) fn intervals<'a>(
        &'a self,
        scene: &'a Scene,
        ray: &'a Ray,
        t_max: f32,
    ) -> Intervals<'a> {
        Intervals {
            list: self,
            scene,
            ray,
            t_max,
            lanes: RayLanes::new(scene, ray),
            next: 0,
            found: (Vec4::ZERO, Vec4::ZERO, 0, 0),
        }
    }

    /// The shapes four at a time, with their boxes in lanes (unused lanes hold empty boxes).
    pub(super) fn fours(&self) -> impl Iterator<Item = (&[u32], &[[Vec4; 3]; 2])> {
        self.indices.chunks(4).zip(&self.boxes)
    }
}

/// The lanes set in a bit mask, lowest first.
#[inline]
pub(super) fn set_lanes(mut mask: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let j = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            j
        })
    })
}

/// [`ShapeList::intervals`]: the list's shapes four at a time, then the non-empty lanes one by one.
pub(super) struct Intervals<'a> {
    list: &'a ShapeList,
    scene: &'a Scene,
    ray: &'a Ray,
    t_max: f32,
    /// `None` for a ray parallel to an axis: every lane is then left to the shape's own test.
    lanes: Option<RayLanes>,
    /// The next four shapes to test.
    next: usize,
    /// The last four's [`RayLanes::intervals`], the lanes still to give out cleared from its masks.
    found: (Vec4, Vec4, u32, u32),
}

impl Iterator for Intervals<'_> {
    type Item = (f32, f32, usize);

    #[inline]
    fn next(&mut self) -> Option<Self::Item> {
        loop {
            let (t0, t1, kept, sure) = &mut self.found;
            while *kept != 0 {
                let j = kept.trailing_zeros() as usize;
                *kept &= *kept - 1;
                let i = self.list.indices[4 * (self.next - 1) + j] as usize;
                if *sure & (1 << j) != 0 {
                    return Some((t0[j], t1[j], i));
                }
                let shape = &self.scene.shapes[i];
                if let Some((t0, t1)) = self.scene.trace_interval(shape, self.ray, self.t_max) {
                    return Some((t0, t1, i));
                }
            }
            let b = self.list.boxes.get(self.next)?;
            let count = (self.list.len() - 4 * self.next).min(4);
            self.next += 1;
            self.found = match &self.lanes {
                Some(lanes) => lanes.intervals(b, self.t_max),
                None => (Vec4::ZERO, Vec4::ZERO, 0b1111, 0),
            };
            self.found.2 &= (1 << count) - 1;
        }
    }
}

/// A ray's origin, reciprocal direction and tolerance in all four lanes, per axis.
struct RayLanes {
    o: [Vec4; 3],
    inv: [Vec4; 3],
    inv_abs: [Vec4; 3],
    /// Largest coordinate magnitude of the origin, where the margins' magnitudes start.
    origin: Vec4,
    /// The tracer's tolerance floor.
    eps: Vec4,
}

impl RayLanes {
    /// `None` for a ray parallel to an axis.
    fn new(scene: &Scene, ray: &Ray) -> Option<Self> {
        let (o, d) = (Vec3A::from(ray.o), Vec3A::from(ray.d));
        if d.cmpeq(Vec3A::ZERO).any() {
            return None;
        }
        // As `Aabb::clip_with_margin` computes it.
        let inv = d.recip();
        Some(Self {
            o: o.to_array().map(Vec4::splat),
            inv: inv.to_array().map(Vec4::splat),
            inv_abs: inv.abs().to_array().map(Vec4::splat),
            origin: Vec4::splat(ray.o.abs().max_element()),
            eps: Vec4::splat(scene.trace.eps),
        })
    }

    /// The intervals `[t0, t1]` along the ray in `[0, t_max]` of boxes `[lo, hi]` grown by the
    /// margin, per lane; the lanes that may be non-empty, and those of them whose interval is sure
    /// (module notes): bit masks.
    #[inline]
    fn intervals(&self, [lo_box, hi_box]: &[[Vec4; 3]; 2], t_max: f32) -> (Vec4, Vec4, u32, u32) {
        let mut lo = [Vec4::ZERO; 3];
        let mut hi = [Vec4::ZERO; 3];
        for a in 0..3 {
            let ta = (lo_box[a] - self.o[a]) * self.inv[a];
            let tb = (hi_box[a] - self.o[a]) * self.inv[a];
            lo[a] = ta.min(tb);
            hi[a] = ta.max(tb);
        }
        let entry = Vec4::ZERO.max(lo[0].max(lo[1]).max(lo[2]));
        let exit = hi[0].min(hi[1]).min(hi[2]);
        // The margin where the ray enters the box, or passes closest to it (`TraceSettings::eps_at`).
        let magnitude = self.origin + entry.min(exit.max(Vec4::ZERO));
        let r = (self.eps)
            .max(Vec4::splat(TOLERANCE_ULPS * f32::EPSILON) * magnitude)
            .max(Vec4::splat(f32::MIN_POSITIVE));
        let grow = self.inv_abs.map(|inv| r * inv);
        let near: [Vec4; 3] = std::array::from_fn(|a| lo[a] - grow[a]);
        let far: [Vec4; 3] = std::array::from_fn(|a| hi[a] + grow[a]);
        let t0 = Vec4::ZERO.max(near[0].max(near[1]).max(near[2]));
        let t1 = Vec4::splat(t_max).min(far[0].min(far[1]).min(far[2]));
        // Where these are numbers, so is every value before them, and the reductions of the lanes
        // and of the shape's own test agree: the same values but for the sign of a zero.
        let numbers = !(near[0].is_nan_mask()
            | near[1].is_nan_mask()
            | near[2].is_nan_mask()
            | far[0].is_nan_mask()
            | far[1].is_nan_mask()
            | far[2].is_nan_mask());
        let empty = t0.cmpgt(t1) & numbers;
        // A start at zero may differ from the shape's own test in the sign of that zero.
        let sure = numbers & t0.cmpgt(Vec4::ZERO);
        (t0, t1, !empty.bitmask() & 0b1111, sure.bitmask())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::Bsdf;
    use crate::camera::Camera;
    use crate::film::Filter;
    use crate::math::Aabb;
    use crate::sampler::Sampler;
    use crate::scalar::Param3;
    use crate::scene::{IntegratorKind, Shape};
    use crate::sdf::Sdf;
    use glam::Vec3;

    /// A number of magnitude up to `scale`, now and then exactly zero, tiny or huge.
    fn coordinate(s: &mut Sampler, scale: f32) -> f32 {
        let u = s.next_1d();
        match (s.next_1d() * 16.0) as u32 {
            0 => 0.0,
            1 => (u - 0.5) * 1e-38,
            2 => (u - 0.5) * 1e-30,
            3 => (u - 0.5) * 1e30,
            _ => (u - 0.5) * 2.0 * scale,
        }
    }

    fn point(s: &mut Sampler, scale: f32) -> Vec3 {
        Vec3::new(
            coordinate(s, scale),
            coordinate(s, scale),
            coordinate(s, scale),
        )
    }

    /// Boxes of every kind a shape may have: small and large, flat, infinite on some sides, empty.
    fn random_box(s: &mut Sampler, centre: Vec3) -> Aabb {
        let c = centre + point(s, 4.0);
        let h = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 0.6;
        let mut b = Aabb::new(c - h, c + h);
        match (s.next_1d() * 10.0) as u32 {
            0 => b.min.y = f32::NEG_INFINITY,
            1 => (b.min, b.max) = (Vec3::splat(f32::NEG_INFINITY), Vec3::splat(f32::INFINITY)),
            2 => b.max.x = b.min.x,
            3 => (b.min, b.max) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            4 => b.min.z = f32::NAN,
            _ => {}
        }
        b
    }

    #[test]
    fn the_intervals_are_each_shapes_own_bit_for_bit() {
        let bsdf = Bsdf::Diffuse {
            albedo: Param3::new([0.5; 3]),
        };
        let camera = Camera::new(
            Vec3::Z * 12.0,
            Vec3::ZERO,
            Vec3::Y,
            40.0,
            8,
            8,
            Filter::Tent,
        );
        let (mut kept, mut dropped) = (0, 0);
        for (seed, centre) in [(1, Vec3::ZERO), (2, Vec3::new(1e5, -3e4, 2e4))] {
            let mut s = Sampler::new(seed, 9, 0, 0);
            let shapes = (0..23)
                .map(|i| {
                    let mut shape =
                        Shape::new(format!("s{i}"), Sdf::sphere([0.0; 3], 0.1), bsdf.clone());
                    shape.bounds = random_box(&mut s, centre);
                    shape
                })
                .collect();
            let scene = Scene::new(camera.clone(), IntegratorKind::Direct, 1, shapes, vec![]);
            let all: Vec<u32> = (0..23).collect();
            let list = ShapeList::new(&scene, &all);
            for k in 0..20_000 {
                // Rays from near the boxes or far away, some along an axis or nearly so, some
                // through a box's corner.
                let o = centre + point(&mut s, if k % 3 == 0 { 40.0 } else { 5.0 });
                let mut d = point(&mut s, 1.0);
                if k % 7 == 0 {
                    let b = scene.shapes[k % 23].bounds;
                    d = Vec3::new(b.min.x, b.max.y, b.min.z) - o;
                }
                let d = d.normalize_or(Vec3::X);
                let ray = Ray::new(o, d);
                let t_max = match k % 4 {
                    0 => f32::INFINITY,
                    _ => s.next_1d() * 20.0,
                };
                let intervals: Vec<_> = list.intervals(&scene, &ray, t_max).collect();
                assert!(intervals.windows(2).all(|w| w[0].2 < w[1].2));
                let mut listed = intervals.iter().peekable();
                for (i, shape) in scene.shapes.iter().enumerate() {
                    let own = scene.trace_interval(shape, &ray, t_max);
                    let found = listed.next_if(|e| e.2 == i).map(|&(t0, t1, _)| (t0, t1));
                    let bits =
                        |e: Option<(f32, f32)>| e.map(|(t0, t1)| (t0.to_bits(), t1.to_bits()));
                    assert_eq!(
                        bits(found),
                        bits(own),
                        "shape {i} {:?}, ray {ray:?} to {t_max}",
                        shape.bounds
                    );
                    if own.is_some() {
                        kept += 1;
                    } else {
                        dropped += 1;
                    }
                }
            }
        }
        // The test sees both sides: many boxes entered, many not.
        assert!(
            dropped > 100_000 && kept > 100_000,
            "{kept} entered, {dropped} not"
        );
    }
}
