//! Sphere tracer against closed-form ray–sphere and ray–box intersections.

use glam::Vec3;
use implicit_psdr::math::Ray;
use implicit_psdr::sampler::Sampler;
use implicit_psdr::sdf::Sdf;
use implicit_psdr::trace::{ShapeTrace, TraceSettings, all_hits, all_hits_checked, sphere_trace};
use implicit_psdr::{Param, Param3};

fn sphere(c: [f32; 3], r: f32) -> Sdf {
    Sdf::Sphere {
        center: Param3::new(c),
        radius: Param::new(r),
    }
}

/// Both roots of `|o + t d − c|² = r²` (in f64), if real.
fn sphere_roots(ray: &Ray, c: Vec3, r: f32) -> Option<(f64, f64)> {
    let oc = (ray.o - c).as_dvec3();
    let d = ray.d.as_dvec3();
    let b = oc.dot(d);
    let cc = oc.dot(oc) - (r as f64) * (r as f64);
    let disc = b * b - d.dot(d) * cc;
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    Some(((-b - s) / d.dot(d), (-b + s) / d.dot(d)))
}

fn unit_vector(u: glam::Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let p = 2.0 * std::f32::consts::PI * u.y;
    Vec3::new(r * p.cos(), r * p.sin(), z)
}

/// A ray from distance 4 to 6 of the centre, passing at impact parameter `b` from it.
fn ray_with_impact(s: &mut Sampler, c: Vec3, b: f32) -> Ray {
    let dist = 4.0 + 2.0 * s.next_1d();
    let o = c + unit_vector(s.next_2d()) * dist;
    let to_c = (c - o).normalize();
    // A unit vector orthogonal to the direction to the centre.
    let mut side = unit_vector(s.next_2d());
    side = (side - to_c * side.dot(to_c)).normalize();
    // Tilt by β with sin β = b / dist: the line then passes at distance b from the centre.
    let sin_b = b / dist;
    let d = to_c * (1.0 - sin_b * sin_b).sqrt() + side * sin_b;
    Ray::new(o, d.normalize())
}

#[test]
fn sphere_hits_match_closed_form_including_grazing() {
    let c = Vec3::new(0.3, -0.2, 0.5);
    let r = 1.0;
    let sdf = sphere(c.to_array(), r);
    let settings = TraceSettings::default();
    let eps = settings.eps;
    let mut worst_phi = 0.0f32;
    let mut worst_dt_scaled = 0.0f64;
    for i in 0..4000u64 {
        let mut s = Sampler::new(1, 0, i, 0);
        // Impact parameters: uniform over the disc, then increasingly close to grazing (1 − 10^−k).
        let b = if i % 2 == 0 {
            r * s.next_1d().sqrt()
        } else {
            r * (1.0 - 10f32.powi(-((1 + i % 6) as i32)))
        };
        let ray = ray_with_impact(&mut s, c, b);
        let (near, far) = sphere_roots(&ray, c, r).expect("ray aimed inside the sphere");
        match sphere_trace(&sdf, 1.0, &ray, 0.0, 100.0, &settings) {
            ShapeTrace::Hit(t) => {
                let phi = sdf.eval_f32(ray.at(t)).abs();
                worst_phi = worst_phi.max(phi);
                // The first root, not the second.
                assert!(
                    (t as f64 - near).abs() < (t as f64 - far).abs() || far - near < 1e-3,
                    "ray {i}: t = {t}, roots {near} {far}"
                );
                // |t − t_true| · |∇φ·d| is the distance-like error; allow float noise at |o| ≈ 6.
                let cos = ((ray.at(near as f32) - c).normalize().dot(ray.d)).abs() as f64;
                let dt = (t as f64 - near).abs() * cos;
                worst_dt_scaled = worst_dt_scaled.max(dt);
                assert!(
                    dt < 0.01 * eps as f64 + 4e-6,
                    "ray {i}: t = {t}, near = {near}, cos = {cos}"
                );
            }
            other => {
                // Only a chord shorter than the largest creep step (64 eps) may be skipped.
                assert!(
                    far - near < 64.0 * eps as f64,
                    "ray {i}: b = {b}, {other:?}, chord {}",
                    far - near
                );
            }
        }
    }
    assert!(
        worst_phi < 0.01 * eps + 2e-6,
        "worst |φ| at hit {worst_phi}"
    );
    eprintln!("worst |φ| {worst_phi:e}, worst |Δt·cos| {worst_dt_scaled:e}");
}

