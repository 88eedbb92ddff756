//! Operations on a grid's control points that an optimisation needs between steps: exact refinement
//! (the same spline on a lattice twice as fine) and redistancing (control points whose spline is the
//! signed distance to the current zero set).
//!
//! **Refinement.** A uniform cubic B-spline with control points `c_i` at spacing `h` equals the one with
//! spacing `h/2` and control points `f_{2i} = (c_{i−1} + 6 c_i + c_{i+1})/8`, `f_{2i+1} = (c_i +
//! c_{i+1})/2` (Lane–Riesenfeld subdivision). With the ghost layers of `grid.rs` (`c_{−1} = 2c_0 − c_1`)
//! the end values are `f_0 = c_0` and the fine lattice's own ghost `2f_0 − f_1` is exactly the
//! subdivided `(c_{−1} + c_0)/2`, so the refined spline is the same function over the whole box (and,
//! its faces unchanged, outside it). Per axis `n → 2n − 1`.
//!
//! **Redistancing.** The spline is sampled at the lattice nodes. Nodes within two lattice steps of a
//! sign change (the control points the zero set's spline depends on) get their distance by projection
//! onto the zero set along the gradient (Newton steps `p ← p − φ∇φ/|∇φ|²`, exact for a distance field
//! and second order otherwise); the others from the eikonal equation `|∇d| = 1` by fast sweeping
//! (Zhao, "A fast sweeping method for eikonal equations", Math. Comp. 2005) with the Godunov upwind
//! update for the three spacings; the sign of the samples is kept. Only the nodes next to a sign change
//! are held fixed: the sweep may lower the band's other projected values where a neighbour proves a
//! shorter path (the projection of a node near a kink can find a far foot), so the distances stay
//! consistent with each other. The sweep alone would not do for the band: first-order sweeping
//! overestimates oblique distances by up to a tenth, and an optimisation redistances every step, so a
//! bias there moves the surface a little every time (a sphere grew by 0.16 cells at 31³ over 40
//! redistancings; with the band, 0.02).
//!
//! The distances `d` are then turned into control points. Taken as they are, the spline `S d` of
//! the samples smooths them: it moves a surface of mean curvature `H` inward by about `h²H/3`.
//! Control points that *interpolate* `d` (solving `S c = d`, per axis `(c_{i−1} + 4c_i +
//! c_{i+1})/6 = d_i`) keep the zero set in place but amplify the kinks of a distance (its medial
//! axis) up to 27-fold in 3-D, and a large lattice difference anywhere raises the Lipschitz bound,
//! and so the number of sphere-tracing steps, everywhere. So the correction is one step of that
//! solve, `c = d + (d − S d)`, capped at a tenth of a cell: where the distance is smooth
//! (curvature radii above about three cells) the cap does not bind and the surface moves by
//! `O(h⁴)` instead of `O(h²)`; at kinks no difference of `c` exceeds those of `d` (at most one
//! spacing, by fast sweeping) by more than a fifth of a cell.

use super::{GridData, Sdf};
use rayon::prelude::*;
use std::sync::Arc;

/// Largest correction, in cells, of a redistanced control point towards interpolation (module
/// docs).
const CORRECTION_CAP_CELLS: f32 = 0.1;

/// How far, in lattice steps per axis, from a node next to a sign change the distances come from
/// projection onto the zero set rather than from the sweep: a cubic spline's value in a cell depends
/// on the 4³ control points around it, so the zero set depends on every node within two steps of a
/// cell it crosses (module docs).
const PROJECTED_BAND_NODES: usize = 2;

/// Newton steps of a projection onto the zero set, its tolerance on `|φ|` and its reach, in cells.
const PROJECTION_STEPS: usize = 8;
const PROJECTION_TOLERANCE_CELLS: f32 = 1e-4;
const PROJECTION_REACH_CELLS: f32 = 5.0;

