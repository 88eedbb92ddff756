//! Whole-scene transformations and extreme cameras whose answers follow from physics, not from a
//! reference renderer: the contact shadow under a ball does not depend on how wide the floor under it
//! is; scaling or rotating a whole scene changes nothing in its image (radiance is per unit area and
//! solid angle), and scaling divides a length's derivative by the scale; a closed room lit from outside
//! is black inside; at 0.01° and at 170° a silhouette's derivative matches finite differences and the
//! closed form of the edge's motion.
//!
//! Monte Carlo bounds quote two runs, `PSDR_TEST_SEED` unset and `=1` (every seed offset), as
//! `(seed 0, seed 1)`; unless said otherwise a bound is about twice the larger.

mod common;

use common::deriv::{
    assert_finite, blurred_rel_l2, diff_options, gray, json_point, rel_l2, scene_json, seed,
};
use implicit_psdr::integrator::fd::render_with_difference;
use implicit_psdr::integrator::{RenderOptions, render, render_derivatives_with_boundary};
use implicit_psdr::scene::Scene;

/// The value straight below a ball of radius `r` whose centre is `D` above a floor of albedo `a` under a
/// constant sky of radiance 1: the ball hides a cap of half-angle `asin(r/D)` around the zenith, whose
/// cosine-weighted share of the hemisphere is `(r/D)²`, so `a (1 − (r/D)²)`.
fn contact_shadow(albedo: f32, r: f32, d: f32) -> f32 {
    albedo * (1.0 - (r / d) * (r / d))
}

/// The floor under the ball: a box slab of the given half width with its top at `y = 0`, or the plane
/// `y = 0`.
#[derive(Copy, Clone, Debug)]
enum Floor {
    Slab(f32),
    Plane,
}

/// The mean of the centre 2×2 pixels of a 4×4 image looking, at a narrow field of view from under the
/// ball, at the floor point below the ball's centre, and the count of rays that ran out of steps.
/// Everything is moved by `offset`.
fn floor_point_value(floor: Floor, offset: [f32; 3], spp: u32) -> (f32, u64) {
    let at = |p: [f32; 3]| json_point(p, offset);
    let scene = scene_json(&format!(
        r#"{{"camera": {{"origin": {eye}, "target": {look}, "up": [0, 1, 0], "fov_y": 0.2,
              "width": 4, "height": 4, "filter": "box"}},
            "integrator": {{"type": "direct"}},
            "shapes": [
              {{"name": "ball", "sdf": {{"type": "sphere", "center": {ball}, "radius": 1}},
               "bsdf": {{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}}},
              {{"name": "floor", "sdf": {floor},
               "bsdf": {{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}}}],
            "emitters": [{{"name": "sky", "type": "constant", "radiance": [1, 1, 1]}}]}}"#,
        eye = at([0.0, 0.3, 4.0]),
        look = at([0.0; 3]),
        ball = at([0.0, 1.5, 0.0]),
        floor = match floor {
            Floor::Slab(w) => format!(
                r#"{{"type": "box", "center": {}, "half_size": [{w}, 0.5, {w}]}}"#,
                at([0.0, -0.5, 0.0])
            ),
            Floor::Plane => format!(
                r#"{{"type": "plane", "normal": [0, 1, 0], "offset": {}}}"#,
                offset[1]
            ),
        },
    ));
    let options = RenderOptions {
        spp,
        seed: 7,
        ..RenderOptions::default()
    };
    let (image, stats) = render(&scene, &options);
    let mut sum = 0.0;
    for (x, y) in [(1, 1), (2, 1), (1, 2), (2, 2)] {
        let i = 3 * (y * 4 + x);
        sum += image.rgb[i];
    }
    (sum / 4.0, stats.exhausted_rays)
}

/// The contact shadow under a unit ball 0.5 above a floor does not depend on the floor's width (5 to
/// 100,000 units, and an unbounded `plane`): the same value at the same seed, the closed form within the
/// noise, no ray out of steps.
#[test]
fn contact_shadow_does_not_depend_on_the_floor_size() {
    let want = contact_shadow(0.5, 1.0, 1.5);
    let (small, exhausted) = floor_point_value(Floor::Slab(2.5), [0.0; 3], 4096);
    assert_eq!(
        exhausted, 0,
        "floor 5 wide: {exhausted} rays ran out of steps"
    );
    // 4 pixels × 4096 samples of values in [0, 1]: a standard error below 0.002; 2% is 3 of them.
    assert!(
        (small - want).abs() < 0.02 * want,
        "floor 5 wide: {small} vs {want}"
    );
    for floor in [
        Floor::Slab(50.0),
        Floor::Slab(5e3),
        Floor::Slab(5e4),
        Floor::Plane,
    ] {
        let (got, exhausted) = floor_point_value(floor, [0.0; 3], 4096);
        assert_eq!(exhausted, 0, "{floor:?}: {exhausted} rays ran out of steps");
        // Same seed, same geometry near the point: the same value up to rounding.
        assert!(
            (got - small).abs() < 1e-3,
            "{floor:?}: {got} vs {small} (5 wide)"
        );
    }
}

/// The same contact shadow with the whole scene moved up to 10⁴ units from the origin degrades only
/// with the float resolution there: rays leaving the floor start four local tolerances, `4·16 ε m` at
/// coordinates of magnitude `m`, above it, where the ball hides a larger cap, `a ((r/(D − h))² −
/// (r/D)²)` more. Measured (same seed as the untranslated scene): −0.1%, −0.8% and −8.8% at 10², 10³
/// and 10⁴, which that formula predicts; the bound is 1.5 times it plus the noise of 1024 samples.
#[test]
fn contact_shadow_far_from_the_origin_degrades_with_the_float_resolution() {
    let (a, r, d) = (0.5f32, 1.0f32, 1.5f32);
    let (at_origin, _) = floor_point_value(Floor::Slab(2.0), [0.0; 3], 1024);
    for offset in [1e2f32, 1e3, 1e4] {
        let (got, exhausted) = floor_point_value(
            Floor::Slab(2.0),
            [offset, -0.7 * offset, 0.3 * offset],
            1024,
        );
        assert_eq!(
            exhausted, 0,
            "offset {offset}: {exhausted} rays ran out of steps"
        );
        let h = 4.0 * implicit_psdr::trace::TOLERANCE_ULPS * f32::EPSILON * offset;
        let predicted = a * ((r / (d - h)).powi(2) - (r / d).powi(2));
        assert!(
            (at_origin - got).abs() <= 1.5 * predicted + 0.004,
            "offset {offset}: {got} vs {at_origin} at the origin (predicted loss {predicted})"
        );
    }
}

