//! Closed-form checks of the primal integrators: a convex diffuse object in a constant environment, the
//! point-to-rectangle form factor, a white furnace, and determinism across thread counts.

use glam::{Vec2, Vec3 as G3};
use implicit_psdr::bsdf::Bsdf;
use implicit_psdr::camera::Camera;
use implicit_psdr::emitter::Emitter;
use implicit_psdr::film::Filter;
use implicit_psdr::integrator::path::{
    LightStrategy, PathRecord, PathVertex, TraceCounters, VertexKind, contribution, detached,
    sample_light,
};
use implicit_psdr::integrator::{IntegratorKind, RenderOptions, render};
use implicit_psdr::math::Ray;
use implicit_psdr::scene::{NamedEmitter, Scene, Shape};
use implicit_psdr::sdf::Sdf;
use implicit_psdr::{Param, Param3};
use std::f64::consts::PI;

fn camera(origin: [f32; 3], target: [f32; 3], fov: f32, w: u32, h: u32) -> Camera {
    Camera {
        origin: Param3::new(origin),
        target: Param3::new(target),
        up: Param3::new([0.0, 1.0, 0.0]),
        fov_y: Param::new(fov),
        width: w,
        height: h,
        filter: Filter::Tent,
    }
}

fn diffuse(a: f32) -> Bsdf {
    Bsdf::Diffuse {
        albedo: Param3::new([a; 3]),
    }
}

fn named(name: &str, emitter: Emitter) -> NamedEmitter {
    NamedEmitter {
        name: name.into(),
        emitter,
    }
}

fn environment(l: f32) -> NamedEmitter {
    named(
        "env",
        Emitter::Constant {
            radiance: Param3::new([l; 3]),
        },
    )
}

fn sphere(name: &str, c: [f32; 3], r: f32, albedo: f32) -> Shape {
    Shape::new(
        name,
        Sdf::Sphere {
            center: Param3::new(c),
            radius: Param::new(r),
        },
        diffuse(albedo),
    )
}

/// Distances along `ray` where it enters the sphere `(c, r)`, if it does.
fn ray_hits_sphere(ray: &Ray, c: G3, r: f32) -> bool {
    let oc = ray.o - c;
    let b = oc.dot(ray.d);
    let disc = b * b - (oc.length_squared() - r * r);
    disc >= 0.0 && -b + disc.sqrt() > 0.0
}

/// Classifies each pixel by rays through its filter footprint (radius 1 for the tent, plus a margin):
/// `Some(true)` all on the sphere, `Some(false)` all off it, `None` mixed.
fn coverage(cam: &Camera, c: G3, r: f32) -> Vec<Option<bool>> {
    let mut out = Vec::new();
    for y in 0..cam.height {
        for x in 0..cam.width {
            let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let mut hits = 0;
            let offsets = [-1.5f32, -0.75, 0.0, 0.75, 1.5];
            for dy in offsets {
                for dx in offsets {
                    let ray = cam.generate_ray(centre + Vec2::new(dx, dy));
                    hits += ray_hits_sphere(&ray, c, r) as usize;
                }
            }
            out.push(match hits {
                0 => Some(false),
                25 => Some(true),
                _ => None,
            });
        }
    }
    out
}

fn check_convex_in_environment(integrator: IntegratorKind) {
    let (rho, l) = (0.6f32, 1.5f32);
    let (c, r) = (G3::ZERO, 1.0);
    let cam = camera([0.0, 0.5, 4.0], [0.0, 0.0, 0.0], 40.0, 32, 32);
    let cover = coverage(&cam, c, r);
    let scene = Scene::new(
        cam,
        integrator,
        64,
        vec![sphere("ball", c.to_array(), r, rho)],
        vec![environment(l)],
    );
    let (image, stats) = render(
        &scene,
        &RenderOptions {
            spp: 128,
            seed: 3,
            progress: Default::default(),
        },
    );
    assert_eq!(stats.samples, 128 * 32 * 32);
    assert_eq!(stats.invalid_samples, 0);
    let (mut on, mut off) = (0, 0);
    let (mut sum_on, mut sum_off) = (0.0f64, 0.0f64);
    for (i, cov) in cover.iter().enumerate() {
        let v = image.rgb[3 * i];
        match cov {
            Some(true) => {
                on += 1;
                sum_on += v as f64;
                assert!(
                    (v - rho * l).abs() < 0.08 * rho * l,
                    "{integrator:?}: pixel {i} on the object: {v} vs {}",
                    rho * l
                );
            }
            Some(false) => {
                off += 1;
                sum_off += v as f64;
                assert_eq!(v, l, "{integrator:?}: pixel {i} sees the environment");
            }
            None => {}
        }
    }
    assert!(on > 100 && off > 100, "coverage {on} on, {off} off");
    let mean_on = sum_on / on as f64;
    assert!(
        (mean_on - (rho * l) as f64).abs() < 0.005 * (rho * l) as f64,
        "{integrator:?}: mean on the object {mean_on} vs {}",
        rho * l
    );
    assert!((sum_off / off as f64 - l as f64).abs() < 1e-6);
}

