//! Camera (projection, rays, film-area Jacobian) and film (filters, EXR/PNG output).

use glam::{Vec2, Vec3};
use implicit_psdr::Scalar;
use implicit_psdr::camera::Camera;
use implicit_psdr::film::Filter;
use implicit_psdr::math::Vec3 as V3;
use implicit_psdr::sampler::Sampler;
use implicit_psdr::scalar::Dual32;

fn test_camera() -> Camera {
    Camera::new(
        Vec3::new(1.0, 2.0, 6.0),
        Vec3::new(0.2, 0.5, -0.3),
        Vec3::new(0.1, 1.0, 0.05),
        40.0,
        64,
        48,
        Filter::Tent,
    )
}

#[test]
fn camera_validates() {
    assert!(test_camera().validate().is_ok());
    let mut c = test_camera();
    c.up = Param3From::from((c.target.value() - c.origin.value()) * 2.0);
    let e = c.validate().unwrap_err().to_string();
    assert!(e.starts_with("up:"), "{e}");
    let mut c = test_camera();
    c.fov_y.value = 180.0;
    assert!(c.validate().unwrap_err().to_string().starts_with("fov_y:"));
}

type Param3From = implicit_psdr::Param3;

#[test]
fn project_inverts_generate_ray() {
    let cam = test_camera();
    for i in 0..500u64 {
        let mut s = Sampler::new(11, 0, i, 0);
        let f = s.next_2d() * Vec2::new(64.0, 48.0);
        let ray = cam.generate_ray(f);
        assert!((ray.d.length() - 1.0).abs() < 1e-5);
        assert_eq!(ray.o, cam.origin.value());
        let t = 0.5 + 10.0 * s.next_1d();
        let (x, y) = cam.project::<f32>(ray.at(t).into()).expect("in front");
        assert!(
            (x - f.x).abs() < 1e-3 && (y - f.y).abs() < 1e-3,
            "{f:?} -> ({x}, {y})"
        );
    }
    // Behind the eye: no projection.
    let behind = cam.origin.value() * 2.0 - cam.target.value();
    assert!(cam.project::<f32>(behind.into()).is_none());
}

#[test]
fn image_conventions() {
    let cam = test_camera();
    let o = cam.origin.value();
    let target = cam.target.value();
    // The optical axis projects to the image centre (32, 24); the centre ray points at the target.
    let (x, y) = cam.project::<f32>((o + (target - o) * 0.7).into()).unwrap();
    assert!((x - 32.0).abs() < 1e-4 && (y - 24.0).abs() < 1e-4);
    let d = cam.generate_ray(Vec2::new(32.0, 24.0)).d;
    assert!((d - (target - o).normalize()).length() < 1e-6);
    // Up is up: a point above the target (along `up`) has a smaller row; row 0 is the top.
    let (_, y_up) = cam.project::<f32>((target + Vec3::Y * 0.3).into()).unwrap();
    assert!(y_up < y - 1.0);
    assert!(cam.generate_ray(Vec2::new(32.0, 0.0)).d.dot(Vec3::Y) > d.dot(Vec3::Y));
    // Right-handed: image +x is forward × up.
    let right = (target - o).cross(Vec3::Y);
    let (x_r, _) = cam
        .project::<f32>((target + right.normalize() * 0.3).into())
        .unwrap();
    assert!(x_r > x + 1.0);
    // fov_y is the full vertical angle: rays through the top and bottom edges of the centre column.
    let top = cam.generate_ray(Vec2::new(32.0, 0.0)).d;
    let bottom = cam.generate_ray(Vec2::new(32.0, 48.0)).d;
    let angle = top.dot(bottom).acos().to_degrees();
    assert!((angle - 40.0).abs() < 1e-3, "{angle}");
}

/// Film area of the projected square patch of side `h` at `p` with normal `n`, by the shoelace formula.
fn patch_film_area(cam: &Camera, p: Vec3, n: Vec3, h: f32) -> f32 {
    let f = implicit_psdr::math::Frame::from_normal(n);
    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(a, b)| {
        cam.project::<f32>((p + (f.s * a + f.t * b) * (0.5 * h)).into())
            .unwrap()
    });
    // Relative to the first corner: absolute film coordinates would cancel catastrophically in f32.
    let (cx, cy) = corners[0];
    let mut area = 0.0;
    for k in 0..4 {
        let (x0, y0) = (corners[k].0 - cx, corners[k].1 - cy);
        let (x1, y1) = (corners[(k + 1) % 4].0 - cx, corners[(k + 1) % 4].1 - cy);
        area += x0 * y1 - x1 * y0;
    }
    0.5 * area.abs()
}

