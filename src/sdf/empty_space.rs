//! Empty-space skipping for grid shapes: where along a ray the surface can first be.
//!
//! A grid's spline on a lattice cell is a convex combination of the cell's 4×4×4 control points, so a
//! cell whose control points all lie on one side of the level holds no surface (it is *empty*); only the
//! *straddling* cells can. Each cell stores its chessboard distance, in cells, to the nearest straddling
//! one: a cell at distance `k ≥ 1` is the centre of a cube of `2k − 1` cells on a side that are all
//! empty, and a ray inside it can jump to where it leaves the cube without evaluating the spline. Sphere
//! tracing then starts at the first straddling cell the ray meets, not where it enters the shape's
//! bounds: the spline's Lipschitz bound (up to `√3` around a baked shape's kinks) makes the steps there
//! short, and each step is an evaluation of 64 control points. Each cell also keeps the Lipschitz
//! bounds and a bound of the second directional derivative over itself and its 26 neighbours (valid
//! within one cell of any of its points), with which the tracer steps inside straddling cells.
//!
//! It applies when the shape's node is a grid under similarity transforms (and names), and when the
//! surface does not reach beyond the grid box (beyond it `φ = φ(clamp(x)) + |x − clamp(x)|`, positive
//! whenever the spline stays above the level on the box's faces; otherwise no skipping). Parameters that
//! change the grid, its level or its transforms rebuild it with the shape.

use super::{Sdf, grid};
use crate::math::{Aabb, Ray};
use std::cmp::Ordering;

/// The chessboard distance map of a grid shape's straddling cells, and the map from the shape's frame to
/// lattice coordinates (cell `(i, j, k)` spans `[i, i + 1] × [j, j + 1] × [k, k + 1]`).
///
/// A cell whose 4×4×4 control points all lie on one side of the level holds no surface (the spline on
/// it is their convex combination); a ray skips runs of such cells, jumping out of the cube of empty
/// cells around the one it is in (the cell's chessboard distance to the nearest straddling cell, `k`,
/// makes the `2k − 1` cells on a side around it empty). In straddling cells it steps with the
/// Lipschitz bound of the cell's neighbourhood, which holds within one cell of any of its points.
/// Applies to a grid under similarity transforms whose surface stays inside the grid box.
#[derive(Clone, Debug, PartialEq)]
pub struct EmptySpace {
    /// The linear part of the map from the shape's frame to lattice coordinates.
    to_lattice: glam::Mat3,
    /// Its offset: `u = to_lattice · x + offset`.
    offset: glam::Vec3,
    /// Cells per axis (`n − 1` for `n` samples).
    cells: [usize; 3],
    /// Per cell (x fastest), the chessboard distance to the nearest straddling cell, saturated at 255.
    distance: Vec<u8>,
    /// Per cell, what holds over the cell and its 26 neighbours (valid within one cell of any point
    /// of the cell), side by side so that a straddling cell's lookup reads one place.
    bounds: Vec<CellBounds>,
    /// The shortest edge of a cell in the shape's frame: how far from a point the neighbourhood's
    /// bounds certainly hold.
    pub cell_size: f32,
}

/// What holds over a cell and its 26 neighbours ([`EmptySpace`]).
#[derive(Copy, Clone, Debug, PartialEq)]
struct CellBounds {
    /// The inverse Lipschitz bounds `[outside, inside]`.
    inv_lipschitz: [f32; 2],
    /// `1/M` for the bound `M` of the spline's second derivative along any unit direction (a
    /// length; infinite where the spline is linear there), inside the grid box.
    curvature_radius: f32,
}

/// What the lattice cells a box touches hold ([`EmptySpace::box_cells`]).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum BoxCells {
    /// Every cell is empty: the box holds no surface point.
    Empty,
    /// One of the cells straddles the level: the box may hold surface points.
    Straddling,
    /// The box reaches beyond the lattice (or is not finite): nothing is known.
    Unknown,
}

