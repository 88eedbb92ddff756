//! Generic shading functions with dual numbers against central differences of their `f32` versions, and
//! the densities of every sampler (BSDF, emitters) against their histograms and the sphere of directions.

use glam::{Vec2, Vec3 as G3};
use implicit_psdr::bsdf::Bsdf;
use implicit_psdr::emitter::Emitter;
use implicit_psdr::integrator::shading::geometry_term;
use implicit_psdr::math::{Ray, Vec3};
use implicit_psdr::scalar::Dual32;
use implicit_psdr::{Param, Param3, Scalar};
use std::f32::consts::PI;

fn v<S: Scalar>(a: [f32; 3]) -> Vec3<S> {
    Vec3::constant(G3::from(a))
}

/// `a` with component `k` lifted into slot 0.
fn lift_component(a: [f32; 3], k: usize) -> Vec3<Dual32> {
    let c = |i: usize| Dual32::lift(a[i], if i == k { Some(0) } else { None });
    Vec3::new(c(0), c(1), c(2))
}

fn assert_close(a: f32, b: f32, tol: f32, what: &str) {
    assert!(
        (a - b).abs() <= tol * (1.0 + b.abs()),
        "{what}: {a} vs {b} (tol {tol})"
    );
}

#[test]
fn bsdf_eval_dual_matches_central_difference_in_albedo() {
    let n = [0.0, 0.0, 1.0];
    let wi = G3::new(0.3, 0.2, 0.9).normalize().to_array();
    let wo = G3::new(-0.5, 0.1, 0.7).normalize().to_array();
    let albedo = [0.8, 0.5, 0.3];
    for k in 0..3 {
        let mut a = Param3::new(albedo);
        a.c[k].slot = Some(0);
        let dual = Bsdf::Diffuse { albedo: a }.eval::<Dual32>(v(n), v(wi), v(wo));
        let h = 1e-2;
        let at = |d: f32| {
            let mut a = albedo;
            a[k] += d;
            Bsdf::Diffuse {
                albedo: Param3::new(a),
            }
            .eval::<f32>(v(n), v(wi), v(wo))
            .get(k)
        };
        let fd = (at(h) - at(-h)) / (2.0 * h);
        assert_close(dual.get(k).eps, fd, 1e-3, "d f / d albedo");
        assert_close(dual.get(k).re, albedo[k] / PI, 1e-6, "f");
        // Moving the directions inside a hemisphere does not change a Lambertian BSDF.
        let d = Bsdf::Diffuse {
            albedo: Param3::new(albedo),
        }
        .eval::<Dual32>(v(n), lift_component(wi, k), v(wo));
        assert_eq!(d.get(k).eps, 0.0);
    }
    // Two-sided: both directions below the surface reflect, opposite sides do not.
    let b = Bsdf::Diffuse {
        albedo: Param3::new(albedo),
    };
    let below = |w: [f32; 3]| [w[0], w[1], -w[2]];
    assert_close(
        b.eval::<f32>(v(n), v(below(wi)), v(below(wo))).x,
        0.8 / PI,
        1e-6,
        "back side",
    );
    assert_eq!(b.eval::<f32>(v(n), v(wi), v(below(wo))).x, 0.0);
}

