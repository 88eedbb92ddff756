//! Culling a CSG node's children (a hierarchy over their boxes) against evaluating every child: the
//! same values bit for bit, with the same gradients and Hessians, on many random points (inside, outside,
//! far away, on and next to the children's surfaces) for unions, differences, intersections and smooth
//! unions of balls, boxes, grids, transforms and nested CSG; and the same image, derivative images and
//! reverse-mode gradient of a scene whose one shape is a union of 200 balls, hard or smooth.

mod common;

use common::SplitMix;
use glam::Vec3;
use implicit_psdr::bsdf::Bsdf;
use implicit_psdr::film::Image;
use implicit_psdr::integrator::{
    DiffOptions, GradientLayout, IntegratorKind, RenderOptions, render, render_derivatives,
    render_gradient,
};
use implicit_psdr::scene::{Scene, Shape};
use implicit_psdr::sdf::{GridData, Sdf};

/// A small grid sampling a ball of radius `r` at `c` (a sampled distance, not an exact one inside).
fn grid_ball(c: Vec3, r: f32) -> Sdf {
    let n = 8;
    let h = 2.0 * (r + 0.1);
    let lo = c - Vec3::splat(r + 0.1);
    let mut values = Vec::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let p = lo + Vec3::new(x as f32, y as f32, z as f32) * (h / (n - 1) as f32);
                values.push((p - c).length() - r);
            }
        }
    }
    let data = GridData {
        dims: [n, n, n],
        values,
    };
    Sdf::grid(data, lo, lo + Vec3::splat(h)).unwrap()
}

/// A random leaf: a ball, a rounded or sharp box, a torus, a grid or a transformed cylinder.
fn leaf(rng: &mut SplitMix, half: f32) -> Sdf {
    let c = rng.point(half);
    let s = rng.range(0.1, 0.4);
    match (rng.next() * 6.0) as u32 {
        0 | 1 => Sdf::sphere(c.to_array(), s),
        2 => Sdf::cuboid(
            c.to_array(),
            [s, rng.range(0.1, 0.4), rng.range(0.1, 0.4)],
            if rng.next() < 0.5 { 0.0 } else { 0.05 },
        ),
        3 => Sdf::torus(c.to_array(), rng.direction(), s, s * 0.3),
        4 => grid_ball(c, s),
        _ => Sdf::transform(
            Sdf::cylinder([0.0; 3], Vec3::Z, s, s * 1.5, 0.02),
            c.to_array(),
            rng.direction(),
            rng.range(0.0, 180.0),
            rng.range(0.5, 2.0),
        ),
    }
}

/// The node with culling turned off: what evaluating every child gives.
fn brute(sdf: &Sdf) -> Sdf {
    let mut copy = sdf.clone();
    copy.set_culling(false);
    copy
}

/// Points to test `sdf` at: random ones in and around `half`, far ones, and ones on and next to the
/// surfaces of `leaves` (a child's surface point, moved a little in and out).
fn points(rng: &mut SplitMix, half: f32, leaves: &[Sdf], n: usize) -> Vec<Vec3> {
    let mut out = Vec::new();
    for _ in 0..n {
        out.push(rng.point(half * 1.3));
        out.push(rng.direction() * rng.range(2.0, 50.0) * half);
    }
    for l in leaves {
        let c = l.bounds().center();
        for _ in 0..4 {
            // March from the centre outward to the child's surface along a random direction.
            let d = rng.direction();
            let (mut t0, mut t1) = (0.0f32, 2.0 * l.bounds().extent().max_element());
            for _ in 0..40 {
                let t = 0.5 * (t0 + t1);
                if l.eval_f32(c + d * t) < 0.0 {
                    t0 = t;
                } else {
                    t1 = t;
                }
            }
            for e in [0.0, 1e-6, -1e-6, 1e-3, -1e-3, 0.05] {
                out.push(c + d * (t1 + e));
            }
        }
    }
    out
}

