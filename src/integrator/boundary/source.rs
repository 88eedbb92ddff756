//! One interface for everything a boundary term samples, and the one loop that runs it (pbrt-v4's
//! `ImageTileIntegrator` owns the loop; its subclasses supply the per-sample work).
//!
//! A [`BoundarySource`] is prepared once per render (silhouette curves extracted, edges and outlines
//! listed) and then only answers for one sample at a time: it draws from the [`Sampler`] of its own
//! random stream and hands its contributions to a [`SampleSink`]. [`run_source`] runs its samples in
//! parallel chunks on the [`driver`]; [`run_term`] shares a term's budget between its sources
//! (equally, the first ones taking the remainder) and gives each a film of its own, which the caller turns into images (forward
//! mode, `term_images`) or into gradient entries (reverse mode). A term lists its sources in one
//! place ([`BoundaryTerm::sources`]).

use crate::film::{Film, Image, SampleSink, SplatFilm};
use crate::integrator::attach::{SceneAttach, for_each_window};
use crate::integrator::boundary::subpaths::CameraVertex;
use crate::integrator::driver::{self, RenderStats};
use crate::integrator::options::{DiffOptions, RenderOptions, VelocityField};
use crate::integrator::path::{PathRecord, TraceCounters};
use crate::integrator::surface_sampling::SurfaceSample;
use crate::sampler::Sampler;
use crate::scalar::Directions;
use crate::scene::Scene;

/// Boundary samples per parallel work item (results are merged in sample order: deterministic).
const CHUNK: u64 = 256;

/// What every sample of one pass needs: the scene whose selected parameters the pass differentiates
/// (a window of them, renumbered from slot 0, in forward mode) and its attached vertices.
pub struct Pass<'a> {
    /// The scene of the pass.
    pub scene: &'a Scene,
    /// Attached vertices with the pass's selected parameters.
    pub attach: SceneAttach<'a>,
}

impl<'a> Pass<'a> {
    /// The pass over `scene`'s selected parameters, moving shapes' points by the field `velocity`.
    pub fn new(scene: &'a Scene, velocity: VelocityField) -> Self {
        Self {
            scene,
            attach: SceneAttach::new(scene, velocity),
        }
    }
}

/// Buffers reused between the samples of one work item (each source uses the ones it needs).
#[derive(Default)]
pub struct Scratch {
    /// A camera path (the background beyond an edge) or a continued path.
    pub record: PathRecord,
    /// A second path record (a continued path truncated per depth).
    pub truncated: PathRecord,
    /// The crossings of a line with a shape.
    pub hits: Vec<SurfaceSample>,
    /// The camera side of a vertex.
    pub cams: Vec<CameraVertex>,
    /// A continued path's radiance per number of scattering vertices.
    pub by_depth: Vec<glam::Vec3>,
}

/// Something a boundary term samples: silhouettes, emitter outlines, crease edges, shadow lines,
/// prepared once per render, in any number type `S` (dual numbers in forward mode, [`crate::scalar::Rev`]
/// in reverse mode).
pub trait BoundarySource<S: Directions>: Sync {
    /// What progress reports the source's work as.
    fn stage(&self) -> &'static str;
    /// The source's random stream (each source draws its own numbers).
    fn stream(&self) -> u64;
    /// Whether the source takes a share of its term's samples (the scene has what it samples).
    fn takes_share(&self) -> bool;
    /// One sample: draws from `sampler` and hands its contributions, not yet divided by the number of
    /// samples, to `sink`.
    fn sample(
        &self,
        pass: &Pass,
        sampler: &mut Sampler,
        scratch: &mut Scratch,
        counters: &mut TraceCounters,
        sink: &mut dyn SampleSink<S>,
    );
}

/// A boundary term: the sources sharing its samples, prepared once per render.
pub trait BoundaryTerm: Sync {
    /// The sources, in the order their samples are drawn and added.
    fn sources<S: Directions>(&self) -> Vec<&dyn BoundarySource<S>>;
}

/// Runs samples `0..samples` of `source` in parallel chunks on the [`driver`] into `film`: sample `k`
/// draws from the [`Sampler`] of `(render.seed, source.stream())` for index `k`, between the tile's
/// `begin_sample` and `end_sample`. Returns the counts of the traced rays.
pub fn run_source<S: Directions, F: Film>(
    source: &dyn BoundarySource<S>,
    pass: &Pass,
    samples: u64,
    render: &RenderOptions,
    film: &mut F,
) -> RenderStats
where
    F::Tile: SampleSink<S>,
{
    if samples == 0 {
        return RenderStats::default();
    }
    let (seed, stream) = (render.seed, source.stream());
    let chunks = samples.div_ceil(CHUNK) as usize;
    driver::run(
        film,
        chunks,
        source.stage(),
        &render.progress,
        |c, tile, stats| {
            let c = c as u64;
            let mut scratch = Scratch::default();
            let mut counters = TraceCounters::default();
            for k in c * CHUNK..((c + 1) * CHUNK).min(samples) {
                let mut sampler = Sampler::new(seed, stream, 0, k);
                tile.begin_sample();
                source.sample(pass, &mut sampler, &mut scratch, &mut counters, tile);
                tile.end_sample();
            }
            stats.exhausted_rays += counters.exhausted;
        },
    )
}

