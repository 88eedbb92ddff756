//! Conformance suite for implicit-surface nodes (`sdf_suite!`, run against every node type) and closed-form
//! checks: values, gradients against central differences, curvature against the divergence of the normal
//! field and against `2/r`, `1/r` and the torus formulas, Lipschitz and bounding-box guarantees, `.npy` I/O.

mod common;

use common::Rng;
use glam::Vec3;
use implicit_psdr::Param;
use implicit_psdr::scalar::Dual32;
use implicit_psdr::sdf::{AngleTrig, GridData, Sdf, bake, read_npy, write_npy};
use std::path::PathBuf;

/// Region the suite samples: the node's box with a generous margin, or a fixed cube for unbounded nodes.
fn region(sdf: &Sdf) -> (Vec3, Vec3) {
    let b = sdf.bounds();
    if b.is_finite() {
        let m = 0.5 * b.extent().max_element() + 0.2;
        (b.min - Vec3::splat(m), b.max + Vec3::splat(m))
    } else {
        (Vec3::splat(-3.0), Vec3::splat(3.0))
    }
}

fn assert_finite(sdf: &Sdf, p: Vec3) {
    let g = sdf.gradient(p);
    let n = sdf.normal(p);
    let k = sdf.curvature(p);
    assert!(
        sdf.eval_f32(p).is_finite() || p.length() > 1e30,
        "φ({p}) not finite"
    );
    assert!(g.is_finite(), "gradient at {p} = {g}");
    assert!(
        n.is_finite() && (n.length() - 1.0).abs() < 1e-4,
        "normal at {p} = {n}"
    );
    assert!(k.is_finite(), "curvature at {p} = {k}");
}

/// Central difference of `φ` along the axes with step `h`.
fn fd_gradient(sdf: &Sdf, p: Vec3, h: f32) -> Vec3 {
    Vec3::from_array(std::array::from_fn(|i| {
        let mut e = Vec3::ZERO;
        e[i] = h;
        (sdf.eval_f32(p + e) - sdf.eval_f32(p - e)) / (2.0 * h)
    }))
}

/// True if the AD gradient is (nearly) the same at the six stencil points as at `p`: no kink of `φ`
/// (crease, medial axis, CSG switch) within the stencil, so finite differences are meaningful there.
fn smooth_at(sdf: &Sdf, p: Vec3, h: f32, tol: f32) -> bool {
    let g = sdf.ad_gradient(p);
    (0..3).all(|i| {
        let mut e = Vec3::ZERO;
        e[i] = h;
        (sdf.ad_gradient(p + e) - g).length() < tol && (sdf.ad_gradient(p - e) - g).length() < tol
    })
}

/// True if `κ` at the six stencil points is close to `κ(p)`.
fn curvature_smooth_at(sdf: &Sdf, p: Vec3, h: f32, k: f32) -> bool {
    (0..3).all(|i| {
        let mut e = Vec3::ZERO;
        e[i] = h;
        [p + e, p - e]
            .iter()
            .all(|&q| (sdf.curvature(q) - k).abs() < 0.05 * (1.0 + k.abs()))
    })
}

/// Divergence of the unit normal field by central differences (`κ = ∇·n`).
fn fd_divergence(sdf: &Sdf, p: Vec3, h: f32) -> f32 {
    (0..3)
        .map(|i| {
            let mut e = Vec3::ZERO;
            e[i] = h;
            (sdf.normal(p + e)[i] - sdf.normal(p - e)[i]) / (2.0 * h)
        })
        .sum()
}

/// Newton projection onto the zero level set (a few steps of `p − φ ∇φ/|∇φ|²`).
fn project(sdf: &Sdf, mut p: Vec3) -> Vec3 {
    for _ in 0..30 {
        let g = sdf.gradient(p);
        let g2 = g.length_squared();
        if g2 < 1e-12 {
            break;
        }
        p -= g * (sdf.eval_f32(p) / g2);
    }
    p
}

/// What a node promises beyond the common checks.
#[derive(Copy, Clone)]
struct Expect {
    /// `| |∇φ| − 1 |` bound away from kinks (`None`: not a distance, e.g. in a smooth-union blend).
    unit_gradient: Option<f32>,
    /// Where the unit-gradient promise holds (`None`: everywhere).
    unit_box: Option<(Vec3, Vec3)>,
}

const EXACT: Expect = Expect {
    unit_gradient: Some(1e-3),
    unit_box: None,
};

