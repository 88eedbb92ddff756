//! The derivative commands of the tool: `params`, `diff`, `fd` and `compare` write exactly the channels
//! they promise, agree with each other on a linear parameter, and fail cleanly (exit code 2, one line on
//! stderr, no output file) on bad inputs.

use implicit_psdr::film::{self, figure};
mod common;

use common::{assert_failure, assert_success, outputs, run};
use std::path::{Path, PathBuf};

/// A fresh, empty working folder for one test.
fn workdir(name: &str) -> PathBuf {
    common::workdir("cli-diff", name)
}

/// The default scene (`scenes/sphere_floor.json`) at 16×16 pixels, 4 spp, with `edit` applied, written
/// to `dir/scene.json`.
fn write_scene(dir: &Path, edit: impl FnOnce(&mut serde_json::Value)) {
    common::write_small_scene(dir, "scene.json", edit);
}

/// The sorted channel names of an EXR file, and its size.
fn exr_channels(path: &Path) -> (u32, u32, Vec<String>) {
    let (w, h, channels) = film::read_exr(path).unwrap();
    let mut names: Vec<String> = channels.into_iter().map(|(n, _)| n).collect();
    names.sort();
    (w, h, names)
}

/// Width and height of a PNG file, from its IHDR chunk.
fn png_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let be = |i: usize| u32::from_be_bytes(bytes[i..i + 4].try_into().unwrap());
    (be(16), be(20))
}

/// Size of the picture of a 16×16 render with `panels` panels (the image and the derivatives).
fn figure_size(panels: u32) -> (u32, u32) {
    let side = 16 * figure::magnification(16);
    let width = panels * side + (panels - 1) * film::colormap::PANEL_GAP;
    (width, figure::TITLE_HEIGHT + side + figure::BAR_HEIGHT)
}

/// `prefix` followed by `R`, `G`, `B`.
fn rgb(prefix: &str) -> Vec<String> {
    ["R", "G", "B"]
        .iter()
        .map(|c| format!("{prefix}{c}"))
        .collect()
}

fn sorted(mut v: Vec<String>) -> Vec<String> {
    v.sort();
    v
}

/// The relative L2 error `compare` prints for `channel` (second column of its row).
fn printed_error(stdout: &str, channel: &str) -> f64 {
    let row = stdout
        .lines()
        .find(|l| l.split_whitespace().next() == Some(channel))
        .unwrap_or_else(|| panic!("no row for {channel} in {stdout}"));
    row.split_whitespace().nth(1).unwrap().parse().unwrap()
}

/// Writes an EXR of `width × height` with the named channels, each a deterministic ramp.
fn write_exr(path: &Path, width: u32, height: u32, names: &[&str]) {
    let n = (width * height) as usize;
    let channels: film::Channels = names
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let values = (0..n).map(|i| (i + k) as f32 * 0.1 - 1.0).collect();
            (name.to_string(), values)
        })
        .collect();
    film::write_exr(path, width, height, &channels).unwrap();
}