/// Runs `term`'s sources with `samples` shared equally between those that take a share (the first
/// ones get the remainder; a source left with none is not run), each into a film of its own:
/// `film(n)` makes it for `n` samples, `done(film, n)` takes it back, source by source in order.
pub fn run_term<S: Directions, F: Film>(
    term: &impl BoundaryTerm,
    pass: &Pass,
    samples: u64,
    render: &RenderOptions,
    mut film: impl FnMut(u64) -> F,
    mut done: impl FnMut(F, u64),
) -> RenderStats
where
    F::Tile: SampleSink<S>,
{
    let sources = term.sources::<S>();
    let shares: Vec<(usize, bool)> = (sources.iter().enumerate())
        .map(|(i, s)| (i, s.takes_share()))
        .collect();
    let mut stats = RenderStats::default();
    for (i, n) in split_equally(samples, &shares) {
        let mut f = film(n);
        stats.absorb(run_source(sources[i], pass, n, render, &mut f));
        done(f, n);
    }
    stats
}

/// Forward mode: `term`'s images for the parameters in slots `0..count` of `scene` (a scene with its
/// [`crate::scene::Selection`] applied), `samples` for the
/// whole image, in passes of `S::COUNT` parameters. Each source's splats are summed in `f64` in sample
/// order and their mean added to `radiance[k]` and, with `coverage`, to `coverage[k]` (the same value
/// in the three channels; empty without it), source by source.
pub(crate) fn term_images<S: Directions>(
    scene: &Scene,
    count: usize,
    options: &DiffOptions,
    samples: u64,
    term: &impl BoundaryTerm,
    coverage: bool,
) -> (Vec<Image>, Vec<Image>, RenderStats) {
    let render = &options.render;
    let mut radiance = Vec::with_capacity(count);
    let mut covered = Vec::with_capacity(if coverage { count } else { 0 });
    let mut stats = RenderStats::default();
    for (r, c, s) in for_each_window(scene, count, S::COUNT, |windowed, width| {
        let (w, h) = (windowed.camera.width, windowed.camera.height);
        let mut r = vec![Image::new(w, h); width];
        let mut c = vec![Image::new(w, h); if coverage { width } else { 0 }];
        let s = run_term::<S, _>(
            term,
            &Pass::new(windowed, options.velocity),
            samples,
            render,
            |_| SplatFilm::<S>::new(w, h, width),
            |film, n| film.add_mean_to(n, &mut r, &mut c),
        );
        (r, c, s)
    }) {
        radiance.extend(r);
        covered.extend(c);
        stats.absorb(s);
    }
    (radiance, covered, stats)
}

/// Shares `samples` equally between the `kinds` that are present (the first ones get the remainder);
/// absent kinds, and kinds left with no sample, get no entry.
fn split_equally<K: Copy>(samples: u64, kinds: &[(K, bool)]) -> Vec<(K, u64)> {
    let present: Vec<K> = kinds.iter().filter(|k| k.1).map(|k| k.0).collect();
    let n = present.len() as u64;
    present
        .into_iter()
        .enumerate()
        .map(|(i, kind)| (kind, samples / n + u64::from((i as u64) < samples % n)))
        .filter(|&(_, k)| k > 0)
        .collect()
}

/// The radiance images (`fixed` normalisation) of `term`'s samples alone, `samples` for the whole
/// image, for the parameters of `selection`: a check of what [`super::motion`] leaves out (the curves
/// it leaves out must give exactly zero). Errors: those of [`crate::scene::Selection::apply`].
pub fn render_term(
    scene: &Scene,
    selection: &crate::scene::Selection,
    options: &DiffOptions,
    samples: u64,
    term: &impl BoundaryTerm,
) -> crate::error::Result<Vec<Image>> {
    let (selected, count) = (selection.apply(scene)?, selection.len());
    if count == 0 {
        return Ok(Vec::new());
    }
    let (radiance, _, _) = crate::scalar::dispatch_directions!(
        count,
        term_images(&selected, count, options, samples, term, false)
    );
    Ok(radiance)
}
