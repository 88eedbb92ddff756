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
//! indices). The Lipschitz bound takes the extended lattice's differences (see `axis_lipschitz`).
//!
//! Outside the box: `φ(x) = φ(clamp(x)) + |x − clamp(x)|`, a valid bound for sphere tracing.

use super::GridData;
use crate::error::{Error, Result};
use crate::math::{Aabb, Vec3};
use crate::scalar::{GridValues, LatticeTaps, Scalar, lattice_sum_nested};

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
    let i = (u.primal().floor().max(0.0) as usize).min(n - 2);
    let t = u - i as f32;
    let t2 = t * t;
    let t3 = t2 * t;
    let s = S::one() - t;
    // Uniform cubic B-spline basis on [0, 1] (de Boor): taps i − 1, i, i + 1, i + 2.
    let sixth = 1.0 / 6.0;
    let b0 = s * s * s * sixth;
    let b1 = (t3 * 3.0 - t2 * 6.0 + 4.0) * sixth;
    let b2 = (t2 * 3.0 + t * 3.0 - t3 * 3.0 + 1.0) * sixth;
    let b3 = t3 * sixth;
    if i == 0 {
        // Ghost c_{−1} = 2c_0 − c_1.
        ([0, 1, 2, 3], [b1 + b0 * 2.0, b2 - b0, b3, S::zero()])
    } else if i == n - 2 {
        // Ghost c_n = 2c_{n−1} − c_{n−2}.
        (
            [n - 3, n - 2, n - 1, n - 1],
            [b0, b1 - b3, b2 + b3 * 2.0, S::zero()],
        )
    } else {
        ([i - 1, i, i + 1, i + 2], [b0, b1, b2, b3])
    }
}

/// The B-spline at `q`, which must lie in the box, with the derivative of the values that `selection`
/// asks for (a forward-mode direction adds `ε_slot · Σ w u`; a reverse-mode block is recorded by
/// [`Scalar::lattice_sum`]).
#[inline(always)]
fn spline<S: Scalar>(
    data: &GridData,
    bmin: glam::Vec3,
    bmax: glam::Vec3,
    selection: &GridValues,
    q: Vec3<S>,
) -> S {
    let ext = bmax - bmin;
    let taps = |a: usize, c: S| {
        let n = data.dims[a];
        // A flat box has one position along that axis: sit on its first layer.
        let inv_h = if ext[a] > 0.0 {
            (n - 1) as f32 / ext[a]
        } else {
            0.0
        };
        axis_taps((c - bmin[a]) * inv_h, n)
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
        GridValues::Direction { slot, u } if u.len() == data.values.len() => {
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
    selection: &GridValues,
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

/// Per-axis bounds `L_a = max |c_{i+1} − c_i| / h_a` over the ghost-extended lattice. Along axis `a` the
/// ghost differences repeat the first and last ones, but the ghost layers of the *other* axes carry
/// extrapolated differences (`2Δ_0 − Δ_1`), which can be larger: they are included.
fn axis_lipschitz(data: &GridData, bmin: glam::Vec3, bmax: glam::Vec3) -> [f32; 3] {
    let [nx, ny, nz] = data.dims;
    let mut m = [0.0f32; 3];
    let ghost = |i: usize, n: usize| i == 0 || i == n + 1;
    // Interior points (no ghost index) read the array directly; only ghost layers recurse.
    let value = |x: usize, y: usize, z: usize| {
        if ghost(x, nx) || ghost(y, ny) || ghost(z, nz) {
            extended(data, x as isize - 1, y as isize - 1, z as isize - 1)
        } else {
            data.at(x - 1, y - 1, z - 1)
        }
    };
    for z in 0..nz + 2 {
        for y in 0..ny + 2 {
            for x in 0..nx + 2 {
                let c = value(x, y, z);
                if x + 1 < nx + 2 {
                    m[0] = m[0].max((value(x + 1, y, z) - c).abs());
                }
                if y + 1 < ny + 2 {
                    m[1] = m[1].max((value(x, y + 1, z) - c).abs());
                }
                if z + 1 < nz + 2 {
                    m[2] = m[2].max((value(x, y, z + 1) - c).abs());
                }
            }
        }
    }
    let ext = bmax - bmin;
    std::array::from_fn(|a| {
        if ext[a] > 0.0 {
            m[a] * (data.dims[a] - 1) as f32 / ext[a]
        } else {
            0.0
        }
    })
}

/// Lipschitz bound of a grid node, exact for the spline.
///
/// The partial `∂_a φ` of a cubic B-spline is a quadratic B-spline (times cubic ones) whose control points
/// are `(c_{i+1} − c_i)/h_a`, a convex combination, so `|∂_a φ| ≤ L_a`. Inside the box
/// `|∇φ|² ≤ Σ L_a²`; beyond face `a` the gradient is `(±1 along a, the other partials)`, so
/// `|∇φ|² ≤ Σ L_a² − L_a² + 1` (edges and corners give less). Hence `L = sqrt(Σ L_a² + max(0, 1 − min L_a²))`
/// (not just `max(1, sqrt(Σ L_a²))`: a planar field `φ = x` has `|∇φ| = √2` beyond a `y` face).
pub(super) fn lipschitz(data: &GridData, bmin: glam::Vec3, bmax: glam::Vec3) -> f32 {
    if !data.usable() {
        return 1.0;
    }
    let l = axis_lipschitz(data, bmin, bmax);
    let sum: f32 = l.iter().map(|v| v * v).sum();
    let min = l.iter().map(|v| v * v).fold(f32::INFINITY, f32::min);
    // A few ulps of headroom: the bound is tight and the tracer divides by it.
    (sum + (1.0 - min).max(0.0)).sqrt() * (1.0 + 1e-6)
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

/// Box of a grid node of iso-level `level`: the grid box, grown by how far below `level` the spline gets
/// on its faces (outside, `φ = φ(face) + distance`, so a face value `level − m` puts zeros up to `m`
/// beyond the face).
pub(super) fn bounds(data: &GridData, bmin: glam::Vec3, bmax: glam::Vec3, level: f32) -> Aabb {
    if !data.usable() {
        return Aabb::EMPTY;
    }
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
    let b = Aabb::new(bmin, bmax);
    b.expanded((level - m).max(0.0) + 1e-6 * b.extent().max_element())
}
