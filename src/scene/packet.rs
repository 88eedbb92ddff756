//! Camera rays eight at a time: the first hits of a packet of rays in the lanes of SIMD registers
//! ([`wide::f32x8`]: two SSE or NEON registers in a default build, one AVX register in a build for a
//! CPU that has it), with each lane's answer the scalar query's, bit for bit.
//!
//! [`Scene::intersect_packet`] does, lane by lane, what [`Scene::intersect_among`] and
//! [`Scene::intersect_resolving`] do for one ray: the nearest finite emitter (one ray at a time),
//! then every shape's interval along the ray (its bounds grown by the tracer's margin, as
//! [`super::shape_list`] computes them for four boxes of one ray, here for eight rays of one box;
//! lanes whose interval the registers cannot vouch for take the shape's own test), then the closed
//! form of the shapes that have one in lanes (spheres, boxes and cylinders with rounded edges,
//! planes, similarity transforms of these: the rays mapped into the child's frame by
//! [`crate::sdf::Similarity::to_child_ray_lanes`]), with the tracer's own arithmetic in the same
//! order, so each lane's crossing is the scalar crossing's bits.
//!
//! The scalar tracer takes a closed form only where it is certain ([`crate::trace::first_crossing`]):
//! the crossing is exact (not on a rounded edge), not within a tolerance of where the ray enters the
//! bounds (there it evaluates the field to tell the side), the two crossings of a pair farther apart
//! than the tracer resolves, the ray outside the solid at its start. Where any of these fails, or the
//! shape has no closed form in lanes (grids, CSG, transforms of those), or the arithmetic gave a NaN
//! or an infinity, the lane *falls back*: it is answered by the scalar query, whole. The others keep the
//! nearest crossing. The scalar query traces shapes in the order the ray enters their bounds and the
//! packet in index order; both keep the nearest crossing, so they agree but on a tie between two
//! shapes at the very same parameter (which the order decides), and a lane with such a tie falls back
//! too. So every lane's intersection is the scalar query's, bit for bit, and the packet only saves
//! the scalar query's per-ray overhead where the answer is certain.

use super::query::Nearest;
use super::shape_list::ShapeList;
use super::{Intersection, Scene, Surface};
use crate::math::{Aabb, Ray};
use crate::sdf::Sdf;
use crate::trace::{MAX_CREEP, TOLERANCE_ULPS};
use wide::f32x8;

/// Rays per packet.
pub const LANES: usize = 8;

/// Fewest rays worth a packet: below, the lanes left empty cost more than they save (a whole render
/// of the default scene at 1,024×1,024: 1.24× the CPU time of tracing one by one at 1 sample per
/// pixel, 1.00× at 3, 0.81× at 8 per packet).
pub const MIN_RAYS: usize = 3;

/// All eight lanes' bits.
const ALL: u32 = (1 << LANES) - 1;

/// Eight rays, per axis.
struct RayLanes {
    o: [f32x8; 3],
    d: [f32x8; 3],
    inv: [f32x8; 3],
    inv_abs: [f32x8; 3],
    /// Largest coordinate magnitude of each origin (where the margins' magnitudes start).
    origin: f32x8,
    /// Each ray's footprint growth ([`crate::trace::TraceSettings::spread`]).
    spread: f32x8,
}

impl RayLanes {
    fn new(rays: &[Ray; LANES], spreads: &[f32; LANES]) -> Self {
        let o = [0, 1, 2].map(|a| f32x8::new(std::array::from_fn(|k| rays[k].o[a])));
        let d = [0, 1, 2].map(|a| f32x8::new(std::array::from_fn(|k| rays[k].d[a])));
        // As `Aabb::clip_with_margin` computes it (`Vec3A::recip`).
        let inv = d.map(|d| f32x8::ONE / d);
        Self {
            o,
            d,
            inv,
            inv_abs: inv.map(f32x8::abs),
            origin: f32x8::new(std::array::from_fn(|k| rays[k].o.abs().max_element())),
            spread: f32x8::new(*spreads),
        }
    }

