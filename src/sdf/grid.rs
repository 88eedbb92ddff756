//! Grid SDFs: samples on a regular lattice, evaluated as a uniform tensor-product cubic B-spline.
//!
//! The samples `c_ijk` are the spline's **control points** (they are not interpolated): the value is
//! `Σ c_ijk B(u − i) B(v − j) B(w − k)` with `B` the C2 cubic B-spline and `(u, v, w)` the position in
//! lattice units. Because `Σ c_i B(u − i)` reproduces polynomials of degree ≤ 1 exactly and
//! `Σ x_i² B(u − i) = u² + 1/3`, the spline smooths a field by about `h²/6 ∇²φ`, an `O(h²)` offset (for a
//! sphere of radius `r`, `h²/(3r)`), in exchange for C2 continuity everywhere, which curvature needs.
//!
//! Edges: the lattice is extended by one ghost layer per face with *linear extrapolation*
//! (`c_{−1} = 2c_0 − c_1`, `c_n = 2c_{n−1} − c_{n−2}`), folded into the weights. The spline stays C2 up
//! to the faces, still reproduces linear fields (no `O(h)` bias at the faces, unlike clamping the
//! indices). The Lipschitz bound takes the extended lattice's differences, patch by patch (see `lipschitz`).
//!
//! Outside the box: `φ(x) = φ(clamp(x)) + |x − clamp(x)|`, a valid bound for sphere tracing.

use super::GridData;
use super::spline_basis::{LaneCells, cubic_basis, cubic_basis_slope, fold_ghosts, inv_spacing};
use crate::error::{Error, Result};
use crate::math::{Aabb, Vec3};
use crate::scalar::{BlockValues, LatticeTaps, Scalar, lattice_sum_nested};

impl GridData {
    /// A grid after checking that every dimension is at least 4, that there are `nx · ny · nz` values
    /// and that they are finite. `what` names the source in errors (a file or a field path).
    pub fn new(dims: [usize; 3], values: Vec<f32>, what: &str) -> Result<Self> {
        let g = Self { dims, values };
        g.validate(what)?;
        Ok(g)
    }

    /// Check the invariants listed in [`GridData::new`].
    pub fn validate(&self, what: &str) -> Result<()> {
        let [nx, ny, nz] = self.dims;
        if nx < 4 || ny < 4 || nz < 4 {
            return Err(Error::file(
                what,
                format!("grid dimensions must be at least 4 (cubic B-spline), got {nx}x{ny}x{nz}"),
            ));
        }
        let n = nx
            .checked_mul(ny)
            .and_then(|v| v.checked_mul(nz))
            .ok_or_else(|| Error::file(what, "grid dimensions overflow"))?;
        if self.values.len() != n {
            return Err(Error::file(
                what,
                format!(
                    "grid {nx}x{ny}x{nz} needs {n} values, got {}",
                    self.values.len()
                ),
            ));
        }
        if let Some(i) = self.values.iter().position(|v| !v.is_finite()) {
            return Err(Error::file(
                what,
                format!("non-finite grid value {} at index {i}", self.values[i]),
            ));
        }
        Ok(())
    }

    /// True if the grid can be evaluated (see [`GridData::validate`]; finiteness is not rechecked).
    #[inline(always)]
    pub(super) fn usable(&self) -> bool {
        let [nx, ny, nz] = self.dims;
        nx >= 4 && ny >= 4 && nz >= 4 && self.values.len() == nx * ny * nz
    }

    #[inline(always)]
    fn at(&self, x: usize, y: usize, z: usize) -> f32 {
        self.values[(z * self.dims[1] + y) * self.dims[0] + x]
    }
}

/// Lattice indices and weights of the four control points that shape coordinate `u` (in lattice units,
/// within `[0, n − 1]`) on one axis, with the ghost points folded in.
#[inline(always)]
fn axis_taps<S: Scalar>(u: S, n: usize) -> ([usize; 4], [S; 4]) {
    // `as usize` truncates towards zero and saturates negatives (and NaN) to 0: for `u ≥ 0` it is the
    // floor, below 0 the clamp to the first cell. Cheaper than `floor`, a libm call without SSE4.1.
    let i = (u.primal() as usize).min(n - 2);
    let t = u - i as f32;
    fold_ghosts(i, n, cubic_basis(t, S::one() - t), S::zero())
}