/// Where a ray can first meet the surface ([`EmptySpace::first_candidate_lattice`]).
#[derive(Copy, Clone, Debug)]
pub struct Candidate {
    /// The ray parameter.
    pub t: f32,
    /// Where the ray leaves the straddling cell it is in at `t`: nothing to skip before.
    pub until: f32,
    /// Inverse Lipschitz bounds `[outside, inside]` that hold within [`EmptySpace::cell_size`] of any
    /// point of that cell.
    pub inv_lipschitz: [f32; 2],
    /// `1/M`, `M` a bound of `|d²φ/dt²|` along a unit direction that holds within
    /// [`EmptySpace::cell_size`] of any point of that cell inside the grid box (0 when unknown).
    pub curvature_radius: f32,
}

impl EmptySpace {
    /// The empty space of `sdf`, if it is a grid under similarity transforms (and names) whose surface
    /// stays inside the grid box; `None` otherwise.
    pub fn of(sdf: &Sdf) -> Option<Self> {
        match sdf {
            Sdf::Named { child, .. } => Self::of(child),
            Sdf::Transform { .. } => {
                let (frame, child) = sdf.frame()?;
                let inner = Self::of(child)?;
                let s = frame.scale();
                if !(s > 0.0 && s.is_finite()) {
                    return None;
                }
                let (to_child, child_offset) = frame.to_child_affine();
                Some(Self {
                    to_lattice: inner.to_lattice * to_child,
                    offset: inner.to_lattice * child_offset + inner.offset,
                    cell_size: frame.from_child_length(inner.cell_size),
                    // Second derivatives scale as 1/length: their radius as a length.
                    bounds: (inner.bounds.iter())
                        .map(|b| CellBounds {
                            curvature_radius: frame.from_child_length(b.curvature_radius),
                            ..*b
                        })
                        .collect(),
                    ..inner
                })
            }
            Sdf::Grid {
                data,
                bbox_min,
                bbox_max,
                level,
                ..
            } => {
                if !data.usable() || grid::faces_min(data) < level.value {
                    return None;
                }
                let ext = *bbox_max - *bbox_min;
                if !(ext.cmpgt(glam::Vec3::ZERO).all() && ext.is_finite()) {
                    return None;
                }
                let cells = data.dims.map(|n| n - 1);
                let scale = glam::Vec3::from(cells.map(|c| c as f32)) / ext;
                let (extended, _) = grid::extended_lattice(data);
                // Independent walks over the cells, in parallel.
                let ((distance, inv_lipschitz), curvature_radius) = rayon::join(
                    || {
                        let patches = grid::patch_lipschitz(
                            data,
                            &extended,
                            *bbox_min,
                            *bbox_max,
                            level.value,
                        );
                        let straddling: Vec<bool> = patches.iter().map(|p| p.straddling).collect();
                        rayon::join(
                            || chessboard_distance(&straddling, cells),
                            || neighbourhood_inverse_bounds(&patches, cells),
                        )
                    },
                    || {
                        let curvature =
                            grid::patch_curvature(data, &extended, *bbox_min, *bbox_max);
                        neighbourhood_max(curvature.into_iter().map(|m| [m]).collect(), cells)
                            .into_iter()
                            .map(|[m]| 1.0 / m)
                            .collect::<Vec<f32>>()
                    },
                );
                let bounds = (inv_lipschitz.into_iter().zip(curvature_radius))
                    .map(|(inv_lipschitz, curvature_radius)| CellBounds {
                        inv_lipschitz,
                        curvature_radius,
                    })
                    .collect();
                Some(Self {
                    to_lattice: glam::Mat3::from_diagonal(scale),
                    offset: -*bbox_min * scale,
                    cells,
                    distance,
                    bounds,
                    cell_size: (ext / glam::Vec3::from(cells.map(|c| c as f32))).min_element(),
                })
            }
            _ => None,
        }
    }