macro_rules! sdf_suite {
    ($($name:ident: $node:expr, $expect:expr;)*) => {$(
        mod $name {
            use super::*;

            fn node() -> Sdf {
                $node
            }

            #[test]
            fn gradient_matches_central_differences() {
                let sdf = node();
                let (lo, hi) = region(&sdf);
                let mut rng = Rng::new(1);
                let (h, mut tested) = (1e-3, 0);
                for _ in 0..300 {
                    let p = rng.in_box(lo, hi);
                    let g = sdf.gradient(p);
                    // Fast paths (sphere, box) agree with AD everywhere, kinks included.
                    assert!((g - sdf.ad_gradient(p)).length() < 1e-5, "fast path at {p}");
                    assert_finite(&sdf, p);
                    if !smooth_at(&sdf, p, h, 1e-2) {
                        continue;
                    }
                    let fd = fd_gradient(&sdf, p, h);
                    let scale = 1.0 + sdf.eval_f32(p).abs();
                    assert!(
                        (g - fd).length() < 2e-3 * scale,
                        "∇φ({p}) = {g}, central differences {fd}"
                    );
                    tested += 1;
                }
                assert!(tested >= 200, "only {tested} smooth points");
            }

            #[test]
            fn gradient_has_unit_length_for_distances() {
                let (sdf, e) = (node(), $expect);
                let Some(tol) = e.unit_gradient else { return };
                let (lo, hi) = e.unit_box.unwrap_or_else(|| region(&sdf));
                let mut rng = Rng::new(2);
                for _ in 0..300 {
                    let p = rng.in_box(lo, hi);
                    // Skip kinks, and focal regions (|κ| large), where a grid's spline rounds off the
                    // distance's cone over a few cells.
                    if !smooth_at(&sdf, p, 1e-3, 1e-2) || sdf.curvature(p).abs() > 8.0 {
                        continue;
                    }
                    let l = sdf.gradient(p).length();
                    assert!((l - 1.0).abs() < tol, "|∇φ({p})| = {l}");
                }
            }

            #[test]
            fn lipschitz_bound_holds() {
                let sdf = node();
                let l = sdf.lipschitz();
                assert!(l >= 1.0 && l.is_finite(), "L = {l}");
                let (lo, hi) = region(&sdf);
                let mut rng = Rng::new(3);
                for i in 0..3000 {
                    let a = rng.in_box(lo, hi);
                    // Half the pairs close together, where a loose bound shows most.
                    let b = if i % 2 == 0 {
                        rng.in_box(lo, hi)
                    } else {
                        a + (rng.in_box(Vec3::splat(-1.0), Vec3::ONE)) * 0.05
                    };
                    let (fa, fb) = (sdf.eval_f32(a), sdf.eval_f32(b));
                    let slack = 2e-6 * (1.0 + fa.abs().max(fb.abs()));
                    assert!(
                        (fa - fb).abs() <= l * (a - b).length() + slack,
                        "|φ({a}) − φ({b})| = {} > {l}·{}",
                        (fa - fb).abs(),
                        (a - b).length()
                    );
                }
            }

            #[test]
            fn bounds_contain_the_solid() {
                let sdf = node();
                let b = sdf.bounds();
                assert!(!b.is_empty());
                let (lo, hi) = region(&sdf);
                let mut rng = Rng::new(4);
                let mut inside = 0;
                for _ in 0..30000 {
                    let p = rng.in_box(lo, hi);
                    if sdf.eval_f32(p) <= 0.0 {
                        inside += 1;
                        assert!(b.contains(p), "φ({p}) ≤ 0 outside {b:?}");
                    }
                }
                assert!(inside > 100, "only {inside} interior samples: the test says nothing");
                // Points just inside along the boundary of the solid too.
                for _ in 0..300 {
                    let p = project(&sdf, rng.in_box(lo, hi));
                    let q = p - sdf.normal(p) * 1e-3;
                    if sdf.eval_f32(q) <= 0.0 && q.is_finite() {
                        assert!(b.contains(q), "surface point {q} outside {b:?}");
                    }
                }
            }

            #[test]
            fn curvature_matches_divergence_of_normal() {
                let sdf = node();
                let (lo, hi) = region(&sdf);
                let mut rng = Rng::new(5);
                let (h, mut tested) = (2e-3, 0);
                for _ in 0..300 {
                    let p = rng.in_box(lo, hi);
                    let g = sdf.gradient(p).length();
                    if g < 0.3 || !smooth_at(&sdf, p, 2.0 * h, 2e-2) {
                        continue;
                    }
                    let k = sdf.curvature(p);
                    if k.abs() > 30.0 || !curvature_smooth_at(&sdf, p, h, k) {
                        // Next to a focal point, or where the shape is only C1 (a flat face meeting a
                        // rounded edge, a capsule's cylinder meeting its cap): κ jumps within the stencil.
                        continue;
                    }
                    let fd = fd_divergence(&sdf, p, h);
                    assert!(
                        (k - fd).abs() < 2e-2 * (1.0 + k.abs()),
                        "κ({p}) = {k}, div n by differences {fd}"
                    );
                    tested += 1;
                }
                assert!(tested >= 100, "only {tested} points tested");
            }

            #[test]
            fn spicy_inputs_stay_finite() {
                let sdf = node();
                let b = sdf.bounds();
                let mut points = vec![
                    Vec3::ZERO,
                    Vec3::new(1e6, -2e6, 3e5),
                    Vec3::new(-1e12, 4e11, 1e12),
                    Vec3::new(1e-30, -1e-30, 0.0),
                    Vec3::splat(f32::MIN_POSITIVE),
                ];
                if b.is_finite() {
                    points.extend([b.center(), b.min, b.max]);
                }
                let (lo, hi) = region(&sdf);
                let mut rng = Rng::new(6);
                for _ in 0..50 {
                    let p = project(&sdf, rng.in_box(lo, hi));
                    // Newton can stall on a medial axis (a concave corner): keep converged points only.
                    if p.is_finite() && sdf.eval_f32(p).abs() < 1e-4 {
                        points.push(p);
                    }
                }
                assert!(points.len() > 30, "projection onto the surface failed too often");
                for p in points {
                    assert_finite(&sdf, p);
                }
            }
        }
    )*};
}

