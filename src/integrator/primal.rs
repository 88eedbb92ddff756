//! The image: one camera path per sample, each pixel the mean of its own samples (the film offset of each
//! sample is drawn exactly from the pixel filter, so every sample's filter weight over its density is 1).

use super::driver::{self, RenderStats};
use super::options::RenderOptions;
use super::path::{
    LightStrategy, PathRecord, TraceCounters, contribution, detached, trace_path_after,
};
use crate::camera::CameraFrame;
use crate::film::{Image, PixelFilm, SampleSink};
use crate::math::Vec3;
use crate::sampler::{Sampler, stratified_2d};
use crate::scene::frustum::PixelShapes;
use crate::scene::shape_list::ShapeList;
use crate::scene::{Intersection, Scene, packet};

/// Stream of the [`Sampler`] used by camera paths.
pub const CAMERA_STREAM: u64 = 0;

/// Camera sample `sample` of pixel `(x, y)`: the film offset drawn from the pixel filter (pixels, from
/// the pixel centre), the camera ray through it and the ray's footprint growth
/// ([`CameraFrame::spread`]). `frame` is `scene.camera.frame::<f32>()`, built once per render.
#[inline]
pub fn camera_ray(
    scene: &Scene,
    frame: &CameraFrame<f32>,
    seed: u64,
    x: u32,
    y: u32,
    sample: u32,
) -> (glam::Vec2, crate::math::Ray, f32) {
    let pixel = y as u64 * scene.camera.width as u64 + x as u64;
    let centre = glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
    let film = stratified_2d(seed, CAMERA_STREAM, pixel, sample as u64);
    let offset = scene.camera.filter.sample(film);
    let ray = frame.generate_ray(centre + offset);
    (offset, ray, frame.spread(ray.d))
}

/// Traces camera sample `sample` of pixel `(x, y)` into `record`: draws the film offset from the pixel
/// filter, generates the ray through it and traces the path. Returns the offset (pixels, from the pixel
/// centre) and the camera ray. `frame` is `scene.camera.frame::<f32>()`, built once per render;
/// `shapes`, when known, the only shapes the pixel's camera rays can meet ([`PixelShapes::gather`]).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn trace_sample(
    scene: &Scene,
    frame: &CameraFrame<f32>,
    seed: u64,
    x: u32,
    y: u32,
    sample: u32,
    shapes: Option<&ShapeList>,
    record: &mut PathRecord,
    counters: &mut TraceCounters,
) -> (glam::Vec2, crate::math::Ray) {
    let pixel = y as u64 * scene.camera.width as u64 + x as u64;
    let mut sampler = Sampler::new(seed, CAMERA_STREAM, pixel, sample as u64);
    let (offset, ray, spread) = camera_ray(scene, frame, seed, x, y, sample);
    let max_scatter = scene.integrator.max_scatter();
    let first = (max_scatter > 0).then(|| scene.intersect_camera(&ray, spread, shapes));
    trace_path_after(
        scene,
        ray,
        first,
        max_scatter,
        &mut sampler,
        record,
        counters,
    );
    (offset, ray)
}

/// [`trace_sample`] for camera samples `samples` of pixel `(x, y)` (at most [`packet::LANES`] of
/// them), their camera rays' first hits found as one packet ([`Scene::intersect_packet`]: the same
/// hits, bit for bit; one by one where the lanes would not pay, [`Scene::packet_pays`]): calls
/// `each(sample, offset, ray, record)` after tracing each sample's path into `record`, in increasing
/// sample order.
#[allow(clippy::too_many_arguments)]
pub fn trace_samples(
    scene: &Scene,
    frame: &CameraFrame<f32>,
    seed: u64,
    x: u32,
    y: u32,
    samples: std::ops::Range<u32>,
    shapes: Option<&ShapeList>,
    record: &mut PathRecord,
    counters: &mut TraceCounters,
    mut each: impl FnMut(u32, glam::Vec2, crate::math::Ray, &PathRecord),
) {
    let count = samples.len();
    assert!(count <= packet::LANES);
    let max_scatter = scene.integrator.max_scatter();
    if max_scatter == 0 || !scene.packet_pays(count, shapes) {
        for s in samples {
            let (offset, ray) = trace_sample(scene, frame, seed, x, y, s, shapes, record, counters);
            each(s, offset, ray, record);
        }
        return;
    }
    let mut rays = [crate::math::Ray::new(glam::Vec3::ZERO, glam::Vec3::ZERO); packet::LANES];
    let mut offsets = [glam::Vec2::ZERO; packet::LANES];
    let mut spreads = [0.0; packet::LANES];
    for (j, s) in samples.clone().enumerate() {
        (offsets[j], rays[j], spreads[j]) = camera_ray(scene, frame, seed, x, y, s);
    }
    let mut firsts = [Intersection::Miss; packet::LANES];
    scene.intersect_packet(
        &rays[..count],
        &spreads[..count],
        shapes,
        &mut firsts[..count],
    );
    let pixel = y as u64 * scene.camera.width as u64 + x as u64;
    for (j, s) in samples.enumerate() {
        let mut sampler = Sampler::new(seed, CAMERA_STREAM, pixel, s as u64);
        trace_path_after(
            scene,
            rays[j],
            Some(firsts[j]),
            max_scatter,
            &mut sampler,
            record,
            counters,
        );
        each(s, offsets[j], rays[j], record);
    }
}