/// [`axis_taps`] for a coordinate `c` seeded in space only ([`Scalar::spatial_only`]): the weights
/// from `f32` (the same bits as `axis_taps`'s primal), each lifted as `w + (c − c̄) w'` with the
/// basis's slope `w'`, which for such a number is exactly what evaluating the basis in its own
/// arithmetic gives, to rounding, at a fraction of the operations.
#[inline(always)]
fn linear_axis_taps<S: Scalar>(c: S, lo: f32, inv_h: f32, n: usize) -> ([usize; 4], [S; 4]) {
    let u = (c.primal() - lo) * inv_h;
    let i = (u as usize).min(n - 2);
    let t = u - i as f32;
    let s = 1.0 - t;
    let (index, w) = fold_ghosts(i, n, cubic_basis(t, s), 0.0);
    let (_, slope) = fold_ghosts(i, n, cubic_basis_slope(t, s).map(|d| d * inv_h), 0.0);
    let moved = c - c.primal();
    (index, std::array::from_fn(|k| moved * slope[k] + w[k]))
}

/// [`spline`] in `f32` (no derivative), bit for bit: the three axes' lattice coordinates and basis
/// weights side by side in the lanes of one vector (the same operations, lane by lane), then the
/// vectorised lattice sum. The tracer's evaluation.
#[inline(always)]
fn spline_f32(data: &GridData, bmin: glam::Vec3, bmax: glam::Vec3, q: glam::Vec3) -> f32 {
    let [nx, ny, _] = data.dims;
    let LaneCells { cell, t, .. } = LaneCells::at(data.dims, bmin, bmax - bmin, q);
    let b = cubic_basis(t, glam::Vec4::ONE - t);
    let axis = |a: usize| fold_ghosts(cell[a], data.dims[a], b.map(|v| v[a]), 0.0);
    let ((ix, wx), (iy, wy), (iz, wz)) = (axis(0), axis(1), axis(2));
    let taps = LatticeTaps {
        index: [ix, iy, iz],
        weight: [wx, wy, wz],
    };
    crate::scalar::lattice_sum_f32(&taps, &data.values, nx, ny)
}

/// The B-spline at `q`, which must lie in the box, with the derivative of the values that `selection`
/// asks for (a forward-mode direction adds `ε_slot · Σ w u`; a reverse-mode block is recorded by
/// [`Scalar::lattice_sum`]).
#[inline(always)]
fn spline<S: Scalar>(
    data: &GridData,
    bmin: glam::Vec3,
    bmax: glam::Vec3,
    selection: &BlockValues,
    q: Vec3<S>,
) -> S {
    if let (Some(x), Some(y), Some(z)) = (q.x.as_f32(), q.y.as_f32(), q.z.as_f32()) {
        return S::constant(spline_f32(data, bmin, bmax, glam::Vec3::new(x, y, z)));
    }
    let linear = q.x.spatial_only() && q.y.spatial_only() && q.z.spatial_only();
    // A point moving with parameters (a transformed grid's attached vertex): by the chain rule from
    // the `f32` jet, for the types that do so; not with a forward-mode direction of the values.
    if !linear && !matches!(selection, BlockValues::Direction { .. }) {
        let jet = || super::grid_jet::lattice_jet(data, bmin, bmax, selection.block(), q.primal());
        if let Some(v) = S::lattice_jet([q.x, q.y, q.z], jet) {
            return v;
        }
    }
    let ext = bmax - bmin;
    let taps = |a: usize, c: S| {
        let n = data.dims[a];
        let inv_h = inv_spacing(n, ext[a]);
        if linear {
            linear_axis_taps(c, bmin[a], inv_h, n)
        } else {
            axis_taps((c - bmin[a]) * inv_h, n)
        }
    };
    let (ix, wx) = taps(0, q.x);
    let (iy, wy) = taps(1, q.y);
    let (iz, wz) = taps(2, q.z);
    let taps = LatticeTaps {
        index: [ix, iy, iz],
        weight: [wx, wy, wz],
    };
    let value = S::lattice_sum(&taps, &data.values, data.dims, selection.block());
    match selection {
        BlockValues::Direction { slot, u } if u.len() == data.values.len() => {
            value
                + S::lift(0.0, Some(*slot))
                    * lattice_sum_nested(&taps, u, data.dims[0], data.dims[1])
        }
        _ => value,
    }
}