/// A mean of absolute differences relative to the reference's: `Σ|a − b| / Σ|b|`.
fn rel_mad(a: &[f64], b: &[f64]) -> f64 {
    let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum();
    let den: f64 = b.iter().map(|y| y.abs()).sum();
    num / den.max(1e-30)
}

/// A ball on a slab under a tilted rectangle light and a dim sky, 16×16 pixels, every position and
/// length times `s` (radiances unchanged), then every position moved by `offset`; the slab's edges
/// rounded by `rounding` (before scaling).
fn ball_on_a_slab(s: f32, rounding: f32, offset: [f32; 3]) -> Scene {
    // `[x, y, z]` times `s`, moved by `offset`, as scene JSON.
    let scaled = |p: [f32; 3], s: f32| {
        format!(
            "[{}, {}, {}]",
            p[0] * s + offset[0],
            p[1] * s + offset[1],
            p[2] * s + offset[2]
        )
    };
    // A size, not a position: not moved.
    let half = format!("[{}, {}, {}]", 1.6 * s, 0.1 * s, 1.6 * s);
    scene_json(&format!(
        r#"{{"camera": {{"origin": {eye}, "target": {look}, "up": [0, 1, 0], "fov_y": 35,
              "width": 16, "height": 16, "filter": "tent"}},
            "integrator": {{"type": "direct"}},
            "shapes": [
              {{"name": "ball", "sdf": {{"type": "sphere", "center": {ball}, "radius": {radius}}},
               "bsdf": {{"type": "diffuse", "albedo": [0.7, 0.7, 0.7]}}}},
              {{"name": "slab", "sdf": {{"type": "box", "center": {slab}, "half_size": {half},
                 "rounding": {rounding}}}, "bsdf": {{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}}}],
            "emitters": [
              {{"name": "light", "type": "rectangle", "center": {light}, "normal": [-0.3, -1, -0.2],
               "u": [1, 0, 0], "size": [{w}, {h}], "radiance": [20, 20, 20]}},
              {{"name": "sky", "type": "constant", "radiance": [0.3, 0.3, 0.3]}}]}}"#,
        eye = scaled([0.3, 1.6, 3.2], s),
        look = scaled([0.0, 0.35, 0.0], s),
        ball = scaled([0.1, 0.55, 0.0], s),
        radius = 0.5 * s,
        slab = scaled([0.0, -0.1, 0.0], s),
        rounding = rounding * s,
        light = scaled([1.2, 3.0, 0.8], s),
        w = 0.8 * s,
        h = 0.6 * s,
    ))
}

/// The lengths whose derivatives [`at_scale`] takes: one of a shape, one of an emitter.
const LENGTHS: [&str; 2] = ["ball.radius", "light.center.x"];

/// One scale's grey image, the complete derivatives (interior, primary and secondary terms) of
/// [`LENGTHS`] times `s` (which undoes their `1/s`), and the rays that ran out of steps in all
/// passes.
fn at_scale(s: f32, rounding: f32, seed: u64) -> (Vec<f64>, Vec<Vec<f64>>, u64) {
    at_scale_and_offset(s, rounding, [0.0; 3], seed)
}

/// [`at_scale`] with the whole scene moved by `offset`.
fn at_scale_and_offset(
    s: f32,
    rounding: f32,
    offset: [f32; 3],
    seed: u64,
) -> (Vec<f64>, Vec<Vec<f64>>, u64) {
    let scene = ball_on_a_slab(s, rounding, offset);
    let lengths = scene.select(&LENGTHS).unwrap();
    // The image of a derivative pass is the primal render's at the same seed and spp.
    let out =
        render_derivatives_with_boundary(&scene, &lengths, &diff_options(64, seed), 20_000, 80_000)
            .unwrap();
    assert_finite(&out, &format!("scale {s}"));
    let derivatives = out
        .total()
        .iter()
        .map(|d| gray(d).iter().map(|v| v * s as f64).collect())
        .collect();
    (gray(&out.image), derivatives, out.stats.exhausted_rays)
}

/// Scaling a whole scene by `s` (camera, shapes, light; radiance is per unit area and solid angle,
/// so unchanged) leaves its image unchanged, and `s · ∂I/∂ℓ` of a length `ℓ` too, at the same seed:
/// the same samples see the same points, only rounded differently, since every tracing tolerance is
/// relative to the shapes' sizes and the coordinates' magnitude. The slab has sharp edges (rounded
/// ones: [`tangent_lines_along_a_rounded_edge_do_not_run_out_of_steps`]).
///
/// Measured against `s = 1` at the same seed, for `s` = 10⁻³, 10⁻², 10², 10³: image mean abs
/// difference (3.7e-8 to 7.3e-8, 3.0e-8 to 6.4e-8) of the mean; relative L2 of
/// `s · ∂I/∂ball.radius` (8.6e-6 to 1.6e-5, 1.3e-6 to 7.1e-6), of `s · ∂I/∂light.center.x`
/// (2.5e-7 to 5.7e-7, 2.5e-7 to 5.9e-7); no ray out of steps in any pass. That is rounding: two
/// seeds at scale 1 differ by (5.2%, 5.0%) in the image and (0.35, 0.43) and (0.20, 0.18) in the derivatives. A
/// sample may still change sides of an edge by rounding alone (none did); the bounds allow a
/// handful (one camera sample moves a pixel by about 1.5e-4 of the image) and stay 50 times (image)
/// and 18 times (derivatives) below the seed-to-seed noise, the least a tolerance tied to absolute
/// lengths would cause at these scales.
#[test]
fn scaling_the_whole_scene_changes_neither_the_image_nor_the_scaled_derivatives() {
    let (image, derivatives, exhausted) = at_scale(1.0, 0.0, seed(31));
    assert_eq!(exhausted, 0, "s = 1: {exhausted} rays ran out of steps");
    let (other, other_derivatives, _) = at_scale(1.0, 0.0, seed(32));
    println!(
        "s = 1, another seed: image {:.2e}, derivatives {:.3} {:.3}",
        rel_mad(&other, &image),
        rel_l2(&other_derivatives[0], &derivatives[0], None),
        rel_l2(&other_derivatives[1], &derivatives[1], None)
    );
    for s in [1e-3f32, 1e-2, 1e2, 1e3] {
        let (got, got_derivatives, exhausted) = at_scale(s, 0.0, seed(31));
        assert_eq!(exhausted, 0, "s = {s}: {exhausted} rays ran out of steps");
        let e = rel_mad(&got, &image);
        println!("s = {s:e}: image {e:.2e}");
        assert!(e <= 1e-3, "s = {s}: image differs by {e} of the mean");
        for (k, name) in LENGTHS.iter().enumerate() {
            let e = rel_l2(&got_derivatives[k], &derivatives[k], None);
            println!("  s · d/d {name}: rel L2 {e:.2e}");
            assert!(e <= 1e-2, "s = {s}: s · d/d {name} differs by {e} (rel L2)");
        }
    }
}

