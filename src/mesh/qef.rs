//! The quadratic error function of dual contouring (Ju et al. 2002, "Dual Contouring of Hermite
//! Data", §2.3): the point `x` minimising `Σ_i (n_i · (x − p_i))²` over the tangent planes `(p_i, n_i)`
//! of a cell's edge crossings.
//!
//! The normal equations `AᵀA x = Aᵀb` are singular on flat and ridge-like cells (one or two distinct
//! normals), so they are solved about the mass point `m` (the crossings' mean) with the
//! pseudo-inverse of `AᵀA`, eigenvalues below a fraction of the largest dropped (Lindstrom 2000,
//! "Out-of-core simplification of large polygonal models", the truncation Ju et al. use): on a face
//! the vertex stays at `m` along the face, on an edge it moves onto the edge, at a corner onto the
//! corner.

use glam::{DMat3, DVec3};

/// Eigenvalues below this fraction of the largest are treated as zero.
const TRUNCATION: f64 = 0.05;

/// Accumulated tangent planes of one cell.
#[derive(Clone, Debug)]
pub(crate) struct Qef {
    ata: DMat3,
    atb: DVec3,
    mass: DVec3,
    count: u32,
}

impl Default for Qef {
    /// No plane (glam's default matrix is the identity, not zero).
    fn default() -> Self {
        Self {
            ata: DMat3::ZERO,
            atb: DVec3::ZERO,
            mass: DVec3::ZERO,
            count: 0,
        }
    }
}

impl Qef {
    /// Adds the tangent plane through `p` with unit normal `n`.
    pub(crate) fn add(&mut self, p: DVec3, n: DVec3) {
        self.ata += DMat3::from_cols(n * n.x, n * n.y, n * n.z);
        self.atb += n * n.dot(p);
        self.mass += p;
        self.count += 1;
    }

    /// The crossings' mean.
    pub(crate) fn mass_point(&self) -> DVec3 {
        self.mass / self.count.max(1) as f64
    }

    /// The minimiser nearest the mass point (module docs).
    pub(crate) fn solve(&self) -> DVec3 {
        let m = self.mass_point();
        let (values, vectors) = symmetric_eigen(self.ata);
        let largest = values.max_element();
        if largest <= 0.0 {
            return m;
        }
        let residual = self.atb - self.ata * m;
        let mut x = m;
        for k in 0..3 {
            if values[k] > TRUNCATION * largest {
                let v = vectors.col(k);
                x += v * (v.dot(residual) / values[k]);
            }
        }
        x
    }
}

/// Eigenvalues and eigenvectors (columns) of the symmetric 3×3 matrix `a`, by cyclic Jacobi rotations
/// (Golub and Van Loan, "Matrix Computations", §8.5): converges quadratically; a few sweeps reach
/// rounding.
pub(crate) fn symmetric_eigen(a: DMat3) -> (DVec3, DMat3) {
    // m[r][c] and v[r][c], row by row (`a` is symmetric, so its columns are its rows).
    let mut m = a.to_cols_array_2d();
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..16 {
        let off = m[0][1].powi(2) + m[0][2].powi(2) + m[1][2].powi(2);
        let scale = m[0][0].powi(2) + m[1][1].powi(2) + m[2][2].powi(2);
        if off <= 1e-30 * scale.max(1e-300) {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if m[p][q] == 0.0 {
                continue;
            }
            let theta = (m[q][q] - m[p][p]) / (2.0 * m[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            // m ← Jᵀ m J and v ← v J for the rotation J in the (p, q) plane.
            for row in &mut m {
                let (a, b) = (row[p], row[q]);
                row[p] = c * a - s * b;
                row[q] = s * a + c * b;
            }
            let (row_p, row_q) = (m[p], m[q]);
            m[p] = std::array::from_fn(|k| c * row_p[k] - s * row_q[k]);
            m[q] = std::array::from_fn(|k| s * row_p[k] + c * row_q[k]);
            for row in &mut v {
                let (a, b) = (row[p], row[q]);
                row[p] = c * a - s * b;
                row[q] = s * a + c * b;
            }
        }
    }
    let values = DVec3::new(m[0][0], m[1][1], m[2][2]);
    // Eigenvector k is column k of v.
    (values, DMat3::from_cols_array_2d(&v).transpose())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigen_decomposition_reconstructs_the_matrix() {
        let a = DMat3::from_cols(
            DVec3::new(4.0, 1.0, -2.0),
            DVec3::new(1.0, 3.0, 0.5),
            DVec3::new(-2.0, 0.5, 5.0),
        );
        let (values, vectors) = symmetric_eigen(a);
        let back = vectors * DMat3::from_diagonal(values) * vectors.transpose();
        for (x, y) in back.to_cols_array().iter().zip(a.to_cols_array()) {
            assert!((x - y).abs() < 1e-12, "{back} vs {a}");
        }
        let identity = vectors.transpose() * vectors;
        assert!((identity - DMat3::IDENTITY).abs_diff_eq(DMat3::ZERO, 1e-12));
    }

    #[test]
    fn three_planes_meet_at_the_corner_two_on_the_edge_one_at_the_mass_point() {
        let corner = DVec3::new(0.5, 0.4, 0.3);
        let mut q = Qef::default();
        // Crossings on three faces of a box corner, off the corner.
        q.add(DVec3::new(0.5, 0.1, 0.0), DVec3::X);
        q.add(DVec3::new(0.2, 0.4, 0.1), DVec3::Y);
        q.add(DVec3::new(0.1, 0.2, 0.3), DVec3::Z);
        assert!((q.solve() - corner).length() < 1e-12, "{}", q.solve());

        let mut edge = Qef::default();
        edge.add(DVec3::new(0.5, 0.1, 0.0), DVec3::X);
        edge.add(DVec3::new(0.2, 0.4, 0.2), DVec3::Y);
        let x = edge.solve();
        assert!(
            (x.x - 0.5).abs() < 1e-12 && (x.y - 0.4).abs() < 1e-12,
            "{x}"
        );
        assert!(
            (x.z - 0.1).abs() < 1e-12,
            "stays at the mass point along the edge: {x}"
        );

        let mut face = Qef::default();
        face.add(DVec3::new(0.5, 0.1, 0.0), DVec3::X);
        face.add(DVec3::new(0.5, 0.3, 0.2), DVec3::X);
        assert!((face.solve() - DVec3::new(0.5, 0.2, 0.1)).length() < 1e-12);
    }
}
