//! Where the commands write, and `fd` with many parameters: every command creates a missing folder
//! of its output paths (and refuses one blocked by a file, before rendering, writing nothing); `fd`
//! with several `--param`s writes, per parameter, the channels a run with that parameter alone
//! writes, bit for bit (each a pair of renders with the image's samples).

mod common;

use common::{assert_failure, assert_success, outputs, run, write_small_scene};
use std::path::Path;

fn workdir(name: &str) -> std::path::PathBuf {
    common::workdir("cli-outputs", name)
}

fn channels(path: &Path) -> Vec<(String, Vec<f32>)> {
    implicit_psdr::film::read_exr(path).unwrap().2
}

#[test]
fn fd_of_several_parameters_is_each_parameter_alone() {
    let dir = workdir("fd");
    write_small_scene(&dir, "scene.json", |_| {});
    let fd = |params: &[&str], out: &str| {
        let (exr, png) = (format!("{out}.exr"), format!("{out}.png"));
        let mut args = vec!["fd", "scene.json", "--out", &exr, "--png", &png];
        for p in params {
            args.extend(["--param", p]);
        }
        assert_success(&run(&dir, &args))
    };
    let stdout = fd(&["ball.radius", "light.center.x"], "both");
    assert!(
        stdout.contains("ball.radius = 1 with h = 0.01, light.center.x = 1.5 with h = 0.015"),
        "{stdout}"
    );
    assert!(stdout.contains("5 times"), "{stdout}");
    fd(&["ball.radius"], "radius");
    fd(&["light.center.x"], "light");
    let both = channels(&dir.join("both.exr"));
    let names: Vec<&str> = both.iter().map(|(n, _)| n.as_str()).collect();
    for name in ["R", "d.ball.radius.R", "d.light.center.x.B"] {
        assert!(names.contains(&name), "{names:?}");
    }
    let alone: Vec<_> = [
        channels(&dir.join("radius.exr")),
        channels(&dir.join("light.exr")),
    ]
    .concat();
    for (name, values) in &both {
        let single = alone.iter().find(|(n, _)| n == name).unwrap();
        assert_eq!(&single.1, values, "{name}");
    }
    // Every name and step is checked before anything is rendered.
    assert_failure(
        &run(
            &dir,
            &[
                "fd",
                "scene.json",
                "--param",
                "ball.radius",
                "--param",
                "ball.radios",
                "--out",
                "bad.exr",
            ],
        ),
        "no parameter \"ball.radios\"",
    );
    assert!(!dir.join("bad.exr").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn every_command_creates_a_missing_output_folder() {
    let dir = workdir("folders");
    write_small_scene(&dir, "scene.json", |_| {});
    let p = "ball.radius";
    let runs: [&[&str]; 6] = [
        &[
            "render",
            "scene.json",
            "--out",
            "a/r/x.exr",
            "--png",
            "b/r/x.png",
        ],
        &[
            "diff",
            "scene.json",
            "--param",
            p,
            "--out",
            "a/d/x.exr",
            "--png",
            "b/d/x.png",
        ],
        &[
            "fd",
            "scene.json",
            "--param",
            p,
            "--out",
            "a/f/x.exr",
            "--png",
            "b/f/x.png",
        ],
        &[
            "grad",
            "scene.json",
            "--target",
            "a/r/x.exr",
            "--param",
            p,
            "--out",
            "a/g/x.json",
        ],
        &[
            "bake",
            "scene.json",
            "--shape",
            "ball",
            "--res",
            "4",
            "--out",
            "a/k/x.npy",
        ],
        &[
            "report",
            "scene.json",
            "--param",
            p,
            "--estimators",
            "primal",
            "--budget",
            "0.05",
            "--out",
            "a/p/r",
        ],
    ];
    // Blocked by a file: refused before anything is rendered, nothing written.
    std::fs::write(dir.join("file"), "").unwrap();
    for args in runs {
        let blocked: Vec<String> = args
            .iter()
            .map(|a| a.replacen("a/", "file/", 1).replacen("b/", "file/", 1))
            .collect();
        let blocked: Vec<&str> = blocked.iter().map(String::as_str).collect();
        let out = run(&dir, &blocked);
        assert_failure(&out, "file is a file, not a folder");
    }
    assert_eq!(outputs(&dir, &["scene.json"]), ["file"]);
    for args in runs {
        assert_success(&run(&dir, args));
    }
    for file in [
        "a/r/x.exr",
        "b/r/x.png",
        "a/d/x.exr",
        "b/d/x.png",
        "a/f/x.exr",
        "b/f/x.png",
        "a/g/x.json",
        "a/k/x.npy",
        "a/p/r/report.md",
    ] {
        assert!(dir.join(file).is_file(), "{file}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
