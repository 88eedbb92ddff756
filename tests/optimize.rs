//! Inverse rendering of named parameters: from a start 10–20% off, a sphere's centre and radius and a
//! light's position converge to the values that rendered the target.

use implicit_psdr::integrator::{BoundaryBudget, Loss};
use implicit_psdr::optimize::{
    AdamOptions, Decay, ImageScale, Optimization, ResolutionPower, Settings, Terms, View,
    render_targets,
};
use implicit_psdr::scene::{Scene, parse};

/// A ball on a floor under a rectangle light and a dim sky, 32×32. The ball sits at `x = 0.5` rather
/// than near the origin: a coordinate's relative error depends on where the origin is, and at 0.5 the
/// tolerance of 2% is 0.01 scene units (1.25% of the radius).
fn scene() -> Scene {
    let json = r#"{
      "camera": {"origin": [0, 2.5, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 45,
                 "width": 32, "height": 32, "filter": "tent"},
      "integrator": {"type": "direct"},
      "shapes": [
        {"name": "ball", "sdf": {"type": "sphere", "center": [0.5, 0, 0], "radius": 0.8},
         "bsdf": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}},
        {"name": "floor", "sdf": {"type": "box", "center": [0, -1.3, 0], "half_size": [4, 0.5, 4],
         "rounding": 0.1}, "bsdf": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}
      ],
      "emitters": [
        {"name": "light", "type": "rectangle", "center": [1.5, 4, 1], "normal": [0, -1, 0],
         "u": [1, 0, 0], "size": [1.5, 1.5], "radiance": [25, 25, 25]},
        {"name": "sky", "type": "constant", "radiance": [0.1, 0.1, 0.1]}
      ]
    }"#;
    parse(json, std::path::Path::new(".")).unwrap()
}

/// Settings with every option off (constant rates, no refinement, redistancing, averaging or
/// reduced images), nothing to optimise, 4 spp and seed 0: each test sets what it needs.
fn plain_settings() -> Settings {
    Settings {
        params: vec![],
        grids: vec![],
        iterations: 0,
        spp: 4,
        loss: Loss::L2,
        learning_rate_grids: 0.0,
        learning_rate_params: 0.0,
        learning_rate_decay: Decay::None,
        learning_rate_resolution: ResolutionPower::Fixed(0.0),
        learning_rate_warmup: 0,
        adam: AdamOptions::default(),
        ema: 0.0,
        loss_scales: 1,
        image_scale: ImageScale::Full,
        views_per_iteration: None,
        seed: 0,
        terms: Terms::Complete,
        boundary: BoundaryBudget::default(),
        upsample_at: vec![],
        redistance_every: None,
        laplacian: 0.0,
    }
}

#[test]
fn named_parameters_converge_from_a_start_off_by_ten_to_twenty_percent() {
    let truth = scene();
    let names = ["ball.center.x", "ball.radius", "light.center.x"];
    let true_values: Vec<f32> = names.iter().map(|n| truth.parameter(n).unwrap()).collect();
    let views = vec![View::of(&truth.camera)];
    let targets = render_targets(&truth, &views, 256, 1000).unwrap();
    let mut start = truth.clone();
    for (name, factor) in names.iter().zip([1.2, 0.85, 1.15]) {
        let v = start.parameter(name).unwrap();
        start = start.with_parameter(name, v * factor).unwrap();
    }
    let settings = Settings {
        params: names.iter().map(|s| s.to_string()).collect(),
        spp: 32,
        learning_rate_params: 0.02,
        seed: 1,
        ..plain_settings()
    };
    let mut opt = Optimization::new(start, views, targets, settings).unwrap();
    // A step decay: Adam's steps are about the learning rate, so the last rate sets the noise floor.
    let (mut first, mut last) = (None, 0.0);
    for (iterations, rate) in [(12, 0.02), (30, 0.005), (15, 0.0015)] {
        opt.settings.learning_rate_params = rate;
        for _ in 0..iterations {
            last = opt.step().unwrap().loss;
            first.get_or_insert(last);
        }
    }
    let first = first.unwrap();
    let values = opt.values().unwrap();
    for ((name, got), want) in names.iter().zip(&values).zip(&true_values) {
        println!("{name}: {got} (true {want})");
    }
    println!("loss {first} -> {last}");
    for ((name, got), want) in names.iter().zip(&values).zip(&true_values) {
        assert!(
            (got - want).abs() <= 0.02 * want.abs(),
            "{name}: {got} vs {want}"
        );
    }
}

