//! Curves left out of the boundary terms (`integrator::boundary::motion`): with one shape of several
//! moving, the silhouettes seen from the camera of the fixed shapes it cannot be seen next to, and the
//! silhouettes seen from a point light of the fixed shapes whose shadow it cannot receive, add exactly
//! nothing, and are not extracted. Checked three ways: the left-out curves' own term is exactly zero
//! in every pixel (a fixed ball in front of the moving one, and a fixed ball casting its hard shadow on
//! it, are kept, and their terms are not zero); a camera parameter keeps every silhouette seen from the
//! camera (and none seen from the light, whose term does not depend on the camera); and the complete
//! derivatives of the moving ball, of the camera and of the point light against central finite
//! differences with common random numbers.
//!
//! The bounds come from two runs with independent seeds (`PSDR_TEST_SEED` unset and `=1`: estimator
//! and finite differences both reseeded), quoted next to each as `(seed 0, seed 1)`, with the finite
//! differences' own seed-to-seed difference and `h/2` against `h` (`PSDR_CHECK_H=1`).

mod common;

use common::deriv::*;
use implicit_psdr::integrator::boundary::delta_shadows::DeltaShadows;
use implicit_psdr::integrator::boundary::primary::Silhouettes;
use implicit_psdr::integrator::boundary::source::render_term;
use implicit_psdr::scene::Scene;