#[test]
fn convex_diffuse_object_in_environment_direct() {
    check_convex_in_environment(IntegratorKind::Direct);
}

#[test]
fn convex_diffuse_object_in_environment_path() {
    check_convex_in_environment(IntegratorKind::Path { max_depth: 4 });
}

/// Form factor from a point to a parallel rectangle `[x0, x1] × [y0, y1]` at height `h` above it
/// (normal facing the rectangle): the corner formula (Howell's catalogue, configuration B-3; Cohen and
/// Wallace 1993, eq. 4.9) `F(a, b) = 1/(2π) [A/√(1+A²) atan(B/√(1+A²)) + B/√(1+B²) atan(A/√(1+B²))]`
/// with `A = a/h`, `B = b/h` is odd in `a` and in `b`, so the rectangle is the signed sum over its corners.
fn point_to_rectangle_form_factor(x0: f64, x1: f64, y0: f64, y1: f64, h: f64) -> f64 {
    let corner = |a: f64, b: f64| {
        let (a, b) = (a / h, b / h);
        let (sa, sb) = ((1.0 + a * a).sqrt(), (1.0 + b * b).sqrt());
        (a / sa * (b / sa).atan() + b / sb * (a / sb).atan()) / (2.0 * PI)
    };
    corner(x1, y1) - corner(x0, y1) - corner(x1, y0) + corner(x0, y0)
}

#[test]
fn form_factor_closed_form_sanity() {
    // A huge rectangle covers the hemisphere: F → 1.
    let f = point_to_rectangle_form_factor(-1e4, 1e4, -1e4, 1e4, 1.0);
    assert!((f - 1.0).abs() < 1e-3, "{f}");
    // A small square of area A straight above at height h: F ≈ A / (π h²).
    let f = point_to_rectangle_form_factor(-0.005, 0.005, -0.005, 0.005, 1.0);
    assert!((f - 1e-4 / PI).abs() < 1e-3 * f, "{f}");
}

/// Irradiance at a point under a rectangle light through the next-event estimator and the generic
/// contribution: the outgoing radiance of a diffuse patch is `ρ/π · E`, `E = π L F`.
#[test]
fn rectangle_light_irradiance_matches_form_factor() {
    let (l, rho, h) = (5.0f32, 0.7f32, 1.3f32);
    let (cx, cz, a, b) = (0.4f32, -0.2f32, 1.0f32, 2.0f32);
    let scene = nee_scene(
        Emitter::Rectangle {
            center: Param3::new([cx, h, cz]),
            normal: -G3::Y,
            u: G3::X,
            size: [Param::new(a), Param::new(b)],
            radiance: Param3::new([l; 3]),
        },
        rho,
    );
    let estimate = nee_estimate(&scene, G3::ZERO, G3::Y, G3::new(0.3, 0.5, 0.4), 200);
    // The rectangle spans x ∈ cx ± a/2 and z ∈ cz ± b/2 at height h above the point.
    let f = point_to_rectangle_form_factor(
        (cx - a / 2.0) as f64,
        (cx + a / 2.0) as f64,
        (cz - b / 2.0) as f64,
        (cz + b / 2.0) as f64,
        h as f64,
    );
    let exact = rho as f64 / PI * (PI * l as f64 * f);
    assert!(
        (estimate - exact).abs() < 2e-3 * exact,
        "{estimate} vs {exact} (F = {f})"
    );
    // Seen from behind, the one-sided rectangle gives nothing.
    let behind = nee_estimate(
        &scene,
        G3::new(0.0, 2.0, 0.0),
        G3::Y,
        G3::new(0.0, 3.0, 0.5),
        8,
    );
    assert_eq!(behind, 0.0);
}