/// The bits of `x`, every NaN the same: Rust leaves a NaN's sign and payload unspecified (the compiler may
/// swap a product's operands, and x86 keeps the first NaN's).
fn bits(x: f32) -> u32 {
    if x.is_nan() {
        f32::NAN.to_bits()
    } else {
        x.to_bits()
    }
}

/// Values, gradients and Hessians of `sdf` and its brute-force copy agree bit for bit at every point.
fn same_everywhere(sdf: &Sdf, pts: &[Vec3]) -> usize {
    let plain = brute(sdf);
    // Compared as text: a NaN parameter is not equal to itself.
    assert_eq!(format!("{plain:?}"), format!("{sdf:?}"));
    let mut inside = 0;
    for &p in pts {
        let (a, b) = (sdf.eval_f32(p), plain.eval_f32(p));
        assert_eq!(bits(a), bits(b), "value at {p}: {a} vs {b}");
        inside += usize::from(a < 0.0);
        let (ga, gb) = (sdf.gradient(p), plain.gradient(p));
        assert_eq!(
            ga.to_array().map(bits),
            gb.to_array().map(bits),
            "gradient at {p}"
        );
        let (fa, fb) = (
            sdf.eval_faces::<f32>(p.into()),
            plain.eval_faces::<f32>(p.into()),
        );
        assert_eq!(bits(fa), bits(fb), "face field at {p}");
        let (ha, hb) = (sdf.hessian(p), plain.hessian(p));
        assert_eq!(
            ha.2.to_cols_array().map(bits),
            hb.2.to_cols_array().map(bits),
            "Hessian at {p}"
        );
    }
    inside
}

fn leaves(rng: &mut SplitMix, n: usize, half: f32) -> Vec<Sdf> {
    (0..n).map(|_| leaf(rng, half)).collect()
}

#[test]
fn unions_of_many_children_give_the_plain_values() {
    let mut rng = SplitMix(1);
    for (n, half) in [(9, 1.0), (40, 2.0), (300, 4.0), (100, 1e3)] {
        let kids = leaves(&mut rng, n, half);
        let union = Sdf::union(kids.clone());
        assert!(matches!(&union, Sdf::Union(c) if c.is_culled()));
        let pts = points(&mut rng, half, &kids, 200);
        let inside = same_everywhere(&union, &pts);
        assert!(inside > 20, "{inside} points inside of {}", pts.len());
    }
}

#[test]
fn smooth_unions_of_many_children_give_the_plain_values() {
    let mut rng = SplitMix(5);
    // Sparse and dense children, blends small and large against their spacing (the dense ones put more
    // children within the blend of a point than the walk's heap holds), and no blend (the hard union).
    for (n, half, k) in [
        (9, 1.0, 0.1),
        (40, 2.0, 0.3),
        (300, 4.0, 0.05),
        (300, 0.5, 0.6),
        (150, 1.0, 2.0),
        (100, 1e3, 1.0),
        (50, 2.0, 0.0),
        (50, 2.0, -1.0),
    ] {
        let kids = leaves(&mut rng, n, half);
        let blend = Sdf::smooth_union(kids.clone(), k);
        assert!(matches!(&blend, Sdf::SmoothUnion { children: c, .. } if c.is_culled()));
        let pts = points(&mut rng, half, &kids, 200);
        let inside = same_everywhere(&blend, &pts);
        assert!(inside > 20, "{inside} points inside of {}", pts.len());
    }
    // Unbounded and NaN children: a plane first (no box), planes among the children (no box, never
    // skipped), a child whose value is NaN.
    let mut kids = leaves(&mut rng, 30, 2.0);
    kids.insert(0, Sdf::plane(Vec3::Y, -1.5));
    kids.insert(17, Sdf::plane(Vec3::new(0.6, 0.0, 0.8), 1.0));
    kids.push(Sdf::sphere([0.0, f32::NAN, 0.0], 0.3));
    kids.push(Sdf::plane(Vec3::X, 0.5));
    let pts = points(&mut rng, 2.0, &kids[1..17], 100);
    same_everywhere(&Sdf::smooth_union(kids, 0.2), &pts);
}