impl GridData {
    /// The control points of the same cubic B-spline on a lattice twice as fine (`n → 2n − 1` per
    /// axis, same box; module docs).
    pub fn refined(&self) -> GridData {
        let mut data = self.clone();
        for axis in 0..3 {
            data = data.map_lines(axis, 2 * data.dims[axis] - 1, |c, out| {
                let n = c.len();
                for i in 0..n {
                    let prev = if i == 0 { 2.0 * c[0] - c[1] } else { c[i - 1] };
                    let next = if i + 1 == n {
                        2.0 * c[n - 1] - c[n - 2]
                    } else {
                        c[i + 1]
                    };
                    out[2 * i] = (prev + 6.0 * c[i] + next) / 8.0;
                    if i + 1 < n {
                        out[2 * i + 1] = 0.5 * (c[i] + c[i + 1]);
                    }
                }
            });
        }
        data
    }

    /// Control points whose spline minus `level` is the signed distance to the zero set of this grid's
    /// spline minus `level` (the grid node's iso-level) over the box `[bbox_min, bbox_max]` (module
    /// docs). A grid without a sign change keeps its values.
    pub fn redistanced(&self, bbox_min: glam::Vec3, bbox_max: glam::Vec3, level: f32) -> GridData {
        let [nx, ny, nz] = self.dims;
        let node = Sdf::Grid {
            data: Arc::new(self.clone()),
            bbox_min,
            bbox_max,
            level: crate::scalar::Param::new(level),
            selection: Default::default(),
        };
        let h = (bbox_max - bbox_min)
            / glam::Vec3::new(nx as f32 - 1.0, ny as f32 - 1.0, nz as f32 - 1.0);
        let at = |x: usize, y: usize, z: usize| {
            bbox_min + glam::Vec3::new(x as f32, y as f32, z as f32) * h
        };
        let index = |x: usize, y: usize, z: usize| (z * ny + y) * nx + x;
        let node_at = |i: usize| (i % nx, (i / nx) % ny, i / (nx * ny));
        // Every node on its own, so the threads change nothing but the time.
        let mut samples = vec![0.0f32; nx * ny * nz];
        samples.par_iter_mut().enumerate().for_each(|(i, v)| {
            let (x, y, z) = node_at(i);
            *v = node.eval_f32(at(x, y, z));
        });
        let step = h.min_element();
        // Nodes next to a sign change: their distance, held fixed by the sweep.
        let seeds: Vec<Option<f32>> = (0..samples.len())
            .into_par_iter()
            .map(|i| {
                let (x, y, z) = node_at(i);
                let s = samples[i];
                // Along each lattice edge with a sign change the zero lies where the samples'
                // linear interpolant vanishes, `t h` away: an upper bound of the distance, and the
                // two ends' bounds sum to `h`, so neighbouring estimates stay consistent.
                let mut edge = f32::INFINITY;
                for (axis, (a, b, c)) in [(1, 0, 0), (0, 1, 0), (0, 0, 1)].into_iter().enumerate() {
                    let fwd = (x + a < nx && y + b < ny && z + c < nz)
                        .then(|| samples[index(x + a, y + b, z + c)]);
                    let back =
                        (x >= a && y >= b && z >= c).then(|| samples[index(x - a, y - b, z - c)]);
                    for t in [fwd, back].into_iter().flatten() {
                        if (t < 0.0) != (s < 0.0) {
                            edge = edge.min(s / (s - t) * h[axis]);
                        }
                    }
                }
                edge.is_finite().then(|| {
                    let est = projected_distance(&node, at(x, y, z), step).unwrap_or_else(|| {
                        let g = node.gradient(at(x, y, z)).length();
                        if g > 1e-6 { s.abs() / g } else { s.abs() }
                    });
                    est.min(edge)
                })
            })
            .collect();
        let frozen: Vec<bool> = seeds.iter().map(Option::is_some).collect();
        if !frozen.contains(&true) {
            return self.clone();
        }
        // The rest of the band the zero set's spline depends on: projected distances as starting
        // values, which the sweep below only lowers (where a neighbour proves a shorter path).
        let band = dilated(&frozen, self.dims, PROJECTED_BAND_NODES);
        let mut d: Vec<f32> = seeds
            .par_iter()
            .enumerate()
            .map(|(i, seed)| match seed {
                Some(v) => *v,
                None if band[i] => {
                    let (x, y, z) = node_at(i);
                    projected_distance(&node, at(x, y, z), step).unwrap_or(f32::INFINITY)
                }
                None => f32::INFINITY,
            })
            .collect();
        fast_sweep(&mut d, &frozen, self.dims, h);
        for (v, s) in d.iter_mut().zip(&samples) {
            if *s < 0.0 {
                *v = -*v;
            }
        }
        // Control points whose spline nearly interpolates the distances near the zero set (plus the
        // level, which the node subtracts).
        let cap = CORRECTION_CAP_CELLS * h.min_element();
        let distances = GridData {
            dims: self.dims,
            values: d,
        };
        let mut smoothed = distances.clone();
        for axis in 0..3 {
            smoothed = smoothed.map_lines(axis, self.dims[axis], spline_at_nodes);
        }
        let values = (distances.values.iter().zip(&smoothed.values))
            .map(|(&d, &s)| d + (d - s).clamp(-cap, cap) + level)
            .collect();
        GridData {
            dims: self.dims,
            values,
        }
    }

