//! The `envmap` emitter: its mapping pinned on a hand-made map (through the emitter and through a
//! rendered image), its direction sampling against its own density (chi-square) and the density's
//! integral, a one-colour map against the `constant` emitter, rotation invariance of a whole scene,
//! and bad input.

mod common;

use common::chi2::{Chi2, assert_fits};
use common::deriv::{blur, gray, rel_l2};
use common::{assert_failure, assert_success, outputs, run, workdir};
use implicit_psdr::emitter::{Emitter, EnvMap};
use implicit_psdr::integrator::{RenderOptions, render};
use implicit_psdr::math::Vec3;
use implicit_psdr::scalar::Param;
use implicit_psdr::scene::Scene;
use std::f32::consts::PI;
use std::path::Path;
use std::sync::Arc;

/// Writes a `w × h` RGB EXR whose texel `(row, column)` is `f(row, column)`.
fn write_map(path: &Path, w: usize, h: usize, f: impl Fn(usize, usize) -> [f32; 3]) {
    let mut planes = [vec![0.0; w * h], vec![0.0; w * h], vec![0.0; w * h]];
    for i in 0..h {
        for j in 0..w {
            let t = f(i, j);
            for c in 0..3 {
                planes[c][i * w + j] = t[c];
            }
        }
    }
    let channels: Vec<(String, Vec<f32>)> = ["R", "G", "B"]
        .iter()
        .zip(planes)
        .map(|(n, p)| (n.to_string(), p))
        .collect();
    implicit_psdr::io::write_exr(path, w as u32, h as u32, &channels).unwrap();
}

/// A sky with a bright Gaussian spot (angular σ `sigma` degrees, peak `peak`) around `sun`, sampled
/// at the texel centres of a `w × h` map.
fn sun_sky(w: usize, h: usize, sun: [f32; 3], sigma: f32, peak: f32) -> Vec<[f32; 3]> {
    let sun = glam::Vec3::from(sun).normalize();
    let mut texels = Vec::new();
    for i in 0..h {
        for j in 0..w {
            let d = EnvMap::direction((j as f32 + 0.5) / w as f32, (i as f32 + 0.5) / h as f32);
            let a = d.dot(sun).clamp(-1.0, 1.0).acos() / sigma.to_radians();
            let s = peak * (-0.5 * a * a).exp();
            let sky = 0.3 + 0.2 * d.y.max(0.0);
            texels.push([sky + s, sky + 0.9 * s, 0.2 + 0.8 * s]);
        }
    }
    texels
}

/// The 4 × 8 hand-made map: texel `(i, j)` is `[1 + 8i + j, 10 + i, 20 + j]`, all distinct.
fn hand_made(i: usize, j: usize) -> [f32; 3] {
    [
        1.0 + 8.0 * i as f32 + j as f32,
        10.0 + i as f32,
        20.0 + j as f32,
    ]
}

fn envmap(map: EnvMap, scale: f32, axis: glam::Vec3, degrees: f32) -> Emitter {
    Emitter::Envmap {
        map: Arc::new(map),
        scale: Param::new(scale),
        axis,
        angle: Param::new(degrees),
    }
}

/// The radiance arriving from world direction `d`.
fn arriving(e: &Emitter, d: glam::Vec3) -> glam::Vec3 {
    let w = Vec3::<f32>::constant(-d);
    e.emitted::<f32>(Vec3::zero(), w, w).into()
}

#[track_caller]
fn assert_rgb(got: glam::Vec3, want: glam::Vec3, label: &str) {
    assert!(
        (got - want).abs().max_element() <= 1e-4 * want.abs().max_element().max(1.0),
        "{label}: {got} vs {want}"
    );
}