fn two_spheres_and_capsule() -> Vec<Sdf> {
    vec![
        Sdf::sphere(Vec3::new(-0.6, 0.0, 0.0), 0.5),
        Sdf::sphere(Vec3::new(0.5, 0.1, 0.0), 0.6),
        Sdf::capsule(Vec3::new(0.0, -0.8, 0.2), Vec3::new(0.1, 0.8, -0.2), 0.25),
    ]
}

/// `grid` with its iso-level set to `level`.
fn dilated(mut grid: Sdf, level: f32) -> Sdf {
    if let Sdf::Grid { level: l, .. } = &mut grid {
        l.value = level;
    }
    grid
}

fn baked_sphere() -> Sdf {
    let (lo, hi) = (Vec3::splat(-1.2), Vec3::splat(1.2));
    let data = bake(&Sdf::sphere(Vec3::new(0.05, -0.1, 0.0), 0.8), lo, hi, 40);
    Sdf::grid(data, lo, hi).unwrap()
}

sdf_suite! {
    sphere: Sdf::sphere(Vec3::new(0.1, -0.2, 0.3), 1.0), EXACT;
    sharp_box: Sdf::cuboid(Vec3::new(0.2, 0.0, -0.1), Vec3::new(1.0, 0.6, 0.8), 0.0), EXACT;
    rounded_box: Sdf::cuboid(Vec3::new(0.2, 0.0, -0.1), Vec3::new(1.0, 0.6, 0.8), 0.2), EXACT;
    torus: Sdf::torus(Vec3::new(0.0, 0.1, 0.0), Vec3::new(0.3, 1.0, 0.2), 1.0, 0.3), EXACT;
    cylinder: Sdf::cylinder(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), 0.5, 0.8, 0.1), EXACT;
    sharp_cylinder: Sdf::cylinder(Vec3::new(0.1, 0.0, 0.0), Vec3::Z, 0.7, 0.4, 0.0), EXACT;
    capsule: Sdf::capsule(Vec3::new(-0.5, 0.0, 0.0), Vec3::new(0.5, 0.3, 0.2), 0.4), EXACT;
    plane: Sdf::plane(Vec3::new(0.2, 1.0, 0.1), 0.3), EXACT;
    union: Sdf::union(vec![
        Sdf::sphere(Vec3::new(-0.5, 0.0, 0.0), 0.7),
        Sdf::cuboid(Vec3::new(0.6, 0.2, 0.0), Vec3::splat(0.5), 0.1),
    ]), EXACT;
    intersection: Sdf::intersection(vec![
        Sdf::sphere(Vec3::ZERO, 1.0),
        Sdf::cuboid(Vec3::new(0.3, 0.0, 0.0), Vec3::splat(0.8), 0.0),
    ]), EXACT;
    difference: Sdf::difference(vec![
        Sdf::cuboid(Vec3::ZERO, Vec3::splat(0.8), 0.1),
        Sdf::sphere(Vec3::new(0.5, 0.5, 0.5), 0.6),
    ]), EXACT;
    smooth_union: Sdf::smooth_union(two_spheres_and_capsule(), 0.4), Expect { unit_gradient: None, unit_box: None };
    transform: Sdf::transform(
        Sdf::cuboid(Vec3::ZERO, Vec3::new(0.6, 0.3, 0.4), 0.1),
        Vec3::new(0.3, -0.5, 0.2),
        Vec3::new(1.0, 2.0, 3.0),
        37.0,
        1.7,
    ), EXACT;
    transformed_torus: Sdf::transform(
        Sdf::torus(Vec3::ZERO, Vec3::Z, 0.7, 0.2),
        Vec3::new(-0.2, 0.0, 0.4),
        Vec3::X,
        -120.0,
        0.6,
    ), EXACT;
    // Outside its box a grid is `φ(face) + distance`: a bound, not a distance.
    grid: baked_sphere(), Expect { unit_gradient: Some(0.03), unit_box: Some((Vec3::splat(-1.2), Vec3::splat(1.2))) };
    // Iso-level 0.5: the surface (radius ≈ 1.3) leaves the grid box (±1.2), so the bounds must grow.
    grid_dilated: dilated(baked_sphere(), 0.5), Expect { unit_gradient: None, unit_box: None };
}

