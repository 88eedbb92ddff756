//! Camera rays eight at a time (`Scene::intersect_packet`) against the scalar query, one ray at a time:
//! the same first hit, bit for bit (parameter, point, normal, surface), on every example scene's camera
//! rays and on random rays through scenes of closed-form shapes (spheres, boxes, cylinders, planes,
//! similarity transforms of them), shapes without one, emitters and a plane: hits, misses, grazes of
//! spheres, rays along axes, along a cylinder's axis and in its caps' planes, rays from inside shapes
//! and from their surfaces, near the origin and far from it, large and small. The packet must also answer most of a
//! simple scene's camera rays in its lanes (else it is only the scalar query with extra work).

mod common;

use common::SplitMix;
use glam::Vec3;
use implicit_psdr::integrator::camera_ray;
use implicit_psdr::math::Ray;
use implicit_psdr::scene::frustum::PixelShapes;
use implicit_psdr::scene::packet::LANES;
use implicit_psdr::scene::shape_list::ShapeList;
use implicit_psdr::scene::{Intersection, Scene, load, parse};
use std::path::Path;

/// Compares the packet of `rays` (at most eight) with the scalar query ray by ray, bit for bit (the
/// `Debug` text tells `-0.0` from `0.0`). Returns how many lanes the packet answered one by one.
fn same_hits(
    scene: &Scene,
    rays: &[Ray],
    spreads: &[f32],
    shapes: Option<&ShapeList>,
    what: &str,
) -> usize {
    let mut out = vec![Intersection::Miss; rays.len()];
    let fallbacks = scene.intersect_packet(rays, spreads, shapes, &mut out);
    for (k, ray) in rays.iter().enumerate() {
        let want = scene.intersect_camera(ray, spreads[k], shapes);
        assert_eq!(
            format!("{:?}", out[k]),
            format!("{want:?}"),
            "{what}: lane {k} of {}, ray {ray:?}, spread {}",
            rays.len(),
            spreads[k]
        );
    }
    fallbacks
}

/// Every pixel's camera rays at `spp` samples, in packets as the renderer forms them; returns the
/// fraction of rays answered in lanes.
fn camera_rays_agree(scene: &Scene, spp: u32, what: &str) -> f64 {
    let frame = scene.camera.frame::<f32>();
    let mut pixel_shapes = PixelShapes::default();
    let (mut rays_total, mut fallbacks) = (0, 0);
    for y in 0..scene.camera.height {
        for x in 0..scene.camera.width {
            let shapes = pixel_shapes.gather(scene, &frame, x, y, spp);
            for first in (0..spp).step_by(LANES) {
                let samples = first..(first + LANES as u32).min(spp);
                let (rays, spreads): (Vec<Ray>, Vec<f32>) = samples
                    .map(|s| {
                        let (_, ray, spread) = camera_ray(scene, &frame, 7, x, y, s);
                        (ray, spread)
                    })
                    .unzip();
                rays_total += rays.len();
                fallbacks += same_hits(scene, &rays, &spreads, shapes, what);
            }
        }
    }
    1.0 - fallbacks as f64 / rays_total as f64
}

#[test]
fn every_example_scenes_camera_rays_hit_what_the_scalar_query_hits() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut checked = 0;
    for entry in std::fs::read_dir(&root).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "json") {
            let mut scene = load(&path).unwrap();
            // A smaller film: every pixel is still checked, in less time.
            scene.camera.width = scene.camera.width.min(48);
            scene.camera.height = scene.camera.height.min(36);
            for spp in [3, 8, 16] {
                let decided = camera_rays_agree(&scene, spp, &path.display().to_string());
                println!("{}: {spp} spp, {decided:.3} in lanes", path.display());
            }
            checked += 1;
        }
    }
    assert!(checked >= 7, "found {checked} example scenes");
}

/// The default scene's camera rays (a ball on a rounded box floor, one rectangle light): nearly all
/// answered in lanes. Measured: 0.99 at 64×64.
#[test]
fn the_packet_answers_the_default_scenes_camera_rays_in_its_lanes() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/sphere_floor.json");
    let scene = load(&path).unwrap();
    let decided = camera_rays_agree(&scene, 8, "default scene");
    println!("default scene: {decided:.4} of camera rays answered in lanes");
    assert!(decided > 0.95, "{decided}");
}

