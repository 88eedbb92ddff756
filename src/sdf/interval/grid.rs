//! Certified enclosures of a grid node over a box.
//!
//! Over a box spanning several cells the spline is enclosed by its control points (B-splines are convex
//! combinations of them; the partial `∂_a φ` likewise of the differences `(c_{i+1} − c_i)/h_a`, see
//! `sdf/grid.rs`): loose, a few cells wide. A box touching at most 3 cells per axis is also bounded cell by
//! cell by the Bernstein coefficients of each cell's tricubic over the part of the box in it (blossoming;
//! computed in `f64` with a rigorous rounding margin), which converge as `O(w²)` in the box width `w`; the
//! pieces are hulled and intersected with the control-point bound.

use crate::math::Vec3;
use crate::scalar::Scalar;
use crate::scalar::interval::{Enclose, Enclosure, Interval, round_down as dn, round_up as up};
use crate::sdf::GridData;

/// The grid node's formula for set-valued scalars ([`grid_enclosure`]); the arguments are the point's
/// coordinates.
pub(in crate::sdf) struct GridEnclosure<'a> {
    /// The samples.
    pub data: &'a GridData,
    /// The grid box's lower corner.
    pub bmin: glam::Vec3,
    /// The grid box's upper corner.
    pub bmax: glam::Vec3,
}

impl Enclose<3> for GridEnclosure<'_> {
    #[inline]
    fn enclose<E: Enclosure>(&self, [x, y, z]: [E; 3]) -> E {
        grid_enclosure(self.data, self.bmin, self.bmax, Vec3::new(x, y, z))
    }
}

/// The control point at extended lattice index `(x, y, z)` (each in `−1..=n`), in `f64`: ghost layers by
/// linear extrapolation as in `sdf/grid.rs` (exact in `f64` for `f32` samples of ordinary magnitude).
fn ext64(data: &GridData, x: isize, y: isize, z: isize) -> f64 {
    let [nx, ny, nz] = data.dims.map(|n| n as isize);
    let fold = |i: isize, n: isize| -> Option<(isize, isize)> {
        if i < 0 {
            Some((0, 1))
        } else if i >= n {
            Some((n - 1, n - 2))
        } else {
            None
        }
    };
    if let Some((a, b)) = fold(x, nx) {
        return 2.0 * ext64(data, a, y, z) - ext64(data, b, y, z);
    }
    if let Some((a, b)) = fold(y, ny) {
        return 2.0 * ext64(data, x, a, z) - ext64(data, x, b, z);
    }
    if let Some((a, b)) = fold(z, nz) {
        return 2.0 * ext64(data, x, y, a) - ext64(data, x, y, b);
    }
    data.values[((z * ny + y) * nx + x) as usize] as f64
}

/// Enclosure of a grid node over the box `p` (module notes): `φ = spline(clamp(p)) + |p − clamp(p)|`,
/// valid inside and outside the grid box, with `p − clamp(p) = max(p − bmax, 0) + min(p − bmin, 0)` (exactly
/// 0 where the box is certainly inside, so the distance term adds nothing there).
pub(super) fn grid_enclosure<E: Enclosure>(
    data: &GridData,
    bmin: glam::Vec3,
    bmax: glam::Vec3,
    p: Vec3<E>,
) -> E {
    if !data.usable() {
        return E::constant(f32::INFINITY);
    }
    let q = Vec3::new(
        p.x.clamp(bmin.x, bmax.x),
        p.y.clamp(bmin.y, bmax.y),
        p.z.clamp(bmin.z, bmax.z),
    );
    let off = |c: E, lo: f32, hi: f32| (c - hi).max(E::zero()) + (c - lo).min(E::zero());
    let d = Vec3::new(
        off(p.x, bmin.x, bmax.x),
        off(p.y, bmin.y, bmax.y),
        off(p.z, bmin.z, bmax.z),
    );
    spline_enclosure(data, bmin, bmax, q) + d.length()
}

