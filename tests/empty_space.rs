//! Empty-space skipping of grid shapes: the cells it skips hold no surface, the neighbourhood Lipschitz
//! bounds it steps with hold, and tracing finds the same hits with and without it; the boxes its cells
//! prove empty hold no surface, and the silhouette culling that uses them keeps the same boxes and
//! extracts the same curves as interval arithmetic alone.
//!
//! The shape is a baked union of two spheres (the kink of its outside distance between the lobes is where
//! a grid's bound is steepest), rotated, scaled and moved away from the origin.

use glam::Vec3;
use implicit_psdr::Param3;
use implicit_psdr::bsdf::Bsdf;
use implicit_psdr::integrator::silhouette_boxes::{BoxClass, classify_box, silhouette_boxes};
use implicit_psdr::integrator::silhouette_curve::{CurveOptions, extract_silhouette};
use implicit_psdr::math::{Aabb, Ray};
use implicit_psdr::sampler::Sampler;
use implicit_psdr::scene::Shape;
use implicit_psdr::sdf::{BoxCells, EmptySpace, Sdf, bake};
use implicit_psdr::trace::{ShapeTrace, TraceSettings, all_crossings_skipping};

fn blob() -> Shape {
    let lobes = Sdf::union(vec![
        Sdf::sphere([-0.5, 0.0, 0.0], 0.7),
        Sdf::sphere([0.55, 0.2, 0.1], 0.55),
    ]);
    let (lo, hi) = (Vec3::new(-1.6, -1.1, -1.1), Vec3::new(1.5, 1.1, 1.1));
    let grid = Sdf::grid(bake(&lobes, lo, hi, 28), lo, hi).expect("valid grid");
    let sdf = Sdf::transform(
        grid,
        [40.0, -25.0, 10.0],
        Vec3::new(1.0, 2.0, 3.0),
        37.0,
        1.7,
    );
    Shape::new(
        "blob",
        sdf,
        Bsdf::Diffuse {
            albedo: Param3::new([0.5; 3]),
        },
    )
}

fn unit_vector(s: &mut Sampler) -> Vec3 {
    let u = s.next_2d();
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let p = 2.0 * std::f32::consts::PI * u.y;
    Vec3::new(r * p.cos(), r * p.sin(), z)
}

/// A point of the shape's bounds, uniformly.
fn point_in_bounds(shape: &Shape, s: &mut Sampler) -> Vec3 {
    let b = shape.bounds;
    b.min + (b.max - b.min) * Vec3::new(s.next_1d(), s.next_1d(), s.next_1d())
}

#[test]
fn skipped_cells_hold_no_surface() {
    let shape = blob();
    let space = shape
        .empty_space
        .as_deref()
        .expect("a grid under transforms");
    let mut s = Sampler::new(11, 0, 0, 0);
    let (mut skipped, mut missed) = (0, 0);
    for _ in 0..3000 {
        // Rays from outside the bounds and from inside them (some inside the shape), towards the bounds.
        let centre = (shape.bounds.min + shape.bounds.max) * 0.5;
        let o = if s.next_1d() < 0.5 {
            centre + unit_vector(&mut s) * 6.0
        } else {
            point_in_bounds(&shape, &mut s)
        };
        let d = (point_in_bounds(&shape, &mut s) - o).normalize();
        let ray = Ray::new(o, d);
        let t_max = 12.0;
        let end = match space.first_candidate(&ray, 0.0, t_max) {
            Some(t) => t,
            None => {
                missed += 1;
                t_max
            }
        };
        if end > 0.0 {
            skipped += 1;
        }
        let first = shape.sdf.eval_f32(ray.o);
        for k in 0..=400 {
            let t = end * k as f32 / 400.0;
            let phi = shape.sdf.eval_f32(ray.at(t));
            assert!(
                phi * first > 0.0,
                "ray {ray:?}: φ changes sign at t = {t} before the candidate {end} (φ(0) = {first})"
            );
        }
    }
    // The test means something only if rays do skip, and some skip the whole shape.
    assert!(
        skipped > 1000 && missed > 100,
        "skipped {skipped}, missed {missed}"
    );
}

