//! Steering the tangent angle `θ_B` of the secondary boundary term towards the emitters
//! (`integrator::boundary::tangent_sampling`): the arcs are exactly the lines that reach each emitter
//! (checked by tracing lines), the mixture density integrates to 1 and matches a histogram of its draws,
//! the steered secondary term has the expectation of the uniform one with less variance, and the
//! complete derivative of an environment-lit scene matches finite differences.

mod common;
use common::deriv::{self as deriv, gray, masked_sum};

use common::Rng;
use implicit_psdr::bsdf::Bsdf;
use implicit_psdr::camera::Camera;
use implicit_psdr::emitter::Emitter;
use implicit_psdr::film::Filter;
use implicit_psdr::integrator::boundary::secondary::render_secondary_with;
use implicit_psdr::integrator::boundary::tangent_sampling::{
    Interval, TangentDistribution, TangentSampler, TangentSampling, UNIFORM_SHARE, emitter_interval,
};
use implicit_psdr::integrator::fd::finite_difference;
use implicit_psdr::integrator::{DiffOptions, render_derivatives_with_boundary};
use implicit_psdr::integrator::{IntegratorKind, RenderOptions};
use implicit_psdr::math::Ray;
use implicit_psdr::scene::{Intersection, NamedEmitter, Scene, Shape, Surface};
use implicit_psdr::sdf::Sdf;
use implicit_psdr::{Param, Param3};
use std::f32::consts::PI;
use std::time::Instant;

use glam::Vec3;

fn rectangle(center: [f32; 3], normal: Vec3, u: Vec3, size: [f32; 2], l: f32) -> Emitter {
    Emitter::Rectangle {
        center: Param3::new(center),
        normal,
        u,
        size: [Param::new(size[0]), Param::new(size[1])],
        radiance: Param3::new([l; 3]),
    }
}

fn sphere(center: [f32; 3], radius: f32, l: f32) -> Emitter {
    Emitter::Sphere {
        center: Param3::new(center),
        radius: Param::new(radius),
        radiance: Param3::new([l; 3]),
    }
}

fn environment(l: f32) -> Emitter {
    Emitter::Constant {
        radiance: Param3::new([l; 3]),
    }
}

/// A tangent frame of `n` turned by `angle` within the plane (moves where the arcs fall in `[0, π)`).
fn frame(n: Vec3, angle: f32) -> (Vec3, Vec3) {
    let (a, b) = n.any_orthonormal_pair();
    let (s, c) = angle.sin_cos();
    (a * c + b * s, b * c - a * s)
}

fn random_unit(rng: &mut Rng) -> Vec3 {
    loop {
        let v = rng.in_box(Vec3::splat(-1.0), Vec3::ONE);
        let l = v.length();
        if l > 0.1 && l <= 1.0 {
            return v / l;
        }
    }
}

/// Whether the line `x_b ± t ω(θ)` meets the emitter, and whether its light can reach the other side
/// (a rectangle emits on the side of its normal only).
fn line_reaches(emitter: &Emitter, x_b: Vec3, omega: Vec3) -> bool {
    let lit = match emitter {
        Emitter::Rectangle { center, normal, .. } => normal.dot(x_b - center.value()) > 0.0,
        _ => true,
    };
    lit && [omega, -omega].iter().any(|&d| {
        emitter
            .intersect(&Ray::new(x_b, d), f32::INFINITY)
            .is_some()
    })
}

/// Distance of `theta` from the ends of `arc`, as lines (mod π).
fn distance_to_ends(arc: &Interval, theta: f32) -> f32 {
    let d = |a: f32| {
        let x = (theta - a).rem_euclid(PI);
        x.min(PI - x)
    };
    d(arc.start).min(d(arc.start + arc.width))
}

