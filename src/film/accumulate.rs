//! Pixel accumulation: where every estimator puts its samples (pbrt's `Film::AddSample`).
//!
//! A pixel is `F_j / W_j` with `F_j = ∫ w_j L` and `W_j = ∫ w_j` over the film (docs/theory.md,
//! "pixel normalisation"; supplemental document of Zhou et al. 2024, §3). Estimators hand each sample's
//! share of `F` (radiance) and `W` (weight) to a [`SampleSink`], in any number type `S`:
//! - [`SampleSink::add_own`]: a camera sample of its own pixel, its film offset drawn from that pixel's
//!   filter, so its filter weight over its density is 1;
//! - [`SampleSink::add_splat`]: a value already multiplied by the receiving pixel's filter weight over
//!   the sample's density (the moving filter of the interior term, boundary samples).
//!
//! Work is split into items that run in parallel (rows of camera samples, chunks of boundary samples);
//! each item writes into its own [`Film::Tile`], and tiles are merged in item order, so every sum is
//! the same whatever the number of threads. Two films implement the seam: [`PixelFilm`] for camera
//! samples (sums in `S`, per row) and [`SplatFilm`] for boundary samples (sums in `f64`, in sample order).
//! A reverse-mode film would turn each sample into the scalar `Σ_j g_j · (its share of pixel j)`.

use super::{Filter, Image};
use crate::math::Vec3;
use crate::scalar::{Directions, Scalar};

/// Receives the samples of one work item.
pub trait SampleSink<S: Scalar> {
    /// A camera sample of pixel `pixel` (row-major index) drawn from that pixel's own filter:
    /// `radiance` is its integrand of `F`, `weight` its integrand of `W`.
    fn add_own(&mut self, pixel: usize, radiance: Vec3<S>, weight: S);
    /// A share of pixel `pixel`'s `F` and `W`, already weighted by that pixel's filter over the
    /// sample's density.
    fn add_splat(&mut self, pixel: usize, radiance: Vec3<S>, weight: S);
    /// The moving pixel filter's shares of a camera sample whose film point `(px, py)` moves with the
    /// parameters (the interior term's `L ∂(w_j J_film)`): for each pixel `j` of a `width × height`
    /// image under `filter` there, [`SampleSink::add_splat`] of `radiance · Δw_j` and `Δw_j`, where
    /// `w_j = filter(p − centre_j) · scale` and `Δw_j = w_j − w̄_j` its derivative part (primal 0);
    /// `radiance` is a constant. A reverse-mode sink may add the footprint's shares as one number.
    #[inline]
    fn add_motion(
        &mut self,
        filter: &Filter,
        (px, py): (S, S),
        scale: S,
        radiance: glam::Vec3,
        (width, height): (u32, u32),
    ) {
        let lp = Vec3::<S>::constant(radiance);
        let p = glam::Vec2::new(px.primal(), py.primal());
        for (jx, jy) in filter.footprint(p, width, height) {
            let dx = px - (jx as f32 + 0.5);
            let dy = py - (jy as f32 + 0.5);
            let weight = filter.eval(dx, dy) * scale;
            let dw = weight - weight.detach();
            self.add_splat((jy * width + jx) as usize, lp * dw, dw);
        }
    }
    /// Whether the camera samples of pixel `pixel` (row-major index) can change what the sink holds;
    /// `false` lets an estimator skip them (a reverse-mode sink whose pixel adjoint is zero wherever
    /// they can land, [`super::AdjointFilm::skipping_zero_adjoint`]).
    #[inline(always)]
    fn needs_pixel(&self, _pixel: usize) -> bool {
        true
    }
    /// Called before a sample's first number is computed (a reverse-mode sink marks its tape here).
    #[inline(always)]
    fn begin_sample(&mut self) {}
    /// Called after a sample's last share (a reverse-mode sink back-propagates the sample here).
    #[inline(always)]
    fn end_sample(&mut self) {}
}