/// Moving a whole scene (the ball on a slab of
/// [`scaling_the_whole_scene_changes_neither_the_image_nor_the_scaled_derivatives`], rounded edges)
/// by 10², 10³ and 10⁴ units along (1, −0.7, 0.3) changes its image and derivatives only as the
/// float resolution there allows: coordinates of magnitude `m` are rounded to `ε m` (1.2e-5, 1.2e-4
/// and 1.2e-3 of a scene about 3 units across), which moves the samples' hits, the tolerances
/// (`16 ε m`) and the rays' offsets (`64 ε m`) with it.
///
/// Measured against the unmoved scene at the same seed (seeds 0 and 1), at 10², 10³, 10⁴: image mean
/// abs difference (1.2e-4, 1.4e-4), (1.5e-3, 1.1e-3), (1.0e-2, 1.0e-2) of the mean; blurred relative
/// L2 of `∂I/∂ball.radius` (1.8e-3, 1.3e-3), (2.4e-2, 2.7e-2), (0.16, 0.14), of
/// `∂I/∂light.center.x` (7.9e-4, 6.8e-4), (1.2e-2, 8.0e-3), (8.4e-2, 6.8e-2): about ten times more
/// per decade, as the resolution. Two seeds at the origin differ by 5% in the image. No ray out of
/// steps. Bounds: twice the larger, per offset (image, radius; the light's below the radius's).
#[test]
fn translating_the_whole_scene_degrades_with_the_float_resolution() {
    translated_scene_degrades(
        0.02,
        seed(33),
        &[
            (1e2, 2.8e-4, 3.6e-3),
            (1e3, 3.0e-3, 5.4e-2),
            (1e4, 2.1e-2, 0.32),
        ],
    );
}

/// The ball on a slab (edges rounded by `rounding`) moved by `m` units along (1, −0.7, 0.3) for each
/// `(m, image bound, derivative bound)` of `offsets`, against the unmoved scene at `seed`: no ray out
/// of steps, the image's mean abs difference and the derivatives' blurred relative L2 within the
/// bounds.
fn translated_scene_degrades(rounding: f32, seed: u64, offsets: &[(f32, f64, f64)]) {
    let (image, derivatives, _) = at_scale_and_offset(1.0, rounding, [0.0; 3], seed);
    for &(m, image_bound, derivative_bound) in offsets {
        let offset = [m, -0.7 * m, 0.3 * m];
        let (got, got_derivatives, exhausted) = at_scale_and_offset(1.0, rounding, offset, seed);
        assert_eq!(
            exhausted, 0,
            "offset {m}: {exhausted} rays ran out of steps"
        );
        let e = rel_mad(&got, &image);
        println!("offset {m:e}: image {e:.2e}");
        assert!(
            e <= image_bound,
            "offset {m}: image differs by {e} of the mean"
        );
        for (k, name) in LENGTHS.iter().enumerate() {
            let e = blurred_rel_l2(&got_derivatives[k], &derivatives[k], 16, 16, None);
            println!("  d/d {name}: blurred rel L2 {e:.2e}");
            assert!(
                e <= derivative_bound,
                "offset {m}: d/d {name} differs by {e} (blurred rel L2)"
            );
        }
    }
}

/// The derivative pass of
/// [`scaling_the_whole_scene_changes_neither_the_image_nor_the_scaled_derivatives`] with the slab's
/// edges rounded by 0.02 runs no ray out of steps. The shadow term's tangent lines on the rounded
/// edges, those nearly along an edge, start a few tolerances off the surface and stay that close to
/// it for much of the edge's length. Before the tracer crept at up to 64 tolerances per step within
/// 64 tolerances of a surface (it stepped by `φ/L`, a few tolerances, there) and sized its budget by
/// the interval's length, (65, 49) of 80,000 boundary samples ran out of steps, the same at every
/// scale: 313 of 18,158 lines tangent to the slab at uniform angles (1.7%), all nearly along an
/// edge. Measured now: none.
#[test]
fn tangent_lines_along_a_rounded_edge_do_not_run_out_of_steps() {
    let (_, _, exhausted) = at_scale(1.0, 0.02, seed(31));
    assert_eq!(exhausted, 0, "{exhausted} rays ran out of steps");
}

/// A ball (and, with `cube`, a rounded cube) on a slab under a tilted rectangle light and a dim
/// sky, 16×16 pixels, the whole scene rotated by `angle` degrees about the axis (1, 2, 3): points
/// and directions of the camera, sphere and light turned by the rotation, the boxes wrapped in
/// `transform` nodes (none at 0°).
fn turned_scene(angle: f32, integrator: &str, cube: bool) -> Scene {
    let q = glam::Quat::from_axis_angle(
        glam::Vec3::new(1.0, 2.0, 3.0).normalize(),
        angle.to_radians(),
    );
    let turn = |p: [f32; 3]| {
        let v = q * glam::Vec3::from(p);
        format!("[{}, {}, {}]", v.x, v.y, v.z)
    };
    let turned = |node: &str| {
        if angle == 0.0 {
            node.to_string()
        } else {
            format!(
                r#"{{"type": "transform", "rotate": {{"axis": [1, 2, 3], "angle": {angle}}}, "child": {node}}}"#
            )
        }
    };
    scene_json(&format!(
        r#"{{"camera": {{"origin": {eye}, "target": {look}, "up": {up}, "fov_y": 40,
              "width": 16, "height": 16, "filter": "tent"}},
            "integrator": {{"type": "{integrator}"}},
            "shapes": [
              {{"name": "ball", "sdf": {{"type": "sphere", "center": {ball}, "radius": 0.5}},
               "bsdf": {{"type": "diffuse", "albedo": [0.7, 0.7, 0.7]}}}},
              {cube}
              {{"name": "slab", "sdf": {slab}, "bsdf": {{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}}}],
            "emitters": [
              {{"name": "light", "type": "rectangle", "center": {light}, "normal": {normal}, "u": {u},
               "size": [0.8, 0.6], "radiance": [20, 20, 20]}},
              {{"name": "sky", "type": "constant", "radiance": [0.3, 0.3, 0.3]}}]}}"#,
        eye = turn([0.3, 1.8, 3.4]),
        look = turn([-0.2, 0.35, 0.0]),
        up = turn([0.0, 1.0, 0.0]),
        ball = turn([0.1, 0.55, 0.0]),
        cube = if cube {
            format!(
                r#"{{"name": "cube", "sdf": {}, "bsdf": {{"type": "diffuse", "albedo": [0.6, 0.6, 0.6]}}}},"#,
                turned(
                    r#"{"type": "box", "center": [-0.8, 0.25, 0.4], "half_size": [0.25, 0.25, 0.25], "rounding": 0.05}"#
                )
            )
        } else {
            String::new()
        },
        slab = turned(r#"{"type": "box", "center": [0, -0.1, 0], "half_size": [1.6, 0.1, 1.6]}"#),
        light = turn([1.2, 3.0, 0.8]),
        normal = turn([-0.3, -1.0, -0.2]),
        u = turn([1.0, 0.0, 0.0]),
    ))
}