// ----- closed forms --------------------------------------------------------------------------------

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn primitive_values_match_closed_forms() {
    let s = Sdf::sphere(Vec3::new(1.0, 2.0, 3.0), 0.5);
    assert!(close(s.eval_f32(Vec3::new(1.0, 2.0, 5.0)), 1.5, 1e-6));
    assert!(close(s.eval_f32(Vec3::new(1.0, 2.0, 3.0)), -0.5, 1e-6));

    let b = Sdf::cuboid(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0), 0.0);
    assert!(close(b.eval_f32(Vec3::new(3.0, 0.0, 0.0)), 2.0, 1e-6)); // face
    assert!(close(
        b.eval_f32(Vec3::new(2.0, 3.0, 0.0)),
        2f32.sqrt(),
        1e-6
    )); // edge
    assert!(close(
        b.eval_f32(Vec3::new(2.0, 3.0, 4.0)),
        3f32.sqrt(),
        1e-6
    )); // corner
    assert!(close(b.eval_f32(Vec3::new(0.5, 0.0, 0.0)), -0.5, 1e-6)); // inside, nearest face x
    // Rounded: outer extents kept, the corner pulled in: distance to the corner sphere of radius r.
    let r = 0.25;
    let rb = Sdf::cuboid(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0), r);
    assert!(close(rb.eval_f32(Vec3::new(1.5, 0.0, 0.0)), 0.5, 1e-6));
    let c = Vec3::new(1.0, 2.0, 3.0) - Vec3::splat(r);
    let p = Vec3::new(2.0, 3.0, 4.0);
    assert!(close(rb.eval_f32(p), (p - c).length() - r, 1e-5));

    // Torus about y: outer equator, inner equator, top of the tube, centre.
    let t = Sdf::torus(Vec3::ZERO, Vec3::Y, 2.0, 0.5);
    assert!(close(t.eval_f32(Vec3::new(3.0, 0.0, 0.0)), 0.5, 1e-6));
    assert!(close(t.eval_f32(Vec3::new(0.0, 0.0, 1.0)), 0.5, 1e-6));
    assert!(close(t.eval_f32(Vec3::new(0.0, 1.0, 2.0)), 0.5, 1e-6));
    assert!(close(t.eval_f32(Vec3::ZERO), 1.5, 1e-6));

    let pl = Sdf::plane(Vec3::new(0.0, 2.0, 0.0), 1.0); // normalised to +y
    assert!(close(pl.eval_f32(Vec3::new(5.0, 3.0, -2.0)), 2.0, 1e-6));

    let cy = Sdf::cylinder(Vec3::ZERO, Vec3::Z, 1.0, 2.0, 0.0);
    assert!(close(cy.eval_f32(Vec3::new(3.0, 0.0, 0.0)), 2.0, 1e-6));
    assert!(close(cy.eval_f32(Vec3::new(0.0, 0.0, 5.0)), 3.0, 1e-6));
    assert!(close(cy.eval_f32(Vec3::new(4.0, 0.0, 6.0)), 5.0, 1e-6)); // rim: (3, 4) → 5
    assert!(close(cy.eval_f32(Vec3::new(0.0, 0.5, 0.0)), -0.5, 1e-6));

    let ca = Sdf::capsule(Vec3::ZERO, Vec3::new(0.0, 0.0, 2.0), 0.5);
    assert!(close(ca.eval_f32(Vec3::new(1.0, 0.0, 1.0)), 0.5, 1e-6));
    assert!(close(ca.eval_f32(Vec3::new(0.0, 0.0, -2.0)), 1.5, 1e-6));
    // Degenerate segment: a sphere.
    let dot = Sdf::capsule(Vec3::ONE, Vec3::ONE, 0.5);
    assert!(close(dot.eval_f32(Vec3::new(1.0, 1.0, 3.0)), 1.5, 1e-6));
    assert!(dot.gradient(Vec3::ONE).is_finite());
}

#[test]
fn sphere_centre_has_a_defined_normal() {
    let c = Vec3::new(0.5, -1.0, 2.0);
    let s = Sdf::sphere(c, 1.0);
    assert_eq!(s.gradient(c), Vec3::ZERO);
    assert_eq!(s.ad_gradient(c), Vec3::ZERO);
    assert_eq!(s.normal(c), Vec3::Z);
    assert_eq!(s.curvature(c), 0.0);
    // Inside a box at its centre: a face direction, not NaN.
    let b = Sdf::cuboid(c, Vec3::ONE, 0.2);
    assert!((b.normal(c).length() - 1.0).abs() < 1e-6);
}

#[test]
fn transform_rotates_scales_and_translates() {
    // A box of half extents (2, 1, 1) turned 90° about z has half extents (1, 2, 1).
    let b = Sdf::cuboid(Vec3::ZERO, Vec3::new(2.0, 1.0, 1.0), 0.0);
    let t = Sdf::transform(b, Vec3::new(10.0, 0.0, 0.0), Vec3::Z, 90.0, 1.0);
    assert!(close(t.eval_f32(Vec3::new(10.0, 1.5, 0.0)), -0.5, 1e-5));
    assert!(close(t.eval_f32(Vec3::new(11.5, 0.0, 0.0)), 0.5, 1e-5));
    let bb = t.bounds();
    assert!(
        (bb.min - Vec3::new(9.0, -2.0, -1.0)).abs().max_element() < 1e-4,
        "{bb:?}"
    );
    assert!(
        (bb.max - Vec3::new(11.0, 2.0, 1.0)).abs().max_element() < 1e-4,
        "{bb:?}"
    );
    // Scale keeps distances: a unit sphere scaled by 2 is a sphere of radius 2.
    let s = Sdf::transform(Sdf::sphere(Vec3::ZERO, 1.0), Vec3::ONE, Vec3::X, 0.0, 2.0);
    assert!(close(s.eval_f32(Vec3::new(4.0, 1.0, 1.0)), 1.0, 1e-6));
    assert!(close(s.curvature(Vec3::new(3.0, 1.0, 1.0)), 1.0, 1e-4)); // 2/r, r = 2
}