/// A film: hands out one tile per work item and merges the tiles back, in item order.
pub trait Film: Sync {
    /// What one work item writes into.
    type Tile: Send;
    /// The empty tile of work item `item`.
    fn tile(&self, item: usize) -> Self::Tile;
    /// Adds a finished tile; called in increasing item order.
    fn merge(&mut self, item: usize, tile: Self::Tile);
    /// Runs one work item's `work` on the worker thread (a reverse-mode film records the item's tape
    /// around it).
    #[inline(always)]
    fn run_item<R>(&self, work: impl FnOnce() -> R) -> R {
        work()
    }
    /// How many items run between merges: tiles of a wave are held until the wave is merged (a film
    /// with large tiles bounds its memory with this). Any value gives the same result.
    fn wave(&self) -> usize {
        usize::MAX
    }
}

/// Splats `radiance` and `weight` at film point `p` (pixels) to every pixel of a `width × height`
/// image whose filter covers it, each weighted by that pixel's filter (evaluated in `f32`).
pub fn splat_filtered<S: Scalar>(
    sink: &mut (impl SampleSink<S> + ?Sized),
    filter: &Filter,
    (width, height): (u32, u32),
    p: glam::Vec2,
    radiance: Vec3<S>,
    weight: S,
) {
    for (jx, jy) in filter.footprint(p, width, height) {
        let fw = filter.eval::<f32>(p.x - (jx as f32 + 0.5), p.y - (jy as f32 + 0.5));
        if fw != 0.0 {
            let fw = S::constant(fw);
            let pixel = jy as usize * width as usize + jx as usize;
            sink.add_splat(pixel, radiance * fw, weight * fw);
        }
    }
}

/// How a pixel's filter weights are normalised (supplemental document, §3).
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum Normalization {
    /// Pixel = mean of `w/p · L` over its samples; `W` is treated as the constant it is in expectation.
    Fixed,
    /// Pixel = `F / W` with both sums differentiated (a control variate; unbiased together with `W`'s
    /// own primary boundary term). The default: at the same cost its error is lower
    /// (docs/derivatives.md, "Pixel normalisation").
    #[default]
    Differentiable,
}

impl std::str::FromStr for Normalization {
    type Err = String;
    /// `"fixed"` or `"differentiable"`.
    fn from_str(text: &str) -> Result<Self, String> {
        match text {
            "fixed" => Ok(Normalization::Fixed),
            "differentiable" => Ok(Normalization::Differentiable),
            _ => Err(format!(
                "unknown normalization {text:?} (expected fixed or differentiable)"
            )),
        }
    }
}

impl Normalization {
    /// The derivative of a pixel from the derivatives `df` of `F` and `dw` of `W` and the pixel's value
    /// `i`: `df` (`Fixed`), or `∂(F/W) = df − i·dw` at `W = 1` (`Differentiable`, supplemental §3,
    /// eq. 26).
    #[inline]
    pub fn derivative(self, df: f32, dw: f32, i: f32) -> f32 {
        match self {
            Normalization::Fixed => df,
            Normalization::Differentiable => df - i * dw,
        }
    }
}

/// Camera samples of a `width × height` image, summed in `S` per pixel: the pixel's own samples
/// (`F`, `W`) and splats from nearby samples (the moving filter), kept apart so that each keeps its
/// own estimator. Work items are rows; a row's splats may reach `reach` rows up and down.
pub struct PixelFilm<S> {
    width: usize,
    height: usize,
    reach: usize,
    own: Vec<Vec3<S>>,
    own_weight: Vec<S>,
    splat: Vec<Vec3<S>>,
    splat_weight: Vec<S>,
}

/// One row of a [`PixelFilm`]: its own pixels' sums, and a band of `2 reach + 1` rows of splats
/// (row `y − reach + b` in band row `b`).
pub struct RowTile<S> {
    y: usize,
    width: usize,
    reach: usize,
    height: usize,
    own: Vec<Vec3<S>>,
    own_weight: Vec<S>,
    splat: Vec<Vec3<S>>,
    splat_weight: Vec<S>,
}