#[test]
fn emitted_dual_matches_central_difference() {
    let radiance = [4.0, 2.0, 1.0];
    let p = [0.0, 1.0, 0.0];
    let nrm = [0.0, -1.0, 0.0];
    let w = G3::new(0.1, -0.9, 0.2).normalize().to_array();
    for k in 0..3 {
        let mut r = Param3::new(radiance);
        r.c[k].slot = Some(0);
        let emitters = [
            Emitter::Rectangle {
                center: Param3::new(p),
                normal: G3::from(nrm),
                u: G3::X,
                size: [Param::new(1.0), Param::new(1.0)],
                radiance: r,
            },
            Emitter::Sphere {
                center: Param3::new([0.0, 2.0, 0.0]),
                radius: Param::new(1.0),
                radiance: r,
            },
            Emitter::Constant { radiance: r },
        ];
        for e in &emitters {
            let d = e.emitted::<Dual32>(v(p), v(nrm), v(w));
            let h = 1e-2;
            let at = |dv: f32| {
                let mut e = e.clone();
                let mut rr = radiance;
                rr[k] += dv;
                match &mut e {
                    Emitter::Rectangle { radiance, .. }
                    | Emitter::Sphere { radiance, .. }
                    | Emitter::Constant { radiance } => *radiance = Param3::new(rr),
                    _ => unreachable!("radiance emitters only"),
                }
                e.emitted::<f32>(v(p), v(nrm), v(w)).get(k)
            };
            assert_close(d.get(k).eps, (at(h) - at(-h)) / (2.0 * h), 1e-3, "dLe");
            assert_close(d.get(k).re, radiance[k], 1e-6, "Le");
            // Position derivative of a uniform emitter is zero (radiance undifferentiated here).
            let plain = match e.clone() {
                Emitter::Rectangle {
                    center,
                    normal,
                    u,
                    size,
                    ..
                } => Emitter::Rectangle {
                    center,
                    normal,
                    u,
                    size,
                    radiance: Param3::new(radiance),
                },
                Emitter::Sphere { center, radius, .. } => Emitter::Sphere {
                    center,
                    radius,
                    radiance: Param3::new(radiance),
                },
                Emitter::Constant { .. } => Emitter::Constant {
                    radiance: Param3::new(radiance),
                },
                _ => unreachable!("radiance emitters only"),
            };
            let dp = plain.emitted::<Dual32>(lift_component(p, k), v(nrm), v(w));
            assert_eq!(dp.get(k).eps, 0.0);
        }
        // One-sided finite emitters: nothing from behind.
        let back = [-w[0], -w[1], -w[2]];
        assert_eq!(emitters[0].emitted::<f32>(v(p), v(nrm), v(back)).x, 0.0);
        assert_eq!(emitters[1].emitted::<f32>(v(p), v(nrm), v(back)).x, 0.0);
        assert!(emitters[2].emitted::<f32>(v(p), v(nrm), v(back)).x > 0.0);
    }
}

#[test]
fn geometry_term_dual_matches_central_difference() {
    let x = [0.1, 0.0, -0.2];
    let nx = G3::new(0.1, 1.0, 0.2).normalize().to_array();
    let y = [0.7, 2.0, 0.4];
    let ny = G3::new(-0.3, -1.0, 0.1).normalize().to_array();
    let g = |x: [f32; 3], nx: [f32; 3], y: [f32; 3], ny: [f32; 3]| {
        geometry_term::<f32>(v(x), v(nx), v(y), v(ny))
    };
    // Closed form |cos_x| |cos_y| / d².
    let (gx, gy) = (G3::from(x), G3::from(y));
    let w = (gy - gx).normalize();
    let expect = G3::from(nx).dot(w).abs() * G3::from(ny).dot(w).abs() / gx.distance_squared(gy);
    assert_close(g(x, nx, y, ny), expect, 1e-5, "G");
    let h = 1e-3;
    for k in 0..3 {
        let shift = |a: [f32; 3], d: f32| {
            let mut a = a;
            a[k] += d;
            a
        };
        let checks: [(Vec3<Dual32>, f32); 4] = [
            (
                geometry_term(lift_component(x, k), v(nx), v(y), v(ny)),
                (g(shift(x, h), nx, y, ny) - g(shift(x, -h), nx, y, ny)) / (2.0 * h),
            ),
            (
                geometry_term(v(x), lift_component(nx, k), v(y), v(ny)),
                (g(x, shift(nx, h), y, ny) - g(x, shift(nx, -h), y, ny)) / (2.0 * h),
            ),
            (
                geometry_term(v(x), v(nx), lift_component(y, k), v(ny)),
                (g(x, nx, shift(y, h), ny) - g(x, nx, shift(y, -h), ny)) / (2.0 * h),
            ),
            (
                geometry_term(v(x), v(nx), v(y), lift_component(ny, k)),
                (g(x, nx, y, shift(ny, h)) - g(x, nx, y, shift(ny, -h))) / (2.0 * h),
            ),
        ]
        .map(|(d, fd)| (Vec3::splat(d), fd));
        for (d, fd) in checks {
            assert!(
                (d.x.eps - fd).abs() < 2e-3 * (1.0 + fd.abs()),
                "dG component {k}: {} vs {fd}",
                d.x.eps
            );
        }
    }
    // Guards: coincident points and zero normals give 0 with a finite derivative.
    let d = geometry_term(lift_component(x, 0), v(nx), v(x), v(ny));
    assert_eq!((d.re, d.eps), (0.0, 0.0));
    let d = geometry_term(lift_component(x, 0), v([0.0; 3]), v(y), v(ny));
    assert!(d.re == 0.0 && d.eps.is_finite());
}

