//! The primary boundary term along the outlines of emitters seen directly (rectangle edges, sphere
//! silhouettes): the complete derivative (interior + primary) against central finite differences with
//! common random numbers, in front of a finite background (an emitting wall, whose points are attached)
//! and in front of the environment, for the light's position and size and the camera.

mod common;

use common::deriv::{self as deriv, gray};
use implicit_psdr::bsdf::Bsdf;
use implicit_psdr::camera::Camera;
use implicit_psdr::emitter::Emitter;
use implicit_psdr::film::Filter;
use implicit_psdr::integrator::boundary::emitter_edges::EmitterOutlines;
use implicit_psdr::integrator::fd::finite_difference;
use implicit_psdr::integrator::{DiffOptions, Normalization, render_derivatives_with_boundary};
use implicit_psdr::integrator::{IntegratorKind, RenderOptions};
use implicit_psdr::scene::{NamedEmitter, Scene, Shape};
use implicit_psdr::sdf::Sdf;
use implicit_psdr::{Param, Param3};

const SIZE: u32 = 32;

fn camera() -> Camera {
    Camera::new(
        glam::Vec3::new(0.0, 0.0, 4.0),
        glam::Vec3::ZERO,
        glam::Vec3::Y,
        40.0,
        SIZE,
        SIZE,
        Filter::Tent,
    )
}

/// A rectangle light facing the camera (about 13 × 9 pixels), tilted a little about y so its image is
/// not axis-aligned; `front` = false turns its back (non-emitting side) to the camera.
fn light(front: bool) -> NamedEmitter {
    let n = glam::Vec3::new(0.25, 0.0, 1.0).normalize() * if front { 1.0 } else { -1.0 };
    let u = glam::Vec3::Y.cross(n).normalize();
    NamedEmitter {
        name: "light".into(),
        emitter: Emitter::Rectangle {
            center: Param3::new([0.1, -0.05, 0.0]),
            normal: n,
            u,
            size: [Param::new(1.2), Param::new(0.8)],
            radiance: Param3::new([4.0, 3.0, 2.0]),
        },
    }
}

/// The light in front of a large emitting wall (a finite background) or of a constant environment.
fn scene(finite_background: bool, front: bool) -> Scene {
    let background = if finite_background {
        NamedEmitter {
            name: "wall".into(),
            emitter: Emitter::Rectangle {
                center: Param3::new([0.0, 0.0, -2.0]),
                normal: glam::Vec3::Z,
                u: glam::Vec3::X,
                size: [Param::new(12.0), Param::new(12.0)],
                radiance: Param3::new([1.0, 2.0, 3.0]),
            },
        }
    } else {
        NamedEmitter {
            name: "env".into(),
            emitter: Emitter::Constant {
                radiance: Param3::new([1.0, 1.0, 1.0]),
            },
        }
    };
    Scene::new(
        camera(),
        IntegratorKind::Direct,
        1,
        vec![],
        vec![light(front), background],
    )
}

/// A sphere light of radius 0.5 in the environment.
fn sphere_scene() -> Scene {
    let ball = NamedEmitter {
        name: "bulb".into(),
        emitter: Emitter::Sphere {
            center: Param3::new([0.15, 0.1, 0.0]),
            radius: Param::new(0.5),
            radiance: Param3::new([3.0, 3.0, 3.0]),
        },
    };
    let env = NamedEmitter {
        name: "env".into(),
        emitter: Emitter::Constant {
            radiance: Param3::new([1.0, 0.5, 0.25]),
        },
    };
    Scene::new(camera(), IntegratorKind::Direct, 1, vec![], vec![ball, env])
}

/// 5×5 box blur of a `SIZE × SIZE` plane.
fn blur(v: &[f64]) -> Vec<f64> {
    deriv::blur(v, SIZE as usize, SIZE as usize, 2)
}

/// Relative L2 error of `a` against `b`.
fn rel_l2(a: &[f64], b: &[f64]) -> f64 {
    deriv::rel_l2(a, b, None)
}

/// Measured errors of one case.
struct Errors {
    /// Relative L2 of the complete derivative against FD after a 5×5 blur.
    l2: f64,
    /// The same without the outline term (interior alone): must be far worse.
    l2_interior: f64,
    /// |Σ total − Σ fd| / Σ|fd|.
    sum: f64,
    /// Σ|fd| (the scale of the comparison).
    abs_fd: f64,
}