impl<S: Scalar> PixelFilm<S> {
    /// An empty film; `reach` is how many rows away from its own row a sample may splat (0: no
    /// splats, as for the image alone).
    pub fn new(width: u32, height: u32, reach: usize) -> Self {
        let n = width as usize * height as usize;
        let splats = if reach > 0 { n } else { 0 };
        Self {
            width: width as usize,
            height: height as usize,
            reach,
            own: vec![Vec3::zero(); n],
            own_weight: vec![S::zero(); n],
            splat: vec![Vec3::zero(); splats],
            splat_weight: vec![S::zero(); splats],
        }
    }

    /// The rows a sample may splat into for a filter of radius `radius`: a film point within `radius`
    /// of its own pixel's centre reaches centres less than `2 radius` away.
    pub fn splat_reach(radius: f32) -> usize {
        ((2.0 * radius).ceil() as i64 - 1).max(0) as usize
    }

    /// The image: the mean of each pixel's own samples (primal), `spp` samples per pixel.
    pub fn image(&self, spp: u32) -> Image {
        let mut image = Image::new(self.width as u32, self.height as u32);
        for (rgb, sum) in image.rgb.chunks_exact_mut(3).zip(&self.own) {
            let mean = sum.primal() / spp as f32;
            rgb.copy_from_slice(&mean.to_array());
        }
        image
    }

    /// The derivative images in directions `0..count` of `S`: `F = (own + splats)/spp` and `W`
    /// likewise, combined by `normalization` with the pixel value `F`'s primal.
    pub fn derivatives(&self, spp: u32, count: usize, normalization: Normalization) -> Vec<Image>
    where
        S: Directions,
    {
        let mut out = vec![Image::new(self.width as u32, self.height as u32); count];
        let inv_spp = S::constant(1.0 / spp as f32);
        let zero = Vec3::zero();
        for p in 0..self.own.len() {
            let splat = self.splat.get(p).copied().unwrap_or(zero);
            let splat_weight = self.splat_weight.get(p).copied().unwrap_or(S::zero());
            let f = (self.own[p] + splat) * inv_spp;
            let w = (self.own_weight[p] + splat_weight) * inv_spp;
            let i = f.primal();
            for (k, d) in out.iter_mut().enumerate() {
                let dw = w.direction(k);
                d.rgb[3 * p] = normalization.derivative(f.x.direction(k), dw, i.x);
                d.rgb[3 * p + 1] = normalization.derivative(f.y.direction(k), dw, i.y);
                d.rgb[3 * p + 2] = normalization.derivative(f.z.direction(k), dw, i.z);
            }
        }
        out
    }
}

impl<S: Scalar + Send + Sync> Film for PixelFilm<S> {
    type Tile = RowTile<S>;

    fn tile(&self, y: usize) -> RowTile<S> {
        let band = if self.reach > 0 {
            (2 * self.reach + 1) * self.width
        } else {
            0
        };
        RowTile {
            y,
            width: self.width,
            reach: self.reach,
            height: self.height,
            own: vec![Vec3::zero(); self.width],
            own_weight: vec![S::zero(); self.width],
            splat: vec![Vec3::zero(); band],
            splat_weight: vec![S::zero(); band],
        }
    }

    fn merge(&mut self, y: usize, tile: RowTile<S>) {
        let row = y * self.width..(y + 1) * self.width;
        self.own[row.clone()].copy_from_slice(&tile.own);
        self.own_weight[row].copy_from_slice(&tile.own_weight);
        if tile.splat.is_empty() {
            return;
        }
        for b in 0..2 * self.reach + 1 {
            let Some(jy) = (y + b).checked_sub(self.reach) else {
                continue;
            };
            if jy >= self.height {
                continue;
            }
            for jx in 0..self.width {
                let (src, dst) = (b * self.width + jx, jy * self.width + jx);
                self.splat[dst] += tile.splat[src];
                self.splat_weight[dst] += tile.splat_weight[src];
            }
        }
    }
}

impl<S: Scalar> SampleSink<S> for RowTile<S> {
    #[inline]
    fn add_own(&mut self, pixel: usize, radiance: Vec3<S>, weight: S) {
        let x = pixel - self.y * self.width;
        self.own[x] += radiance;
        self.own_weight[x] += weight;
    }

