//! Light transport estimators. Paths are traced in `f32`; their contributions are evaluated with the
//! generic shading code.
//!
//! Both estimators share one tracer ([`path::trace_path`]): `Direct` is a path with a single scattering
//! vertex. A pixel is the mean of its samples' radiances: the film offset of each sample is drawn
//! exactly from the pixel filter, so every sample's filter weight over its density is 1.

pub mod attach;
pub mod boundary;
pub mod derivative;
pub mod fd;
pub mod path;
pub mod shading;
pub mod silhouette_boxes;
pub mod silhouette_curve;
pub mod surface_sampling;

use crate::camera::CameraFrame;
use crate::film::Image;
use crate::sampler::Sampler;
use crate::scene::Scene;
use path::{PathRecord, TraceCounters, contribution, detached, trace_path};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// Which estimator renders the image.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum IntegratorKind {
    /// Emission seen directly plus next-event estimation at the first hit, combined with BSDF sampling
    /// by multiple importance sampling.
    Direct,
    /// Path tracing with next-event estimation and MIS, up to `max_depth` bounces.
    Path {
        /// Longest path in segments after the camera (1 = direct lighting only).
        ///
        /// Counted as scattering vertices: `max_depth = d` scatters at `x1 … xd`, each with a light
        /// sample and a BSDF sample, so `1` is exactly [`IntegratorKind::Direct`] and `0` shows emitters
        /// only. No Russian roulette: the estimate of the `d`-bounce truncation is unbiased.
        max_depth: u32,
    },
}

impl IntegratorKind {
    /// Number of scattering vertices of the longest path.
    pub fn max_scatter(&self) -> u32 {
        match self {
            IntegratorKind::Direct => 1,
            IntegratorKind::Path { max_depth } => *max_depth,
        }
    }
}

/// What to render apart from the scene itself.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Samples per pixel.
    pub spp: u32,
    /// Seed of the deterministic sampler.
    pub seed: u64,
    /// Show a progress bar (only meaningful on a terminal).
    pub progress: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            spp: 64,
            seed: 0,
            progress: false,
        }
    }
}

/// Counters of a render.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Camera samples taken.
    pub samples: u64,
    /// Rays whose sphere tracing ran out of steps (treated as misses).
    pub exhausted_rays: u64,
    /// Samples whose radiance was not finite (NaN or infinite); they count as black. The first one is
    /// reported on stderr with its pixel and sample index.
    pub invalid_samples: u64,
    /// Derivative passes only: samples with a finite radiance but a non-finite derivative (a bug; their
    /// derivative counts as zero). The first one is reported on stderr with its pixel and sample index.
    pub invalid_derivatives: u64,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// Stream of the [`Sampler`] used by camera paths.
pub const CAMERA_STREAM: u64 = 0;

/// Traces camera sample `sample` of pixel `(x, y)` into `record`: draws the film offset from the pixel
/// filter, generates the ray through it and traces the path. Returns the offset (pixels, from the pixel
/// centre) and the camera ray. `frame` is `scene.camera.frame::<f32>()`, built once per render.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn trace_sample(
    scene: &Scene,
    frame: &CameraFrame<f32>,
    seed: u64,
    x: u32,
    y: u32,
    sample: u32,
    record: &mut PathRecord,
    counters: &mut TraceCounters,
) -> (glam::Vec2, crate::math::Ray) {
    let camera = &scene.camera;
    let pixel = y as u64 * camera.width as u64 + x as u64;
    let mut sampler = Sampler::new(seed, CAMERA_STREAM, pixel, sample as u64);
    let centre = glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
    let offset = camera.filter.sample(sampler.next_2d());
    let ray = frame.generate_ray(centre + offset);
    trace_path(
        scene,
        ray,
        scene.integrator.max_scatter(),
        &mut sampler,
        record,
        counters,
    );
    (offset, ray)
}

/// Radiance of one camera sample of pixel `(x, y)` (f32 image pass), with its tracing counters.
/// `frame` is `scene.camera.frame::<f32>()`, built once per render.
#[allow(clippy::too_many_arguments)]
pub fn sample_pixel(
    scene: &Scene,
    frame: &CameraFrame<f32>,
    seed: u64,
    x: u32,
    y: u32,
    sample: u32,
    record: &mut PathRecord,
    counters: &mut TraceCounters,
) -> glam::Vec3 {
    trace_sample(scene, frame, seed, x, y, sample, record, counters);
    contribution::<f32>(scene, record, detached).into()
}

/// Renders the image of `scene`.
///
/// Rows are rendered in parallel; each pixel sums its own samples in a fixed order, so the image is
/// identical bit for bit whatever the number of threads.
pub fn render(scene: &Scene, options: &RenderOptions) -> (Image, RenderStats) {
    let start = std::time::Instant::now();
    let (width, height) = (scene.camera.width, scene.camera.height);
    let mut image = Image::new(width, height);
    let exhausted = AtomicU64::new(0);
    let invalid = AtomicU64::new(0);
    let bar = options.progress.then(|| {
        let bar = indicatif::ProgressBar::new(height as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} rows {elapsed}/{eta}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar
    });
    let spp = options.spp.max(1);
    let frame = scene.camera.frame::<f32>();
    let row_len = 3 * width as usize;
    if row_len > 0 {
        image
            .rgb
            .par_chunks_mut(row_len)
            .enumerate()
            .for_each(|(y, row)| {
                let y = y as u32;
                let mut record = PathRecord::default();
                let mut counters = TraceCounters::default();
                let mut row_invalid = 0u64;
                for x in 0..width {
                    let mut sum = glam::Vec3::ZERO;
                    for s in 0..spp {
                        let l = sample_pixel(
                            scene,
                            &frame,
                            options.seed,
                            x,
                            y,
                            s,
                            &mut record,
                            &mut counters,
                        );
                        if l.is_finite() {
                            sum += l;
                        } else {
                            if invalid.load(Ordering::Relaxed) == 0 && row_invalid == 0 {
                                eprintln!(
                                    "non-finite radiance {l} at pixel ({x}, {y}), sample {s}"
                                );
                            }
                            row_invalid += 1;
                        }
                    }
                    let mean = sum / spp as f32;
                    let i = 3 * x as usize;
                    row[i..i + 3].copy_from_slice(&mean.to_array());
                }
                exhausted.fetch_add(counters.exhausted, Ordering::Relaxed);
                invalid.fetch_add(row_invalid, Ordering::Relaxed);
                if let Some(bar) = &bar {
                    bar.inc(1);
                }
            });
    }
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let stats = RenderStats {
        samples: spp as u64 * width as u64 * height as u64,
        exhausted_rays: exhausted.into_inner(),
        invalid_samples: invalid.into_inner(),
        invalid_derivatives: 0,
        seconds: start.elapsed().as_secs_f64(),
    };
    (image, stats)
}