/// `φ(p)` of a grid node. A grid that fails [`GridData::validate`]'s shape checks is treated as empty
/// (`+∞`) rather than panicking.
#[inline]
pub(super) fn eval<S: Scalar>(
    data: &GridData,
    bmin: glam::Vec3,
    bmax: glam::Vec3,
    selection: &BlockValues,
    p: Vec3<S>,
) -> S {
    // Interval types take the certified path: a box may span several cells, which the primal branches
    // below (inside the grid box or not, which cell) cannot express.
    let node = super::interval::GridEnclosure { data, bmin, bmax };
    if let Some(v) = S::enclosure(&node, [p.x, p.y, p.z]) {
        return v;
    }
    if !data.usable() {
        return S::constant(f32::INFINITY);
    }
    let pp = p.primal();
    if pp.cmpge(bmin).all() && pp.cmple(bmax).all() {
        return spline(data, bmin, bmax, selection, p);
    }
    // Outside: clamp (zero derivative across the face) plus the distance to the box, which supplies the
    // normal component of the gradient.
    let q = Vec3::new(
        p.x.clamp(bmin.x, bmax.x),
        p.y.clamp(bmin.y, bmax.y),
        p.z.clamp(bmin.z, bmax.z),
    );
    spline(data, bmin, bmax, selection, q) + (p - q).length()
}

/// The control point at extended lattice index `(x, y, z)`, each in `−1..=n`: ghost layers by linear
/// extrapolation along every axis that is out of range (bilinear and trilinear at ghost edges and corners).
fn extended(data: &GridData, x: isize, y: isize, z: isize) -> f32 {
    let [nx, ny, nz] = data.dims.map(|n| n as isize);
    if x < 0 {
        return 2.0 * extended(data, 0, y, z) - extended(data, 1, y, z);
    }
    if x >= nx {
        return 2.0 * extended(data, nx - 1, y, z) - extended(data, nx - 2, y, z);
    }
    if y < 0 {
        return 2.0 * extended(data, x, 0, z) - extended(data, x, 1, z);
    }
    if y >= ny {
        return 2.0 * extended(data, x, ny - 1, z) - extended(data, x, ny - 2, z);
    }
    if z < 0 {
        return 2.0 * extended(data, x, y, 0) - extended(data, x, y, 1);
    }
    if z >= nz {
        return 2.0 * extended(data, x, y, nz - 1) - extended(data, x, y, nz - 2);
    }
    data.at(x as usize, y as usize, z as usize)
}

/// The ghost-extended lattice (`(nx + 2)(ny + 2)(nz + 2)` values, x fastest) and its dimensions.
pub(super) fn extended_lattice(data: &GridData) -> (Vec<f32>, [usize; 3]) {
    let [nx, ny, nz] = data.dims;
    let e = [nx + 2, ny + 2, nz + 2];
    let mut out = Vec::with_capacity(e[0] * e[1] * e[2]);
    for z in 0..e[2] {
        for y in 0..e[1] {
            for x in 0..e[0] {
                let interior =
                    (1..=nx).contains(&x) && (1..=ny).contains(&y) && (1..=nz).contains(&z);
                out.push(if interior {
                    data.at(x - 1, y - 1, z - 1)
                } else {
                    extended(data, x as isize - 1, y as isize - 1, z as isize - 1)
                });
            }
        }
    }
    (out, e)
}

/// A lattice of `dims` (x fastest) padded by one layer of a fill value on every side, so that every
/// point of the lattice has its 26 neighbours (the sweeps of the chessboard transform and of
/// redistancing read them without bounds tests).
pub(super) struct Padded<T> {
    /// The padded values, `(dims[0] + 2) × (dims[1] + 2) × (dims[2] + 2)`, x fastest.
    pub values: Vec<T>,
    dims: [usize; 3],
}