/// The grey image of `scene` and its rays out of steps.
fn image_of(scene: &Scene, spp: u32, seed: u64) -> (Vec<f64>, u64) {
    let (image, stats) = render(
        scene,
        &RenderOptions {
            spp,
            seed,
            ..RenderOptions::default()
        },
    );
    (gray(&image), stats.exhausted_rays)
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// The standard deviation of the difference of two images' means, from two independent renders `a`
/// and `b` of one scene: `√Σ(a − b)² / N`.
fn sigma_of_mean_difference(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt()
        / a.len() as f64
}

/// Rotating a whole scene (37° about (1, 2, 3); a slab and a rounded cube turned by `transform`
/// nodes, the sphere's centre, the light's centre, normal and `u`, the camera's eye, target and up
/// turned with them) leaves its image unchanged within the noise, with `direct` and `path`, and the
/// complete derivative of a ball's radius (a rotation-invariant parameter) too. At one seed the
/// camera samples and the rectangle light's are shared; the sky's (uniform over world directions)
/// and the BSDF's (in a frame built from the normal's coordinates) are not, so a rotated image
/// differs from the unrotated one by part of the noise.
///
/// Measured (16×16, 1024 spp, 24 seeds): mean abs difference to the unrotated image at the same
/// seed, as a share of the one between two seeds, `direct` 0.69–0.92, `path` 0.61–0.92 (bound 1:
/// no more than an independent seed's; the camera's film positions, stratified, carry little of
/// the noise, the unshared sky and BSDF samples most of it); the image means differ by at most 2.3
/// standard deviations of a difference of means (bound 3). The derivative (64 spp, 40,000 + 160,000
/// boundary samples, the rounded cube's edges among the shadow term's tangent lines): blurred
/// relative L2 to the unrotated one summed over four seeds, as a share of the seed-to-seed one
/// summed over four pairs, 0.24–0.42 (bound 0.7). No ray out of steps.
#[test]
fn rotating_the_whole_scene_changes_the_image_only_within_the_noise() {
    for integrator in ["direct", "path"] {
        let spp = 1024;
        let plain = turned_scene(0.0, integrator, true);
        let turned = turned_scene(37.0, integrator, true);
        let (a, ea) = image_of(&plain, spp, seed(41));
        let (b, eb) = image_of(&plain, spp, seed(42));
        let (r, er) = image_of(&turned, spp, seed(41));
        assert_eq!(
            (ea, eb, er),
            (0, 0, 0),
            "{integrator}: rays ran out of steps"
        );
        let noise = rel_mad(&b, &a);
        let turned_diff = rel_mad(&r, &a);
        let sigma = sigma_of_mean_difference(&a, &b);
        let mean_diff = mean(&r) - mean(&a);
        println!(
            "{integrator}: mean abs difference {turned_diff:.4} (seed to seed {noise:.4}, ratio {:.2}); \
             difference of means {mean_diff:.2e} = {:.2} σ",
            turned_diff / noise,
            mean_diff / sigma
        );
        assert!(
            turned_diff <= noise,
            "{integrator}: rotated image differs by {turned_diff} (seed to seed {noise})"
        );
        assert!(
            mean_diff.abs() <= 3.0 * sigma,
            "{integrator}: image means differ by {mean_diff} (σ {sigma})"
        );
    }
    let derivative = |angle: f32, seed: u64| {
        let scene = turned_scene(angle, "direct", true);
        let radius = scene.select(&["ball.radius"]).unwrap();
        let out = render_derivatives_with_boundary(
            &scene,
            &radius,
            &diff_options(64, seed),
            40_000,
            160_000,
        )
        .unwrap();
        assert_finite(&out, &format!("{angle}°"));
        assert_eq!(
            out.stats.exhausted_rays, 0,
            "{angle}°: rays ran out of steps"
        );
        gray(&out.total()[0])
    };
    // Sums over four seeds: one seed's ratio scatters too widely for a bound (0.16 to 0.79 over 24).
    let (mut noise, mut turned_diff) = (0.0, 0.0);
    for base in [41, 43, 45, 47] {
        let a = derivative(0.0, seed(base));
        let b = derivative(0.0, seed(base + 1));
        let r = derivative(37.0, seed(base));
        noise += blurred_rel_l2(&b, &a, 16, 16, None);
        turned_diff += blurred_rel_l2(&r, &a, 16, 16, None);
    }
    println!(
        "d/d ball.radius: blurred rel L2 {turned_diff:.4} (seed to seed {noise:.4}; sums over four \
         seeds), ratio {:.2}",
        turned_diff / noise
    );
    assert!(
        turned_diff <= 0.7 * noise,
        "d/d ball.radius rotated differs by {turned_diff} (seed to seed {noise})"
    );
}

/// A room (`room`: an sdf node around the origin, at least 1.6 from it in every direction) with a
/// ball inside, lit only from outside: a rectangle light 4.5 above the origin facing down and a
/// white sky. 16×16 pixels at 90°, the camera at `eye` looking at `look`.
fn room_scene(room: &str, integrator: &str, eye: [f32; 3], look: [f32; 3]) -> Scene {
    scene_json(&format!(
        r#"{{"camera": {{"origin": {eye:?}, "target": {look:?}, "up": [0, 1, 0], "fov_y": 90,
              "width": 16, "height": 16, "filter": "tent"}},
            "integrator": {integrator},
            "shapes": [
              {{"name": "room", "sdf": {room}, "bsdf": {{"type": "diffuse", "albedo": [0.9, 0.9, 0.9]}}}},
              {{"name": "ball", "sdf": {{"type": "sphere", "center": [0.5, -0.6, -0.5], "radius": 0.4}},
               "bsdf": {{"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}}}}],
            "emitters": [
              {{"name": "light", "type": "rectangle", "center": [0.3, 4.5, 0.2], "normal": [0, -1, 0],
               "u": [1, 0, 0], "size": [1, 1], "radiance": [50, 50, 50]}},
              {{"name": "sky", "type": "constant", "radiance": [1, 1, 1]}}]}}"#
    ))
}

const DIRECT: &str = r#"{"type": "direct"}"#;
const PATH: &str = r#"{"type": "path", "max_depth": 8}"#;

/// Renders `room` from inside at 256 spp (seed 1) and returns the count of non-zero channel values,
/// the largest, and the rays out of steps; checks that the same room seen from outside is lit (so
/// black inside is not the scene's fault).
fn inside_the_room(room: &str, integrator: &str) -> (usize, f32, u64) {
    let outside = room_scene(room, integrator, [0.3, 4.0, 7.0], [0.0; 3]);
    let (image, _) = render(
        &outside,
        &RenderOptions {
            spp: 4,
            seed: 1,
            ..RenderOptions::default()
        },
    );
    assert!(
        image.rgb.iter().all(|v| *v > 0.0),
        "{room}: the room seen from outside has black pixels"
    );
    let inside = room_scene(room, integrator, [0.3, 0.2, 1.2], [-0.5, -0.3, -1.0]);
    let (image, stats) = render(
        &inside,
        &RenderOptions {
            spp: 256,
            seed: 1,
            ..RenderOptions::default()
        },
    );
    let lit = image.rgb.iter().filter(|v| **v != 0.0).count();
    let max = image.rgb.iter().copied().fold(0.0f32, f32::max);
    (lit, max, stats.exhausted_rays)
}

/// A closed room lit only from outside is black inside: every channel of every pixel exactly 0,
/// with `direct` and with `path` (8 bounces), for a camera inside a solid sphere (it sees the
/// sphere's inner side: the tracer reports the exit), inside the cavity of a spherical shell (a
/// `difference`), and inside the same shell turned by a `transform`. Anything that lets one ray
/// through a wall (a graze dropped, a shadow ray starting on the wrong side, a ray out of steps
/// counted as escaping) shows as a non-zero value, however rare: the sky's radiance is 1 and the
/// light's 50, so one leaking sample adds at least ~1e-5 to a pixel, and the same rooms seen from
/// outside are lit everywhere. Measured: 0 non-zero values, 0 rays out of steps (an earlier layout,
/// with `path`: none in 8 other seeds either). Box rooms:
/// [`a_box_room_with_marched_walls_lit_from_outside_is_black`],
/// [`a_sharp_box_room_lit_from_outside_is_black`].
#[test]
fn a_closed_room_lit_from_outside_is_black() {
    let shell = r#"{"type": "difference", "children": [
        {"type": "sphere", "center": [0, 0, 0], "radius": 2.1},
        {"type": "sphere", "center": [0, 0, 0], "radius": 1.9}]}"#;
    let rooms = [
        (
            "solid sphere",
            r#"{"type": "sphere", "center": [0, 0, 0], "radius": 2}"#.to_string(),
        ),
        ("spherical shell", shell.to_string()),
        (
            "turned spherical shell",
            format!(
                r#"{{"type": "transform", "rotate": {{"axis": [1, 2, 3], "angle": 37}}, "child": {shell}}}"#
            ),
        ),
    ];
    for (name, room) in &rooms {
        for integrator in [DIRECT, PATH] {
            let (lit, max, exhausted) = inside_the_room(room, integrator);
            println!(
                "{name} {integrator}: {lit} non-zero values (max {max}), {exhausted} exhausted"
            );
            assert_eq!(exhausted, 0, "{name}, {integrator}: rays ran out of steps");
            assert_eq!(
                lit, 0,
                "{name}, {integrator}: {lit} channel values are not 0 (max {max})"
            );
        }
    }
}