/// For random points, normals and frames around a rectangle and a sphere emitter: a line is in the
/// emitter's arc iff tracing it (both ways) hits the emitter's lit side, on 720 lines per configuration
/// (lines within 2e-3 rad of an arc's ends are skipped: rounding decides there). Also counts that the
/// configurations include arcs crossing `θ = π`, wide arcs (`x_B` close to the emitter's plane or
/// sphere) and no arc.
#[test]
fn arcs_are_exactly_the_lines_that_reach_the_emitter() {
    let emitters = [
        rectangle([0.0, 2.0, 0.0], -Vec3::Y, Vec3::X, [1.0, 0.6], 1.0),
        rectangle(
            [0.3, 1.0, -0.2],
            Vec3::new(1.0, 1.0, 0.0).normalize(),
            Vec3::Z,
            [0.4, 2.0],
            1.0,
        ),
        sphere([0.0, 2.0, 0.0], 0.5, 1.0),
    ];
    let mut rng = Rng::new(3);
    let (mut arcs, mut wrapped, mut wide, mut none, mut checked) = (0, 0, 0, 0, 0);
    for (e, emitter) in emitters.iter().enumerate() {
        for trial in 0..300 {
            // Points all around, some very close to the emitter's plane or sphere.
            let x_b = match (e, trial % 3) {
                (2, 0) => {
                    let d = random_unit(&mut rng);
                    Vec3::new(0.0, 2.0, 0.0) + d * (0.5 + 1e-3 * rng.f32())
                }
                (0, 0) => {
                    let p = rng.in_box(Vec3::new(-0.8, 0.0, -0.5), Vec3::new(0.8, 0.0, 0.5));
                    Vec3::new(p.x, 2.0 - 1e-3 * rng.f32(), p.z)
                }
                _ => rng.in_box(Vec3::new(-2.0, -1.0, -2.0), Vec3::new(2.0, 3.0, 2.0)),
            };
            let n = random_unit(&mut rng);
            let (t1, t2) = frame(n, 2.0 * PI * rng.f32());
            let arc = emitter_interval(emitter, x_b, t1, t2, n);
            match arc {
                Some(a) => {
                    arcs += 1;
                    assert!(a.start >= 0.0 && a.start < PI && a.width > 0.0 && a.width <= PI);
                    wrapped += (a.start + a.width > PI) as u32;
                    wide += (a.width > 2.5) as u32;
                }
                None => none += 1,
            }
            for k in 0..720 {
                let theta = (k as f32 + 0.5) * PI / 720.0;
                if arc.is_some_and(|a| distance_to_ends(&a, theta) < 2e-3) {
                    continue;
                }
                let inside = arc.is_some_and(|a| a.contains(theta));
                let omega = t1 * theta.cos() + t2 * theta.sin();
                assert_eq!(
                    inside,
                    line_reaches(emitter, x_b, omega),
                    "emitter {e}, x_B {x_b}, n {n}, θ {theta}, arc {arc:?}"
                );
                checked += 1;
            }
        }
    }
    println!(
        "{arcs} arcs ({wrapped} crossing π, {wide} wider than 2.5), {none} without; {checked} lines"
    );
    assert!(arcs > 250 && wrapped > 50 && wide > 20 && none > 100);
}

/// `∫₀^π p = 1` by a fine midpoint rule (the density is piecewise constant: the error is at most the
/// number of jumps times the largest density times the step).
fn integral(d: &TangentDistribution) -> (f64, f64) {
    let n = 1 << 20;
    let step = PI as f64 / n as f64;
    let mut sum = 0.0;
    let mut max = 0.0f64;
    for k in 0..n {
        let p = d.pdf(((k as f64 + 0.5) * step) as f32) as f64;
        assert!(
            p.is_finite() && p >= (UNIFORM_SHARE / PI) as f64 * 0.999,
            "p = {p}"
        );
        max = max.max(p);
        sum += p;
    }
    let bound = 2.0 * (d.arcs().len() as f64 + 1.0) * max * step * 2.0;
    (sum * step, bound)
}