#[test]
fn parameter_derivatives_with_dual_numbers() {
    // ∂φ/∂r = −1 for a sphere; ∂φ/∂angle of a rotated box against a central difference.
    let mut s = Sdf::sphere(Vec3::ZERO, 1.0);
    if let Sdf::Sphere { radius, .. } = &mut s {
        radius.slot = Some(0);
    }
    let p = implicit_psdr::Vec3::new(Dual32::from(2.0), Dual32::from(0.5), Dual32::from(0.0));
    assert!(close(s.eval::<Dual32>(p).eps, -1.0, 1e-6));

    let make = |deg: f32, slot| Sdf::Transform {
        translate: [0.1, 0.2, 0.0].into(),
        axis: Vec3::new(0.0, 0.6, 0.8),
        angle: Param { value: deg, slot },
        trig: AngleTrig::of(deg),
        scale: Param::new(1.3),
        child: Box::new(Sdf::cuboid(Vec3::ZERO, Vec3::new(1.0, 0.5, 0.3), 0.1)),
    };
    let x = Vec3::new(1.1, 0.7, -0.4);
    let px = implicit_psdr::Vec3::new(Dual32::from(x.x), Dual32::from(x.y), Dual32::from(x.z));
    let d = make(25.0, Some(0)).eval::<Dual32>(px).eps;
    let h = 0.05;
    let fd = (make(25.0 + h, None).eval_f32(x) - make(25.0 - h, None).eval_f32(x)) / (2.0 * h);
    assert!(
        close(d, fd, 2e-4 * (1.0 + fd.abs())),
        "∂φ/∂angle = {d}, differences {fd}"
    );
    assert!(d.abs() > 1e-3, "the test point must feel the rotation");
}

#[test]
fn curvature_closed_forms() {
    // Sphere: κ = 2/r on the surface (and 2/|p − c| on every level set).
    let r = 0.7;
    let s = Sdf::sphere(Vec3::new(0.3, 0.0, -0.2), r);
    for d in [Vec3::X, Vec3::new(1.0, -2.0, 0.5).normalize(), -Vec3::Z] {
        let p = Vec3::new(0.3, 0.0, -0.2) + d * r;
        assert!(close(s.curvature(p), 2.0 / r, 1e-4), "{}", s.curvature(p));
    }
    // Cylinder side: κ = 1/r.
    let cy = Sdf::cylinder(Vec3::ZERO, Vec3::new(0.0, 1.0, 1.0), 0.4, 2.0, 0.1);
    let side = Vec3::X * 0.4 + Vec3::new(0.0, 1.0, 1.0).normalize() * 0.3;
    assert!(close(cy.eval_f32(side), 0.0, 1e-6));
    assert!(
        close(cy.curvature(side), 1.0 / 0.4, 1e-3),
        "{}",
        cy.curvature(side)
    );
    // Torus: outer equator 1/r + 1/(R + r), inner equator 1/r − 1/(R − r).
    let (big, small) = (1.5, 0.4);
    let t = Sdf::torus(Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0), big, small);
    let outer = t.curvature(Vec3::new(big + small, 0.0, 0.0));
    let inner = t.curvature(Vec3::new(0.0, big - small, 0.0));
    assert!(
        close(outer, 1.0 / small + 1.0 / (big + small), 1e-3),
        "{outer}"
    );
    assert!(
        close(inner, 1.0 / small - 1.0 / (big - small), 1e-3),
        "{inner}"
    );
    // Normal curvature of the torus at the outer equator: along the tube 1/r, around the axis 1/(R + r).
    let p = Vec3::new(big + small, 0.0, 0.0);
    assert!(close(t.normal_curvature(p, Vec3::Z), 1.0 / small, 1e-3));
    assert!(close(
        t.normal_curvature(p, Vec3::Y),
        1.0 / (big + small),
        1e-3
    ));
}

