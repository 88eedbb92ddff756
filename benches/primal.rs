//! Primal throughput on the default scene of the issue: a sphere on a box floor under a rectangle light,
//! 64×64, direct integrator. Criterion reports samples per second (a sample = camera ray + light sample
//! with its shadow ray + BSDF sample with its ray).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use implicit_psdr::bsdf::Bsdf;
use implicit_psdr::camera::Camera;
use implicit_psdr::emitter::Emitter;
use implicit_psdr::film::Filter;
use implicit_psdr::integrator::{IntegratorKind, RenderOptions, render};
use implicit_psdr::scene::{NamedEmitter, Scene, Shape};
use implicit_psdr::sdf::Sdf;
use implicit_psdr::{Param, Param3};
use std::hint::black_box;

fn default_scene(integrator: IntegratorKind) -> Scene {
    let camera = Camera {
        origin: Param3::new([0.0, 3.0, 4.0]),
        target: Param3::new([0.0, 0.0, 0.0]),
        up: Param3::new([0.0, 1.0, 0.0]),
        fov_y: Param::new(45.0),
        width: 64,
        height: 64,
        filter: Filter::Tent,
    };
    let diffuse = |a: f32| Bsdf::Diffuse {
        albedo: Param3::new([a; 3]),
    };
    let shapes = vec![
        Shape::new(
            "sphere",
            Sdf::Sphere {
                center: Param3::new([0.0, 0.0, 0.0]),
                radius: Param::new(1.0),
            },
            diffuse(0.8),
        ),
        Shape::new(
            "floor",
            Sdf::Box {
                center: Param3::new([0.0, -2.0, 0.0]),
                half_size: Param3::new([50.0, 0.5, 50.0]),
                rounding: Param::new(0.0),
            },
            diffuse(0.5),
        ),
    ];
    let emitters = vec![NamedEmitter {
        name: "light".into(),
        emitter: Emitter::Rectangle {
            center: Param3::new([1.5, 4.0, 2.0]),
            normal: glam::Vec3::NEG_Y,
            u: glam::Vec3::X,
            size: [Param::new(1.0), Param::new(1.0)],
            radiance: Param3::new([40.0; 3]),
        },
    }];
    Scene::new(camera, integrator, 16, shapes, emitters)
}

fn primal(c: &mut Criterion) {
    let spp = 16u32;
    let options = RenderOptions {
        spp,
        seed: 0,
        progress: false,
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