    /// What the cells touched by the box `b` (in the shape's frame) hold. The box's corners are mapped
    /// to the lattice and the cells of their bounding box, grown by a thousandth of a cell against the
    /// map's rounding, are looked up: [`BoxCells::Empty`] proves that no surface point is in `b`
    /// (module notes), without evaluating the spline.
    pub fn box_cells(&self, b: &Aabb) -> BoxCells {
        let (mut lo, mut hi) = (glam::Vec3::INFINITY, glam::Vec3::NEG_INFINITY);
        for k in 0..8 {
            let corner = glam::Vec3::new(
                if k & 1 == 0 { b.min.x } else { b.max.x },
                if k & 2 == 0 { b.min.y } else { b.max.y },
                if k & 4 == 0 { b.min.z } else { b.max.z },
            );
            let u = self.to_lattice * corner + self.offset;
            lo = lo.min(u);
            hi = hi.max(u);
        }
        const SLACK: f32 = 1e-3;
        let mut range = [(0usize, 0usize); 3];
        for a in 0..3 {
            let (l, h) = ((lo[a] - SLACK).floor(), (hi[a] + SLACK).floor());
            // Also refuses NaN: the comparisons fail.
            if !(l >= 0.0 && h < self.cells[a] as f32 && l <= h) {
                return BoxCells::Unknown;
            }
            range[a] = (l as usize, h as usize);
        }
        for z in range[2].0..=range[2].1 {
            for y in range[1].0..=range[1].1 {
                let row = self.cells[0] * (y + self.cells[1] * z);
                if self.distance[row + range[0].0..=row + range[0].1].contains(&0) {
                    return BoxCells::Straddling;
                }
            }
        }
        BoxCells::Empty
    }

    /// The ray (in the shape's frame) in lattice coordinates, with the same parameter `t`.
    #[inline]
    pub fn lattice_ray(&self, ray: &Ray) -> LatticeRay {
        let (o, d) = (
            self.to_lattice * ray.o + self.offset,
            self.to_lattice * ray.d,
        );
        let extent = glam::Vec3::from(self.cells.map(|c| c as f32));
        let (enter, exit) = slab(o, d, glam::Vec3::ZERO, extent).unwrap_or((1.0, 0.0));
        LatticeRay {
            o,
            d,
            inv: d.recip(),
            enter,
            exit,
        }
    }

    /// The first parameter in `[t0, t1]` from which the ray (in the shape's frame) can meet the surface:
    /// `t0` itself when it starts in a straddling cell, `None` when every cell it crosses up to `t1` is
    /// empty. Nothing before the returned parameter is on the surface.
    #[inline]
    pub fn first_candidate(&self, ray: &Ray, t0: f32, t1: f32) -> Option<f32> {
        self.first_candidate_lattice(&self.lattice_ray(ray), t0, t1)
            .map(|c| c.t)
    }

    /// [`EmptySpace::first_candidate`] for a ray already in lattice coordinates
    /// ([`EmptySpace::lattice_ray`]), with what holds in the straddling cell found there.
    #[inline]
    pub fn first_candidate_lattice(&self, ray: &LatticeRay, t0: f32, t1: f32) -> Option<Candidate> {
        // Outside the lattice box everything is empty.
        let mut t = t0.max(ray.enter);
        let t_end = t1.min(ray.exit);
        // A ray crosses at most `Σ cells` cells; the bound only guards against rounding loops.
        let steps = self.cells.iter().sum::<usize>() * 3 + 8;
        for _ in 0..steps {
            // Also stops on a NaN parameter.
            if !matches!(
                t.partial_cmp(&t_end),
                Some(Ordering::Less | Ordering::Equal)
            ) {
                return None;
            }
            let u = ray.o + t * ray.d;
            let cell = std::array::from_fn::<usize, 3, _>(|a| {
                // `as usize` saturates: a point a rounding below 0 is in the first cell.
                (u[a] as usize).min(self.cells[a] - 1)
            });
            let index = cell[0] + self.cells[0] * (cell[1] + self.cells[1] * cell[2]);
            let k = self.distance[index];
            // The cube of cells within `k − 1` of this one is empty (for `k = 0`, the cell itself is
            // straddling): the ray leaves it through its far faces.
            let c = glam::Vec3::from(cell.map(|c| c as f32));
            let reach = k.max(1) as f32;
            let positive = ray.d.cmpgt(glam::Vec3::ZERO);
            let far = glam::Vec3::select(positive, c + reach, c - (reach - 1.0));
            let across = (far - ray.o) * ray.inv;
            // An axis the ray is parallel to does not bound it (its `inv` is infinite).
            let parallel = ray.d.cmpeq(glam::Vec3::ZERO);
            let leave = glam::Vec3::select(parallel, glam::Vec3::INFINITY, across).min_element();
            if k == 0 {
                let CellBounds {
                    inv_lipschitz,
                    curvature_radius,
                } = self.bounds[index];
                return Some(Candidate {
                    t,
                    until: leave,
                    inv_lipschitz,
                    curvature_radius,
                });
            }
            // Rounding can put `leave` at or behind `t` on a cell's face: move on by a sliver.
            t = if leave > t {
                leave
            } else {
                t + 1e-6 * (1.0 + t.abs())
            };
        }
        // Out of iterations (rounding): no skipping here, and no local bound (the caller's applies).
        Some(Candidate {
            t: t.min(t1),
            until: t.min(t1),
            inv_lipschitz: [0.0; 2],
            curvature_radius: 0.0,
        })
    }
}

