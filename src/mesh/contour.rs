//! Dual contouring (Ju, Losasso, Schaefer and Warren 2002, "Dual Contouring of Hermite Data") of a
//! signed distance on a uniform lattice: one vertex per cell whose corners change sign, placed where
//! the tangent planes of the cell's edge crossings meet ([`super::qef`]), and one quad per lattice
//! edge whose ends change sign, joining the four cells around it. Unlike marching cubes, a vertex can
//! sit on a crease or a corner inside its cell, so the sharp edges of boxes, cylinders and hard CSG
//! stay sharp.
//!
//! The crossings are found on the field itself (Illinois regula falsi from the lattice's linear
//! guess), their normals from its gradient, and every vertex is then moved onto the zero set by
//! Newton steps along the gradient (kept only while they reduce `|φ|`). Cells are enumerated in a
//! fixed order, so the mesh is the same whatever the thread count.

use super::TriangleMesh;
use super::qef::Qef;
use glam::Vec3;
use rayon::prelude::*;

/// A signed distance and its gradient, in the lattice's coordinates.
pub trait Field: Sync {
    /// `φ(p)`: negative inside.
    fn value(&self, p: Vec3) -> f32;
    /// `∇φ(p)` (not necessarily unit).
    fn gradient(&self, p: Vec3) -> Vec3;
}

/// Regula falsi iterations per edge crossing.
const CROSSING_STEPS: usize = 12;
/// Newton steps moving a vertex onto the zero set.
const NEWTON_STEPS: usize = 4;

/// The lattice: `dims` points per axis spanning `[lo, hi]`.
#[derive(Clone, Copy, Debug)]
pub struct Lattice {
    /// The first lattice point.
    pub lo: Vec3,
    /// The last lattice point.
    pub hi: Vec3,
    /// Points per axis `[nx, ny, nz]`, at least 2 each.
    pub dims: [usize; 3],
}

impl Lattice {
    fn step(&self) -> Vec3 {
        (self.hi - self.lo) / Vec3::from_array(self.dims.map(|n| (n - 1) as f32))
    }

    fn point(&self, [i, j, k]: [usize; 3]) -> Vec3 {
        self.lo + self.step() * Vec3::new(i as f32, j as f32, k as f32)
    }

    fn index(&self, [i, j, k]: [usize; 3]) -> usize {
        (k * self.dims[1] + j) * self.dims[0] + i
    }
}

/// The surface `φ = 0` of `field` inside `lattice`, as a closed triangle mesh wherever the surface
/// does not reach the lattice's outer cells (module docs). Triangles face outwards (towards `φ > 0`).
pub fn dual_contour(field: &dyn Field, lattice: &Lattice) -> TriangleMesh {
    let [nx, ny, nz] = lattice.dims;
    let values: Vec<f32> = (0..nx * ny * nz)
        .into_par_iter()
        .map(|n| {
            let (i, j, k) = (n % nx, (n / nx) % ny, n / (nx * ny));
            field.value(lattice.point([i, j, k]))
        })
        .collect();
    let inside = |c: [usize; 3]| values[lattice.index(c)] < 0.0;
    // Cells with a sign change, numbered in lattice order.
    let cells = [nx - 1, ny - 1, nz - 1];
    let cell_index = |[i, j, k]: [usize; 3]| (k * cells[1] + j) * cells[0] + i;
    let mixed: Vec<[usize; 3]> = (0..cells[0] * cells[1] * cells[2])
        .filter_map(|n| {
            let c = [
                n % cells[0],
                (n / cells[0]) % cells[1],
                n / (cells[0] * cells[1]),
            ];
            let first = inside(c);
            let changes = (1..8).any(|corner| inside(offset(c, corner)) != first);
            changes.then_some(c)
        })
        .collect();
    let mut vertex_of = vec![u32::MAX; cells[0] * cells[1] * cells[2]];
    for (v, c) in mixed.iter().enumerate() {
        vertex_of[cell_index(*c)] = v as u32;
    }
    let vertices: Vec<Vec3> = mixed
        .par_iter()
        .map(|&c| cell_vertex(field, lattice, &values, c))
        .collect();
    let normals = vertices
        .iter()
        .map(|&p| field.gradient(p).normalize_or_zero())
        .collect();
    let mut faces = Vec::new();
    for axis in 0..3 {
        let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let a = [i, j, k];
                    if a[axis] + 1 >= lattice.dims[axis] || a[u] == 0 || a[w] == 0 {
                        continue;
                    }
                    if a[u] + 1 >= lattice.dims[u] || a[w] + 1 >= lattice.dims[w] {
                        continue;
                    }
                    let mut b = a;
                    b[axis] += 1;
                    let (ia, ib) = (inside(a), inside(b));
                    if ia == ib {
                        continue;
                    }
                    // The four cells around the edge, counter-clockwise seen from +axis.
                    let around = [(1, 1), (0, 1), (0, 0), (1, 0)].map(|(du, dw)| {
                        let mut c = a;
                        c[u] -= du;
                        c[w] -= dw;
                        vertex_of[cell_index(c)]
                    });
                    let mut quad = around;
                    if !ia {
                        quad.reverse();
                    }
                    faces.extend(split(quad, &vertices));
                }
            }
        }
    }
    TriangleMesh {
        vertices,
        normals,
        faces,
    }
}