    /// Applies `f(line, out)` to every line of values along `axis`, `out` of length `new_len`.
    fn map_lines(&self, axis: usize, new_len: usize, f: impl Fn(&[f32], &mut [f32])) -> GridData {
        let mut dims = self.dims;
        dims[axis] = new_len;
        let [nx, ny, nz] = self.dims;
        let (mx, my) = (dims[0], dims[1]);
        let mut values = vec![0.0f32; dims.iter().product()];
        let n = self.dims[axis];
        let (mut line, mut out) = (vec![0.0f32; n], vec![0.0f32; new_len]);
        let outer: [usize; 2] = match axis {
            0 => [ny, nz],
            1 => [nx, nz],
            _ => [nx, ny],
        };
        for u in 0..outer[0] {
            for v in 0..outer[1] {
                let src = |k: usize| match axis {
                    0 => (v * ny + u) * nx + k,
                    1 => (v * ny + k) * nx + u,
                    _ => (k * ny + v) * nx + u,
                };
                let dst = |k: usize| match axis {
                    0 => (v * my + u) * mx + k,
                    1 => (v * my + k) * mx + u,
                    _ => (k * my + v) * mx + u,
                };
                for (k, l) in line.iter_mut().enumerate() {
                    *l = self.values[src(k)];
                }
                f(&line, &mut out);
                for (k, o) in out.iter().enumerate() {
                    values[dst(k)] = *o;
                }
            }
        }
        GridData { dims, values }
    }
}

/// The distance from `x` to the zero set of `node` along its gradient (Newton steps `p ← p −
/// φ ∇φ/|∇φ|²`; exact for a distance field, whose gradient lines are straight and normal to the
/// zero set). `None` when the steps do not settle within [`PROJECTION_REACH_CELLS`] cells of `x`
/// (`cell` the smallest spacing), e.g. at a critical point.
fn projected_distance(node: &Sdf, x: glam::Vec3, cell: f32) -> Option<f32> {
    let mut p = x;
    for _ in 0..PROJECTION_STEPS {
        let v = node.eval_f32(p);
        if v.abs() <= PROJECTION_TOLERANCE_CELLS * cell {
            return Some((p - x).length());
        }
        let g = node.gradient(p);
        let g2 = g.length_squared();
        if g2.is_nan() || g2 <= 1e-12 {
            return None;
        }
        p -= g * (v / g2);
        if (p - x).length() > PROJECTION_REACH_CELLS * cell {
            return None;
        }
    }
    None
}

/// The nodes within `radius` lattice steps per axis (a cube) of a `true` one in `mask`.
fn dilated(mask: &[bool], dims: [usize; 3], radius: usize) -> Vec<bool> {
    let mut out = mask.to_vec();
    for axis in 0..3 {
        let stride = [1, dims[0], dims[0] * dims[1]][axis];
        let n = dims[axis];
        let src = out.clone();
        for (i, o) in out.iter_mut().enumerate() {
            let k = (i / stride) % n;
            let (lo, hi) = (k.saturating_sub(radius), (k + radius).min(n - 1));
            *o = (lo..=hi).any(|j| src[i - k * stride + j * stride]);
        }
    }
    out
}

