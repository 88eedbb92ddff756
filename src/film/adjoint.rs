//! The reverse-mode film: instead of accumulating an image, each sample's shares of the pixels become
//! one scalar, `s = scale · Σ_j g_j · (ΔF_j − I_j ΔW_j)` (`g` the pixel adjoint `∂L/∂I`, `I` the image
//! of the same samples, which enters as a constant; the `W` part only with the differentiable
//! normalisation, supplemental document §3), which is swept backwards through the sample's tape into the
//! gradient. Since every estimator's derivative image is `scale · Σ_samples (ΔF − I ΔW)`, the sum of
//! these sweeps is `Σ_j g_j · ∂I_j = ∂L` by linearity (docs/theory.md (10.2)).
//!
//! Each work item has a dense `f32` gradient buffer; buffers are merged in item order into an `f64`
//! total, so the gradient is the same whatever the number of threads. A sample whose gradient is not
//! finite is dropped and counted, as forward mode does with its derivatives. An item touches few of
//! the entries (a row of pixels sees a band of a grid's values), so it lists those it touched and the
//! merge adds only them, zeroing them again for the next item to reuse the buffer: the same sums in
//! the same order as a merge of every entry, without clearing and adding a grid's worth of zeros per
//! item (at 61³, 227k entries for each of an image's rows).
//!
//! The zeroed buffers go back to one pool shared by every film, so that the next item, or the next
//! film of the same length (an optimisation's next view or term), takes one instead of fresh pages
//! from the system (at 61³, eight buffers of 0.9 MB per film, three films per view).
//!
//! **Pixels of zero adjoint.** A share for a pixel whose adjoint is zero adds nothing, so a camera
//! sample whose own pixel and splat footprint all have zero adjoint contributes exactly nothing
//! ([`AdjointFilm::skipping_zero_adjoint`] lets the interior pass skip such pixels' samples
//! without tracing them; the gradient is bit for bit the same). In inverse rendering against a
//! target with a plain background most of the image is such pixels.

use super::accumulate::{Film, SampleSink};
use super::{Filter, Image, Normalization};
use crate::math::Vec3;
use crate::scalar::{DualN, Mark, Recording, Rev, Scalar};
use std::sync::{Arc, Mutex};

/// Two derivative directions: a pixel filter's value with its partials along x and y.
type Dual2 = DualN<2>;

/// Zeroed item buffers returned by the films' merges, for the next items of any film.
static SPARE_BUFFERS: Mutex<Vec<Vec<f32>>> = Mutex::new(Vec::new());

/// How many spare buffers are kept at most, per thread: a film holds one per item in flight, up to
/// its wave of 4 per thread, and an optimisation runs a few views' films at once.
const SPARE_BUFFERS_PER_THREAD: usize = 8;

/// Returns a buffer, all zero again, to the pool, unless the pool is full.
fn spare_buffer(buffer: Vec<f32>) {
    if let Ok(mut spare) = SPARE_BUFFERS.lock()
        && spare.len() < SPARE_BUFFERS_PER_THREAD * rayon::current_num_threads()
    {
        spare.push(buffer);
    }
}

/// A zeroed buffer of `entries` values: a spare one if there is one of that length (spares of
/// another length, left by films of another layout, are dropped), else a new one.
fn zeroed_buffer(entries: usize) -> Vec<f32> {
    if let Ok(mut spare) = SPARE_BUFFERS.lock() {
        spare.retain(|b| b.len() == entries);
        if let Some(buffer) = spare.pop() {
            return buffer;
        }
    }
    vec![0.0; entries]
}

/// A reverse-mode film over a `width × height` image.
pub struct AdjointFilm<'a> {
    adjoint: &'a [f32],
    image: Option<&'a [f32]>,
    scale: f32,
    entries: usize,
    /// The gradient so far, one entry per parameter slot (named parameters, then grid blocks).
    pub gradient: Vec<f64>,
    /// Samples whose gradient was not finite (dropped).
    pub invalid: u64,
    /// Per pixel, whether its camera samples can reach a pixel of non-zero adjoint (`None`: all).
    needed: Option<Arc<[bool]>>,
}