#[test]
fn baked_sphere_grid_has_sphere_curvature() {
    let r = 1.0;
    let (lo, hi) = (Vec3::splat(-1.5), Vec3::splat(1.5));
    let g = Sdf::grid(bake(&Sdf::sphere(Vec3::ZERO, r), lo, hi, 64), lo, hi).unwrap();
    let mut rng = Rng::new(7);
    for _ in 0..50 {
        let dir = (rng.in_box(Vec3::splat(-1.0), Vec3::ONE)).normalize_or(Vec3::X);
        let p = project(&g, dir * r);
        // The spline is offset by about h²/(3r) (h = 3/63): the surface sits within 0.2% of r.
        assert!(close(p.length(), r, 2e-3), "|p| = {}", p.length());
        let k = g.curvature(p);
        assert!(close(k, 2.0 / r, 0.04 * 2.0 / r), "κ = {k} at {p}");
        assert!((g.normal(p) - p.normalize()).length() < 2e-3);
    }
    // The bound is taken patch by patch and per side. Outside a sampled distance its gradient is a unit
    // vector turning slowly from patch to patch, except beyond the box, where `φ` grows by the distance
    // to the face: `(1, ∂_b φ, ∂_c φ)` there, `√(1 + 2/3)` = 1.29 off a face where the gradient is
    // diagonal. Inside, the patch around the centre (where the gradient takes every direction) gives
    // the per-axis bound, √3.
    let l = g.lipschitz_sided();
    assert!((1.0..1.35).contains(&l.outside), "{l:?}");
    assert!((1.6..1.8).contains(&l.inside), "{l:?}");
}

#[test]
fn grid_lipschitz_covers_the_outside_extension() {
    // φ = x sampled on a grid: inside |∇φ| = 1, but beyond a y face ∇φ = (1, ±1, 0), |∇φ| = √2.
    let (lo, hi) = (Vec3::ZERO, Vec3::splat(3.0));
    let g = Sdf::grid(bake(&Sdf::plane(Vec3::X, 1.0), lo, hi, 4), lo, hi).unwrap();
    assert!(close(g.eval_f32(Vec3::new(2.5, 1.0, 1.0)), 1.5, 1e-5)); // linear fields reproduced
    assert!(close(g.eval_f32(Vec3::new(0.0, 1.0, 1.0)), -1.0, 1e-5)); // ... up to the faces
    let p = Vec3::new(2.0, 5.0, 1.0);
    assert!(close(g.gradient(p).length(), 2f32.sqrt(), 1e-4));
    assert!(g.lipschitz() >= 2f32.sqrt() && g.lipschitz() < 1.415);
    // The solid x < 1 reaches the grid faces: bounds grow by the depth of the face values.
    let b = g.bounds();
    assert!(b.min.x <= -1.0 + 1e-4, "{b:?}");
}

#[test]
fn smooth_union_blend_is_c2_and_lowers_by_k_over_6() {
    let k = 0.6;
    let a = Sdf::plane(Vec3::X, 0.0); // φ = x
    let b = Sdf::plane(-Vec3::X, 0.0); // φ = −x
    let u = Sdf::smooth_union(vec![a, b], k);
    // At x = 0 both are 0: lowered by k/6. Beyond |a − b| = 2|x| ≥ k, exactly the minimum.
    assert!(close(u.eval_f32(Vec3::ZERO), -k / 6.0, 1e-6));
    assert!(close(u.eval_f32(Vec3::new(0.31, 0.0, 0.0)), -0.31, 1e-6));
    // Second derivative along x continuous at the blend edge |x| = k/2 (C2): one-sided values agree.
    let d2 = |x: f32| u.hessian(Vec3::new(x, 0.0, 0.0)).2.x_axis.x;
    let e = 1e-4;
    assert!(
        close(d2(k / 2.0 - e), d2(k / 2.0 + e), 1e-2),
        "{} {}",
        d2(k / 2.0 - e),
        d2(k / 2.0 + e)
    );
    assert!(close(d2(-e), d2(e), 1e-3));
    // −|x| smoothed: d²/dx² = −(4/k)(1 − 2|x|/k), −4/k at the centre.
    assert!(close(d2(0.0), -4.0 / k, 1e-3), "{}", d2(0.0));
}

// ----- .npy ----------------------------------------------------------------------------------------