#[test]
fn film_area_jacobian_matches_projected_patches() {
    let cam = test_camera();
    for i in 0..200u64 {
        let mut s = Sampler::new(12, 0, i, 0);
        // A point in view and a random normal tilted at most ~75° from the direction to the eye.
        let film = (s.next_2d() * 0.8 + 0.1) * Vec2::new(64.0, 48.0);
        let ray = cam.generate_ray(film);
        let p = ray.at(3.0 + 5.0 * s.next_1d());
        let u = s.next_2d();
        let tilt = 1.3 * u.x;
        let fr = implicit_psdr::math::Frame::from_normal(-ray.d);
        let n = fr.to_world(Vec3::new(
            tilt.sin() * (std::f32::consts::TAU * u.y).cos(),
            tilt.sin() * (std::f32::consts::TAU * u.y).sin(),
            tilt.cos(),
        ));
        let h = 0.02;
        let numeric = patch_film_area(&cam, p, n, h) / (h * h);
        let j = cam.film_area_jacobian::<f32>(p.into(), n.into());
        assert!(
            (numeric - j).abs() < 2e-3 * j,
            "sample {i}: numeric {numeric}, jacobian {j}"
        );
        // The sign of the normal does not matter.
        assert_eq!(j, cam.film_area_jacobian::<f32>(p.into(), (-n).into()));
    }
}

#[test]
fn dual_derivatives_match_central_differences() {
    // Differentiate w.r.t. each lifted camera coordinate in turn: origin.x, target.y, up.z, fov_y.
    let p = V3::<f32>::new(0.4, 0.8, 0.1);
    let n = V3::<f32>::new(0.3, 0.5, 0.81).normalize_or_zero();
    let lift = |v: V3<f32>| V3::<Dual32>::constant(v.into());
    for which in 0..4 {
        let set = |cam: &mut Camera, delta: f32, slot: Option<u16>| match which {
            0 => {
                cam.origin.c[0].value += delta;
                cam.origin.c[0].slot = slot;
            }
            1 => {
                cam.target.c[1].value += delta;
                cam.target.c[1].slot = slot;
            }
            2 => {
                cam.up.c[2].value += delta;
                cam.up.c[2].slot = slot;
            }
            _ => {
                cam.fov_y.value += delta;
                cam.fov_y.slot = slot;
            }
        };
        let mut cam = test_camera();
        set(&mut cam, 0.0, Some(0));
        let (x, y) = cam.project::<Dual32>(lift(p)).unwrap();
        let j = cam.film_area_jacobian::<Dual32>(lift(p), lift(n));
        let h = 1e-2;
        let eval = |delta: f32| {
            let mut c = test_camera();
            set(&mut c, delta, None);
            let (x, y) = c.project::<f32>(p).unwrap();
            (x as f64, y as f64, c.film_area_jacobian::<f32>(p, n) as f64)
        };
        let (xp, yp, jp) = eval(h);
        let (xm, ym, jm) = eval(-h);
        let h = h as f64;
        let fd = [
            (xp - xm) / (2.0 * h),
            (yp - ym) / (2.0 * h),
            (jp - jm) / (2.0 * h),
        ];
        let ad = [x.eps as f64, y.eps as f64, j.eps as f64];
        for k in 0..3 {
            let tol = 2e-3 * fd[k].abs().max(ad[k].abs()) + 1e-2;
            assert!(
                (fd[k] - ad[k]).abs() < tol,
                "param {which}, output {k}: fd {} vs dual {}",
                fd[k],
                ad[k]
            );
        }
        assert!(
            ad.iter().any(|v| v.abs() > 1e-2),
            "param {which}: derivative unexpectedly zero"
        );
        // The primal of the dual evaluation equals the f32 evaluation.
        assert!((x.primal() as f64 - eval(0.0).0).abs() < 1e-4);
    }
    // An attached point: d(project)/dp·v against central differences.
    let cam = test_camera();
    let v = V3::<f32>::new(0.2, -0.7, 0.4);
    let pd = V3::new(
        Dual32::new(p.x, v.x),
        Dual32::new(p.y, v.y),
        Dual32::new(p.z, v.z),
    );
    let (x, y) = cam.project::<Dual32>(pd).unwrap();
    let h = 1e-2;
    let (xp, yp) = cam.project::<f32>(p + v.scale(h)).unwrap();
    let (xm, ym) = cam.project::<f32>(p - v.scale(h)).unwrap();
    assert!((x.eps - (xp - xm) / (2.0 * h)).abs() < 2e-3 * x.eps.abs() + 1e-2);
    assert!((y.eps - (yp - ym) / (2.0 * h)).abs() < 2e-3 * y.eps.abs() + 1e-2);
}
