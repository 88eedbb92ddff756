//! Next-event estimation's choice of emitters: a constant sky is left to the BSDF's samples (with
//! weight 1), which makes a convex diffuse shape under it noiseless, and the light samples of the
//! other emitters are chosen among them alone, so that the emitters' images still add up.

use implicit_psdr::integrator::{RenderOptions, render};
use implicit_psdr::scene::parse;
use std::path::Path;

fn options(spp: u32, seed: u64) -> RenderOptions {
    RenderOptions {
        spp,
        seed,
        progress: Default::default(),
    }
}

/// A scene of `shapes` and `emitters` (JSON arrays' contents) seen by a 32×32 camera, `integrator`.
fn scene(shapes: &str, emitters: &str, integrator: &str) -> String {
    format!(
        r#"{{"camera": {{"origin": [0, 1.5, 4], "target": [0, 0.3, 0], "up": [0, 1, 0], "fov_y": 40,
              "width": 32, "height": 32, "filter": "tent"}},
            "integrator": {integrator},
            "shapes": [{shapes}],
            "emitters": [{emitters}]}}"#
    )
}

const BALL: &str = r#"{"name": "ball", "sdf": {"type": "sphere", "center": [0, 0.3, 0], "radius": 0.8},
                       "bsdf": {"type": "diffuse", "albedo": [0.8, 0.6, 0.4]}}"#;

/// Under radiance `L` from every direction a convex diffuse shape reflects exactly `albedo · L`
/// towards every direction, and a BSDF sample (cosine-distributed) estimates it with no variance: at
/// 1 spp every pixel is either the sky or the ball, to rounding. Light samples of the sky (uniform
/// over the sphere), weighted against the BSDF's, would scatter the ball's pixels around it.
#[test]
fn a_convex_diffuse_shape_under_a_constant_sky_has_no_noise() {
    let sky = [0.9f32, 0.7, 0.5];
    let ball = [0.8 * sky[0], 0.6 * sky[1], 0.4 * sky[2]];
    let emitter = format!(r#"{{"name": "sky", "type": "constant", "radiance": {sky:?}}}"#);
    for integrator in [
        r#"{"type": "direct"}"#,
        r#"{"type": "path", "max_depth": 3}"#,
    ] {
        let s = parse(&scene(BALL, &emitter, integrator), Path::new(".")).unwrap();
        let image = render(&s, &options(1, 3)).0;
        let (mut skies, mut balls) = (0, 0);
        for (k, px) in image.rgb.chunks(3).enumerate() {
            let near = |want: [f32; 3]| (0..3).all(|c| (px[c] - want[c]).abs() <= 1e-5 * want[c]);
            if near(sky) {
                skies += 1;
            } else if near(ball) {
                balls += 1;
            } else {
                panic!(
                    "{integrator}: pixel {k} is {px:?}, neither the sky {sky:?} nor the ball {ball:?}"
                );
            }
        }
        assert!(
            skies > 100 && balls > 100,
            "{integrator}: {skies} sky, {balls} ball pixels"
        );
    }
}

/// Light is additive: the image under a sphere light and a constant sky together is the sum of the
/// images under each alone (in expectation; the sums of whole images at 256 spp, within their noise).
/// The light sample picks among the emitters it samples (here only the sphere light), so a choice
/// that still counted the sky would halve the sphere light's share and fail this by far.
#[test]
fn the_images_of_a_sky_and_a_light_add_up() {
    let shapes = format!(
        r#"{BALL}, {{"name": "floor", "sdf": {{"type": "box", "center": [0, -0.7, 0], "half_size": [3, 0.2, 3]}},
                    "bsdf": {{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}}}"#
    );
    let sky = r#"{"name": "sky", "type": "constant", "radiance": [0.4, 0.4, 0.4]}"#;
    let lamp = r#"{"name": "lamp", "type": "sphere", "center": [1.5, 3, 2], "radius": 0.3, "radiance": [30, 30, 30]}"#;
    for integrator in [
        r#"{"type": "direct"}"#,
        r#"{"type": "path", "max_depth": 3}"#,
    ] {
        let total = |emitters: &str, seed: u64| -> f64 {
            let s = parse(&scene(&shapes, emitters, integrator), Path::new(".")).unwrap();
            render(&s, &options(256, seed))
                .0
                .rgb
                .iter()
                .map(|&v| v as f64)
                .sum()
        };
        let both = total(&format!("{sky}, {lamp}"), 1);
        let apart = total(sky, 2) + total(lamp, 3);
        let error = (both - apart).abs() / apart;
        println!("{integrator}: both {both:.1}, apart {apart:.1}, relative difference {error:.2e}");
        assert!(error < 0.01, "{integrator}: {both} against {apart}");
    }
}