/// The mixture density integrates to 1 and the draws follow it: χ² of 100 bins over 400 000 draws
/// (expected counts by integrating the density over each bin) below `dof + 6 √(2 dof)`; for a rectangle
/// and a sphere emitter (alone and together with an environment), arcs crossing `π`, `x_B` just off the
/// rectangle's plane, and a point whose tangent plane misses every emitter (uniform).
#[test]
fn mixture_density_integrates_to_one_and_matches_its_draws() {
    let rect = rectangle([0.0, 2.0, 0.0], -Vec3::Y, Vec3::X, [1.0, 0.6], 8.0);
    let ball = sphere([1.5, 1.0, 0.0], 0.3, 3.0);
    let cases: Vec<(&str, Vec<Emitter>, Vec3, Vec3, f32)> = vec![
        ("rectangle", vec![rect.clone()], Vec3::ZERO, Vec3::Z, 0.0),
        // The frame turned so that the rectangle's arc (around +y, φ = π/2) crosses θ = π.
        (
            "rectangle, wrapped",
            vec![rect.clone()],
            Vec3::ZERO,
            Vec3::Z,
            PI / 2.0,
        ),
        (
            "near the plane",
            vec![rect.clone()],
            Vec3::new(0.1, 1.999, 0.05),
            Vec3::new(1.0, 0.0, 0.2).normalize(),
            0.3,
        ),
        ("sphere", vec![ball.clone()], Vec3::ZERO, Vec3::Z, 1.0),
        (
            "sphere grazed",
            vec![ball.clone()],
            Vec3::new(1.5, 1.0, 0.0) + Vec3::new(-0.3002, 0.0, 0.0),
            Vec3::new(0.0, 0.3, 1.0).normalize(),
            0.0,
        ),
        (
            "both and an environment",
            vec![rect.clone(), ball.clone(), environment(0.5)],
            Vec3::new(0.5, 0.2, 0.0),
            Vec3::new(0.2, 0.0, 1.0).normalize(),
            2.0,
        ),
        (
            "missed",
            vec![rect.clone(), ball.clone()],
            Vec3::ZERO,
            Vec3::Y,
            0.0,
        ),
    ];
    let mut rng = Rng::new(17);
    for (name, emitters, x_b, n, turn) in cases {
        let (t1, t2) = frame(n, turn);
        let d = TangentSampler::from_emitters(&emitters, TangentSampling::Steered)
            .distribution(x_b, t1, t2, n);
        if name == "missed" {
            assert_eq!(d, TangentDistribution::uniform());
        } else {
            assert!(!d.arcs().is_empty(), "{name}: no arc");
        }
        if name.contains("wrapped") {
            assert!(d.arcs().iter().any(|(a, _)| a.start + a.width > PI));
        }
        let total: f32 = d.uniform_probability() + d.arcs().iter().map(|(_, p)| p).sum::<f32>();
        assert!(
            (total - 1.0).abs() < 1e-5,
            "{name}: probabilities sum to {total}"
        );
        let (mass, bound) = integral(&d);
        assert!(
            (mass - 1.0).abs() < bound.max(1e-5),
            "{name}: ∫p = {mass} (±{bound})"
        );

        let bins = 100usize;
        let draws = 400_000usize;
        let mut counts = vec![0.0f64; bins];
        for _ in 0..draws {
            let theta = d.sample(rng.f32());
            assert!((0.0..PI).contains(&theta), "{name}: θ = {theta}");
            counts[((theta / PI * bins as f32) as usize).min(bins - 1)] += 1.0;
        }
        let sub = 2000;
        let mut chi2 = 0.0;
        for (b, &c) in counts.iter().enumerate() {
            let h = PI as f64 / (bins * sub) as f64;
            let p: f64 = (0..sub)
                .map(|k| d.pdf((((b * sub + k) as f64 + 0.5) * h) as f32) as f64 * h)
                .sum();
            let expected = p * draws as f64;
            chi2 += (c - expected).powi(2) / expected;
        }
        let dof = (bins - 1) as f64;
        println!(
            "{name}: {} arcs, uniform {:.3}, ∫p − 1 = {:.1e}, χ² = {chi2:.1} (dof {dof})",
            d.arcs().len(),
            d.uniform_probability(),
            mass - 1.0
        );
        assert!(chi2 < dof + 6.0 * (2.0 * dof).sqrt(), "{name}: χ² {chi2}");
    }
}