/// A scene with one emitter and one diffuse "patch" shape whose surface is never traced (its bounds lie
/// away from every shadow ray): the next-event estimator can be run at any point.
fn nee_scene(emitter: Emitter, rho: f32) -> Scene {
    let cam = camera([0.3, 0.5, 0.4], [0.0, 0.0, 0.0], 40.0, 4, 4);
    let mut scene = Scene::new(
        cam,
        IntegratorKind::Direct,
        1,
        vec![],
        vec![named("light", emitter)],
    );
    scene.shapes.push(Shape::new(
        "patch",
        Sdf::Sphere {
            center: Param3::new([0.0, -10.0, 0.0]),
            radius: Param::new(0.1),
        },
        diffuse(rho),
    ));
    scene
}

/// Mean over `m²` stratified light samples of the next-event estimate (MIS weight forced to 1) of the
/// radiance reflected by the patch at `p` (normal `n`) towards `camera`.
fn nee_estimate(scene: &Scene, p: G3, n: G3, camera: G3, m: usize) -> f64 {
    let wo = (camera - p).normalize();
    let mut counters = TraceCounters::default();
    let mut record = PathRecord {
        camera,
        vertices: vec![PathVertex {
            p,
            n,
            kind: VertexKind::Shape(0),
            pdf: 1.0,
            mis: 0.0,
        }],
        lights: vec![],
        strategy: LightStrategy::Derivative,
        ..PathRecord::default()
    };
    let mut sum = 0.0f64;
    for i in 0..m {
        for j in 0..m {
            let u = Vec2::new((i as f32 + 0.5) / m as f32, (j as f32 + 0.5) / m as f32);
            record.lights.clear();
            let strategy = LightStrategy::Derivative;
            if let Some(lv) =
                sample_light(scene, strategy, 0, 0, p, n, wo, 0.5, u, None, &mut counters)
            {
                record
                    .lights
                    .push(implicit_psdr::integrator::path::LightVertex { mis: 1.0, ..lv });
            }
            sum += contribution::<f32>(scene, &record, detached).x as f64;
        }
    }
    sum / (m * m) as f64
}

/// A sphere light wholly above the horizon gives the irradiance of a point source of intensity
/// `π r² L`: `E = π L (r/d)² cos θ` (Nusselt analog; sin² of the half-angle is `(r/d)²`).
#[test]
fn sphere_light_irradiance_matches_closed_form() {
    let (l, rho, r) = (3.0f32, 0.6f32, 0.5f32);
    let c = G3::new(0.8, 2.0, -0.4);
    let scene = nee_scene(
        Emitter::Sphere {
            center: Param3::new(c.to_array()),
            radius: Param::new(r),
            radiance: Param3::new([l; 3]),
        },
        rho,
    );
    let (p, n) = (G3::new(0.1, 0.0, 0.2), G3::Y);
    let estimate = nee_estimate(&scene, p, n, G3::new(0.3, 0.5, 0.4), 200);
    let d = c - p;
    let cos = n.dot(d.normalize()) as f64;
    let e = PI * l as f64 * (r as f64 / d.length() as f64).powi(2) * cos;
    let exact = rho as f64 / PI * e;
    assert!(
        (estimate - exact).abs() < 2e-3 * exact,
        "{estimate} vs {exact}"
    );
}