/// Bins of equal solid angle: `NZ` bands of `cos θ` times `NP` sectors of `φ`.
const NZ: usize = 16;
const NP: usize = 16;

fn bin_of(w: G3) -> usize {
    let z = ((w.z + 1.0) * 0.5 * NZ as f32).clamp(0.0, NZ as f32 - 1.0) as usize;
    let phi = w.y.atan2(w.x).rem_euclid(2.0 * PI);
    let p = (phi / (2.0 * PI) * NP as f32).clamp(0.0, NP as f32 - 1.0) as usize;
    z * NP + p
}

/// Checks a direction sampler against its density: the density integrates to 1 over the sphere, the
/// histogram of samples matches the density integrated over each bin, and the sampler's reported density
/// equals the density function at the sampled direction.
fn check_sampler(name: &str, sample: impl Fn(Vec2) -> Option<(G3, f32)>, pdf: impl Fn(G3) -> f32) {
    // Midpoint quadrature over (cos θ, φ), which is area-preserving: dω = dz dφ.
    let sub = 24;
    let mut expected = vec![0.0f64; NZ * NP];
    let cell = (2.0 / (NZ * sub) as f64) * (2.0 * std::f64::consts::PI / (NP * sub) as f64);
    for iz in 0..NZ * sub {
        let z = -1.0 + (iz as f32 + 0.5) * 2.0 / (NZ * sub) as f32;
        let r = (1.0 - z * z).max(0.0).sqrt();
        for ip in 0..NP * sub {
            let phi = (ip as f32 + 0.5) * 2.0 * PI / (NP * sub) as f32;
            let w = G3::new(r * phi.cos(), r * phi.sin(), z);
            expected[(iz / sub) * NP + ip / sub] += pdf(w) as f64 * cell;
        }
    }
    let total: f64 = expected.iter().sum();
    assert!(
        (total - 1.0).abs() < 0.01,
        "{name}: pdf integrates to {total}"
    );

    let n = 400usize;
    let mut hist = vec![0.0f64; NZ * NP];
    let mut count = 0usize;
    for i in 0..n {
        for j in 0..n {
            // Stratified, with a scrambled offset so strata do not line up with bins.
            let u = Vec2::new(
                (i as f32 + 0.5 + 0.3 * ((j * 7 % 11) as f32 / 11.0 - 0.5)) / n as f32,
                (j as f32 + 0.5 + 0.3 * ((i * 5 % 13) as f32 / 13.0 - 0.5)) / n as f32,
            );
            if let Some((w, p)) = sample(u) {
                let q = pdf(w);
                assert!(
                    (p - q).abs() <= 2e-3 * p.max(q),
                    "{name}: sampled pdf {p} vs pdf {q} at {w}"
                );
                hist[bin_of(w)] += 1.0;
            }
            count += 1;
        }
    }
    let valid: f64 = hist.iter().sum();
    let mut l1 = 0.0;
    for b in 0..NZ * NP {
        let obs = hist[b] / count as f64;
        let exp = expected[b];
        l1 += (obs - exp).abs();
        let sigma = (exp / count as f64).sqrt();
        assert!(
            (obs - exp).abs() < 5.0 * sigma + 0.03 * exp + 2e-4,
            "{name}: bin {b}: observed {obs}, expected {exp}"
        );
    }
    assert!(l1 < 0.02, "{name}: L1 histogram error {l1}");
    // Every sample counts when the density integrates to 1 (no silent rejections).
    assert!(
        valid / count as f64 > 0.99,
        "{name}: only {valid} of {count} samples valid"
    );
}

#[test]
fn bsdf_sampling_matches_pdf() {
    let b = Bsdf::Diffuse {
        albedo: Param3::new([0.5; 3]),
    };
    for (n, wo) in [
        (G3::Z, G3::new(0.2, 0.1, 1.0).normalize()),
        (
            G3::new(0.3, -0.4, 0.5).normalize(),
            G3::new(-0.6, 0.1, -0.5).normalize(),
        ),
    ] {
        check_sampler(
            "diffuse",
            |u| b.sample(n, wo, u).map(|s| (s.wi, s.pdf)),
            |wi| b.pdf(n, wo, wi),
        );
    }
    assert!(b.sample(G3::Z, G3::X, Vec2::splat(0.5)).is_none());
}