fn temp_path(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("implicit-psdr-sdf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn npy_bytes(version: u8, header: &str, data: &[u8]) -> Vec<u8> {
    let mut out = b"\x93NUMPY".to_vec();
    out.extend_from_slice(&[version, 0]);
    if version == 1 {
        out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    } else {
        out.extend_from_slice(&(header.len() as u32).to_le_bytes());
    }
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(data);
    out
}

fn f32_bytes(n: usize) -> Vec<u8> {
    (0..n)
        .flat_map(|i| (i as f32 * 0.25 - 1.0).to_le_bytes())
        .collect()
}

#[test]
fn npy_round_trip() {
    let grid = GridData {
        dims: [5, 6, 7],
        values: (0..210).map(|i| (i as f32).sin() * 3.0).collect(),
    };
    let path = temp_path("round_trip.npy");
    write_npy(&path, &grid).unwrap();
    assert_eq!(read_npy(&path).unwrap(), grid);
    // No temporary file left beside it.
    let dir = path.parent().unwrap();
    let leftovers: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp"))
        .collect();
    assert!(leftovers.is_empty());
    // Data layout: shape [nz, ny, nx], C order, x fastest: the first values are along x.
    let bytes = std::fs::read(&path).unwrap();
    let text = String::from_utf8_lossy(&bytes[10..128]);
    assert!(text.contains("'shape': (7, 6, 5)"), "{text}");
}

#[test]
fn npy_versions_2_and_float64_are_read() {
    let header = "{'descr': '<f4', 'fortran_order': False, 'shape': (4, 4, 5), }\n";
    let path = temp_path("v2.npy");
    std::fs::write(&path, npy_bytes(2, header, &f32_bytes(80))).unwrap();
    let g = read_npy(&path).unwrap();
    assert_eq!(g.dims, [5, 4, 4]);
    assert_eq!(g.values[3], 0.25 * 3.0 - 1.0);

    let header = "{'descr': '<f8', 'fortran_order': False, 'shape': (4, 4, 4), }\n";
    let data: Vec<u8> = (0..64)
        .flat_map(|i| (i as f64 * 0.5).to_le_bytes())
        .collect();
    std::fs::write(&path, npy_bytes(1, header, &data)).unwrap();
    assert_eq!(read_npy(&path).unwrap().values[63], 31.5);
}

#[test]
fn malformed_npy_files_are_errors() {
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("magic", b"PK\x03\x04 not numpy".to_vec(), "magic"),
        (
            "dtype",
            npy_bytes(
                1,
                "{'descr': '<i4', 'fortran_order': False, 'shape': (4, 4, 4), }",
                &f32_bytes(64),
            ),
            "dtype",
        ),
        (
            "big_endian",
            npy_bytes(
                1,
                "{'descr': '>f4', 'fortran_order': False, 'shape': (4, 4, 4), }",
                &f32_bytes(64),
            ),
            "dtype",
        ),
        (
            "ndim",
            npy_bytes(
                1,
                "{'descr': '<f4', 'fortran_order': False, 'shape': (16, 4), }",
                &f32_bytes(64),
            ),
            "3-D",
        ),
        (
            "fortran",
            npy_bytes(
                1,
                "{'descr': '<f4', 'fortran_order': True, 'shape': (4, 4, 4), }",
                &f32_bytes(64),
            ),
            "fortran",
        ),
        (
            "truncated",
            npy_bytes(
                1,
                "{'descr': '<f4', 'fortran_order': False, 'shape': (4, 4, 4), }",
                &f32_bytes(63),
            ),
            "truncated",
        ),
        (
            "small",
            npy_bytes(
                1,
                "{'descr': '<f4', 'fortran_order': False, 'shape': (4, 3, 4), }",
                &f32_bytes(48),
            ),
            "at least 4",
        ),
        (
            "header_cut",
            npy_bytes(
                1,
                "{'descr': '<f4', 'fortran_order': False, 'shape': (4, 4, 4), }",
                &[],
            )[..30]
                .to_vec(),
            "truncated",
        ),
        (
            "no_shape",
            npy_bytes(
                1,
                "{'descr': '<f4', 'fortran_order': False, }",
                &f32_bytes(64),
            ),
            "shape",
        ),
        (
            "nan",
            npy_bytes(
                1,
                "{'descr': '<f4', 'fortran_order': False, 'shape': (4, 4, 4), }",
                &(0..64)
                    .flat_map(|i| if i == 9 { f32::NAN } else { 0.0 }.to_le_bytes())
                    .collect::<Vec<u8>>(),
            ),
            "non-finite",
        ),
        ("empty", Vec::new(), "magic"),
    ];
    for (name, bytes, needle) in cases {
        let path = temp_path(&format!("bad_{name}.npy"));
        std::fs::write(&path, bytes).unwrap();
        match read_npy(&path) {
            Ok(_) => panic!("{name}: accepted"),
            Err(e) => {
                let msg = e.to_string();
                assert!(
                    matches!(e, implicit_psdr::Error::File { .. }),
                    "{name}: {msg}"
                );
                assert!(msg.contains(needle) && !msg.contains('\n'), "{name}: {msg}");
            }
        }
    }
    assert!(read_npy(&temp_path("does_not_exist.npy")).is_err());
    // Writing an invalid grid is refused, and leaves no file.
    let path = temp_path("invalid.npy");
    let bad = GridData {
        dims: [4, 4, 4],
        values: vec![0.0; 10],
    };
    assert!(write_npy(&path, &bad).is_err());
    assert!(!path.exists());
}

#[test]
fn bake_samples_on_the_box_faces() {
    let s = Sdf::sphere(Vec3::ZERO, 1.0);
    let (lo, hi) = (Vec3::new(-2.0, -1.0, -1.0), Vec3::new(2.0, 1.0, 1.5));
    let g = bake(&s, lo, hi, 33);
    assert_eq!(g.dims, [33, 17, 21]);
    assert!(close(g.values[0], s.eval_f32(lo), 1e-6));
    assert!(close(*g.values.last().unwrap(), s.eval_f32(hi), 1e-5));
    assert_eq!(implicit_psdr::sdf::bake_dims(lo, hi, 2), [4, 4, 4]);
}

