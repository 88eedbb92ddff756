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

/// `Σ_c wz[c] Σ_b wy[b] Σ_a wx[a] · values[(iz[c] · ny + iy[b]) · nx + ix[a]]`, nested in this order
/// (the order of the floating-point operations is part of the image's bit-for-bit contract).
#[inline(always)]
pub fn lattice_sum_nested<S: Scalar>(
    taps: &LatticeTaps<S>,
    values: &[f32],
    nx: usize,
    ny: usize,
) -> S {
    let [ix, iy, iz] = taps.index;
    let [wx, wy, wz] = taps.weight;
    let mut acc = S::zero();
    for c in 0..4 {
        let mut acc_y = S::zero();
        for b in 0..4 {
            let row = (iz[c] * ny + iy[b]) * nx;
            let v = &values[row..row + nx];
            let acc_x = wx[0] * v[ix[0]] + wx[1] * v[ix[1]] + wx[2] * v[ix[2]] + wx[3] * v[ix[3]];
            acc_y += wy[b] * acc_x;
        }
        acc += wz[c] * acc_y;
    }
    acc
}