/// `pdf_li` seen as a density over directions: trace the emitter along `w` to find `p` and `n`.
fn emitter_direction_pdf(e: &Emitter, reference: G3, w: G3) -> f32 {
    if e.is_infinite() {
        return e.pdf_li(reference, w, reference + w, -w);
    }
    match e.intersect(&Ray::new(reference, w), f32::INFINITY) {
        Some((t, n)) => {
            let p = reference + w * t;
            // Only the emitting side is sampled for a rectangle.
            e.pdf_li(reference, w, p, n)
        }
        None => 0.0,
    }
}

fn check_emitter(name: &str, e: &Emitter, reference: G3) {
    check_sampler(
        name,
        |u| {
            e.sample_li(reference, u).map(|s| {
                let q = e.pdf_li(reference, s.wi, s.p, s.n);
                assert!(
                    (s.pdf - q).abs() <= 1e-4 * s.pdf,
                    "{name}: sample_li pdf {} vs pdf_li {q}",
                    s.pdf
                );
                if !e.is_infinite() {
                    assert!((reference + s.wi * s.dist - s.p).length() < 1e-4 * (1.0 + s.dist));
                }
                (s.wi, s.pdf)
            })
        },
        |w| emitter_direction_pdf(e, reference, w),
    );
}

#[test]
fn emitter_sampling_matches_pdf() {
    let rect = Emitter::Rectangle {
        center: Param3::new([0.2, 0.0, 1.0]),
        normal: -G3::Z,
        u: G3::new(1.0, 1.0, 0.0).normalize(),
        size: [Param::new(2.0), Param::new(1.5)],
        radiance: Param3::new([1.0; 3]),
    };
    check_emitter("rectangle", &rect, G3::new(0.1, -0.3, 0.0));
    let sphere = Emitter::Sphere {
        center: Param3::new([0.5, 1.2, 1.0]),
        radius: Param::new(1.0),
        radiance: Param3::new([1.0; 3]),
    };
    check_emitter("sphere outside", &sphere, G3::ZERO);
    check_emitter("sphere inside", &sphere, G3::new(0.5, 1.5, 1.3));
    let env = Emitter::Constant {
        radiance: Param3::new([1.0; 3]),
    };
    check_emitter("constant", &env, G3::new(3.0, 1.0, 2.0));
}

#[test]
fn rectangle_is_one_sided_but_blocks_both_ways() {
    let rect = Emitter::Rectangle {
        center: Param3::new([0.0, 0.0, 1.0]),
        normal: -G3::Z,
        u: G3::X,
        size: [Param::new(1.0), Param::new(1.0)],
        radiance: Param3::new([1.0; 3]),
    };
    // From behind (above the rectangle), no light is sampled but rays still hit it.
    let above = G3::new(0.0, 0.0, 2.0);
    for i in 0..16 {
        let u = Vec2::new((i as f32 + 0.5) / 16.0, ((i * 7) % 16) as f32 / 16.0);
        assert!(rect.sample_li(above, u).is_none());
    }
    let (t, n) = rect.intersect(&Ray::new(above, -G3::Z), 10.0).unwrap();
    assert_close(t, 1.0, 1e-6, "t from behind");
    assert_eq!(n, -G3::Z);
    assert!(rect.intersect(&Ray::new(above, -G3::Z), 0.5).is_none());
    assert!(
        rect.intersect(&Ray::new(above, G3::new(0.8, 0.0, -0.6)), 10.0)
            .is_none()
    );
    // From below, the closed-form solid angle of a square seen on its axis: Ω = 4 asin(a² / (a² + 4h²))
    // for side a at height h; the mean of 1/pdf over samples estimates it.
    let below = G3::ZERO;
    let mut sum = 0.0f64;
    let m = 256;
    for i in 0..m {
        for j in 0..m {
            let u = Vec2::new((i as f32 + 0.5) / m as f32, (j as f32 + 0.5) / m as f32);
            sum += 1.0 / rect.sample_li(below, u).unwrap().pdf as f64;
        }
    }
    let omega = sum / (m * m) as f64;
    let exact = 4.0 * (1.0f64 / (1.0 + 4.0)).asin();
    assert!((omega - exact).abs() < 1e-4 * exact, "{omega} vs {exact}");
}

#[test]
fn sphere_emitter_far_away_keeps_precision() {
    let sphere = Emitter::Sphere {
        center: Param3::new([0.0, 0.0, 1000.0]),
        radius: Param::new(0.01),
        radiance: Param3::new([1.0; 3]),
    };
    // Solid angle 2π(1 − cos θmax) ≈ π r² / d² for a far sphere.
    let s = sphere.sample_li(G3::ZERO, Vec2::new(0.3, 0.7)).unwrap();
    let omega = 1.0 / s.pdf;
    let exact = PI * 1e-4 / 1e6;
    assert_close(omega, exact, 1e-3, "far sphere solid angle");
    assert!((s.p - G3::new(0.0, 0.0, 1000.0)).length() < 0.0101);
}