impl<T: Copy> Padded<T> {
    /// `values` (dimensions `dims`) surrounded by `fill`.
    pub fn new(values: &[T], dims: [usize; 3], fill: T) -> Self {
        let mut padded = Self {
            values: vec![fill; (dims[0] + 2) * (dims[1] + 2) * (dims[2] + 2)],
            dims,
        };
        let row = dims[0];
        for (r, line) in values.chunks_exact(row).enumerate() {
            let at = padded.index(0, r % dims[1], r / dims[1]);
            padded.values[at..at + row].copy_from_slice(line);
        }
        padded
    }

    /// The position of lattice point `(x, y, z)` (unpadded coordinates) in [`Padded::values`].
    #[inline(always)]
    pub fn index(&self, x: usize, y: usize, z: usize) -> usize {
        (x + 1) + (self.dims[0] + 2) * ((y + 1) + (self.dims[1] + 2) * (z + 1))
    }

    /// The steps in [`Padded::values`] from a point to its next neighbour along x, y and z.
    pub fn strides(&self) -> [usize; 3] {
        let px = self.dims[0] + 2;
        [1, px, px * (self.dims[1] + 2)]
    }

    /// The lattice without its padding.
    pub fn unpadded(&self) -> Vec<T> {
        let row = self.dims[0];
        let mut out = Vec::with_capacity(row * self.dims[1] * self.dims[2]);
        for z in 0..self.dims[2] {
            for y in 0..self.dims[1] {
                let at = self.index(0, y, z);
                out.extend_from_slice(&self.values[at..at + row]);
            }
        }
        out
    }
}

/// The maximum of `v` (dimensions `dims`, x fastest) over windows of `w` consecutive entries along `axis`:
/// the result has `dims[axis] − w + 1` entries along it.
fn window_max(v: &[f32], dims: [usize; 3], axis: usize, w: usize) -> (Vec<f32>, [usize; 3]) {
    let mut out_dims = dims;
    out_dims[axis] = dims[axis] + 1 - w;
    let stride = [1, dims[0], dims[0] * dims[1]];
    let row = out_dims[0];
    let mut out = vec![f32::NEG_INFINITY; out_dims.iter().product()];
    // Row by row (x fastest): each output row is the elementwise maximum of `w` input rows shifted
    // along `axis`, a loop the compiler vectorises.
    for (r, out_row) in out.chunks_exact_mut(row).enumerate() {
        let (y, z) = (r % out_dims[1], r / out_dims[1]);
        let first = y * stride[1] + z * stride[2];
        for k in 0..w {
            let start = first + k * stride[axis];
            for (o, &x) in out_row.iter_mut().zip(&v[start..start + row]) {
                *o = o.max(x);
            }
        }
    }
    (out, out_dims)
}

/// The maximum of `v` (dimensions `dims`, x fastest) over windows of `w[a]` entries along each axis `a`,
/// one per spline patch (`patch_dims` of them).
fn patch_windows(v: Vec<f32>, dims: [usize; 3], w: [usize; 3], patch_dims: [usize; 3]) -> Vec<f32> {
    let (mut m, mut d) = (v, dims);
    for (a, &w) in w.iter().enumerate() {
        (m, d) = window_max(&m, d, a, w);
    }
    debug_assert_eq!(d, patch_dims);
    m
}

/// Lipschitz bounds of a grid node over the outside (`φ ≥ 0`) and the inside (`φ ≤ 0`), from each spline
/// patch's own control points; `level` is the node's iso-level (the function is `spline − level`).
///
/// On the patch of lattice cell `i` (its 4×4×4 control points, ghosts included) the partial `∂_a φ` is a
/// quadratic-by-cubic B-spline whose control points are the patch's differences `(c_{i+1} − c_i)/h_a`, a
/// convex combination, so `|∂_a φ| ≤ L_a`, the largest of those. Inside the box `|∇φ|² ≤ Σ L_a²`; beyond
/// face `a` the gradient is `(±1 along a, the face patch's other partials)`, so `|∇φ|² ≤ Σ L_b² − L_a² + 1`
/// on the patches of that face (beyond an edge or a corner, less). The patch's bound is the largest of
/// these.
///
/// The value on a patch is a convex combination of its control points, so a patch whose control points
/// all lie above the level is entirely outside, and one whose points all lie below is entirely inside:
/// the outside bound is the largest over the patches with a control point at or above the level, the
/// inside bound over those with one at or below (patches on the box's faces count for both: beyond the
/// box the function grows by the distance to it, whatever the sign on the face). Sphere tracing outside
/// needs only the outside bound (the segment from a point to the nearest surface point lies outside). For
/// a distance field this matters: within the patches around its medial axis (the centre of a sphere)
/// the gradient turns through every direction and the bound is `√3`, but those lie inside the shape;
/// outside, the gradient is a unit vector turning slowly from patch to patch and the bound stays near 1.
pub(super) fn lipschitz_sided(
    data: &GridData,
    bmin: glam::Vec3,
    bmax: glam::Vec3,
    level: f32,
) -> (f32, f32) {
    if !data.usable() {
        return (1.0, 1.0);
    }
    let (mut outside, mut inside) = (0.0f32, 0.0f32);
    for patch in patch_lipschitz(data, &extended_lattice(data).0, bmin, bmax, level) {
        if patch.outside {
            outside = outside.max(patch.bound);
        }
        if patch.inside {
            inside = inside.max(patch.bound);
        }
    }
    // Both are at least 1: the face patches count for both sides, and beyond the box the function grows
    // by the distance to it.
    (outside, inside)
}