/// The bilinear value of the hand-made map at texel coordinates `(row, column)` (centres at
/// integers), written out independently of the renderer: columns wrap, rows clamp.
fn expected(row: f32, column: f32) -> glam::Vec3 {
    let (w, h) = (8i64, 4i64);
    let (i0, j0) = (row.floor(), column.floor());
    let (fy, fx) = (row - i0, column - j0);
    let t = |i: i64, j: i64| {
        glam::Vec3::from(hand_made(
            i.clamp(0, h - 1) as usize,
            j.rem_euclid(w) as usize,
        ))
    };
    let (i0, j0) = (i0 as i64, j0 as i64);
    (t(i0, j0) * (1.0 - fx) + t(i0, j0 + 1) * fx) * (1.0 - fy)
        + (t(i0 + 1, j0) * (1.0 - fx) + t(i0 + 1, j0 + 1) * fx) * fy
}

/// The convention, pinned: `u = atan2(x, −z)/2π`, `v = acos(y)/π`, row 0 up, texel `(i, j)` at
/// `u = (j + 0.5)/W`, `v = i/(H − 1)` (Mitsuba 3's), bilinear, wrapping in `u`; `rotate` maps the map
/// into the world (a world direction is looked up at `R⁻¹ d`), the angle in degrees.
#[test]
fn mapping_of_a_hand_made_map() {
    let map = || {
        let texels = (0..32).map(|k| hand_made(k / 8, k % 8)).collect();
        EnvMap::new(8, 4, texels).unwrap()
    };
    let e = envmap(map(), 1.0, glam::Vec3::Y, 0.0);
    // Texels (the first and last rows lie at the poles, where every column meets).
    for (i, j) in [(1usize, 2usize), (2, 6), (1, 0), (2, 7)] {
        let d = EnvMap::direction((j as f32 + 0.5) / 8.0, i as f32 / 3.0);
        assert_rgb(arriving(&e, d), hand_made(i, j).into(), "texel centre");
    }
    // Known directions. −z: u = 0 (half-way between the last and the first column), v = 1/2 (half-way
    // between rows 1 and 2).
    let cases = [
        (glam::Vec3::NEG_Z, expected(1.5, -0.5)),
        // +x: u = 1/4 (between columns 1 and 2).
        (glam::Vec3::X, expected(1.5, 1.5)),
        // +z: u = 1/2; −x: u = 3/4.
        (glam::Vec3::Z, expected(1.5, 3.5)),
        (glam::Vec3::NEG_X, expected(1.5, 5.5)),
        // 30° above the horizon towards +x: v = 1/3, row coordinate 3 · 1/3.
        (
            glam::Vec3::new(60f32.to_radians().sin(), 60f32.to_radians().cos(), 0.0),
            expected(1.0, 1.5),
        ),
        // 10° from the zenith towards −z: v = 1/18, row coordinate 1/6.
        (
            glam::Vec3::new(0.0, 10f32.to_radians().cos(), -(10f32.to_radians().sin())),
            expected(1.0 / 6.0, -0.5),
        ),
        // 10° from the nadir towards +z: v = 17/18, row coordinate 17/6.
        (
            glam::Vec3::new(0.0, -(10f32.to_radians().cos()), 10f32.to_radians().sin()),
            expected(17.0 / 6.0, 3.5),
        ),
    ];
    for (d, want) in cases {
        assert_rgb(arriving(&e, d), want, &format!("direction {d}"));
    }
    // Wrapping: u = 0.01 lies between column 7 (wrapped) and column 0.
    let d = EnvMap::direction(0.01, 0.375);
    assert_rgb(arriving(&e, d), expected(1.125, 0.08 - 0.5), "wrap");
    // Scale multiplies.
    let scaled = envmap(map(), 2.5, glam::Vec3::Y, 0.0);
    assert_rgb(
        arriving(&scaled, glam::Vec3::X),
        expected(1.5, 1.5) * 2.5,
        "scale",
    );
    // Rotation by 90° about +y maps the map's −z to the world's −x: the world's −x sees u = 0.
    let turned = envmap(map(), 1.0, glam::Vec3::Y, 90.0);
    assert_rgb(
        arriving(&turned, glam::Vec3::NEG_X),
        expected(1.5, -0.5),
        "rotate",
    );
    assert_rgb(
        arriving(&turned, glam::Vec3::NEG_Z),
        expected(1.5, 1.5),
        "rotate (the map's +x now at −z)",
    );
}