    /// The intervals `[t0, t1]` in `[0, t_max]` of `bounds` grown by the scene's margin, per lane
    /// ([`super::shape_list`]'s arithmetic); the lanes that may be non-empty, and those of them whose
    /// interval is sure: bit masks.
    fn intervals(&self, bounds: &Aabb, eps: f32, t_max: f32x8) -> (f32x8, f32x8, u32, u32) {
        let (mut lo, mut hi) = ([f32x8::ZERO; 3], [f32x8::ZERO; 3]);
        for a in 0..3 {
            let ta = (f32x8::splat(bounds.min[a]) - self.o[a]) * self.inv[a];
            let tb = (f32x8::splat(bounds.max[a]) - self.o[a]) * self.inv[a];
            lo[a] = ta.min(tb);
            hi[a] = ta.max(tb);
        }
        let entry = f32x8::ZERO.max(lo[0].max(lo[1]).max(lo[2]));
        let exit = hi[0].min(hi[1]).min(hi[2]);
        let magnitude = self.origin + entry.min(exit.max(f32x8::ZERO));
        let r = f32x8::splat(eps)
            .max(f32x8::splat(TOLERANCE_ULPS * f32::EPSILON) * magnitude)
            .max(f32x8::splat(f32::MIN_POSITIVE));
        let near: [f32x8; 3] = std::array::from_fn(|a| lo[a] - r * self.inv_abs[a]);
        let far: [f32x8; 3] = std::array::from_fn(|a| hi[a] + r * self.inv_abs[a]);
        let t0 = f32x8::ZERO.max(near[0].max(near[1]).max(near[2]));
        let t1 = t_max.min(far[0].min(far[1]).min(far[2]));
        let nan = near[0].is_nan()
            | near[1].is_nan()
            | near[2].is_nan()
            | far[0].is_nan()
            | far[1].is_nan()
            | far[2].is_nan();
        let numbers = !nan.to_bitmask() & ALL;
        let empty = t0.simd_gt(t1).to_bitmask() & numbers;
        // A start at zero may differ from the shape's own test in the sign of that zero.
        let sure = numbers & t0.simd_gt(f32x8::ZERO).to_bitmask();
        (t0, t1, !empty & ALL, sure)
    }
}

/// A whole line's crossings with a surface in lanes ([`crate::sdf::line_crossings`]'s values).
struct LaneCrossings {
    /// The first crossing and the second (where there are two).
    t: [f32x8; 2],
    /// Lanes with at least one crossing, with two.
    some: u32,
    two: u32,
    /// Lanes whose first crossing is exact (see [`crate::sdf::line_crossings::LineCrossings`]).
    exact_first: u32,
    /// Lanes where the line is inside the solid before its first crossing.
    inside_before: u32,
    /// Lanes where the scalar `line_crossings` gives no answer (a NaN or an infinity).
    invalid: u32,
}

/// `x.copysign(s)` lane by lane.
fn copysign(x: f32x8, s: f32x8) -> f32x8 {
    let sign = f32x8::splat(-0.0);
    x.abs() | (s & sign)
}

/// `a · b` as `glam::Vec3::dot` sums it.
fn dot(a: &[f32x8; 3], b: &[f32x8; 3]) -> f32x8 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The lanes where `x` is finite, as bits.
fn finite(x: f32x8) -> u32 {
    x.is_finite().to_bitmask()
}

impl LaneCrossings {
    /// Whether [`LaneCrossings::of`] answers for `sdf`.
    fn exists(sdf: &Sdf) -> bool {
        match sdf {
            Sdf::Named { child, .. } => Self::exists(child),
            Sdf::Transform { child, .. } => Self::exists(child),
            Sdf::Sphere { .. } | Sdf::Box { .. } | Sdf::Plane { .. } | Sdf::Cylinder { .. } => true,
            _ => false,
        }
    }