/// A scene of closed-form shapes (spheres, rounded and sharp boxes, a shape translated, a plane), shapes
/// without one (a torus, a smooth union) and a rectangle light, around `offset`, `scale` times the
/// size; the camera looks at its centre from `eye` (relative, unscaled).
fn mixed_scene(offset: Vec3, scale: f32, eye: Vec3, plane: bool) -> Scene {
    let p = |v: [f32; 3]| {
        let v = offset + Vec3::from(v) * scale;
        format!("[{}, {}, {}]", v.x, v.y, v.z)
    };
    let s = |x: f32| x * scale;
    let mut shapes = vec![
        format!(
            r#"{{"name": "ball", "sdf": {{"type": "sphere", "center": {}, "radius": {}}}}}"#,
            p([0.0, 0.0, 0.0]),
            s(1.0)
        ),
        format!(
            r#"{{"name": "small", "sdf": {{"type": "sphere", "center": {}, "radius": {}}}}}"#,
            p([1.6, 0.9, 0.4]),
            s(0.3)
        ),
        format!(
            r#"{{"name": "floor", "sdf": {{"type": "box", "center": {}, "half_size": [{}, {}, {}], "rounding": {}}}}}"#,
            p([0.0, -2.0, 0.0]),
            s(8.0),
            s(0.5),
            s(8.0),
            s(0.25)
        ),
        format!(
            r#"{{"name": "crate", "sdf": {{"type": "box", "center": {}, "half_size": [{}, {}, {}], "rounding": 0}}}}"#,
            p([-1.8, -0.9, 0.6]),
            s(0.5),
            s(0.6),
            s(0.4)
        ),
        format!(
            r#"{{"name": "moved", "translate": {}, "sdf": {{"type": "sphere", "center": [0, 0, 0], "radius": {}}}}}"#,
            p([0.4, 1.5, -1.2]),
            s(0.45)
        ),
        format!(
            r#"{{"name": "ring", "sdf": {{"type": "torus", "center": {}, "axis": [0, 1, 0], "major_radius": {}, "minor_radius": {}}}}}"#,
            p([1.5, -1.2, 1.5]),
            s(0.5),
            s(0.15)
        ),
        format!(
            r#"{{"name": "blob", "sdf": {{"type": "smooth_union", "k": {}, "children": [
                {{"type": "sphere", "center": {}, "radius": {}}},
                {{"type": "sphere", "center": {}, "radius": {}}}]}}}}"#,
            s(0.2),
            p([-1.2, 1.2, -0.5]),
            s(0.4),
            p([-0.8, 1.3, -0.4]),
            s(0.35)
        ),
        format!(
            r#"{{"name": "turned", "sdf": {{"type": "transform", "translate": {}, "rotate": {{"axis": [0.3, 1, 0.2], "angle": 37}}, "scale": {},
                "child": {{"type": "box", "center": [0.1, 0, 0], "half_size": [0.5, 0.3, 0.4], "rounding": 0.1}}}}}}"#,
            p([2.4, 0.2, -1.0]),
            s(1.3)
        ),
        format!(
            r#"{{"name": "turned_ball", "sdf": {{"type": "transform", "translate": {}, "rotate": {{"axis": [1, 0, 0], "angle": -70}}, "scale": {},
                "child": {{"type": "sphere", "center": [0, 0.2, 0], "radius": 0.3}}}}}}"#,
            p([-2.4, -0.4, -1.4]),
            s(0.9)
        ),
        format!(
            r#"{{"name": "can", "sdf": {{"type": "cylinder", "center": {}, "axis": [0, 1, 0], "radius": {}, "half_height": {}, "rounding": 0}}}}"#,
            p([CAN[0], CAN[1], CAN[2]]),
            s(0.4),
            s(0.5)
        ),
        format!(
            r#"{{"name": "tilted_can", "sdf": {{"type": "cylinder", "center": {}, "axis": [0.6, 0.8, 0], "radius": {}, "half_height": {}, "rounding": {}}}}}"#,
            p([-0.6, -1.0, 2.0]),
            s(0.35),
            s(0.3),
            s(0.1)
        ),
        format!(
            r#"{{"name": "turned_can", "sdf": {{"type": "transform", "translate": {}, "rotate": {{"axis": [0, 0, 1], "angle": 90}}, "scale": {},
                "child": {{"type": "transform", "translate": [0, 0.2, 0], "rotate": {{"axis": [0, 1, 0], "angle": 15}}, "scale": 0.5,
                    "child": {{"type": "cylinder", "center": [0, 0, 0], "axis": [0, 0, 1], "radius": 0.6, "half_height": 0.5, "rounding": 0.05}}}}}}}}"#,
            p([0.9, 1.9, 1.6]),
            s(1.0)
        ),
    ];
    if plane {
        shapes.push(format!(
            r#"{{"name": "ground", "sdf": {{"type": "plane", "normal": [0, 1, 0], "offset": {}}}}}"#,
            offset.y - s(2.6)
        ));
    }
    let shapes = shapes
        .iter()
        .map(|s| {
            format!(
                r#"{}, "bsdf": {{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}}}"#,
                &s[..s.len() - 1]
            )
        })
        .collect::<Vec<_>>()
        .join(",\n");
    let json = format!(
        r#"{{"camera": {{"origin": {}, "target": {}, "up": [0, 1, 0], "fov_y": 40, "width": 24, "height": 18}},
            "integrator": {{"type": "direct"}}, "spp": 8,
            "shapes": [{shapes}],
            "emitters": [{{"name": "light", "type": "rectangle", "center": {}, "normal": [0, -1, 0],
                           "u": [1, 0, 0], "size": [{}, {}], "radiance": [10, 10, 10]}}]}}"#,
        p(eye.to_array()),
        p([0.0, 0.0, 0.0]),
        p([0.5, 2.4, 0.5]),
        s(1.0),
        s(1.0)
    );
    parse(&json, Path::new(".")).unwrap()
}