/// One work item of an [`AdjointFilm`].
pub struct AdjointTile<'a> {
    adjoint: &'a [f32],
    image: Option<&'a [f32]>,
    scale: f32,
    mark: Mark,
    sum: Rev,
    shares: Vec<(u32, f32)>,
    gradient: Vec<f32>,
    /// The entries this item gave a share, each listed when a share reached it while it was zero (so
    /// every non-zero entry of `gradient` is listed, and one whose sum returned to zero may be listed
    /// twice).
    touched: Vec<u32>,
    invalid: u64,
    needed: Option<Arc<[bool]>>,
}

impl<'a> AdjointFilm<'a> {
    /// A film for the pixel adjoint `adjoint` (`∂L/∂I`, same size as the image), the image `image` of
    /// the same samples (used with `Differentiable` normalisation), each sample's shares multiplied by
    /// `scale` (`1/spp`, or `1/N` for `N` boundary samples), and `entries` gradient entries.
    pub fn new(
        adjoint: &'a Image,
        image: &'a Image,
        normalization: Normalization,
        scale: f32,
        entries: usize,
    ) -> Self {
        Self {
            adjoint: &adjoint.rgb,
            image: (normalization == Normalization::Differentiable).then_some(&image.rgb[..]),
            scale,
            entries,
            gradient: vec![0.0; entries],
            invalid: 0,
            needed: None,
        }
    }

    /// The film with [`SampleSink::needs_pixel`] false for the pixels of a `width`-wide image whose
    /// camera samples, each drawn within `reach` pixels of its pixel's centre and splatted within
    /// `reach` of where it lands (the pixel filter's radius), cannot touch a pixel of non-zero adjoint:
    /// every pixel farther than `⌈2 reach⌉ + 1` pixels (along x or y; one pixel of margin for
    /// rounding) from all of them.
    pub fn skipping_zero_adjoint(mut self, width: u32, reach: f32) -> Self {
        let w = width.max(1) as usize;
        let h = self.adjoint.len() / 3 / w;
        let r = (2.0 * reach).ceil() as usize + 1;
        // Separable dilation of the non-zero pixels by a square of side 2r + 1.
        let mut rows = vec![false; w * h];
        for y in 0..h {
            for x in 0..w {
                let g = &self.adjoint[3 * (y * w + x)..3 * (y * w + x) + 3];
                if g != [0.0; 3] {
                    for xx in x.saturating_sub(r)..(x + r + 1).min(w) {
                        rows[y * w + xx] = true;
                    }
                }
            }
        }
        let mut needed = vec![false; w * h];
        for y in 0..h {
            for x in 0..w {
                if rows[y * w + x] {
                    for yy in y.saturating_sub(r)..(y + r + 1).min(h) {
                        needed[yy * w + x] = true;
                    }
                }
            }
        }
        self.needed = Some(needed.into());
        self
    }
}

impl<'a> Film for AdjointFilm<'a> {
    type Tile = AdjointTile<'a>;

    fn tile(&self, _item: usize) -> AdjointTile<'a> {
        AdjointTile {
            adjoint: self.adjoint,
            image: self.image,
            scale: self.scale,
            mark: Mark::default(),
            sum: Rev::zero(),
            shares: Vec::new(),
            gradient: zeroed_buffer(self.entries),
            touched: Vec::new(),
            invalid: 0,
            needed: self.needed.clone(),
        }
    }

    fn merge(&mut self, _item: usize, mut tile: AdjointTile<'a>) {
        // Every other entry of the buffer is zero, and adding zero leaves a total as it is (up to the
        // sign of a zero total).
        for &entry in &tile.touched {
            let g = std::mem::take(&mut tile.gradient[entry as usize]);
            self.gradient[entry as usize] += g as f64;
        }
        self.invalid += tile.invalid;
        spare_buffer(tile.gradient);
    }

    fn run_item<R>(&self, work: impl FnOnce() -> R) -> R {
        let _recording = Recording::start();
        work()
    }

    fn wave(&self) -> usize {
        4 * rayon::current_num_threads()
    }
}

