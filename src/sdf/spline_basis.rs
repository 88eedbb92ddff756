//! The uniform cubic B-spline's basis on a grid's lattice, shared by the lookups in every number
//! type ([`super::grid`]) and the `f32` value, gradient and Hessian from the taps
//! ([`super::grid_jet`]): the basis and its slope, the lattice spacing, the ghost layers folded into
//! the weights, and the cells of a point with the three axes in the lanes of a vector.

/// The uniform cubic B-spline basis on `[0, 1]` (de Boor) at `t`, given `s = 1 − t`: the weights of taps
/// `i − 1, i, i + 1, i + 2`. One formula for every type that evaluates it (a scalar type, `f32`, or the
/// three axes side by side in a vector), so that all give the same bits.
#[inline(always)]
pub(super) fn cubic_basis<T>(t: T, s: T) -> [T; 4]
where
    T: Copy
        + std::ops::Add<Output = T>
        + std::ops::Sub<Output = T>
        + std::ops::Mul<Output = T>
        + std::ops::Add<f32, Output = T>
        + std::ops::Mul<f32, Output = T>,
{
    let t2 = t * t;
    let t3 = t2 * t;
    let sixth = 1.0 / 6.0;
    [
        s * s * s * sixth,
        (t3 * 3.0 - t2 * 6.0 + 4.0) * sixth,
        (t2 * 3.0 + t * 3.0 - t3 * 3.0 + 1.0) * sixth,
        t3 * sixth,
    ]
}

/// The derivatives in `t` of [`cubic_basis`], given `s = 1 − t`; like it, one formula for `f32` and
/// for the three axes side by side in a vector.
#[inline(always)]
pub(super) fn cubic_basis_slope<T>(t: T, s: T) -> [T; 4]
where
    T: Copy
        + std::ops::Add<Output = T>
        + std::ops::Sub<Output = T>
        + std::ops::Mul<Output = T>
        + std::ops::Add<f32, Output = T>
        + std::ops::Mul<f32, Output = T>,
{
    let t2 = t * t;
    [
        s * -0.5 * s,
        t2 * 1.5 - t * 2.0,
        t2 * -1.5 + t + 0.5,
        t2 * 0.5,
    ]
}

/// Lattice cells per unit length along an axis of `n` points spanning `ext`; 0 for a flat box (one
/// position along that axis: the spline sits on its first layer).
#[inline(always)]
pub(super) fn inv_spacing(n: usize, ext: f32) -> f32 {
    if ext > 0.0 { (n - 1) as f32 / ext } else { 0.0 }
}

/// The lattice indices of the four taps of cell `i` (of `n ≥ 4` points) with the weights `b` of taps
/// `i − 1 ..= i + 2` (any linear quantity: the basis or its derivatives), the ghost points folded in.
#[inline(always)]
pub(super) fn fold_ghosts<T>(i: usize, n: usize, b: [T; 4], zero: T) -> ([usize; 4], [T; 4])
where
    T: Copy
        + std::ops::Add<Output = T>
        + std::ops::Sub<Output = T>
        + std::ops::Mul<f32, Output = T>,
{
    let [b0, b1, b2, b3] = b;
    if i == 0 {
        // Ghost c_{−1} = 2c_0 − c_1.
        ([0, 1, 2, 3], [b1 + b0 * 2.0, b2 - b0, b3, zero])
    } else if i == n - 2 {
        // Ghost c_n = 2c_{n−1} − c_{n−2}; the taps stay four consecutive indices (the first with
        // weight 0) so that a row of them is one vector load.
        (
            [n - 4, n - 3, n - 2, n - 1],
            [zero, b0, b1 - b3, b2 + b3 * 2.0],
        )
    } else {
        ([i - 1, i, i + 1, i + 2], [b0, b1, b2, b3])
    }
}

/// The cells of the three axes at a point of a grid's box, with the axes side by side in the lanes of
/// a vector (the fourth lane unused): the same operations, lane by lane, as the grid's `axis_taps` in `f32`.
pub(super) struct LaneCells {
    /// Each axis's cell: the index of its first lattice point.
    pub cell: [usize; 3],
    /// The position within the cell, in `[0, 1]` per axis.
    pub t: glam::Vec4,
    /// Lattice points per unit length along each axis.
    pub inv_h: glam::Vec4,
}

impl LaneCells {
    /// At `q` in the box `[lo, lo + ext]` of a lattice of `dims` (each at least 4) points.
    #[inline(always)]
    pub fn at(dims: [usize; 3], lo: glam::Vec3, ext: glam::Vec3, q: glam::Vec3) -> Self {
        let [nx, ny, nz] = dims;
        let inv_h = glam::Vec4::new(
            inv_spacing(nx, ext.x),
            inv_spacing(ny, ext.y),
            inv_spacing(nz, ext.z),
            0.0,
        );
        let u = (glam::Vec4::from((q, 0.0)) - glam::Vec4::from((lo, 0.0))) * inv_h;
        // As `axis_taps`: truncation (saturating NaN and negatives to 0), then the last cell.
        let cell = [
            (u.x as usize).min(nx - 2),
            (u.y as usize).min(ny - 2),
            (u.z as usize).min(nz - 2),
        ];
        let t = u - glam::Vec4::new(cell[0] as f32, cell[1] as f32, cell[2] as f32, 0.0);
        Self { cell, t, inv_h }
    }
}
