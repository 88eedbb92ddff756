//! Closed-form crossings (`Sdf::line_crossings`, `first_crossing`, `all_crossings_checked`) of spheres,
//! planes, boxes and cylinders against the exact roots in `f64` and against the sphere tracer they
//! replace: the same crossing to the tracer's
//! tolerance, the same misses, the same answers for rays that start inside, near or on the surface.

use glam::Vec3;
use implicit_psdr::math::Ray;
use implicit_psdr::sampler::Sampler;
use implicit_psdr::sdf::{AngleTrig, Sdf};
use implicit_psdr::trace::{
    ShapeTrace, TraceSettings, all_crossings_checked, all_hits_checked, first_crossing,
    sphere_trace,
};
use implicit_psdr::{Param, Param3};

fn unit_vector(u: glam::Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let p = 2.0 * std::f32::consts::PI * u.y;
    Vec3::new(r * p.cos(), r * p.sin(), z)
}

fn sphere(c: Vec3, r: f32) -> Sdf {
    Sdf::Sphere {
        center: Param3::new(c.to_array()),
        radius: Param::new(r),
    }
}

fn cuboid(c: Vec3, h: Vec3, rounding: f32) -> Sdf {
    Sdf::Box {
        center: Param3::new(c.to_array()),
        half_size: Param3::new(h.to_array()),
        rounding: Param::new(rounding),
    }
}

fn plane(n: Vec3, offset: f32) -> Sdf {
    Sdf::Plane {
        normal: n.normalize(),
        offset: Param::new(offset),
    }
}

fn cylinder(c: Vec3, axis: Vec3, radius: f32, half_height: f32, rounding: f32) -> Sdf {
    Sdf::Cylinder {
        center: Param3::new(c.to_array()),
        axis: axis.normalize(),
        radius: Param::new(radius),
        half_height: Param::new(half_height),
        rounding: Param::new(rounding),
    }
}

fn transformed(child: Sdf, translate: Vec3, axis: Vec3, angle: f32, scale: f32) -> Sdf {
    Sdf::Transform {
        translate: Param3::new(translate.to_array()),
        axis: axis.normalize(),
        angle: Param::new(angle),
        trig: AngleTrig::of(angle),
        scale: Param::new(scale),
        child: Box::new(child),
    }
}

/// The shapes with closed forms, centred near `c`, each with a size (for the ray generator).
fn shapes(c: Vec3) -> Vec<(&'static str, Sdf, f32)> {
    vec![
        ("sphere", sphere(c, 1.0), 1.0),
        ("sharp box", cuboid(c, Vec3::new(1.0, 0.5, 0.75), 0.0), 1.0),
        (
            "rounded box",
            cuboid(c, Vec3::new(1.0, 0.5, 0.75), 0.25),
            1.0,
        ),
        (
            "floor slab",
            cuboid(c, Vec3::new(50.0, 0.5, 50.0), 0.25),
            3.0,
        ),
        ("plane", plane(Vec3::new(0.2, 1.0, -0.1), c.y), 2.0),
        (
            "rotated scaled box",
            transformed(
                cuboid(Vec3::ZERO, Vec3::new(1.0, 0.4, 0.6), 0.1),
                c,
                Vec3::new(1.0, 2.0, 0.5),
                37.0,
                1.3,
            ),
            1.3,
        ),
        (
            "sharp cylinder",
            cylinder(c, Vec3::new(0.0, 1.0, 0.0), 0.8, 0.6, 0.0),
            1.0,
        ),
        (
            "rounded tilted cylinder",
            cylinder(c, Vec3::new(0.3, 1.0, -0.5), 0.7, 0.9, 0.2),
            1.0,
        ),
        (
            "flat disc",
            cylinder(c, Vec3::new(1.0, 0.2, 0.1), 1.5, 0.05, 0.02),
            1.5,
        ),
        (
            "rotated scaled cylinder",
            transformed(
                cylinder(Vec3::ZERO, Vec3::Z, 0.5, 1.2, 0.1),
                c,
                Vec3::new(-1.0, 0.5, 2.0),
                71.0,
                0.8,
            ),
            1.0,
        ),
        (
            "named sphere",
            Sdf::Named {
                name: "ball".into(),
                child: Box::new(sphere(c, 0.7)),
            },
            0.7,
        ),
    ]
}