/// The values at the nodes of the spline of one line of control points `c`:
/// `(c_{i−1} + 4c_i + c_{i+1})/6`, with the ghost rule `c_{−1} = 2c_0 − c_1` making the end values
/// `c_0` and `c_{n−1}`.
fn spline_at_nodes(c: &[f32], out: &mut [f32]) {
    let n = c.len();
    out.copy_from_slice(c);
    for i in 1..n.saturating_sub(1) {
        out[i] = (c[i - 1] + 4.0 * c[i] + c[i + 1]) / 6.0;
    }
}

/// Fast sweeping for `|∇d| = 1` on a lattice of spacings `h`: the non-frozen entries of `d` (initially
/// `∞`) become the upwind distances from the frozen ones, in eight sweep orders, repeated until nothing
/// changes (at most four rounds). A node is visited again only after a neighbour of it changed.
///
/// The sweeps run on a copy of `d` padded by one layer of `∞` on every side, so that every node has its
/// six neighbours (a missing one counted as `∞`, as it was).
fn fast_sweep(d: &mut [f32], frozen: &[bool], dims: [usize; 3], h: glam::Vec3) {
    let [nx, ny, _] = dims;
    let index = |x: usize, y: usize, z: usize| (z * ny + y) * nx + x;
    let mut p = super::grid::Padded::new(d, dims, f32::INFINITY);
    let h = [h.x, h.y, h.z];
    let stride = p.strides();
    // Whether a node's neighbours changed since it was last updated: one whose neighbours did not
    // would compute the same value again, which cannot lower its own, so it is skipped (the same
    // result as visiting every node, in a fraction of the visits).
    let mut stale = vec![true; p.values.len()];
    for _round in 0..4 {
        let mut changed = false;
        sweep_orders(dims, |x, y, z| {
            let i = p.index(x, y, z);
            if !stale[i] || frozen[index(x, y, z)] {
                return;
            }
            stale[i] = false;
            let v = &mut p.values;
            let near = [0, 1, 2].map(|a| (v[i - stride[a]].min(v[i + stride[a]]), h[a]));
            let u = godunov(near);
            if u < v[i] {
                v[i] = u;
                changed = true;
                for a in 0..3 {
                    stale[i - stride[a]] = true;
                    stale[i + stride[a]] = true;
                }
            }
        });
        if !changed {
            break;
        }
    }
    d.copy_from_slice(&p.unpadded());
}

/// Visits every node of a lattice of `dims` in each of fast sweeping's eight orders in turn (x, y
/// and z each ascending or descending; x fastest).
#[inline(always)]
fn sweep_orders(dims: [usize; 3], mut visit: impl FnMut(usize, usize, usize)) {
    let [nx, ny, nz] = dims;
    let order = |n: usize, flip: bool| (0..n).map(move |i| if flip { n - 1 - i } else { i });
    for dir in 0..8 {
        for z in order(nz, dir & 4 != 0) {
            for y in order(ny, dir & 2 != 0) {
                for x in order(nx, dir & 1 != 0) {
                    visit(x, y, z);
                }
            }
        }
    }
}