#[test]
fn neighbourhood_bounds_hold_within_a_cell() {
    let shape = blob();
    let space = shape.empty_space.as_deref().unwrap();
    let mut s = Sampler::new(12, 0, 0, 0);
    let (mut checked, mut tightest) = (0, 0.0f32);
    for _ in 0..20000 {
        let p = point_in_bounds(&shape, &mut s);
        // A ray starting at `p` finds its own cell when that cell straddles the surface.
        let ray = Ray::new(p, unit_vector(&mut s));
        let Some(cell) = space.first_candidate_lattice(&space.lattice_ray(&ray), 0.0, 1.0) else {
            continue;
        };
        if cell.t != 0.0 {
            continue;
        }
        let q = p + unit_vector(&mut s) * space.cell_size * s.next_1d();
        let (fp, fq) = (shape.sdf.eval_f32(p), shape.sdf.eval_f32(q));
        // The side's bound holds on segments that stay on that side.
        let side = if fp > 0.0 && fq > 0.0 {
            0
        } else if fp < 0.0 && fq < 0.0 {
            1
        } else {
            continue;
        };
        let same_side = (1..16).all(|k| {
            let v = shape.sdf.eval_f32(p.lerp(q, k as f32 / 16.0));
            (v > 0.0) == (side == 0)
        });
        if !same_side || cell.inv_lipschitz[side] == 0.0 {
            continue;
        }
        let bound = 1.0 / cell.inv_lipschitz[side];
        let slope = (fp - fq).abs() / (p - q).length();
        // Rounding of two values near 1 in f32 over a short segment.
        let noise = 4.0 * f32::EPSILON * (fp.abs() + fq.abs() + 1.0) / (p - q).length();
        assert!(
            slope <= bound + noise,
            "slope {slope} above the neighbourhood bound {bound} between {p} and {q}"
        );
        tightest = tightest.max(slope / bound);
        checked += 1;
    }
    // Enough pairs, and bounds that are not loose everywhere (the check would pass for any huge bound).
    assert!(checked > 2000, "checked {checked}");
    assert!(tightest > 0.8, "largest slope / bound {tightest}");
}

/// Under a transform, and without one (where the marcher takes the slope from the same pass over the
/// taps as the value wherever a search starts or resumes).
#[test]
fn tracing_finds_the_same_hits_with_and_without_skipping() {
    for shape in [blob(), aligned_blob()] {
        same_hits_with_and_without_skipping(shape);
    }
}

fn same_hits_with_and_without_skipping(shape: Shape) {
    let mut plain = shape.clone();
    plain.empty_space = None;
    let settings = TraceSettings {
        eps: 1e-4 * shape.bounds.extent().min_element(),
        ..TraceSettings::default()
    };
    let mut s = Sampler::new(13, 0, 0, 0);
    let centre = (shape.bounds.min + shape.bounds.max) * 0.5;
    let (mut hits, mut grazes, mut leaving) = (0, 0, 0);
    for i in 0..8000 {
        // Rays from afar, then rays leaving the surface where one of them hit (shadow and bounce rays).
        let mut ray = Ray::new(centre + unit_vector(&mut s) * 6.0, Vec3::ZERO);
        ray.d = (point_in_bounds(&shape, &mut s) - ray.o).normalize();
        if i % 2 == 1
            && let ShapeTrace::Hit(t) = plain.trace(&ray, 0.0, 12.0, &settings)
        {
            let p = ray.at(t);
            let n = shape.normal(p);
            let w = unit_vector(&mut s);
            let w = if w.dot(n) < 0.0 { -w } else { w };
            ray = Ray::new(p + n * 4.0 * settings.eps_at_point(p), w);
            leaving += 1;
        }
        let a = shape.trace(&ray, 0.0, 12.0, &settings);
        let b = plain.trace(&ray, 0.0, 12.0, &settings);
        match (a, b) {
            (ShapeTrace::Hit(ta), ShapeTrace::Hit(tb)) => {
                let cos = shape.normal(ray.at(tb)).dot(ray.d).abs();
                let tolerance = settings.eps_at_point(ray.at(tb)) / cos.max(1e-3);
                assert!(
                    (ta - tb).abs() <= tolerance,
                    "ray {ray:?}: hit at {ta} with skipping, {tb} without (|cos| {cos})"
                );
                hits += 1;
            }
            (ShapeTrace::Miss, ShapeTrace::Miss) => {}
            (ShapeTrace::Hit(t), ShapeTrace::Miss) | (ShapeTrace::Miss, ShapeTrace::Hit(t)) => {
                // Only a graze may be found by one and stepped over by the other.
                let cos = shape.normal(ray.at(t)).dot(ray.d).abs();
                assert!(
                    cos < 0.05,
                    "ray {ray:?}: one hit at {t} (|cos| {cos}), one miss"
                );
                grazes += 1;
            }
            other => panic!("ray {ray:?}: {other:?}"),
        }
    }
    assert!(
        hits > 800 && leaving > 800,
        "hits {hits}, leaving rays {leaving}"
    );
    eprintln!("hits {hits}, leaving {leaving}, grazes {grazes}");
    assert!(grazes <= 4, "{grazes} grazes found by one tracer only");
}

