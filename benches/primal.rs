//! Primal throughput on the default scene of the issue: a sphere on a box floor under a rectangle light,
//! 64×64, direct integrator. Criterion reports samples per second (a sample = camera ray + light sample
//! with its shadow ray + BSDF sample with its ray).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use implicit_psdr::integrator::{IntegratorKind, RenderOptions, render};
use implicit_psdr::scene::{Scene, load};
use std::hint::black_box;
use std::path::Path;

/// The default scene, `scenes/sphere_floor.json`, with the given integrator.
fn default_scene(integrator: IntegratorKind) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/sphere_floor.json");
    let mut scene = load(&path).expect("the default scene parses");
    scene.integrator = integrator;
    scene
}

fn primal(c: &mut Criterion) {
    let spp = 16u32;
    let options = RenderOptions {
        spp,
        seed: 0,
        progress: Default::default(),
    };
    let mut group = c.benchmark_group("primal_64x64");
    group.throughput(Throughput::Elements(spp as u64 * 64 * 64));
    group.sample_size(20);
    for (name, kind) in [
        ("direct", IntegratorKind::Direct),
        ("path3", IntegratorKind::Path { max_depth: 3 }),
    ] {
        let scene = default_scene(kind);
        // One render up front: prints the absolute rate once, beside criterion's statistics.
        let (_, stats) = render(&scene, &options);
        eprintln!(
            "{name}: {:.2} M samples/s ({} samples in {:.3} s, {} exhausted rays)",
            stats.samples as f64 / stats.seconds / 1e6,
            stats.samples,
            stats.seconds,
            stats.exhausted_rays
        );
        group.bench_function(name, |b| b.iter(|| black_box(render(&scene, &options))));
    }
    group.finish();
}

criterion_group!(benches, primal);
criterion_main!(benches);