/// An unoccluded point in a constant environment `L` receives `E = π L`, by the light samples of the
/// derivative passes (which keep the sky light-sampled); the image passes leave the sky to the BSDF's
/// samples, and their light sample gives nothing for it (`tests/light_sampling.rs` checks their
/// estimate, `ρ L` on every pixel of a convex diffuse shape, to rounding).
#[test]
fn environment_irradiance_is_pi_l() {
    let (l, rho) = (2.0f32, 0.4f32);
    let scene = nee_scene(
        Emitter::Constant {
            radiance: Param3::new([l; 3]),
        },
        rho,
    );
    let n = G3::new(0.3, 0.9, -0.2).normalize();
    let camera = n * 2.0 + G3::X;
    let estimate = nee_estimate(&scene, G3::ZERO, n, camera, 400);
    let exact = (rho * l) as f64;
    assert!(
        (estimate - exact).abs() < 5e-3 * exact,
        "{estimate} vs {exact}"
    );
    let (u, wo) = (Vec2::new(0.3, 0.7), camera.normalize());
    let mut counters = TraceCounters::default();
    let image = LightStrategy::Image;
    assert!(
        sample_light(
            &scene,
            image,
            0,
            0,
            G3::ZERO,
            n,
            wo,
            0.5,
            u,
            None,
            &mut counters
        )
        .is_none()
    );
}

/// The floor slab whose top face is the plane `y = top`: a box as in the default scene, or the
/// equivalent half-space.
fn floor_sdf(top: f32, half_size: f32, as_box: bool) -> Sdf {
    if as_box {
        Sdf::Box {
            center: Param3::new([0.0, top - 0.5, 0.0]),
            half_size: Param3::new([half_size, 0.5, half_size]),
            rounding: Param::new(0.0),
        }
    } else {
        Sdf::Plane {
            normal: G3::Y,
            offset: Param::new(top),
        }
    }
}

/// The default scene of the issue: a sphere on a floor (a box, or a half-space with the same top face)
/// under a rectangle light.
fn default_scene(integrator: IntegratorKind, w: u32, h: u32) -> Scene {
    default_scene_with(integrator, w, h, false)
}

fn default_scene_with(integrator: IntegratorKind, w: u32, h: u32, box_floor: bool) -> Scene {
    let floor = Shape::new("floor", floor_sdf(-1.5, 50.0, box_floor), diffuse(0.5));
    let light = Emitter::Rectangle {
        center: Param3::new([1.5, 4.0, 2.0]),
        normal: -G3::Y,
        u: G3::X,
        size: [Param::new(1.0), Param::new(1.0)],
        radiance: Param3::new([40.0; 3]),
    };
    Scene::new(
        camera([0.0, 3.0, 4.0], [0.0, 0.0, 0.0], 45.0, w, h),
        integrator,
        16,
        vec![sphere("ball", [0.0; 3], 1.0, 0.8), floor],
        vec![named("light", light)],
    )
}

/// A floor lit by a rectangle light, seen through the renderer: each pixel is `ρ L F(x)` at the floor
/// point `x` under its centre (the tent filter blurs a smooth function only to second order).
#[test]
fn floor_under_rectangle_light_matches_form_factor() {
    check_floor_under_rectangle_light(false);
}

/// The same with a box floor: camera rays enter the box's bounding box exactly on its top face.
#[test]
fn box_floor_under_rectangle_light_matches_form_factor() {
    check_floor_under_rectangle_light(true);
}

fn check_floor_under_rectangle_light(box_floor: bool) {
    let (l, rho, hl) = (6.0f32, 0.5f32, 2.0f32);
    let cam = camera([0.0, 1.5, 2.0], [0.0, 0.0, 0.0], 40.0, 24, 24);
    let floor = Shape::new("floor", floor_sdf(0.0, 20.0, box_floor), diffuse(rho));
    let light = Emitter::Rectangle {
        center: Param3::new([0.0, hl, 0.0]),
        normal: -G3::Y,
        u: G3::X,
        size: [Param::new(1.0), Param::new(1.0)],
        radiance: Param3::new([l; 3]),
    };
    let scene = Scene::new(
        cam.clone(),
        IntegratorKind::Direct,
        64,
        vec![floor],
        vec![named("light", light)],
    );
    // The tolerance comes from the extent of the finite parts (camera and light here, the floor being a
    // half-space): it must be a usable size, not the 1e-8 of a point-sized extent.
    assert!(scene.trace.eps > 1e-6, "{:?}", scene.trace);
    let (image, _) = render(
        &scene,
        &RenderOptions {
            spp: 256,
            seed: 5,
            progress: Default::default(),
        },
    );
    let (mut worst, mut signed) = (0.0f64, 0.0f64);
    for y in 0..cam.height {
        for x in 0..cam.width {
            let ray = cam.generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            assert!(ray.d.y < 0.0, "every pixel sees the floor");
            let t = -ray.o.y / ray.d.y;
            let p = ray.at(t);
            let (px, pz) = (p.x as f64, p.z as f64);
            let f =
                point_to_rectangle_form_factor(-0.5 - px, 0.5 - px, -0.5 - pz, 0.5 - pz, hl as f64);
            let exact = (rho * l) as f64 * f;
            let v = image.pixel(x, y)[0] as f64;
            worst = worst.max((v - exact).abs() / exact);
            signed += (v - exact) / exact;
        }
    }
    // Per pixel: 256 samples leave a few percent of noise at grazing angles (the far rows).
    assert!(worst < 0.07, "worst relative pixel error {worst}");
    let bias = signed / (cam.width * cam.height) as f64;
    assert!(bias.abs() < 0.004, "mean relative error {bias}");
}