/// The same convention through the scene file and a rendered image: a 1 × 1 image with a narrow
/// field of view looking along known directions sees the expected bilinear value (the EXR's first row
/// is `v = 0`, its first column `u ∈ [0, 1/W]`).
#[test]
fn rendered_pixels_see_the_mapping() {
    let dir = workdir("envmap", "mapping");
    write_map(&dir.join("map.exr"), 8, 4, hand_made);
    for (target, want) in [
        ([0.0, 0.0, -1.0], expected(1.5, -0.5)),
        ([1.0, 0.0, 0.0], expected(1.5, 1.5)),
        ([0.0, 0.0, 1.0], expected(1.5, 3.5)),
        (
            [60f32.to_radians().sin(), 60f32.to_radians().cos(), 0.0],
            expected(1.0, 1.5),
        ),
    ] {
        let json = format!(
            r#"{{"camera": {{"origin": [0, 0, 0], "target": {target:?}, "up": [0.3, 0.2, 1], "fov_y": 0.001,
                 "width": 1, "height": 1, "filter": "box"}},
               "emitters": [{{"name": "env", "type": "envmap", "file": "map.exr"}}]}}"#
        );
        let scene = implicit_psdr::scene::parse(&json, &dir).unwrap();
        let image = render(&scene, &options(4, 1)).0;
        let got = glam::Vec3::from_slice(&image.rgb);
        assert!(
            (got - want).abs().max_element() <= 1e-3 * want.max_element(),
            "looking at {target:?}: {got} vs {want}"
        );
    }
}

fn options(spp: u32, seed: u64) -> RenderOptions {
    RenderOptions {
        spp,
        seed,
        progress: Default::default(),
    }
}

/// Chi-square goodness-of-fit of the map's sampling against its density, and of the emitter's
/// (rotated about a tilted axis); both densities integrate to the fraction of draws that return a
/// direction (1). The map's own sampling is binned with the test's polar axis along the map's `x`:
/// the density per steradian grows like `1/sin θ` towards the map's poles, and the harness's midpoint
/// rule along `cos θ` would under-count a whole ring of bins around a pole on its axis (by 3% here),
/// where near the equator it misses only the sub-cell that holds the pole.
#[test]
fn sampling_fits_its_density() {
    let (w, h) = (40, 20);
    let map = EnvMap::new(w, h, sun_sky(w, h, [0.4, 0.5, -0.3], 9.0, 40.0)).unwrap();
    // The map's frame as the test's (x, y, z) = (y, z, x), a rotation.
    let to_test = |d: glam::Vec3| glam::Vec3::new(d.y, d.z, d.x);
    let from_test = |t: glam::Vec3| glam::Vec3::new(t.z, t.x, t.y);
    let chi2 = Chi2 {
        theta_bins: 20,
        phi_bins: 20,
        sub: 96,
        samples: 1_000_000,
        seed: 3,
    };
    let o = chi2.run(
        |u| map.sample(u).map(|(d, p)| (to_test(d), p)),
        |t| map.pdf(from_test(t)),
    );
    assert_fits("map", &o, 2e-3);
    let e = envmap(
        map.clone(),
        1.0,
        glam::Vec3::new(1.0, 2.0, 0.5).normalize(),
        70.0,
    );
    let o = chi2.run(
        |u| e.sample_li(glam::Vec3::ZERO, u).map(|s| (s.wi, s.pdf)),
        |d| e.pdf_li(glam::Vec3::ZERO, d, d, -d),
    );
    assert_fits("rotated emitter", &o, 2e-3);
    // A sun at the pole and a one-colour map (sampled uniformly) fit too.
    let polar = EnvMap::new(w, h, sun_sky(w, h, [0.05, 1.0, 0.0], 6.0, 80.0)).unwrap();
    let o = chi2.run(
        |u| polar.sample(u).map(|(d, p)| (to_test(d), p)),
        |t| polar.pdf(from_test(t)),
    );
    assert_fits("polar sun", &o, 2e-3);
    let flat = EnvMap::new(3, 2, vec![[0.5, 0.25, 1.0]; 6]).unwrap();
    let o = chi2.run(|u| flat.sample(u), |d| flat.pdf(d));
    assert_fits("one colour", &o, 1e-3);
}

