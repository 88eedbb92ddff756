//! The scene's bounding volume hierarchy against testing every shape: the same nearest hit, bit for bit,
//! and the same answer to "is anything in the way", on many random rays through random scenes of many
//! shapes (hits, misses, grazes, rays starting on surfaces, successive hits along lines), near the
//! origin and far from it; the shapes gathered for a pixel's camera rays hold every shape those rays
//! meet (tiny fields of view, far from the origin, the eye inside shapes' boxes); and the same image
//! and derivative image of a scene of many balls.

mod common;

use common::SplitMix;
use glam::Vec3;
use implicit_psdr::bsdf::Bsdf;
use implicit_psdr::camera::Camera;
use implicit_psdr::film::Filter;
use implicit_psdr::integrator::{
    DiffOptions, IntegratorKind, RenderOptions, render, render_derivatives,
};
use implicit_psdr::math::Ray;
use implicit_psdr::scene::frustum::PixelShapes;
use implicit_psdr::scene::{Intersection, Scene, Shape, Surface};
use implicit_psdr::sdf::Sdf;

fn diffuse() -> Bsdf {
    Bsdf::Diffuse {
        albedo: [0.6, 0.6, 0.6].into(),
    }
}

/// `n` random shapes of many kinds (spheres, rounded and sharp boxes, tori, transformed cylinders,
/// unions and smooth unions) in a cube of half-width 4 around `offset`, some overlapping, plus a floor
/// plane when `plane`.
fn random_scene(n: usize, seed: u64, offset: Vec3, plane: bool) -> Scene {
    let mut rng = SplitMix(seed);
    let mut shapes = Vec::new();
    for i in 0..n {
        let c = offset + rng.point(4.0);
        let r = rng.range(0.05, 0.6);
        let sdf = match i % 6 {
            0 => Sdf::sphere(c.to_array(), r),
            1 => Sdf::cuboid(c.to_array(), [r, 0.5 * r, 0.8 * r], 0.1 * r),
            2 => Sdf::cuboid(c.to_array(), [0.7 * r, r, 0.3 * r], 0.0),
            3 => Sdf::torus(c.to_array(), rng.direction(), r, 0.3 * r),
            4 => Sdf::transform(
                Sdf::cylinder([0.0; 3], Vec3::Y, r, 0.5 * r, 0.0),
                c.to_array(),
                rng.direction(),
                rng.range(0.0, 90.0),
                rng.range(0.5, 2.0),
            ),
            _ => {
                let d = rng.direction() * r;
                let pair = vec![
                    Sdf::sphere((c - d).to_array(), 0.7 * r),
                    Sdf::sphere((c + d).to_array(), 0.7 * r),
                ];
                if i % 12 == 5 {
                    Sdf::union(pair)
                } else {
                    Sdf::smooth_union(pair, 0.3 * r)
                }
            }
        };
        shapes.push(Shape::new(format!("s{i}"), sdf, diffuse()));
    }
    if plane {
        shapes.push(Shape::new(
            "floor",
            Sdf::plane(Vec3::Y, offset.y - 4.5),
            diffuse(),
        ));
    }
    let camera = Camera::new(
        offset + Vec3::new(0.0, 0.0, 12.0),
        offset,
        Vec3::Y,
        40.0,
        8,
        8,
        Filter::Tent,
    );
    Scene::new(camera, IntegratorKind::Direct, 1, shapes, vec![])
}

fn brute(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    s.use_bvh = false;
    s
}

/// A point on or near the surface of a random shape: its bounds' centre, or a hit of a ray at it.
fn aim(scene: &Scene, rng: &mut SplitMix) -> Vec3 {
    let shape =
        &scene.shapes[(rng.next() * scene.shapes.len() as f32) as usize % scene.shapes.len()];
    let b = shape.bounds;
    if b.is_finite() {
        b.min + (b.max - b.min) * Vec3::new(rng.next(), rng.next(), rng.next())
    } else {
        rng.point(4.0)
    }
}

