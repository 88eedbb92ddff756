//! Reverse mode on the command line: `grad` writes the loss and its gradient (grad.json and one `.npy`
//! per grid) exactly as the library computes them, `diff --grid-direction` writes the forward-mode
//! derivative along a direction of grid values exactly as the library does, the two agree through the
//! adjoint (dot-product test across commands), `params` lists each grid's values once, and bad inputs
//! fail cleanly (exit code 2, one line on stderr, no output file).

mod common;

use common::{Rng, assert_failure, assert_success, npy_bytes, outputs, run};
use implicit_psdr::film::{self, Image};
use implicit_psdr::integrator::{
    self, DiffOptions, GradientLayout, Loss, Normalization, RenderOptions, loss_gradient,
};
use implicit_psdr::scene::{self, GridDirection};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The grid's `.npy` shape `[nz, ny, nx]`: three different sizes, so that a transposed shape shows.
const SHAPE: [usize; 3] = [5, 6, 7];
/// The image size of the test scene.
const SIZE: u32 = 16;
/// The files every test folder starts with.
const INPUTS: [&str; 3] = ["scene.json", "g.npy", "t.exr"];

fn workdir(name: &str) -> PathBuf {
    common::workdir("cli-grad", name)
}

/// A float32 `.npy` of shape `shape` holding `values`.
fn npy_f32(shape: &[usize], values: &[f32]) -> Vec<u8> {
    let data: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    npy_bytes("<f4", shape, &data)
}

/// The grid's values: the distance to a sphere of radius 0.45 in the middle of its box, sampled at
/// `bbox_min + i · size / (n − 1)` (control points of the spline: the surface is near that sphere).
fn grid_values() -> Vec<f32> {
    let [nz, ny, nx] = SHAPE;
    let mut values = Vec::new();
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let t = |i: usize, n: usize| i as f32 / (n - 1) as f32 * 1.2 - 0.6;
                let p = glam::Vec3::new(t(x, nx), t(y, ny), t(z, nz));
                values.push(p.length() - 0.45);
            }
        }
    }
    values
}

/// `scenes/sphere_floor.json` at 16×16 pixels and 4 spp, the ball made smaller, with a grid shape
/// `blob` (file `g.npy`) beside it; and a target image `t.exr` (a colour ramp).
fn setup(name: &str) -> PathBuf {
    let dir = workdir(name);
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/sphere_floor.json");
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    v["camera"]["width"] = SIZE.into();
    v["camera"]["height"] = SIZE.into();
    v["spp"] = 4.into();
    v["shapes"][0]["sdf"]["radius"] = 0.7.into();
    v["shapes"].as_array_mut().unwrap().push(serde_json::json!(
        {"name": "blob", "sdf": {"type": "grid", "file": "g.npy",
                                 "bbox_min": [0.6, -1.35, -0.1], "bbox_max": [1.8, -0.15, 1.1]},
         "bsdf": {"type": "diffuse", "albedo": [0.3, 0.6, 0.9]}}));
    std::fs::write(dir.join("scene.json"), v.to_string()).unwrap();
    std::fs::write(dir.join("g.npy"), npy_f32(&SHAPE, &grid_values())).unwrap();
    write_target(&dir.join("t.exr"), SIZE, SIZE, &["R", "G", "B"]);
    dir
}

/// An EXR of `width × height` with the named channels, each a ramp in [0.1, 0.5].
fn write_target(path: &Path, width: u32, height: u32, names: &[&str]) {
    let n = (width * height) as usize;
    let channels: film::Channels = (names.iter().enumerate())
        .map(|(k, name)| {
            let values = (0..n)
                .map(|i| 0.1 + 0.4 * ((i * (k + 1)) % n) as f32 / n as f32)
                .collect();
            (name.to_string(), values)
        })
        .collect();
    film::write_exr(path, width, height, &channels).unwrap();
}

/// The R, G, B channels of an EXR file as an image.
fn read_image(path: &Path) -> Image {
    let (w, h, channels) = film::read_exr(path).unwrap();
    let mut image = Image::new(w, h);
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        let (_, values) = channels.iter().find(|(n, _)| n == name).unwrap();
        for (i, v) in values.iter().enumerate() {
            image.rgb[3 * i + c] = *v;
        }
    }
    image
}