/// [`a_closed_room_lit_from_outside_is_black`] for box rooms whose walls are marched (a rounded
/// box, a `difference` of two boxes). A next-event ray to the sky that leaves a wall nearly parallel
/// to it (0.01–0.04° off) runs along that wall inside the room, a few tolerances from it; it must
/// finish (reach the far wall) rather than run out of steps and count as unoccluded. Before the
/// tracer crept at up to 64 tolerances per step near surfaces, at 16×16, 256 spp, seed 1: solid
/// rounded box (half size 2, 1.5, 2.5, rounding 0.3) `direct` 12 rays out of steps and 36 non-zero
/// values (up to 3.4e-5), `path` 72 and 183; shell of two boxes `direct` 13 and 39, `path` 100 and
/// 225 (up to 1.2e-3). Measured now: none.
#[test]
fn a_box_room_with_marched_walls_lit_from_outside_is_black() {
    let rooms = [
        (
            "solid rounded box",
            r#"{"type": "box", "center": [0, 0, 0], "half_size": [2, 1.5, 2.5], "rounding": 0.3}"#,
        ),
        (
            "shell of two boxes",
            r#"{"type": "difference", "children": [
                {"type": "box", "center": [0, 0, 0], "half_size": [2.2, 1.7, 2.7], "rounding": 0.3},
                {"type": "box", "center": [0, 0, 0], "half_size": [2, 1.5, 2.5], "rounding": 0.1}]}"#,
        ),
    ];
    let mut leaks = Vec::new();
    for (name, room) in rooms {
        for integrator in [DIRECT, PATH] {
            let (lit, max, exhausted) = inside_the_room(room, integrator);
            println!(
                "{name} {integrator}: {lit} non-zero values (max {max}), {exhausted} exhausted"
            );
            if lit > 0 || exhausted > 0 {
                leaks.push(format!(
                    "{name}, {integrator}: {lit} non-zero values (max {max}), {exhausted} rays out of steps"
                ));
            }
        }
    }
    assert!(leaks.is_empty(), "{}", leaks.join("; "));
}