/// With `ema` β the run's result is the moving average of the values after each step, its weight
/// on the past `min(β, (1 + t)/(10 + t))` after `t` values: checked against that recurrence, in
/// `f64`, over five steps of the named parameters; the steps themselves are those of a run without
/// the average (it only reads them).
#[test]
fn the_result_is_the_moving_average_of_the_steps() {
    let truth = scene();
    let names = ["ball.center.x", "ball.radius"];
    let views = vec![View::of(&truth.camera)];
    let targets = render_targets(&truth, &views, 16, 1000).unwrap();
    let start = truth.with_parameter("ball.radius", 0.7).unwrap();
    let settings = |ema| Settings {
        params: names.iter().map(|s| s.to_string()).collect(),
        spp: 4,
        learning_rate_params: 0.02,
        ema,
        ..plain_settings()
    };
    let mut averaged =
        Optimization::new(start.clone(), views.clone(), targets.clone(), settings(0.9)).unwrap();
    let mut last = Optimization::new(start, views, targets, settings(0.0)).unwrap();
    // Before the first step there is nothing to average: the current scene.
    let read = |s: &Scene| names.map(|n| s.parameter(n).unwrap());
    assert_eq!(
        read(&averaged.averaged_scene().unwrap()),
        read(&averaged.scene)
    );
    let mut want = [0.0f64; 2];
    for t in 0..5u32 {
        averaged.step().unwrap();
        last.step().unwrap();
        let values = read(&averaged.scene);
        assert_eq!(
            values,
            read(&last.scene),
            "step {t}: the average changed a step"
        );
        assert_eq!(read(&last.averaged_scene().unwrap()), values);
        let w = if t == 0 {
            0.0
        } else {
            0.9f64.min((1.0 + t as f64) / (10.0 + t as f64))
        };
        for (a, &x) in want.iter_mut().zip(&values) {
            *a = w * *a + (1.0 - w) * x as f64;
        }
        let got = read(&averaged.averaged_scene().unwrap());
        for (g, w) in got.iter().zip(&want) {
            assert!(
                (*g as f64 - w).abs() <= 1e-6 * w.abs(),
                "step {t}: {g} vs {w}"
            );
        }
    }
    assert_ne!(
        read(&averaged.averaged_scene().unwrap()),
        read(&averaged.scene),
        "five steps of a moving start all ended where the average is"
    );
}

/// Left out of `OPT.json`, `ema` is 0.9 (the race's `opt.json` leaves it out); the other examples
/// set 0, the last values, as their documented runs had.
#[test]
fn the_moving_average_is_the_default_result() {
    use implicit_psdr::optimize::config::{DEFAULT_EMA, OptimizeConfig};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/inverse");
    assert_eq!(DEFAULT_EMA, 0.9);
    for entry in std::fs::read_dir(&root).unwrap() {
        let dir = entry.unwrap().path();
        let cfg = OptimizeConfig::load(&dir.join("opt.json")).unwrap();
        let name = dir.file_name().unwrap().to_string_lossy().to_string();
        let want = if name == "race" { DEFAULT_EMA } else { 0.0 };
        assert_eq!(cfg.settings.ema, want, "{name}");
    }
}