/// The Lipschitz bound of one spline patch (see [`lipschitz_sided`]) and the sides of the surface it
/// reaches.
#[derive(Copy, Clone, Debug)]
pub(super) struct PatchLipschitz {
    /// Bound of `|∇φ|` over the patch (and beyond the box's face, for a patch on it), with a few ulps
    /// of headroom: the bounds are tight and the tracer divides by them.
    pub bound: f32,
    /// Whether the patch can hold points outside (`φ ≥ 0`): a control point at or above the level, or
    /// a patch on the box's faces.
    pub outside: bool,
    /// Whether it can hold points inside (`φ ≤ 0`).
    pub inside: bool,
    /// Whether its control points lie on both sides of the level (or on it): only such a patch can
    /// hold the surface ([`straddling_cells`]).
    pub straddling: bool,
}

/// [`PatchLipschitz`] of every patch (lattice cell), x fastest, from `data`'s [`extended_lattice`]
/// `values`. `data` must be usable.
pub(super) fn patch_lipschitz(
    data: &GridData,
    values: &[f32],
    bmin: glam::Vec3,
    bmax: glam::Vec3,
    level: f32,
) -> Vec<PatchLipschitz> {
    let e = data.dims.map(|n| n + 2);
    let ext = bmax - bmin;
    let patch_dims = data.dims.map(|n| n - 1);
    let windows =
        |v: Vec<f32>, dims: [usize; 3], w: [usize; 3]| patch_windows(v, dims, w, patch_dims);
    let per_axis: [Vec<f32>; 3] = std::array::from_fn(|a| {
        let inv_h = inv_spacing(data.dims[a], ext[a]);
        // |differences| along `a`; a patch reads 3 of them along `a` and 4 across.
        let stride = [1, e[0], e[0] * e[1]][a];
        let mut dims = e;
        dims[a] -= 1;
        let mut diff = Vec::with_capacity(dims.iter().product());
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                for x in 0..dims[0] {
                    let i = x + e[0] * (y + e[1] * z);
                    diff.push((values[i + stride] - values[i]).abs() * inv_h);
                }
            }
        }
        let mut w = [4; 3];
        w[a] = 3;
        windows(diff, dims, w)
    });
    let highest = windows(values.iter().map(|v| v - level).collect(), e, [4; 3]);
    let lowest = windows(values.iter().map(|v| level - v).collect(), e, [4; 3]);
    let mut out = Vec::with_capacity(patch_dims.iter().product());
    let mut k = 0;
    for z in 0..patch_dims[2] {
        for y in 0..patch_dims[1] {
            for x in 0..patch_dims[0] {
                let sq = per_axis.each_ref().map(|m| m[k] * m[k]);
                let sum = sq[0] + sq[1] + sq[2];
                // Beyond face `a` (only patches on it reach there), `±1` replaces the partial along `a`.
                let mut bound = sum;
                let mut on_face = false;
                for (a, (&i, n)) in [x, y, z].iter().zip(patch_dims).enumerate() {
                    if i == 0 || i + 1 == n {
                        on_face = true;
                        bound = bound.max(sum - sq[a] + 1.0);
                    }
                }
                out.push(PatchLipschitz {
                    bound: bound.sqrt() * (1.0 + 1e-6),
                    outside: on_face || highest[k] >= 0.0,
                    inside: on_face || lowest[k] >= 0.0,
                    straddling: highest[k] >= 0.0 && lowest[k] >= 0.0,
                });
                k += 1;
            }
        }
    }
    out
}