/// The recorded-path contribution evaluated with dual numbers: the estimate is linear in the light's
/// radiance and in the albedo, so its derivatives equal value / parameter; moving the shading point
/// matches a central difference of the `f32` evaluation of the same record.
#[test]
fn path_contribution_dual_matches_central_difference() {
    use implicit_psdr::camera::Camera;
    use implicit_psdr::film::Filter;
    use implicit_psdr::integrator::IntegratorKind;
    use implicit_psdr::integrator::path::{
        LightVertex, PathRecord, PathVertex, VertexKind, contribution, detached,
    };
    use implicit_psdr::scene::{NamedEmitter, Scene, Shape};
    use implicit_psdr::sdf::Sdf;

    let scene_with = |radiance: Param3, albedo: Param3| {
        let camera = Camera {
            origin: Param3::new([0.0, 1.0, 2.0]),
            target: Param3::new([0.0; 3]),
            up: Param3::new([0.0, 1.0, 0.0]),
            fov_y: Param::new(40.0),
            width: 4,
            height: 4,
            filter: Filter::Tent,
        };
        let light = Emitter::Rectangle {
            center: Param3::new([0.3, 2.0, 0.1]),
            normal: -G3::Y,
            u: G3::X,
            size: [Param::new(1.0), Param::new(0.5)],
            radiance,
        };
        let mut scene = Scene::new(
            camera,
            IntegratorKind::Direct,
            1,
            vec![],
            vec![NamedEmitter {
                name: "light".into(),
                emitter: light,
            }],
        );
        scene.shapes.push(Shape::new(
            "patch",
            Sdf::Sphere {
                center: Param3::new([0.0, -10.0, 0.0]),
                radius: Param::new(0.1),
            },
            Bsdf::Diffuse { albedo },
        ));
        scene
    };
    let (l, rho) = ([3.0, 2.0, 1.0], [0.5, 0.6, 0.7]);
    let record = PathRecord {
        camera: G3::new(0.0, 1.0, 2.0),
        vertices: vec![PathVertex {
            p: G3::ZERO,
            n: G3::Y,
            kind: VertexKind::Shape(0),
            pdf: 1.0,
            mis: 0.0,
        }],
        lights: vec![LightVertex {
            from: 0,
            emitter: 0,
            p: G3::new(0.5, 2.0, 0.2),
            n: -G3::Y,
            pdf: 1.7,
            mis: 0.8,
        }],
        ..PathRecord::default()
    };
    let plain = scene_with(Param3::new(l), Param3::new(rho));
    let value = contribution::<f32>(&plain, &record, detached);
    assert!(value.x > 0.0);
    for k in 0..3 {
        let mut lp = Param3::new(l);
        lp.c[k].slot = Some(0);
        let d = contribution::<Dual32>(&scene_with(lp, Param3::new(rho)), &record, detached);
        assert_close(d.get(k).eps, value.get(k) / l[k], 1e-5, "d/dL");
        let mut rp = Param3::new(rho);
        rp.c[k].slot = Some(0);
        let d = contribution::<Dual32>(&scene_with(Param3::new(l), rp), &record, detached);
        assert_close(d.get(k).eps, value.get(k) / rho[k], 1e-5, "d/drho");
    }
    // Attach the shading point: x(π) = p + π e_k (a rigid translation of that vertex only).
    let h = 1e-3;
    for k in 0..3 {
        let e = G3::AXES[k];
        let attach = |p: G3, n: G3| -> (Vec3<Dual32>, Vec3<Dual32>) {
            let mut x: Vec3<Dual32> = Vec3::constant(p);
            if p == G3::ZERO {
                x += lift_component([0.0; 3], k);
            }
            (x, Vec3::constant(n))
        };
        let d = contribution::<Dual32>(&plain, &record, attach);
        let at = |s: f32| {
            let mut r = record.clone();
            r.vertices[0].p += e * s;
            contribution::<f32>(&plain, &r, detached).x
        };
        let fd = (at(h) - at(-h)) / (2.0 * h);
        assert!(
            (d.x.eps - fd).abs() < 2e-3 * (1.0 + fd.abs()),
            "d/dx_{k}: {} vs {fd}",
            d.x.eps
        );
    }
}