/// A grid shape `blob` (a sphere baked at 16³ over `[-1.2, 1.2]³`) on a floor, and the target scene in
/// which `blob` is two blended spheres; light and sky as in [`scene`], `size × size` pixels.
fn grid_scenes(dir: &std::path::Path, size: u32) -> (Scene, Scene) {
    use implicit_psdr::sdf::{Sdf, bake, write_npy};
    let (lo, hi) = (glam::Vec3::splat(-1.2), glam::Vec3::splat(1.2));
    let start = bake(&Sdf::sphere([0.0, 0.0, 0.0], 0.7), lo, hi, 16);
    write_npy(&dir.join("start.npy"), &start).unwrap();
    let common = |shape: &str| {
        format!(
            r#"{{
      "camera": {{"origin": [0, 1.5, 3.5], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 40,
                 "width": {size}, "height": {size}, "filter": "tent"}},
      "integrator": {{"type": "direct"}},
      "shapes": [
        {{"name": "blob", "sdf": {shape}, "bsdf": {{"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}}}},
        {{"name": "floor", "sdf": {{"type": "box", "center": [0, -1.7, 0], "half_size": [4, 0.5, 4],
         "rounding": 0.1}}, "bsdf": {{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}}}
      ],
      "emitters": [
        {{"name": "light", "type": "rectangle", "center": [1.5, 4, 1], "normal": [0, -1, 0],
         "u": [1, 0, 0], "size": [1.5, 1.5], "radiance": [25, 25, 25]}},
        {{"name": "sky", "type": "constant", "radiance": [0.3, 0.3, 0.3]}}
      ]
    }}"#
        )
    };
    let grid = r#"{"type": "grid", "file": "start.npy", "bbox_min": [-1.2, -1.2, -1.2],
                   "bbox_max": [1.2, 1.2, 1.2]}"#;
    let target = r#"{"type": "smooth_union", "k": 0.3, "children": [
        {"type": "sphere", "center": [-0.35, 0.0, 0.0], "radius": 0.55},
        {"type": "sphere", "center": [0.4, 0.15, 0.1], "radius": 0.45}]}"#;
    (
        parse(&common(grid), dir).unwrap(),
        parse(&common(target), dir).unwrap(),
    )
}

/// IoU of `blob` in the two scenes over the grid box.
fn blob_iou(a: &Scene, b: &Scene) -> f64 {
    use implicit_psdr::math::Aabb;
    let region = Aabb::new(glam::Vec3::splat(-1.2), glam::Vec3::splat(1.2));
    implicit_psdr::optimize::metrics::iou(
        a.shape_named("blob").unwrap(),
        b.shape_named("blob").unwrap(),
        region,
        48,
    )
}