/// A ray in a grid's lattice coordinates ([`EmptySpace::lattice_ray`]), with what each skip needs.
#[derive(Copy, Clone, Debug)]
pub struct LatticeRay {
    o: glam::Vec3,
    d: glam::Vec3,
    /// `1 / d` per axis (infinite where `d` is zero).
    inv: glam::Vec3,
    /// Where the line enters and leaves the lattice box (`enter > exit` when it misses).
    enter: f32,
    exit: f32,
}

impl LatticeRay {
    /// Where the ray leaves the grid box (its parameter `t`; below `enter` when it misses the box).
    #[inline]
    pub fn exit(&self) -> f32 {
        self.exit
    }
}

/// Where the line `o + t d` is inside the box `[lo, hi]`: `(enter, exit)`, or `None` if it misses. Axes
/// the line is parallel to bound it only if it lies outside their slab.
fn slab(o: glam::Vec3, d: glam::Vec3, lo: glam::Vec3, hi: glam::Vec3) -> Option<(f32, f32)> {
    let (mut enter, mut exit) = (f32::NEG_INFINITY, f32::INFINITY);
    for a in 0..3 {
        if d[a] == 0.0 {
            if o[a] < lo[a] || o[a] > hi[a] {
                return None;
            }
            continue;
        }
        let inv = 1.0 / d[a];
        let (ta, tb) = ((lo[a] - o[a]) * inv, (hi[a] - o[a]) * inv);
        enter = enter.max(ta.min(tb));
        exit = exit.min(ta.max(tb));
    }
    (enter <= exit).then_some((enter, exit))
}

/// Per cell, `1 / max` of the patch bounds over the cell and its 26 neighbours, for each side, counting
/// only patches that reach that side (see [`grid::PatchLipschitz`]); 0 where none does (no point of
/// the cell is on that side; the caller's global bound then applies).
fn neighbourhood_inverse_bounds(
    patches: &[grid::PatchLipschitz],
    cells: [usize; 3],
) -> Vec<[f32; 2]> {
    let bound: Vec<[f32; 2]> = (patches.iter())
        .map(|p| [p.outside, p.inside].map(|reaches| if reaches { p.bound } else { 0.0 }))
        .collect();
    neighbourhood_max(bound, cells)
        .into_iter()
        .map(|b| b.map(|b| if b > 0.0 { 1.0 / b } else { 0.0 }))
        .collect()
}

/// Per cell (x fastest, `cells` per axis), the elementwise maximum of `v` over the cell and its 26
/// neighbours (those that exist).
fn neighbourhood_max<const N: usize>(mut v: Vec<[f32; N]>, cells: [usize; 3]) -> Vec<[f32; N]> {
    // The maximum over the 3×3×3 block is three maxima over 3 cells along each axis in turn.
    let strides = [1, cells[0], cells[0] * cells[1]];
    for (a, &n) in cells.iter().enumerate() {
        let stride = strides[a];
        let before = v.clone();
        for (k, out) in v.iter_mut().enumerate() {
            let i = (k / stride) % n;
            let (lo, hi) = (i.saturating_sub(1), (i + 1).min(n - 1));
            for j in lo..=hi {
                let b = before[k - i * stride + j * stride];
                *out = std::array::from_fn(|c| out[c].max(b[c]));
            }
        }
    }
    v
}

