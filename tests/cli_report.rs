//! The `report` command on a tiny scene (16×16, budgets of a few seconds): the CSV has its documented
//! columns and one row per run, errors fall as spp grows for the unbiased estimators, the interior term
//! alone keeps a floor well above the complete derivative's on a parameter that moves a silhouette,
//! the plots are valid files, and bad inputs fail cleanly (exit code 2, one line, no output).

mod common;

use common::{assert_failure, assert_success, outputs, run};
use implicit_psdr::report::plot::PANEL_SIZE;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The columns `report.csv` documents (docs/report.md).
const COLUMNS: [&str; 11] = [
    "parameter",
    "estimator",
    "spp",
    "seed",
    "seconds",
    "raw_error",
    "blurred_error",
    "noise",
    "bias_floor",
    "reference_noise",
    "reference_floor",
];

/// A fresh folder holding the default scene at 16×16 as `scene.json`.
fn setup(name: &str) -> PathBuf {
    let dir = common::workdir("cli-report", name);
    common::write_small_scene(&dir, "scene.json", |_| {});
    dir
}

/// One row of report.csv.
#[derive(Debug)]
struct Row {
    parameter: String,
    estimator: String,
    spp: u32,
    seed: u64,
    raw: f64,
    blurred: f64,
    bias_floor: f64,
    reference_floor: Option<f64>,
}

/// The rows of `report.csv`, after checking its header and that every row has every column.
fn rows(path: &Path) -> Vec<Row> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap(), COLUMNS.join(","));
    lines
        .map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            assert_eq!(f.len(), COLUMNS.len(), "{line}");
            let num = |i: usize| -> f64 { f[i].parse().unwrap_or_else(|_| panic!("{line}")) };
            let seconds = num(4);
            assert!(seconds > 0.0 && seconds.is_finite(), "{line}");
            Row {
                parameter: f[0].to_string(),
                estimator: f[1].to_string(),
                spp: f[2].parse().unwrap(),
                seed: f[3].parse().unwrap(),
                raw: num(5),
                blurred: num(6),
                bias_floor: num(8),
                reference_floor: (!f[10].is_empty()).then(|| num(10)),
            }
        })
        .collect()
}

/// Per spp, the mean over the seeds of `value`, for one estimator; checks the points are 1, 2, 4, …
/// with two distinct seeds each.
fn series(rows: &[Row], estimator: &str, value: fn(&Row) -> f64) -> Vec<(u32, f64)> {
    let mut by_spp: BTreeMap<u32, Vec<&Row>> = BTreeMap::new();
    for r in rows.iter().filter(|r| r.estimator == estimator) {
        by_spp.entry(r.spp).or_default().push(r);
    }
    assert!(!by_spp.is_empty(), "no rows for {estimator}");
    for (k, (spp, runs)) in by_spp.iter().enumerate() {
        assert_eq!(*spp, 1 << k, "{estimator}: spp {spp} out of the doubling");
        assert_eq!(runs.len(), 2, "{estimator} at {spp} spp: {runs:?}");
        assert_ne!(runs[0].seed, runs[1].seed);
    }
    (by_spp.into_iter())
        .map(|(spp, runs)| (spp, runs.iter().map(|r| value(r)).sum::<f64>() / 2.0))
        .collect()
}