/// Every crossing along a line, as the surface sampler traces them (axis-aligned lines across the
/// bounds, in the shape's frame) and along random lines through the bounds: the same crossings with and
/// without skipping (both sides of the surface are skipped), each within the tracing tolerance.
#[test]
fn all_crossings_are_the_same_with_and_without_skipping() {
    let shape = blob();
    let space = shape.empty_space.as_deref();
    assert!(space.is_some(), "the blob skips");
    let settings = TraceSettings {
        eps: 1e-4 * shape.bounds.extent().min_element(),
        ..TraceSettings::default()
    };
    let b = shape.bounds;
    let pad = 0.01 * b.extent().max_element();
    let mut s = Sampler::new(17, 0, 0, 0);
    let (mut crossings, mut lines_with_two) = (0, 0);
    for i in 0..3000 {
        let mut o = point_in_bounds(&shape, &mut s);
        let (d, length) = if i % 2 == 0 {
            let a = i / 2 % 3;
            o[a] = b.min[a] - pad;
            (Vec3::AXES[a], b.extent()[a] + 2.0 * pad)
        } else {
            let d = unit_vector(&mut s);
            o -= d * 4.0;
            (d, 8.0)
        };
        let ray = shape.local_ray(&Ray::new(o, d));
        let with = all_crossings_skipping(
            &shape.sdf,
            shape.lipschitz,
            space,
            &ray,
            0.0,
            length,
            &settings,
        );
        let without = all_crossings_skipping(
            &shape.sdf,
            shape.lipschitz,
            None,
            &ray,
            0.0,
            length,
            &settings,
        );
        assert_eq!(with.1, None, "budget exhausted along {ray:?}");
        assert_eq!(without.1, None, "budget exhausted along {ray:?}");
        assert_eq!(
            with.0.len(),
            without.0.len(),
            "line {ray:?}: {:?} with skipping, {:?} without",
            with.0,
            without.0
        );
        for (&ta, &tb) in with.0.iter().zip(&without.0) {
            let p = ray.at(tb) + (o - ray.o);
            let cos = shape.normal(p).dot(d).abs();
            let tolerance = settings.eps_at_point(p) / cos.max(1e-3);
            assert!(
                (ta - tb).abs() <= tolerance,
                "line {ray:?}: crossing at {ta} with skipping, {tb} without (|cos| {cos})"
            );
        }
        crossings += with.0.len();
        lines_with_two += usize::from(with.0.len() >= 2);
    }
    assert!(
        crossings > 1000 && lines_with_two > 500,
        "crossings {crossings}, lines crossing twice or more {lines_with_two}"
    );
}

#[test]
fn only_grids_whose_surface_stays_in_their_box_skip() {
    assert!(blob().empty_space.is_some());
    assert!(EmptySpace::of(&Sdf::sphere([0.0; 3], 1.0)).is_none());
    // A grid baked too tight for its surface (its faces dip below the level): no skipping.
    let (lo, hi) = (Vec3::splat(-0.5), Vec3::splat(0.5));
    let grid = Sdf::grid(bake(&Sdf::sphere([0.0; 3], 1.0), lo, hi, 8), lo, hi).unwrap();
    assert!(EmptySpace::of(&grid).is_none());
}

/// A random box inside the shape's bounds, from a tenth of a cell to about ten cells wide.
fn box_in_bounds(shape: &Shape, s: &mut Sampler) -> Aabb {
    let cell = shape.empty_space.as_deref().expect("a grid").cell_size;
    let half = cell * 0.05 * 100f32.powf(s.next_1d());
    let c = point_in_bounds(shape, s);
    let h = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * half + Vec3::splat(0.1 * half);
    Aabb::new(c - h, c + h)
}