    /// Splats beyond the tile's band of rows are dropped: a film point stays within the filter's
    /// radius of its own pixel's centre, so they do not occur but for rounding.
    #[inline]
    fn add_splat(&mut self, pixel: usize, radiance: Vec3<S>, weight: S) {
        let (jx, jy) = (pixel % self.width, pixel / self.width);
        let b = jy + self.reach;
        if self.splat.is_empty() || b < self.y || b - self.y > 2 * self.reach || jy >= self.height {
            return;
        }
        let i = (b - self.y) * self.width + jx;
        self.splat[i] += radiance;
        self.splat_weight[i] += weight;
    }
}

/// Boundary samples of a `width × height` image in directions `0..count` of `S`: splats summed in
/// `f64` in sample order and divided by the number of samples of the whole image. Work items are
/// chunks of samples.
pub struct SplatFilm<S> {
    pixels: usize,
    count: usize,
    radiance: Vec<f64>,
    weight: Vec<f64>,
    marker: std::marker::PhantomData<fn() -> S>,
}

/// One splat of a boundary sample.
pub struct Splat<S> {
    pixel: usize,
    radiance: Vec3<S>,
    weight: S,
}

/// A chunk of boundary samples' splats, in sample order.
pub struct SplatTile<S>(Vec<Splat<S>>);

impl<S: Directions> SplatFilm<S> {
    /// An empty film for directions `0..count` of `S`.
    pub fn new(width: u32, height: u32, count: usize) -> Self {
        let pixels = width as usize * height as usize;
        Self {
            pixels,
            count,
            radiance: vec![0.0; 3 * count * pixels],
            weight: vec![0.0; count * pixels],
            marker: std::marker::PhantomData,
        }
    }

    /// Adds the mean over `samples` samples to `radiance[k]` and `weight[k]` (the same value in the
    /// three channels) for each direction `k`.
    pub fn add_mean_to(&self, samples: u64, radiance: &mut [Image], weight: &mut [Image]) {
        let (n, inv) = (self.pixels, 1.0 / samples as f64);
        for (k, image) in radiance.iter_mut().take(self.count).enumerate() {
            for (d, a) in image
                .rgb
                .iter_mut()
                .zip(&self.radiance[3 * k * n..3 * (k + 1) * n])
            {
                *d += (a * inv) as f32;
            }
        }
        for (k, image) in weight.iter_mut().take(self.count).enumerate() {
            let sums = &self.weight[k * n..(k + 1) * n];
            for (d, a) in image.rgb.chunks_exact_mut(3).zip(sums) {
                for c in d {
                    *c += (a * inv) as f32;
                }
            }
        }
    }
}

impl<S: Directions + Send> Film for SplatFilm<S> {
    type Tile = SplatTile<S>;

    fn tile(&self, _item: usize) -> SplatTile<S> {
        SplatTile(Vec::new())
    }

    fn merge(&mut self, _item: usize, tile: SplatTile<S>) {
        let n = self.pixels;
        for s in &tile.0 {
            for k in 0..self.count {
                let base = 3 * (k * n + s.pixel);
                self.radiance[base] += s.radiance.x.direction(k) as f64;
                self.radiance[base + 1] += s.radiance.y.direction(k) as f64;
                self.radiance[base + 2] += s.radiance.z.direction(k) as f64;
                self.weight[k * n + s.pixel] += s.weight.direction(k) as f64;
            }
        }
    }
}

impl<S: Scalar> SampleSink<S> for SplatTile<S> {
    /// Boundary estimators have no pixel of their own: the same as a splat.
    fn add_own(&mut self, pixel: usize, radiance: Vec3<S>, weight: S) {
        self.add_splat(pixel, radiance, weight);
    }

    fn add_splat(&mut self, pixel: usize, radiance: Vec3<S>, weight: S) {
        self.0.push(Splat {
            pixel,
            radiance,
            weight,
        });
    }
}