#[test]
fn misses_and_tangent_grazes_are_misses() {
    let c = Vec3::ZERO;
    let sdf = sphere([0.0; 3], 1.0);
    let settings = TraceSettings::default();
    for i in 0..2000u64 {
        let mut s = Sampler::new(2, 0, i, 0);
        // From clear misses down to rays passing eps/2 outside the surface (a graze, not a crossing).
        let b = match i % 4 {
            0 => 1.0 + 2.0 * s.next_1d(),
            1 => 1.0 + 1e-2 * s.next_1d() + settings.eps,
            2 => 1.0 + 0.5 * settings.eps,
            _ => 1.0 + 2.0 * settings.eps,
        };
        let ray = ray_with_impact(&mut s, c, b);
        let res = sphere_trace(&sdf, 1.0, &ray, 0.0, 100.0, &settings);
        assert_eq!(res, ShapeTrace::Miss, "ray {i}, b = {b}");
        assert!(all_hits(&sdf, 1.0, &ray, 0.0, 100.0, &settings).is_empty());
    }
    // A hit beyond t1 is a miss; the interval is closed at t1.
    let ray = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
    assert_eq!(
        sphere_trace(&sdf, 1.0, &ray, 0.0, 3.9, &settings),
        ShapeTrace::Miss
    );
    assert!(
        matches!(sphere_trace(&sdf, 1.0, &ray, 0.0, 4.0, &settings), ShapeTrace::Hit(t) if (t - 4.0).abs() < 1e-5)
    );
    // An empty or NaN interval is a miss.
    assert_eq!(
        sphere_trace(&sdf, 1.0, &ray, 3.0, 2.0, &settings),
        ShapeTrace::Miss
    );
    assert_eq!(
        sphere_trace(&sdf, 1.0, &ray, f32::NAN, 2.0, &settings),
        ShapeTrace::Miss
    );
}

#[test]
fn ray_starting_inside_finds_the_exit() {
    let c = Vec3::new(1.0, 2.0, 3.0);
    let r = 1.5;
    let sdf = sphere(c.to_array(), r);
    let settings = TraceSettings::default();
    for i in 0..1000u64 {
        let mut s = Sampler::new(3, 0, i, 0);
        let o = c + unit_vector(s.next_2d()) * (r * 0.999 * s.next_1d().cbrt());
        let ray = Ray::new(o, unit_vector(s.next_2d()));
        let (_, far) = sphere_roots(&ray, c, r).unwrap();
        let ShapeTrace::Hit(t) = sphere_trace(&sdf, 1.0, &ray, 0.0, 100.0, &settings) else {
            panic!("ray {i} from inside found no exit");
        };
        assert!(
            (t as f64 - far).abs() < 1e-5,
            "ray {i}: t = {t}, exit {far}"
        );
        let hits = all_hits(&sdf, 1.0, &ray, 0.0, 100.0, &settings);
        assert_eq!(hits, vec![t]);
    }
}