/// Where `mixed_scene`'s upright cylinder stands (relative, unscaled): rays along its axis and in its
/// caps' planes are among the random rays.
const CAN: [f32; 3] = [2.0, -1.0, 1.2];

/// Random rays of every kind through `scene`, scaled by `scale` around `offset`, in packets of random
/// sizes; returns how many rays were compared.
fn random_rays_agree(scene: &Scene, offset: Vec3, scale: f32, seed: u64) -> usize {
    let mut rng = SplitMix(seed);
    let ball_centre = offset;
    let ball_r = scale;
    let mut compared = 0;
    for round in 0..400 {
        let n = 1 + (rng.next() * LANES as f32) as usize % LANES;
        let mut rays = Vec::new();
        let mut spreads = Vec::new();
        for _ in 0..n {
            let o = offset + rng.point(5.0) * scale;
            let mut o_override = None;
            let kind = (rng.next() * 9.0) as u32;
            let d = match kind {
                // At a random point near the shapes.
                0 | 1 => ((offset + rng.point(2.0) * scale) - o).normalize(),
                // Grazing the ball: along a tangent from `o`, nudged by a few ulps either way.
                2 => {
                    let to = ball_centre - o;
                    let dist = to.length();
                    if dist <= ball_r {
                        rng.direction()
                    } else {
                        let axis = to / dist;
                        let side = axis.any_orthonormal_vector();
                        let sin = ball_r / dist;
                        let cos = (1.0 - sin * sin).sqrt();
                        let nudge = 1.0 + (rng.next() - 0.5) * 1e-6;
                        (axis * cos + side * (sin * nudge)).normalize()
                    }
                }
                // Along an axis.
                3 => [Vec3::X, Vec3::NEG_Y, Vec3::Z][(rng.next() * 3.0) as usize % 3],
                // Parallel to the upright cylinder's axis (within its radius half the time), or in
                // the plane of one of its caps.
                6 => {
                    let up = rng.next() < 0.5;
                    if rng.next() < 0.5 {
                        let across = Vec3::new(rng.next() - 0.5, 0.0, rng.next() - 0.5) * 0.7;
                        let height = if up { -3.0 } else { 3.0 };
                        let from = Vec3::from(CAN) + across + Vec3::Y * height;
                        o_override = Some(offset + from * scale);
                    }
                    if up { Vec3::Y } else { Vec3::NEG_Y }
                }
                7 => {
                    let cap = offset + (Vec3::from(CAN) + Vec3::Y * 0.5) * scale;
                    let to = Vec3::new(cap.x - o.x, 0.0, cap.z - o.z);
                    o_override = Some(Vec3::new(o.x, cap.y, o.z));
                    to.try_normalize().unwrap_or(Vec3::X)
                }
                _ => rng.direction(),
            };
            let mut ray = Ray::new(o_override.unwrap_or(o), d);
            // Some rays start on a surface: where an earlier ray hit it, leaving in a random direction.
            if kind == 4
                && let Intersection::Hit(h) = scene.intersect_resolving(&ray, f32::INFINITY, 0.0)
            {
                ray = Ray::new(h.p, rng.direction());
            }
            // Some start within a few tolerances of the ball's surface, on either side, heading into
            // it: there the tracer must look at the field to tell the side.
            if kind == 5 {
                let n = rng.direction();
                let eps = scene.trace.eps_at(offset.abs().max_element() + scale);
                let h = ball_r + (rng.next() - 0.5) * 4.0 * eps;
                ray = Ray::new(
                    ball_centre + n * h,
                    (-n + rng.direction() * 0.5).normalize(),
                );
            }
            rays.push(ray);
            spreads.push([0.0, 1e-3, 2e-2][round % 3]);
        }
        same_hits(scene, &rays, &spreads, None, "random rays");
        compared += n;
    }
    compared
}

#[test]
fn random_rays_hit_what_the_scalar_query_hits_at_every_scale() {
    let eyes = [
        Vec3::new(0.0, 2.0, 7.0),
        // Inside the ball.
        Vec3::new(0.1, 0.2, 0.3),
        // Inside the floor slab itself (its top face is at y = -1.5), under the ball.
        Vec3::new(0.5, -1.8, 0.5),
    ];
    for (offset, scale) in [
        (Vec3::ZERO, 1.0),
        (Vec3::new(1e4, -3e3, 2e4), 1.0),
        (Vec3::ZERO, 1e-3),
        (Vec3::new(-50.0, 20.0, 5.0), 300.0),
    ] {
        for (j, &eye) in eyes.iter().enumerate() {
            for plane in [false, true] {
                let scene = mixed_scene(offset, scale, eye, plane);
                let seed = 11 + j as u64;
                let n = random_rays_agree(&scene, offset, scale, seed);
                assert!(n > 1000);
                let decided = camera_rays_agree(&scene, 8, "mixed scene camera rays");
                println!(
                    "offset {offset}, scale {scale}, eye {eye}, plane {plane}: {decided:.3} of camera rays in lanes"
                );
            }
        }
    }
}
