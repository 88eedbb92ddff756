//! How close a triangle mesh is to a reference mesh, the usual measures of surface reconstruction:
//!
//! - **Chamfer distance** ([`MeshMetrics::chamfer`]): points sampled uniformly by area on each
//!   surface ([`MetricOptions::samples`] per surface, 10,000 by default); for each, the Euclidean
//!   distance to the nearest point of the *other surface* (its triangles, through a BVH: exact, with no
//!   floor from the spacing of a second point set); the **mean** of those distances in each direction,
//!   and the mean of the two directions, divided by the length of the reference's bounding-box
//!   diagonal. Distances, not squared distances.
//! - **Normal consistency** ([`MeshMetrics::normal_consistency`]): over the same points, the mean of
//!   `|n_a · n_b|`, `n_a` the normal of the triangle a point was sampled on and `n_b` that of the
//!   triangle holding its nearest point on the other surface; the mean of the two directions. 1 for
//!   identical surfaces, orientation ignored.
//! - **IoU** ([`MeshMetrics::iou`]): volume of the intersection over volume of the union of the two
//!   insides, a point being inside a mesh where its generalised winding number is at least ½
//!   ([`super::winding`]), counted at the cell centres of a lattice over the union of the two
//!   bounding boxes, [`MetricOptions::iou_resolution`] cells along its longest side (64 by default)
//!   and near-cubic cells on the others.
//!
//! Samples are a pure function of [`MetricOptions::seed`], so the measures are reproducible.

use super::TriangleMesh;
use super::signed_distance::MeshSdf;
use crate::error::{Error, Result};
use crate::math::Aabb;
use crate::sampler::Sampler;
use glam::Vec3;
use rayon::prelude::*;

/// Points per surface of the Chamfer distance and the normal consistency by default.
pub const DEFAULT_SAMPLES: usize = 10_000;
/// Lattice cells along the longest side of the IoU's box by default.
pub const DEFAULT_IOU_RESOLUTION: usize = 64;

/// The random stream of the surface samples.
const SURFACE_STREAM: u64 = 0x5A3F_11E0;

/// How the measures are taken.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MetricOptions {
    /// Points sampled on each surface.
    pub samples: usize,
    /// Lattice cells along the longest side of the IoU's box.
    pub iou_resolution: usize,
    /// Seed of the surface samples.
    pub seed: u64,
}

impl Default for MetricOptions {
    fn default() -> Self {
        Self {
            samples: DEFAULT_SAMPLES,
            iou_resolution: DEFAULT_IOU_RESOLUTION,
            seed: 0,
        }
    }
}

/// The measures of a mesh against a reference (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshMetrics {
    /// Symmetric Chamfer distance as a fraction of the reference's bounding-box diagonal.
    pub chamfer: f64,
    /// Mean `|n_a · n_b|` of nearest points, both directions.
    pub normal_consistency: f64,
    /// Intersection over union of the insides.
    pub iou: f64,
}

/// A mesh ready to be measured: its distance structure and its area table.
#[derive(Clone, Debug)]
pub struct Measured {
    sdf: MeshSdf,
    mesh: TriangleMesh,
    /// Running sum of the triangles' areas.
    cdf: Vec<f64>,
}