/// Lattice point `corner` (bits x, y, z) of cell `c`.
fn offset(c: [usize; 3], corner: usize) -> [usize; 3] {
    [
        c[0] + (corner & 1),
        c[1] + ((corner >> 1) & 1),
        c[2] + ((corner >> 2) & 1),
    ]
}

/// A quad as two triangles, split along its shorter diagonal.
fn split(q: [u32; 4], vertices: &[Vec3]) -> [[u32; 3]; 2] {
    let p = |k: usize| vertices[q[k] as usize];
    if p(0).distance_squared(p(2)) <= p(1).distance_squared(p(3)) {
        [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
    } else {
        [[q[0], q[1], q[3]], [q[1], q[2], q[3]]]
    }
}

/// The vertex of mixed cell `c`: the QEF's minimiser clamped to the cell, then moved onto the zero set.
fn cell_vertex(field: &dyn Field, lattice: &Lattice, values: &[f32], c: [usize; 3]) -> Vec3 {
    const EDGES: [(usize, usize); 12] = [
        (0, 1),
        (2, 3),
        (4, 5),
        (6, 7),
        (0, 2),
        (1, 3),
        (4, 6),
        (5, 7),
        (0, 4),
        (1, 5),
        (2, 6),
        (3, 7),
    ];
    let mut qef = Qef::default();
    for (a, b) in EDGES {
        let (ca, cb) = (offset(c, a), offset(c, b));
        let (va, vb) = (values[lattice.index(ca)], values[lattice.index(cb)]);
        if (va < 0.0) == (vb < 0.0) {
            continue;
        }
        let p = crossing(field, lattice.point(ca), lattice.point(cb), va, vb);
        let n = field.gradient(p).normalize_or_zero();
        qef.add(p.as_dvec3(), n.as_dvec3());
    }
    let lo = lattice.point(c).as_dvec3();
    let hi = lattice.point(offset(c, 7)).as_dvec3();
    let x = qef.solve().clamp(lo, hi);
    project(field, x.as_vec3(), (hi - lo).length() as f32)
}

/// The zero of `φ` on the segment `a → b` (`φ(a) = va`, `φ(b) = vb`, opposite signs), by the Illinois
/// variant of regula falsi (which keeps the bracket and converges superlinearly).
fn crossing(field: &dyn Field, a: Vec3, b: Vec3, va: f32, vb: f32) -> Vec3 {
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    let (mut f0, mut f1) = (va as f64, vb as f64);
    let mut side = 0i8;
    for _ in 0..CROSSING_STEPS {
        let t = (t0 * f1 - t1 * f0) / (f1 - f0);
        if !t.is_finite() {
            break;
        }
        let f = field.value(a.lerp(b, t as f32)) as f64;
        if f == 0.0 {
            return a.lerp(b, t as f32);
        }
        if (f < 0.0) == (f0 < 0.0) {
            (t0, f0) = (t, f);
            if side == -1 {
                f1 *= 0.5;
            }
            side = -1;
        } else {
            (t1, f1) = (t, f);
            if side == 1 {
                f0 *= 0.5;
            }
            side = 1;
        }
    }
    a.lerp(b, ((t0 * f1 - t1 * f0) / (f1 - f0)).clamp(0.0, 1.0) as f32)
}

/// `x` moved onto `φ = 0` by Newton steps along the gradient, each kept only if it reduces `|φ|` and
/// moves less than `reach` (a cell's diagonal).
fn project(field: &dyn Field, mut x: Vec3, reach: f32) -> Vec3 {
    let start = x;
    let mut f = field.value(x);
    for _ in 0..NEWTON_STEPS {
        let g = field.gradient(x);
        let g2 = g.length_squared();
        if f == 0.0 || g2 <= 0.0 || !g2.is_finite() {
            break;
        }
        let next = x - g * (f / g2);
        let fn_ = field.value(next);
        if fn_.abs() >= f.abs() || next.distance(start) > reach {
            break;
        }
        (x, f) = (next, fn_);
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Ball;
    impl Field for Ball {
        fn value(&self, p: Vec3) -> f32 {
            p.length() - 1.0
        }
        fn gradient(&self, p: Vec3) -> Vec3 {
            p.normalize_or_zero()
        }
    }

    #[test]
    fn the_illinois_crossing_finds_the_zero() {
        let a = Vec3::new(0.2, 0.1, 0.0);
        let b = Vec3::new(1.7, 0.3, 0.1);
        let p = crossing(&Ball, a, b, Ball.value(a), Ball.value(b));
        assert!(Ball.value(p).abs() < 1e-6, "{p}");
    }

    #[test]
    fn a_ball_is_closed_and_on_its_surface() {
        let lattice = Lattice {
            lo: Vec3::splat(-1.5),
            hi: Vec3::splat(1.5),
            dims: [17; 3],
        };
        let mesh = dual_contour(&Ball, &lattice);
        assert!(mesh.faces.len() > 100);
        assert_eq!(mesh.boundary_edges(), 0);
        assert_eq!(mesh.non_manifold_edges(), 0);
        assert_eq!(mesh.euler_characteristic(), 2);
        for v in &mesh.vertices {
            assert!(Ball.value(*v).abs() < 1e-5, "{v}");
        }
        // Outward triangles: a positive volume, below the ball's (every triangle is a chord: vertices on
        // the sphere) and within 5% of it.
        let ball = 4.0 / 3.0 * std::f64::consts::PI;
        let volume = mesh.volume();
        assert!(volume < ball && volume > 0.95 * ball, "{volume}");
    }
}