/// Flat pieces only: planes, sharp boxes and hard CSG of them; anything rounded or curved is not.
#[test]
fn piecewise_flat_shapes() {
    let sharp = Sdf::cuboid([0.0, 0.0, 0.0], [1.0, 1.0, 1.0], 0.0);
    let rounded = Sdf::cuboid([0.0, 0.0, 0.0], [1.0, 1.0, 1.0], 0.1);
    let plane = Sdf::plane(Vec3::Y, 0.0);
    let ball = Sdf::sphere([0.0, 0.0, 0.0], 1.0);
    assert!(sharp.is_piecewise_flat());
    assert!(plane.is_piecewise_flat());
    assert!(Sdf::union(vec![sharp.clone(), plane.clone()]).is_piecewise_flat());
    assert!(!rounded.is_piecewise_flat());
    assert!(!ball.is_piecewise_flat());
    assert!(!Sdf::difference(vec![sharp.clone(), ball.clone()]).is_piecewise_flat());
    assert!(!Sdf::smooth_union(vec![sharp.clone(), plane], 0.1).is_piecewise_flat());
}

/// The patch-by-patch Lipschitz bounds hold on their sides: on grids of random values (no structure to
/// help them) at an iso-level, at random points inside the box and beyond its faces, edges and corners,
/// `|∇φ|` is at most the outside bound where `φ ≥ 0` and the inside bound where `φ ≤ 0`.
#[test]
fn grid_lipschitz_bounds_the_gradient_on_each_side() {
    let mut rng = Rng::new(11);
    for (trial, dims) in [[5, 4, 6], [8, 8, 8], [4, 9, 5]].into_iter().enumerate() {
        let n = dims[0] * dims[1] * dims[2];
        let values: Vec<f32> = (0..n)
            .map(|_| rng.in_box(Vec3::splat(-1.0), Vec3::ONE).x)
            .collect();
        let (lo, hi) = (Vec3::new(-1.0, -0.5, 0.0), Vec3::new(1.0, 0.7, 1.5));
        let mut g = Sdf::grid(GridData::new(dims, values, "random").unwrap(), lo, hi).unwrap();
        if let Sdf::Grid { level, .. } = &mut g {
            *level = Param::new(0.3);
        }
        let l = g.lipschitz_sided();
        let (mut outside, mut inside) = (0, 0);
        for k in 0..20000 {
            // Two thirds inside, one third up to half the box beyond it.
            let grow = if k % 3 == 0 { 0.5 } else { 0.0 };
            let size = hi - lo;
            let p = rng.in_box(lo - grow * size, hi + grow * size);
            let grad = g.gradient(p).length();
            let (bound, count) = if g.eval_f32(p) >= 0.0 {
                (l.outside, &mut outside)
            } else {
                (l.inside, &mut inside)
            };
            *count += 1;
            assert!(
                grad <= bound * (1.0 + 1e-4),
                "grid {trial}: |∇φ| = {grad} > {l:?} at {p}"
            );
        }
        assert!(outside > 1000 && inside > 1000, "{outside} {inside}");
    }
}

/// A grid's bounds are the cells that can hold its surface, not its whole (padded) box: for a sphere
/// of radius 0.8 baked over ±1.2 (cells 0.06 wide), the sphere's box grown by at most three cells
/// (the 4×4×4 control points of a cell near the surface straddle the level up to two cells away).
/// That the bounds hold every point of the solid is the conformance suite's `bounds_contain_the_solid`.
#[test]
fn grid_bounds_hug_the_surface() {
    let (c, r, cell) = (Vec3::new(0.05, -0.1, 0.0), 0.8, 2.4 / 39.0);
    let b = baked_sphere().bounds();
    for a in 0..3 {
        let (lo, hi) = (c[a] - r, c[a] + r);
        assert!(
            b.min[a] <= lo && b.max[a] >= hi,
            "axis {a}: {b:?} does not hold the sphere"
        );
        assert!(
            lo - b.min[a] <= 3.0 * cell && b.max[a] - hi <= 3.0 * cell,
            "axis {a}: {b:?} is not within three cells of the sphere's box"
        );
    }
}

/// A transform keeps its angle's cosine and sine; an angle set in place afterwards (as parameters are)
/// must not be evaluated with the old ones.
#[test]
fn transform_angle_set_in_place_is_not_served_stale() {
    let child = Sdf::cuboid(Vec3::ZERO, Vec3::new(1.0, 0.5, 0.3), 0.1);
    let axis = Vec3::new(0.0, 0.6, 0.8);
    let mut moved = Sdf::transform(child.clone(), [0.1, 0.2, 0.0], axis, 25.0, 1.3);
    if let Sdf::Transform { angle, .. } = &mut moved {
        angle.value = 40.0;
    }
    let fresh = Sdf::transform(child, [0.1, 0.2, 0.0], axis, 40.0, 1.3);
    for p in [
        Vec3::new(1.1, 0.7, -0.4),
        Vec3::new(-0.3, 0.2, 0.9),
        Vec3::new(0.5, -0.8, 0.1),
    ] {
        assert_eq!(moved.eval_f32(p), fresh.eval_f32(p), "at {p}");
    }
    assert_eq!(moved.refreshed(), fresh);
}
