//! The one operation of a grid SDF that touches its values: a separable weighted sum over a 4×4×4 block
//! of the lattice (the cubic B-spline at a point), as a [`Scalar`] method so that a reverse-mode type can
//! record it as a single tape entry whose operands are the 64 values, not 64 leaves.

use super::{Scalar, Slot};

/// The taps of a tensor-product cubic B-spline at one point: per axis (x, y, z) four lattice indices and
/// their weights. Ghost layers are already folded in, so an index may repeat (with the extra weight 0).
#[derive(Copy, Clone, Debug)]
pub struct LatticeTaps<S> {
    /// Lattice indices per axis: `index[0]` along x, `index[1]` along y, `index[2]` along z.
    pub index: [[usize; 4]; 3],
    /// The weights of those indices, per axis.
    pub weight: [[S; 4]; 3],
}

impl<S: Copy> LatticeTaps<S> {
    /// The same indices with every weight mapped by `f(axis, weight)`.
    #[inline(always)]
    pub fn map<T>(&self, mut f: impl FnMut(usize, S) -> T) -> LatticeTaps<T> {
        LatticeTaps {
            index: self.index,
            weight: std::array::from_fn(|a| self.weight[a].map(|w| f(a, w))),
        }
    }
}

/// A grid lookup's `f32` jet at a point, with its taps: what [`Scalar::lattice_jet`] builds a lookup
/// at a moving point from. Derivatives are per unit length of the grid's frame.
#[derive(Clone, Debug)]
pub struct LatticeJet<'a> {
    /// The spline's value (the image's bits).
    pub value: f32,
    /// Its gradient.
    pub gradient: [f32; 3],
    /// Its Hessian, `hessian[a][b] = ∂a ∂b φ`.
    pub hessian: [[f32; 3]; 3],
    /// The taps at the point, with the value's weights.
    pub taps: LatticeTaps<f32>,
    /// Each axis's weights differentiated along that axis.
    pub deriv: [[f32; 4]; 3],
    /// The lattice's values (x fastest).
    pub values: &'a [f32],
    /// The lattice's dimensions `[nx, ny, nz]`.
    pub dims: [usize; 3],
    /// The reverse-mode block of the values ([`BlockValues::block`]).
    pub block: Slot,
}

/// How the values of a parameter block (a grid's samples, a volume texture's texels) are
/// differentiated in the current pass.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum BlockValues {
    /// The values are constants.
    #[default]
    Constant,
    /// Forward mode: the derivative along a perturbation `u` of the values (same layout and length),
    /// fed into derivative slot `slot`.
    Direction {
        /// The derivative slot (as a named parameter's).
        slot: u32,
        /// The perturbation of each value.
        u: std::sync::Arc<Vec<f32>>,
    },
    /// Reverse mode: value `i` is gradient entry `first + i`.
    Gradient {
        /// The gradient entry of the first value.
        first: u32,
    },
}

/// The former name of [`BlockValues`] (grids were the first kind of block).
pub type GridValues = BlockValues;

impl BlockValues {
    /// The reverse-mode block of [`Scalar::lattice_sum`]: the first gradient entry, if any.
    #[inline]
    pub fn block(&self) -> Slot {
        match self {
            BlockValues::Gradient { first } => Some(*first),
            _ => None,
        }
    }
}

/// `Σ_a wx[a] · Σ_c wz[c] Σ_b wy[b] · values[(iz[c] · ny + iy[b]) · nx + ix[a]]`: the four x taps are
/// carried side by side through the sums over y and z (as four SIMD lanes in [`lattice_sum_f32`]) and
/// contracted with the x weights last. The order of the floating-point operations is part of the
/// image's bit-for-bit contract: every type's primal follows it exactly.
#[inline(always)]
pub fn lattice_sum_nested<S: Scalar>(
    taps: &LatticeTaps<S>,
    values: &[f32],
    nx: usize,
    ny: usize,
) -> S {
    let [ix, iy, iz] = taps.index;
    let [wx, wy, wz] = taps.weight;
    let mut acc = [S::zero(); 4];
    for c in 0..4 {
        let mut acc_y = [S::zero(); 4];
        for b in 0..4 {
            let row = (iz[c] * ny + iy[b]) * nx;
            for a in 0..4 {
                acc_y[a] += wy[b] * values[row + ix[a]];
            }
        }
        for a in 0..4 {
            acc[a] += wz[c] * acc_y[a];
        }
    }
    wx[0] * acc[0] + wx[1] * acc[1] + wx[2] * acc[2] + wx[3] * acc[3]
}