/// White furnace: an albedo-1, non-convex object (two spheres that see each other) in a constant
/// environment `L` reflects exactly `L` once every path escapes (here: all but a negligible fraction
/// within 24 bounces).
#[test]
fn white_furnace_path() {
    let l = 0.8f32;
    let scene = Scene::new(
        camera([0.0, 0.3, 4.0], [0.0, 0.0, 0.0], 40.0, 24, 24),
        IntegratorKind::Path { max_depth: 24 },
        64,
        vec![
            sphere("a", [-0.75, 0.0, 0.0], 0.7, 1.0),
            sphere("b", [0.75, 0.0, 0.0], 0.7, 1.0),
        ],
        vec![environment(l)],
    );
    let (image, stats) = render(
        &scene,
        &RenderOptions {
            spp: 256,
            seed: 11,
            progress: Default::default(),
        },
    );
    assert_eq!(stats.invalid_samples, 0);
    let mut sum = 0.0f64;
    for (i, v) in image.rgb.iter().enumerate() {
        assert!((v - l).abs() < 0.08 * l, "value {i}: {v} vs {l}");
        sum += *v as f64;
    }
    let mean = sum / image.rgb.len() as f64;
    assert!((mean - l as f64).abs() < 0.004 * l as f64, "mean {mean}");
}

/// Path tracing with one scattering vertex is the direct estimator, sample for sample.
#[test]
fn path_depth_one_equals_direct() {
    let options = RenderOptions {
        spp: 4,
        seed: 2,
        progress: Default::default(),
    };
    let (a, _) = render(&default_scene(IntegratorKind::Direct, 16, 16), &options);
    let (b, _) = render(
        &default_scene(IntegratorKind::Path { max_depth: 1 }, 16, 16),
        &options,
    );
    assert_eq!(a, b);
    // A second bounce only adds light.
    let (c, _) = render(
        &default_scene(IntegratorKind::Path { max_depth: 3 }, 16, 16),
        &options,
    );
    let (sa, sc): (f32, f32) = (a.rgb.iter().sum(), c.rgb.iter().sum());
    assert!(sc > sa * 1.01, "{sc} vs {sa}");
}

/// The default scene with its box floor: the floor must be lit from above.
#[test]
fn default_scene_box_floor_is_lit() {
    let options = RenderOptions {
        spp: 4,
        seed: 2,
        progress: Default::default(),
    };
    let (a, _) = render(
        &default_scene_with(IntegratorKind::Direct, 16, 16, true),
        &options,
    );
    let (b, _) = render(
        &default_scene_with(IntegratorKind::Direct, 16, 16, false),
        &options,
    );
    let (sa, sb): (f32, f32) = (a.rgb.iter().sum(), b.rgb.iter().sum());
    assert!(
        (sa - sb).abs() < 0.05 * sb,
        "box floor {sa} vs plane floor {sb}"
    );
}

/// The image does not depend on the thread count, bit for bit.
#[test]
fn same_seed_same_image_for_any_thread_count() {
    let scene = default_scene(IntegratorKind::Path { max_depth: 3 }, 20, 12);
    let options = RenderOptions {
        spp: 3,
        seed: 9,
        progress: Default::default(),
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| render(&scene, &options))
    };
    let (one, s1) = run(1);
    let (two, s2) = run(2);
    assert_eq!(one, two);
    assert_eq!(s1.exhausted_rays, s2.exhausted_rays);
    assert!(one.rgb.iter().any(|&v| v > 0.0));
}