    /// The crossings of the lines `o + t d` (in the node's frame) with `sdf`, or `None` where the node
    /// has no closed form in lanes.
    fn of(sdf: &Sdf, o: &[f32x8; 3], d: &[f32x8; 3]) -> Option<Self> {
        match sdf {
            Sdf::Named { child, .. } => Self::of(child, o, d),
            Sdf::Sphere { center, radius } => {
                let c = center.value();
                let f = [o[0] - c.x, o[1] - c.y, o[2] - c.z];
                Some(Self::ball(&f, d, radius.value))
            }
            Sdf::Box {
                center,
                half_size,
                rounding,
            } => {
                let c = center.value();
                let q = [o[0] - c.x, o[1] - c.y, o[2] - c.z];
                Some(Self::cuboid(&q, d, half_size.value(), rounding.value))
            }
            Sdf::Cylinder {
                center,
                axis,
                radius,
                half_height,
                rounding,
            } => {
                let c = center.value();
                let f = [o[0] - c.x, o[1] - c.y, o[2] - c.z];
                Some(Self::cylinder(
                    &f,
                    d,
                    *axis,
                    [radius.value, half_height.value],
                    rounding.value,
                ))
            }
            Sdf::Transform { .. } => {
                let (frame, child) = sdf.frame()?;
                let (o, d) = frame.to_child_ray_lanes(*o, *d);
                Self::of(child, &o, &d)
            }
            Sdf::Plane { normal, offset } => {
                let n = [normal.x, normal.y, normal.z].map(f32x8::splat);
                let height = dot(&n, o) - f32x8::splat(offset.value);
                let slope = dot(&n, d);
                let t = -height / slope;
                let some = finite(t);
                Some(Self {
                    t: [t, t],
                    some,
                    two: 0,
                    exact_first: ALL,
                    inside_before: slope.simd_gt(f32x8::ZERO).to_bitmask() & some,
                    invalid: 0,
                })
            }
            _ => None,
        }
    }

    /// `ball_roots` of `line_crossings`, lane by lane: the roots, the lanes where they exist (the
    /// line crosses), and those where the scalar function gives no answer (`h²` not a number).
    fn ball_roots(f: &[f32x8; 3], d: &[f32x8; 3], r: f32) -> ([f32x8; 2], u32, u32) {
        let r = f32x8::splat(r);
        let a = dot(d, d);
        let b = -dot(f, d);
        let ba = b / a;
        let v = [f[0] + ba * d[0], f[1] + ba * d[1], f[2] + ba * d[2]];
        let v_len = dot(&v, &v).sqrt();
        let h2 = (r - v_len) * (r + v_len) / a;
        let nan = h2.is_nan().to_bitmask();
        let hit = h2.simd_gt(f32x8::ZERO).to_bitmask() & !nan;
        let q = ba + copysign(h2.sqrt(), b);
        let f_len = dot(f, f).sqrt();
        let c = (f_len - r) * (f_len + r);
        let (near, far) = (c / (a * q), q);
        ([near.min(far), near.max(far)], hit, nan)
    }

    /// A sphere's crossings (`line_crossings`), lane by lane.
    fn ball(f: &[f32x8; 3], d: &[f32x8; 3], r: f32) -> Self {
        let (t, hit, nan) = Self::ball_roots(f, d, r);
        let invalid = nan | (hit & !(finite(t[0]) & finite(t[1])));
        Self {
            t,
            some: hit,
            two: hit,
            exact_first: ALL,
            inside_before: 0,
            invalid,
        }
    }