/// Complete derivative (default `differentiable` normalisation unless `fixed`) against FD.
fn compare(base: &Scene, name: &str, h: f32, spp: u32, fixed: bool) -> Errors {
    let selection = base.select(&[name]).unwrap();
    let opts = DiffOptions {
        render: RenderOptions {
            spp,
            seed: 5,
            progress: Default::default(),
        },
        normalization: if fixed {
            Normalization::Fixed
        } else {
            Normalization::Differentiable
        },
        ..Default::default()
    };
    let out = render_derivatives_with_boundary(base, &selection, &opts, 100_000, 0).unwrap();
    let total = gray(&out.total()[0]);
    let interior = gray(&out.interior[0]);
    for img in out.total().iter().chain(&out.primary) {
        assert!(img.rgb.iter().all(|v| v.is_finite()), "{name}: non-finite");
    }
    let fd = gray(
        &finite_difference(
            base,
            name,
            h,
            &RenderOptions {
                spp: 1024,
                seed: 11,
                progress: Default::default(),
            },
        )
        .unwrap(),
    );
    let (bt, bi, bf) = (blur(&total), blur(&interior), blur(&fd));
    let abs_fd: f64 = fd.iter().map(|v| v.abs()).sum();
    let sum = (total.iter().sum::<f64>() - fd.iter().sum::<f64>()).abs() / abs_fd;
    let e = Errors {
        l2: rel_l2(&bt, &bf),
        l2_interior: rel_l2(&bi, &bf),
        sum,
        abs_fd,
    };
    eprintln!(
        "{name} ({}): blurred rel L2 {:.3} (interior alone {:.3}); |Σ total − Σ fd| / Σ|fd| {:.4}; \
         Σ|fd| {:.2}",
        if fixed { "fixed" } else { "differentiable" },
        e.l2,
        e.l2_interior,
        e.sum,
        e.abs_fd
    );
    e
}

#[test]
fn outlines_of_visible_emitters() {
    let s = scene(false, true);
    let outlines = EmitterOutlines::seen_from(&s);
    // The whole rectangle is in view: its perimeter.
    let perimeter = 2.0 * (1.2 + 0.8);
    assert!((outlines.total_length() - perimeter).abs() < 1e-4);
    // A sphere of radius r at distance d: a circle of radius r √(1 − r²/d²).
    let b = sphere_scene();
    let d = glam::Vec3::new(0.15, 0.1, -4.0).length();
    let expected = std::f32::consts::TAU * 0.5 * (1.0 - 0.25 / (d * d)).sqrt();
    let o = EmitterOutlines::seen_from(&b);
    assert!((o.total_length() - expected).abs() < 1e-4);
    for i in 0..64 {
        let p = o.sample([(i as f32 + 0.5) / 64.0, 0.37]).unwrap();
        let eye = glam::Vec3::new(0.0, 0.0, 4.0);
        // The view ray is tangent to the sphere at every outline point.
        assert!((p.x - eye).normalize().dot(p.outward).abs() < 1e-5);
        assert!(((p.x - glam::Vec3::new(0.15, 0.1, 0.0)).length() - 0.5).abs() < 1e-5);
    }
    // A light outside the view: nothing to sample.
    let mut away = scene(false, true);
    if let Emitter::Rectangle { center, .. } = &mut away.emitters[0].emitter {
        *center = Param3::new([5.0, 0.0, 0.0]);
    }
    assert!(EmitterOutlines::seen_from(&away).is_empty());
    // Partly outside: clipped to the frustum grown by the filter radius and one pixel.
    let mut half = scene(false, true);
    if let Emitter::Rectangle { center, .. } = &mut half.emitters[0].emitter {
        *center = Param3::new([1.5, 0.0, 0.0]);
    }
    let l = EmitterOutlines::seen_from(&half).total_length();
    assert!(l > 0.8 && l < perimeter - 0.5, "{l}");
}

/// Light position and size and the camera, in front of the emitting wall (finite background).
#[test]
fn rectangle_before_a_finite_background() {
    let base = scene(true, true);
    // The camera's interior term is noisy (moving projections through the filter) and nearly cancels
    // the outline term (Σ|fd| is 1/20 of the others): its sum error is interior noise, measured 0.026
    // at 4096 spp and 0.0098 at 16384 spp.
    for (name, h, spp, sum_bound) in [
        ("light.center.x", 0.02f32, 64, 0.03),
        ("light.size.y", 0.02, 64, 0.03),
        ("camera.origin.x", 0.05, 4096, 0.05),
    ] {
        let e = compare(&base, name, h, spp, false);
        assert!(e.l2 < 0.1, "{name}: blurred rel L2 {}", e.l2);
        assert!(e.sum < sum_bound, "{name}: sums {}", e.sum);
        assert!(
            e.l2_interior > 3.0 * e.l2,
            "{name}: the interior alone should fail"
        );
    }
}