/// The density integrates to one over the sphere: `∫ p sin θ dθ dφ` by a midpoint rule on a fine
/// `(θ, φ)` grid not aligned with the texel cells (`p sin θ` is bounded, where `p` alone has the
/// `1/sin θ` of the poles; the rule's error comes from cells cut by the grid, below 1e-3 here).
#[test]
fn density_integrates_to_one() {
    let (w, h) = (64, 32);
    for (label, map) in [
        (
            "sun",
            EnvMap::new(w, h, sun_sky(w, h, [0.4, 0.5, -0.3], 5.0, 300.0)),
        ),
        (
            "polar",
            EnvMap::new(w, h, sun_sky(w, h, [0.0, 1.0, 0.0], 5.0, 300.0)),
        ),
        (
            "tiny",
            EnvMap::new(2, 1, vec![[1.0, 0.0, 0.0], [0.0, 0.0, 4.0]]),
        ),
    ] {
        let map = map.unwrap();
        let (nt, np) = (1999, 2001);
        let pi = std::f64::consts::PI;
        let mut sum = 0.0f64;
        for a in 0..nt {
            let theta = pi * (a as f64 + 0.5) / nt as f64;
            let (r, z) = (theta.sin(), theta.cos());
            for b in 0..np {
                let phi = 2.0 * pi * (b as f64 + 0.5) / np as f64;
                let d = glam::Vec3::new((r * phi.cos()) as f32, z as f32, (r * phi.sin()) as f32);
                sum += map.pdf(d) as f64 * r;
            }
        }
        let integral = sum * 2.0 * pi * pi / (nt * np) as f64;
        println!("{label}: ∫ pdf dω = {integral}");
        assert!((integral - 1.0).abs() < 1e-3, "{label}: {integral}");
    }
}

/// A sphere and a torus on a floor, diffuse and metal, under `emitter` (JSON), `integrator`.
fn objects(emitter: &str, integrator: &str, size: u32) -> String {
    format!(
        r#"{{"camera": {{"origin": [0, 2.5, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 45,
              "width": {size}, "height": {size}, "filter": "tent"}},
            "integrator": {integrator},
            "shapes": [
              {{"name": "ball", "sdf": {{"type": "sphere", "center": [-0.6, 0.5, 0], "radius": 0.5}},
               "bsdf": {{"type": "diffuse", "albedo": [0.8, 0.6, 0.4]}}}},
              {{"name": "ring", "sdf": {{"type": "torus", "center": [0.7, 0.3, 0.2], "axis": [0.2, 1, 0.1],
                                          "major_radius": 0.45, "minor_radius": 0.18}},
               "bsdf": {{"type": "roughconductor", "alpha": 0.2, "eta": [0.2, 0.4, 1.4], "k": [3.9, 2.4, 1.6]}}}},
              {{"name": "floor", "sdf": {{"type": "box", "center": [0, -0.3, 0], "half_size": [3, 0.3, 3], "rounding": 0.1}},
               "bsdf": {{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}}}],
            "emitters": [{emitter}]}}"#
    )
}