/// Counts of what the compared queries met.
#[derive(Debug, Default)]
struct Met {
    hits: usize,
    misses: usize,
    on_surface: usize,
    blocked: usize,
}

/// The nearest hit along `ray` with and without the hierarchy: equal, bit for bit.
fn same_nearest(
    with: &Scene,
    without: &Scene,
    ray: &Ray,
    t_max: f32,
    leaving: Option<usize>,
    what: &str,
) -> Intersection {
    let a = with.intersect_leaving(ray, t_max, leaving);
    let b = without.intersect_leaving(ray, t_max, leaving);
    assert_eq!(
        a, b,
        "{what}: ray {ray:?}, t_max {t_max}, leaving {leaving:?}"
    );
    let spread = 1e-3;
    let (a, b) = (
        with.intersect_resolving(ray, t_max, spread),
        without.intersect_resolving(ray, t_max, spread),
    );
    assert_eq!(a, b, "{what} (camera ray): ray {ray:?}");
    a
}

/// Random rays of every kind through `scene`, compared with and without the hierarchy.
fn compare(scene: &Scene, rays: usize, seed: u64) -> Met {
    let without = brute(scene);
    let mut rng = SplitMix(seed);
    let mut met = Met::default();
    let centre = scene.camera.target.value();
    let mut exhausted = (0u64, 0u64);
    for k in 0..rays {
        let o = centre + rng.point(7.0);
        // Aimed at a shape's box (mostly hits), or anywhere (mostly misses).
        let d = if k % 3 == 0 {
            rng.direction()
        } else {
            (aim(scene, &mut rng) - o)
                .try_normalize()
                .unwrap_or(Vec3::X)
        };
        let ray = Ray::new(o, d);
        let t_max = if k % 5 == 0 {
            rng.range(0.5, 10.0)
        } else {
            f32::INFINITY
        };
        let first = same_nearest(scene, &without, &ray, t_max, None, "random");
        let blocked = scene.shapes_block(&ray, t_max, None, &mut exhausted.0);
        assert_eq!(
            blocked,
            without.shapes_block(&ray, t_max, None, &mut exhausted.1),
            "occlusion: ray {ray:?} t_max {t_max}"
        );
        met.blocked += blocked as usize;
        let Intersection::Hit(hit) = first else {
            met.misses += 1;
            continue;
        };
        met.hits += 1;
        let Surface::Shape(i) = hit.surface else {
            continue;
        };
        // Successive hits along the line, each ray starting exactly on the surface it met, both ways
        // along the line: the tracer probes which side it leaves into.
        let mut p = hit.p;
        let mut from = i;
        for _ in 0..6 {
            met.on_surface += 1;
            let n = scene.shapes[from].normal(p);
            let back = Ray::new(p, -d);
            let leaving = scene.leaving(from, n, -d);
            same_nearest(
                scene,
                &without,
                &back,
                f32::INFINITY,
                leaving,
                "back along the line",
            );
            let leaving = scene.leaving(from, n, d);
            let next = Ray::new(p, d);
            match same_nearest(
                scene,
                &without,
                &next,
                f32::INFINITY,
                leaving,
                "along the line",
            ) {
                Intersection::Hit(h) => match h.surface {
                    Surface::Shape(j) => {
                        p = h.p;
                        from = j;
                    }
                    Surface::Emitter(_) => break,
                },
                _ => break,
            }
        }
        // Grazing: a ray through the hit point along the tangent plane, started off it, and a
        // shadow-like ray leaving it (offset as the integrators offset it).
        let n = scene.shapes[i].normal(hit.p);
        let tangent = n.any_orthonormal_vector();
        let graze = Ray::new(hit.p - 2.0 * tangent, tangent);
        same_nearest(scene, &without, &graze, f32::INFINITY, None, "grazing");
        let w = (n + rng.direction()).try_normalize().unwrap_or(n);
        let o = scene.offset_origin(i, hit.p, n, w);
        let leave = Ray::new(o, w);
        let leaving = scene.leaving(i, n, w);
        same_nearest(scene, &without, &leave, f32::INFINITY, leaving, "leaving");
        assert_eq!(
            scene.shapes_block(&leave, 5.0, leaving, &mut exhausted.0),
            without.shapes_block(&leave, 5.0, leaving, &mut exhausted.1),
            "occlusion leaving shape {i}: {leave:?}"
        );
    }
    met
}