#[test]
fn differences_of_many_children_give_the_plain_values() {
    let mut rng = SplitMix(2);
    for (n, half) in [(10, 1.0), (60, 2.0)] {
        let mut kids = leaves(&mut rng, n, half);
        kids[0] = Sdf::cuboid([0.0; 3], [half; 3], 0.1);
        let diff = Sdf::difference(kids.clone());
        let pts = points(&mut rng, half, &kids, 300);
        let inside = same_everywhere(&diff, &pts);
        assert!(inside > 20, "{inside} points inside");
    }
}

#[test]
fn nested_csg_and_unculled_kinds_give_the_plain_values() {
    let mut rng = SplitMix(3);
    let half = 2.0;
    // Unions of unions, smooth unions and intersections of many children (these two evaluated in full,
    // their culling boxes used by the outer union), a plane (never culled) and transformed groups.
    let group = |rng: &mut SplitMix| Sdf::union(leaves(rng, 12, half));
    let mut kids: Vec<Sdf> = (0..6).map(|_| group(&mut rng)).collect();
    kids.push(Sdf::smooth_union(leaves(&mut rng, 12, half), 0.2));
    kids.push(Sdf::intersection(vec![
        Sdf::sphere([0.5, 0.5, 0.5], 0.8),
        Sdf::cuboid([0.6, 0.4, 0.5], [0.5, 0.5, 0.5], 0.0),
    ]));
    kids.push(Sdf::intersection(leaves(&mut rng, 10, 0.3)));
    kids.push(Sdf::transform(
        group(&mut rng),
        [1.0, 0.0, 0.0],
        Vec3::Y,
        30.0,
        0.7,
    ));
    kids.push(Sdf::difference(leaves(&mut rng, 11, half)));
    kids.push(Sdf::named("n", group(&mut rng)));
    kids.push(Sdf::plane(Vec3::Y, -3.0));
    let union = Sdf::union(kids.clone());
    let diff = Sdf::difference({
        let mut d = vec![Sdf::cuboid([0.0; 3], [half; 3], 0.0)];
        d.extend(kids.iter().cloned());
        d
    });
    let mut surface_leaves = Vec::new();
    for k in &kids {
        match k {
            Sdf::Union(c) | Sdf::SmoothUnion { children: c, .. } => {
                surface_leaves.extend(c.iter().cloned())
            }
            other => surface_leaves.push(other.clone()),
        }
    }
    surface_leaves.pop(); // the plane has no centre to march from
    let pts = points(&mut rng, half, &surface_leaves, 300);
    assert!(same_everywhere(&union, &pts) > 20);
    same_everywhere(&diff, &pts);
    same_everywhere(&Sdf::smooth_union(kids.clone(), 0.1), &pts);
    same_everywhere(&Sdf::intersection(kids), &pts);
}

#[test]
fn parameters_set_in_place_and_refreshed_keep_the_values_right() {
    let mut rng = SplitMix(4);
    let kids: Vec<Sdf> = (0..50)
        .map(|i| Sdf::named(format!("b{i}"), Sdf::sphere(rng.point(2.0).to_array(), 0.2)))
        .collect();
    let mut union = Sdf::union(kids);
    let p = Vec3::new(0.0, 0.0, 30.0);
    // Move one ball next to `p` by mutable access: the hierarchy is dropped, values stay right.
    if let Sdf::Union(c) = &mut union {
        c[7] = Sdf::sphere([0.0, 0.0, 29.0], 0.5);
        assert!(!c.is_culled());
    }
    assert_eq!(union.eval_f32(p), 0.5);
    let union = union.refreshed();
    assert!(matches!(&union, Sdf::Union(c) if c.is_culled()));
    assert_eq!(union.eval_f32(p), 0.5);
}