#[test]
fn params_lists_the_default_scene() {
    let dir = workdir("params");
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/sphere_floor.json");
    let stdout = assert_success(&run(&dir, &["params", scenes.to_str().unwrap()]));
    let lines: Vec<&str> = stdout.lines().collect();
    for expected in [
        "ball.radius 1",
        "ball.albedo.r 0.8",
        "light.center.y 4",
        "ball.translate.x 0",
    ] {
        assert!(lines.contains(&expected), "{expected:?} not in {stdout}");
    }
    assert!(lines.iter().all(|l| l.split(' ').count() == 2), "{stdout}");
    assert_eq!(outputs(&dir, &[]), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A sharp floor's edges and a bounded hard CSG crease are sampled (no note, with either
/// integrator); a crease of unbounded CSG children is named.
#[test]
fn diff_note_names_creased_shapes() {
    let dir = workdir("diff-crease");
    let args = [
        "diff",
        "scene.json",
        "--param",
        "ball.translate.x",
        "--spp",
        "1",
    ];
    for integrator in [
        serde_json::json!({"type": "direct"}),
        serde_json::json!({"type": "path", "max_depth": 2}),
    ] {
        write_scene(&dir, |v| {
            v["shapes"][1]["sdf"]["rounding"] = serde_json::json!(0);
            v["integrator"] = integrator;
        });
        let stdout = assert_success(&run(&dir, &args));
        assert!(!stdout.contains("crease"), "{stdout}");
    }
    write_scene(&dir, |v| {
        let ball = v["shapes"][0]["sdf"].clone();
        v["shapes"][0]["sdf"] = serde_json::json!({"type": "intersection", "children": [
            ball,
            {"type": "sphere", "center": [0.5, 0.0, 0.0], "radius": 1.0}
        ]});
    });
    let stdout = assert_success(&run(&dir, &args));
    assert!(!stdout.contains("crease"), "{stdout}");
    // Two planes cross along a line no finite box of the shape holds: sampled within the scene's
    // crease region only, and named with it.
    write_scene(&dir, |v| {
        v["shapes"][0]["sdf"] = serde_json::json!({"type": "intersection", "children": [
            {"type": "plane", "normal": [0.0, 1.0, 0.0], "offset": 0.0},
            {"type": "plane", "normal": [1.0, 0.0, 0.0], "offset": 0.0}
        ]});
    });
    let stdout = assert_success(&run(&dir, &args));
    assert!(
        stdout.contains("not sampled along crease curves")
            && stdout.contains(
                "ball (hard CSG of unbounded children (planes) whose crease no bounded child \
                 cuts, sampled only within ["
            ),
        "{stdout}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn diff_writes_the_promised_channels() {
    let dir = workdir("diff");
    write_scene(&dir, |_| {});
    let out = run(
        &dir,
        &[
            "diff",
            "scene.json",
            "--param",
            "ball.radius",
            "--param",
            "light.center.y",
            "--spp",
            "2",
        ],
    );
    let stdout = assert_success(&out);
    assert!(
        stdout.contains(
            "note: derivatives hold the interior, secondary (shadow) and primary (silhouette) terms"
        ),
        "{stdout}"
    );
    // The default scene's shapes are all smooth: no crease warning.
    assert!(!stdout.contains("crease"), "{stdout}");
    assert!(
        stdout.contains("d.ball.radius: PNG colour scale ±"),
        "{stdout}"
    );
    assert!(
        stdout.contains("d.light.center.y: PNG colour scale ±"),
        "{stdout}"
    );
    assert_eq!(outputs(&dir, &["scene.json"]), ["diff.exr", "diff.png"]);
    let (w, h, names) = exr_channels(&dir.join("diff.exr"));
    assert_eq!((w, h), (16, 16));
    let expected = [rgb(""), rgb("d.ball.radius."), rgb("d.light.center.y.")].concat();
    assert_eq!(names, sorted(expected));
    // The image and two panels, 4 pixels apart, magnified, under their titles and above the
    // derivatives' colour bars.
    assert_eq!(png_size(&dir.join("diff.png")), figure_size(3));

    // --terms adds each term under its own name; other file names.
    let out = run(
        &dir,
        &[
            "diff",
            "scene.json",
            "--param",
            "ball.radius",
            "--spp",
            "1",
            "--terms",
            "--out",
            "t.exr",
            "--png",
            "t.png",
        ],
    );
    assert_success(&out);
    let (_, _, names) = exr_channels(&dir.join("t.exr"));
    let expected = [
        rgb(""),
        rgb("d.ball.radius."),
        rgb("d_interior.ball.radius."),
        rgb("d_primary.ball.radius."),
        rgb("d_secondary.ball.radius."),
    ]
    .concat();
    assert_eq!(names, sorted(expected));
    assert_eq!(png_size(&dir.join("t.png")), figure_size(2));

    // Without boundary samples the derivative is the interior term, and the command says so.
    let out = run(
        &dir,
        &[
            "diff",
            "scene.json",
            "--param",
            "ball.radius",
            "--spp",
            "1",
            "--terms",
            "--spp-secondary",
            "0",
            "--spp-primary",
            "0",
            "--out",
            "i.exr",
            "--png",
            "i.png",
        ],
    );
    let stdout = assert_success(&out);
    assert!(
        stdout.contains("note: derivatives hold the interior term only"),
        "{stdout}"
    );
    let (_, _, names) = exr_channels(&dir.join("i.exr"));
    let expected = [
        rgb(""),
        rgb("d.ball.radius."),
        rgb("d_interior.ball.radius."),
    ]
    .concat();
    assert_eq!(names, sorted(expected));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A `path` scene gets both boundary terms too, and the note says so.
#[test]
fn diff_adds_the_boundary_terms_of_path_scenes() {
    let dir = workdir("diff-path");
    write_scene(&dir, |v| {
        v["integrator"] = serde_json::json!({"type": "path", "max_depth": 2});
    });
    let out = run(
        &dir,
        &[
            "diff",
            "scene.json",
            "--param",
            "ball.radius",
            "--spp",
            "1",
            "--spp-secondary",
            "8",
            "--spp-primary",
            "0.5",
            "--terms",
        ],
    );
    let stdout = assert_success(&out);
    assert!(
        stdout.contains(
            "note: derivatives hold the interior, secondary (shadow) and primary (silhouette) terms"
        ),
        "{stdout}"
    );
    assert!(!stdout.contains("path integrator"), "{stdout}");
    let (_, _, names) = exr_channels(&dir.join("diff.exr"));
    let expected = [
        rgb(""),
        rgb("d.ball.radius."),
        rgb("d_interior.ball.radius."),
        rgb("d_primary.ball.radius."),
        rgb("d_secondary.ball.radius."),
    ]
    .concat();
    assert_eq!(names, sorted(expected));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn fd_writes_the_promised_channels() {
    let dir = workdir("fd");
    write_scene(&dir, |_| {});
    let out = run(
        &dir,
        &["fd", "scene.json", "--param", "ball.radius", "--spp", "2"],
    );
    let stdout = assert_success(&out);
    assert!(stdout.contains("ball.radius = 1 with h = 0.01"), "{stdout}");
    assert_eq!(outputs(&dir, &["scene.json"]), ["fd.exr", "fd.png"]);
    let (w, h, names) = exr_channels(&dir.join("fd.exr"));
    assert_eq!((w, h), (16, 16));
    assert_eq!(names, sorted([rgb(""), rgb("d.ball.radius.")].concat()));
    assert_eq!(png_size(&dir.join("fd.png")), figure_size(2));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn compare_of_a_file_with_itself() {
    let dir = workdir("compare-self");
    write_exr(
        &dir.join("a.exr"),
        8,
        4,
        &["R", "G", "B", "d.p.R", "d_interior.p.R"],
    );
    let stdout = assert_success(&run(&dir, &["compare", "a.exr", "a.exr"]));
    assert_eq!(printed_error(&stdout, "d.p.R"), 0.0);
    assert_eq!(printed_error(&stdout, "d_interior.p.R"), 0.0);
    // Image channels only when asked for.
    assert!(!stdout.lines().any(|l| l.starts_with("R ")), "{stdout}");
    let stdout = assert_success(&run(&dir, &["compare", "a.exr", "a.exr", "--channel", "R"]));
    assert_eq!(printed_error(&stdout, "R"), 0.0);
    assert!(!stdout.contains("d.p.R"), "{stdout}");
    assert_eq!(outputs(&dir, &["a.exr"]), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn compare_rejects_mismatched_files() {
    let dir = workdir("compare-bad");
    write_exr(&dir.join("a.exr"), 8, 4, &["R", "d.p.R"]);
    write_exr(&dir.join("b.exr"), 4, 8, &["R", "d.p.R"]);
    write_exr(&dir.join("c.exr"), 8, 4, &["R", "d.q.R"]);
    let inputs = ["a.exr", "b.exr", "c.exr"];
    assert_failure(
        &run(&dir, &["compare", "a.exr", "b.exr"]),
        "image sizes differ: 8x4 and 4x8",
    );
    assert_failure(
        &run(&dir, &["compare", "a.exr", "c.exr"]),
        "no derivative channel",
    );
    assert_failure(
        &run(&dir, &["compare", "a.exr", "a.exr", "--channel", "d.q"]),
        "no channel starting with \"d.q\"",
    );
    assert_failure(&run(&dir, &["compare", "a.exr", "nope.exr"]), "nope.exr");
    assert_eq!(outputs(&dir, &inputs), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The albedo enters the image linearly: the forward-mode derivative and the central difference agree
/// to rounding (same seed, same samples), so `compare` reports a tiny error.
#[test]
fn diff_and_fd_agree_on_a_linear_parameter() {
    let dir = workdir("diff-vs-fd");
    write_scene(&dir, |_| {});
    let common = ["scene.json", "--param", "ball.albedo.r", "--spp", "2"];
    assert_success(&run(&dir, &[&["diff"], &common[..]].concat()));
    assert_success(&run(&dir, &[&["fd"], &common[..]].concat()));
    let stdout = assert_success(&run(&dir, &["compare", "diff.exr", "fd.exr"]));
    let error = printed_error(&stdout, "d.ball.albedo.r.R");
    assert!(error < 1e-3, "relative error {error}\n{stdout}");
    // The green and blue channels do not depend on the red albedo: both zero.
    assert_eq!(printed_error(&stdout, "d.ball.albedo.r.G"), 0.0);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_arguments_exit_2_without_output() {
    let dir = workdir("bad-args");
    write_scene(&dir, |_| {});
    let cases: &[(&[&str], &str)] = &[
        (&["diff", "scene.json"], "--param"),
        (
            &[
                "diff",
                "scene.json",
                "--param",
                "ball.radius",
                "--param",
                "ball.radius",
            ],
            "--param: parameter \"ball.radius\" is given twice",
        ),
        (
            &[
                "diff",
                "scene.json",
                "--param",
                "ball.radius",
                "--out",
                "scene.json/x.exr",
            ],
            "--out scene.json/x.exr: scene.json is a file, not a folder",
        ),
        (
            &[
                "diff",
                "scene.json",
                "--param",
                "ball.radius",
                "--normalization",
                "soft",
            ],
            "--normalization",
        ),
        (
            &[
                "diff",
                "scene.json",
                "--param",
                "ball.radius",
                "--velocity-field",
                "tangent",
            ],
            "--velocity-field",
        ),
        (
            &[
                "diff",
                "scene.json",
                "--param",
                "ball.radius",
                "--spp-secondary",
                "-0.5",
            ],
            "--spp-secondary",
        ),
        (
            &[
                "diff",
                "scene.json",
                "--param",
                "ball.radius",
                "--spp-primary",
                "NaN",
            ],
            "--spp-primary",
        ),
        (
            &["fd", "scene.json", "--param", "ball.radius", "--h", "0"],
            "--h",
        ),
        (
            &["fd", "scene.json", "--param", "ball.radius", "--h=-1"],
            "--h",
        ),
        (&["fd", "scene.json"], "--param"),
        (
            &["diff", "missing.json", "--param", "ball.radius"],
            "missing.json",
        ),
        (&["params", "missing.json"], "missing.json"),
    ];
    for (args, expected) in cases {
        assert_failure(&run(&dir, args), expected);
    }
    assert_eq!(outputs(&dir, &["scene.json"]), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--velocity-field`: on the default scene `auto` keeps the normal field (the ball's curvature radius
/// is far above a pixel), bit for bit, and `carried` moves the ball rigidly: another estimate.
#[test]
fn diff_velocity_field_chooses_the_motion() {
    let dir = workdir("velocity-field");
    write_scene(&dir, |_| {});
    let channels = |field: &str| {
        let out = format!("{field}.exr");
        let args = [
            "diff",
            "scene.json",
            "--param",
            "ball.center.x",
            "--velocity-field",
            field,
            "--out",
            &out,
            "--png",
            &format!("{field}.png"),
        ];
        assert_success(&run(&dir, &args));
        let (_, _, c) = film::read_exr(&dir.join(&out)).unwrap();
        c
    };
    let (auto, normal, carried) = (channels("auto"), channels("normal"), channels("carried"));
    assert_eq!(auto, normal);
    assert_ne!(auto, carried);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_parameters_exit_2_without_output() {
    let dir = workdir("bad-params");
    write_scene(&dir, |_| {});
    std::fs::write(
        dir.join("box.json"),
        std::fs::read_to_string(dir.join("scene.json"))
            .unwrap()
            .replace("\"tent\"", "\"box\""),
    )
    .unwrap();
    let inputs = ["scene.json", "box.json"];
    // Unknown names: the registry's message, with near matches.
    assert_failure(
        &run(&dir, &["diff", "scene.json", "--param", "ball.radios"]),
        "ball.radius",
    );
    assert_failure(
        &run(&dir, &["fd", "scene.json", "--param", "ball.radios"]),
        "ball.radius",
    );
    // A step that makes the radius negative: the message names the step, both values and the file.
    let out = run(
        &dir,
        &["fd", "scene.json", "--param", "ball.radius", "--h", "2"],
    );
    assert_failure(
        &out,
        "scene.json: ball.radius: must be > 0, got -1 (the step h = 2 takes ball.radius = 1 to 3 and -1)",
    );
    // A negative step is a value, not a flag.
    assert_failure(
        &run(
            &dir,
            &["fd", "scene.json", "--param", "ball.radius", "--h", "-0.01"],
        ),
        "expected a finite number > 0, got \"-0.01\"",
    );
    // Derivatives through a box filter are refused by the library, naming the file and field.
    assert_failure(
        &run(&dir, &["diff", "box.json", "--param", "ball.radius"]),
        "box.json: camera.filter: the interior term with the box filter",
    );
    // Outputs must carry their format's extension.
    assert_failure(
        &run(
            &dir,
            &[
                "diff",
                "scene.json",
                "--param",
                "ball.radius",
                "--out",
                "p.txt",
            ],
        ),
        "--out p.txt: must end in .exr",
    );
    assert_failure(
        &run(&dir, &["render", "scene.json", "--png", "p.exr"]),
        "--png p.exr: must end in .png",
    );
    // --set: unknown names, out-of-range and malformed values.
    for (set, expected) in [
        ("ball.radios=1", "ball.radius"),
        (
            "ball.radius=-1",
            "--set ball.radius=-1: scene.json: ball.radius: must be > 0, got -1",
        ),
        ("ball.radius", "expected NAME=VALUE"),
        ("ball.radius=nan", "is not a finite number"),
    ] {
        assert_failure(
            &run(&dir, &["render", "scene.json", "--set", set]),
            expected,
        );
    }
    assert_eq!(outputs(&dir, &inputs), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--set NAME=VALUE` renders what editing the scene file renders, bit for bit.
#[test]
fn set_overrides_a_parameter_like_the_file() {
    let dir = workdir("set");
    write_scene(&dir, |_| {});
    common::write_small_scene(&dir, "edited.json", |v| {
        v["shapes"][0]["sdf"]["radius"] = 0.7.into()
    });
    let set = run(
        &dir,
        &[
            "render",
            "scene.json",
            "--spp",
            "2",
            "--set",
            "ball.radius=0.7",
            "--out",
            "set.exr",
            "--png",
            "set.png",
        ],
    );
    assert!(
        set.status.success(),
        "{}",
        String::from_utf8_lossy(&set.stderr)
    );
    let edited = run(
        &dir,
        &[
            "render",
            "edited.json",
            "--spp",
            "2",
            "--out",
            "edited.exr",
            "--png",
            "edited.png",
        ],
    );
    assert!(
        edited.status.success(),
        "{}",
        String::from_utf8_lossy(&edited.stderr)
    );
    let plain = run(&dir, &["render", "scene.json", "--spp", "2"]);
    assert!(plain.status.success());
    let read = |f: &str| implicit_psdr::film::read_exr(&dir.join(f)).unwrap().2;
    assert_eq!(read("set.exr"), read("edited.exr"));
    assert_ne!(read("set.exr"), read("out.exr"));
    std::fs::remove_dir_all(&dir).unwrap();
}