    /// `cylinder_crossings` of `line_crossings`, lane by lane (`f` from the centre, unit `axis`,
    /// `[radius, half height]`). The lanes where the scalar function gives no answer, and those of
    /// a line parallel to the axis (which it decides apart), are marked invalid: the scalar query
    /// answers them.
    fn cylinder(
        f: &[f32x8; 3],
        d: &[f32x8; 3],
        axis: glam::Vec3,
        [r, half]: [f32; 2],
        rounding: f32,
    ) -> Self {
        let k = [axis.x, axis.y, axis.z].map(f32x8::splat);
        let (h0, dh) = (dot(f, &k), dot(d, &k));
        let rf: [f32x8; 3] = std::array::from_fn(|a| f[a] - h0 * k[a]);
        let rd: [f32x8; 3] = std::array::from_fn(|a| d[a] - dh * k[a]);
        let half_x = f32x8::splat(half);
        let (ta, tb) = ((-half_x - h0) / dh, (half_x - h0) / dh);
        let caps_nan = (ta.is_nan() | tb.is_nan()).to_bitmask();
        let (cap_in, cap_out) = (ta.min(tb), ta.max(tb));
        let parallel =
            (rd[0].simd_eq(f32x8::ZERO) & rd[1].simd_eq(f32x8::ZERO) & rd[2].simd_eq(f32x8::ZERO))
                .to_bitmask();
        let ([side_in, side_out], side_hit, side_nan) = Self::ball_roots(&rf, &rd, r);
        let (t_in, t_out) = (cap_in.max(side_in), cap_out.min(side_out));
        let hit = side_hit & t_in.simd_lt(t_out).to_bitmask();
        // Exact on a cap within its flat part, or on the side within its straight part.
        let on_cap = cap_in.simd_ge(side_in).to_bitmask();
        let p: [f32x8; 3] = std::array::from_fn(|a| rf[a] + t_in * rd[a]);
        let flat_cap = dot(&p, &p)
            .sqrt()
            .simd_le(f32x8::splat(r - rounding))
            .to_bitmask();
        let straight_side = (h0 + t_in * dh)
            .abs()
            .simd_le(f32x8::splat(half - rounding))
            .to_bitmask();
        let exact_first = (on_cap & flat_cap) | (!on_cap & straight_side);
        let invalid = caps_nan | parallel | side_nan | (hit & !(finite(t_in) & finite(t_out)));
        Self {
            t: [t_in, t_out],
            some: hit & !invalid,
            two: hit & !invalid,
            exact_first,
            inside_before: 0,
            invalid,
        }
    }

    /// `box_crossings` of `line_crossings`, lane by lane.
    fn cuboid(q: &[f32x8; 3], d: &[f32x8; 3], half: glam::Vec3, rounding: f32) -> Self {
        let inv = d.map(|d| f32x8::ONE / d);
        let half = [half.x, half.y, half.z].map(f32x8::splat);
        let ta: [f32x8; 3] = std::array::from_fn(|a| (-half[a] - q[a]) * inv[a]);
        let tb: [f32x8; 3] = std::array::from_fn(|a| (half[a] - q[a]) * inv[a]);
        let nan = (0..3).fold(0, |m, a| m | (ta[a].is_nan() | tb[a].is_nan()).to_bitmask());
        let lo: [f32x8; 3] = std::array::from_fn(|a| ta[a].min(tb[a]));
        let hi: [f32x8; 3] = std::array::from_fn(|a| ta[a].max(tb[a]));
        let t_in = lo[0].max(lo[1]).max(lo[2]);
        let t_out = hi[0].min(hi[1]).min(hi[2]);
        let hit = t_in.simd_lt(t_out).to_bitmask() & !nan;
        // The face is the first axis whose slab gave the crossing; the point lies within the flat
        // part of every other axis's extent.
        let inner: [f32x8; 3] = std::array::from_fn(|a| half[a] - f32x8::splat(rounding));
        let face_x = lo[0].simd_eq(t_in).to_bitmask();
        let face_y = !face_x & lo[1].simd_eq(t_in).to_bitmask();
        let face_z = !face_x & !face_y & lo[2].simd_eq(t_in).to_bitmask();
        let face = [ALL & !face_y & !face_z, face_y, face_z];
        let flat = (0..3).fold(ALL, |m, a| {
            let within = (q[a] + t_in * d[a]).abs().simd_le(inner[a]).to_bitmask();
            m & (within | face[a])
        });
        let invalid = nan | (hit & !(finite(t_in) & finite(t_out)));
        Self {
            t: [t_in, t_out],
            some: hit,
            two: hit,
            exact_first: flat,
            inside_before: 0,
            invalid,
        }
    }
}

/// `TraceSettings::eps_along` lane by lane, for tolerance floor `eps`.
fn eps_along(eps: f32, spread: f32x8, origin_magnitude: f32x8, t: f32x8) -> f32x8 {
    let magnitude = origin_magnitude + t.abs();
    let footprint = spread * t.abs();
    let ulps = f32x8::splat(TOLERANCE_ULPS * f32::EPSILON) * magnitude;
    let min = f32x8::splat(f32::MIN_POSITIVE);
    let small = footprint.simd_lt(f32x8::splat(eps));
    let floor = small.select(footprint, f32x8::splat(eps));
    floor.max(ulps).max(min)
}