/// One channel of an EXR file.
fn read_channel(path: &Path, name: &str) -> Vec<f32> {
    let (_, _, channels) = film::read_exr(path).unwrap();
    let found = channels.into_iter().find(|(n, _)| n == name);
    found
        .unwrap_or_else(|| panic!("no channel {name} in {}", path.display()))
        .1
}

/// The loss printed on the summary line, `<loss> loss <value> against ...`.
fn printed_loss(stdout: &str) -> f64 {
    let line = (stdout.lines())
        .find(|l| l.contains(" loss ") && l.contains(" against "))
        .unwrap_or_else(|| panic!("no loss line in {stdout}"));
    let value = line.split_whitespace().nth(2).unwrap();
    value
        .parse()
        .unwrap_or_else(|_| panic!("bad loss in {line}"))
}

/// The library's options for `--spp spp --seed seed` and the default budgets.
fn options(spp: u32, seed: u64, normalization: Normalization) -> DiffOptions {
    DiffOptions {
        render: RenderOptions {
            spp,
            seed,
            ..RenderOptions::default()
        },
        normalization,
        ..DiffOptions::default()
    }
}

/// A `.npy` file's values as a grid, checking that its header holds `shape`.
fn read_npy_checked(path: &Path, shape: [usize; 3]) -> Vec<f32> {
    let bytes = std::fs::read(path).unwrap();
    let header = String::from_utf8_lossy(&bytes[10..128.min(bytes.len())]).into_owned();
    let [nz, ny, nx] = shape;
    assert!(
        header.contains(&format!("'shape': ({nz}, {ny}, {nx})")) && header.contains("'<f4'"),
        "{header}"
    );
    let grid = implicit_psdr::sdf::read_npy(path).unwrap();
    assert_eq!(grid.dims, [nx, ny, nz]);
    grid.values
}

fn strings(names: &[&str]) -> Vec<String> {
    names.iter().map(|s| s.to_string()).collect()
}

/// `prefix` followed by `R`, `G`, `B`.
fn rgb(prefix: &str) -> Vec<String> {
    ["R", "G", "B"].map(|c| format!("{prefix}{c}")).to_vec()
}

