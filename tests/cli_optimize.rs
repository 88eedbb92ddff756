//! `optimize` on the command line: a tiny run writes every output, well-formed (progress.csv row per
//! iteration, PNGs of the right size, a result.json that renders and holds the moved parameter), reuses
//! its cached targets, optimises a grid (refined n → 2n − 1) into NODE.npy with grid paths that resolve
//! from the output folder, and bad OPT.json inputs fail cleanly (exit code 2, one line naming the file
//! and the field) without touching a previous run's files.

mod common;

use common::{assert_failure, assert_success, npy_bytes, run};
use implicit_psdr::film::figure::TITLE_HEIGHT;
use implicit_psdr::film::{self, Image};
use implicit_psdr::optimize::pictures::VIEWS_MIN_WIDTH;
use implicit_psdr::scene;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// The image size of the test scenes.
const SIZE: u32 = 16;
/// The starting and target radius of the ball.
const START: f32 = 0.7;
const TRUTH: f32 = 0.9;

fn workdir(name: &str) -> PathBuf {
    common::workdir("cli-optimize", name)
}

/// A ball under a rectangle light and a dim sky, 16×16.
fn ball_scene(radius: f32) -> Value {
    json!({
      "camera": {"origin": [0, 2.5, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 45,
                 "width": SIZE, "height": SIZE},
      "shapes": [
        {"name": "ball", "sdf": {"type": "sphere", "center": [0, 0, 0], "radius": radius},
         "bsdf": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}}
      ],
      "emitters": [
        {"name": "light", "type": "rectangle", "center": [1.5, 4, 1], "normal": [0, -1, 0],
         "u": [1, 0, 0], "size": [1.5, 1.5], "radiance": [25, 25, 25]},
        {"name": "sky", "type": "constant", "radiance": [0.2, 0.2, 0.2]}
      ]
    })
}

/// The tiny run: 2 orbit views, the ball's radius, 5 iterations at 4 spp.
fn tiny_opt() -> Value {
    json!({
      "scene": "start.json",
      "target": {"scene": "target.json"},
      "views": {"orbit": {"count": 2, "radius": 4, "height": 2.5}},
      "optimize": {"params": ["ball.radius"]},
      "iterations": 5,
      "spp": 4,
      "target_spp": 16,
      "learning_rate": 0.05,
      "snapshot_every": 2
    })
}

fn write_json(path: &Path, v: &Value) {
    std::fs::write(path, serde_json::to_string_pretty(v).unwrap()).unwrap();
}

/// A folder with start.json, target.json and opt.json (`opt`).
fn setup(name: &str, opt: &Value) -> PathBuf {
    let dir = workdir(name);
    write_json(&dir.join("start.json"), &ball_scene(START));
    write_json(&dir.join("target.json"), &ball_scene(TRUTH));
    write_json(&dir.join("opt.json"), opt);
    dir
}

/// The width and height of a PNG file.
fn png_size(path: &Path) -> (u32, u32) {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .unwrap();
    let info = reader.info();
    (info.width, info.height)
}

/// The rows of progress.csv as numbers, after checking its header.
fn progress(path: &Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let timing =
        ",loss_pass_seconds,interior_seconds,primary_seconds,secondary_seconds,grid_edit_seconds";
    assert!(
        header == format!("iteration,loss,seconds,gradient_norm{timing}")
            || header == format!("iteration,loss,seconds,gradient_norm,iou,chamfer{timing}")
            || header
                == format!(
                    "iteration,loss,seconds,gradient_norm,mesh_chamfer,mesh_normal_consistency,\
                     mesh_iou{timing}"
                ),
        "{header}"
    );
    lines
        .map(|l| l.split(',').map(|x| x.parse::<f64>().unwrap()).collect())
        .collect()
}