// ---------------------------------------------------------------------------------------------------
// The secondary term with steering: same expectation, less variance.

const SIZE: u32 = 32;

fn diffuse(a: [f32; 3]) -> Bsdf {
    Bsdf::Diffuse {
        albedo: Param3::new(a),
    }
}

fn diff_options(spp: u32, seed: u64) -> DiffOptions {
    DiffOptions {
        render: RenderOptions {
            spp,
            seed,
            progress: Default::default(),
        },
        ..DiffOptions::default()
    }
}

/// The floor-shadow scene of `tests/secondary_boundary.rs`: a ball above a floor under a small
/// rectangle light; the camera sees the floor shadow, not the ball.
fn shadow_scene() -> Scene {
    let camera = Camera::new(
        Vec3::new(-1.2, 2.6, 2.2),
        Vec3::new(-1.2, 0.0, 0.0),
        Vec3::Y,
        40.0,
        SIZE,
        SIZE,
        Filter::Tent,
    );
    let floor = Shape::new("floor", Sdf::plane(Vec3::Y, 0.0), diffuse([0.6; 3]));
    let ball = Shape::new("ball", Sdf::sphere([0.0, 0.9, 0.0], 0.4), diffuse([0.5; 3]));
    let light = NamedEmitter {
        name: "light".into(),
        emitter: rectangle([2.0, 2.6, 0.0], -Vec3::Y, Vec3::X, [0.6, 0.6], 8.0),
    };
    Scene::new(
        camera,
        IntegratorKind::Direct,
        1,
        vec![floor, ball],
        vec![light],
    )
}

/// `(2k+1)²` box blur of a `SIZE × SIZE` plane.
fn blur(v: &[f64], k: i64) -> Vec<f64> {
    deriv::blur(v, SIZE as usize, SIZE as usize, k)
}

/// Relative L2 error of `a` against `b` over `mask` after a 5×5 blur.
fn rel_l2(a: &[f64], b: &[f64], mask: &[bool]) -> f64 {
    deriv::rel_l2(&blur(a, 2), &blur(b, 2), Some(mask))
}

/// Pixels whose whole filter footprint (±1.5 px) sees shape `shape` (or, for `None`, anything).
fn footprint_mask(scene: &Scene, shape: Option<usize>) -> Vec<bool> {
    let frame = scene.camera.frame::<f32>();
    let mut mask = vec![true; (SIZE * SIZE) as usize];
    for y in 0..SIZE {
        for x in 0..SIZE {
            for oy in [-1.5f32, 0.0, 1.5] {
                for ox in [-1.5f32, 0.0, 1.5] {
                    let film = glam::Vec2::new(x as f32 + 0.5 + ox, y as f32 + 0.5 + oy);
                    let ray: Ray = frame.generate_ray(film);
                    let seen = match scene.intersect(&ray, f32::INFINITY) {
                        Intersection::Hit(h) => {
                            shape.is_none_or(|s| h.surface == Surface::Shape(s))
                        }
                        _ => false,
                    };
                    mask[(y * SIZE + x) as usize] &= seen;
                }
            }
        }
    }
    mask
}