/// Enclosure of the B-spline over the box `q` (inside the grid box): the control-point hull, intersected
/// with the per-cell Bernstein bounds when the box touches at most [`MAX_CELL_PIECES`] cells (module notes).
fn spline_enclosure<E: Enclosure>(
    data: &GridData,
    bmin: glam::Vec3,
    bmax: glam::Vec3,
    q: Vec3<E>,
) -> E {
    let ext = bmax - bmin;
    let qs = [q.x, q.y, q.z];
    // Lattice coordinate u = (q − bmin)·inv_h with the same f32 inv_h as `sdf/grid.rs`.
    let mut inv_h = [0.0f32; 3];
    let mut cells = [(0isize, 0isize); 3];
    for a in 0..3 {
        let n = data.dims[a];
        inv_h[a] = if ext[a] > 0.0 {
            (n - 1) as f32 / ext[a]
        } else {
            0.0
        };
        let u = (qs[a].value() - Interval::constant(bmin[a])) * Interval::constant(inv_h[a]);
        let cell = |x: f64| {
            if x.is_nan() {
                0
            } else {
                (x.floor().clamp(0.0, (n - 2) as f64)) as isize
            }
        };
        cells[a] = (cell(u.lo), cell(u.hi));
    }
    // Control points (and their differences) of every cell the box touches: taps i − 1 ..= i + 2.
    let lo = cells.map(|c| c.0 - 1);
    let hi = cells.map(|c| c.1 + 2);
    let size = [0, 1, 2].map(|a| (hi[a] - lo[a] + 1) as usize);
    let mut block = Vec::with_capacity(size[0] * size[1] * size[2]);
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                block.push(ext64(data, x, y, z));
            }
        }
    }
    let at = |x: usize, y: usize, z: usize| block[(z * size[1] + y) * size[0] + x];
    let (mut vmin, mut vmax) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut dmin = [f64::INFINITY; 3];
    let mut dmax = [f64::NEG_INFINITY; 3];
    for z in 0..size[2] {
        for y in 0..size[1] {
            for x in 0..size[0] {
                let c = at(x, y, z);
                vmin = vmin.min(c);
                vmax = vmax.max(c);
                if !E::GRADIENT {
                    // A plain interval's enclosure ignores the partials.
                    continue;
                }
                let step = [(x + 1, y, z), (x, y + 1, z), (x, y, z + 1)];
                for (a, &(i, j, k)) in step.iter().enumerate() {
                    if i < size[0] && j < size[1] && k < size[2] {
                        let dlt = at(i, j, k) - c;
                        dmin[a] = dmin[a].min(dlt);
                        dmax[a] = dmax[a].max(dlt);
                    }
                }
            }
        }
    }
    // Ghost points and differences are exact in f64 up to a few ulps: grow by a relative hair.
    let value = Interval::new(vmin, vmax).inflate(1e-12, 0.0);
    let partials: [Interval; 3] = std::array::from_fn(|a| {
        if E::GRADIENT {
            Interval::new(dmin[a], dmax[a]).inflate(1e-12, 0.0) * Interval::constant(inv_h[a])
        } else {
            Interval::ZERO
        }
    });
    let hull = E::compose(value, partials, q);
    let pieces: isize = cells.iter().map(|c| c.1 - c.0 + 1).product();
    if pieces > MAX_CELL_PIECES {
        return hull;
    }
    // Each cell the box touches: the Bernstein form of the cell's tricubic over the part of the box in the
    // cell, whose coefficients bound the value and, differenced, the partials (convergence O(w²) in the
    // box width w, where the control-point hull stays a few cells wide).
    // The rows of each axis's cells (at most 3 per axis), computed once for all the cells they meet.
    let axis_rows: [Vec<_>; 3] = std::array::from_fn(|a| {
        (cells[a].0..=cells[a].1)
            .map(|i| {
                let t = (qs[a].value() - Interval::constant(bmin[a]))
                    * Interval::constant(inv_h[a])
                    - Interval::point(i as f64);
                let t = t.intersect(Interval::new(0.0, 1.0));
                bernstein_rows(t.lo, t.hi)
            })
            .collect()
    });
    let mut out: Option<E> = None;
    for cz in cells[2].0..=cells[2].1 {
        for cy in cells[1].0..=cells[1].1 {
            for cx in cells[0].0..=cells[0].1 {
                let cell = [cx, cy, cz];
                let rows: [_; 3] =
                    std::array::from_fn(|a| axis_rows[a][(cell[a] - cells[a].0) as usize]);
                // The cell's 4 × 4 × 4 control values (taps i − 1 ..= i + 2, at block offset i − 1 − lo).
                let o = [0, 1, 2].map(|a| (cell[a] - 1 - lo[a]) as usize);
                let mut c = [0.0f64; 64];
                let mut cmax = 0.0f64;
                for z in 0..4 {
                    for y in 0..4 {
                        for x in 0..4 {
                            let v = at(o[0] + x, o[1] + y, o[2] + z);
                            c[(z * 4 + y) * 4 + x] = v;
                            cmax = cmax.max(v.abs());
                        }
                    }
                }
                // Rounding of the f64 transform: each coefficient is a sum of 64 products of three row
                // entries and a control value, Σ|terms| ≤ 6 max|c| (value rows are convex, derivative rows
                // sum to at most 6 in absolute value), about 25 roundings deep: error ≤ 25 · 2⁻⁵³ · 6 max|c|
                // ≈ 2e-14 max|c|. The margin is 50 times that.
                let margin = 1e-12 * cmax;
                let (m, d) = (rows.map(|r| r.0), rows.map(|r| r.1));
                let z = apply::<2, 4>(&c, &m[2]);
                let zy = apply::<1, 4>(&z, &m[1]);
                let v = range(&apply::<0, 4>(&zy, &m[0]), [4, 4, 4], margin);
                let partials: [Interval; 3] = if E::GRADIENT {
                    let zx = apply::<0, 4>(&z, &m[0]);
                    let yx = apply::<0, 4>(&apply::<1, 4>(&c, &m[1]), &m[0]);
                    let d = [
                        range(&apply::<0, 3>(&zy, &d[0]), [3, 4, 4], margin),
                        range(&apply::<1, 3>(&zx, &d[1]), [4, 3, 4], margin),
                        range(&apply::<2, 3>(&yx, &d[2]), [4, 4, 3], margin),
                    ];
                    std::array::from_fn(|a| d[a] * Interval::constant(inv_h[a]))
                } else {
                    [Interval::ZERO; 3]
                };
                let piece = E::compose(v, partials, q);
                out = Some(out.map_or(piece, |p| p.hull(piece)));
            }
        }
    }
    match out {
        Some(p) => hull.intersect(p),
        None => hull,
    }
}