/// One shape's first crossings along the lanes' rays within their intervals, from the closed form
/// ([`Scene::lane_first_crossings`]).
struct FirstCrossings {
    /// The first crossing after the interval's start, where `reached`.
    first: f32x8,
    /// Lanes whose first crossing is certain and lies within the interval (`≤ t1`).
    reached: u32,
    /// Lanes the scalar tracer would not answer from the closed form (it would march).
    uncertain: u32,
}

impl Scene {
    /// Shape `shape`'s intervals along the lanes' rays in `[0, t_max]`, as [`Scene::trace_interval`]
    /// gives them bit for bit (the lanes the registers cannot vouch for take that test, except those
    /// of `skip`): `(t0, t1, lanes that are non-empty)`.
    fn lane_intervals(
        &self,
        shape: &super::Shape,
        lanes: &RayLanes,
        rays: &[Ray; LANES],
        t_max: f32x8,
        t_max_each: &[f32; LANES],
        skip: u32,
    ) -> (f32x8, f32x8, u32) {
        let (mut t0, mut t1, mut open, sure) =
            lanes.intervals(&shape.bounds, self.trace.eps, t_max);
        let unsure = open & !sure & !skip;
        if unsure != 0 {
            let (mut a0, mut a1) = (t0.to_array(), t1.to_array());
            for k in (0..LANES).filter(|k| unsure & (1 << k) != 0) {
                match self.trace_interval(shape, &rays[k], t_max_each[k]) {
                    Some((s0, s1)) => (a0[k], a1[k]) = (s0, s1),
                    None => open &= !(1 << k),
                }
            }
            (t0, t1) = (f32x8::new(a0), f32x8::new(a1));
        }
        (t0, t1, open & !skip)
    }

    /// The first crossings of `shape` along the lanes' rays in `[t0, t1]` as the scalar tracer's
    /// closed form finds them (`crate::trace::first_crossing_skipping`), or `None` when the shape has
    /// no closed form in lanes.
    fn lane_first_crossings(
        &self,
        shape: &super::Shape,
        lanes: &RayLanes,
        t0: f32x8,
        t1: f32x8,
    ) -> Option<FirstCrossings> {
        let t = shape.translate.value();
        let o = [lanes.o[0] - t.x, lanes.o[1] - t.y, lanes.o[2] - t.z];
        let line = LaneCrossings::of(&shape.sdf, &o, &lanes.d)?;
        let origin = o[0].abs().max(o[1].abs()).max(o[2].abs());
        let eps = self.shape_trace(shape).eps;
        let [first, second] = line.t;
        let apart = eps_along(eps, lanes.spread, origin, first.abs().max(second.abs()));
        let close_pair = line.two
            & (second - first)
                .simd_lt(f32x8::splat(2.0 * MAX_CREEP) * apart)
                .to_bitmask();
        let eps0 = eps_along(eps, lanes.spread, origin, t0);
        let near_start = line.some & (first - t0).abs().simd_le(eps0).to_bitmask()
            | line.two & (second - t0).abs().simd_le(eps0).to_bitmask();
        let behind = line.some & first.simd_le(t0).to_bitmask();
        let uncertain = line.invalid
            | close_pair
            | near_start
            | behind
            | (line.some & (line.inside_before | !line.exact_first));
        let reached = line.some & !uncertain & first.simd_le(t1).to_bitmask();
        Some(FirstCrossings {
            first,
            reached,
            uncertain,
        })
    }
}

impl Scene {
    /// Whether [`Scene::intersect_packet`] does `n` camera rays' work in lanes, with the pixel's
    /// `shapes`: at least [`MIN_RAYS`] of them; not a scene whose hierarchy they would walk (no
    /// pixel list); not rays that can meet only shapes without a closed form in lanes (all but those
    /// that miss them would be answered one by one after the lanes' work). Otherwise it answers them
    /// one by one.
    pub fn packet_pays(&self, n: usize, shapes: Option<&ShapeList>) -> bool {
        let count = shapes.map_or(self.shapes.len(), ShapeList::len);
        let index = |j: usize| shapes.map_or(j, |list| list.indices()[j] as usize);
        n >= MIN_RAYS
            && (shapes.is_some() || self.hierarchy().is_none())
            && (0..count).any(|j| LaneCrossings::exists(&self.shapes[index(j)].sdf))
    }