/// A one-colour map gives the image of the `constant` emitter of its colour, in expectation: the map
/// is light-sampled (uniformly over the sphere, at one luminance) and weighted against the BSDF's
/// samples, the constant emitter left to the BSDF's samples alone (a different estimator of the same
/// integral). `direct` and `path`, 256 spp: the whole images' sums within 1%, and the images, blurred
/// over 3×3 pixels, within 3% (relative L2; the map's estimator is the noisier).
#[test]
fn one_colour_map_is_the_constant_emitter() {
    let dir = workdir("envmap", "constant");
    let colour = [0.7f32, 0.5, 0.3];
    write_map(&dir.join("flat.exr"), 6, 3, |_, _| colour);
    for integrator in [
        r#"{"type": "direct"}"#,
        r#"{"type": "path", "max_depth": 3}"#,
    ] {
        let parse =
            |e: &str| implicit_psdr::scene::parse(&objects(e, integrator, 24), &dir).unwrap();
        let constant = parse(&format!(
            r#"{{"name": "sky", "type": "constant", "radiance": {colour:?}}}"#
        ));
        let map = parse(
            r#"{"name": "sky", "type": "envmap", "file": "flat.exr", "rotate": {"axis": [1, 0, 0], "angle": 40}}"#,
        );
        let a = gray(&render(&constant, &options(256, 5)).0);
        let b = gray(&render(&map, &options(256, 6)).0);
        let sums = (a.iter().sum::<f64>() - b.iter().sum::<f64>()).abs() / a.iter().sum::<f64>();
        let images = rel_l2(&blur(&b, 24, 24, 1), &blur(&a, 24, 24, 1), None);
        println!("{integrator}: sums differ by {sums:.2e}, blurred images by {images:.2e}");
        assert!(
            sums < 0.01 && images < 0.03,
            "{integrator}: {sums}, {images}"
        );
    }
}

/// `p` rotated by `degrees` about the unit `axis` (Rodrigues).
fn rotate(p: [f32; 3], axis: glam::Vec3, degrees: f32) -> [f32; 3] {
    (glam::Quat::from_axis_angle(axis, degrees.to_radians()) * glam::Vec3::from(p)).to_array()
}

/// A ball and a metal ball on a plane under a sun map, everything (camera, shapes, the plane's
/// normal, the map) rotated by `degrees` about `axis`; the map by `map_degrees`.
fn turned_scene(dir: &Path, axis: glam::Vec3, degrees: f32, map_degrees: f32) -> Scene {
    let r = |p: [f32; 3]| format!("{:?}", rotate(p, axis, degrees));
    let json = format!(
        r#"{{"camera": {{"origin": {o}, "target": {t}, "up": {u}, "fov_y": 45, "width": 24, "height": 24, "filter": "tent"}},
            "integrator": {{"type": "path", "max_depth": 2}},
            "shapes": [
              {{"name": "ball", "sdf": {{"type": "sphere", "center": {b}, "radius": 0.5}},
               "bsdf": {{"type": "diffuse", "albedo": [0.8, 0.6, 0.4]}}}},
              {{"name": "metal", "sdf": {{"type": "sphere", "center": {m}, "radius": 0.4}},
               "bsdf": {{"type": "roughconductor", "alpha": 0.3}}}},
              {{"name": "floor", "sdf": {{"type": "plane", "normal": {n}, "offset": {off}}},
               "bsdf": {{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}}}],
            "emitters": [{{"name": "env", "type": "envmap", "file": "sun.exr",
                           "rotate": {{"axis": {a:?}, "angle": {map_degrees}}}}}]}}"#,
        o = r([0.0, 2.5, 4.0]),
        t = r([0.0, 0.2, 0.0]),
        u = r([0.0, 1.0, 0.0]),
        b = r([-0.6, 0.5, 0.0]),
        m = r([0.6, 0.4, 0.3]),
        n = r([0.0, 1.0, 0.0]),
        off = 0.0,
        a = axis.to_array(),
    );
    implicit_psdr::scene::parse(&json, dir).unwrap()
}