/// A ray toward a point near `c` (within `size`), starting 2 to 6 sizes away, or inside (every fourth
/// ray), or 4 tolerances off the surface along its normal as a shadow ray starts (every fourth).
fn ray_near(s: &mut Sampler, sdf: &Sdf, c: Vec3, size: f32, kind: u64, eps: f32) -> Ray {
    let target = c + (unit_vector(s.next_2d()) * s.next_1d()) * size;
    match kind % 4 {
        0 | 1 => {
            let o = target + unit_vector(s.next_2d()) * size * (2.0 + 4.0 * s.next_1d());
            Ray::new(o, (target - o).normalize())
        }
        2 => Ray::new(target, unit_vector(s.next_2d())),
        _ => {
            // Onto the surface along the gradient, then 4 eps off it, leaving to a random side.
            let mut p = target;
            for _ in 0..8 {
                let g = sdf.gradient(p);
                p -= sdf.eval_f32(p) * g / g.length_squared().max(1e-12);
            }
            let n = sdf.normal(p);
            let mut w = unit_vector(s.next_2d());
            if s.next_1d() < 0.5 {
                w = if w.dot(n) < 0.0 { -w } else { w };
            }
            let side = if w.dot(n) >= 0.0 { 1.0 } else { -1.0 };
            Ray::new(p + n * side * 4.0 * eps, w)
        }
    }
}

/// The largest acceptable `|Δt|` between two answers for the same crossing at `t`: the tracer's
/// tolerance (its hits satisfy `|φ| ≤ eps/100`) divided by the cosine at the crossing, plus a few ulps
/// of the coordinates.
fn agreement(sdf: &Sdf, ray: &Ray, t: f32, settings: &TraceSettings) -> f32 {
    let p = ray.at(t);
    let cos = sdf.normal(p).dot(ray.d).abs().max(1e-3);
    let m = ray.o.abs().max_element() + t.abs();
    (settings.on_surface_at(m) + 64.0 * f32::EPSILON * m) / cos
}

#[test]
fn closed_forms_find_what_the_tracer_finds() {
    for c in [Vec3::new(0.3, -0.2, 0.5), Vec3::new(1000.0, -300.0, 700.0)] {
        for (name, sdf, size) in shapes(c) {
            let settings = TraceSettings {
                eps: 1e-4 * size,
                max_steps: 1 << 16,
                ..TraceSettings::default()
            };
            let (mut hits, mut compared) = (0, 0);
            for i in 0..3000u64 {
                let mut s = Sampler::new(11, 0, i, 0);
                let eps = settings.eps_at_point(c);
                let ray = ray_near(&mut s, &sdf, c, size, i, eps);
                let t1 = if i % 5 == 0 {
                    size * 4.0 * s.next_1d()
                } else {
                    f32::INFINITY
                };
                let lipschitz = sdf.lipschitz();
                let marched = sphere_trace(&sdf, lipschitz, &ray, 0.0, t1, &settings);
                let closed = first_crossing(&sdf, lipschitz, &ray, 0.0, t1, &settings);
                if let ShapeTrace::Exhausted(_) = marched {
                    continue;
                }
                compared += 1;
                match (marched, closed) {
                    (ShapeTrace::Hit(a), ShapeTrace::Hit(b)) => {
                        hits += 1;
                        let tol = agreement(&sdf, &ray, a, &settings);
                        assert!(
                            (a - b).abs() <= tol,
                            "{name} at {c}, ray {i}: marched {a}, closed form {b} (tolerance {tol})"
                        );
                    }
                    (a, b) => assert_eq!(a, b, "{name} at {c}, ray {i}: {ray:?}"),
                }
                let (all_marched, out_a) =
                    all_hits_checked(&sdf, lipschitz, &ray, 0.0, t1, &settings);
                let (all_closed, out_b) =
                    all_crossings_checked(&sdf, lipschitz, &ray, 0.0, t1, &settings);
                if out_a.is_none() {
                    assert_eq!(out_b, None);
                    assert_eq!(
                        all_marched.len(),
                        all_closed.len(),
                        "{name} at {c}, ray {i}: {all_marched:?} vs {all_closed:?}"
                    );
                    for (a, b) in all_marched.iter().zip(&all_closed) {
                        assert!((a - b).abs() <= agreement(&sdf, &ray, *a, &settings));
                    }
                }
            }
            assert!(compared > 2900, "{name}: only {compared} rays compared");
            assert!(hits > 500, "{name}: only {hits} hits");
        }
    }
}