#[test]
fn exhausted_rays_are_reported() {
    let sdf = sphere([0.0, 0.0, 10.0], 1.0);
    let ray = Ray::new(Vec3::ZERO, Vec3::new(0.01, 0.0, 1.0).normalize());
    let tiny = TraceSettings {
        max_steps: 3,
        ..TraceSettings::default()
    };
    // Lipschitz bound 1000 (valid, loose): each step is a thousandth of the distance, so the budget (3
    // steps, plus at most 16 × 3 for the interval's length: `TraceSettings::max_steps`) cannot arrive.
    match sphere_trace(&sdf, 1000.0, &ray, 0.0, 100.0, &tiny) {
        ShapeTrace::Exhausted(t) => assert!(t > 0.0 && t < 9.0, "stopped at {t}"),
        other => panic!("expected Exhausted, got {other:?}"),
    }
    let (hits, ex) = all_hits_checked(&sdf, 1000.0, &ray, 0.0, 100.0, &tiny);
    assert!(hits.is_empty() && ex.is_some());
    // With the default budget the same ray hits, and a loose Lipschitz bound still finds the same root.
    let settings = TraceSettings::default();
    let ShapeTrace::Hit(t4) = sphere_trace(&sdf, 4.0, &ray, 0.0, 100.0, &settings) else {
        panic!()
    };
    let ShapeTrace::Hit(t1) = sphere_trace(&sdf, 1.0, &ray, 0.0, 100.0, &settings) else {
        panic!()
    };
    assert!((t4 - t1).abs() < 1e-5);
}

#[test]
fn all_hits_on_two_spheres_in_a_row() {
    let a = Vec3::new(0.0, 0.0, 0.0);
    let b = Vec3::new(3.0, 0.2, 0.0);
    let sdf_a = sphere(a.to_array(), 1.0);
    let sdf_b = sphere(b.to_array(), 0.8);
    let union = Sdf::union(vec![sdf_a.clone(), sdf_b.clone()]);
    let settings = TraceSettings::default();
    for i in 0..200u64 {
        let mut s = Sampler::new(4, 0, i, 0);
        let o = Vec3::new(-5.0, 0.3 * (s.next_1d() - 0.5), 0.3 * (s.next_1d() - 0.5));
        let target = Vec3::new(
            5.0,
            0.2 + 0.3 * (s.next_1d() - 0.5),
            0.3 * (s.next_1d() - 0.5),
        );
        let ray = Ray::new(o, (target - o).normalize());
        let (a0, a1) = sphere_roots(&ray, a, 1.0).unwrap();
        let (b0, b1) = sphere_roots(&ray, b, 0.8).unwrap();
        let expected = [a0, a1, b0, b1];
        let hits = all_hits(&union, union.lipschitz(), &ray, 0.0, 20.0, &settings);
        assert_eq!(hits.len(), 4, "ray {i}: {hits:?}");
        for (h, e) in hits.iter().zip(expected) {
            assert!(
                (*h as f64 - e).abs() < 1e-5,
                "ray {i}: {hits:?} vs {expected:?}"
            );
        }
        // Each sphere alone gives its own pair; the first hit of the union is the first entry.
        assert_eq!(all_hits(&sdf_a, 1.0, &ray, 0.0, 20.0, &settings).len(), 2);
        assert_eq!(all_hits(&sdf_b, 1.0, &ray, 0.0, 20.0, &settings).len(), 2);
        assert_eq!(
            sphere_trace(&union, 1.0, &ray, 0.0, 20.0, &settings),
            ShapeTrace::Hit(hits[0])
        );
        // Starting inside the second sphere: its exit only.
        let mid = (0.5 * (b0 + b1)) as f32;
        let rest = all_hits(&union, 1.0, &ray, mid, 20.0, &settings);
        assert_eq!(rest.len(), 1);
        assert!((rest[0] as f64 - b1).abs() < 1e-5);
    }
}

/// Slab intersection of a ray with an axis-aligned box (f64).
fn box_roots(ray: &Ray, c: Vec3, h: Vec3) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for k in 0..3 {
        let o = (ray.o[k] - c[k]) as f64;
        let d = ray.d[k] as f64;
        let (t0, t1) = ((-h[k] as f64 - o) / d, (h[k] as f64 - o) / d);
        lo = lo.max(t0.min(t1));
        hi = hi.min(t0.max(t1));
    }
    (lo <= hi).then_some((lo, hi))
}