/// A ball `mover` on a floor plane, a fixed ball `front` partly in front of it, a fixed ball `caster`
/// between it and both lights (a rectangle light and a point light `bulb` just below it), a fixed
/// ball `shaded` in its shadow, and two fixed balls `far_left`, `far_right` seen apart from it;
/// `size × size` pixels, `direct`.
fn scene(size: u32) -> Scene {
    scene_json(&format!(
        r#"{{"camera": {{"origin": [0, 3.5, 4], "target": [0, 0.5, 0], "up": [0, 1, 0], "fov_y": 45,
                "width": {size}, "height": {size}, "filter": "tent"}},
            "integrator": {{"type": "direct"}}, "spp": 1,
            "shapes": [
              {{"name": "mover", "sdf": {{"type": "sphere", "center": [0, 0.7, 0], "radius": 0.6}},
               "bsdf": {{"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}}}},
              {{"name": "front", "sdf": {{"type": "sphere", "center": [0.35, 1.6, 1.4], "radius": 0.3}},
               "bsdf": {{"type": "diffuse", "albedo": [0.6, 0.7, 0.8]}}}},
              {{"name": "caster", "sdf": {{"type": "sphere", "center": [0.45, 2.3, 0.6], "radius": 0.2}},
               "bsdf": {{"type": "diffuse", "albedo": [0.8, 0.6, 0.6]}}}},
              {{"name": "shaded", "sdf": {{"type": "sphere", "center": [-0.9, 0.25, -0.9], "radius": 0.25}},
               "bsdf": {{"type": "diffuse", "albedo": [0.7, 0.8, 0.7]}}}},
              {{"name": "far_left", "sdf": {{"type": "sphere", "center": [-1.6, 0.4, -0.5], "radius": 0.3}},
               "bsdf": {{"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}}}},
              {{"name": "far_right", "sdf": {{"type": "sphere", "center": [1.5, 0.35, -1.2], "radius": 0.3}},
               "bsdf": {{"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}}}},
              {{"name": "floor", "sdf": {{"type": "plane", "normal": [0, 1, 0], "offset": 0}},
               "bsdf": {{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}}}],
            "emitters": [{{"name": "light", "type": "rectangle", "center": [1.5, 4.5, 2],
               "normal": [0, -1, 0], "u": [1, 0, 0], "size": [1, 1], "radiance": [25, 25, 25]}},
              {{"name": "bulb", "type": "point", "position": [1.4, 4.2, 1.9],
               "intensity": [12, 12, 12]}}]}}"#
    ))
}

/// The names of the shapes whose silhouettes `curves` holds.
fn names(scene: &Scene, curves: &Silhouettes) -> Vec<String> {
    (curves.0.iter())
        .map(|(i, _)| scene.shapes[*i].name.clone())
        .collect()
}

/// The names of the occluders whose silhouettes seen from a delta light `shadows` holds.
fn occluders(scene: &Scene, shadows: &DeltaShadows) -> Vec<String> {
    (shadows.pairs().iter())
        .map(|(_, m)| scene.shapes[*m].name.clone())
        .collect()
}

/// The index of the shape called `name`.
fn shape(scene: &Scene, name: &str) -> usize {
    scene.shapes.iter().position(|s| s.name == name).unwrap()
}

/// The silhouettes of `all` whose shape is `keep`.
fn only(all: &Silhouettes, keep: impl Fn(usize) -> bool) -> Silhouettes {
    Silhouettes(all.0.iter().filter(|(i, _)| keep(*i)).cloned().collect())
}

/// The number of non-zero values (any channel, any pixel) of `images`, per image.
fn nonzero(images: &[implicit_psdr::film::Image]) -> Vec<usize> {
    (images.iter())
        .map(|i| i.rgb.iter().filter(|v| **v != 0.0).count())
        .collect()
}

/// Σ|·| of every value of `image`.
fn mass(image: &implicit_psdr::film::Image) -> f64 {
    image.rgb.iter().map(|v| v.abs() as f64).sum()
}

const PARAMS: [&str; 3] = ["mover.radius", "mover.translate.x", "front.albedo.r"];

#[test]
fn left_out_silhouettes_add_exactly_zero() {
    let scene = scene(32);
    let selection = scene.select(&PARAMS).unwrap();
    let all = Silhouettes::unpruned(&scene).unwrap();
    let kept = Silhouettes::of(&selection.apply(&scene).unwrap()).unwrap();
    let (all_names, kept_names) = (names(&scene, &all), names(&scene, &kept));
    println!("every silhouette {all_names:?}, kept {kept_names:?}");
    assert_eq!(all_names.len(), 6, "every ball has a silhouette in view");
    // The moving ball, and the fixed ball seen over it; not the balls seen apart from it.
    for name in ["mover", "front"] {
        assert!(kept_names.iter().any(|n| n == name), "{name} not kept");
    }
    for name in ["far_left", "far_right"] {
        assert!(!kept_names.iter().any(|n| n == name), "{name} kept");
    }
    let kept_index: Vec<usize> = kept.0.iter().map(|(i, _)| *i).collect();
    let dropped = only(&all, |i| !kept_index.contains(&i));
    let options = diff_options(1, 7);
    // All the samples on the left-out curves: every pixel of every parameter exactly zero.
    let images = render_term(&scene, &selection, &options, 40_000, &dropped).unwrap();
    assert_eq!(
        nonzero(&images),
        [0, 0, 0],
        "left-out silhouettes, {PARAMS:?}"
    );
    // The fixed ball in front of the moving one is not zero: the moving ball slides behind its edge.
    let front = shape(&scene, "front");
    let front_only = only(&all, |i| i == front);
    let images = render_term(&scene, &selection, &options, 40_000, &front_only).unwrap();
    println!(
        "front's silhouette: Σ|·| {:?}",
        images.iter().map(mass).collect::<Vec<_>>()
    );
    assert!(
        mass(&images[0]) > 0.0 && mass(&images[1]) > 0.0,
        "front adds nothing"
    );
    // A material parameter moves nothing: no silhouette is kept.
    let material = scene.select(&["front.albedo.r"]).unwrap();
    let none = Silhouettes::of(&material.apply(&scene).unwrap()).unwrap();
    assert!(none.0.is_empty(), "kept {:?}", names(&scene, &none));
}

#[test]
fn left_out_delta_shadows_add_exactly_zero() {
    let scene = scene(32);
    let selection = scene.select(&PARAMS).unwrap();
    let all = DeltaShadows::unpruned(&scene);
    let kept = DeltaShadows::of(&selection.apply(&scene).unwrap());
    let (all_names, kept_names) = (occluders(&scene, &all), occluders(&scene, &kept));
    println!("every occluder seen from the bulb {all_names:?}, kept {kept_names:?}");
    assert_eq!(
        all_names.len(),
        6,
        "every ball has a silhouette seen from the bulb"
    );
    // The moving ball, and the fixed ball that shadows it; not the ball far from its shadow.
    for name in ["mover", "caster"] {
        assert!(kept_names.iter().any(|n| n == name), "{name} not kept");
    }
    assert!(
        !kept_names.iter().any(|n| n == "far_right"),
        "far_right kept"
    );
    let kept_pairs = kept.pairs();
    let dropped = all.only(|e, m| !kept_pairs.contains(&(e, m)));
    let options = diff_options(1, 9);
    let images = render_term(&scene, &selection, &options, 40_000, &dropped).unwrap();
    assert_eq!(nonzero(&images), [0, 0, 0], "left-out shadows, {PARAMS:?}");
    // The fixed ball between the bulb and the moving ball is not zero: its hard shadow slides over
    // the moving receiver.
    let caster = shape(&scene, "caster");
    let caster_only = all.only(|_, m| m == caster);
    let images = render_term(&scene, &selection, &options, 40_000, &caster_only).unwrap();
    println!(
        "caster's shadow: Σ|·| {:?}",
        images.iter().map(mass).collect::<Vec<_>>()
    );
    assert!(
        mass(&images[0]) > 0.0 && mass(&images[1]) > 0.0,
        "caster adds nothing"
    );
    // A material parameter moves no shadow.
    let material = scene.select(&["front.albedo.r"]).unwrap();
    let none = DeltaShadows::of(&material.apply(&scene).unwrap());
    assert!(none.is_empty(), "kept {:?}", occluders(&scene, &none));
}

#[test]
fn camera_and_light_parameters() {
    let scene = scene(32);
    let all = names(&scene, &Silhouettes::unpruned(&scene).unwrap());
    let every_pair = DeltaShadows::unpruned(&scene).pairs();
    for params in [
        &["camera.origin.x"][..],
        &["camera.fov_y", "mover.radius"][..],
    ] {
        let selected = scene.select(params).unwrap().apply(&scene).unwrap();
        let kept = Silhouettes::of(&selected).unwrap();
        assert_eq!(names(&scene, &kept), all, "{params:?}");
    }
    // The camera does not move the hard shadows' term (the camera's side is a detached estimate):
    // with only the camera selected no shadow is kept, and the left-out ones add exactly zero.
    let camera = scene.select(&["camera.origin.x"]).unwrap();
    let none = DeltaShadows::of(&camera.apply(&scene).unwrap());
    assert!(none.is_empty(), "kept {:?}", occluders(&scene, &none));
    let every = DeltaShadows::unpruned(&scene);
    let images = render_term(&scene, &camera, &diff_options(1, 5), 40_000, &every).unwrap();
    assert_eq!(nonzero(&images), [0], "the camera moved a hard shadow");
    // The point light moves every shadow it casts and no silhouette seen from the camera (no camera
    // ray meets it); the rectangle light is above the film, so no silhouette is seen next to it.
    for params in [&["bulb.position.x"][..], &["light.center.x"][..]] {
        let selected = scene.select(params).unwrap().apply(&scene).unwrap();
        let kept = Silhouettes::of(&selected).unwrap();
        assert!(
            kept.0.is_empty(),
            "{params:?}: kept {:?}",
            names(&scene, &kept)
        );
    }
    let bulb = scene.select(&["bulb.position.x"]).unwrap();
    assert_eq!(
        DeltaShadows::of(&bulb.apply(&scene).unwrap()).pairs(),
        every_pair
    );
}

fn budget() -> Budget {
    Budget {
        spp: 32,
        primary: 40_000,
        secondary: 120_000,
        fd_spp: 256,
    }
}

#[test]
fn one_moving_ball_among_fixed_ones_against_fd() {
    let scene = scene(32);
    let checks = [
        Check {
            name: "mover.radius",
            h: 0.01,
            // L2 (0.075, 0.110), sums ≤ 0.084; interior alone 0.56; FD noise 0.097, h/2 0.106.
            l2: 0.22,
            sum: 0.17,
        },
        Check {
            name: "mover.translate.x",
            h: 0.01,
            // L2 (0.064, 0.068), sums ≤ 0.075; interior alone 0.39; FD noise 0.081, h/2 0.046.
            l2: 0.14,
            sum: 0.15,
        },
    ];
    check_against_fd("one mover", &scene, &checks, budget(), 11);
}

#[test]
fn camera_and_bulb_among_fixed_balls_against_fd() {
    let scene = scene(32);
    let checks = [
        Check {
            name: "camera.origin.x",
            h: 0.01,
            // L2 (0.22, 0.15), sums ≤ 0.112; interior alone 0.72; FD noise 0.131, h/2 0.141 (the
            // finite differences' noise dominates).
            l2: 0.45,
            sum: 0.23,
        },
        Check {
            name: "bulb.position.x",
            h: 0.02,
            // L2 (0.119, 0.105), sums ≤ 0.054; interior alone 0.71; FD noise 0.183, h/2 0.084.
            l2: 0.24,
            sum: 0.11,
        },
    ];
    check_against_fd("camera and bulb", &scene, &checks, budget(), 13);
}