/// Exact roots in `f64` of the line `o + t d` (as stored, `|d|` = 1 only to rounding) with a sphere.
fn sphere_roots(ray: &Ray, c: Vec3, r: f32) -> Option<(f64, f64)> {
    let f = ray.o.as_dvec3() - c.as_dvec3();
    let d = ray.d.as_dvec3();
    let (a, b) = (d.dot(d), f.dot(d));
    let disc = b * b - a * (f.dot(f) - (r as f64).powi(2));
    (disc >= 0.0).then(|| ((-b - disc.sqrt()) / a, (-b + disc.sqrt()) / a))
}

#[test]
fn sphere_roots_are_accurate_far_away_and_grazing() {
    // Far rays (1e4 sizes away) and rays grazing to 1e-6 of the radius: within a few ulps of the
    // distance travelled.
    let c = Vec3::new(0.3, -0.2, 0.5);
    let sdf = sphere(c, 1.0);
    let mut checked = 0;
    for i in 0..2000u64 {
        let mut s = Sampler::new(12, 0, i, 0);
        let dist = 10f32.powf(4.0 * s.next_1d()) * 2.0;
        let impact = if i % 2 == 0 {
            s.next_1d().sqrt()
        } else {
            1.0 - 10f32.powf(-6.0 * s.next_1d())
        };
        let o = c + unit_vector(s.next_2d()) * dist;
        let to_c = (c - o).normalize();
        let side = {
            let w = unit_vector(s.next_2d());
            (w - to_c * w.dot(to_c)).normalize()
        };
        let sin_b = impact / dist;
        let ray = Ray::new(
            o,
            (to_c * (1.0 - sin_b * sin_b).sqrt() + side * sin_b).normalize(),
        );
        let Some((near, far)) = sphere_roots(&ray, c, 1.0) else {
            continue;
        };
        let line = sdf
            .line_crossings(&ray)
            .expect("a sphere has a closed form");
        // The float resolution of the inputs: `f = o − c` is known to a few ulps of `dist`, which moves
        // `φ` by as much, and a crossing by that over the cosine there (`h/r`, `h` the half chord).
        let resolution = 8.0 * f32::EPSILON as f64 * dist as f64;
        let half_chord = 0.5 * (far - near);
        if line.count == 0 {
            assert!(
                half_chord * half_chord < 2.0 * resolution,
                "ray {i}: missed a chord of {}",
                far - near
            );
            continue;
        }
        checked += 1;
        let tol = resolution / half_chord + 2.0 * resolution;
        for (t, exact) in line.t.iter().zip([near, far]) {
            assert!(
                (*t as f64 - exact).abs() < tol,
                "ray {i}: {:?} vs {near} {far}, dist {dist}, tolerance {tol}",
                line.t
            );
        }
    }
    assert!(checked > 1900);
}