/// The upwind solution `u` of `Σ_k ((u − a_k)⁺ / h_k)² = 1` for each axis's smaller neighbour value
/// `a_k` and spacing `h_k`, using as many axes as stay below `u`.
fn godunov(mut near: [(f32, f32); 3]) -> f32 {
    // A stable sort of three by value (ties keep their axis order).
    for (j, k) in [(0, 1), (1, 2), (0, 1)] {
        if near[j].0.total_cmp(&near[k].0).is_gt() {
            near.swap(j, k);
        }
    }
    let (a0, h0) = near[0];
    if !a0.is_finite() {
        return f32::INFINITY;
    }
    let mut u = a0 + h0;
    // Add axes while the solution exceeds the next neighbour: solve Σ (u − a_k)²/h_k² = 1.
    for m in 2..=3 {
        let (next, _) = near[m - 1];
        if u <= next {
            break;
        }
        let (mut qa, mut qb, mut qc) = (0.0f64, 0.0f64, -1.0f64);
        for &(a, h) in &near[..m] {
            let w = 1.0 / (h as f64 * h as f64);
            qa += w;
            qb -= 2.0 * a as f64 * w;
            qc += a as f64 * a as f64 * w;
        }
        let disc = qb * qb - 4.0 * qa * qc;
        if disc < 0.0 {
            break;
        }
        u = ((-qb + disc.sqrt()) / (2.0 * qa)) as f32;
    }
    u
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sdf::bake;

    /// Fast sweeping that visits every node in every sweep: what [`fast_sweep`]'s skipping must
    /// reproduce bit for bit.
    fn sweep_every_node(d: &mut [f32], frozen: &[bool], dims: [usize; 3], h: [f32; 3]) {
        let [nx, ny, _] = dims;
        let at = |x: usize, y: usize, z: usize| (z * ny + y) * nx + x;
        for _round in 0..4 {
            let mut changed = false;
            sweep_orders(dims, |x, y, z| {
                let i = at(x, y, z);
                if frozen[i] {
                    return;
                }
                let c = [x, y, z];
                let near = [0, 1, 2].map(|a| {
                    let mut m = f32::INFINITY;
                    for side in [-1isize, 1] {
                        let k = c[a] as isize + side;
                        if k >= 0 && (k as usize) < dims[a] {
                            let mut n = c;
                            n[a] = k as usize;
                            m = m.min(d[at(n[0], n[1], n[2])]);
                        }
                    }
                    (m, h[a])
                });
                let u = godunov(near);
                if u < d[i] {
                    d[i] = u;
                    changed = true;
                }
            });
            if !changed {
                break;
            }
        }
    }

    /// Skipping the nodes whose neighbours did not change gives the same distances, bit for bit, as
    /// visiting every node (scattered seeds on an anisotropic lattice).
    #[test]
    fn fast_sweep_skips_only_what_cannot_change() {
        let dims = [13, 9, 11];
        let h = glam::Vec3::new(0.1, 0.13, 0.07);
        let n: usize = dims.iter().product();
        let frozen: Vec<bool> = (0..n).map(|k| (k * 37 + 5) % 97 < 3).collect();
        let start: Vec<f32> = (0..n)
            .map(|k| {
                if frozen[k] {
                    0.01 * ((k * 13) % 7) as f32
                } else {
                    f32::INFINITY
                }
            })
            .collect();
        let (mut fast, mut every) = (start.clone(), start);
        fast_sweep(&mut fast, &frozen, dims, h);
        sweep_every_node(&mut every, &frozen, dims, [h.x, h.y, h.z]);
        assert!(fast.iter().all(|v| v.is_finite()));
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&fast), bits(&every));
    }

    fn grid_node(data: GridData, lo: glam::Vec3, hi: glam::Vec3) -> Sdf {
        Sdf::grid(data, lo, hi).unwrap()
    }

    /// A deterministic point in the box.
    fn point(k: u32, lo: glam::Vec3, hi: glam::Vec3) -> glam::Vec3 {
        let f = |s: u32| {
            ((k.wrapping_mul(2654435761).wrapping_add(s * 40503)) % 10007) as f32 / 10007.0
        };
        lo + (hi - lo) * glam::Vec3::new(f(1), f(2), f(3))
    }

    /// The distance `t` in `[near, far]` from `centre` along `dir` where `node` changes from inside
    /// to outside (bisection, 40 halvings).
    fn zero_along(node: &Sdf, centre: glam::Vec3, dir: glam::Vec3, near: f32, far: f32) -> f32 {
        let (mut a, mut b) = (near, far);
        for _ in 0..40 {
            let m = 0.5 * (a + b);
            if node.eval_f32(centre + dir * m) < 0.0 {
                a = m;
            } else {
                b = m;
            }
        }
        a
    }

    #[test]
    fn refinement_keeps_the_spline() {
        let (lo, hi) = (
            glam::Vec3::new(-1.2, -1.0, -0.9),
            glam::Vec3::new(1.1, 1.3, 1.0),
        );
        let blob = Sdf::smooth_union(
            vec![
                Sdf::sphere([-0.3, 0.0, 0.1], 0.6),
                Sdf::sphere([0.4, 0.2, -0.1], 0.45),
            ],
            0.3,
        );
        let coarse = bake(&blob, lo, hi, 9);
        let fine = coarse.refined();
        for a in 0..3 {
            assert_eq!(fine.dims[a], 2 * coarse.dims[a] - 1);
        }
        let (c, f) = (grid_node(coarse, lo, hi), grid_node(fine.clone(), lo, hi));
        let mut largest = 0.0f32;
        for k in 0..500 {
            // Inside the box, on its faces' neighbourhood and outside it.
            let p = point(k, lo - 0.2, hi + 0.2);
            let (a, b) = (c.eval_f32(p), f.eval_f32(p));
            largest = largest.max((a - b).abs() / a.abs().max(1.0));
        }
        // Rounding only: a few f32 ulps of values of order 1.
        assert!(largest < 2e-6, "largest relative difference {largest}");
        // Twice refined is still the same function.
        let ff = grid_node(fine.refined(), lo, hi);
        for k in 0..100 {
            let p = point(k, lo, hi);
            assert!((c.eval_f32(p) - ff.eval_f32(p)).abs() < 4e-6);
        }
    }

    #[test]
    fn redistancing_restores_a_distance_and_keeps_the_zero_set() {
        let (lo, hi) = (glam::Vec3::splat(-1.5), glam::Vec3::splat(1.5));
        let r = 0.9;
        let sphere = Sdf::sphere([0.1, -0.05, 0.0], r);
        let mut doubled = bake(&sphere, lo, hi, 24);
        for v in &mut doubled.values {
            *v *= 2.0;
        }
        let before = grid_node(doubled.clone(), lo, hi);
        let after = grid_node(doubled.redistanced(lo, hi, 0.0), lo, hi);
        let h = 3.0 / 23.0;
        let centre = glam::Vec3::new(0.1, -0.05, 0.0);
        let (mut zero_shift, mut near_error, mut far_error) = (0.0f32, 0.0f32, 0.0f32);
        for k in 0..400 {
            let p = point(k, lo + 0.2, hi - 0.2);
            let dir = (p - centre).normalize();
            // Where the doubled grid's zero set is, along this direction.
            let a = zero_along(&before, centre, dir, 0.2, 1.4);
            zero_shift = zero_shift.max(after.eval_f32(centre + dir * a).abs());
            // The distance to that zero set (a sphere of radius `a` around `centre`).
            let want = (p - centre).length() - a;
            let e = (after.eval_f32(p) - want).abs();
            if want.abs() <= 2.0 * h {
                near_error = near_error.max(e);
            } else {
                far_error = far_error.max(e / want.abs());
            }
        }
        // Measured: the zero set moved by 0.0005 (0.35% of a cell); the distance is off by 0.11 h
        // within two cells of the surface and by up to 9.9% of the distance farther out (first-order
        // sweeping overestimates oblique distances). Bounds: 1.5–2× those (the zero set's: 2× the
        // 0.6% it moved before the band of projected distances).
        assert!(
            zero_shift < 0.012 * h,
            "zero set moved by {zero_shift} (h = {h})"
        );
        assert!(
            near_error < 0.2 * h,
            "error {near_error} near the surface (h = {h})"
        );
        assert!(
            far_error < 0.15,
            "relative error {far_error} of the distance farther out"
        );
        // The gradient's length is back near 1 (it was 2), away from the centre: the distance has a
        // kink there that a C2 spline smooths (within 4 cells of it |∇φ| drops to 0.89).
        for k in 0..100 {
            let p = point(k, lo + 0.3, hi - 0.3);
            if (p - centre).length() > 4.0 * h {
                let g = after.gradient(p).length();
                assert!((g - 1.0).abs() < 0.1, "|∇φ| = {g} at {p}");
            }
        }
    }

    /// Redistancing a shape whose distance has kinks (a box: its medial axis) keeps every lattice
    /// difference near one spacing, so the Lipschitz bound stays near that of a distance field (√3
    /// for the per-axis bound); interpolating the distances exactly would amplify the kinks.
    #[test]
    fn redistancing_keeps_the_lipschitz_bound_of_a_distance() {
        let (lo, hi) = (glam::Vec3::splat(-1.5), glam::Vec3::splat(1.5));
        let boxed = Sdf::cuboid([0.1, -0.2, 0.05], [0.9, 0.5, 0.7], 0.05);
        let mut doubled = bake(&boxed, lo, hi, 31);
        for v in &mut doubled.values {
            *v *= 2.0;
        }
        let after = grid_node(doubled.redistanced(lo, hi, 0.0), lo, hi);
        let l = after.lipschitz();
        assert!(l < 1.2 * 3f32.sqrt(), "Lipschitz bound {l}");
    }

    /// Redistancing again and again (an optimisation does it every step) leaves the zero set where
    /// it is: a sphere's radius, measured by bisection along 200 directions, after 40 redistancings
    /// at two resolutions.
    #[test]
    fn repeated_redistancing_does_not_move_the_zero_set() {
        let (lo, hi) = (glam::Vec3::ZERO, glam::Vec3::ONE);
        let centre = glam::Vec3::new(0.5, 0.48, 0.51);
        let sphere = Sdf::sphere(centre.to_array(), 0.3);
        for n in [31, 61] {
            let mean_radius = |data: &GridData| {
                let node = grid_node(data.clone(), lo, hi);
                let mut sum = 0.0f64;
                for k in 0..200 {
                    let dir = (point(k, -glam::Vec3::ONE, glam::Vec3::ONE)).normalize();
                    sum += zero_along(&node, centre, dir, 0.1, 0.45) as f64;
                }
                (sum / 200.0) as f32
            };
            let mut data = bake(&sphere, lo, hi, n);
            let h = 1.0 / (data.dims[0] as f32 - 1.0);
            let before = mean_radius(&data);
            for _ in 0..40 {
                data = data.redistanced(lo, hi, 0.0);
            }
            let moved = (mean_radius(&data) - before) / h;
            // Measured: 0.023 cells at 31³ and −0.004 at 61³ (0.155 and 0.088 when only the nodes
            // next to a sign change took a distance of their own and the sweep did the rest).
            assert!(
                moved.abs() < 0.05,
                "{n}³: the radius moved by {moved} cells"
            );
        }
    }

    /// With an iso-level, the node's function (spline − level) becomes the distance, and its zero set
    /// stays: the same sphere as a grid of `distance + 0.3` at level 0.3.
    #[test]
    fn redistancing_respects_the_level() {
        let (lo, hi) = (glam::Vec3::splat(-1.5), glam::Vec3::splat(1.5));
        let sphere = Sdf::sphere([0.0; 3], 0.8);
        let mut shifted = bake(&sphere, lo, hi, 20);
        for v in &mut shifted.values {
            *v = 2.0 * *v + 0.3;
        }
        let with_level = |data: GridData| {
            let mut node = grid_node(data, lo, hi);
            if let Sdf::Grid { level, .. } = &mut node {
                level.value = 0.3;
            }
            node
        };
        let before = with_level(shifted.clone());
        let after = with_level(shifted.redistanced(lo, hi, 0.3));
        for k in 0..50 {
            let p = point(k, lo + 0.3, hi - 0.3);
            let (b, a) = (before.eval_f32(p), after.eval_f32(p));
            // Same sign (the zero set stays), half the value (the factor 2 is gone) away from it.
            assert_eq!(a < 0.0, b < 0.0, "at {p}: {a} vs {b}");
            if b.abs() > 0.1 {
                assert!((a - 0.5 * b).abs() < 0.1 * b.abs(), "at {p}: {a} vs {b}/2");
            }
        }
    }
}