    /// The first hits of up to [`LANES`] camera rays: `out[k]` is, bit for bit, what
    /// [`Scene::intersect_camera`] gives for `rays[k]` with footprint growth `spreads[k]` and the
    /// pixel's `shapes`. The lanes whose answer the closed forms make certain are found eight at a
    /// time, the others one by one (module notes; all of them where [`Scene::packet_pays`] says
    /// no). Returns how many lanes were answered one by one.
    ///
    /// # Panics
    ///
    /// If the three slices differ in length or hold more than [`LANES`] rays.
    pub fn intersect_packet(
        &self,
        rays: &[Ray],
        spreads: &[f32],
        shapes: Option<&ShapeList>,
        out: &mut [Intersection],
    ) -> usize {
        let n = rays.len();
        assert!(n <= LANES && spreads.len() == n && out.len() == n);
        let scalar = |k: usize| self.intersect_camera(&rays[k], spreads[k], shapes);
        if !self.packet_pays(n, shapes) {
            for (k, o) in out.iter_mut().enumerate() {
                *o = scalar(k);
            }
            return n;
        }
        // Unused lanes repeat the last ray and are never read.
        let lane_rays: [Ray; LANES] = std::array::from_fn(|k| rays[k.min(n - 1)]);
        let lane_spreads: [f32; LANES] = std::array::from_fn(|k| spreads[k.min(n - 1)]);
        let lanes = RayLanes::new(&lane_rays, &lane_spreads);
        // Unused lanes, and rays along an axis (whose slabs the registers do not test), are done
        // apart.
        let mut fallback = !((1u32 << n) - 1) & ALL;
        for d in &lanes.d {
            fallback |= d.simd_eq(f32x8::ZERO).to_bitmask();
        }
        let nearest: [Nearest; LANES] =
            std::array::from_fn(|k| self.nearest_emitter(&lane_rays[k], f32::INFINITY));
        let t_max_each = nearest.each_ref().map(|n| n.t);
        let t_max = f32x8::new(t_max_each);
        let mut best = t_max;
        let mut shape_hit = [usize::MAX; LANES];
        let count = shapes.map_or(self.shapes.len(), ShapeList::len);
        for j in 0..count {
            if fallback == ALL {
                break;
            }
            let i = shapes.map_or(j, |list| list.indices()[j] as usize);
            let shape = &self.shapes[i];
            let (t0, t1, open) =
                self.lane_intervals(shape, &lanes, &lane_rays, t_max, &t_max_each, fallback);
            // A start level with the nearest hit: the scalar query skips the shape or traces it,
            // by the order it takes.
            fallback |= open & t0.simd_eq(best).to_bitmask();
            let active = open & !fallback & t0.simd_lt(best).to_bitmask();
            if active == 0 {
                continue;
            }
            let Some(line) = self.lane_first_crossings(shape, &lanes, t0, t1) else {
                fallback |= active;
                continue;
            };
            let first = line.first;
            let tie = line.reached & first.simd_eq(best).to_bitmask();
            let uncertain = line.uncertain | tie;
            fallback |= active & uncertain;
            let take = active & !uncertain & line.reached & first.simd_lt(best).to_bitmask();
            if take != 0 {
                let mask = f32x8::new(std::array::from_fn(|k| {
                    if take & (1 << k) != 0 {
                        f32::from_bits(u32::MAX)
                    } else {
                        0.0
                    }
                }));
                best = mask.select(first, best);
                for (k, hit) in shape_hit.iter_mut().enumerate() {
                    if take & (1 << k) != 0 {
                        *hit = i;
                    }
                }
            }
        }
        let best = best.to_array();
        for k in 0..n {
            out[k] = if fallback & (1 << k) != 0 {
                scalar(k)
            } else {
                let mut found = nearest[k];
                if shape_hit[k] != usize::MAX {
                    found.t = best[k];
                    found.surface = Some(Surface::Shape(shape_hit[k]));
                }
                self.nearest_hit(&lane_rays[k], found)
            };
        }
        (fallback & ((1 << n) - 1)).count_ones() as usize
    }
}
