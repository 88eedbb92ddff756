//! Silhouettes left out of the primary boundary term (`integrator::boundary::motion`): with one shape
//! of several moving, the silhouettes of the fixed shapes it cannot be seen next to add exactly
//! nothing, and are not extracted. Checked three ways: the left-out curves' own term is exactly zero
//! in every pixel (a fixed ball in front of the moving one is kept, and its term is not zero); with a
//! camera parameter selected nothing is left out; and the complete derivative of the moving ball
//! (silhouette over other shapes, shadows cast onto it by a fixed ball and by it onto the floor and
//! another ball) and of the camera against central finite differences with common random numbers.

mod common;

use common::deriv::*;
use implicit_psdr::integrator::boundary::primary::{Silhouettes, render_silhouettes};
use implicit_psdr::scene::Scene;

/// A ball `mover` on a floor plane, a fixed ball `front` partly in front of it, a fixed ball `caster`
/// between it and the light, a fixed ball `shaded` in its shadow, and two fixed balls `far_left`,
/// `far_right` seen apart from it; `size × size` pixels, `direct`.
fn scene(size: u32) -> Scene {
    scene_json(&format!(
        r#"{{"camera": {{"origin": [0, 3.5, 4], "target": [0, 0.5, 0], "up": [0, 1, 0], "fov_y": 45,
                "width": {size}, "height": {size}, "filter": "tent"}},
            "integrator": {{"type": "direct"}}, "spp": 1,
            "shapes": [
              {{"name": "mover", "sdf": {{"type": "sphere", "center": [0, 0.7, 0], "radius": 0.6}},
               "bsdf": {{"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}}}},
              {{"name": "front", "sdf": {{"type": "sphere", "center": [0.5, 1.0, 1.4], "radius": 0.3}},
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
               "normal": [0, -1, 0], "u": [1, 0, 0], "size": [1, 1], "radiance": [40, 40, 40]}}]}}"#
    ))
}

/// The names of the shapes whose silhouettes `curves` holds.
fn names(scene: &Scene, curves: &Silhouettes) -> Vec<String> {
    curves
        .0
        .iter()
        .map(|(i, _)| scene.shapes[*i].name.clone())
        .collect()
}

/// The silhouettes of `all` whose shape is `keep`.
fn only(all: &Silhouettes, keep: impl Fn(usize) -> bool) -> Silhouettes {
    Silhouettes(all.0.iter().filter(|(i, _)| keep(*i)).cloned().collect())
}

#[test]
fn left_out_silhouettes_add_exactly_zero() {
    let scene = scene(32);
    let params = ["mover.radius", "mover.translate.x", "front.albedo.r"];
    let selection = scene.select(&params).unwrap();
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
    let images = render_silhouettes(&scene, &selection, &options, 40_000, &dropped).unwrap();
    for (name, image) in params.iter().zip(&images) {
        let nonzero = image.rgb.iter().filter(|v| **v != 0.0).count();
        assert_eq!(nonzero, 0, "{name}: left-out silhouettes gave {nonzero} non-zero values");
    }
    // The fixed ball in front of the moving one is not zero: the moving ball slides behind its edge.
    let front = scene.shapes.iter().position(|s| s.name == "front").unwrap();
    let images = render_silhouettes(&scene, &selection, &options, 40_000, &only(&all, |i| i == front))
        .unwrap();
    let mass: f64 = images[1].rgb.iter().map(|v| v.abs() as f64).sum();
    println!("front's silhouette, mover.translate.x: Σ|·| = {mass}");
    assert!(mass > 0.0, "the silhouette of the ball in front of the moving one adds nothing");
    // A material parameter moves nothing: no silhouette is kept.
    let material = scene.select(&["front.albedo.r"]).unwrap();
    let none = Silhouettes::of(&material.apply(&scene).unwrap()).unwrap();
    assert!(none.0.is_empty(), "kept {:?}", names(&scene, &none));
}

#[test]
fn camera_parameters_keep_every_silhouette() {
    let scene = scene(32);
    let all = names(&scene, &Silhouettes::unpruned(&scene).unwrap());
    for params in [&["camera.origin.x"][..], &["camera.fov_y", "mover.radius"][..]] {
        let selection = scene.select(params).unwrap();
        let kept = Silhouettes::of(&selection.apply(&scene).unwrap()).unwrap();
        assert_eq!(names(&scene, &kept), all, "{params:?}");
    }
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
            l2: 0.35,
            sum: 0.3,
        },
        Check {
            name: "mover.translate.x",
            h: 0.01,
            l2: 0.35,
            sum: 0.3,
        },
    ];
    check_against_fd("one mover", &scene, &checks, budget(), 11);
}

#[test]
fn camera_among_many_balls_against_fd() {
    let scene = scene(32);
    let checks = [Check {
        name: "camera.origin.x",
        h: 0.01,
        l2: 0.35,
        sum: 0.3,
    }];
    check_against_fd("camera", &scene, &checks, budget(), 13);
}