/// Shadow rays in runs from one small patch towards one small light, as a pixel's samples cast them,
/// each told which shape blocked the one before ([`Scene::shapes_block_after`]): every answer is the
/// walk's own. Returns how many rays a blocker known from the ray before blocked too.
fn shadow_runs_get_the_walks_answers(scene: &Scene, seed: u64) -> usize {
    let mut rng = SplitMix(seed);
    let mut exhausted = 0;
    let mut blocker = None;
    let mut repeated = 0;
    for run in 0..300 {
        let patch = aim(scene, &mut rng) + rng.point(0.5);
        let light = scene.camera.target.value() + rng.point(6.0) + Vec3::Y * 6.0;
        for k in 0..12 {
            let from = patch + rng.point(0.05);
            let to = light + rng.point(0.3);
            // Now and then the ray leaves a shape: the one that blocked the ray before.
            let leaving = (k % 5 == 4)
                .then_some(blocker)
                .flatten()
                .map(|i: u32| i as usize);
            let (ray, t_max) = if run % 7 == 6 {
                (Ray::new(from, rng.direction()), f32::INFINITY)
            } else {
                (
                    Ray::new(from, (to - from).normalize()),
                    (to - from).length(),
                )
            };
            let before = blocker;
            let walked = scene.shapes_block(&ray, t_max, leaving, &mut exhausted);
            let after =
                scene.shapes_block_after(&ray, t_max, leaving, &mut blocker, &mut exhausted);
            assert_eq!(
                after, walked,
                "run {run} ray {k}: {ray:?} to {t_max}, blocker {before:?}"
            );
            repeated += (after && before.is_some() && before == blocker) as usize;
        }
    }
    repeated
}

#[test]
fn a_shadow_ray_told_the_last_blocker_gets_the_walks_answer() {
    let far = Vec3::new(1e5, -3e4, 2e4);
    for (seed, n, offset, plane) in [
        (11, 200, Vec3::ZERO, true),
        (12, 600, Vec3::ZERO, false),
        (13, 40, Vec3::ZERO, true),
        (14, 200, far, true),
    ] {
        let scene = random_scene(n, seed, offset, plane);
        let repeated = shadow_runs_get_the_walks_answers(&scene, seed);
        // The known blocker often decides: the test sees the shortcut taken.
        assert!(
            repeated > 100,
            "seed {seed}: {repeated} rays blocked by the blocker before"
        );
    }
}

#[test]
fn nearest_hits_and_occlusion_match_testing_every_shape() {
    for (seed, n, plane) in [(1, 40, true), (2, 200, false), (3, 600, true), (4, 7, true)] {
        let scene = random_scene(n, seed, Vec3::ZERO, plane);
        let met = compare(&scene, 400, seed + 100);
        // Each kind of query met enough cases to mean something.
        assert!(
            met.hits > 100 && met.misses > 20 && met.on_surface > 300 && met.blocked > 50,
            "{n} shapes: {met:?}"
        );
    }
}

#[test]
fn far_from_the_origin_the_hierarchy_still_keeps_every_shape() {
    // At 10⁵ the local tolerance (16 ulps) is about 0.2: far larger than the floor of a shape's size,
    // and growing along every ray; the node tests must grow with it.
    for (seed, offset) in [
        (5, Vec3::new(1e5, -3e4, 2e4)),
        (6, Vec3::new(-4e3, 7e3, 1e4)),
    ] {
        let scene = random_scene(150, seed, offset, true);
        let met = compare(&scene, 300, seed + 200);
        assert!(met.hits > 50 && met.misses > 20, "{offset}: {met:?}");
    }
}