/// [`a_closed_room_lit_from_outside_is_black`] for a sharp box room, traced in closed form. A path
/// vertex that lands on a wall within the box's on-surface tolerance (3e-6 here) of an edge
/// continues into the room; pushed off the wall it hit along that wall's normal, its origin would
/// still be on the neighbouring wall, and a ray from there into that wall starts on the surface, where
/// the tracer reports no crossing: the path escaped to the sky. [`Scene::offset_origin`] now pushes
/// such an origin off the neighbouring face too. Before, with `path` (16×16, 256 spp), the box
/// turned 37° about (1, 2, 3), seeds 1 to 8 gave 0, 0, 0, 3, 0, 6, 0, 3 non-zero values (one leaking
/// sample, in an earlier layout, carried 0.57); measured now: none. The ray itself: from the wall
/// `z = 2.5`, 3e-6 below the ceiling `y = 1.5`, into the room and up at 7.8°, must hit the ceiling.
#[test]
fn a_sharp_box_room_lit_from_outside_is_black() {
    let room = r#"{"type": "transform", "rotate": {"axis": [1, 2, 3], "angle": 37},
        "child": {"type": "box", "center": [0, 0, 0], "half_size": [2, 1.5, 2.5]}}"#;
    let scene = room_scene(room, PATH, [0.3, 0.2, 1.2], [-0.5, -0.3, -1.0]);
    let mut leaks = Vec::new();
    for seed in 1..=8 {
        let (image, stats) = render(
            &scene,
            &RenderOptions {
                spp: 256,
                seed,
                ..RenderOptions::default()
            },
        );
        let lit = image.rgb.iter().filter(|v| **v != 0.0).count();
        println!(
            "seed {seed}: {lit} non-zero values, {} exhausted",
            stats.exhausted_rays
        );
        if lit > 0 || stats.exhausted_rays > 0 {
            leaks.push(format!(
                "seed {seed}: {lit} non-zero values, {} rays out of steps",
                stats.exhausted_rays
            ));
        }
    }
    assert!(leaks.is_empty(), "{}", leaks.join("; "));
    let room = r#"{"type": "box", "center": [0, 0, 0], "half_size": [2, 1.5, 2.5]}"#;
    let scene = room_scene(room, PATH, [0.3, 0.2, 1.2], [-0.5, -0.3, -1.0]);
    let p = glam::Vec3::new(0.11, 1.5 - 3e-6, 2.5);
    let d = glam::Vec3::new(0.686, 0.135, -0.715).normalize();
    let ray = implicit_psdr::math::Ray::new(scene.offset_origin(0, p, glam::Vec3::Z, d), d);
    match scene.intersect(&ray, f32::INFINITY) {
        implicit_psdr::scene::Intersection::Hit(h) => {
            assert!((h.p.y - 1.5).abs() < 1e-5, "hit {:?}, not the ceiling", h.p)
        }
        other => panic!("a ray inside the room next to its edge: {other:?}"),
    }
}

/// A unit sphere at the origin (albedo ρ = 0.5) under a white sky (L = 1), seen on a square film of
/// `size` pixels at `fov` degrees by a camera at `(0, 0, d)` aimed at the point of its silhouette
/// on the `+x` side, `(√(1 − 1/d²), 0, 1/d)`: the silhouette passes through the film's centre,
/// vertically, the sphere to its left.
fn silhouette_view(fov: f32, size: u32, d: f32) -> Scene {
    let aim = [(1.0 - 1.0 / (d * d)).sqrt(), 0.0, 1.0 / d];
    scene_json(&format!(
        r#"{{"camera": {{"origin": [0, 0, {d}], "target": {aim:?}, "up": [0, 1, 0], "fov_y": {fov},
              "width": {size}, "height": {size}, "filter": "tent"}},
            "integrator": {{"type": "direct"}},
            "shapes": [{{"name": "ball", "sdf": {{"type": "sphere", "center": [0, 0, 0], "radius": 1}},
               "bsdf": {{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}}}],
            "emitters": [{{"name": "sky", "type": "constant", "radiance": [1, 1, 1]}}]}}"#
    ))
}

/// The two geometric parameters of [`silhouette_view`]'s sphere.
const SILHOUETTE_PARAMETERS: [&str; 2] = ["ball.center.x", "ball.radius"];

/// The focal length in pixels of a film `size` pixels high at `fov` degrees.
fn focal_px(fov: f64, size: u32) -> f64 {
    0.5 * size as f64 / (0.5 * fov).to_radians().tan()
}

/// The image sum (pixels and channels) of the derivative of [`silhouette_view`] with respect to
/// [`SILHOUETTE_PARAMETERS`] when the film is so narrow that it sees a straight piece of
/// silhouette: a sphere of radius 1 seen from distance `d` has the angular radius `α = asin(1/d)`;
/// moving its centre sideways turns its direction by `1/d` per unit, growing its radius widens `α`
/// by `1/(d cos α)`; the edge crosses the film's `size` rows moving `f` times that many pixels, and
/// turns background (L) into sphere (ρL) in each of the three channels: `3 (ρ − 1) L · size · f ·
/// ω`. The pixel filter's translates sum to 1 (the tent of every row integrates to 1).
fn straight_edge_sums(fov: f64, size: u32, d: f64) -> [f64; 2] {
    let f = focal_px(fov, size);
    let jump = 3.0 * (0.5 - 1.0);
    let cos_a = (1.0 - 1.0 / (d * d)).sqrt();
    [
        jump * size as f64 * f / d,
        jump * size as f64 * f / (d * cos_a),
    ]
}

/// The same sums when the whole silhouette is on the film, well inside it: `3 (ρ − 1) L dA/dπ` with
/// `A` the area (pixels²) of the sphere's image, an ellipse: for angular radius `α` and angle `γ`
/// between the sphere's direction and the optical axis, `A = π f² sin²α cos α / (cos²γ −
/// sin²α)^{3/2}`. Aimed at the silhouette, `γ = α`; moving the centre along `x` turns it towards
/// the axis (`dγ = −dx/d`), growing the radius widens `α` (`dα = dr / (d cos α)`).
fn ellipse_sums(fov: f64, size: u32, d: f64) -> [f64; 2] {
    let f = focal_px(fov, size);
    let area = |a: f64, g: f64| {
        std::f64::consts::PI * f * f * a.sin().powi(2) * a.cos()
            / (g.cos().powi(2) - a.sin().powi(2)).powf(1.5)
    };
    let a = (1.0 / d).asin();
    let h = 1e-6;
    let da = (area(a + h, a) - area(a - h, a)) / (2.0 * h);
    let dg = (area(a, a + h) - area(a, a - h)) / (2.0 * h);
    let jump = 3.0 * (0.5 - 1.0);
    [jump * dg * (-1.0 / d), jump * da / (d * a.cos())]
}