/// A bound of the spline's second derivative along any unit direction, `|dᵀ H d| ≤ M`, over each patch
/// (lattice cell), x fastest, from `data`'s [`extended_lattice`] `values`; `data` must be usable.
///
/// On a patch, `∂_a∂_a φ` is a linear-by-cubic-by-cubic B-spline whose control points are the patch's
/// second differences `Δ_a² c / h_a²`, and `∂_a∂_b φ` (a ≠ b) a quadratic-by-quadratic-by-cubic one of
/// the mixed differences `Δ_a Δ_b c / (h_a h_b)`: convex combinations, so `|H_ab| ≤ B_ab`, the largest
/// of those. Then `|dᵀ H d| ≤ Σ_ab |d_a| |d_b| B_ab ≤ max_a Σ_b B_ab` (the largest row sum bounds the
/// spectral norm of the non-negative matrix `B`). A few ulps of headroom are added. Inside the box
/// only: beyond it the distance to the box adds its own curvature.
pub(super) fn patch_curvature(
    data: &GridData,
    values: &[f32],
    bmin: glam::Vec3,
    bmax: glam::Vec3,
) -> Vec<f32> {
    let e = data.dims.map(|n| n + 2);
    let ext = bmax - bmin;
    let patch_dims = data.dims.map(|n| n - 1);
    let inv_h: [f32; 3] = std::array::from_fn(|a| inv_spacing(data.dims[a], ext[a]));
    let stride = [1, e[0], e[0] * e[1]];
    // bound[a][b] per patch, for a ≤ b.
    let mut bound: [[Vec<f32>; 3]; 3] = Default::default();
    for a in 0..3 {
        for b in a..3 {
            let (sa, sb) = (stride[a], stride[b]);
            let mut dims = e;
            dims[a] -= 1;
            dims[b] -= 1;
            let mut w = [4; 3];
            w[a] -= 1;
            w[b] -= 1;
            let scale = inv_h[a] * inv_h[b];
            let mut diff = Vec::with_capacity(dims.iter().product());
            for z in 0..dims[2] {
                for y in 0..dims[1] {
                    for x in 0..dims[0] {
                        let i = x + e[0] * (y + e[1] * z);
                        let d = values[i + sa + sb] - values[i + sa] - values[i + sb] + values[i];
                        diff.push(d.abs() * scale);
                    }
                }
            }
            bound[a][b] = patch_windows(diff, dims, w, patch_dims);
        }
    }
    (0..patch_dims.iter().product::<usize>())
        .map(|k| {
            let b = |a: usize, c: usize| bound[a.min(c)][a.max(c)][k];
            let rows = [0, 1, 2].map(|a| b(a, 0) + b(a, 1) + b(a, 2));
            rows[0].max(rows[1]).max(rows[2]) * (1.0 + 1e-5)
        })
        .collect()
}

/// `min` over the ghost-extended 2-D lattice of one face layer: a lower bound of the spline on that face
/// (the face value is the 2-D spline of the layer, a convex combination of its extended control points).
fn face_min(get: impl Fn(usize, usize) -> f32, n1: usize, n2: usize) -> f32 {
    let ext = |f: &dyn Fn(usize) -> f32, n: usize, i: isize| -> f32 {
        if i < 0 {
            2.0 * f(0) - f(1)
        } else if i as usize >= n {
            2.0 * f(n - 1) - f(n - 2)
        } else {
            f(i as usize)
        }
    };
    let mut m = f32::INFINITY;
    for i in -1..=n1 as isize {
        for j in -1..=n2 as isize {
            let v = ext(&|a| ext(&|b| get(a, b), n2, j), n1, i);
            m = m.min(v);
        }
    }
    m
}