/// Rotating the whole scene and the map together leaves the image unchanged within noise: the
/// blurred relative L2 between the turned and the original image stays within 1.5 times that
/// between two seeds of the original (the BSDF frames are not rotation-equivariant, so the two
/// images are independent renders of the same expectation, like two seeds). Turning the map the other
/// way must fail that bound by far.
#[test]
fn turning_scene_and_map_together_changes_nothing() {
    let dir = workdir("envmap", "turn");
    let texels = sun_sky(32, 16, [0.5, 0.7, 0.4], 8.0, 60.0);
    write_map(&dir.join("sun.exr"), 32, 16, |i, j| texels[i * 32 + j]);
    let axis = glam::Vec3::new(0.3, 1.0, -0.4).normalize();
    let spp = 64;
    let base = gray(&render(&turned_scene(&dir, axis, 0.0, 0.0), &options(spp, 1)).0);
    let other_seed = gray(&render(&turned_scene(&dir, axis, 0.0, 0.0), &options(spp, 2)).0);
    let turned = gray(&render(&turned_scene(&dir, axis, 50.0, 50.0), &options(spp, 1)).0);
    let wrong = gray(&render(&turned_scene(&dir, axis, 50.0, -50.0), &options(spp, 1)).0);
    let d = |a: &[f64], b: &[f64]| rel_l2(&blur(a, 24, 24, 1), &blur(b, 24, 24, 1), None);
    let (noise, got, bad) = (d(&other_seed, &base), d(&turned, &base), d(&wrong, &base));
    println!("seed to seed {noise:.4}, turned {got:.4}, map turned the wrong way {bad:.4}");
    assert!(got <= 1.5 * noise, "turned {got} vs noise {noise}");
    assert!(
        bad > 4.0 * noise,
        "the wrong turn {bad} is not detected (noise {noise})"
    );
}

