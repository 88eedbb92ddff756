//! Sampling any node onto a grid.

use super::{GridData, Sdf};
use rayon::prelude::*;

/// Sample counts per axis for [`bake`]: `res` along the longest edge of the box, and on the other axes
/// the count that keeps the spacing closest to it (`round((res − 1) e_a / e_max) + 1`), each at least 4.
pub fn bake_dims(bbox_min: glam::Vec3, bbox_max: glam::Vec3, res: usize) -> [usize; 3] {
    let res = res.max(4);
    let ext = (bbox_max - bbox_min).max(glam::Vec3::ZERO);
    let longest = ext.max_element();
    std::array::from_fn(|a| {
        if longest > 0.0 && longest.is_finite() {
            (((res - 1) as f32 * ext[a] / longest).round() as usize + 1).max(4)
        } else {
            res
        }
    })
}

/// Sample `sdf` on the lattice over `[bbox_min, bbox_max]` with [`bake_dims`] samples per axis: sample
/// `(i, j, k)` at `bbox_min + (i, j, k) · (bbox_max − bbox_min)/(dims − 1)`, so the first and last samples
/// lie on the faces (the grid node built from the result uses the same box). Cells are near-cubic: spacing
/// differs between axes only by the rounding of the counts. Runs in parallel over z slices.
///
/// The samples become B-spline control points, so the baked surface sits about `h²/6 ∇²φ` off the
/// original (see [`crate::sdf`]'s grid notes); keep a margin of a few cells between the surface and the box.
pub fn bake(sdf: &Sdf, bbox_min: glam::Vec3, bbox_max: glam::Vec3, res: usize) -> GridData {
    let dims = bake_dims(bbox_min, bbox_max, res);
    let [nx, ny, nz] = dims;
    let step =
        (bbox_max - bbox_min) / (glam::UVec3::from_array(dims.map(|n| n as u32)) - 1).as_vec3();
    let mut values = vec![0.0f32; nx * ny * nz];
    values
        .par_chunks_mut(nx * ny)
        .enumerate()
        .for_each(|(z, slice)| {
            for y in 0..ny {
                for x in 0..nx {
                    let p = bbox_min + glam::Vec3::new(x as f32, y as f32, z as f32) * step;
                    slice[y * nx + x] = sdf.eval_f32(p);
                }
            }
        });
    GridData { dims, values }
}

/// Relative padding of [`bake_padded`]'s box: the B-spline needs samples beyond the surface on every
/// side, where its reconstruction is accurate.
pub const BAKE_PADDING: f32 = 0.1;

/// A node sampled onto a grid by [`bake_padded`], with the box its samples span.
#[derive(Clone, Debug)]
pub struct Baked {
    /// The samples, `[nx, ny, nz]`.
    pub grid: GridData,
    /// Corner of the box at the first sample.
    pub bbox_min: glam::Vec3,
    /// Corner of the box at the last sample.
    pub bbox_max: glam::Vec3,
}

impl Baked {
    /// The grid node of a scene file that uses the samples written to `file` (a path relative to the
    /// scene file), as one line of JSON.
    pub fn scene_node(&self, file: &str) -> String {
        let (lo, hi) = (self.bbox_min, self.bbox_max);
        let file = serde_json::Value::from(file);
        format!(
            "{{\"type\": \"grid\", \"file\": {file}, \"bbox_min\": [{}, {}, {}], \"bbox_max\": [{}, {}, {}]}}",
            lo.x, lo.y, lo.z, hi.x, hi.y, hi.z
        )
    }
}

/// Samples `sdf` in its own coordinates over its bounds padded by [`BAKE_PADDING`] of the longest
/// edge, `res` samples along the longest edge ([`bake`]). Errors: an unbounded node (e.g. a plane),
/// named `what` in the message.
pub fn bake_padded(sdf: &Sdf, res: usize, what: &str) -> crate::Result<Baked> {
    bake_padded_by(sdf, res, BAKE_PADDING, what)
}

/// [`bake_padded`] with the box grown by `padding` (≥ 0) times the longest edge of the bounds on every
/// side. Errors: an unbounded node, or a box with no volume (a flat node without padding).
pub fn bake_padded_by(sdf: &Sdf, res: usize, padding: f32, what: &str) -> crate::Result<Baked> {
    let local = sdf.bounds();
    if !local.is_finite() || local.is_empty() {
        return Err(crate::Error::Unsupported(format!(
            "{what} is unbounded (e.g. a plane), it cannot be baked into a grid"
        )));
    }
    let padded = local.expanded(padding * local.extent().max_element());
    if padded.extent().min_element().partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(crate::Error::Unsupported(format!(
            "{what}'s box has no volume with padding {padding}; use a padding > 0"
        )));
    }
    Ok(Baked {
        grid: bake(sdf, padded.min, padded.max, res),
        bbox_min: padded.min,
        bbox_max: padded.max,
    })
}
