//! Interval enclosures of SDF nodes (soundness against point evaluations, tightness on small boxes) and the
//! certified silhouette culling built on them: every silhouette point seen from the eye (analytic for a
//! sphere, found by Newton's method for a torus, a smooth union and a grid) lies in a kept box, the kept
//! volume shrinks about ×4 per level, and boxes away from the surface or the silhouette are culled.

mod common;

use common::Rng;
use glam::Vec3;
use implicit_psdr::Param3;
use implicit_psdr::bsdf::Bsdf;
use implicit_psdr::integrator::silhouette_boxes::{BoxClass, classify_box, silhouette_boxes};
use implicit_psdr::math::Aabb;
use implicit_psdr::scalar::Scalar;
use implicit_psdr::scene::Shape;
use implicit_psdr::sdf::interval::Interval;
use implicit_psdr::sdf::{Sdf, bake};

fn shape(sdf: Sdf) -> Shape {
    shape_at(sdf, Vec3::ZERO)
}

fn shape_at(sdf: Sdf, translate: Vec3) -> Shape {
    Shape::translated(
        "s",
        sdf,
        Bsdf::Diffuse {
            albedo: Param3::new([0.5; 3]),
        },
        Param3::from(translate),
    )
}

fn baked_sphere(res: usize) -> Sdf {
    let (lo, hi) = (Vec3::splat(-1.5), Vec3::splat(1.5));
    let data = bake(&Sdf::sphere([0.0; 3], 1.0), lo, hi, res);
    Sdf::grid(data, lo, hi).unwrap()
}

/// One node of every kind, and some nesting.
fn nodes() -> Vec<(&'static str, Sdf)> {
    let tilted = Vec3::new(0.3, 1.0, 0.2);
    vec![
        ("sphere", Sdf::sphere([0.1, -0.2, 0.3], 0.8)),
        ("rounded box", Sdf::cuboid([0.0; 3], [0.7, 0.5, 0.4], 0.1)),
        (
            "sharp box",
            Sdf::cuboid([0.1, 0.0, 0.0], [0.6, 0.5, 0.4], 0.0),
        ),
        ("torus", Sdf::torus([0.0; 3], tilted, 0.8, 0.25)),
        ("cylinder", Sdf::cylinder([0.0; 3], tilted, 0.5, 0.7, 0.1)),
        (
            "sharp cylinder",
            Sdf::cylinder([0.0; 3], Vec3::Z, 0.5, 0.7, 0.0),
        ),
        (
            "capsule",
            Sdf::capsule([-0.5, 0.0, 0.1], [0.5, 0.3, -0.2], 0.3),
        ),
        ("plane", Sdf::plane(Vec3::new(0.2, 1.0, 0.1), 0.3)),
        (
            "union",
            Sdf::union(vec![
                Sdf::sphere([-0.4, 0.0, 0.0], 0.5),
                Sdf::cuboid([0.4, 0.0, 0.0], [0.4; 3], 0.05),
            ]),
        ),
        (
            "intersection",
            Sdf::intersection(vec![
                Sdf::sphere([0.0; 3], 0.8),
                Sdf::cuboid([0.0; 3], [0.6; 3], 0.0),
            ]),
        ),
        (
            "difference",
            Sdf::difference(vec![
                Sdf::cuboid([0.0; 3], [0.6; 3], 0.05),
                Sdf::sphere([0.3, 0.3, 0.3], 0.5),
            ]),
        ),
        (
            "smooth union",
            Sdf::smooth_union(
                vec![
                    Sdf::sphere([-0.4, 0.0, 0.0], 0.5),
                    Sdf::sphere([0.4, 0.1, 0.0], 0.4),
                    Sdf::torus([0.0, -0.3, 0.0], Vec3::Y, 0.6, 0.15),
                ],
                0.3,
            ),
        ),
        (
            "transform",
            Sdf::transform(
                Sdf::cuboid([0.0; 3], [0.5, 0.3, 0.2], 0.05),
                [0.1, 0.2, -0.1],
                Vec3::new(1.0, 1.0, 0.0),
                35.0,
                1.3,
            ),
        ),
        ("grid", baked_sphere(16)),
        ("random grid", random_grid()),
        (
            "transformed grid",
            Sdf::transform(baked_sphere(12), [0.2, 0.0, 0.0], Vec3::Z, 20.0, 0.7),
        ),
        (
            "named",
            Sdf::named("t", Sdf::torus([0.0; 3], Vec3::X, 0.7, 0.2)),
        ),
    ]
}