/// Where the silhouette is on the film's middle row: the largest film `x` (pixels, to 0.001) within
/// two pixels of the centre whose camera ray (traced as the renderer traces it, resolving its pixel)
/// hits the sphere (the sphere is on the left).
fn traced_edge(scene: &Scene) -> f32 {
    let frame = scene.camera.frame::<f32>();
    let (cx, cy) = (
        0.5 * scene.camera.width as f32,
        0.5 * scene.camera.height as f32,
    );
    (0..=4000)
        .map(|k| cx - 2.0 + 0.001 * k as f32)
        .filter(|&x| {
            let ray = frame.generate_ray(glam::Vec2::new(x, cy));
            matches!(
                scene.intersect_resolving(&ray, f32::INFINITY, frame.spread(ray.d)),
                implicit_psdr::scene::Intersection::Hit(_)
            )
        })
        .fold(f32::NEG_INFINITY, f32::max)
}

/// Budgets and bounds of one silhouette check.
struct SilhouetteCheck {
    spp: u32,
    primary: u64,
    secondary: u64,
    fd_spp: u32,
    /// Finite-difference step (both parameters).
    h: f32,
    /// Bound on `|Σ diff − Σ fd| / |Σ fd|`.
    sum_fd: f64,
    /// Bound on `|Σ diff − closed form| / |closed form|`.
    sum_closed: f64,
    /// Bound on `|Σ fd − closed form| / |closed form|`.
    fd_sum: f64,
    /// Bound on the blurred relative L2 of the derivative against FD.
    l2: f64,
}

/// Checks [`SILHOUETTE_PARAMETERS`]' complete derivatives on `scene` (one pass, every term finite,
/// no ray out of steps) against central finite differences with common random numbers (no ray out
/// of steps in their renders either) and against the closed-form image sums `expected`; the
/// silhouette's traced position on the middle row within 0.05 px of the film's centre, where it is.
fn check_silhouette(
    label: &str,
    scene: &Scene,
    expected: [f64; 2],
    c: &SilhouetteCheck,
    base: u64,
) {
    let size = scene.camera.width as usize;
    let edge = traced_edge(scene) - 0.5 * size as f32;
    println!("{label}: traced silhouette {edge:+.3} px from the exact one");
    let selection = scene.select(&SILHOUETTE_PARAMETERS).unwrap();
    let out = render_derivatives_with_boundary(
        scene,
        &selection,
        &diff_options(c.spp, seed(base)),
        c.primary,
        c.secondary,
    )
    .unwrap();
    assert_finite(&out, label);
    assert_eq!(
        out.stats.exhausted_rays, 0,
        "{label}: rays ran out of steps"
    );
    let sum = |v: &[f64]| v.iter().sum::<f64>();
    for (k, name) in SILHOUETTE_PARAMETERS.iter().enumerate() {
        let total = gray(&out.total()[k]);
        let interior = gray(&out.interior[k]);
        let reference = render_with_difference(
            scene,
            name,
            Some(c.h),
            &RenderOptions {
                spp: c.fd_spp,
                seed: seed(base + 500),
                ..RenderOptions::default()
            },
        )
        .unwrap();
        assert_eq!(
            reference.stats.exhausted_rays, 0,
            "{label} {name}: FD rays ran out of steps"
        );
        let f = gray(&reference.derivative);
        assert!(
            f.iter().all(|v| v.is_finite()),
            "{label} {name}: FD not finite"
        );
        let (st, sf, want) = (sum(&total), sum(&f), expected[k]);
        let e_fd = (st - sf).abs() / sf.abs();
        let e_cf = (st - want).abs() / want.abs();
        let e_fd_cf = (sf - want).abs() / want.abs();
        let e_interior = (sum(&interior) - sf).abs() / sf.abs();
        let l2 = blurred_rel_l2(&total, &f, size, size, None);
        println!(
            "{label} {name}: Σ {st:.5e} (interior {:.4e} primary {:.4e} secondary {:.4e}), FD {sf:.5e}, \
             closed form {want:.5e}: vs FD {e_fd:.4}, vs closed form {e_cf:.4}, FD vs closed form \
             {e_fd_cf:.4}, interior alone vs FD {e_interior:.3}; blurred rel L2 {l2:.4}",
            sum(&interior),
            sum(&gray(&out.primary[k])),
            sum(&gray(&out.secondary[k])),
        );
        assert!(
            e_fd <= c.sum_fd,
            "{label} {name}: Σ {st} vs FD {sf} ({e_fd})"
        );
        assert!(
            e_cf <= c.sum_closed,
            "{label} {name}: Σ {st} vs closed form {want} ({e_cf})"
        );
        assert!(
            e_fd_cf <= c.fd_sum,
            "{label} {name}: FD {sf} vs closed form {want} ({e_fd_cf})"
        );
        assert!(l2 <= c.l2, "{label} {name}: blurred rel L2 {l2}");
        // The boundary term matters: without it the sum misses by about half.
        assert!(
            e_interior > 4.0 * c.sum_fd,
            "{label} {name}: interior alone {e_interior}"
        );
    }
    assert!(
        edge.abs() <= 0.05,
        "{label}: silhouette traced {edge} px off"
    );
}

