//! A grid's value, gradient and Hessian in `f32`, straight from the spline's taps.
//!
//! The spline is a tensor product, so each spatial derivative is the same lattice sum with one axis's
//! weights replaced by their derivatives: `∂x φ = Σ c B'(u) B(v) B(w) / h_x`, `∂x∂y φ = Σ c B'(u)
//! B'(v) B(w) / (h_x h_y)`, and so on. Carrying each row's four x taps as one 4-lane vector through the
//! sums over y and z with the weights of each order, then contracting with x's, gives all ten numbers
//! in about 50 vector and 40 scalar operations, where second-order forward AD carries a 3-vector and a
//! 3×3 matrix through every one of the spline's operations. The ghost layers fold into the derivative weights exactly as
//! into the weights ([`super::grid`]'s module docs): folding is linear.
//!
//! Inside the grid's box only; outside it the field adds the distance to the box, and callers fall
//! back to AD there.

use super::GridData;
use super::spline_basis::{LaneCells, cubic_basis, cubic_basis_slope, fold_ghosts};
use crate::scalar::{LatticeJet, LatticeTaps, Slot};
use glam::Vec4;

/// The weights of one axis's four taps for the value and its first and second derivatives along the
/// axis (per unit length, not per lattice cell), with the taps' lattice indices.
struct AxisJet {
    index: [usize; 4],
    w: [f32; 4],
    d: [f32; 4],
    dd: [f32; 4],
}

/// The taps along the three axes of a lattice of `dims` (each at least 4) points spanning `[lo, lo +
/// ext]`, at `p` in that box, computed for the three axes at once in the lanes of a vector as
/// [`super::grid`]'s `f32` spline does, so the value weights are its weights bit for bit.
#[inline(always)]
fn axes_jet(p: glam::Vec3, lo: glam::Vec3, ext: glam::Vec3, dims: [usize; 3]) -> [AxisJet; 3] {
    let LaneCells { cell, t, inv_h } = LaneCells::at(dims, lo, ext, p);
    let s = Vec4::ONE - t;
    // The grid's basis, and its derivatives in t.
    let w = cubic_basis(t, s);
    let d = cubic_basis_slope(t, s).map(|v| v * inv_h);
    let dd = [s, t * 3.0 - 2.0, Vec4::ONE - t * 3.0, t].map(|v| v * (inv_h * inv_h));
    let axis = |a: usize| {
        let n = dims[a];
        let (index, w) = fold_ghosts(cell[a], n, w.map(|v| v[a]), 0.0);
        let (_, d) = fold_ghosts(cell[a], n, d.map(|v| v[a]), 0.0);
        let (_, dd) = fold_ghosts(cell[a], n, dd.map(|v| v[a]), 0.0);
        AxisJet { index, w, d, dd }
    };
    [axis(0), axis(1), axis(2)]
}

#[inline(always)]
fn dot(a: &[f32; 4], b: &[f32; 4]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]
}

/// The spline's value (before the level is subtracted), gradient and, with `SECOND`, Hessian (zero
/// without) at `p`, or `None` where `p` is outside the box `[bmin, bmax]` (or not a number) or the grid
/// is unusable.
#[inline]
pub(super) fn jet<const SECOND: bool>(
    data: &GridData,
    bmin: glam::Vec3,
    bmax: glam::Vec3,
    p: glam::Vec3,
) -> Option<(f32, glam::Vec3, glam::Mat3)> {
    if !has_jet(data, bmin, bmax, p) {
        return None;
    }
    Some(sums::<SECOND>(
        data,
        &axes_jet(p, bmin, bmax - bmin, data.dims),
    ))
}

/// Whether the taps answer at `p`: a usable grid and `p` in its box (not a NaN).
#[inline(always)]
fn has_jet(data: &GridData, bmin: glam::Vec3, bmax: glam::Vec3, p: glam::Vec3) -> bool {
    data.usable() && p.cmpge(bmin).all() && p.cmple(bmax).all()
}