/// Mean and standard error of the mean.
fn mean_se(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// On the floor shadow (`ball.radius`), `RUNS` independent seeds per mode: the floor
/// sums of the steered and the uniform secondary term agree within 4 combined standard errors (the
/// expectation is unchanged), and the steered term's per-pixel variance (summed over the floor, after a
/// 5×5 blur) is at least 3 times smaller at equal sample count. Prints the variance ratio, the time per
/// sample, the efficiency gain (variance × time) and the relative L2 (5×5 blur) of one run against the
/// mean of all runs of both modes.
#[test]
fn steering_keeps_the_expectation_and_reduces_variance() {
    const RUNS: u64 = 8;
    const SAMPLES: u64 = 10_000;
    let mask = footprint_mask(&shadow_scene(), Some(0));
    for name in ["ball.radius"] {
        let scene = shadow_scene();
        let selection = scene.select(&[name]).unwrap();
        let mut runs = [Vec::new(), Vec::new()];
        let mut seconds = [0.0; 2];
        for (m, mode) in [TangentSampling::Uniform, TangentSampling::Steered]
            .into_iter()
            .enumerate()
        {
            for seed in 0..RUNS {
                let start = Instant::now();
                let options = diff_options(1, 100 + seed);
                let out =
                    render_secondary_with(&scene, &selection, &options, SAMPLES, mode).unwrap();
                seconds[m] += start.elapsed().as_secs_f64();
                let g = gray(&out[0]);
                assert!(g.iter().all(|v| v.is_finite()));
                runs[m].push(g);
            }
        }
        let sums = runs
            .each_ref()
            .map(|r| mean_se(&r.iter().map(|g| masked_sum(g, &mask)).collect::<Vec<_>>()));
        let npix = runs[0][0].len();
        let all: Vec<&Vec<f64>> = runs.iter().flatten().collect();
        let reference: Vec<f64> = (0..npix)
            .map(|i| all.iter().map(|g| g[i]).sum::<f64>() / all.len() as f64)
            .collect();
        let variance = runs.each_ref().map(|r| {
            let blurred: Vec<Vec<f64>> = r.iter().map(|g| blur(g, 2)).collect();
            (0..npix)
                .filter(|&i| mask[i])
                .map(|i| {
                    mean_se(&blurred.iter().map(|g| g[i]).collect::<Vec<_>>())
                        .1
                        .powi(2)
                })
                .sum::<f64>()
                * RUNS as f64
        });
        let l2 = runs
            .each_ref()
            .map(|r| r.iter().map(|g| rel_l2(g, &reference, &mask)).sum::<f64>() / RUNS as f64);
        let ratio = variance[0] / variance[1];
        let efficiency = ratio * seconds[0] / seconds[1];
        println!(
            "{name}: floor sums uniform {:.3} ± {:.3}, steered {:.3} ± {:.3}; variance ratio {ratio:.1} \
             (time per run uniform {:.3} s, steered {:.3} s: efficiency ×{efficiency:.1}); rel L2 (5x5) \
             per run uniform {:.3}, steered {:.3}",
            sums[0].0,
            sums[0].1,
            sums[1].0,
            sums[1].1,
            seconds[0] / RUNS as f64,
            seconds[1] / RUNS as f64,
            l2[0],
            l2[1],
        );
        let se = (sums[0].1.powi(2) + sums[1].1.powi(2)).sqrt();
        assert!(
            (sums[0].0 - sums[1].0).abs() < 4.0 * se,
            "{name}: the floor sums differ by {} (standard error {se})",
            sums[0].0 - sums[1].0
        );
        assert!(ratio > 3.0, "{name}: variance ratio {ratio}");
    }
}

// ---------------------------------------------------------------------------------------------------
// The environment case: every escaping tangent line reaches the emitter at infinity.

/// A ball hovering just above a floor, lit only by a constant environment, seen from above at an angle
/// (silhouette and floor occlusion both in view).
fn environment_scene() -> Scene {
    let camera = Camera::new(
        Vec3::new(0.0, 1.6, 2.6),
        Vec3::new(0.0, 0.3, 0.0),
        Vec3::Y,
        40.0,
        SIZE,
        SIZE,
        Filter::Tent,
    );
    let floor = Shape::new("floor", Sdf::plane(Vec3::Y, 0.0), diffuse([0.6; 3]));
    let ball = Shape::new(
        "ball",
        Sdf::sphere([0.0, 0.55, 0.0], 0.4),
        diffuse([0.5; 3]),
    );
    let sky = NamedEmitter {
        name: "sky".into(),
        emitter: environment(1.0),
    };
    Scene::new(
        camera,
        IntegratorKind::Direct,
        1,
        vec![floor, ball],
        vec![sky],
    )
}

/// The floor of [`environment_scene`] in closed form: a diffuse floor (albedo `ρ`) under a constant
/// environment `L` and a ball of radius `R` wholly above the floor's horizon has radiance
/// `ρ L (1 − F)`, `F = R² cos θ / D² = R² H / D³` the form factor from a differential area to a sphere
/// (`D` the distance to the centre, `H` its height, `cos θ = H / D`), so (gray = 3 channels)
/// `∂H L = −3 ρ L R² (D² − 3H²) / D⁵` and `∂R L = −3 ρ L 2 R H / D³`. The floor does not move, so a floor
/// pixel's derivative is that field filtered by the pixel's tent (16 × 16 film points).
fn floor_closed_form(scene: &Scene, mask: &[bool]) -> [Vec<f64>; 2] {
    let (c, r, rho, l) = (Vec3::new(0.0, 0.55, 0.0).as_dvec3(), 0.4f64, 0.6f64, 1.0f64);
    let frame = scene.camera.frame::<f32>();
    let mut out = [vec![0.0; mask.len()], vec![0.0; mask.len()]];
    let m = 16;
    for (j, _) in mask.iter().enumerate().filter(|(_, m)| **m) {
        let (jx, jy) = (
            (j as u32 % SIZE) as f32 + 0.5,
            (j as u32 / SIZE) as f32 + 0.5,
        );
        let (mut acc, mut wsum) = ([0.0; 2], 0.0);
        for a in 0..m {
            for b in 0..m {
                let dx = (a as f32 + 0.5) / m as f32 * 2.0 - 1.0;
                let dy = (b as f32 + 0.5) / m as f32 * 2.0 - 1.0;
                let w = ((1.0 - dx.abs()) * (1.0 - dy.abs())) as f64;
                let ray: Ray = frame.generate_ray(glam::Vec2::new(jx + dx, jy + dy));
                let (o, d) = (ray.o.as_dvec3(), ray.d.as_dvec3());
                let x = o + d * (-o.y / d.y);
                let dd = (c - x).length();
                let h = c.y;
                acc[0] += w * -3.0 * rho * l * r * r * (dd * dd - 3.0 * h * h) / dd.powi(5);
                acc[1] += w * -3.0 * rho * l * 2.0 * r * h / dd.powi(3);
                wsum += w;
            }
        }
        out[0][j] = acc[0] / wsum;
        out[1][j] = acc[1] / wsum;
    }
    out
}

/// [`rel_l2`] restricted to `mask`: both images zeroed outside it before the 5×5 blur, the error taken
/// where the whole 5×5 window lies in the mask (the reference is known on the mask only).
fn rel_l2_within(a: &[f64], b: &[f64], mask: &[bool]) -> f64 {
    let cut = |v: &[f64]| -> Vec<f64> {
        v.iter()
            .zip(mask)
            .map(|(x, m)| if *m { *x } else { 0.0 })
            .collect()
    };
    let inside: Vec<f64> = mask.iter().map(|&m| m as u8 as f64).collect();
    let eroded: Vec<bool> = blur(&inside, 2).iter().map(|&v| v > 1.0 - 1e-9).collect();
    rel_l2(&cut(a), &cut(b), &eroded)
}

/// The complete derivative (interior + primary + secondary) of the environment-lit scene, for
/// `ball.center.y` and `ball.radius`:
/// - on the floor (pixels whose filter sees only the floor) against the closed form
///   [`floor_closed_form`] (no noise in the reference): there the interior and primary terms are 0 and
///   the secondary term with `x_D` at infinity is the whole derivative;
/// - on the whole image and on the ball against central finite differences with common random numbers.
///
/// Noise, measured with 4 other seeds (same budgets): ... (see the bounds).
#[test]
fn environment_lit_complete_derivative_matches_finite_differences() {
    let seed: u64 = std::env::var("SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    let names = ["ball.center.y", "ball.radius"];
    let scene = environment_scene();
    let selection = scene.select(&names).unwrap();
    let floor = footprint_mask(&scene, Some(0));
    let ball = footprint_mask(&scene, Some(1));
    let all = vec![true; (SIZE * SIZE) as usize];
    let closed = floor_closed_form(&scene, &floor);
    let start = Instant::now();
    let options = diff_options(16, 5 + seed);
    let out =
        render_derivatives_with_boundary(&scene, &selection, &options, 20_000, 60_000).unwrap();
    let t_ours = start.elapsed().as_secs_f64();
    let total = out.total();
    for (k, name) in names.iter().enumerate() {
        let start = Instant::now();
        let fd = finite_difference(
            &environment_scene(),
            name,
            0.02,
            &RenderOptions {
                spp: 128,
                seed: 9 + seed,
                progress: Default::default(),
            },
        )
        .unwrap();
        let t_fd = start.elapsed().as_secs_f64();
        let (t, fd) = (gray(&total[k]), gray(&fd));
        let (i, p, s) = (
            gray(&out.interior[k]),
            gray(&out.primary[k]),
            gray(&out.secondary[k]),
        );
        assert!(t.iter().all(|v| v.is_finite()));
        let exact = &closed[k];
        println!(
            "{name} floor: sum {:.3} closed form {:.3} (fd {:.3}); rel L2 (5x5) {:.4} (fd {:.4})",
            masked_sum(&t, &floor),
            masked_sum(exact, &floor),
            masked_sum(&fd, &floor),
            rel_l2_within(&t, exact, &floor),
            rel_l2_within(&fd, exact, &floor),
        );
        for (region, mask) in [("ball", &ball), ("image", &all)] {
            println!(
                "{name} {region}: sums total {:.3} (interior {:.3}, primary {:.3}, secondary {:.3}) fd \
                 {:.3}; rel L2 (5x5) total {:.3}, interior {:.3}",
                masked_sum(&t, mask),
                masked_sum(&i, mask),
                masked_sum(&p, mask),
                masked_sum(&s, mask),
                masked_sum(&fd, mask),
                rel_l2(&t, &fd, mask),
                rel_l2(&i, &fd, mask),
            );
        }
        println!("time: ours {t_ours:.2} s (both), fd {t_fd:.2} s");
        let (floor_tol, floor_l2) = [(0.06, 0.09), (0.015, 0.045)][k];
        let (sum, reference) = (masked_sum(&t, &floor), masked_sum(exact, &floor));
        assert!(
            (sum - reference).abs() <= floor_tol * reference.abs(),
            "{name}: floor sum {sum} vs closed form {reference}"
        );
        let l2 = rel_l2_within(&t, exact, &floor);
        assert!(l2 < floor_l2, "{name}: floor relative L2 {l2}");
        let (l2, l2_interior) = (rel_l2(&t, &fd, &all), rel_l2(&i, &fd, &all));
        assert!(l2 < 0.3, "{name}: relative L2 against FD {l2}");
        // Twice the bound on the complete derivative: the interior alone measured 0.68 (ball.center.y)
        // and more with the default (differentiable) normalisation, above 1.7 with the fixed one.
        assert!(
            l2_interior > 0.6,
            "{name}: the interior alone ({l2_interior}) must not match"
        );
        let scale: f64 = [&i, &p, &s].iter().map(|v| masked_sum(v, &all).abs()).sum();
        let (st, sf) = (masked_sum(&t, &all), masked_sum(&fd, &all));
        assert!(
            (st - sf).abs() <= 0.1 * scale,
            "{name}: image sum {st} vs FD {sf} (scale {scale})"
        );
    }
}