/// The chessboard (L∞) distance, in cells, from each cell to the nearest `seed` cell, saturated at 255
/// (255 everywhere when there is none): the two-pass chamfer transform with the full 3×3×3 mask of unit
/// weights, which is exact for this metric. The cells are padded by one layer of 255 on every side, so
/// that every cell has all its neighbours.
fn chessboard_distance(seed: &[bool], cells: [usize; 3]) -> Vec<u8> {
    let [nx, ny, nz] = cells;
    let start: Vec<u8> = seed.iter().map(|&s| if s { 0 } else { 255 }).collect();
    let mut d = grid::Padded::new(&start, cells, 255u8);
    let stride = d.strides();
    // The 13 neighbours that come before a cell in scan order, as offsets back from it.
    let mut back = Vec::with_capacity(13);
    for dz in -1isize..=1 {
        for dy in -1isize..=1 {
            for dx in -1isize..=1 {
                if (dz, dy, dx) < (0, 0, 0) {
                    let ahead = dx + dy * stride[1] as isize + dz * stride[2] as isize;
                    back.push((-ahead) as usize);
                }
            }
        }
    }
    let relax = |d: &mut [u8], k: usize, forward: bool| {
        let mut best = d[k];
        for &o in &back {
            let n = if forward { d[k - o] } else { d[k + o] };
            best = best.min(n.saturating_add(1));
        }
        d[k] = best;
    };
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let k = d.index(x, y, z);
                relax(&mut d.values, k, true);
            }
        }
    }
    for z in (0..nz).rev() {
        for y in (0..ny).rev() {
            for x in (0..nx).rev() {
                let k = d.index(x, y, z);
                relax(&mut d.values, k, false);
            }
        }
    }
    d.unpadded()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn neighbourhood_bounds_match_brute_force() {
        let cells = [6, 4, 5];
        let n: usize = cells.iter().product();
        let patches: Vec<grid::PatchLipschitz> = (0..n)
            .map(|k| grid::PatchLipschitz {
                bound: 1.0 + ((k * 29 + 7) % 31) as f32 / 8.0,
                outside: k % 3 != 0,
                inside: k % 5 == 1,
                straddling: false,
            })
            .collect();
        let got = neighbourhood_inverse_bounds(&patches, cells);
        let coords = |k: usize| {
            [
                k % cells[0],
                (k / cells[0]) % cells[1],
                k / (cells[0] * cells[1]),
            ]
        };
        for (k, got) in got.iter().enumerate() {
            let mut want = [0.0f32; 2];
            for (j, p) in patches.iter().enumerate() {
                let (a, b) = (coords(k), coords(j));
                if (0..3).all(|i| a[i].abs_diff(b[i]) <= 1) {
                    for (side, reaches) in [p.outside, p.inside].into_iter().enumerate() {
                        if reaches {
                            want[side] = want[side].max(p.bound);
                        }
                    }
                }
            }
            let want = want.map(|b| if b > 0.0 { 1.0 / b } else { 0.0 });
            assert_eq!(*got, want, "cell {:?}", coords(k));
        }
    }

    #[test]
    fn chessboard_distance_matches_brute_force() {
        let cells = [7, 5, 6];
        let n = cells.iter().product();
        let seed: Vec<bool> = (0..n).map(|k| (k * 37 + 11) % 53 == 0).collect();
        let got = chessboard_distance(&seed, cells);
        let coords = |k: usize| {
            [
                k % cells[0],
                (k / cells[0]) % cells[1],
                k / (cells[0] * cells[1]),
            ]
        };
        for (k, &got) in got.iter().enumerate() {
            let want = (0..n)
                .filter(|&j| seed[j])
                .map(|j| {
                    let (a, b) = (coords(k), coords(j));
                    (0..3).map(|i| a[i].abs_diff(b[i])).max().unwrap()
                })
                .min()
                .map_or(255, |v| v.min(255) as u8);
            assert_eq!(got, want, "cell {:?}", coords(k));
        }
    }
}