/// Whether the spline may take the value `level` on each lattice cell (x fastest, `n − 1` cells per
/// axis): whether the cell's 4×4×4 control points (ghosts included) straddle the level. The spline on a
/// cell is a convex combination of them, so every other cell lies strictly on one side.
pub(super) fn straddling_cells(data: &GridData, level: f32) -> Vec<bool> {
    let (values, e) = extended_lattice(data);
    let patch_dims = data.dims.map(|n| n - 1);
    let highest = patch_windows(
        values.iter().map(|v| v - level).collect(),
        e,
        [4; 3],
        patch_dims,
    );
    let lowest = patch_windows(
        values.iter().map(|v| level - v).collect(),
        e,
        [4; 3],
        patch_dims,
    );
    highest
        .iter()
        .zip(&lowest)
        .map(|(&h, &l)| h >= 0.0 && l >= 0.0)
        .collect()
}

/// The least value of the spline on the grid box's faces (a lower bound: each face's ghost-extended
/// control points). Below `level`, the surface reaches beyond the box.
pub(super) fn faces_min(data: &GridData) -> f32 {
    let [nx, ny, nz] = data.dims;
    let mut m = f32::INFINITY;
    for x in [0, nx - 1] {
        m = m.min(face_min(|y, z| data.at(x, y, z), ny, nz));
    }
    for y in [0, ny - 1] {
        m = m.min(face_min(|x, z| data.at(x, y, z), nx, nz));
    }
    for z in [0, nz - 1] {
        m = m.min(face_min(|x, y| data.at(x, y, z), nx, ny));
    }
    m
}

/// Culling box of a grid node ([`Sdf::cull_bounds`]): the grid box, grown by how far the face values go
/// below `level`. Outside it `φ = φ(face) + dist(p, grid box) ≥ dist(p, grid box) − (level − m)`, which
/// is at least the distance to the grown box (a box grown by `g` per axis holds the `g`-neighbourhood);
/// the tighter [`bounds`] of the straddling cells has no such property (inside the grid box the spline
/// is no distance).
pub(super) fn cull_bounds(data: &GridData, bmin: glam::Vec3, bmax: glam::Vec3, level: f32) -> Aabb {
    face_grown_box(data, bmin, bmax, level).map_or(Aabb::EMPTY, |(b, _)| b)
}

/// The grid box grown by how far the face values go below `level`, and whether it was grown (`None`
/// for an unusable grid).
fn face_grown_box(
    data: &GridData,
    bmin: glam::Vec3,
    bmax: glam::Vec3,
    level: f32,
) -> Option<(Aabb, bool)> {
    if !data.usable() {
        return None;
    }
    let m = faces_min(data);
    let b = Aabb::new(bmin, bmax);
    let pad = 1e-6 * b.extent().max_element();
    Some(if m < level {
        (b.expanded(level - m + pad), true)
    } else {
        (b, false)
    })
}

/// Box of a grid node of iso-level `level`. Where the spline gets below `level` on the grid box's faces,
/// the grid box grown by how far below (outside, `φ = φ(face) + distance`, so a face value `level − m`
/// puts zeros up to `m` beyond the face). Otherwise every zero lies in a cell whose 4×4×4 control
/// points straddle the level (the spline on a cell is a convex combination of them): the box of those
/// cells, often far smaller than the grid box (a baked shape is sampled over padded bounds), so rays
/// that pass beside the surface skip the shape.
pub(super) fn bounds(data: &GridData, bmin: glam::Vec3, bmax: glam::Vec3, level: f32) -> Aabb {
    let Some((b, grown)) = face_grown_box(data, bmin, bmax, level) else {
        return Aabb::EMPTY;
    };
    if grown {
        return b;
    }
    let pad = 1e-6 * b.extent().max_element();
    let patch_dims = data.dims.map(|n| n - 1);
    let straddling = straddling_cells(data, level);
    // Cell `(x, y, z)` spans lattice coordinates `[x, x + 1] × …`, patch `k` in x-fastest order.
    let (mut lo, mut hi) = ([usize::MAX; 3], [0usize; 3]);
    let mut k = 0;
    for z in 0..patch_dims[2] {
        for y in 0..patch_dims[1] {
            for x in 0..patch_dims[0] {
                if straddling[k] {
                    for (a, i) in [x, y, z].into_iter().enumerate() {
                        lo[a] = lo[a].min(i);
                        hi[a] = hi[a].max(i + 1);
                    }
                }
                k += 1;
            }
        }
    }
    if lo[0] == usize::MAX {
        // No cell holds the level: no surface (the grid box, as before, for callers that need one).
        return b.expanded(pad);
    }
    let h = (bmax - bmin) / glam::Vec3::from(patch_dims.map(|n| n.max(1) as f32));
    let at = |i: [usize; 3]| bmin + h * glam::Vec3::from(i.map(|v| v as f32));
    Aabb::new(at(lo).max(bmin), at(hi).min(bmax)).expanded(pad)
}