/// [`lattice_sum_nested`] in `f32`, bit for bit, with each row's four x taps loaded and weighted as one
/// 4-lane vector when they are consecutive (as the grid's taps always are): a quarter of the loads
/// and arithmetic instructions of the scalar sum.
#[inline(always)]
pub fn lattice_sum_f32(taps: &LatticeTaps<f32>, values: &[f32], nx: usize, ny: usize) -> f32 {
    let [ix, iy, iz] = taps.index;
    let [wx, wy, wz] = taps.weight;
    let x0 = ix[0];
    if ix != [x0, x0 + 1, x0 + 2, x0 + 3] {
        return lattice_sum_nested(taps, values, nx, ny);
    }
    let mut acc = glam::Vec4::ZERO;
    for c in 0..4 {
        let mut acc_y = glam::Vec4::ZERO;
        for b in 0..4 {
            let row = (iz[c] * ny + iy[b]) * nx + x0;
            acc_y += glam::Vec4::from_slice(&values[row..row + 4]) * wy[b];
        }
        acc += acc_y * wz[c];
    }
    let r = acc.to_array();
    wx[0] * r[0] + wx[1] * r[1] + wx[2] * r[2] + wx[3] * r[3]
}

/// The four sums a spatially seeded lookup needs, at once: [`lattice_sum_f32`] with `taps`' weights,
/// then with the x, the y and the z weights replaced by `deriv[0]`, `deriv[1]` and `deriv[2]` (the
/// weights' derivatives along their own axis), each bit for bit as [`lattice_sum_f32`] computes it
/// (the value shares its y and z sums with the x derivative and its y sums with the z derivative).
/// `None` unless the x taps are consecutive.
#[inline(always)]
pub fn lattice_sums_with_derivatives_f32(
    taps: &LatticeTaps<f32>,
    deriv: &[[f32; 4]; 3],
    values: &[f32],
    nx: usize,
    ny: usize,
) -> Option<[f32; 4]> {
    let [ix, iy, iz] = taps.index;
    let [wx, wy, wz] = taps.weight;
    let [dx, dy, dz] = *deriv;
    let x0 = ix[0];
    if ix != [x0, x0 + 1, x0 + 2, x0 + 3] {
        return None;
    }
    let (mut acc, mut acc_dy, mut acc_dz) = (glam::Vec4::ZERO, glam::Vec4::ZERO, glam::Vec4::ZERO);
    for c in 0..4 {
        let (mut acc_y, mut acc_y_dy) = (glam::Vec4::ZERO, glam::Vec4::ZERO);
        for b in 0..4 {
            let row = (iz[c] * ny + iy[b]) * nx + x0;
            let v = glam::Vec4::from_slice(&values[row..row + 4]);
            acc_y += v * wy[b];
            acc_y_dy += v * dy[b];
        }
        acc += acc_y * wz[c];
        acc_dy += acc_y_dy * wz[c];
        acc_dz += acc_y * dz[c];
    }
    let contract = |w: [f32; 4], r: glam::Vec4| {
        let r = r.to_array();
        w[0] * r[0] + w[1] * r[1] + w[2] * r[2] + w[3] * r[3]
    };
    Some([
        contract(wx, acc),
        contract(dx, acc),
        contract(wx, acc_dy),
        contract(wx, acc_dz),
    ])
}