/// grad.json has the promised fields and types, its loss is the one printed and the mean squared error
/// of the image `render` makes with the same seed, and every number (loss, parameters, grid values) is
/// the library's `loss_gradient` for the same scene, `--set`, seed and spp, bit for bit.
#[test]
fn grad_writes_what_the_library_computes() {
    let dir = setup("grad");
    let args = [
        "grad",
        "scene.json",
        "--target",
        "t.exr",
        "--param",
        "ball.radius",
        "--param",
        "light.center.y",
        "--grid",
        "blob",
        "--set",
        "ball.albedo.g=0.5",
        "--spp",
        "4",
        "--seed",
        "3",
    ];
    let stdout = assert_success(&run(&dir, &args));
    assert!(
        stdout.contains(
            "note: the gradient holds the interior, secondary (shadow) and primary (silhouette) terms"
        ),
        "{stdout}"
    );
    assert!(
        stdout.contains("with respect to 2 parameters and 210 values of 1 grid")
            && stdout.contains("at 4 spp")
            && stdout.contains("wrote grad.json and grad.blob.values.npy"),
        "{stdout}"
    );
    assert_eq!(
        outputs(&dir, &INPUTS),
        ["grad.blob.values.npy", "grad.json"]
    );
    let text = std::fs::read_to_string(dir.join("grad.json")).unwrap();
    let json: Value = serde_json::from_str(&text).unwrap();
    let object = json.as_object().unwrap();
    let mut keys: Vec<&str> = object.keys().map(String::as_str).collect();
    keys.sort();
    assert_eq!(keys, ["grids", "loss", "params", "seed", "spp"]);
    let loss = json["loss"].as_f64().unwrap();
    assert_eq!(printed_loss(&stdout), loss);
    assert_eq!(json["spp"].as_u64(), Some(4));
    assert_eq!(json["seed"].as_u64(), Some(3));
    let params = json["params"].as_object().unwrap();
    assert_eq!(params.len(), 2);
    // The parameters in --param order.
    assert!(
        text.find("ball.radius") < text.find("light.center.y"),
        "{text}"
    );
    assert_eq!(
        json["grids"],
        serde_json::json!({"blob": "grad.blob.values.npy"})
    );
    let values = read_npy_checked(&dir.join("grad.blob.values.npy"), SHAPE);
    assert!(values.iter().all(|v| v.is_finite()));
    assert!(values.iter().any(|&v| v != 0.0), "the blob is seen");

    // The loss is that of the image `render` makes with the same seed.
    let render = [
        "render",
        "scene.json",
        "--set",
        "ball.albedo.g=0.5",
        "--spp",
        "4",
        "--seed",
        "3",
    ];
    assert_success(&run(&dir, &render));
    let (image, target) = (
        read_image(&dir.join("out.exr")),
        read_image(&dir.join("t.exr")),
    );
    let sum: f64 = (image.rgb.iter().zip(&target.rgb))
        .map(|(&i, &t)| (i as f64 - t as f64).powi(2))
        .sum();
    let mse = sum / image.rgb.len() as f64;
    assert!((loss - mse).abs() <= 1e-12 * mse, "{loss} vs {mse}");

    // The library, for the same inputs.
    let scene = scene::load(&dir.join("scene.json"))
        .unwrap()
        .with_parameter("ball.albedo.g", 0.5)
        .unwrap();
    let params_wanted = strings(&["ball.radius", "light.center.y"]);
    let layout = GradientLayout::select(&scene, &params_wanted, &strings(&["blob"])).unwrap();
    let options = options(4, 3, Normalization::Differentiable);
    let want = loss_gradient(&scene, &layout, &target, Loss::L2, &options).unwrap();
    let total = want.gradient.total();
    assert_eq!(loss, want.loss);
    for (k, name) in params_wanted.iter().enumerate() {
        assert_eq!(params[name].as_f64(), Some(total[k]), "{name}");
    }
    let (block, first) = &layout.grids[0];
    assert_eq!(block.shape, SHAPE);
    let grid: Vec<f32> = total[*first..first + block.len()]
        .iter()
        .map(|&g| g as f32)
        .collect();
    assert_eq!(values, grid);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--out dir/NAME.json` writes `dir/NAME.NODE.values.npy` and names it in the JSON; a grid may be
/// given by its block name (`blob.values`); runs are deterministic bit for bit; `--loss l1` is the
/// mean absolute error.
#[test]
fn grad_out_names_grid_files_after_its_stem() {
    let dir = setup("grad-out");
    std::fs::create_dir(dir.join("runs")).unwrap();
    let grad = |out: &str, grid: &str, loss: &str| {
        let args = [
            "grad",
            "scene.json",
            "--target",
            "t.exr",
            "--grid",
            grid,
            "--loss",
            loss,
            "--spp",
            "2",
            "--out",
            out,
        ];
        assert_success(&run(&dir, &args))
    };
    let stdout = grad("runs/a.json", "blob.values", "l1");
    assert!(
        stdout.starts_with("note: ") && stdout.contains("l1 loss "),
        "{stdout}"
    );
    assert!(
        stdout.contains("wrote runs/a.json and runs/a.blob.values.npy"),
        "{stdout}"
    );
    grad("runs/b.json", "blob", "l1");
    assert_eq!(outputs(&dir, &INPUTS), ["runs"]);
    let mut files = outputs(&dir.join("runs"), &[]);
    files.sort();
    assert_eq!(
        files,
        ["a.blob.values.npy", "a.json", "b.blob.values.npy", "b.json"]
    );
    let json: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("runs/a.json")).unwrap()).unwrap();
    assert_eq!(
        json["grids"],
        serde_json::json!({"blob": "a.blob.values.npy"})
    );
    assert_eq!(json["params"], serde_json::json!({}));
    let read = |f: &str| std::fs::read(dir.join("runs").join(f)).unwrap();
    assert_eq!(read("a.blob.values.npy"), read("b.blob.values.npy"));

    // The L1 loss of the image of the same seed (0).
    assert_success(&run(&dir, &["render", "scene.json", "--spp", "2"]));
    let (image, target) = (
        read_image(&dir.join("out.exr")),
        read_image(&dir.join("t.exr")),
    );
    let sum: f64 = (image.rgb.iter().zip(&target.rgb))
        .map(|(&i, &t)| (i as f64 - t as f64).abs())
        .sum();
    let mae = sum / image.rgb.len() as f64;
    let loss = json["loss"].as_f64().unwrap();
    assert!((loss - mae).abs() <= 1e-12 * mae, "{loss} vs {mae}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A deterministic direction of grid values in [-1, 1].
fn direction() -> Vec<f32> {
    let mut rng = Rng::new(17);
    (0..SHAPE.iter().product::<usize>())
        .map(|_| 2.0 * rng.f32() - 1.0)
        .collect()
}

/// `diff --grid-direction blob=U.npy` writes `d.blob.values.*` (and its terms) after the `--param`s,
/// equal bit for bit to the library's derivative along U for the same seed.
#[test]
fn diff_grid_direction_writes_what_the_library_computes() {
    let dir = setup("diff-direction");
    let u = direction();
    std::fs::write(dir.join("u.npy"), npy_f32(&SHAPE, &u)).unwrap();
    let args = [
        "diff",
        "scene.json",
        "--param",
        "ball.radius",
        "--grid-direction",
        "blob=u.npy",
        "--spp",
        "4",
        "--seed",
        "1",
        "--terms",
    ];
    let stdout = assert_success(&run(&dir, &args));
    assert!(
        stdout.contains("d.blob.values: PNG colour scale ±"),
        "{stdout}"
    );
    let exr = dir.join("diff.exr");
    let (_, _, channels) = film::read_exr(&exr).unwrap();
    let mut names: Vec<String> = channels.into_iter().map(|(n, _)| n).collect();
    names.sort();
    let mut expected = rgb("");
    for term in ["d", "d_interior", "d_primary", "d_secondary"] {
        for p in ["ball.radius", "blob.values"] {
            expected.extend(rgb(&format!("{term}.{p}.")));
        }
    }
    expected.sort();
    assert_eq!(names, expected);

    let scene = scene::load(&dir.join("scene.json")).unwrap();
    let along = GridDirection {
        node: "blob".into(),
        shape: SHAPE.to_vec(),
        values: Arc::new(u),
        source: "u".into(),
    };
    let selection = scene
        .select_with_grid_directions(&["ball.radius"], &[along])
        .unwrap();
    assert_eq!(selection.names(), ["ball.radius", "blob.values"]);
    let options = options(4, 1, Normalization::Differentiable);
    let want = integrator::render_derivatives(&scene, &selection, &options).unwrap();
    let total = want.total();
    let mut nonzero = false;
    for (c, channel) in ["R", "G", "B"].into_iter().enumerate() {
        let got = read_channel(&exr, &format!("d.blob.values.{channel}"));
        assert!(got.iter().all(|v| v.is_finite()));
        nonzero |= got.iter().any(|&v| v != 0.0);
        assert_eq!(got, total[1].channel(c), "d.blob.values.{channel}");
        let got = read_channel(&exr, &format!("d.ball.radius.{channel}"));
        assert_eq!(got, total[0].channel(c), "d.ball.radius.{channel}");
    }
    assert!(nonzero, "the blob is seen");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The dot-product test across commands: `grad` (loss of seed 0, gradient from seed 1) dotted with U
/// equals `Σ_j g_j · d.blob.values_j` from `diff --seed 1`, `g = 2 (I − T) / n` the adjoint of the L2
/// loss of the image `render --seed 0` makes; the same for a named parameter. (With the fixed
/// normalisation, whose derivative of a pixel does not depend on the pixel's value.)
#[test]
fn grad_and_diff_agree_through_the_adjoint() {
    let dir = setup("grad-vs-diff");
    let u = direction();
    std::fs::write(dir.join("u.npy"), npy_f32(&SHAPE, &u)).unwrap();
    let common = ["scene.json", "--spp", "4", "--normalization", "fixed"];
    let grad = [
        "grad",
        "--target",
        "t.exr",
        "--param",
        "ball.radius",
        "--grid",
        "blob",
    ];
    assert_success(&run(&dir, &[&grad[..], &common[..]].concat()));
    let diff = [
        "diff",
        "--param",
        "ball.radius",
        "--grid-direction",
        "blob=u.npy",
        "--seed",
        "1",
    ];
    assert_success(&run(&dir, &[&diff[..], &common[..]].concat()));
    assert_success(&run(&dir, &["render", "scene.json", "--spp", "4"]));

    let (image, target) = (
        read_image(&dir.join("out.exr")),
        read_image(&dir.join("t.exr")),
    );
    let n = image.rgb.len() as f64;
    let adjoint: Vec<f64> = (image.rgb.iter().zip(&target.rgb))
        .map(|(&i, &t)| 2.0 * (i as f64 - t as f64) / n)
        .collect();
    let dot = |name: &str| -> (f64, f64) {
        let planes: Vec<Vec<f32>> = ["R", "G", "B"]
            .iter()
            .map(|c| read_channel(&dir.join("diff.exr"), &format!("d.{name}.{c}")))
            .collect();
        let terms = (0..adjoint.len()).map(|i| adjoint[i] * planes[i % 3][i / 3] as f64);
        terms.fold((0.0, 0.0), |(s, a), t| (s + t, a + t.abs()))
    };
    let json: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("grad.json")).unwrap()).unwrap();
    let grid = read_npy_checked(&dir.join("grad.blob.values.npy"), SHAPE);
    let reverse_grid: f64 = grid
        .iter()
        .zip(&u)
        .map(|(g, u)| *g as f64 * *u as f64)
        .sum();
    let reverse_radius = json["params"]["ball.radius"].as_f64().unwrap();
    for (name, reverse) in [
        ("blob.values", reverse_grid),
        ("ball.radius", reverse_radius),
    ] {
        let (forward, scale) = dot(name);
        println!("{name}: reverse {reverse:.6e} forward {forward:.6e} (Σ|terms| {scale:.3e})");
        assert!(
            (reverse - forward).abs() <= 1e-4 * scale.max(1e-9),
            "{name}: reverse {reverse} vs forward {forward}"
        );
        assert!(forward.abs() > 1e-3 * scale, "{name}: a meaningful check");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `params` lists the grid's values once, after the node's `level`, with its shape.
#[test]
fn params_lists_each_grid_once() {
    let dir = setup("params");
    let stdout = assert_success(&run(&dir, &["params", "scene.json"]));
    let lines: Vec<&str> = stdout.lines().collect();
    let grid: Vec<usize> = (0..lines.len())
        .filter(|&i| lines[i].contains("values"))
        .collect();
    assert_eq!(grid.len(), 1, "{stdout}");
    let i = grid[0];
    assert_eq!(
        lines[i],
        "blob.values [5, 6, 7] (210 values; select with --grid blob or --grid-direction \
         blob=U.npy)"
    );
    assert_eq!(lines[i - 1], "blob.level 0");
    for (k, line) in lines.iter().enumerate().filter(|(k, _)| *k != i) {
        let fields: Vec<&str> = line.split(' ').collect();
        assert!(
            fields.len() == 2 && fields[1].parse::<f32>().is_ok(),
            "line {k}: {line:?}"
        );
    }
    assert_eq!(outputs(&dir, &INPUTS), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_inputs_exit_2_without_output() {
    let dir = setup("bad");
    write_target(&dir.join("t8.exr"), 8, 8, &["R", "G", "B"]);
    write_target(&dir.join("rg.exr"), SIZE, SIZE, &["R", "G"]);
    std::fs::write(dir.join("u444.npy"), npy_f32(&[4, 4, 4], &[0.5; 64])).unwrap();
    std::fs::write(dir.join("u765.npy"), npy_f32(&[7, 6, 5], &[0.5; 210])).unwrap();
    // The scene with the box pixel filter: reverse mode refuses it after the loss pass has rendered.
    let text = std::fs::read_to_string(dir.join("scene.json")).unwrap();
    std::fs::write(dir.join("box.json"), text.replace("\"tent\"", "\"box\"")).unwrap();
    let inputs = [
        &INPUTS[..],
        &["t8.exr", "rg.exr", "u444.npy", "u765.npy", "box.json"],
    ]
    .concat();
    let grad = |extra: &[&str]| {
        let args = [
            &["grad", "scene.json", "--target", "t.exr", "--spp", "1"],
            extra,
        ]
        .concat();
        run(&dir, &args)
    };
    let cases: &[(&[&str], &str)] = &[
        (&["--param", "ball.radios"], "did you mean ball.radius?"),
        (
            &["--param", "ball.radius", "--param", "ball.radius"],
            "--param: parameter \"ball.radius\" is given twice",
        ),
        (
            &["--grid", "blub"],
            "scene.json: --grid: no grid node \"blub\" (grid nodes: blob)",
        ),
        (
            &[],
            "the following required arguments were not provided: <--param <P>|--grid <NODE>>",
        ),
        (
            &["--param", "ball.radius", "--loss", "l3"],
            "unknown loss \"l3\" (expected l2 or l1)",
        ),
        (
            &["--param", "ball.radius", "--out", "g.txt"],
            "--out g.txt: must end in .json",
        ),
        (
            &["--param", "ball.radius", "--out", "scene.json/g.json"],
            "--out scene.json/g.json: scene.json is a file, not a folder",
        ),
        (
            &["--param", "ball.radius", "--out", "./scene.json"],
            "--out ./scene.json: is the scene file",
        ),
    ];
    for (extra, expected) in cases {
        assert_failure(&grad(extra), expected);
    }
    let target_cases: &[(&str, &str)] = &[
        (
            "t8.exr",
            "t8.exr: the target is 8x8, the scene's image 16x16",
        ),
        ("rg.exr", "rg.exr: no channel B (channels: G, R)"),
        ("nope.exr", "nope.exr: "),
    ];
    for (target, expected) in target_cases {
        let args = ["grad", "scene.json", "--target", target, "--grid", "blob"];
        assert_failure(&run(&dir, &args), expected);
    }
    assert_failure(
        &run(&dir, &["grad", "scene.json", "--grid", "blob"]),
        "--target",
    );
    let args = [
        "grad",
        "box.json",
        "--target",
        "t.exr",
        "--param",
        "ball.radius",
        "--spp",
        "1",
    ];
    assert_failure(&run(&dir, &args), "box.json: camera.filter: ");

    let diff = |direction: &str| {
        let args = [
            "diff",
            "scene.json",
            "--spp",
            "1",
            "--grid-direction",
            direction,
        ];
        run(&dir, &args)
    };
    let cases: &[(&str, &str)] = &[
        (
            "blob=u444.npy",
            "u444.npy: shape [4, 4, 4], but grid \"blob\" has shape [5, 6, 7]",
        ),
        (
            "blob=u765.npy",
            "u765.npy: shape [7, 6, 5], but grid \"blob\" has shape [5, 6, 7]",
        ),
        (
            "blub=u765.npy",
            "scene.json: --grid-direction: no grid node \"blub\" (grid nodes: blob)",
        ),
        ("blob=nope.npy", "nope.npy: cannot read"),
        ("blob", "expected NODE=U.npy"),
    ];
    for (direction, expected) in cases {
        assert_failure(&diff(direction), expected);
    }
    assert_failure(
        &run(&dir, &["diff", "scene.json"]),
        "<--param <P>|--grid-direction <NODE=U.npy>>",
    );
    assert_eq!(outputs(&dir, &inputs), Vec::<String>::new());

    // A folder where a grid's gradient would go: refused before rendering.
    std::fs::create_dir(dir.join("grad.blob.values.npy")).unwrap();
    assert_failure(
        &grad(&["--grid", "blob"]),
        "grad.blob.values.npy: is a folder",
    );
    let inputs = [&inputs[..], &["grad.blob.values.npy"]].concat();
    assert_eq!(outputs(&dir, &inputs), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).unwrap();
}