/// The same light in front of the environment (the background at infinity: fixed directions), the
/// light seen from behind (dark, still blocking), and the fixed normalisation.
#[test]
fn rectangle_before_the_environment() {
    let base = scene(false, true);
    for (name, h, spp, fixed) in [
        ("light.center.x", 0.02f32, 64, false),
        ("light.size.x", 0.02, 64, true),
        ("camera.target.x", 0.02, 4096, false),
    ] {
        let e = compare(&base, name, h, spp, fixed);
        assert!(e.l2 < 0.1, "{name}: blurred rel L2 {}", e.l2);
        assert!(e.sum < 0.03, "{name}: sums {}", e.sum);
    }
    let back = scene(false, false);
    let e = compare(&back, "light.center.x", 0.02, 64, false);
    assert!(e.l2 < 0.1, "back side: blurred rel L2 {}", e.l2);
    assert!(e.sum < 0.03, "back side: sums {}", e.sum);
    assert!(e.l2_interior > 3.0 * e.l2);
}

/// A sphere light's silhouette circle: its radius and position.
#[test]
fn sphere_light_silhouette() {
    let base = sphere_scene();
    for (name, h) in [("bulb.radius", 0.02f32), ("bulb.center.y", 0.02)] {
        let e = compare(&base, name, h, 64, false);
        assert!(e.l2 < 0.1, "{name}: blurred rel L2 {}", e.l2);
        assert!(e.sum < 0.03, "{name}: sums {}", e.sum);
        assert!(e.l2_interior > 3.0 * e.l2);
    }
}

/// A diffuse ball beside a small rectangle light, both in the environment: the samples are shared
/// between the ball's silhouette and the light's edges. Camera parameters move no shadow, so the
/// complete derivative is interior + primary. A camera rotation moves the environment on the film (the
/// interior attaches escaping rays to their direction), so both boundary parts must measure their
/// velocity relative to fixed directions, not fixed film points: with fixed film points the primary
/// term for `camera.origin.x` (which turns the camera to keep its target) was nearly zero and the
/// complete derivative off by the interior's whole moving-environment term (Σ|total − fd| 262 against
/// Σ|fd| 9 on a lone ball).
#[test]
fn camera_in_the_environment_with_silhouettes_and_outlines() {
    let mut base = scene(false, true);
    if let Emitter::Rectangle { center, size, .. } = &mut base.emitters[0].emitter {
        *center = Param3::new([0.55, 0.1, 0.0]);
        *size = [Param::new(0.6), Param::new(0.6)];
    }
    base.shapes.push(Shape::new(
        "ball",
        Sdf::sphere([-0.6, 0.0, 0.0], 0.45),
        Bsdf::Diffuse {
            albedo: Param3::new([0.5; 3]),
        },
    ));
    let base = Scene::new(
        base.camera.clone(),
        IntegratorKind::Direct,
        1,
        base.shapes.clone(),
        base.emitters.clone(),
    );
    // Measured: camera.origin.x blurred rel L2 0.158 / 0.088 / 0.088 at 1024 / 2048 / 8192 spp (the
    // rest is FD and boundary-sample noise), sums within 0.021; camera.target.y 0.020 and 0.006.
    for (name, h) in [("camera.origin.x", 0.05f32), ("camera.target.y", 0.02)] {
        let e = compare(&base, name, h, 2048, false);
        assert!(e.l2 < 0.15, "{name}: blurred rel L2 {}", e.l2);
        assert!(e.sum < 0.05, "{name}: sums {}", e.sum);
    }
}

/// Identical bit for bit with 1 and 2 threads, finite, and nonzero for a moving light.
#[test]
fn outline_term_is_deterministic() {
    let scene = scene(true, true);
    let two = scene
        .select(&["light.center.y", "camera.origin.y"])
        .unwrap();
    let opts = DiffOptions {
        render: RenderOptions {
            spp: 1,
            seed: 3,
            progress: Default::default(),
        },
        normalization: Normalization::Differentiable,
        ..Default::default()
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                implicit_psdr::integrator::boundary::primary::render_primary_terms(
                    &scene, &two, &opts, 20_000,
                )
                .unwrap()
            })
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a, b);
    for img in a.radiance.iter().chain(&a.coverage) {
        assert!(img.rgb.iter().all(|v| v.is_finite()));
        assert!(img.rgb.iter().any(|v| *v != 0.0));
    }
}