/// For every pixel of `scene`'s camera, the shapes [`PixelShapes`] gathers hold every shape that
/// camera rays through the pixel's filter support meet (their intervals along the ray are empty for
/// the others), and tracing them alone gives the intersection tracing the scene does, bit for bit.
/// Film offsets on a grid over the filter's sampling domain, its corners included. Returns the
/// number of rays that hit a shape.
fn pixel_shapes_hold_what_camera_rays_meet(scene: &Scene, what: &str) -> usize {
    let frame = scene.camera.frame::<f32>();
    let filter = scene.camera.filter;
    let mut gathered = PixelShapes::default();
    let mut hits = 0;
    const GRID: usize = 5;
    for y in 0..scene.camera.height {
        for x in 0..scene.camera.width {
            let list = gathered
                .gather(scene, &frame, x, y, 16)
                .unwrap_or_else(|| panic!("{what}: no shapes gathered at ({x}, {y})"))
                .clone();
            let shapes = list.indices();
            assert!(shapes.windows(2).all(|w| w[0] < w[1]), "{what}: order");
            for k in 0..GRID * GRID {
                let u = |i: usize| (i as f32 / (GRID - 1) as f32).min(1.0 - f32::EPSILON);
                let offset = filter.sample(glam::Vec2::new(u(k % GRID), u(k / GRID)));
                let centre = glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let ray = frame.generate_ray(centre + offset);
                for (i, shape) in scene.shapes.iter().enumerate() {
                    if !shapes.contains(&(i as u32)) {
                        assert_eq!(
                            scene.trace_interval(shape, &ray, f32::INFINITY),
                            None,
                            "{what}: pixel ({x}, {y}) offset {offset} dropped shape {i}"
                        );
                    }
                }
                let spread = frame.spread(ray.d);
                let among = scene.intersect_among(&ray, f32::INFINITY, spread, &list);
                let all = scene.intersect_resolving(&ray, f32::INFINITY, spread);
                assert_eq!(among, all, "{what}: pixel ({x}, {y}) offset {offset}");
                hits += matches!(all, Intersection::Hit(_)) as usize;
            }
        }
    }
    hits
}

#[test]
fn a_pixels_shapes_hold_every_shape_its_camera_rays_meet() {
    // The random scenes' camera, far from the origin too; a field of view of a thousandth of a
    // degree (a pixel is then a few ulps of a direction wide) aimed at a shape; the eye inside
    // shapes' boxes.
    for (seed, offset, fov) in [
        (21, Vec3::ZERO, 40.0),
        (22, Vec3::new(1e5, -3e4, 2e4), 40.0),
        (23, Vec3::ZERO, 1e-3),
        (24, Vec3::new(-4e3, 7e3, 1e4), 1e-3),
    ] {
        let mut scene = random_scene(120, seed, offset, true);
        let target = scene.shapes[0].bounds.center();
        let eye = scene.camera.origin.value();
        if fov < 1.0 {
            scene.camera = Camera::new(eye, target, Vec3::Y, fov, 8, 8, Filter::Tent);
        }
        let what = format!("seed {seed}, offset {offset}, fov {fov}");
        let hits = pixel_shapes_hold_what_camera_rays_meet(&scene, &what);
        assert!(hits > 40, "{what}: {hits} hits");
    }
    for filter in [Filter::Box, Filter::Gaussian] {
        let mut scene = random_scene(120, 25, Vec3::ZERO, false);
        let c = scene.shapes[7].bounds.center();
        scene.camera = Camera::new(c, c + Vec3::Z, Vec3::Y, 90.0, 8, 8, filter);
        let what = format!("eye inside shape 7's box, {filter:?}");
        assert!(pixel_shapes_hold_what_camera_rays_meet(&scene, &what) > 0);
    }
}