/// A scene with an envmap emitter given by `emitter` (JSON), in a fresh folder holding `setup`'s
/// files; `render` must fail cleanly (exit 2, one line naming the field and the file, nothing
/// written).
#[track_caller]
fn assert_bad(name: &str, emitters: &str, setup: impl Fn(&Path), args: &[&str], expected: &[&str]) {
    let dir = workdir("envmap", name);
    setup(&dir);
    let inputs: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .chain(["scene.json".to_string()])
        .collect();
    std::fs::write(
        dir.join("scene.json"),
        objects(emitters, r#"{"type": "direct"}"#, 8),
    )
    .unwrap();
    let mut all = vec!["render", "scene.json", "--spp", "1"];
    all.extend_from_slice(args);
    let out = run(&dir, &all);
    for e in expected {
        assert_failure(&out, e);
    }
    let inputs: Vec<&str> = inputs.iter().map(String::as_str).collect();
    assert!(
        outputs(&dir, &inputs).is_empty(),
        "{name}: something was written"
    );
}

#[test]
fn bad_input_is_refused() {
    let good = |d: &Path| write_map(&d.join("sky.exr"), 4, 2, |_, _| [1.0, 1.0, 1.0]);
    assert_bad(
        "missing",
        r#"{"name": "env", "type": "envmap", "file": "nowhere.exr"}"#,
        |_| {},
        &[],
        &["emitters[0].file", "nowhere.exr", "not found"],
    );
    assert_bad(
        "not_rgb",
        r#"{"name": "env", "type": "envmap", "file": "grey.exr"}"#,
        |d| {
            implicit_psdr::io::write_exr(&d.join("grey.exr"), 2, 1, &[("Y".into(), vec![1.0, 2.0])])
                .unwrap()
        },
        &[],
        &["emitters[0].file", "grey.exr", "no channel R"],
    );
    assert_bad(
        "not_exr",
        r#"{"name": "env", "type": "envmap", "file": "sky.exr"}"#,
        |d| std::fs::write(d.join("sky.exr"), "not an image").unwrap(),
        &[],
        &["emitters[0].file", "sky.exr"],
    );
    assert_bad(
        "negative",
        r#"{"name": "env", "type": "envmap", "file": "neg.exr"}"#,
        |d| {
            write_map(&d.join("neg.exr"), 4, 2, |i, j| {
                [1.0, if (i, j) == (1, 2) { -0.5 } else { 1.0 }, 1.0]
            })
        },
        &[],
        &[
            "emitters[0].file",
            "neg.exr",
            "texel (row 1, column 2) channel G is -0.5",
        ],
    );
    assert_bad(
        "nan",
        r#"{"name": "env", "type": "envmap", "file": "nan.exr"}"#,
        |d| {
            write_map(&d.join("nan.exr"), 4, 2, |i, _| {
                [if i == 0 { f32::NAN } else { 1.0 }, 1.0, 1.0]
            })
        },
        &[],
        &["emitters[0].file", "nan.exr", "NaN"],
    );
    assert_bad(
        "scale",
        r#"{"name": "env", "type": "envmap", "file": "sky.exr", "scale": -1}"#,
        good,
        &[],
        &["emitters[0].scale", "must be >= 0"],
    );
    assert_bad(
        "set_scale",
        r#"{"name": "env", "type": "envmap", "file": "sky.exr"}"#,
        good,
        &["--set", "env.scale=nan"],
        &["env.scale"],
    );
    assert_bad(
        "both",
        r#"{"name": "sky", "type": "constant", "radiance": [1, 1, 1]},
           {"name": "env", "type": "envmap", "file": "sky.exr"}"#,
        good,
        &[],
        &[
            "emitters[1].type",
            "at most one environment emitter",
            "emitters[0]",
        ],
    );
    // And a good one renders, with the parameters named as documented.
    let dir = workdir("envmap", "good");
    good(&dir);
    std::fs::write(
        dir.join("scene.json"),
        objects(
            r#"{"name": "env", "type": "envmap", "file": "sky.exr", "rotate": {"axis": [0, 1, 0], "angle": 10}}"#,
            r#"{"type": "direct"}"#,
            8,
        ),
    )
    .unwrap();
    let params = assert_success(&run(&dir, &["params", "scene.json"]));
    assert!(
        params.contains("env.scale 1") && params.contains("env.rotate.angle 10"),
        "{params}"
    );
}

/// The radiance is continuous across the `u` seam and the density positive wherever the radiance is
/// (a black texel next to a bright one is still drawn where the interpolation reaches it).
#[test]
fn seam_is_continuous_and_support_is_covered() {
    let map = EnvMap::new(8, 4, (0..32).map(|k| hand_made(k / 8, k % 8)).collect()).unwrap();
    let e = envmap(map, 1.0, glam::Vec3::Y, 0.0);
    let (a, b) = (
        arriving(&e, EnvMap::direction(1.0 - 1e-5, 0.4)),
        arriving(&e, EnvMap::direction(1e-5, 0.4)),
    );
    assert!((a - b).abs().max_element() < 1e-2, "{a} vs {b}");
    let mut texels = vec![[0.0f32; 3]; 32];
    texels[8 + 3] = [5.0, 5.0, 5.0];
    let sparse = EnvMap::new(8, 4, texels).unwrap();
    let e = envmap(sparse.clone(), 1.0, glam::Vec3::Y, 0.0);
    for k in 0..2000 {
        let (u, v) = ((k % 50) as f32 / 50.0 + 0.01, (k / 50) as f32 / 40.0 + 0.01);
        let d = EnvMap::direction(u, v);
        if arriving(&e, d).max_element() > 0.0 {
            assert!(
                sparse.pdf(d) > 0.0,
                "radiance without density at u {u}, v {v}"
            );
        }
    }
    let _ = PI;
}
