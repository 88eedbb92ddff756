//! Triangle meshes out of the scene's shapes and into grids. Out: a shape's surface extracted by dual
//! contouring ([`contour`]), with sharp edges kept sharp, vertices on the zero set and normals from
//! the gradient; files are written by [`crate::io::write_mesh`]. In: a mesh read by
//! [`crate::io::read_mesh`] has a signed distance ([`signed_distance`]: exact distances through a
//! BVH, [`bvh`], and the inside from the generalised winding number, [`winding`]) that
//! [`bake_mesh`] samples for a `grid` node. [`metrics`] compares two meshes (Chamfer distance,
//! normal consistency, IoU).
//!
//! The mesh is closed (every edge on an even number of triangles). As with every dual contouring with
//! one vertex per cell, a lattice face whose corners alternate in sign (a sharp edge crossing it
//! diagonally) gives an edge shared by four triangles: the surface touches itself along it, a few in
//! ten thousand edges of a rotated box at 64³ ([`TriangleMesh::non_manifold_edges`]).

pub mod bvh;
pub mod contour;
pub mod metrics;
mod qef;
pub mod shapes;
pub mod signed_distance;
pub mod winding;

pub use signed_distance::{MeshSdf, bake_mesh};

use crate::error::{Error, Result};
use crate::scene::Shape;
use crate::sdf::bake_dims;
use contour::{Field, Lattice, dual_contour};
use glam::Vec3;
use std::collections::HashMap;

/// The default lattice resolution of [`extract_shape`]: points along the longest side of the box.
pub const DEFAULT_RESOLUTION: usize = 128;

/// A triangle mesh: vertices, their unit normals (zero where the gradient vanishes), and triangles
/// as vertex indices, counter-clockwise seen from outside.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions (scene units).
    pub vertices: Vec<Vec3>,
    /// Unit normal per vertex.
    pub normals: Vec<Vec3>,
    /// Triangles, as indices into `vertices`.
    pub faces: Vec<[u32; 3]>,
}

impl TriangleMesh {
    /// How many times each undirected edge is used, by its vertex pair (smaller index first).
    fn edge_uses(&self) -> HashMap<(u32, u32), u32> {
        let mut uses = HashMap::new();
        for f in &self.faces {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                *uses.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        uses
    }

    /// Number of distinct edges.
    pub fn edge_count(&self) -> usize {
        self.edge_uses().len()
    }

    /// Edges on the boundary of the surface (used by an odd number of triangles): 0 for a closed
    /// (watertight) mesh.
    pub fn boundary_edges(&self) -> usize {
        self.edge_uses().values().filter(|&&n| n % 2 == 1).count()
    }

    /// Edges shared by four or more triangles (the surface touches itself there): 0 for a manifold
    /// mesh.
    pub fn non_manifold_edges(&self) -> usize {
        self.edge_uses().values().filter(|&&n| n > 2).count()
    }

    /// `V − E + F` (2 for a closed surface of genus 0, 0 for a torus).
    pub fn euler_characteristic(&self) -> i64 {
        let edges = self.edge_uses().len() as i64;
        self.vertices.len() as i64 - edges + self.faces.len() as i64
    }

    /// Total area of the triangles.
    pub fn area(&self) -> f64 {
        let p = |i: u32| self.vertices[i as usize].as_dvec3();
        (self.faces.iter())
            .map(|f| 0.5 * (p(f[1]) - p(f[0])).cross(p(f[2]) - p(f[0])).length())
            .sum()
    }

    /// The enclosed volume (divergence theorem; positive when the triangles face outwards).
    pub fn volume(&self) -> f64 {
        let p = |i: u32| self.vertices[i as usize].as_dvec3();
        (self.faces.iter())
            .map(|f| p(f[0]).dot(p(f[1]).cross(p(f[2]))) / 6.0)
            .sum()
    }

    /// Unit normal per vertex: the sum of the area vectors of the triangles around it, normalised
    /// (zero where they cancel or no triangle uses the vertex).
    pub fn vertex_normals(&self) -> Vec<Vec3> {
        let mut sums = vec![Vec3::ZERO; self.vertices.len()];
        for f in &self.faces {
            let p = f.map(|i| self.vertices[i as usize]);
            let area = (p[1] - p[0]).cross(p[2] - p[0]);
            for i in f {
                sums[*i as usize] += area;
            }
        }
        sums.into_iter().map(Vec3::normalize_or_zero).collect()
    }

    /// The mesh moved by `offset`.
    pub fn translated(mut self, offset: Vec3) -> Self {
        self.vertices.iter_mut().for_each(|v| *v += offset);
        self
    }
}

/// A shape's SDF in its own coordinates, as the contouring's field.
struct ShapeField<'a>(&'a Shape);

impl Field for ShapeField<'_> {
    fn value(&self, p: Vec3) -> f32 {
        self.0.sdf.eval_f32(p)
    }
    fn gradient(&self, p: Vec3) -> Vec3 {
        self.0.sdf.gradient(p)
    }
}

/// The surface of `shape` (for a grid, the spline at its `level`) as a closed triangle mesh in scene
/// coordinates (its translation applied), from a lattice of `res` points along the longest side of
/// its bounds (grown so that the surface stays off the lattice's outer cells; near-cubic cells).
/// Errors: an unbounded shape (a plane), `res` below 4.
pub fn extract_shape(shape: &Shape, res: usize) -> Result<TriangleMesh> {
    if res < 4 {
        return Err(Error::field(
            "res",
            format!("must be at least 4, got {res}"),
        ));
    }
    let local = shape.sdf.bounds();
    if !local.is_finite() || local.is_empty() {
        return Err(Error::Unsupported(format!(
            "shape {:?} is unbounded (e.g. a plane): it has no closed surface to extract",
            shape.name
        )));
    }
    // Two cells and 5% of the box on every side keep the surface off the outer cells.
    let extent = local.extent().max_element();
    let pad = 0.05 * extent + 2.0 * extent / (res - 1) as f32;
    let (lo, hi) = (local.min - pad, local.max + pad);
    let lattice = Lattice {
        lo,
        hi,
        dims: bake_dims(lo, hi, res),
    };
    let mesh = dual_contour(&ShapeField(shape), &lattice);
    Ok(mesh.translated(shape.translate.value()))
}