/// Control values at random: neighbouring cells' polynomials differ a lot, so a box spanning cells must
/// not be bounded by one cell's polynomial.
fn random_grid() -> Sdf {
    let mut rng = Rng::new(99);
    let dims = [6, 5, 7];
    let values = (0..6 * 5 * 7).map(|_| 2.0 * rng.f32() - 1.0).collect();
    let data = implicit_psdr::sdf::GridData::new(dims, values, "random").unwrap();
    Sdf::grid(data, Vec3::new(-1.0, -0.8, -1.2), Vec3::new(1.0, 0.8, 1.2)).unwrap()
}

fn region(sdf: &Sdf) -> (Vec3, Vec3) {
    let b = sdf.bounds();
    if b.is_finite() {
        (b.min - Vec3::splat(0.4), b.max + Vec3::splat(0.4))
    } else {
        (Vec3::splat(-2.0), Vec3::splat(2.0))
    }
}

/// A random box inside the region, edge lengths log-uniform in `[1e-3, 1]` of the region's size.
fn random_box(rng: &mut Rng, lo: Vec3, hi: Vec3) -> Aabb {
    let size = (hi - lo).max_element();
    let half = Vec3::new(rng.f32(), rng.f32(), rng.f32()).map(|u| 0.5 * size * 1e-3f32.powf(u));
    let c = rng.in_box(lo, hi);
    Aabb::new(c - half, c + half)
}

fn within(i: Interval, v: f32, tol: f64) -> bool {
    let v = v as f64;
    let t = tol * (1.0 + v.abs());
    i.lo - t <= v && v <= i.hi + t
}