impl Measured {
    /// Prepares `mesh`. Errors: as [`MeshSdf::new`], or a mesh of zero area.
    pub fn new(mesh: &TriangleMesh) -> Result<Self> {
        let sdf = MeshSdf::new(mesh)?;
        let mut cdf = Vec::with_capacity(mesh.faces.len());
        let mut total = 0.0;
        for f in &mesh.faces {
            let [a, b, c] = f.map(|i| mesh.vertices[i as usize].as_dvec3());
            total += 0.5 * (b - a).cross(c - a).length();
            cdf.push(total);
        }
        if total.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(Error::Unsupported("the mesh has no area".into()));
        }
        Ok(Self {
            sdf,
            mesh: mesh.clone(),
            cdf,
        })
    }

    /// The box of the mesh.
    pub fn bounds(&self) -> Aabb {
        self.sdf.bounds
    }

    /// The unit normal of triangle `f` (zero if degenerate).
    fn face_normal(&self, f: u32) -> Vec3 {
        let [a, b, c] = self.mesh.faces[f as usize].map(|i| self.mesh.vertices[i as usize]);
        (b - a).cross(c - a).normalize_or_zero()
    }

    /// `n` points uniform by area, with the normal of their triangle.
    fn sample(&self, n: usize, seed: u64) -> Vec<(Vec3, Vec3)> {
        let total = *self.cdf.last().expect("checked: at least one triangle");
        (0..n)
            .into_par_iter()
            .map(|k| {
                let mut sampler = Sampler::new(seed, SURFACE_STREAM, 0, k as u64);
                let u = sampler.next_1d() as f64 * total;
                let f = self
                    .cdf
                    .partition_point(|&c| c <= u)
                    .min(self.cdf.len() - 1);
                let [a, b, c] = self.mesh.faces[f].map(|i| self.mesh.vertices[i as usize]);
                let uv = sampler.next_2d();
                // Uniform on the triangle (Osada et al. 2002).
                let s = uv.x.sqrt();
                let p = a * (1.0 - s) + b * (s * (1.0 - uv.y)) + c * (s * uv.y);
                (p, self.face_normal(f as u32))
            })
            .collect()
    }

    /// Mean distance and mean `|n·n'|` from the points `from` to this surface.
    fn one_way(&self, from: &[(Vec3, Vec3)]) -> (f64, f64) {
        let (d, n) = from
            .par_iter()
            .map(|&(p, normal)| {
                let c = self.sdf.closest(p);
                let dot = normal.dot(self.face_normal(c.face)).abs();
                (c.distance2.sqrt() as f64, dot as f64)
            })
            .reduce(|| (0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
        let k = from.len().max(1) as f64;
        (d / k, n / k)
    }

    /// True where the winding number is at least ½.
    pub fn inside(&self, p: Vec3) -> bool {
        self.sdf.inside(p)
    }
}

/// The measures of `mesh` against `reference` (module docs). Errors: a mesh without triangles or
/// area, a reference whose box has no diagonal.
pub fn compare(
    mesh: &TriangleMesh,
    reference: &TriangleMesh,
    options: &MetricOptions,
) -> Result<MeshMetrics> {
    compare_prepared(&Measured::new(mesh)?, &Measured::new(reference)?, options)
}

/// [`compare`] with meshes already prepared (the reference of an optimisation is prepared once).
pub fn compare_prepared(
    a: &Measured,
    reference: &Measured,
    options: &MetricOptions,
) -> Result<MeshMetrics> {
    let diagonal = reference.bounds().extent().length() as f64;
    if diagonal.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(Error::Unsupported(
            "the reference mesh's bounding box has no diagonal".into(),
        ));
    }
    let n = options.samples.max(1);
    let (pa, pb) = (
        a.sample(n, options.seed),
        reference.sample(n, options.seed.wrapping_add(1)),
    );
    let (d_ab, n_ab) = reference.one_way(&pa);
    let (d_ba, n_ba) = a.one_way(&pb);
    Ok(MeshMetrics {
        chamfer: 0.5 * (d_ab + d_ba) / diagonal,
        normal_consistency: 0.5 * (n_ab + n_ba),
        iou: iou(a, reference, options.iou_resolution),
    })
}

/// The IoU of the insides of `a` and `b` on `res` cells along the longest side of the union of their
/// boxes (module docs); 1 when neither holds a cell centre.
pub fn iou(a: &Measured, b: &Measured, res: usize) -> f64 {
    let region = a.bounds().union(&b.bounds());
    let res = res.max(1);
    let ext = region.extent();
    let longest = ext.max_element();
    let dims: [usize; 3] = std::array::from_fn(|k| {
        if longest > 0.0 {
            ((res as f32 * ext[k] / longest).round() as usize).max(1)
        } else {
            1
        }
    });
    let cell = ext / Vec3::from_array(dims.map(|n| n as f32));
    let [nx, ny, nz] = dims;
    let (both, either) = (0..nz)
        .into_par_iter()
        .map(|z| {
            let (mut both, mut either) = (0u64, 0u64);
            for y in 0..ny {
                for x in 0..nx {
                    let p = region.min + (Vec3::new(x as f32, y as f32, z as f32) + 0.5) * cell;
                    let (ia, ib) = (a.inside(p), b.inside(p));
                    both += u64::from(ia && ib);
                    either += u64::from(ia || ib);
                }
            }
            (both, either)
        })
        .reduce(|| (0, 0), |x, y| (x.0 + y.0, x.1 + y.1));
    if either == 0 {
        1.0
    } else {
        both as f64 / either as f64
    }
}