/// [`jet`] with the Hessian and the taps, for a lookup at a point that carries derivatives
/// ([`crate::scalar::Scalar::lattice_jet`]); `block` is the values' reverse-mode block.
#[inline]
pub(super) fn lattice_jet<'a>(
    data: &'a GridData,
    bmin: glam::Vec3,
    bmax: glam::Vec3,
    block: Slot,
    p: glam::Vec3,
) -> Option<LatticeJet<'a>> {
    if !has_jet(data, bmin, bmax, p) {
        return None;
    }
    let axes = axes_jet(p, bmin, bmax - bmin, data.dims);
    let (value, g, h) = sums::<true>(data, &axes);
    let [x, y, z] = &axes;
    Some(LatticeJet {
        value,
        gradient: g.to_array(),
        hessian: h.transpose().to_cols_array_2d(),
        taps: LatticeTaps {
            index: [x.index, y.index, z.index],
            weight: [x.w, y.w, z.w],
        },
        deriv: [x.d, y.d, z.d],
        values: &data.values,
        dims: data.dims,
        block,
    })
}

/// The value, gradient and (with `SECOND`) Hessian sums over the taps `axes`.
#[inline(always)]
fn sums<const SECOND: bool>(data: &GridData, axes: &[AxisJet; 3]) -> (f32, glam::Vec3, glam::Mat3) {
    let [nx, ny, _] = data.dims;
    let [x, y, z] = axes;
    let values = &data.values;
    // Each row's four x taps ride as one vector through the sums over y and z, weighted by (y order, z
    // order), and meet the x weights of each order last, the spline's own summation order
    // (`scalar::lattice_sum_nested`): the value is the field's bit for bit.
    let mut a = [Vec4::ZERO; 6];
    for c in 0..4 {
        // Sums over y of the rows with the y weights of order 0, 1 and 2.
        let mut ay = [Vec4::ZERO; 3];
        for b in 0..4 {
            let row = (z.index[c] * ny + y.index[b]) * nx + x.index[0];
            let r = Vec4::from_slice(&values[row..row + 4]);
            ay[0] += r * y.w[b];
            ay[1] += r * y.d[b];
            if SECOND {
                ay[2] += r * y.dd[b];
            }
        }
        // By (y order, z order): 00, 10, 01, then 20, 02, 11.
        a[0] += ay[0] * z.w[c];
        a[1] += ay[1] * z.w[c];
        a[2] += ay[0] * z.d[c];
        if SECOND {
            a[3] += ay[2] * z.w[c];
            a[4] += ay[0] * z.dd[c];
            a[5] += ay[1] * z.d[c];
        }
    }
    let [a00, a10, a01, a20, a02, a11] = a.map(|v| v.to_array());
    let g = glam::Vec3::new(dot(&x.d, &a00), dot(&x.w, &a10), dot(&x.w, &a01));
    let h = if SECOND {
        let (xy, xz, yz) = (dot(&x.d, &a10), dot(&x.d, &a01), dot(&x.w, &a11));
        glam::Mat3::from_cols(
            glam::Vec3::new(dot(&x.dd, &a00), xy, xz),
            glam::Vec3::new(xy, dot(&x.w, &a20), yz),
            glam::Vec3::new(xz, yz, dot(&x.w, &a02)),
        )
    } else {
        glam::Mat3::ZERO
    };
    (dot(&x.w, &a00), g, h)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scalar::{BlockValues, Grad, Param};
    use crate::sdf::Sdf;
    use std::sync::Arc;

    /// A grid node of `dims` with pseudo-random values in [−1, 1] over `[bmin, bmax]`.
    fn grid(dims: [usize; 3], bmin: glam::Vec3, bmax: glam::Vec3, seed: u32) -> Sdf {
        let n = dims.iter().product::<usize>();
        let values = (0..n)
            .map(|k| {
                let h = (k as u32 ^ seed)
                    .wrapping_mul(2_654_435_761)
                    .rotate_left(13)
                    .wrapping_mul(40_503);
                (h % 2001) as f32 / 1000.0 - 1.0
            })
            .collect();
        Sdf::Grid {
            data: Arc::new(GridData { dims, values }),
            bbox_min: bmin,
            bbox_max: bmax,
            level: Param::new(0.125),
            selection: BlockValues::Constant,
        }
    }

    /// A point of the box from three numbers in [0, 1], every eighth snapped onto a face (the ghost
    /// cells' taps and the box's closed ends).
    fn point(bmin: glam::Vec3, bmax: glam::Vec3, u: [f32; 3], k: usize) -> glam::Vec3 {
        let mut u = glam::Vec3::from(u);
        if k.is_multiple_of(8) {
            u[k / 8 % 3] = (k / 24 % 2) as f32;
        }
        (bmin + (bmax - bmin) * u).clamp(bmin, bmax)
    }

    /// The curvature bound of each patch holds: `|dᵀ H d| ≤ M` at random points of the cell and random
    /// unit directions (the Hessian from the taps), on random lattices that are anisotropic, far from
    /// the origin or tiny, with points on faces; and the bound is not loose by orders of magnitude
    /// (the largest ratio seen is above a tenth on these random lattices).
    #[test]
    fn curvature_bound_holds_on_each_patch() {
        let cases = [
            ([4, 4, 4], glam::Vec3::ZERO, glam::Vec3::ONE),
            (
                [5, 7, 6],
                glam::Vec3::new(-2.0, 0.5, -1.0),
                glam::Vec3::new(1.0, 1.5, 3.0),
            ),
            (
                [9, 4, 12],
                glam::Vec3::splat(1000.0),
                glam::Vec3::splat(1001.0),
            ),
            ([6, 6, 6], glam::Vec3::splat(-1e-3), glam::Vec3::splat(1e-3)),
        ];
        let mut rng = crate::sampler::Sampler::new(0, 0, 11, 0);
        for (c, (dims, bmin, bmax)) in cases.into_iter().enumerate() {
            let node = grid(dims, bmin, bmax, 100 + c as u32);
            let Sdf::Grid { data, .. } = &node else {
                unreachable!()
            };
            let (extended, _) = crate::sdf::grid::extended_lattice(data);
            let bound = crate::sdf::grid::patch_curvature(data, &extended, bmin, bmax);
            let cells = dims.map(|n| n - 1);
            let size = (bmax - bmin) / glam::Vec3::from(cells.map(|n| n as f32));
            let mut tightest = 0.0f32;
            for k in 0..3000 {
                let u = glam::Vec3::new(rng.next_1d(), rng.next_1d(), rng.next_1d());
                let p = point(bmin, bmax, u.into(), k);
                let cell = std::array::from_fn::<usize, 3, _>(|a| {
                    (((p[a] - bmin[a]) / size[a]) as usize).min(cells[a] - 1)
                });
                let m = bound[cell[0] + cells[0] * (cell[1] + cells[1] * cell[2])];
                let (_, _, h) = node.hessian(p);
                let d = glam::Vec3::new(rng.next_1d(), rng.next_1d(), rng.next_1d()) * 2.0
                    - glam::Vec3::ONE;
                let d = d.normalize_or(glam::Vec3::X);
                let curvature = d.dot(h * d).abs();
                // The Hessian from the taps is rounded: a few ulps of its largest entries.
                let slack = 1e-5 * h.to_cols_array().iter().fold(0.0f32, |a, v| a.max(v.abs()));
                assert!(
                    curvature <= m + slack,
                    "case {c}: |dᵀHd| = {curvature} above the bound {m} at {p} along {d}"
                );
                tightest = tightest.max(curvature / m);
            }
            assert!(tightest > 0.1, "case {c}: the bound is loose ({tightest})");
        }
    }

    /// The taps' value is the field's, bit for bit; gradient and Hessian are second-order AD's to
    /// rounding (relative to the largest derivative a lattice of values in [−1, 1] can have), over
    /// small and large lattices, boxes far from the origin and tiny ones, with points on faces. So is
    /// the gradient of a lookup in `Grad` at a point seeded in space only, whose taps are linearised
    /// (`grid::linear_axis_taps`), with the field's value bit for bit.
    #[test]
    fn value_gradient_and_hessian_match_forward_ad() {
        let cases = [
            ([4, 4, 4], glam::Vec3::ZERO, glam::Vec3::ONE),
            (
                [5, 7, 6],
                glam::Vec3::new(-2.0, 0.5, -1.0),
                glam::Vec3::new(1.0, 1.5, 3.0),
            ),
            (
                [31, 31, 31],
                glam::Vec3::splat(1000.0),
                glam::Vec3::splat(1001.0),
            ),
            (
                [9, 4, 12],
                glam::Vec3::splat(-1e-3),
                glam::Vec3::splat(1e-3),
            ),
        ];
        let mut rng = crate::sampler::Sampler::new(0, 0, 7, 0);
        for (c, (dims, bmin, bmax)) in cases.into_iter().enumerate() {
            let node = grid(dims, bmin, bmax, c as u32);
            let inv_h = glam::Vec3::from(dims.map(|n| (n - 1) as f32)) / (bmax - bmin);
            // A value, derivative and second derivative of the spline are sums of at most 64 taps of
            // at most 1 in magnitude times weights whose sums are at most 2, 2 inv_h and 8 inv_h².
            let (scale1, scale2) = (2.0 * inv_h.max_element(), 8.0 * inv_h.max_element().powi(2));
            let (mut worst_g, mut worst_h, mut worst_linear) = (0.0f32, 0.0f32, 0.0f32);
            for k in 0..4000 {
                let u = [rng.next_1d(), rng.next_1d(), rng.next_1d()];
                let p = point(bmin, bmax, u, k);
                let (v, g, h) = node.hessian(p);
                let (va, ga, ha) = node.ad_hessian_as::<false>(p);
                assert_eq!(v.to_bits(), node.eval_f32(p).to_bits(), "value at {p}");
                assert_eq!(v.to_bits(), va.to_bits(), "value at {p}");
                assert_eq!(node.gradient(p), g, "first-order path at {p}");
                worst_g = worst_g.max((g - ga).abs().max_element() / scale1);
                let dh = (h - ha).to_cols_array().map(f32::abs);
                worst_h = worst_h.max(dh.into_iter().fold(0.0, f32::max) / scale2);
                assert!(h == h.transpose(), "symmetric at {p}");
                let linear = node.eval::<Grad<f32>>(Grad::seed(p));
                assert_eq!(linear.v.to_bits(), v.to_bits(), "linearised value at {p}");
                let gl = glam::Vec3::from(linear.g);
                worst_linear = worst_linear.max((gl - ga).abs().max_element() / scale1);
            }
            assert!(
                worst_g < 1e-6,
                "case {c}: gradient off by {worst_g} of its scale"
            );
            assert!(
                worst_linear < 1e-6,
                "case {c}: linearised gradient off by {worst_linear} of its scale"
            );
            assert!(
                worst_h < 1e-6,
                "case {c}: Hessian off by {worst_h} of its scale"
            );
        }
    }

    /// Under similarity transforms (rotated, scaled, moved away from the origin, nested, named) the
    /// mapped jet is AD's through the transforms to rounding.
    #[test]
    fn transformed_grids_match_forward_ad() {
        let (bmin, bmax) = (
            glam::Vec3::new(-1.0, -0.5, -1.5),
            glam::Vec3::new(1.0, 1.0, 0.5),
        );
        let inner = Sdf::transform(
            grid([7, 6, 8], bmin, bmax, 5),
            [0.5, -0.25, 2.0],
            glam::Vec3::new(0.0, 1.0, 0.0),
            -20.0,
            0.5,
        );
        let node = Sdf::transform(
            Sdf::named("blob", inner),
            [40.0, -25.0, 10.0],
            glam::Vec3::new(1.0, 2.0, 3.0),
            37.0,
            1.7,
        );
        let mut rng = crate::sampler::Sampler::new(1, 0, 3, 0);
        let (outer, named) = node.frame().expect("a transform");
        let Sdf::Named { child: inner, .. } = named else {
            unreachable!()
        };
        let (inner, _) = inner.frame().expect("a transform");
        // The grid's box seen from outside both transforms: its corners mapped out.
        let corner = |k: usize| -> glam::Vec3 {
            let c = glam::Vec3::new(
                if k & 1 == 0 { bmin.x } else { bmax.x },
                if k & 2 == 0 { bmin.y } else { bmax.y },
                if k & 4 == 0 { bmin.z } else { bmax.z },
            );
            let mid: glam::Vec3 = inner.from_child_point(c.into()).into();
            outer.from_child_point(mid.into()).into()
        };
        let (mut jets, mut worst_g, mut worst_h) = (0, 0.0f32, 0.0f32);
        for _ in 0..3000 {
            // A point between two random corners: inside the (convex) mapped box.
            let (a, b) = (
                corner((rng.next_1d() * 8.0) as usize % 8),
                corner((rng.next_1d() * 8.0) as usize % 8),
            );
            let p = a
                .lerp(b, rng.next_1d())
                .lerp(corner(0).lerp(corner(7), 0.5), 0.2);
            let Some((v, g, h)) = node.grid_jet::<true>(p) else {
                continue;
            };
            jets += 1;
            let (va, ga, ha) = node.ad_hessian_as::<false>(p);
            assert!(
                (v - va).abs() <= 1e-5 * (1.0 + va.abs()),
                "value at {p}: {v} vs {va}"
            );
            assert_eq!(node.gradient(p), g, "first-order path at {p}");
            worst_g = worst_g.max((g - ga).abs().max_element() / (1.0 + ga.abs().max_element()));
            let dh = (h - ha)
                .to_cols_array()
                .map(f32::abs)
                .into_iter()
                .fold(0.0, f32::max);
            worst_h = worst_h.max(
                dh / (1.0
                    + ha.to_cols_array()
                        .map(f32::abs)
                        .into_iter()
                        .fold(0.0, f32::max)),
            );
        }
        assert!(jets > 1000, "only {jets} points inside the grid's box");
        assert!(worst_g < 1e-5, "gradient off by {worst_g} relative");
        assert!(worst_h < 1e-5, "Hessian off by {worst_h} relative");
    }

    /// A grid in the frame of a rotation by `θ` about a fixed axis, a translation `t` and a scale `s`
    /// (`q = Rᵀ(θ)(x − t)/s`), looked up at `x` seeded in space: the lookup at a moving point.
    fn moving_lookup<S: crate::scalar::Scalar>(
        data: &GridData,
        (bmin, bmax): (glam::Vec3, glam::Vec3),
        selection: &BlockValues,
        x: glam::Vec3,
        [theta, tx, s]: [S; 3],
        t: glam::Vec3,
    ) -> Grad<S> {
        use crate::math::Vec3;
        use crate::scalar::Scalar;
        let axis = glam::Vec3::new(1.0, 2.0, 2.0) / 3.0;
        let lift = |v: S| Grad {
            v,
            g: [S::zero(); 3],
        };
        let (theta, s) = (lift(theta), lift(s));
        let a = Vec3::new(
            Grad::constant(axis.x),
            Grad::constant(axis.y),
            Grad::constant(axis.z),
        );
        let d = Grad::<S>::seed(x) - Vec3::new(lift(tx), Grad::constant(t.y), Grad::constant(t.z));
        // Rodrigues for the inverse rotation: v cos θ − (a × v) sin θ + a (a · v)(1 − cos θ).
        let (cos, sin) = (theta.cos(), theta.sin());
        let along = a.dot(d) * (Grad::one() - cos);
        let q = (d * cos - a.cross(d) * sin + a * along) * s.recip();
        crate::sdf::grid::eval(data, bmin, bmax, selection, q)
    }

    /// A lookup at a point that moves with parameters (a rotated, moved and scaled grid's attached
    /// vertex), built from the `f32` jet by the chain rule, has the derivatives of the generic path
    /// (the basis in `Grad<S>` arithmetic, which a forward-mode direction of the values still takes),
    /// to rounding: in forward mode for the transform's parameters, and in reverse mode for them and
    /// for the grid's values (against forward mode's direction `u` of the values).
    #[test]
    fn lookups_at_moving_points_match_the_generic_path() {
        use crate::scalar::{Dual4, Recording, Rev, Scalar};
        let (bmin, bmax) = (
            glam::Vec3::new(-1.0, -0.5, -1.5),
            glam::Vec3::new(1.0, 1.0, 0.5),
        );
        let node = grid([7, 6, 9], bmin, bmax, 21);
        let Sdf::Grid { data, .. } = &node else {
            unreachable!()
        };
        let n = data.values.len();
        let u: Vec<f32> = (0..n)
            .map(|k| ((k * 37 % 101) as f32 / 50.0) - 1.0)
            .collect();
        let direction = BlockValues::Direction {
            slot: 3,
            u: Arc::new(u.clone()),
        };
        let (theta, t, scale) = (0.7f32, glam::Vec3::new(0.3, -0.2, 0.1), 1.3f32);
        let rotation = glam::Quat::from_axis_angle(glam::Vec3::new(1.0, 2.0, 2.0) / 3.0, theta);
        let mut rng = crate::sampler::Sampler::new(2, 0, 5, 0);
        let _recording = Recording::start();
        let mut worst = 0.0f32;
        for _ in 0..2000 {
            // Not on the box's faces, where the field's gradient jumps and an ulp of `q` picks the
            // side; the first and last cells (the ghost points' taps) are still met.
            let r = glam::Vec3::new(rng.next_1d(), rng.next_1d(), rng.next_1d());
            let q = bmin + (bmax - bmin) * (r * 0.998 + 0.001);
            let x = rotation * (q * scale) + t;
            let params = |slot: u32, v: f32| Dual4::lift(v, Some(slot));
            let dual = [params(0, theta), params(1, t.x), params(2, scale)];
            let lookup =
                |selection: &BlockValues| moving_lookup(data, (bmin, bmax), selection, x, dual, t);
            let (jet, generic) = (lookup(&BlockValues::Constant), lookup(&direction));
            let mark = Recording::mark();
            let rev = [0, 1, 2].map(|i| Rev::lift([theta, t.x, scale][i], Some(i as u32)));
            let reverse = moving_lookup(
                data,
                (bmin, bmax),
                &BlockValues::Gradient { first: 3 },
                x,
                rev,
                t,
            );
            let outputs = |g: &Grad<Dual4>| [g.v, g.g[0], g.g[1], g.g[2]];
            let reverse = [reverse.v, reverse.g[0], reverse.g[1], reverse.g[2]];
            for ((a, b), r) in outputs(&jet).iter().zip(outputs(&generic)).zip(reverse) {
                // The generic path's slot 3 is the values' direction; the jet's (constant values)
                // has none.
                let mut rev = [0.0f32; 4];
                Recording::sweep(r, |e, d| {
                    if e < 3 {
                        rev[e as usize] += d
                    } else {
                        rev[3] += d * u[e as usize - 3]
                    }
                });
                let scale = 1.0 + b.re.abs() + b.eps.iter().fold(0.0f32, |m, e| m.max(e.abs()));
                assert!(
                    (a.re - b.re).abs() <= 1e-5 * scale,
                    "value at {q}: {a:?} vs {b:?}"
                );
                assert_eq!(
                    r.primal().to_bits(),
                    a.re.to_bits(),
                    "reverse primal at {q}"
                );
                for (i, &reverse) in rev.iter().enumerate() {
                    let jet_eps = if i < 3 { a.eps[i] } else { b.eps[3] };
                    for got in [jet_eps, reverse] {
                        let err = (got - b.eps[i]).abs() / scale;
                        worst = worst.max(err);
                        assert!(err < 2e-5, "direction {i} at {q}: {got} vs {}", b.eps[i]);
                    }
                }
            }
            Recording::rewind(mark);
        }
        assert!(
            worst > 0.0,
            "the paths agree bit for bit: is the jet's path taken?"
        );
    }

    /// Outside the box there is no jet (the field adds the distance to the box there).
    #[test]
    fn outside_the_box_is_left_to_ad() {
        let node = grid([6, 6, 6], glam::Vec3::ZERO, glam::Vec3::ONE, 3);
        let Sdf::Grid { data, .. } = &node else {
            unreachable!()
        };
        for p in [
            glam::Vec3::new(1.0 + 1e-6, 0.5, 0.5),
            glam::Vec3::NAN,
            glam::Vec3::splat(-0.1),
        ] {
            assert!(jet::<true>(data, glam::Vec3::ZERO, glam::Vec3::ONE, p).is_none());
        }
        let p = glam::Vec3::new(1.5, 0.5, 0.25);
        assert_eq!(node.hessian(p), node.ad_hessian_as::<false>(p));
    }
}