/// Apply the `R` rows `m` (each over 4 inputs) along axis `AXIS` of the 4 × 4 × 4 array `c` (x
/// fastest): the result has `R` entries along `AXIS` and 4 along the others, same layout. The axis and
/// the extents are constants so that the loops unroll; each entry is the same sum, in the same order,
/// as the generic loop's.
#[inline(always)]
fn apply<const AXIS: usize, const R: usize>(c: &[f64; 64], m: &[[f64; 4]; R]) -> [f64; 64] {
    let s = [1, 4, 16][AXIS];
    let extent = |a: usize| if a == AXIS { R } else { 4 };
    let mut out = [0.0; 64];
    for z in 0..extent(2) {
        for y in 0..extent(1) {
            for x in 0..extent(0) {
                let mut idx = [x, y, z];
                let row = &m[idx[AXIS]];
                idx[AXIS] = 0;
                let b = idx[0] + 4 * idx[1] + 16 * idx[2];
                out[x + 4 * y + 16 * z] = row[0] * c[b]
                    + row[1] * c[b + s]
                    + row[2] * c[b + 2 * s]
                    + row[3] * c[b + 3 * s];
            }
        }
    }
    out
}

/// `[min − margin, max + margin]` over the used extent `dims` of a 4 × 4 × 4 array (x fastest).
fn range(c: &[f64; 64], dims: [usize; 3], margin: f64) -> Interval {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let v = c[x + 4 * y + 16 * z];
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
    }
    Interval::new(dn(lo - margin), up(hi + margin))
}

/// Rows of the linear maps from the four control values `d_0..d_3` of one uniform cubic B-spline segment
/// (taps `i − 1 ..= i + 2`, segment `t ∈ [0, 1]`) to the Bernstein coefficients over `[t0, t1]` of the
/// segment (4 rows) and of its derivative `d/dt` (3 rows), by blossoming (de Boor's algorithm with distinct
/// arguments; Ramshaw, "Blossoms are polar forms", 1989): `b_m = P(t0^{3−m}, t1^m)` and
/// `b'_m = 3 (P(t0^{2−m}, t1^m, 1) − P(t0^{2−m}, t1^m, 0))`. For `t0, t1 ∈ [0, 1]` every de Boor weight
/// lies in `[0, 1]`: value rows are convex (entries ≥ 0, sum 1), derivative rows sum to at most 6 in
/// absolute value (the rounding margin in `spline_enclosure` relies on it).
#[allow(clippy::type_complexity)]
fn bernstein_rows(t0: f64, t1: f64) -> ([[f64; 4]; 4], [[f64; 4]; 3]) {
    // The segment's knots are −2 … 3 and d_j is the blossom P(j − 2, j − 1, j).
    type Lin = [f64; 4];
    let comb = |wa: f64, a: &Lin, wb: f64, b: &Lin, div: f64| -> Lin {
        std::array::from_fn(|k| (wa * a[k] + wb * b[k]) / div)
    };
    // (P(s1, s2, 0), P(s1, s2, 1)) as rows over d_0..d_3.
    let two = |s1: f64, s2: f64| -> (Lin, Lin) {
        let d: [Lin; 4] = std::array::from_fn(|j| {
            let mut e = [0.0; 4];
            e[j] = 1.0;
            e
        });
        let d1: [Lin; 3] = std::array::from_fn(|i| {
            let j = (i + 1) as f64;
            comb(j - s1, &d[i], s1 - (j - 3.0), &d[i + 1], 3.0)
        });
        let d2: [Lin; 2] = std::array::from_fn(|i| {
            let j = (i + 2) as f64;
            comb(j - 1.0 - s2, &d1[i], s2 - (j - 3.0), &d1[i + 1], 2.0)
        });
        (d2[0], d2[1])
    };
    let eval3 = |s1: f64, s2: f64, s3: f64| -> Lin {
        let (p0, p1) = two(s1, s2);
        std::array::from_fn(|k| (1.0 - s3) * p0[k] + s3 * p1[k])
    };
    let deriv = |s1: f64, s2: f64| -> Lin {
        let (p0, p1) = two(s1, s2);
        std::array::from_fn(|k| 3.0 * (p1[k] - p0[k]))
    };
    (
        [
            eval3(t0, t0, t0),
            eval3(t0, t0, t1),
            eval3(t0, t1, t1),
            eval3(t1, t1, t1),
        ],
        [deriv(t0, t0), deriv(t0, t1), deriv(t1, t1)],
    )
}

/// Most cells a box may touch for [`spline_enclosure`] to bound each cell's polynomial (3 per axis).
const MAX_CELL_PIECES: isize = 27;