/// `n` balls of radius 0.15 in a cube of half-width 1.5 above a box floor, under a rectangle light, 24×24.
fn balls(n: usize) -> Scene {
    let mut rng = SplitMix(9);
    let mut shapes: Vec<Shape> = (0..n)
        .map(|i| {
            let c = rng.point(1.5);
            Shape::new(
                format!("ball{i}"),
                Sdf::sphere(c.to_array(), 0.15),
                diffuse(),
            )
        })
        .collect();
    shapes.push(Shape::new(
        "floor",
        Sdf::cuboid([0.0, -2.0, 0.0], [10.0, 0.5, 10.0], 0.25),
        diffuse(),
    ));
    let json = r#"{"name": "light", "type": "rectangle", "center": [1.5, 4, 2], "normal": [0, -1, 0],
        "u": [1, 0, 0], "size": [1, 1], "radiance": [40, 40, 40]}"#;
    let light = common::deriv::scene_json(&format!(
        r#"{{"camera": {{"origin": [0, 3, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 45,
              "width": 24, "height": 24}},
            "integrator": {{"type": "direct"}}, "shapes": [], "emitters": [{json}]}}"#
    ));
    Scene::new(
        light.camera.clone(),
        IntegratorKind::Direct,
        4,
        shapes,
        light.emitters.clone(),
    )
}

#[test]
fn a_scene_of_many_balls_renders_the_same_image_and_derivative_with_the_hierarchy() {
    let with = balls(300);
    assert!(with.bvh.len() == with.shapes.len());
    let without = brute(&with);
    // Enough samples per pixel that the camera rays trace their pixel's gathered shapes.
    let options = RenderOptions {
        spp: 8,
        seed: 3,
        progress: Default::default(),
    };
    let (a, sa) = render(&with, &options);
    let (b, sb) = render(&without, &options);
    assert_eq!(a.rgb, b.rgb, "images differ");
    assert_eq!(sa.exhausted_rays, sb.exhausted_rays);
    let (mut w, mut wo) = (with.clone(), without.clone());
    w.integrator = IntegratorKind::Path { max_depth: 3 };
    wo.integrator = w.integrator;
    assert_eq!(render(&w, &options).0.rgb, render(&wo, &options).0.rgb);
    // The complete derivative: interior, silhouettes and shadows (their rays and tangent lines).
    let selection = with.select(&["ball0.radius", "ball7.center.x"]).unwrap();
    let diff = DiffOptions {
        render: options.clone(),
        ..DiffOptions::default()
    };
    let da = render_derivatives(&with, &selection, &diff).unwrap();
    let db = render_derivatives(&without, &selection, &diff).unwrap();
    assert_eq!(da.image.rgb, db.image.rgb);
    for (x, y) in da.total().iter().zip(db.total()) {
        assert_eq!(x.rgb, y.rgb, "derivative images differ");
    }
    // The images are not trivial: some pixels see balls.
    assert!(a.rgb.iter().any(|&v| v > 0.0));
}

#[test]
fn changing_shapes_in_place_and_refreshing_rebuilds_the_hierarchy() {
    let mut scene = random_scene(50, 12, Vec3::ZERO, false);
    let far = Shape::new("far", Sdf::sphere([0.0, 0.0, -30.0], 1.0), diffuse());
    scene.shapes[3] = far;
    scene.refresh_bvh();
    let ray = Ray::new(Vec3::new(0.0, 0.0, -40.0), Vec3::Z);
    match scene.intersect(&ray, f32::INFINITY) {
        Intersection::Hit(h) => assert_eq!(h.surface, Surface::Shape(3)),
        other => panic!("{other:?}"),
    }
    compare(&scene, 50, 13);
    // A parameter change rebuilds it too.
    let moved = scene.with_parameter("far.center.z", -20.0).unwrap();
    match moved.intersect(&ray, f32::INFINITY) {
        Intersection::Hit(h) => assert!((h.t - 19.0).abs() < 1e-3, "{h:?}"),
        other => panic!("{other:?}"),
    }
}