#[test]
fn boxes_of_empty_cells_hold_no_surface() {
    let shape = blob();
    let space = shape.empty_space.as_deref().expect("a grid");
    let mut s = Sampler::new(13, 0, 0, 0);
    let mut counts = [0usize; 3];
    for _ in 0..3000 {
        let b = box_in_bounds(&shape, &mut s);
        let cells = space.box_cells(&b);
        counts[cells as usize] += 1;
        if cells != BoxCells::Empty {
            continue;
        }
        // φ keeps one sign over a 9 × 9 × 9 lattice of the box's points, faces and corners included.
        let at = |i: usize, j: usize, k: usize| {
            let f = Vec3::new(i as f32, j as f32, k as f32) / 8.0;
            shape.sdf.eval_f32(b.min + (b.max - b.min) * f)
        };
        let first = at(0, 0, 0);
        for k in 0..9 {
            for j in 0..9 {
                for i in 0..9 {
                    let phi = at(i, j, k);
                    assert!(phi * first > 0.0, "box {b:?}: φ = {phi} against {first}");
                }
            }
        }
    }
    // Boxes of every kind: empty, next to the surface, reaching out of the lattice.
    assert!(counts.iter().all(|&n| n > 200), "{counts:?}");
}

/// The blob's grid without its transform, moved by the shape's translation: lattice-aligned boxes.
fn aligned_blob() -> Shape {
    let blob = blob();
    let Sdf::Transform { child, .. } = &blob.sdf else {
        panic!("the blob is a transformed grid");
    };
    Shape::translated(
        "aligned",
        (**child).clone(),
        blob.bsdf.clone(),
        Param3::new([3.0, -2.0, 1.5]),
    )
}

/// Where the cell map proves a box empty, interval arithmetic (which encloses a rotated box's image
/// in the lattice more loosely) may keep it: the only difference allowed, and the extracted curve is
/// the same. Lattice-aligned, the kept boxes are the same too.
#[test]
fn silhouette_culling_is_the_same_with_and_without_the_cell_map() {
    let mut s = Sampler::new(17, 0, 0, 0);
    for (shape, aligned) in [(blob(), false), (aligned_blob(), true)] {
        let plain = Shape {
            empty_space: None,
            enclosures: None,
            ..shape.clone()
        };
        let space = shape.empty_space.clone().expect("a grid");
        let t = shape.translate.value();
        let centre = (shape.bounds.min + shape.bounds.max) * 0.5;
        let radius = (shape.bounds.max - shape.bounds.min).length();
        let mut differ = 0;
        for _ in 0..4 {
            let eye = centre + unit_vector(&mut s) * 2.0 * radius;
            for _ in 0..500 {
                let b = box_in_bounds(&shape, &mut s);
                let (got, want) = (classify_box(&shape, eye, &b), classify_box(&plain, eye, &b));
                if got != want {
                    differ += 1;
                    let local = Aabb::new(b.min - t, b.max - t);
                    assert!(
                        got == BoxClass::NoSurface && space.box_cells(&local) == BoxCells::Empty,
                        "box {b:?} seen from {eye}: {got:?} against {want:?}"
                    );
                }
            }
            let (with, without) = (
                silhouette_boxes(&shape, eye, 6, 0.0).unwrap(),
                silhouette_boxes(&plain, eye, 6, 0.0).unwrap(),
            );
            assert!(with.iter().all(|b| without.contains(b)));
            if aligned {
                assert_eq!(with, without);
            }
            let options = CurveOptions::default();
            let curve = extract_silhouette(&shape, eye, &options).unwrap();
            let reference = extract_silhouette(&plain, eye, &options).unwrap();
            assert!(curve.polyline.segments.len() > 50);
            assert_eq!(curve.polyline.points, reference.polyline.points);
            assert_eq!(curve.polyline.segments, reference.polyline.segments);
            // A second extraction reads the memo's enclosures: the same curve.
            assert_eq!(curve, extract_silhouette(&shape, eye, &options).unwrap());
        }
        assert!(aligned || differ > 0, "the rotated grid's boxes all agree");
        assert!(
            !aligned || differ == 0,
            "{differ} lattice-aligned boxes differ"
        );
    }
}