/// `n` balls of radius 0.12 as one union shape named `balls` (smooth with blend `k` when given) above
/// a floor, under a rectangle light.
fn ball_union(n: usize, k: Option<f32>) -> Scene {
    let mut rng = SplitMix(9);
    let kids: Vec<Sdf> = (0..n)
        .map(|i| {
            Sdf::named(
                format!("b{i}"),
                Sdf::sphere(rng.point(1.5).to_array(), 0.12),
            )
        })
        .collect();
    let diffuse = || Bsdf::Diffuse {
        albedo: [0.6, 0.6, 0.6].into(),
    };
    let shapes = vec![
        Shape::new(
            "balls",
            match k {
                Some(k) => Sdf::smooth_union(kids, k),
                None => Sdf::union(kids),
            },
            diffuse(),
        ),
        Shape::new(
            "floor",
            Sdf::cuboid([0.0, -2.0, 0.0], [10.0, 0.5, 10.0], 0.25),
            diffuse(),
        ),
    ];
    let json = r#"{"name": "light", "type": "rectangle", "center": [1.5, 4, 2], "normal": [0, -1, 0],
        "u": [1, 0, 0], "size": [1, 1], "radiance": [40, 40, 40]}"#;
    let light = common::deriv::scene_json(&format!(
        r#"{{"camera": {{"origin": [0, 3, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 45,
              "width": 24, "height": 24}},
            "integrator": {{"type": "direct"}}, "shapes": [], "emitters": [{json}]}}"#
    ));
    Scene::new(
        light.camera.clone(),
        IntegratorKind::Direct,
        4,
        shapes,
        light.emitters.clone(),
    )
}

#[test]
fn a_union_of_200_balls_renders_the_same_image_and_derivative_culled() {
    for k in [None, Some(0.1)] {
        let with = ball_union(200, k);
        assert!(matches!(&with.shapes[0].sdf,
            Sdf::Union(c) | Sdf::SmoothUnion { children: c, .. } if c.is_culled()));
        let mut without = with.clone();
        without.shapes[0].sdf = brute(&with.shapes[0].sdf);
        let options = RenderOptions {
            spp: 4,
            seed: 3,
            progress: Default::default(),
        };
        let (a, _) = render(&with, &options);
        let (b, _) = render(&without, &options);
        assert_eq!(a.rgb, b.rgb, "images differ ({k:?})");
        assert!(a.rgb.iter().any(|&v| v > 0.0));
        // Selecting parameters refreshes the scene: the hierarchy is rebuilt, the derivatives the same.
        let mut names = vec!["b0.radius", "b3.center.x"];
        if k.is_some() {
            names.push("balls.k");
        }
        let selection = with.select(&names).unwrap();
        let diff = DiffOptions {
            render: options.clone(),
            ..DiffOptions::default()
        };
        let da = render_derivatives(&with, &selection, &diff).unwrap();
        let db = render_derivatives(&without, &without.select(&names).unwrap(), &diff).unwrap();
        assert_eq!(da.image.rgb, db.image.rgb);
        for (x, y) in da.total().iter().zip(db.total()) {
            assert_eq!(x.rgb, y.rgb, "derivative images differ ({k:?})");
            assert!(
                x.rgb.iter().any(|&v| v != 0.0),
                "a zero derivative image ({k:?})"
            );
        }
        // Reverse mode (its own scalar type through the same culled evaluation): the same gradient.
        let params: Vec<String> = names.iter().map(|n| n.to_string()).collect();
        let mut adjoint = Image::new(a.width, a.height);
        for (j, v) in adjoint.rgb.iter_mut().enumerate() {
            *v = ((j * 7919) % 13) as f32 / 6.0 - 1.0;
        }
        let gradient = |scene: &Scene| {
            let layout = GradientLayout::select(scene, &params, &[]).unwrap();
            render_gradient(scene, &layout, &adjoint, &diff).unwrap()
        };
        let (ga, gb) = (gradient(&with), gradient(&without));
        for (x, y) in [
            (&ga.interior, &gb.interior),
            (&ga.primary, &gb.primary),
            (&ga.secondary, &gb.secondary),
        ] {
            assert_eq!(x, y, "reverse-mode gradients differ ({k:?})");
        }
        assert!(ga.interior.iter().all(|&v| v != 0.0 && v.is_finite()));
    }
}