impl AdjointTile<'_> {
    /// Pixel `pixel`'s adjoint `g_j` and `g_j · I_j` (0 with the fixed normalisation); `None` where
    /// the adjoint is zero, so the pixel's shares add nothing.
    #[inline]
    fn adjoint_at(&self, pixel: usize) -> Option<([f32; 3], f32)> {
        let g = &self.adjoint[3 * pixel..3 * pixel + 3];
        if g == [0.0; 3] {
            return None;
        }
        let gi = self.image.map_or(0.0, |i| {
            let i = &i[3 * pixel..3 * pixel + 3];
            g[0] * i[0] + g[1] * i[1] + g[2] * i[2]
        });
        Some(([g[0], g[1], g[2]], gi))
    }

    /// Adds `scale · g_j · (radiance − I_j weight)` to the sample's scalar.
    #[inline]
    fn add(&mut self, pixel: usize, radiance: Vec3<Rev>, weight: Rev) {
        let Some((g, gi)) = self.adjoint_at(pixel) else {
            return;
        };
        let k = self.scale;
        self.sum = Rev::linear_combination(&[
            (self.sum, 1.0),
            (radiance.x, g[0] * k),
            (radiance.y, g[1] * k),
            (radiance.z, g[2] * k),
            (weight, -gi * k),
        ]);
    }
}

impl SampleSink<Rev> for AdjointTile<'_> {
    #[inline]
    fn needs_pixel(&self, pixel: usize) -> bool {
        self.needed.as_ref().is_none_or(|m| m[pixel])
    }

    #[inline]
    fn add_own(&mut self, pixel: usize, radiance: Vec3<Rev>, weight: Rev) {
        self.add(pixel, radiance, weight);
    }

    #[inline]
    fn add_splat(&mut self, pixel: usize, radiance: Vec3<Rev>, weight: Rev) {
        self.add(pixel, radiance, weight);
    }

    /// The footprint's shares contracted in `f32`: each pixel adds `c_j Δw_j` with `c_j = scale ·
    /// (g_j · radiance − g_j · I_j)`, and `Δw_j` is linear in the film point's and the density
    /// scale's derivatives (`s̄ (∂x f dpx + ∂y f dpy) + f̄ ds`, the filter's partials in `f32`), so
    /// the sum is one node over `px`, `py` and `scale` instead of a dozen per pixel.
    #[inline]
    fn add_motion(
        &mut self,
        filter: &Filter,
        (px, py): (Rev, Rev),
        scale: Rev,
        radiance: glam::Vec3,
        (width, height): (u32, u32),
    ) {
        let p = glam::Vec2::new(px.primal(), py.primal());
        let (mut along_x, mut along_y, mut along_scale) = (0.0f32, 0.0f32, 0.0f32);
        for (jx, jy) in filter.footprint(p, width, height) {
            let Some((g, gi)) = self.adjoint_at((jy * width + jx) as usize) else {
                continue;
            };
            let c = self.scale * (g[0] * radiance.x + g[1] * radiance.y + g[2] * radiance.z - gi);
            let f = filter.eval(
                Dual2::lift(p.x - (jx as f32 + 0.5), Some(0)),
                Dual2::lift(p.y - (jy as f32 + 0.5), Some(1)),
            );
            along_x += c * f.eps[0];
            along_y += c * f.eps[1];
            along_scale += c * f.re;
        }
        let s = scale.primal();
        self.sum = Rev::affine(
            self.sum.primal(),
            &[
                (self.sum, 1.0),
                (px, along_x * s),
                (py, along_y * s),
                (scale, along_scale),
            ],
        );
    }

    fn begin_sample(&mut self) {
        self.mark = Recording::mark();
        self.sum = Rev::zero();
    }

    fn end_sample(&mut self) {
        self.shares.clear();
        let shares = &mut self.shares;
        Recording::sweep(self.sum, |entry, d| shares.push((entry, d)));
        if self.shares.iter().all(|(_, d)| d.is_finite()) {
            for &(entry, d) in &self.shares {
                let g = &mut self.gradient[entry as usize];
                if *g == 0.0 {
                    self.touched.push(entry);
                }
                *g += d;
            }
        } else {
            self.invalid += 1;
        }
        self.sum = Rev::zero();
        Recording::rewind(self.mark);
    }
}