#[test]
fn all_hits_on_a_box() {
    let c = Vec3::new(0.5, 0.0, -0.5);
    let h = Vec3::new(1.0, 0.5, 0.75);
    let sdf = Sdf::Box {
        center: Param3::new(c.to_array()),
        half_size: Param3::new(h.to_array()),
        rounding: Param::new(0.0),
    };
    let settings = TraceSettings::default();
    let mut tested = 0;
    for i in 0..500u64 {
        let mut s = Sampler::new(5, 0, i, 0);
        let o = c + unit_vector(s.next_2d()) * 5.0;
        let target = c + (s.next_2d() - 0.5).extend(s.next_1d() - 0.5) * 1.2;
        let ray = Ray::new(o, (target - o).normalize());
        let Some((t0, t1)) = box_roots(&ray, c, h) else {
            continue;
        };
        if t1 - t0 < 1e-2 {
            // A corner clip: a crossing this short is at the tracer's resolution only.
            continue;
        }
        tested += 1;
        let hits = all_hits(&sdf, 1.0, &ray, 0.0, 20.0, &settings);
        assert_eq!(hits.len(), 2, "ray {i}: {hits:?} vs {t0} {t1}");
        // Near edges the box SDF's gradient along the ray can be small: allow a loose bound there.
        assert!(
            (hits[0] as f64 - t0).abs() < 1e-4 && (hits[1] as f64 - t1).abs() < 1e-4,
            "ray {i}: {hits:?} vs {t0} {t1}"
        );
        assert_eq!(
            sphere_trace(&sdf, 1.0, &ray, 0.0, 20.0, &settings),
            ShapeTrace::Hit(hits[0])
        );
    }
    assert!(tested > 100);
}

#[test]
fn error_shrinks_with_eps() {
    // The tolerance is stated as |φ(t)| ≤ eps/100: check that the worst error over rays follows eps.
    let c = Vec3::ZERO;
    let sdf = sphere([0.0; 3], 1.0);
    let mut worst = Vec::new();
    for eps in [1e-2f32, 1e-3, 1e-4] {
        let settings = TraceSettings {
            eps,
            max_steps: 4096,
            ..TraceSettings::default()
        };
        let mut w = 0.0f64;
        for i in 0..500u64 {
            let mut s = Sampler::new(6, 0, i, 0);
            let b = s.next_1d().sqrt() * 0.95;
            let ray = ray_with_impact(&mut s, c, b);
            let (near, _) = sphere_roots(&ray, c, 1.0).unwrap();
            let ShapeTrace::Hit(t) = sphere_trace(&sdf, 1.0, &ray, 0.0, 100.0, &settings) else {
                panic!()
            };
            w = w.max((t as f64 - near).abs());
        }
        worst.push(w);
    }
    eprintln!("worst |Δt| per eps: {worst:?}");
    assert!(worst[0] < 1e-2 * 1e-2 * 4.0 && worst[1] < 1e-3 * 1e-2 * 4.0 + 2e-6);
    assert!(worst[2] <= worst[1] && worst[1] < worst[0]);
}

#[test]
fn tangent_line_from_the_surface_skips_its_own_tangency() {
    // The boundary sampler's use: a line tangent to the surface at x_B, started at x_B, must not report
    // x_B itself, and must find the next real crossing.
    let a = sphere([0.0; 3], 1.0);
    let settings = TraceSettings::default();
    for i in 0..500u64 {
        let mut s = Sampler::new(7, 0, i, 0);
        let n = unit_vector(s.next_2d());
        let mut w = unit_vector(s.next_2d());
        w = (w - n * w.dot(n)).normalize();
        let ray = Ray::new(n, w);
        assert_eq!(
            sphere_trace(&a, 1.0, &ray, 0.0, 50.0, &settings),
            ShapeTrace::Miss,
            "ray {i}"
        );
        // A second sphere straddling the tangent line further along.
        let c2 = n + w * 3.0 + n * 0.1;
        let b = sphere(c2.to_array(), 0.5);
        let (near, _) = sphere_roots(&ray, c2, 0.5).unwrap();
        let ShapeTrace::Hit(t) = sphere_trace(&b, 1.0, &ray, 0.0, 50.0, &settings) else {
            panic!("ray {i}")
        };
        assert!((t as f64 - near).abs() < 1e-5);
    }
}
