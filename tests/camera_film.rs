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
        let set = |cam: &mut Camera, delta: f32, slot: Option<u32>| match which {
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

// ---------------------------------------------------------------------------------------------------
// Filters

const FILTERS: [Filter; 3] = [Filter::Box, Filter::Tent, Filter::Gaussian];

/// Midpoint-rule integral of the filter over the square `[x0, x1] × [y0, y1]` with `n × n` cells.
fn integrate(f: Filter, x0: f64, x1: f64, y0: f64, y1: f64, n: usize) -> f64 {
    let (hx, hy) = ((x1 - x0) / n as f64, (y1 - y0) / n as f64);
    let mut sum = 0.0;
    for i in 0..n {
        for j in 0..n {
            let x = x0 + (i as f64 + 0.5) * hx;
            let y = y0 + (j as f64 + 0.5) * hy;
            sum += f.eval::<f32>(x as f32, y as f32) as f64;
        }
    }
    sum * hx * hy
}

#[test]
fn filters_integrate_to_one() {
    for f in FILTERS {
        let r = f.radius() as f64;
        // A slightly larger square: nothing may live outside the stated radius.
        let total = integrate(f, -r - 0.1, r + 0.1, -r - 0.1, r + 0.1, 600);
        assert!((total - 1.0).abs() < 2e-3, "{f:?}: ∫ = {total}");
        assert_eq!(f.eval::<f32>(r as f32 + 1e-3, 0.0), 0.0);
        assert_eq!(f.eval::<f32>(0.0, -(r as f32) - 1e-3), 0.0);
    }
    // Finer: the smooth filters to 1e-5.
    for f in [Filter::Tent, Filter::Gaussian] {
        let r = f.radius() as f64;
        let total = integrate(f, -r, r, -r, r, 1200);
        assert!((total - 1.0).abs() < 1e-5, "{f:?}: ∫ = {total}");
    }
}

#[test]
fn filter_samples_are_distributed_as_eval() {
    let bins = 10;
    let n = 200_000u64;
    for f in FILTERS {
        let r = f.radius();
        let mut counts = vec![0u64; bins * bins];
        for i in 0..n {
            let mut s = Sampler::new(21, 0, i, 0);
            let p = f.sample(s.next_2d());
            assert!(
                p.x.abs() <= r && p.y.abs() <= r,
                "{f:?}: sample {p:?} outside the support"
            );
            // The density at the sample is positive (weight / pdf = 1 needs eval > 0 where samples land).
            assert!(
                f.eval::<f32>(p.x, p.y) > 0.0 || p.x.abs() >= r * 0.999 || p.y.abs() >= r * 0.999
            );
            let bx = (((p.x + r) / (2.0 * r)) * bins as f32).clamp(0.0, bins as f32 - 1.0) as usize;
            let by = (((p.y + r) / (2.0 * r)) * bins as f32).clamp(0.0, bins as f32 - 1.0) as usize;
            counts[by * bins + bx] += 1;
        }
        let w = 2.0 * r as f64 / bins as f64;
        let mut chi2 = 0.0;
        let mut dof = 0;
        for by in 0..bins {
            for bx in 0..bins {
                let x0 = -(r as f64) + bx as f64 * w;
                let y0 = -(r as f64) + by as f64 * w;
                let expected = n as f64 * integrate(f, x0, x0 + w, y0, y0 + w, 40);
                if expected < 20.0 {
                    continue;
                }
                let d = counts[by * bins + bx] as f64 - expected;
                chi2 += d * d / expected;
                dof += 1;
            }
        }
        // χ² with `dof` degrees of freedom: mean dof, sd √(2 dof); allow 5 sd.
        let limit = dof as f64 + 5.0 * (2.0 * dof as f64).sqrt();
        assert!(chi2 < limit, "{f:?}: χ² = {chi2} over {dof} bins");
    }
}

#[test]
fn smooth_filter_samples_invert_the_cdf() {
    // Tent marginal CDF F(x) = (1+x)²/2 for x ≤ 0, 1 − (1−x)²/2 for x ≥ 0.
    let cdf = |x: f64| {
        if x <= 0.0 {
            0.5 * (1.0 + x) * (1.0 + x)
        } else {
            1.0 - 0.5 * (1.0 - x) * (1.0 - x)
        }
    };
    for k in 0..=1000 {
        let u = (k as f32 / 1000.0).min(0.999_999);
        let p = Filter::Tent.sample(Vec2::new(u, 0.5));
        assert!(
            (cdf(p.x as f64) - u as f64).abs() < 1e-6,
            "u = {u}: x = {}",
            p.x
        );
        assert!(p.y.abs() < 1e-6);
    }
    // Gaussian marginal CDF by quadrature of eval along x (eval(x, 0) / eval1d(0) gives the 1D filter).
    let g = Filter::Gaussian;
    let g0 = g.eval::<f32>(0.0, 0.0).sqrt() as f64;
    let marginal = |x: f64| g.eval::<f32>(x as f32, 0.0) as f64 / g0;
    for k in 1..20 {
        let u = k as f32 / 20.0;
        let x = g.sample(Vec2::new(u, 0.5)).x as f64;
        let m = 4000;
        let h = (x + 1.5) / m as f64;
        let cdf: f64 = (0..m)
            .map(|i| marginal(-1.5 + (i as f64 + 0.5) * h))
            .sum::<f64>()
            * h;
        assert!(
            (cdf - u as f64).abs() < 2e-6,
            "u = {u}: x = {x}, cdf = {cdf}"
        );
    }
}

#[test]
fn filter_dual_derivatives_match_central_differences() {
    for f in [Filter::Tent, Filter::Gaussian] {
        let r = f.radius();
        for i in 0..300u64 {
            let mut s = Sampler::new(22, 0, i, 0);
            let p = (s.next_2d() * 2.0 - 1.0) * r;
            // Away from the tent's kinks (axes and edges) where the one-sided derivatives differ.
            if p.x.abs() < 0.02 || p.y.abs() < 0.02 || p.x.abs() > r - 0.02 || p.y.abs() > r - 0.02
            {
                continue;
            }
            let v = s.next_2d() - 0.5;
            let d = f.eval::<Dual32>(Dual32::new(p.x, v.x), Dual32::new(p.y, v.y));
            let h = 1e-3;
            let fp = f.eval::<f32>(p.x + h * v.x, p.y + h * v.y) as f64;
            let fm = f.eval::<f32>(p.x - h * v.x, p.y - h * v.y) as f64;
            let fd = (fp - fm) / (2.0 * h as f64);
            assert!(
                (d.eps as f64 - fd).abs() < 1e-3 * fd.abs() + 2e-4,
                "{f:?} at {p:?}: dual {} fd {fd}",
                d.eps
            );
            assert_eq!(d.re, f.eval::<f32>(p.x, p.y));
        }
    }
}

#[test]
fn box_filter_is_discontinuous_with_zero_derivative() {
    let b = Filter::Box;
    assert!(!b.is_continuous() && Filter::Tent.is_continuous() && Filter::Gaussian.is_continuous());
    assert_eq!(b.eval::<f32>(0.499, 0.0), 1.0);
    assert_eq!(b.eval::<f32>(0.5, -0.5), 1.0);
    assert_eq!(b.eval::<f32>(0.501, 0.0), 0.0);
    let d = b.eval::<Dual32>(Dual32::new(0.2, 1.0), Dual32::new(-0.3, 1.0));
    assert_eq!((d.re, d.eps), (1.0, 0.0));
    // The smooth filters are continuous at their edges.
    for f in [Filter::Tent, Filter::Gaussian] {
        let r = f.radius();
        assert!(f.eval::<f32>(r - 1e-4, 0.0) < 1e-3, "{f:?}");
    }
}

// ---------------------------------------------------------------------------------------------------
// Output

fn scratch_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("ipsdr-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn exr_round_trip_with_odd_channel_names() {
    use implicit_psdr::film::{read_exr, write_exr};
    let dir = scratch_dir("exr");
    let path = dir.join("out.exr");
    let (w, h) = (5u32, 3u32);
    let names = [
        "R",
        "G",
        "B",
        "d.ball.radius.R",
        "d.cam.fov_y.B",
        "weird name-1",
    ];
    let channels: Vec<(String, Vec<f32>)> = names
        .iter()
        .enumerate()
        .map(|(c, n)| {
            let values = (0..w * h)
                .map(|i| c as f32 * 1000.0 + i as f32 - 0.25 * (i % 3) as f32)
                .collect();
            (n.to_string(), values)
        })
        .collect();
    write_exr(&path, w, h, &channels).unwrap();
    let (rw, rh, back) = read_exr(&path).unwrap();
    assert_eq!((rw, rh), (w, h));
    assert_eq!(back.len(), channels.len());
    for (name, values) in &channels {
        let (_, got) = back
            .iter()
            .find(|(n, _)| n == name)
            .unwrap_or_else(|| panic!("channel {name} lost"));
        // Bit-exact, pixel (x, y) at y·w + x with row 0 first (OpenEXR: increasing y is downward).
        assert_eq!(got, values, "channel {name}");
    }
    // Only the file itself remains (no temporary files).
    let entries: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(entries, vec![std::ffi::OsString::from("out.exr")]);
    // Errors name the file and leave nothing behind.
    let bad = dir.join("bad.exr");
    let e = write_exr(&bad, w, h, &[("R".into(), vec![0.0; 7])]).unwrap_err();
    assert!(
        matches!(e, implicit_psdr::Error::File { .. }) && e.to_string().contains("bad.exr"),
        "{e}"
    );
    let missing = dir.join("no/such/dir/x.exr");
    let e = write_exr(&missing, w, h, &channels).unwrap_err();
    assert!(e.to_string().contains("x.exr"), "{e}");
    assert!(
        read_exr(&dir.join("nothing.exr"))
            .unwrap_err()
            .to_string()
            .contains("nothing.exr")
    );
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn png_is_srgb_encoded_row_major_from_the_top() {
    use implicit_psdr::film::write_png;
    let dir = scratch_dir("png");
    let path = dir.join("out.png");
    let (w, h) = (3u32, 2u32);
    let mut rgb = vec![0.0f32; 3 * 6];
    // (1, 0): red, top row; (0, 1): mid grey, bottom row; (2, 1): out of range values.
    rgb[3] = 1.0;
    rgb[9..12].copy_from_slice(&[0.5, 0.5, 0.5]);
    rgb[15..18].copy_from_slice(&[7.0, -1.0, f32::NAN]);
    write_png(&path, w, h, &rgb).unwrap();
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0u8; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (w, h));
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let bytes = &buf[..info.buffer_size()];
    assert_eq!(&bytes[0..6], &[0, 0, 0, 255, 0, 0]);
    // sRGB(0.5) = 1.055·0.5^(1/2.4) − 0.055 = 0.73536 → 187.5 → 188.
    assert_eq!(&bytes[9..12], &[188, 188, 188]);
    assert_eq!(&bytes[15..18], &[255, 0, 0]);
    let e = write_png(&dir.join("bad.png"), w, h, &rgb[..5]).unwrap_err();
    assert!(e.to_string().contains("bad.png"));
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
    std::fs::remove_dir_all(&dir).unwrap();
}
