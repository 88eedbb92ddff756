//! A triangle mesh's signed distance: the exact distance to the nearest triangle ([`Bvh::closest`]),
//! negative where the generalised winding number ([`Winding`]) is at least ½. On a closed mesh facing
//! outwards this is the usual signed distance; on a scan with holes, several components, doubled,
//! flipped or self-intersecting triangles, the inside is where the triangles wrap a point at least
//! halfway, which is what a person would call inside.
//!
//! [`bake_mesh`] samples it on the lattice of [`crate::sdf::bake`] for a `grid` node.

use super::TriangleMesh;
use super::bvh::{Bvh, Closest};
use super::winding::Winding;
use crate::error::{Error, Result};
use crate::math::Aabb;
use crate::sdf::{Baked, GridData, bake_dims};
use glam::Vec3;
use rayon::prelude::*;

/// A mesh prepared for distance and inside queries.
#[derive(Clone, Debug)]
pub struct MeshSdf {
    bvh: Bvh,
    winding: Winding,
    /// The box of the mesh's vertices used by its triangles.
    pub bounds: Aabb,
}

impl MeshSdf {
    /// The tree and its moments for `mesh` (its faces' indices must be in range, as
    /// [`crate::io::read_mesh`] checks). Errors: no triangle, a coordinate that is not finite.
    pub fn new(mesh: &TriangleMesh) -> Result<Self> {
        if mesh.faces.is_empty() {
            return Err(Error::Unsupported("the mesh has no triangle".into()));
        }
        let n = mesh.vertices.len();
        if mesh.faces.iter().flatten().any(|&i| i as usize >= n) {
            return Err(Error::Unsupported(format!(
                "a triangle uses a vertex out of range (the mesh has {n} vertices)"
            )));
        }
        let mut bounds = Aabb::EMPTY;
        for &i in mesh.faces.iter().flatten() {
            let v = mesh.vertices[i as usize];
            bounds = bounds.union(&Aabb::new(v, v));
        }
        if !bounds.is_finite() {
            return Err(Error::Unsupported(
                "a vertex has a coordinate that is not finite".into(),
            ));
        }
        let bvh = Bvh::new(&mesh.vertices, &mesh.faces);
        let winding = Winding::new(&bvh);
        Ok(Self {
            bvh,
            winding,
            bounds,
        })
    }

    /// The closest point of the mesh to `q`.
    pub fn closest(&self, q: Vec3) -> Closest {
        self.bvh
            .closest(q, f32::INFINITY)
            .expect("a mesh with triangles has a closest point")
    }

    /// The distance from `q` to the nearest triangle.
    pub fn distance(&self, q: Vec3) -> f32 {
        self.closest(q).distance2.sqrt()
    }

    /// The generalised winding number at `q` (1 inside a closed outward-facing mesh, 0 outside).
    pub fn winding(&self, q: Vec3) -> f64 {
        self.winding.at(&self.bvh, q)
    }

    /// True where the winding number is at least ½.
    pub fn inside(&self, q: Vec3) -> bool {
        self.winding(q) >= 0.5
    }

    /// The signed distance at `q`: negative inside.
    pub fn signed(&self, q: Vec3) -> f32 {
        let d = self.distance(q);
        if self.inside(q) { -d } else { d }
    }

    /// The signed distance on the lattice of [`crate::sdf::bake`]: [`bake_dims`] samples per axis
    /// over `[lo, hi]`, the first and last on the box's faces, `x` fastest: exact distances, signs
    /// from the winding number evaluated as [`MeshSdf::insides`] says. In parallel over `z` slices.
    pub fn sample(&self, lo: Vec3, hi: Vec3, res: usize) -> GridData {
        self.sample_dims(lo, hi, bake_dims(lo, hi, res))
    }

    /// [`MeshSdf::sample`] with `dims` samples per axis (each at least 2).
    pub fn sample_dims(&self, lo: Vec3, hi: Vec3, dims: [usize; 3]) -> GridData {
        let dims = dims.map(|n| n.max(2));
        let lattice = Lattice::new(lo, hi, dims);
        let distances = self.distances(&lattice);
        let inside = self.insides(&lattice, &distances);
        let values = (distances.iter().zip(&inside))
            .map(|(&d, &i)| if i { -d } else { d })
            .collect();
        GridData { dims, values }
    }

    /// The unsigned distance at every lattice point, `x` fastest. In parallel over `z` slices; each
    /// closest-point search starts from the previous point's closest triangle, whose distance is
    /// within a step of the answer and so prunes all but a few nodes of the tree.
    fn distances(&self, lattice: &Lattice) -> Vec<f32> {
        let [nx, ny, nz] = lattice.dims;
        let mut values = vec![0.0f32; nx * ny * nz];
        values
            .par_chunks_mut(nx * ny)
            .enumerate()
            .for_each(|(z, slice)| {
                // The closest triangle of the previous point (along the row, or the row's first
                // point for the next row's) starts each search.
                let mut row_start = self.closest(lattice.point([0, 0, z])).slot;
                for y in 0..ny {
                    let mut slot = row_start;
                    for x in 0..nx {
                        let c = self.bvh.closest_near(lattice.point([x, y, z]), slot);
                        slot = c.slot;
                        if x == 0 {
                            row_start = slot;
                        }
                        slice[y * nx + x] = c.distance2.sqrt();
                    }
                }
            });
        values
    }