/// At a 170° field of view the sphere of [`silhouette_view`], 1.5 from the camera, spans the
/// directions from the optical axis out to 83.6° from it: on the 32-pixel film an ellipse 12.5 px
/// long from the centre, 3.5 px from the film's edge, where a pixel spans 0.5° (41° at the centre).
/// The complete derivative of its centre's `x` and of its radius matches finite differences and the
/// closed form of the ellipse's area ([`ellipse_sums`]).
///
/// Measured (32×32, 256 spp, 300,000 + 30,000 boundary samples; FD `h = 0.01` at 1024 spp; four
/// seeds, `PSDR_TEST_SEED` 0 to 3): image sums, closed form 738.71 (`x`) and −1090.19 (radius);
/// relative errors of the derivative against FD at most 0.015 (`x`) and 0.019 (radius), against the
/// closed form 0.016 and 0.013, of FD against the closed form 0.014 and 0.016; blurred relative L2
/// against FD 0.068–0.076 and 0.107–0.114; the interior term alone 46–48% off. The silhouette is
/// traced within 0.001 px of where it is. Bounds: twice the largest of the four.
#[test]
fn silhouette_derivative_at_a_170_degree_field_of_view() {
    let (fov, size, d) = (170.0, 32, 1.5);
    check_silhouette(
        "170°",
        &silhouette_view(fov, size, d),
        ellipse_sums(fov as f64, size, d as f64),
        &SilhouetteCheck {
            spp: 256,
            primary: 300_000,
            secondary: 30_000,
            fd_spp: 1024,
            h: 0.01,
            sum_fd: 0.04,
            sum_closed: 0.032,
            fd_sum: 0.035,
            l2: 0.23,
        },
        51,
    );
}

/// At a hundredth of a degree the film of [`silhouette_view`] (16×16, the sphere 100 from the
/// camera) sees 1.7e-4 radians of a silhouette 1.0e-2 in radius, a straight vertical edge: a pixel
/// spans 1.1e-3 units there. The complete derivative of the centre's `x` and of the radius match
/// finite differences and the straight edge's closed form ([`straight_edge_sums`]). Only 0.28% of
/// the silhouette is on the film, and the primary term samples the whole curve: it needs 10⁶
/// samples.
///
/// The two fields of view see different pieces of different silhouettes, so their sums are not
/// comparable with each other; each is compared with the closed form of the same motion (the
/// sphere's direction turning by `1/d` per unit of `x`, its angular radius widening by
/// `1/(d cos α)` per unit of radius), integrated over what its film sees.
///
/// Measured (256 spp, 10⁶ + 10⁴ boundary samples; FD `h = 5e-4` (0.46 px) at 256 spp; 32 seeds,
/// `PSDR_TEST_SEED` 0 to 31, 22 of them for the radius): image sums, closed form −22,001.6 (`x`) and
/// −22,002.7 (radius); relative errors of the derivative against FD mean 0.014, at most 0.048 (`x`;
/// radius 0.008, 0.016), against the closed form the same, the noise of the ~2,800 primary samples
/// that land on the film; of FD against the closed form at most 0.0026; blurred relative L2 against
/// FD 0.031 on average, at most 0.053; the interior term alone 49–53% off. The silhouette is traced
/// 0.004 px inside the true one (camera rays resolve a sixteenth of a pixel, 6.8e-5 here, below the
/// sphere's tolerance floor 2e-4). Bounds: 1.25 times the largest of the 32.
#[test]
fn silhouette_derivative_at_a_hundredth_of_a_degree() {
    let (fov, size, d) = (0.01, 16, 100.0);
    check_silhouette(
        "0.01°",
        &silhouette_view(fov, size, d),
        straight_edge_sums(fov as f64, size, d as f64),
        &SilhouetteCheck {
            spp: 256,
            primary: 1_000_000,
            secondary: 10_000,
            fd_spp: 256,
            h: 5e-4,
            sum_fd: 0.06,
            sum_closed: 0.059,
            fd_sum: 0.0033,
            l2: 0.067,
        },
        52,
    );
}

/// [`silhouette_derivative_at_a_hundredth_of_a_degree`] with the sphere 4 from the camera: a pixel
/// spans 4.2e-5 units at the silhouette, less than the sphere's tracing tolerance floor (2e-4), so
/// camera rays resolve a sixteenth of their pixel instead ([`TraceSettings::spread`]). Before they
/// did, rays passing up to 1.35e-5 inside the silhouette were stepped over as grazes, the rendered
/// silhouette sat 0.32 px inside the true one while the primary term put the edge on the true
/// curve, and with the default (differentiable) pixel normalisation the derivative's image sum fell
/// 20% short (−4.27e5 and −4.35e5 against the closed form −5.50e5).
///
/// Measured (256 spp, 4·10⁶ + 10⁴ boundary samples; FD `h = 2e-5` at 256 spp; four seeds,
/// `PSDR_TEST_SEED` 0 to 3): the silhouette is traced 0.004 px inside the true one; image sums
/// against FD at most 0.033 off, against the closed form 0.027, FD against the closed form 0.011;
/// blurred relative L2 against FD 0.033–0.057. Only 1.1·10⁻⁴ of the silhouette's length is on the
/// film, about 440 primary samples: the sums' noise is that count's (4×, 16·10⁶ samples and 1024
/// spp, measured the same spread). Bounds: twice the largest of the four.
#[test]
fn silhouette_derivative_at_a_hundredth_of_a_degree_close_up() {
    let (fov, size, d) = (0.01, 16, 4.0);
    check_silhouette(
        "0.01° close up",
        &silhouette_view(fov, size, d),
        straight_edge_sums(fov as f64, size, d as f64),
        &SilhouetteCheck {
            spp: 256,
            primary: 4_000_000,
            secondary: 10_000,
            fd_spp: 256,
            h: 2e-5,
            sum_fd: 0.065,
            sum_closed: 0.055,
            fd_sum: 0.022,
            l2: 0.115,
        },
        53,
    );
}

/// [`translating_the_whole_scene_degrades_with_the_float_resolution`] with the slab's edges sharp, so
/// that its crease edges' terms (seen by the camera, casting the ball-lit slab's shadows) move with
/// the scene too: their samples are placed, clipped and tested in world coordinates.
///
/// Measured against the unmoved scene at the same seed (seeds 0 and 1), at 10² and 10³: image mean
/// abs difference (1.1e-4, 1.2e-4), (1.1e-3, 1.4e-3) of the mean; blurred relative L2 of
/// `∂I/∂ball.radius` (2.1e-3, 7.8e-3), (2.3e-2, 3.2e-2), of `∂I/∂light.center.x` (1.4e-3, 9.8e-4),
/// (1.4e-2, 8.4e-3): as with rounded edges. Bounds: twice the larger, per offset (image, radius).
#[test]
fn translating_a_scene_with_crease_edges_degrades_with_the_float_resolution() {
    translated_scene_degrades(
        0.0,
        seed(34),
        &[(1e2, 2.4e-4, 1.6e-2), (1e3, 2.8e-3, 6.4e-2)],
    );
}