/// Radiance of one camera sample of pixel `(x, y)` (f32 image pass), with its tracing counters.
/// `frame` and `shapes` as for [`trace_sample`].
#[allow(clippy::too_many_arguments)]
pub fn sample_pixel(
    scene: &Scene,
    frame: &CameraFrame<f32>,
    seed: u64,
    x: u32,
    y: u32,
    sample: u32,
    shapes: Option<&ShapeList>,
    record: &mut PathRecord,
    counters: &mut TraceCounters,
) -> glam::Vec3 {
    trace_sample(scene, frame, seed, x, y, sample, shapes, record, counters);
    contribution::<f32>(scene, record, detached).into()
}

/// Renders the image of `scene`.
///
/// Rows are rendered in parallel ([`driver::run`]); each pixel sums its own samples in a fixed order,
/// so the image is identical bit for bit whatever the number of threads.
pub fn render(scene: &Scene, options: &RenderOptions) -> (Image, RenderStats) {
    render_with(scene, options, LightStrategy::Image)
}

/// [`render`] with the light samples of `strategy`: [`LightStrategy::Derivative`] gives, bit for bit,
/// the image of the interior derivative pass with the same options (reverse mode's pixel values).
pub(crate) fn render_with(
    scene: &Scene,
    options: &RenderOptions,
    strategy: LightStrategy,
) -> (Image, RenderStats) {
    let start = std::time::Instant::now();
    let (width, height) = (scene.camera.width, scene.camera.height);
    let spp = options.spp.max(1);
    let frame = scene.camera.frame::<f32>();
    let mut film = PixelFilm::<f32>::new(width, height, 0);
    let mut stats = driver::run(
        &mut film,
        height as usize,
        "image",
        &options.progress,
        |y, tile, stats| {
            let y = y as u32;
            let mut record = PathRecord {
                strategy,
                ..PathRecord::default()
            };
            let mut counters = TraceCounters::default();
            let mut pixel_shapes = PixelShapes::default();
            for x in 0..width {
                let pixel = (y * width + x) as usize;
                let shapes = pixel_shapes.gather(scene, &frame, x, y, spp);
                for first in (0..spp).step_by(packet::LANES) {
                    let samples = first..(first + packet::LANES as u32).min(spp);
                    trace_samples(
                        scene,
                        &frame,
                        options.seed,
                        x,
                        y,
                        samples,
                        shapes,
                        &mut record,
                        &mut counters,
                        |s, _, _, record| {
                            let l: glam::Vec3 = contribution::<f32>(scene, record, detached).into();
                            if l.is_finite() {
                                tile.add_own(pixel, Vec3::from(l), 1.0);
                            } else {
                                stats.invalid(false, || {
                                    format!(
                                        "non-finite radiance {l} at pixel ({x}, {y}), sample {s}"
                                    )
                                });
                            }
                        },
                    );
                }
            }
            stats.exhausted_rays += counters.exhausted;
        },
    );
    stats.samples = spp as u64 * width as u64 * height as u64;
    stats.seconds = start.elapsed().as_secs_f64();
    (film.image(spp), stats)
}