#[test]
fn interval_operations_enclose_their_point_values() {
    let mut rng = Rng::new(1);
    let rand_iv = |rng: &mut Rng| {
        let a = 6.0 * rng.f64() - 3.0;
        let w = if rng.f64() < 0.2 {
            0.0
        } else {
            4.0 * rng.f64().powi(2)
        };
        Interval::new(a, a + w)
    };
    let pick = |rng: &mut Rng, i: Interval| i.lo + (i.hi - i.lo) * rng.f64();
    type Un = (&'static str, fn(Interval) -> Interval, fn(f64) -> f64);
    let unary: [Un; 10] = [
        ("sqrt", |x| x.sqrt(), |x| x.max(0.0).sqrt()),
        ("exp", |x| x.exp(), f64::exp),
        ("ln", |x| x.ln(), f64::ln),
        ("sin", |x| x.sin(), f64::sin),
        ("cos", |x| x.cos(), f64::cos),
        ("acos", |x| x.acos(), |x| x.clamp(-1.0, 1.0).acos()),
        ("abs", |x| x.abs(), f64::abs),
        ("sqr", |x| x.sqr(), |x| x * x),
        ("pow 2.5", |x| x.powf(2.5), |x| x.powf(2.5)),
        ("clamp", |x| x.clamp(-0.5, 1.0), |x| x.clamp(-0.5, 1.0)),
    ];
    type Bin = (
        &'static str,
        fn(Interval, Interval) -> Interval,
        fn(f64, f64) -> f64,
    );
    let binary: [Bin; 7] = [
        ("add", |a, b| a + b, |a, b| a + b),
        ("sub", |a, b| a - b, |a, b| a - b),
        ("mul", |a, b| a * b, |a, b| a * b),
        ("div", |a, b| a / b, |a, b| a / b),
        ("max", |a, b| a.max(b), f64::max),
        ("min", |a, b| a.min(b), f64::min),
        ("atan2", |a, b| a.atan2(b), f64::atan2),
    ];
    for _ in 0..2000 {
        let (x, y) = (rand_iv(&mut rng), rand_iv(&mut rng));
        for (name, f, g) in unary {
            let r = f(x);
            for _ in 0..8 {
                let v = pick(&mut rng, x);
                let e = g(v);
                if e.is_nan() {
                    continue;
                }
                assert!(
                    r.lo <= e && e <= r.hi,
                    "{name}({x:?}) = {r:?} misses {name}({v}) = {e}"
                );
            }
        }
        for (name, f, g) in binary {
            let r = f(x, y);
            for _ in 0..8 {
                let (a, b) = (pick(&mut rng, x), pick(&mut rng, y));
                let e = g(a, b);
                if e.is_nan() {
                    continue;
                }
                assert!(
                    r.lo <= e && e <= r.hi,
                    "{name}({x:?}, {y:?}) = {r:?} misses {name}({a}, {b}) = {e}"
                );
            }
        }
    }
    // Ends of wide sine ranges: the extrema inside are found.
    let s = Interval::new(1.0, 2.0).sin();
    assert_eq!(s.hi, 1.0);
    assert!(Interval::new(3.0, 3.5).cos().lo == -1.0);
}

#[test]
fn enclosures_hold_values_and_gradients_of_every_node() {
    let mut rng = Rng::new(7);
    for (name, sdf) in nodes() {
        let (lo, hi) = region(&sdf);
        for _ in 0..60 {
            let b = random_box(&mut rng, lo, hi);
            let v = sdf.enclose(&b);
            let vg = sdf.enclose_gradient(&b);
            assert!(
                v.lo <= v.hi && vg.v.lo <= vg.v.hi,
                "{name}: empty enclosure"
            );
            for _ in 0..12 {
                let p = rng.in_box(b.min, b.max);
                let f = sdf.eval_f32(p);
                assert!(
                    within(v, f, 1e-5),
                    "{name}: φ({p}) = {f} outside {v:?} over {b:?}"
                );
                assert!(
                    within(vg.v, f, 1e-5),
                    "{name}: φ({p}) = {f} outside {:?}",
                    vg.v
                );
                let g = sdf.ad_gradient(p);
                for k in 0..3 {
                    assert!(
                        within(vg.g[k], g[k], 1e-4),
                        "{name}: ∂{k}φ({p}) = {} outside {:?} over {b:?}",
                        g[k],
                        vg.g[k]
                    );
                }
            }
        }
    }
}

#[test]
fn smooth_union_enclosure_holds_across_the_blend_edge() {
    // φ = smin(x, −x) with k = 1: over x ∈ [0.2, 0.8] the midpoint has |a − b| = 1 = k (outside the blend),
    // but at x = 0.2 the blend still lowers φ and tilts its gradient (∂φ/∂x = −1 + (1 − 2x)² = −0.64).
    let su = Sdf::smooth_union(
        vec![Sdf::plane(Vec3::X, 0.0), Sdf::plane(-Vec3::X, 0.0)],
        1.0,
    );
    let b = Aabb::new(Vec3::new(0.2, -0.1, -0.1), Vec3::new(0.8, 0.1, 0.1));
    let e = su.enclose_gradient(&b);
    let v = su.enclose(&b);
    for i in 0..=60 {
        let p = Vec3::new(0.2 + 0.01 * i as f32, 0.0, 0.0);
        let (f, g) = (su.eval_f32(p), su.ad_gradient(p));
        assert!(
            within(v, f, 1e-6) && within(e.v, f, 1e-6),
            "φ({p}) = {f}: {v:?}, {:?}",
            e.v
        );
        assert!(
            within(e.g[0], g.x, 1e-6),
            "∂φ/∂x({p}) = {}: {:?}",
            g.x,
            e.g[0]
        );
    }
    assert!(e.g[0].lo <= -1.0 + 1e-9 && e.g[0].hi >= -0.64 - 1e-6);
}

#[test]
fn enclosures_shrink_with_the_box() {
    let sdfs = [
        ("sphere", Sdf::sphere([0.0; 3], 1.0)),
        ("torus", Sdf::torus([0.0; 3], Vec3::Z, 0.8, 0.3)),
        (
            "smooth union",
            Sdf::smooth_union(
                vec![
                    Sdf::sphere([-0.5, 0.0, 0.0], 0.6),
                    Sdf::sphere([0.5, 0.0, 0.0], 0.6),
                ],
                0.4,
            ),
        ),
        ("grid", baked_sphere(24)),
    ];
    for (name, sdf) in sdfs {
        // A point on the surface off any axis, near the smooth union's blend for that node.
        let p = Vec3::new(0.05, 0.55, 0.4);
        let p = p - sdf.eval_f32(p) * sdf.gradient(p);
        let mut last = f64::INFINITY;
        for h in [0.1f32, 0.01, 0.001] {
            let b = Aabb::around(p, Vec3::splat(h));
            let e = sdf.enclose_gradient(&b);
            let gw = e.g.iter().map(|g| g.width()).fold(0.0, f64::max);
            // |∇φ| ≤ 1.2 here and the curvature is a few units: widths O(h).
            assert!(
                e.v.width() < 8.0 * h as f64 && gw < 40.0 * h as f64,
                "{name} at h = {h}: widths {} and {gw}",
                e.v.width()
            );
            assert!(e.v.width() < last, "{name}: not shrinking");
            last = e.v.width();
        }
    }
}

/// Points of `{φ = 0, ψ = 0}` seen from `eye`: random starts moved onto the surface, then Newton's method on
/// `(φ, ψ)` with minimum-norm steps (`∇ψ = H(c − x) − ∇φ`), kept if both residuals are tiny.
fn silhouette_points(shape: &Shape, eye: Vec3, n: usize, seed: u64) -> Vec<Vec3> {
    let mut rng = Rng::new(seed);
    let b = shape.bounds;
    let t = shape.translate.value();
    let mut out = Vec::new();
    for _ in 0..n {
        let mut x = rng.in_box(b.min, b.max).as_dvec3();
        for _ in 0..40 {
            let (f, g, h) = shape.sdf.hessian(x.as_vec3() - t);
            let (g, h) = (g.as_dvec3(), h.as_dmat3());
            let to_eye = eye.as_dvec3() - x;
            let psi = g.dot(to_eye);
            let gpsi = h * to_eye - g;
            // J = [gᵀ; gpsiᵀ], step = Jᵀ (J Jᵀ)⁻¹ F.
            let (a, bb, c) = (g.dot(g), g.dot(gpsi), gpsi.dot(gpsi));
            let det = a * c - bb * bb;
            if det.abs() < 1e-18 {
                break;
            }
            let (l0, l1) = (
                (c * f as f64 - bb * psi) / det,
                (a * psi - bb * f as f64) / det,
            );
            let step = g * l0 + gpsi * l1;
            // Damped: keep the iterate from jumping across the shape.
            let len = step.length();
            x -= if len > 0.2 { step * (0.2 / len) } else { step };
        }
        let xf = x.as_vec3();
        let f = shape.eval_f32(xf);
        let g = shape.gradient(xf);
        let psi = g.dot(eye - xf) / (g.length() * (eye - xf).length());
        if f.abs() < 1e-5 && psi.abs() < 1e-5 && b.contains(xf) {
            out.push(xf);
        }
    }
    out
}

fn assert_covered(name: &str, boxes: &[Aabb], points: &[Vec3], tol: f32) {
    for p in points {
        assert!(
            boxes.iter().any(|b| b.expanded(tol).contains(*p)),
            "{name}: silhouette point {p} in no kept box ({} boxes)",
            boxes.len()
        );
    }
}

fn volume(boxes: &[Aabb]) -> f64 {
    boxes
        .iter()
        .map(|b| {
            let e = b.extent();
            e.x as f64 * e.y as f64 * e.z as f64
        })
        .sum()
}

/// Kept boxes at depths `depths`, with their counts and volumes printed; checks that the volume shrinks
/// about ×4 per level over the deepest levels (a curve: ×2 in count, ×8 smaller boxes).
fn check_levels(
    name: &str,
    shape: &Shape,
    eye: Vec3,
    depths: std::ops::RangeInclusive<u32>,
) -> Vec<Aabb> {
    let mut prev: Option<f64> = None;
    let mut last = Vec::new();
    let deepest = *depths.end();
    for d in depths {
        let boxes = silhouette_boxes(shape, eye, d, 0.0).unwrap();
        let v = volume(&boxes);
        println!("{name}: depth {d}: {} boxes, volume {v:.3e}", boxes.len());
        if let Some(pv) = prev
            && d + 1 >= deepest
        {
            let r = pv / v;
            assert!(
                (2.5..7.0).contains(&r),
                "{name}: volume ratio {r} at depth {d}"
            );
        }
        prev = Some(v);
        last = boxes;
    }
    last
}

#[test]
fn sphere_silhouette_circle_lies_in_kept_boxes() {
    let t = Vec3::new(0.2, 0.1, -0.1);
    let s = shape_at(Sdf::sphere([0.1, -0.2, 0.3], 1.0), t);
    let eye = Vec3::new(0.7, 1.2, 4.0);
    let boxes = check_levels("sphere", &s, eye, 3..=7);
    // The contour circle: in the plane at r²/D from the centre towards the eye, radius r√(1 − r²/D²).
    let o = Vec3::new(0.1, -0.2, 0.3) + t;
    let d = eye - o;
    let dist = d.length();
    let axis = d / dist;
    let centre = o + axis / dist;
    let radius = (1.0 - 1.0 / (dist * dist)).sqrt();
    let (u, v) = axis.any_orthonormal_pair();
    let points: Vec<Vec3> = (0..512)
        .map(|i| {
            let a = i as f32 / 512.0 * std::f32::consts::TAU;
            centre + radius * (u * a.cos() + v * a.sin())
        })
        .collect();
    assert_covered("sphere", &boxes, &points, 1e-5);
}

#[test]
fn torus_and_smooth_union_silhouettes_lie_in_kept_boxes() {
    let eye = Vec3::new(1.0, 2.5, 3.5);
    let cases = [
        (
            "torus",
            shape_at(
                Sdf::torus([0.0; 3], Vec3::new(0.2, 1.0, 0.3), 0.8, 0.3),
                Vec3::new(0.0, 0.1, 0.0),
            ),
        ),
        (
            "smooth union",
            shape(Sdf::smooth_union(
                vec![
                    Sdf::sphere([-0.5, 0.0, 0.0], 0.6),
                    Sdf::sphere([0.5, 0.2, 0.0], 0.5),
                ],
                0.4,
            )),
        ),
    ];
    for (name, s) in cases {
        let boxes = check_levels(name, &s, eye, 4..=7);
        let points = silhouette_points(&s, eye, 600, 3);
        assert!(points.len() > 100, "{name}: only {} points", points.len());
        assert_covered(name, &boxes, &points, 1e-4);
    }
}

#[test]
fn grid_silhouette_lies_in_kept_boxes() {
    let s = shape(baked_sphere(24));
    let eye = Vec3::new(-1.0, 2.0, 3.5);
    let boxes = check_levels("grid", &s, eye, 3..=6);
    let points = silhouette_points(&s, eye, 400, 5);
    assert!(points.len() > 80, "grid: only {} points", points.len());
    assert_covered("grid", &boxes, &points, 1e-4);
}

#[test]
fn boxes_away_from_surface_or_silhouette_are_culled() {
    let s = shape(Sdf::sphere([0.0; 3], 1.0));
    let eye = Vec3::new(0.0, 0.0, 4.0);
    let small = |c: Vec3| Aabb::around(c, Vec3::splat(0.05));
    // Far outside and deep inside: no surface.
    assert_eq!(
        classify_box(&s, eye, &small(Vec3::splat(2.0))),
        BoxClass::NoSurface
    );
    assert_eq!(
        classify_box(&s, eye, &small(Vec3::ZERO)),
        BoxClass::NoSurface
    );
    // On the cap facing the eye: surface, but ψ = n·(c − x) > 0 there.
    assert_eq!(
        classify_box(&s, eye, &small(Vec3::Z)),
        BoxClass::NoSilhouette
    );
    // Across the contour circle (z = 1/4, radius √15/4).
    let on = Vec3::new(15f32.sqrt() / 4.0, 0.0, 0.25);
    assert_eq!(classify_box(&s, eye, &small(on)), BoxClass::Kept);
    // A plane has no finite root box.
    assert!(silhouette_boxes(&shape(Sdf::plane(Vec3::Y, 0.0)), eye, 3, 0.0).is_err());
}

#[test]
fn point_types_are_unchanged_by_the_interval_hooks() {
    // The smooth minimum's early exit and the grid's dispatch are skipped only for interval types: f32 and
    // the gradient dual give the same values as before (compared here with closed forms of the branches).
    let su = Sdf::smooth_union(
        vec![
            Sdf::sphere([-0.5, 0.0, 0.0], 0.6),
            Sdf::sphere([0.5, 0.0, 0.0], 0.6),
        ],
        0.4,
    );
    let p = Vec3::new(2.0, 0.3, 0.1);
    let a = (p - Vec3::new(-0.5, 0.0, 0.0)).length() - 0.6;
    let b = (p - Vec3::new(0.5, 0.0, 0.0)).length() - 0.6;
    assert_eq!(su.eval_f32(p), a.min(b));
    let q = Vec3::new(0.0, 0.3, 0.1);
    let (a, b) = (
        (q - Vec3::new(-0.5, 0.0, 0.0)).length() - 0.6,
        (q - Vec3::new(0.5, 0.0, 0.0)).length() - 0.6,
    );
    let h = (0.4 - (a - b).abs()) / 0.4;
    assert!((su.eval_f32(q) - (a.min(b) - h * h * h * 0.4 / 6.0)).abs() < 1e-6);
}