#[test]
fn rays_skimming_a_plane_to_the_horizon_finish() {
    // The sphere tracer needs unboundedly many steps for these (each step is the height above the
    // plane); the closed form needs none.
    let floor = plane(Vec3::Y, 0.0);
    let settings = TraceSettings::default();
    for k in 1..8 {
        let slope = 10f32.powi(-k);
        let ray = Ray::new(
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(1.0, -slope, 0.0).normalize(),
        );
        match first_crossing(&floor, 1.0, &ray, 0.0, f32::INFINITY, &settings) {
            ShapeTrace::Hit(t) => {
                let expect = (1.0 / slope as f64) * (1.0 + (slope as f64).powi(2)).sqrt();
                assert!(
                    ((t as f64 - expect) / expect).abs() < 1e-5,
                    "slope {slope}: {t}"
                );
            }
            other => panic!("slope {slope}: {other:?}"),
        }
        let up = Ray::new(ray.o, Vec3::new(1.0, slope, 0.0).normalize());
        assert_eq!(
            first_crossing(&floor, 1.0, &up, 0.0, f32::INFINITY, &settings),
            ShapeTrace::Miss
        );
    }
    // A ray under the plane (inside the solid) leaves it; one on the plane, moving in, never crosses.
    let below = Ray::new(Vec3::new(0.0, -1.0, 0.0), Vec3::new(0.6, 0.8, 0.0));
    assert_eq!(
        first_crossing(&floor, 1.0, &below, 0.0, f32::INFINITY, &settings),
        ShapeTrace::Hit(1.25)
    );
}

/// Regression: a crossing on a rounded edge is the sharp shape's, so the true crossing lies on the
/// solid's side of it. A ray leaving a rounded box (or cylinder) through its rim with the interval
/// ending between the true and the sharp exit, or starting in the gap between the sharp and the
/// rounded corner, once took the closed form's word (a miss, or the exit for the entry).
#[test]
fn crossings_on_rounded_edges_near_the_interval_ends_are_traced() {
    let settings = TraceSettings {
        eps: 1e-4,
        ..TraceSettings::default()
    };
    let diagonal = Vec3::new(1.0, 1.0, 0.0).normalize();
    for (name, sdf) in [
        ("rounded box", cuboid(Vec3::ZERO, Vec3::ONE, 0.25)),
        (
            "rounded cylinder",
            cylinder(Vec3::ZERO, Vec3::Z, 1.0, 1.0, 0.25),
        ),
    ] {
        let lipschitz = sdf.lipschitz();
        // From the centre out through the rim along the diagonal of the x-y plane (for the cylinder,
        // along z after a turn: its rim is where the side meets a cap).
        let d = if name == "rounded box" {
            diagonal
        } else {
            Vec3::new(1.0, 0.0, 1.0).normalize()
        };
        let out = Ray::new(Vec3::ZERO, d);
        let exit = match sphere_trace(&sdf, lipschitz, &out, 0.0, 10.0, &settings) {
            ShapeTrace::Hit(t) => t,
            other => panic!("{name}: {other:?}"),
        };
        let sharp = sdf.line_crossings(&out).unwrap().t[1];
        assert!(sharp > exit + 0.05, "{name}: sharp {sharp}, true {exit}");
        let t1 = 0.5 * (exit + sharp);
        match first_crossing(&sdf, lipschitz, &out, 0.0, t1, &settings) {
            ShapeTrace::Hit(t) => assert!((t - exit).abs() < 1e-4, "{name}: {t} vs {exit}"),
            other => panic!("{name}: leaving through the rim before {t1}: {other:?}"),
        }
        // From the gap between the sharp and the rounded rim, inward: the entry comes first.
        let start = out.at(0.5 * (exit + sharp));
        assert!(sdf.eval_f32(start) > 0.0);
        let inward = Ray::new(start, -d);
        let entry = match sphere_trace(&sdf, lipschitz, &inward, 0.0, 10.0, &settings) {
            ShapeTrace::Hit(t) => t,
            other => panic!("{name}: {other:?}"),
        };
        match first_crossing(&sdf, lipschitz, &inward, 0.0, 10.0, &settings) {
            ShapeTrace::Hit(t) => assert!((t - entry).abs() < 1e-4, "{name}: {t} vs {entry}"),
            other => panic!("{name}: entering from the rim's gap: {other:?}"),
        }
    }
}