    /// Whether each lattice point is inside (winding number ≥ ½), given the distances.
    ///
    /// The winding number is evaluated on a coarse lattice of every [`BLOCK`]-th point first. A
    /// block of [`BLOCK`]³ cells that holds no triangle (a corner's distance exceeds the block's
    /// diagonal) and whose corners all lie on the same side takes that side for all its points: on a
    /// closed mesh the winding number is constant (an integer) where no triangle separates two
    /// points, so this is exact; on an open one it is harmonic there, and a block whose corners
    /// agree is taken to agree inside. The other blocks evaluate every point.
    fn insides(&self, lattice: &Lattice, distances: &[f32]) -> Vec<bool> {
        let [nx, ny, nz] = lattice.dims;
        // Coarse nodes: every BLOCK-th index and the last.
        let coarse = |n: usize| -> Vec<usize> {
            let mut v: Vec<usize> = (0..n).step_by(BLOCK).collect();
            if *v.last().expect("n >= 1") != n - 1 {
                v.push(n - 1);
            }
            v
        };
        let (cx, cy, cz) = (coarse(nx), coarse(ny), coarse(nz));
        let index = |[x, y, z]: [usize; 3]| (z * ny + y) * nx + x;
        let corner_inside: Vec<bool> = (0..cx.len() * cy.len() * cz.len())
            .into_par_iter()
            .map(|n| {
                let (i, j, k) = (
                    n % cx.len(),
                    (n / cx.len()) % cy.len(),
                    n / (cx.len() * cy.len()),
                );
                self.inside(lattice.point([cx[i], cy[j], cz[k]]))
            })
            .collect();
        let corner =
            |i: usize, j: usize, k: usize| corner_inside[(k * cy.len() + j) * cx.len() + i];
        let mut inside = vec![false; nx * ny * nz];
        // One slab of blocks per task: the blocks between coarse z nodes k and k + 1.
        let slabs: Vec<(usize, Vec<(usize, bool)>)> = (0..cz.len() - 1)
            .into_par_iter()
            .map(|k| {
                let mut out = Vec::new();
                let z_end = if k + 2 == cz.len() {
                    cz[k + 1] + 1
                } else {
                    cz[k + 1]
                };
                for j in 0..cy.len() - 1 {
                    let y_end = if j + 2 == cy.len() {
                        cy[j + 1] + 1
                    } else {
                        cy[j + 1]
                    };
                    for i in 0..cx.len() - 1 {
                        let x_end = if i + 2 == cx.len() {
                            cx[i + 1] + 1
                        } else {
                            cx[i + 1]
                        };
                        let (lo, hi) = ([cx[i], cy[j], cz[k]], [cx[i + 1], cy[j + 1], cz[k + 1]]);
                        let diagonal = (lattice.point(hi) - lattice.point(lo)).length();
                        let corners = [0, 1, 2, 3, 4, 5, 6, 7].map(|c| {
                            let (a, b, d) = (i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2));
                            (corner(a, b, d), distances[index([cx[a], cy[b], cz[d]])])
                        });
                        let free = corners.iter().any(|c| c.1 > diagonal);
                        let same = corners.iter().all(|c| c.0 == corners[0].0);
                        for z in cz[k]..z_end {
                            for y in cy[j]..y_end {
                                for x in cx[i]..x_end {
                                    let side = if free && same {
                                        corners[0].0
                                    } else {
                                        self.inside(lattice.point([x, y, z]))
                                    };
                                    out.push((index([x, y, z]), side));
                                }
                            }
                        }
                    }
                }
                (k, out)
            })
            .collect();
        for (_, points) in slabs {
            for (n, side) in points {
                inside[n] = side;
            }
        }
        inside
    }
}

/// Lattice points per side of the blocks whose sign is decided at their corners.
const BLOCK: usize = 4;

/// The lattice of [`crate::sdf::bake`].
struct Lattice {
    lo: Vec3,
    step: Vec3,
    dims: [usize; 3],
}

impl Lattice {
    fn new(lo: Vec3, hi: Vec3, dims: [usize; 3]) -> Self {
        let step = (hi - lo) / (glam::UVec3::from_array(dims.map(|n| n as u32)) - 1).as_vec3();
        Self { lo, step, dims }
    }

    #[inline]
    fn point(&self, [x, y, z]: [usize; 3]) -> Vec3 {
        self.lo + Vec3::new(x as f32, y as f32, z as f32) * self.step
    }
}

/// The box a mesh is baked over: its bounds grown by `padding` times their longest edge on every side
/// (as [`crate::sdf::bake_padded`] does for shapes, [`crate::sdf::BAKE_PADDING`] by default). Errors:
/// a box with no volume (a flat mesh without padding, or a single point).
pub fn padded_box(bounds: Aabb, padding: f32) -> Result<Aabb> {
    let padded = bounds.expanded(padding * bounds.extent().max_element());
    if padded.extent().min_element().partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
        || !padded.is_finite()
    {
        return Err(Error::Unsupported(format!(
            "the mesh's box {:?} to {:?} (padded by {padding} of its longest edge) has no volume; \
             use a padding > 0",
            padded.min.to_array(),
            padded.max.to_array()
        )));
    }
    Ok(padded)
}

/// The signed distance of `mesh` sampled over its bounds padded by `padding` times their longest edge,
/// `res` samples along the longest edge of the padded box ([`MeshSdf::sample`]), with the box (for the
/// `grid` node, [`Baked::scene_node`]). Errors: as [`MeshSdf::new`] and [`padded_box`].
pub fn bake_mesh(mesh: &TriangleMesh, res: usize, padding: f32) -> Result<Baked> {
    let sdf = MeshSdf::new(mesh)?;
    let padded = padded_box(sdf.bounds, padding)?;
    Ok(Baked {
        grid: sdf.sample(padded.min, padded.max, res),
        bbox_min: padded.min,
        bbox_max: padded.max,
    })
}