/// Runs the 16³, 24×24, 4-view problem for 30 iterations with `terms` and `seed`: (first loss, mean
/// of the last five losses, IoU before, IoU after).
fn grid_run(terms: Terms, seed: u64) -> (f64, f64, f64, f64) {
    use implicit_psdr::optimize::orbit;
    let dir = std::env::temp_dir().join(format!(
        "psdr-optimize-grid-{}-{seed}-{terms:?}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let (start, target) = grid_scenes(&dir, 24);
    let views = orbit(4, 3.5, &[1.5], glam::Vec3::ZERO, 40.0);
    let targets = render_targets(&target, &views, 64, 500).unwrap();
    let settings = Settings {
        grids: vec!["blob".into()],
        learning_rate_grids: 0.02,
        seed,
        terms,
        redistance_every: Some(10),
        ..plain_settings()
    };
    let iou_before = blob_iou(&start, &target);
    let mut opt = Optimization::new(start, views, targets, settings).unwrap();
    let losses: Vec<f64> = (0..30).map(|_| opt.step().unwrap().loss).collect();
    let iou_after = blob_iou(&opt.scene, &target);
    let _ = std::fs::remove_dir_all(&dir);
    let last = losses[25..].iter().sum::<f64>() / 5.0;
    (losses[0], last, iou_before, iou_after)
}

/// A 16³ grid from 4 orbit views at 24×24 for 30 iterations: the loss falls and the IoU with the
/// target shape rises; with the interior term alone (what renderers without boundary terms compute)
/// it does not. The loss at 4 spp is mostly the images' noise, so it cannot fall far. Measured (seeds 3
/// and 4): complete, loss × 0.65 and × 0.58, IoU 0.52 → 0.85 and 0.87; interior alone, loss × 1.02 and
/// × 0.95, IoU 0.52 → 0.49 and 0.49. The ordering holds for both seeds, so it is asserted.
#[test]
fn a_grid_moves_towards_the_target_shape_only_with_the_boundary_terms() {
    let (first, last, before, after) = grid_run(Terms::Complete, 3);
    println!("complete: loss {first} -> {last}; IoU {before} -> {after}");
    assert!(last < 0.8 * first, "loss {first} -> {last}");
    assert!(after > before + 0.2, "IoU {before} -> {after}");
    let (_, interior_last, _, interior_after) = grid_run(Terms::Interior, 3);
    println!("interior alone: loss {first} -> {interior_last}; IoU {before} -> {interior_after}");
    assert!(
        after > interior_after + 0.2,
        "IoU complete {after}, interior alone {interior_after}"
    );
}

/// The views of an iteration run in parallel (each view's passes too), and their results are added
/// in view order: the same losses and values, bit for bit, with 1, 2 and 3 threads (the 16³ problem
/// at 24×24, 4 views, 3 iterations with redistancing and the moving average).
#[test]
fn the_steps_are_the_same_whatever_the_thread_count() {
    use implicit_psdr::optimize::orbit;
    let dir = std::env::temp_dir().join(format!("psdr-optimize-threads-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (start, target) = grid_scenes(&dir, 24);
    let views = orbit(4, 3.5, &[1.5], glam::Vec3::ZERO, 40.0);
    let targets = render_targets(&target, &views, 16, 500).unwrap();
    let settings = Settings {
        grids: vec!["blob".into()],
        learning_rate_grids: 0.02,
        ema: 0.9,
        seed: 5,
        redistance_every: Some(1),
        ..plain_settings()
    };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut opt = Optimization::new(
                start.clone(),
                views.clone(),
                targets.clone(),
                settings.clone(),
            )
            .unwrap();
            let losses: Vec<u64> = (0..3).map(|_| opt.step().unwrap().loss.to_bits()).collect();
            let values: Vec<u32> = (opt.values().unwrap().iter())
                .map(|v| v.to_bits())
                .collect();
            (losses, values)
        })
    };
    let one = run(1);
    for threads in [2, 3] {
        let other = run(threads);
        assert_eq!(one.0, other.0, "losses with 1 and {threads} threads");
        assert!(
            one.1 == other.1,
            "values differ with 1 and {threads} threads"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Coarse-to-fine image resolution: the 16³ problem on a 48×48 film rendered at half resolution (the
/// 24×24 of the test above) for 20 iterations, then refined to 31³ and rendered at full resolution for
/// 2. At half resolution the loss falls and the IoU rises as at 24×24; the full-resolution iterations
/// after it run, and their loss (against the full targets) is of the same order.
#[test]
fn a_grid_moves_towards_the_target_at_half_resolution_then_refines_at_full() {
    use implicit_psdr::optimize::orbit;
    let dir = std::env::temp_dir().join(format!("psdr-optimize-half-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (start, target) = grid_scenes(&dir, 48);
    let views = orbit(4, 3.5, &[1.5], glam::Vec3::ZERO, 40.0);
    let targets = render_targets(&target, &views, 64, 500).unwrap();
    let settings = Settings {
        grids: vec!["blob".into()],
        learning_rate_grids: 0.02,
        image_scale: ImageScale::Stages(vec![2, 1]),
        seed: 3,
        upsample_at: vec![20],
        redistance_every: Some(10),
        ..plain_settings()
    };
    let before = blob_iou(&start, &target);
    let mut opt = Optimization::new(start, views, targets, settings).unwrap();
    assert_eq!(opt.stage_divisors, [2, 1]);
    assert_eq!((opt.divisor_at(19), opt.divisor_at(20)), (2, 1));
    let losses: Vec<f64> = (0..20).map(|_| opt.step().unwrap().loss).collect();
    let half = blob_iou(&opt.scene, &target);
    let last = losses[15..].iter().sum::<f64>() / 5.0;
    println!(
        "half resolution: loss {} -> {last}; IoU {before} -> {half}",
        losses[0]
    );
    assert!(last < 0.8 * losses[0], "loss {} -> {last}", losses[0]);
    assert!(half > before + 0.2, "IoU {before} -> {half}");
    let full: Vec<f64> = (0..2).map(|_| opt.step().unwrap().loss).collect();
    let after = blob_iou(&opt.scene, &target);
    println!("full resolution: loss {full:?}; IoU {after}");
    assert_eq!(opt.scene.grid_values("blob").unwrap().dims, [31, 31, 31]);
    assert!(
        full.iter().all(|l| l.is_finite() && *l < 2.0 * losses[0]),
        "{full:?}"
    );
    assert!(after > before + 0.2, "IoU {before} -> {after}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `image_scale: "auto"` on the race: a 16³ cell over the unit cube seen from at most 2.085 away
/// with a 39° field of view on a 128-pixel film projects to `(64 / tan 19.5°) / 15 / 2.085 = 5.78`
/// pixels, 2.89 at half resolution (≥ 2.5) and 1.44 at a quarter; at 31³ it is 2.89 at full
/// resolution. So: half, full, full.
#[test]
fn automatic_image_scale_on_the_race_is_half_then_full() {
    use implicit_psdr::optimize::config::OptimizeConfig;
    use implicit_psdr::optimize::resolution::auto_divisors;
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/inverse/race/opt.json");
    let cfg = OptimizeConfig::load(&path).unwrap();
    let d = auto_divisors(&cfg.scene, &cfg.views, &cfg.settings.grids, 3).unwrap();
    assert_eq!(d, [2, 1, 1]);
    // Nearer views (the same views at 3/4 of their distance): a cell is 7.7 pixels, a quarter 1.9;
    // at 31³ half is 1.9 again.
    let centre = glam::Vec3::splat(0.5);
    let near: Vec<View> = (cfg.views.iter())
        .map(|v| View {
            origin: centre + 0.75 * (v.origin - centre),
            ..*v
        })
        .collect();
    assert_eq!(
        auto_divisors(&cfg.scene, &near, &cfg.settings.grids, 3).unwrap(),
        [2, 1, 1]
    );
    // Twice as near: 11.6 pixels at 16³ (quarter: 2.9), 5.8 at 31³ (half: 2.9), 2.9 at 61³.
    let near: Vec<View> = (cfg.views.iter())
        .map(|v| View {
            origin: centre + 0.5 * (v.origin - centre),
            ..*v
        })
        .collect();
    assert_eq!(
        auto_divisors(&cfg.scene, &near, &cfg.settings.grids, 3).unwrap(),
        [4, 2, 1]
    );
    // No grid named: full resolution.
    assert_eq!(
        auto_divisors(&cfg.scene, &cfg.views, &[], 2).unwrap(),
        [1, 1]
    );
}

/// The examples in `scenes/inverse/` stay loadable: their OPT.json, both scenes and the grids they name.
#[test]
fn inverse_examples_load() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/inverse");
    let mut count = 0;
    for entry in std::fs::read_dir(&root).unwrap() {
        let opt = entry.unwrap().path().join("opt.json");
        implicit_psdr::optimize::config::OptimizeConfig::load(&opt)
            .unwrap_or_else(|e| panic!("{}: {e}", opt.display()));
        count += 1;
    }
    assert!(count >= 3, "{count} examples");
}

/// The race's second target (`opt_torus.json`) loads and keeps the race's settings: every field but
/// the description and the target is `opt.json`'s, and the torus's target scene is the race's but
/// for its shapes, so a change to the race's schedule, sky or film reaches both.
#[test]
fn the_race_with_the_torus_is_the_race_with_another_target() {
    let race = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/inverse/race");
    let read_without = |name: &str, fields: &[&str]| -> serde_json::Value {
        let text = std::fs::read_to_string(race.join(name)).unwrap();
        let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
        for field in ["description"].iter().chain(fields) {
            json.as_object_mut().unwrap().remove(*field);
        }
        json
    };
    let mut torus = read_without("opt_torus.json", &[]);
    assert_eq!(torus["target"]["scene"], "torus_target.json");
    torus.as_object_mut().unwrap().remove("target");
    assert_eq!(read_without("opt.json", &["target"]), torus);
    assert_eq!(
        read_without("target.json", &["shapes"]),
        read_without("torus_target.json", &["shapes"])
    );
    let cfg = implicit_psdr::optimize::config::OptimizeConfig::load(&race.join("opt_torus.json"))
        .unwrap_or_else(|e| panic!("opt_torus.json: {e}"));
    assert_eq!(cfg.views.len(), 12);
}

/// Left out of `OPT.json`, `image_scale` is `"auto"` when only SDF grids (and named parameters) are
/// optimised, and full resolution when a texture or an environment map is (their texels are seen
/// at the film's resolution): on the race, whose 16³ cells project to about 6 pixels, the first
/// stage renders at half size; the examples that optimise texels stay at full size.
#[test]
fn image_scale_defaults_to_auto_only_for_sdf_grids() {
    use implicit_psdr::optimize::config::OptimizeConfig;
    use implicit_psdr::optimize::resolution::divisors;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/inverse");
    for (name, scale, expected) in [
        ("race", ImageScale::Auto, vec![2, 1, 1]),
        ("shadow", ImageScale::Auto, vec![1]),
        ("named", ImageScale::Full, vec![1]),
        ("paint", ImageScale::Full, vec![1]),
        ("envmap_light", ImageScale::Full, vec![1]),
        ("shape_albedo_env", ImageScale::Full, vec![1]),
    ] {
        let cfg = OptimizeConfig::load(&root.join(name).join("opt.json")).unwrap();
        let s = &cfg.settings;
        assert_eq!(s.image_scale, scale, "{name}");
        let stages = s.upsample_at.len() + 1;
        let d = divisors(&s.image_scale, &cfg.scene, &cfg.views, &s.grids, stages).unwrap();
        assert_eq!(d, expected, "{name}");
    }
}

/// `learning_rate_resolution`: absent or `true` is the default power 1, `"auto"` chooses per
/// refinement, `false` is 0, a number itself (the race's `opt.json` with each value, its paths made
/// absolute).
#[test]
fn learning_rate_resolution_takes_a_power() {
    use implicit_psdr::optimize::config::{DEFAULT_LEARNING_RATE_RESOLUTION, OptimizeConfig};
    let race = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/inverse/race");
    let text = std::fs::read_to_string(race.join("opt.json")).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json["scene"] = race.join("start.json").to_str().unwrap().into();
    json["target"]["scene"] = race.join("target.json").to_str().unwrap().into();
    let dir = std::env::temp_dir().join(format!("psdr-optimize-power-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    assert_eq!(
        DEFAULT_LEARNING_RATE_RESOLUTION,
        ResolutionPower::Fixed(1.0)
    );
    for (value, expected) in [
        (None, ResolutionPower::Fixed(1.0)),
        (Some(serde_json::json!("auto")), ResolutionPower::Auto),
        (Some(serde_json::json!(true)), ResolutionPower::Fixed(1.0)),
        (Some(serde_json::json!(false)), ResolutionPower::Fixed(0.0)),
        (Some(serde_json::json!(2)), ResolutionPower::Fixed(2.0)),
        (Some(serde_json::json!(0.5)), ResolutionPower::Fixed(0.5)),
    ] {
        let mut j = json.clone();
        if let Some(v) = &value {
            j["learning_rate_resolution"] = v.clone();
        }
        let path = dir.join("opt.json");
        std::fs::write(&path, serde_json::to_string(&j).unwrap()).unwrap();
        let cfg = OptimizeConfig::load(&path).unwrap();
        assert_eq!(cfg.settings.learning_rate_resolution, expected, "{value:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs the 16³, 24×24, 4-view problem towards `target` (the start itself or the blended spheres)
/// for 10 iterations, then refines: the refinement that `learning_rate_resolution` `"auto"` made.
fn refinement_towards(to_itself: bool) -> implicit_psdr::optimize::Refinement {
    use implicit_psdr::optimize::orbit;
    let dir = std::env::temp_dir().join(format!(
        "psdr-optimize-auto-{}-{to_itself}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let (start, target) = grid_scenes(&dir, 24);
    let target = if to_itself { start.clone() } else { target };
    let views = orbit(4, 3.5, &[1.5], glam::Vec3::ZERO, 40.0);
    let targets = render_targets(&target, &views, 64, 500).unwrap();
    let settings = Settings {
        grids: vec!["blob".into()],
        learning_rate_grids: 0.02,
        learning_rate_resolution: ResolutionPower::Auto,
        seed: 3,
        upsample_at: vec![10],
        ..plain_settings()
    };
    let mut opt = Optimization::new(start, views, targets, settings).unwrap();
    for _ in 0..11 {
        opt.step().unwrap();
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(opt.refinements().len(), 1);
    opt.refinements()[0].clone()
}

/// `learning_rate_resolution` `"auto"`: a grid whose target is its own start has only noise in its
/// gradients, so its stage counts as converged and the refined grid's rate follows the spacing's
/// square (a quarter); a grid still moving towards a different shape keeps the first power (a half).
#[test]
fn automatic_resolution_power_follows_the_stage_convergence() {
    let converged = refinement_towards(true);
    let moving = refinement_towards(false);
    println!("converged: {converged:?}\nmoving: {moving:?}");
    for r in [&converged, &moving] {
        assert_eq!((r.iteration, r.node.as_str()), (10, "blob"));
        assert!(r.signal_ratio.is_some_and(f64::is_finite));
    }
    assert_eq!((converged.power, converged.rate_scale), (2.0, 0.25));
    assert_eq!((moving.power, moving.rate_scale), (1.0, 0.5));
}

/// `spp_primary` and `spp_secondary`: absent, the primary term takes `diff`'s default and the
/// secondary term a 64th of `spp` per pixel (a quarter at the race's 16); given, any finite rate
/// ≥ 0 is kept, fractions included; anything else is refused naming the field.
#[test]
fn boundary_budgets_default_and_parse() {
    use implicit_psdr::optimize::config::{DEFAULT_SECONDARY_SHARE, OptimizeConfig};
    let race = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/inverse/race");
    let text = std::fs::read_to_string(race.join("opt.json")).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json["scene"] = race.join("start.json").to_str().unwrap().into();
    json["target"]["scene"] = race.join("target.json").to_str().unwrap().into();
    let dir = std::env::temp_dir().join(format!("psdr-optimize-budget-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("opt.json");
    let load = |j: &serde_json::Value| {
        std::fs::write(&path, serde_json::to_string(j).unwrap()).unwrap();
        OptimizeConfig::load(&path)
    };
    assert_eq!(DEFAULT_SECONDARY_SHARE, 1.0 / 64.0);
    let cfg = load(&json).unwrap();
    assert_eq!(
        cfg.settings.boundary,
        BoundaryBudget {
            primary_spp: None,
            secondary_spp: Some(0.25)
        }
    );
    // 128×128 views: a quarter of a sample per pixel is 4096 tangent-line samples per view.
    assert_eq!(
        cfg.settings.boundary.totals(&cfg.scene, cfg.settings.spp),
        (16384, 4096)
    );
    // At least one sample where the rate is positive, none where it is 0.
    let sparse = BoundaryBudget {
        primary_spp: Some(0.0),
        secondary_spp: Some(1e-9),
    };
    assert_eq!(sparse.totals(&cfg.scene, 16), (0, 1));
    let mut j = json.clone();
    j["spp_primary"] = serde_json::json!(0.5);
    j["spp_secondary"] = serde_json::json!(2);
    let cfg = load(&j).unwrap();
    assert_eq!(
        cfg.settings.boundary,
        BoundaryBudget {
            primary_spp: Some(0.5),
            secondary_spp: Some(2.0)
        }
    );
    for (key, value) in [
        ("spp_secondary", serde_json::json!(-1)),
        ("spp_primary", serde_json::json!("many")),
        ("spp_secondary", serde_json::json!(1e39)),
    ] {
        let mut j = json.clone();
        j[key] = value.clone();
        let message = load(&j).unwrap_err().to_string();
        assert!(message.contains(key), "{value}: {message}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
