use super::Ray;
use glam::Vec3;

/// An axis-aligned box in `f32`, in scene units. An empty box has `min > max`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Aabb {
    /// The largest coordinate magnitude of the box's corners (infinite for unbounded boxes): where the
    /// tracer's local tolerance is taken for the box ([`crate::trace::TraceSettings::eps_at`]).
    pub fn magnitude(&self) -> f32 {
        self.min.abs().max(self.max.abs()).max_element()
    }

    /// The box with corners `min` and `max`.
    #[inline]
    pub fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }
    /// The empty box (identity of [`Aabb::union`]).
    pub const EMPTY: Self = Self {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };
    /// The whole space (for unbounded shapes such as planes).
    pub const INFINITE: Self = Self {
        min: Vec3::splat(f32::NEG_INFINITY),
        max: Vec3::splat(f32::INFINITY),
    };
    /// A cube of half-width `r` around `c`.
    #[inline]
    pub fn around(c: Vec3, r: Vec3) -> Self {
        Self::new(c - r, c + r)
    }
    /// Smallest box holding both.
    #[inline]
    pub fn union(&self, o: &Self) -> Self {
        Self::new(self.min.min(o.min), self.max.max(o.max))
    }
    /// Largest box inside both (possibly empty).
    #[inline]
    pub fn intersection(&self, o: &Self) -> Self {
        Self::new(self.min.max(o.min), self.max.min(o.max))
    }
    /// Grown by `r` on every side.
    #[inline]
    pub fn expanded(&self, r: f32) -> Self {
        Self::new(self.min - Vec3::splat(r), self.max + Vec3::splat(r))
    }
    /// True if the box holds no point.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }
    /// True if every bound is finite.
    #[inline]
    pub fn is_finite(&self) -> bool {
        self.min.is_finite() && self.max.is_finite()
    }
    /// The eight corners of the box; corner `i` takes the upper bound along x, y, z when bit 0, 1, 2 of
    /// `i` is set.
    pub fn corners(&self) -> [Vec3; 8] {
        std::array::from_fn(|i| {
            let pick = |bit: usize, k: usize| {
                if i & bit == 0 {
                    self.min[k]
                } else {
                    self.max[k]
                }
            };
            Vec3::new(pick(1, 0), pick(2, 1), pick(4, 2))
        })
    }
    /// The eight octants of the box (split at its centre); octant `i` takes the upper half along x, y, z
    /// when bit 0, 1, 2 of `i` is set.
    pub fn octants(&self) -> [Aabb; 8] {
        let c = self.center();
        std::array::from_fn(|i| {
            let pick = |bit: usize, k: usize| {
                if i & bit == 0 {
                    (self.min[k], c[k])
                } else {
                    (c[k], self.max[k])
                }
            };
            let (x0, x1) = pick(1, 0);
            let (y0, y1) = pick(2, 1);
            let (z0, z1) = pick(4, 2);
            Aabb::new(Vec3::new(x0, y0, z0), Vec3::new(x1, y1, z1))
        })
    }
    /// Centre of the box.
    #[inline]
    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }
    /// Edge lengths.
    #[inline]
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }
    /// True if `p` lies inside or on the box.
    #[inline]
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }
    /// The parameter interval `[t0, t1]` of `ray` inside the box, clipped to `[t_min, t_max]`, if any.
    /// Robust to zero direction components (IEEE infinities).
    #[inline]
    pub fn clip(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<(f32, f32)> {
        let inv = ray.d.recip();
        let ta = (self.min - ray.o) * inv;
        let tb = (self.max - ray.o) * inv;
        let lo = ta.min(tb);
        let hi = ta.max(tb);
        // NaN (0 * inf, ray in a face plane) must not shrink the interval: max/min ignore NaN in glam? No,
        // so compare explicitly.
        let mut t0 = t_min;
        let mut t1 = t_max;
        for i in 0..3 {
            if lo[i] > t0 {
                t0 = lo[i];
            }
            if hi[i] < t1 {
                t1 = hi[i];
            }
        }
        (t0 <= t1).then_some((t0, t1))
    }

    /// As [`Aabb::clip`] for the box grown by `margin(t)` on every side, `t` the parameter where the ray
    /// enters the box itself (`t_min` if it starts inside): one slab test for both.
    #[inline]
    pub fn clip_with_margin(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        margin: impl FnOnce(f32) -> f32,
    ) -> Option<(f32, f32)> {
        // Branch-free (this runs for every shape on every ray): lanes of axes the ray is parallel to
        // are masked out of the slab tests (they do not bound it; their arithmetic is NaN or infinite,
        // e.g. a ray in a face's plane) and tested against the grown slab directly. In SIMD lanes
        // (`Vec3A`): the same IEEE operations lane by lane as in `Vec3`, so the same interval but for
        // the sign of a zero end.
        use glam::Vec3A;
        let (o, d) = (Vec3A::from(ray.o), Vec3A::from(ray.d));
        let (min, max) = (Vec3A::from(self.min), Vec3A::from(self.max));
        let inv = d.recip();
        let parallel = d.cmpeq(Vec3A::ZERO);
        let ta = (min - o) * inv;
        let tb = (max - o) * inv;
        let lo = Vec3A::select(parallel, Vec3A::NEG_INFINITY, ta.min(tb));
        let hi = Vec3A::select(parallel, Vec3A::INFINITY, ta.max(tb));
        let entry = t_min.max(lo.max_element());
        let exit = hi.min_element();
        // A ray that misses the box passes closest to it between leaving one slab and entering the next.
        let r = margin(entry.min(exit.max(t_min)));
        let outside = o.cmplt(min - Vec3A::splat(r)) | o.cmpgt(max + Vec3A::splat(r));
        if (parallel & outside).any() {
            return None;
        }
        let grow = Vec3A::select(parallel, Vec3A::ZERO, r * inv.abs());
        let t0 = t_min.max((lo - grow).max_element());
        let t1 = t_max.min((hi + grow).min_element());
        (t0 <= t1).then_some((t0, t1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clip_axis_aligned_and_parallel_rays() {
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let r = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
        assert_eq!(b.clip(&r, 0.0, f32::INFINITY), Some((4.0, 6.0)));
        let miss = Ray::new(Vec3::new(2.0, 0.0, -5.0), Vec3::Z);
        assert_eq!(b.clip(&miss, 0.0, f32::INFINITY), None);
        let inside = Ray::new(Vec3::ZERO, Vec3::X);
        assert_eq!(b.clip(&inside, 0.0, 10.0), Some((0.0, 1.0)));
    }

    #[test]
    fn clip_with_margin_matches_clipping_the_grown_box() {
        let b = Aabb::new(Vec3::new(-1.0, -0.5, -2.0), Vec3::new(1.0, 0.5, 2.0));
        let margin = |t: f32| 0.01 * (1.0 + t.abs());
        let mut checked = 0;
        for i in 0..400 {
            let f = i as f32;
            let o = Vec3::new(
                (f * 0.37).sin() * 4.0,
                (f * 0.11).cos() * 3.0,
                (f * 0.23).sin() * 5.0,
            );
            // Every tenth ray is parallel to an axis, some of them in a face's plane or just outside it.
            let d = match i % 10 {
                0 => Vec3::X,
                1 => Vec3::NEG_Y,
                // Aimed at a point inside the box grown by a quarter: most rays hit it.
                _ => {
                    (Vec3::new((f * 0.71).cos(), (f * 0.53).sin(), (f * 0.29).cos()) * b.max * 1.25
                        - o)
                        .normalize()
                }
            };
            let o = if i % 20 == 0 {
                Vec3::new(o.x, 0.5, o.z)
            } else {
                o
            };
            let o = if i % 20 == 10 {
                Vec3::new(o.x, 0.505, o.z)
            } else {
                o
            };
            let ray = Ray::new(o, d);
            let entry = b.clip(&ray, 0.0, 100.0).map(|(t0, _)| t0);
            let got = b.clip_with_margin(&ray, 0.0, 100.0, margin);
            if let Some(t) = entry {
                let want = b.expanded(margin(t)).clip(&ray, 0.0, 100.0);
                let (g, w) = (got.unwrap(), want.unwrap());
                assert!(
                    (g.0 - w.0).abs() < 1e-5 && (g.1 - w.1).abs() < 1e-5,
                    "ray {i}: {g:?} vs {w:?}"
                );
                checked += 1;
            } else if let Some((t0, t1)) = got {
                // Missing the box itself: only a sliver of a box grown by about the margin may remain.
                let grown = b.expanded(margin(t1) * 2.0);
                assert!(grown.contains(ray.at(0.5 * (t0 + t1))), "ray {i}");
            }
        }
        assert!(checked > 100);
    }

    #[test]
    fn octants_tile_the_box_by_index_bits() {
        let b = Aabb::new(Vec3::new(0.0, -2.0, 4.0), Vec3::new(2.0, 2.0, 8.0));
        let o = b.octants();
        assert_eq!(o[0], Aabb::new(b.min, b.center()));
        assert_eq!(o[7], Aabb::new(b.center(), b.max));
        assert_eq!(
            o[0b101],
            Aabb::new(Vec3::new(1.0, -2.0, 6.0), Vec3::new(2.0, 0.0, 8.0))
        );
        let volume = |a: &Aabb| a.extent().x * a.extent().y * a.extent().z;
        assert_eq!(o.iter().map(volume).sum::<f32>(), volume(&b));
    }
}