/// Files and folders in `dir`, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn tiny_run_writes_every_output_and_moves_the_parameter() {
    let dir = setup("tiny", &tiny_opt());
    let result = run(&dir, &["optimize", "opt.json", "--out", "out"]);
    let stdout = assert_success(&result);
    let summary: Vec<&str> = stdout.lines().collect();
    assert_eq!(summary.len(), 3, "{stdout}");
    assert!(
        summary[0].contains("5 iterations")
            && summary[0].contains(" -> ")
            && summary[0].contains("out"),
        "{stdout}"
    );
    // The optimised parameter's start and end (checked against result.json below), and the file.
    let (from, to) = (summary[1].strip_prefix("  ball.radius: ").unwrap())
        .split_once(" -> ")
        .unwrap();
    assert_eq!(from.parse::<f32>().unwrap(), START);
    let printed: f32 = to.parse().unwrap();
    assert!(summary[2].contains(&format!(
        "{}",
        Path::new("out").join("result.json").display()
    )));
    // stderr is not a terminal here: a one-line record per iteration at most, the first and the last
    // always, with the loss, the time so far and to go.
    let stderr = String::from_utf8_lossy(&result.stderr);
    let records: Vec<&str> = stderr.lines().collect();
    assert!(records.len() >= 2, "{stderr}");
    assert!(
        records[0].starts_with("progress: iteration 1/5: loss "),
        "{stderr}"
    );
    assert!(
        records
            .last()
            .unwrap()
            .starts_with("progress: iteration 5/5: loss "),
        "{stderr}"
    );
    assert!(records.last().unwrap().ends_with(", eta 0.0 s"), "{stderr}");
    assert!(records.iter().all(|r| r.contains("; elapsed ")), "{stderr}");
    let out = dir.join("out");
    assert_eq!(
        listing(&out),
        [
            "loss.png",
            "progress.csv",
            "result.json",
            "snapshots",
            "targets",
            "views.png"
        ]
    );
    assert_eq!(
        listing(&out.join("snapshots")),
        ["views_00002.png", "views_00004.png"]
    );
    assert_eq!(
        listing(&out.join("targets")),
        ["targets.json", "view_0.exr", "view_1.exr"]
    );

    let rows = progress(&out.join("progress.csv"));
    assert_eq!(rows.len(), 5);
    for (i, row) in rows.iter().enumerate() {
        // The four columns, then the five stages' seconds (no shape columns: the target has no grid).
        assert_eq!(row.len(), 9);
        assert!(
            row[4..].iter().all(|t| t.is_finite() && *t >= 0.0),
            "{row:?}"
        );
        assert!(
            row[4..].iter().sum::<f64>() <= row[2] + 1e-3,
            "stages exceed the time: {row:?}"
        );
        assert_eq!(row[0], i as f64);
        assert!(row[1].is_finite() && row[1] > 0.0, "loss {row:?}");
        assert!(row[2] > 0.0 && row[3].is_finite(), "{row:?}");
        if i > 0 {
            assert!(row[2] >= rows[i - 1][2], "seconds are cumulative: {rows:?}");
        }
    }

    // Per view a row: target | current, 4 pixels apart, magnified; the titles above the first.
    let side = SIZE * VIEWS_MIN_WIDTH.div_ceil(SIZE);
    assert_eq!(
        png_size(&out.join("views.png")),
        (2 * side + 4, TITLE_HEIGHT + 2 * side + 4)
    );
    assert_eq!(png_size(&out.join("loss.png")), (640, 400));
    for k in 0..2 {
        let target = film::read_exr_rgb(&out.join(format!("targets/view_{k}.exr"))).unwrap();
        assert_eq!((target.width, target.height), (SIZE, SIZE));
    }

    // result.json renders, and its radius moved towards the target's.
    assert_success(&run(
        &out,
        &["render", "result.json", "--out", "r.exr", "--png", "r.png"],
    ));
    let result = scene::load(&out.join("result.json")).unwrap();
    let radius = result.parameter("ball.radius").unwrap();
    println!("ball.radius {START} -> {radius} (target {TRUTH})");
    assert_eq!(printed, radius);
    assert!(
        (radius - TRUTH).abs() < (START - TRUTH).abs() - 0.05,
        "radius {radius}"
    );
    // Everything else is the starting scene's.
    let start = scene::load(&dir.join("start.json")).unwrap();
    for ((n, a), (m, b)) in result.parameters().iter().zip(start.parameters()) {
        assert_eq!(*n, m);
        if n != "ball.radius" {
            assert_eq!(*a, b, "{n}");
        }
    }

    // The same targets given as images: the same run.
    for k in 0..2 {
        let name = format!("v{k}.exr");
        std::fs::copy(out.join(format!("targets/view_{k}.exr")), dir.join(&name)).unwrap();
    }
    let mut opt = tiny_opt();
    opt["target"] = json!({"images": ["v0.exr", "v1.exr"]});
    write_json(&dir.join("images.json"), &opt);
    assert_success(&run(
        &dir,
        &["optimize", "images.json", "--out", "from_images"],
    ));
    let without_seconds =
        |rows: &[Vec<f64>]| -> Vec<[f64; 3]> { rows.iter().map(|r| [r[0], r[1], r[3]]).collect() };
    let again = progress(&dir.join("from_images/progress.csv"));
    assert_eq!(without_seconds(&again), without_seconds(&rows));
    assert!(!dir.join("from_images/targets").exists());

    // A second run reuses the cached targets (same files, same losses); a changed target scene does
    // not.
    let exr = out.join("targets/view_0.exr");
    let modified = |p: &Path| std::fs::metadata(p).unwrap().modified().unwrap();
    let before = modified(&exr);
    assert_success(&run(&dir, &["optimize", "opt.json", "--out", "out"]));
    assert_eq!(modified(&exr), before);
    assert_eq!(progress(&out.join("progress.csv"))[0][1], rows[0][1]);
    let old_target = std::fs::read(&exr).unwrap();
    write_json(&dir.join("target.json"), &ball_scene(0.95));
    assert_success(&run(&dir, &["optimize", "opt.json", "--out", "out"]));
    assert_ne!(std::fs::read(&exr).unwrap(), old_target);
    assert!(
        !listing(&out)
            .iter()
            .any(|n| n.contains("partial") || n.ends_with(".tmp"))
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A float32 `.npy` of an `n³` grid: the distance to a sphere of radius `r` in the middle of the box
/// `[-1, 1]³`.
fn sphere_grid(n: usize, r: f32) -> Vec<u8> {
    let mut data = Vec::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let t = |i: usize| i as f32 / (n - 1) as f32 * 2.0 - 1.0;
                let d = glam::Vec3::new(t(x), t(y), t(z)).length() - r;
                data.extend_from_slice(&d.to_le_bytes());
            }
        }
    }
    npy_bytes("<f4", &[n, n, n], &data)
}