/// The declaration of the grid node's fields ([`crate::declare`]).
pub(super) mod kinds {
    use crate::declare::{Field, Kind, Rule, Value, on};
    use crate::error::Error;
    use crate::scalar::{BlockValues, Param};
    use crate::sdf::{GridData, Sdf, read_npy};
    use std::sync::Arc;

    /// `{"type": "grid", "file": ".npy of shape [nz, ny, nx]", "bbox_min", "bbox_max", "level"
    /// (default 0)}`.
    pub(in crate::sdf) const GRID: Kind<Sdf> = Kind {
        type_name: "grid",
        fields: &[
            Field {
                key: "file",
                value: Value::File { load: load_grid },
            },
            Field {
                key: "bbox_min",
                value: Value::Fixed {
                    access: on!(Sdf::Grid { bbox_min, .. } => bbox_min),
                    after: None,
                },
            },
            Field {
                key: "bbox_max",
                value: Value::Fixed {
                    access: on!(Sdf::Grid { bbox_max, .. } => bbox_max),
                    after: Some(|n| {
                        let Sdf::Grid {
                            bbox_min, bbox_max, ..
                        } = n
                        else {
                            unreachable!("a grid's rule")
                        };
                        if bbox_max.cmpgt(*bbox_min).all() {
                            return Ok(());
                        }
                        let fmt = |v: glam::Vec3| format!("[{}, {}, {}]", v.x, v.y, v.z);
                        Err(format!(
                            "must exceed bbox_min {} in every component, got {}",
                            fmt(*bbox_min),
                            fmt(*bbox_max)
                        ))
                    }),
                },
            },
            Field::number(
                "level",
                on!(Sdf::Grid { level, .. } => level),
                Some(0.0),
                Rule::Any,
            ),
        ],
        blank: || Sdf::Grid {
            data: Arc::new(GridData {
                dims: [0; 3],
                values: Vec::new(),
            }),
            bbox_min: glam::Vec3::ZERO,
            bbox_max: glam::Vec3::ZERO,
            level: Param::new(0.0),
            selection: BlockValues::Constant,
        },
        example: r#"{"type": "grid", "file": "example_grid.npy", "bbox_min": [-1, -0.5, -1], "bbox_max": [1, 1.5, 1], "level": 0.05}"#,
    };

    /// Reads a grid's `.npy` into the node and checks it (at least 4 samples per axis, finite values).
    fn load_grid(node: &mut Sdf, file: &std::path::Path) -> Result<(), String> {
        let data = read_npy(file).map_err(|e| match e {
            // The reader's own message names the file already when it is a file error.
            Error::File { message, .. } => message,
            e => e.to_string(),
        })?;
        check_grid(&data)?;
        let Sdf::Grid { data: slot, .. } = node else {
            unreachable!("a grid's file")
        };
        *slot = Arc::new(data);
        Ok(())
    }

    /// What a grid must satisfy beyond being a float32 3-D array: enough samples for a cubic B-spline
    /// and finite values.
    fn check_grid(data: &GridData) -> Result<(), String> {
        let [nx, ny, nz] = data.dims;
        if data.dims.iter().any(|&n| n < 4) {
            return Err(format!(
                "needs at least 4 samples along each axis, got shape [{nz}, {ny}, {nx}] (z, y, x)"
            ));
        }
        if data.values.len() != nx * ny * nz {
            return Err(format!(
                "holds {} values, expected {} for shape [{nz}, {ny}, {nx}]",
                data.values.len(),
                nx * ny * nz
            ));
        }
        if let Some(i) = data.values.iter().position(|v| !v.is_finite()) {
            return Err(format!("value {i} is not finite ({})", data.values[i]));
        }
        Ok(())
    }
}