/// A PNG file decoded whole: its width and height.
fn decoded_png_size(path: &Path) -> (u32, u32) {
    let file = std::fs::File::open(path).unwrap();
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .unwrap();
    let mut buf = vec![0u8; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    (info.width, info.height)
}

#[test]
fn report_of_a_silhouette_parameter() {
    let dir = setup("radius");
    // A given reference (central differences at 4096 spp) costs a fraction of a computed one, which
    // the next test covers.
    let fd = [
        "fd",
        "scene.json",
        "--param",
        "ball.radius",
        "--spp",
        "4096",
        "--out",
        "ref.exr",
        "--png",
        "ref.png",
    ];
    assert_success(&run(&dir, &fd));
    let args = [
        "report",
        "scene.json",
        "--param",
        "ball.radius",
        "--reference",
        "ref.exr",
        "--estimators",
        "complete,interior,fd",
        "--budget",
        "6",
        "--out",
        "rep",
    ];
    assert_success(&run(&dir, &args));
    let out = dir.join("rep");
    assert_eq!(
        outputs(&out, &[]),
        ["report.csv", "report.md", "report.png", "report.svg"]
    );
    let rows = rows(&out.join("report.csv"));
    assert!(rows.iter().all(|r| r.parameter == "ball.radius"));
    assert!(rows.iter().all(|r| r.reference_floor.is_none()));

    // Unbiased estimators: the per-pixel error falls with the samples. The complete derivative's
    // boundary budgets stay at one sample per pixel up to 8 spp (and its silhouette term costs a
    // fixed 0.1–0.2 s a run), so only its interior part's noise falls over the few points it reaches.
    for (estimator, least_spp, factor) in [("complete", 4, 0.85), ("fd", 64, 0.4)] {
        let raw = series(&rows, estimator, |r| r.raw);
        let (first, last) = (raw[0], *raw.last().unwrap());
        assert!(last.0 >= least_spp, "{estimator} stopped at {} spp", last.0);
        assert!(
            last.1 < factor * first.1,
            "{estimator}: raw error {} at 1 spp, {} at {} spp",
            first.1,
            last.1,
            last.0
        );
    }
    let fd = series(&rows, "fd", |r| r.blurred);
    assert!(fd.last().unwrap().1 < 0.5 * fd[0].1, "fd blurred: {fd:?}");

    // The interior term alone misses the silhouette's term: a floor that more samples do not lower.
    let interior = series(&rows, "interior", |r| r.bias_floor);
    let complete = series(&rows, "complete", |r| r.bias_floor);
    let (i, c) = (interior.last().unwrap().1, complete.last().unwrap().1);
    assert!(interior.last().unwrap().0 >= 256, "{interior:?}");
    assert!(i > 2.0 * c && i > 0.2, "interior floor {i}, complete {c}");

    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    for needle in [
        "## `ball.radius`",
        "| complete |",
        "| interior |",
        "| fd |",
        "to 5%",
    ] {
        assert!(md.contains(needle), "report.md lacks {needle:?}:\n{md}");
    }
    assert_eq!(decoded_png_size(&out.join("report.png")), PANEL_SIZE);
    let svg = std::fs::read_to_string(out.join("report.svg")).unwrap();
    assert!(svg.trim_start().starts_with("<svg"), "{}", &svg[..80]);
    assert!(svg.trim_end().ends_with("</svg>"));
    for text in ["ball.radius", "interior", "complete", "seconds per run"] {
        assert!(svg.contains(text), "the SVG lacks {text:?}");
    }
}

#[test]
fn report_of_the_image_with_computed_references() {
    let dir = setup("computed");
    let args = [
        "report",
        "scene.json",
        "--param",
        "ball.center.x",
        "--estimators",
        "interior,primal",
        "--budget",
        "1",
    ];
    let result = run(&dir, &args);
    let stdout = assert_success(&result);
    assert!(stdout.contains("truncation"), "{stdout}");
    // Each estimator's floor, or that the budget ran out before it showed.
    for line in stdout.lines().filter(|l| l.contains(" to 5%: ")) {
        assert!(
            line.contains("bias floor 0.")
                || line.contains("bias floor not reached within the budget (error "),
            "{line}"
        );
    }
    // stderr is not a terminal here: one-line progress records, the first at once, the last at the
    // end, each with the time so far and to go.
    let stderr = String::from_utf8_lossy(&result.stderr);
    let records: Vec<&str> = stderr.lines().collect();
    assert!(records.len() >= 2, "{stderr}");
    for r in &records {
        assert!(
            r.starts_with("progress: ")
                && r.contains("s of budget spent; ")
                && r.contains(", eta "),
            "{stderr}"
        );
    }
    assert!(records[0].contains("; elapsed "), "{stderr}");
    assert!(
        records.last().unwrap().contains("; done; elapsed "),
        "{stderr}"
    );
    let out = dir.join("report");
    let rows = rows(&out.join("report.csv"));
    for r in &rows {
        let expected = if r.estimator == "primal" {
            "image"
        } else {
            "ball.center.x"
        };
        assert_eq!(r.parameter, expected, "{r:?}");
        let floor = r.reference_floor.expect("a computed reference has a floor");
        assert!(floor > 0.0 && floor < 0.05, "{r:?}");
    }
    let primal = series(&rows, "primal", |r| r.blurred);
    assert!(primal.last().unwrap().0 >= 64, "{primal:?}");
    assert!(primal.last().unwrap().1 < 0.25 * primal[0].1, "{primal:?}");
    // Two panels side by side: the parameter and the image, each with its reference's floor.
    let (w, h) = PANEL_SIZE;
    assert_eq!(decoded_png_size(&out.join("report.png")), (2 * w, h));
    let svg = std::fs::read_to_string(out.join("report.svg")).unwrap();
    assert_eq!(svg.matches("reference floor").count(), 2);
}

#[test]
fn bad_inputs_fail_before_anything_is_written() {
    let dir = setup("bad");
    let exr = |name: &str, size: u32, channels: &[&str]| {
        let n = (size * size) as usize;
        let list: implicit_psdr::film::Channels = (channels.iter())
            .map(|c| (c.to_string(), vec![0.5; n]))
            .collect();
        implicit_psdr::film::write_exr(&dir.join(name), size, size, &list).unwrap();
    };
    let radius = ["d.ball.radius.R", "d.ball.radius.G", "d.ball.radius.B"];
    exr("small.exr", 8, &radius);
    exr("other.exr", 16, &["R", "G", "B", "d.ball.center.x.R"]);
    let base = [
        "report",
        "scene.json",
        "--param",
        "ball.radius",
        "--out",
        "rep",
    ];
    let cases: [(&[&str], &str); 8] = [
        (&["--param", "ball.radus"], "ball.radus"),
        (&["--estimators", "complete,fdd"], "\"fdd\""),
        (&["--budget", "-1"], "--budget"),
        (&["--budget", "nan"], "--budget"),
        (&["--reference", "missing.exr"], "missing.exr"),
        (&["--reference", "small.exr"], "8x8"),
        (&["--reference", "other.exr"], "d.ball.radius.R"),
        (&["--param", "ball.radius"], "twice"),
    ];
    for (extra, expected) in cases {
        let args: Vec<&str> = base.iter().chain(extra).copied().collect();
        assert_failure(&run(&dir, &args), expected);
        assert_eq!(
            outputs(&dir, &["scene.json", "small.exr", "other.exr"]),
            Vec::<String>::new(),
            "{args:?} left files"
        );
    }
    let missing = ["report", "nope.json", "--param", "ball.radius"];
    assert_failure(&run(&dir, &missing), "nope.json");
}