#[test]
fn grid_run_writes_the_refined_grid_and_a_result_whose_paths_resolve() {
    let dir = workdir("grid");
    let scenes = dir.join("scenes");
    std::fs::create_dir_all(&scenes).unwrap();
    std::fs::write(scenes.join("blob.npy"), sphere_grid(8, 0.55)).unwrap();
    std::fs::write(scenes.join("fixed.npy"), sphere_grid(6, 0.5)).unwrap();
    let grid = |file: &str, lo: [f32; 3], hi: [f32; 3]| json!({"type": "grid", "file": file, "bbox_min": lo, "bbox_max": hi});
    let mut start = ball_scene(START);
    start["shapes"] = json!([
        {"name": "blob", "sdf": grid("blob.npy", [-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]),
         "bsdf": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}},
        {"name": "fixed", "sdf": grid("fixed.npy", [1.2, -0.5, -0.5], [2.2, 0.5, 0.5]),
         "bsdf": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}
    ]);
    write_json(&scenes.join("start.json"), &start);
    write_json(&dir.join("target.json"), &ball_scene(TRUTH));
    let opt = json!({
      "scene": "scenes/start.json",
      "target": {"scene": "target.json"},
      "views": [{"origin": [0, 2.5, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 45}],
      "optimize": {"grids": ["blob"]},
      "iterations": 2,
      "spp": 2,
      "target_spp": 4,
      "upsample_at": [1],
      "redistance_every": 1,
      "laplacian": 0.01
    });
    write_json(&dir.join("opt.json"), &opt);
    let out = dir.join("out");

    // Without refinement, the grid keeps its shape.
    let mut plain = opt.clone();
    for key in ["upsample_at", "redistance_every", "laplacian"] {
        plain.as_object_mut().unwrap().remove(key);
    }
    plain["iterations"] = json!(1);
    write_json(&dir.join("plain.json"), &plain);
    let stdout = assert_success(&run(&dir, &["optimize", "plain.json", "--out", "plain"]));
    assert!(stdout.contains("blob.npy"), "{stdout}");
    let grid = implicit_psdr::sdf::read_npy(&dir.join("plain/blob.npy")).unwrap();
    assert_eq!(grid.dims, [8, 8, 8]);

    assert_success(&run(&dir, &["optimize", "opt.json", "--out", "out"]));
    // Refined once before iteration 1: 8 → 15 samples per axis.
    let grid = implicit_psdr::sdf::read_npy(&out.join("blob.npy")).unwrap();
    assert_eq!(grid.dims, [15, 15, 15]);
    assert!(grid.values.iter().all(|v| v.is_finite()));
    assert_eq!(progress(&out.join("progress.csv")).len(), 2);

    let result: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("result.json")).unwrap()).unwrap();
    assert_eq!(result["shapes"][0]["sdf"]["file"], "blob.npy");
    assert_eq!(result["shapes"][1]["sdf"]["file"], "../scenes/fixed.npy");
    let back = scene::load(&out.join("result.json")).unwrap();
    assert_eq!(back.grid_values("blob").unwrap().values, grid.values);
    assert_success(&run(
        &out,
        &["render", "result.json", "--out", "r.exr", "--png", "r.png"],
    ));

    // A target scene that holds a shape named `blob` too: IoU and Chamfer columns.
    let mut target = start.clone();
    target["shapes"][0]["sdf"] = json!({"type": "sphere", "center": [0, 0, 0], "radius": 0.6});
    target["shapes"][1]["sdf"]["file"] = json!("scenes/fixed.npy");
    write_json(&dir.join("blob_target.json"), &target);
    let mut with_shape = plain.clone();
    with_shape["target"] = json!({"scene": "blob_target.json"});
    write_json(&dir.join("with_shape.json"), &with_shape);
    assert_success(&run(
        &dir,
        &["optimize", "with_shape.json", "--out", "shape"],
    ));
    let text = std::fs::read_to_string(dir.join("shape/progress.csv")).unwrap();
    assert!(
        text.starts_with("iteration,loss,seconds,gradient_norm,iou,chamfer,"),
        "{text}"
    );
    let row = &progress(&dir.join("shape/progress.csv"))[0];
    // The 8³ grid samples a sphere of radius 0.55, which its spline shrinks by about h²/(3r) to
    // about 0.50 (h = 2/7); against the target's 0.6 that is an IoU near (0.5/0.6)³ = 0.58 and a
    // Chamfer distance near 0.1. The first step moves each value by at most the grid's rate, 0.04:
    // a radius of at most 0.54, an IoU of at most (0.54/0.6)³ = 0.73 (measured: 0.68).
    assert!(row[4] > 0.45 && row[4] < 0.75, "IoU {}", row[4]);
    assert!(row[5] > 0.05 && row[5] < 0.15, "Chamfer {}", row[5]);
    // loss.png gains the IoU panel below the loss.
    assert_eq!(png_size(&dir.join("shape/loss.png")), (640, 600));

    // A reference mesh (a sphere of radius 0.6, as the target): three more columns, and the grid's
    // mesh beside its values and beside each snapshot.
    let sphere = implicit_psdr::mesh::shapes::uv_sphere(glam::Vec3::ZERO, 0.6, 48, 24);
    implicit_psdr::io::write_mesh(&dir.join("ref.obj"), &sphere).unwrap();
    let mut with_mesh = plain.clone();
    with_mesh["reference_mesh"] = json!("ref.obj");
    with_mesh["iterations"] = json!(2);
    with_mesh["snapshot_every"] = json!(1);
    write_json(&dir.join("with_mesh.json"), &with_mesh);
    let stdout = assert_success(&run(&dir, &["optimize", "with_mesh.json", "--out", "mesh"]));
    assert!(
        stdout.contains("final metrics against the reference mesh"),
        "{stdout}"
    );
    let text = std::fs::read_to_string(dir.join("mesh/progress.csv")).unwrap();
    assert!(
        text.starts_with(
            "iteration,loss,seconds,gradient_norm,mesh_chamfer,mesh_normal_consistency,mesh_iou,"
        ),
        "{text}"
    );
    let rows = progress(&dir.join("mesh/progress.csv"));
    assert_eq!(rows.len(), 2);
    // As above: a sphere of radius 0.50–0.54 against 0.6: Chamfer about 0.1 of the reference's
    // diagonal 1.2 √3 (0.05), normals alike, IoU from 0.58 to 0.73 (measured: 0.70).
    let (chamfer, normals, iou) = (rows[0][4], rows[0][5], rows[0][6]);
    assert!(chamfer > 0.025 && chamfer < 0.075, "Chamfer {chamfer}");
    assert!(
        normals > 0.95 && normals <= 1.0,
        "normal consistency {normals}"
    );
    assert!(iou > 0.45 && iou < 0.75, "IoU {iou}");
    for ply in ["mesh/blob.ply", "mesh/snapshots/blob_00001.ply"] {
        let mesh = implicit_psdr::io::read_mesh(&dir.join(ply)).unwrap();
        assert!(
            mesh.faces.len() > 100 && mesh.volume() > 0.2,
            "{ply}: {}",
            mesh.volume()
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A 16×16 EXR (`size`), for target images.
fn write_image(path: &Path, size: u32) {
    let mut image = Image::new(size, size);
    image.rgb.fill(0.25);
    film::write_exr(path, size, size, &image.rgb_channels("")).unwrap();
}

#[test]
fn bad_inputs_fail_with_one_line_naming_the_field_and_touch_nothing() {
    let dir = setup("bad", &tiny_opt());
    write_image(&dir.join("v0.exr"), SIZE);
    write_image(&dir.join("v1.exr"), SIZE);
    write_image(&dir.join("small.exr"), 8);
    // A previous run's files, which a failed run must leave alone.
    let out = dir.join("out");
    std::fs::create_dir_all(out.join("targets")).unwrap();
    for f in [
        "progress.csv",
        "result.json",
        "views.png",
        "loss.png",
        "targets/view_0.exr",
    ] {
        std::fs::write(out.join(f), "previous run").unwrap();
    }
    let before = listing(&out);

    type Edit = fn(&mut Value);
    let cases: &[(&str, Edit, &str)] = &[
        (
            "unknown field",
            |o| o["iteratons"] = json!(5),
            "opt.json: iteratons: unknown field",
        ),
        (
            "missing scene",
            |o| {
                o.as_object_mut().unwrap().remove("scene");
            },
            "opt.json: scene: missing",
        ),
        (
            "missing iterations",
            |o| {
                o.as_object_mut().unwrap().remove("iterations");
            },
            "opt.json: iterations: missing",
        ),
        (
            "scene not found",
            |o| o["scene"] = json!("nope.json"),
            "opt.json: scene: file",
        ),
        (
            "zero views per iteration",
            |o| o["views_per_iteration"] = json!(0),
            "opt.json: views_per_iteration: must be >= 1, got 0",
        ),
        (
            "too many views per iteration",
            |o| o["views_per_iteration"] = json!(3),
            "opt.json: views_per_iteration: must be <= 2 (the number of views), got 3",
        ),
        (
            "unknown loss",
            |o| o["loss"] = json!("l3"),
            "opt.json: loss: unknown loss \"l3\", expected one of l2, l1",
        ),
        (
            "unknown terms",
            |o| o["terms"] = json!("boundary"),
            "opt.json: terms: unknown terms",
        ),
        (
            "zero iterations",
            |o| o["iterations"] = json!(0),
            "opt.json: iterations: must be >= 1",
        ),
        (
            "negative spp",
            |o| o["spp"] = json!(-4),
            "opt.json: spp: must be >= 1",
        ),
        (
            "spp as a string",
            |o| o["spp"] = json!("4"),
            "opt.json: spp: expected an integer",
        ),
        (
            "negative learning rate",
            |o| o["learning_rate"] = json!({"params": -0.1}),
            "opt.json: learning_rate.params: must be > 0",
        ),
        (
            "unknown param",
            |o| o["optimize"]["params"] = json!(["ball.radus"]),
            "opt.json: optimize.params[0]: no parameter \"ball.radus\"; did you mean ball.radius?",
        ),
        (
            "unknown grid",
            |o| o["optimize"] = json!({"grids": ["blob"]}),
            "opt.json: optimize.grids[0]: no grid node \"blob\"",
        ),
        (
            "nothing to optimise",
            |o| o["optimize"] = json!({}),
            "opt.json: optimize: nothing to optimise",
        ),
        (
            "grid option without grids",
            |o| o["laplacian"] = json!(0.1),
            "opt.json: laplacian: is a grid option",
        ),
        (
            "warm-up without grids",
            |o| o["learning_rate_warmup"] = json!(3),
            "opt.json: learning_rate_warmup: is a grid option",
        ),
        (
            "negative warm-up",
            |o| o["learning_rate_warmup"] = json!(-1),
            "opt.json: learning_rate_warmup: must be >= 0, got -1",
        ),
        (
            "negative resolution power",
            |o| o["learning_rate_resolution"] = json!(-1),
            "opt.json: learning_rate_resolution: expected \"auto\", true, false or a power in [0, 8], got number -1",
        ),
        (
            "resolution power as a string",
            |o| o["learning_rate_resolution"] = json!("2"),
            "opt.json: learning_rate_resolution: expected \"auto\", true, false or a power in [0, 8], got string \"2\"",
        ),
        (
            "orbit without views",
            |o| o["views"]["orbit"]["count"] = json!(0),
            "opt.json: views.orbit.count: must be >= 1",
        ),
        (
            "orbit with a bad height",
            |o| o["views"]["orbit"]["height"] = json!([2, "low"]),
            "opt.json: views.orbit.height[1]: expected a number",
        ),
        (
            "orbit with no heights",
            |o| o["views"]["orbit"]["height"] = json!([]),
            "opt.json: views.orbit.height: an empty list of heights",
        ),
        (
            "view with a bad field of view",
            |o| {
                o["views"] = json!([{"origin": [0, 1, 4], "target": [0, 0, 0], "fov_y": 190}]);
            },
            "opt.json: views[0].fov_y: must be in (0, 180)",
        ),
        (
            "target with both",
            |o| {
                o["target"] = json!({"scene": "target.json", "images": ["v0.exr", "v1.exr"]});
            },
            "opt.json: target: expected exactly one of",
        ),
        (
            "one image for two views",
            |o| o["target"] = json!({"images": ["v0.exr"]}),
            "opt.json: target.images: 1 image for 2 views",
        ),
        (
            "wrong-size image",
            |o| o["target"] = json!({"images": ["v0.exr", "small.exr"]}),
            "opt.json: target.images[1]: small.exr is 8x8, the scene's image 16x16",
        ),
        (
            "missing image",
            |o| o["target"] = json!({"images": ["v0.exr", "v9.exr"]}),
            "opt.json: target.images[1]: file v9.exr not found",
        ),
        (
            "image scale not a list",
            |o| o["image_scale"] = json!(0.5),
            "opt.json: image_scale: expected a list of scales",
        ),
        (
            "image scale of another stage count",
            |o| o["image_scale"] = json!([0.5, 1]),
            "opt.json: image_scale: needs one scale per grid stage (1",
        ),
        (
            "image scale not a power of two",
            |o| o["image_scale"] = json!([0.3]),
            "opt.json: image_scale[0]: expected 1, 0.5 or 0.25",
        ),
        (
            "automatic image scale without grids",
            |o| o["image_scale"] = json!("auto"),
            "opt.json: image_scale: \"auto\" follows the grids' cells",
        ),
        (
            "upsample beyond the run",
            |o| {
                o["optimize"] = json!({"params": ["ball.radius"]});
                o["upsample_at"] = json!([5]);
            },
            "opt.json: upsample_at[0]: must be an iteration in [1, 4]",
        ),
    ];
    for (what, edit, expected) in cases {
        let mut opt = tiny_opt();
        edit(&mut opt);
        write_json(&dir.join("opt.json"), &opt);
        let result = run(&dir, &["optimize", "opt.json", "--out", "out"]);
        println!(
            "{what}: {}",
            String::from_utf8_lossy(&result.stderr).trim_end()
        );
        assert_failure(&result, expected);
        assert_eq!(listing(&out), before, "{what}");
        for f in [
            "progress.csv",
            "result.json",
            "views.png",
            "loss.png",
            "targets/view_0.exr",
        ] {
            assert_eq!(
                std::fs::read(out.join(f)).unwrap(),
                b"previous run",
                "{what}: {f}"
            );
        }
        // A bad input creates no output folder either.
        let fresh = run(&dir, &["optimize", "opt.json", "--out", "fresh"]);
        assert_failure(&fresh, expected);
        assert!(!dir.join("fresh").exists(), "{what}");
    }

    // Syntax errors name the file; an output folder that is a file is refused.
    std::fs::write(dir.join("opt.json"), "{\"scene\": ").unwrap();
    assert_failure(
        &run(&dir, &["optimize", "opt.json"]),
        "opt.json: EOF while parsing",
    );
    write_json(&dir.join("opt.json"), &tiny_opt());
    assert_failure(
        &run(&dir, &["optimize", "opt.json", "--out", "v0.exr"]),
        "--out v0.exr: is not a folder",
    );
    // An output that would replace an input.
    let mut opt = tiny_opt();
    opt["scene"] = json!("out/result.json");
    std::fs::copy(dir.join("start.json"), out.join("result.json")).unwrap();
    write_json(&dir.join("opt.json"), &opt);
    assert_failure(
        &run(&dir, &["optimize", "opt.json", "--out", "out"]),
        "result.json would replace the input",
    );
    let _ = std::fs::remove_dir_all(&dir);
}
