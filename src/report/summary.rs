//! What a finished report says: times to reach an error, bias floors, and the texts of `report.csv`
//! and `report.md`.

use super::Estimator;
use super::protocol::{Report, Run, Section};
use std::fmt::Write as _;

/// The blurred errors `report.md` gives the time to reach.
pub const TARGETS: [f64; 3] = [0.10, 0.05, 0.02];

/// The columns of `report.csv`, in order.
pub const CSV_COLUMNS: [&str; 11] = [
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

/// The name of a section in the CSV, the Markdown and the plot: the parameter, or `image`.
pub fn section_name(parameter: Option<&str>) -> &str {
    parameter.unwrap_or("image")
}

/// One point of a series: the spp and the mean over its two seeds of the run time and the blurred
/// error, and the point's bias floor (the mean blurred error less the noise, in quadrature).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    /// Samples per pixel.
    pub spp: u32,
    /// Mean run time of the seeds, seconds.
    pub seconds: f64,
    /// Mean blurred error of the seeds.
    pub blurred_error: f64,
    /// Mean raw error of the seeds.
    pub raw_error: f64,
    /// `√max(blurred_error² − noise², 0)`.
    pub bias_floor: f64,
    /// One run's seed-to-seed noise at this spp (blurred, relative).
    pub noise: f64,
}

/// The share of the bias floor under which a point's noise must be for the floor to count as reached:
/// with noise at most half the floor, the floor is most of the error (`floor² ≥ 4 · noise²`), so the
/// estimate is bias rather than a small difference of two noisy numbers.
pub const FLOOR_NOISE_SHARE: f64 = 0.5;

/// Whether the point's bias floor is reached: its noise is at most [`FLOOR_NOISE_SHARE`] of the
/// floor. Otherwise the budget ran out before the error stopped falling with the samples, and the
/// floor is not known (it may be as small as zero, or as large as the error).
pub fn floor_reached(point: &Point) -> bool {
    point.noise <= FLOOR_NOISE_SHARE * point.bias_floor
}

/// The bias floor of a series' last point as the table and the command print it: the floor (`5.3%`),
/// or that it was not reached within the budget, with the error and noise it saw.
pub fn describe_floor(point: &Point) -> String {
    match floor_reached(point) {
        true => percent(point.bias_floor),
        false => format!(
            "not reached within the budget (error {}, noise {} at {} spp)",
            percent(point.blurred_error),
            percent(point.noise),
            point.spp
        ),
    }
}

/// The points of `estimator` in `section`, by increasing spp.
pub fn points(section: &Section, estimator: Estimator) -> Vec<Point> {
    let runs: Vec<&Run> = (section.runs.iter())
        .filter(|r| r.estimator == estimator)
        .collect();
    let mut points: Vec<Point> = Vec::new();
    for chunk in runs.chunk_by(|a, b| a.spp == b.spp) {
        let n = chunk.len() as f64;
        let mean = |f: fn(&Run) -> f64| chunk.iter().map(|r| f(r)).sum::<f64>() / n;
        let blurred = mean(|r| r.blurred_error);
        points.push(Point {
            spp: chunk[0].spp,
            seconds: mean(|r| r.seconds),
            blurred_error: blurred,
            raw_error: mean(|r| r.raw_error),
            bias_floor: super::bias_floor(blurred, chunk[0].noise),
            noise: chunk[0].noise,
        });
    }
    points
}

/// The time one run takes to reach a blurred error below `target`: the mean run time at the first spp
/// whose mean blurred error over the two seeds is below it (not interpolated: a run of that spp is the
/// cheapest the protocol saw reach it), with that spp; `None` if no point did.
pub fn time_to(points: &[Point], target: f64) -> Option<(f64, u32)> {
    (points.iter())
        .find(|p| p.blurred_error < target)
        .map(|p| (p.seconds, p.spp))
}

/// The estimators with runs in `section`, in the order of [`Estimator::ALL`].
pub fn estimators(section: &Section) -> Vec<Estimator> {
    (Estimator::ALL.into_iter())
        .filter(|e| section.runs.iter().any(|r| r.estimator == *e))
        .collect()
}

/// A number for the CSV: empty when unknown.
fn csv_number(v: Option<f64>) -> String {
    v.map_or(String::new(), |v| format!("{v:.6e}"))
}

/// The text of `report.csv`: a header of [`CSV_COLUMNS`] and one row per run.
pub fn csv(report: &Report) -> String {
    let mut text = CSV_COLUMNS.join(",") + "\n";
    for section in &report.sections {
        let reference = &section.reference;
        for r in &section.runs {
            let _ = writeln!(
                text,
                "{},{},{},{},{:.6},{:.6e},{:.6e},{:.6e},{:.6e},{},{}",
                section_name(r.parameter.as_deref()),
                r.estimator.name(),
                r.spp,
                r.seed,
                r.seconds,
                r.raw_error,
                r.blurred_error,
                r.noise,
                r.bias_floor,
                csv_number(reference.noise),
                csv_number(reference.floor()),
            );
        }
    }
    text
}

/// A time to reach a target, as `report.md` shows it.
fn show_time(t: Option<(f64, u32)>) -> String {
    match t {
        Some((s, spp)) => format!("{} ({spp} spp)", seconds(s)),
        None => "not reached".into(),
    }
}

/// A duration with about three significant digits: `1.23 s`, `0.123 s`, `4.56 ms`.
pub fn seconds(s: f64) -> String {
    if s >= 1.0 {
        format!("{s:.2} s")
    } else if s >= 0.01 {
        format!("{s:.3} s")
    } else {
        format!("{:.2} ms", s * 1e3)
    }
}

/// A percentage with about two significant digits (whole percentages without decimals).
pub fn percent(v: f64) -> String {
    if !v.is_finite() {
        return "∞".into();
    }
    let p = 100.0 * v;
    if p >= 10.0 || (p - p.round()).abs() < 1e-9 {
        format!("{p:.0}%")
    } else if p >= 1.0 {
        format!("{p:.1}%")
    } else {
        format!("{p:.2}%")
    }
}

/// What a section's reference is, in one line.
pub fn describe_reference(section: &Section) -> String {
    let r = &section.reference;
    let Some(noise) = r.noise else {
        return "the given EXR (its own error is unknown)".into();
    };
    let what = match r.step {
        Some(h) => format!("`fd` with step {h} (half the default)"),
        None => "`render`".into(),
    };
    let truncation = r
        .truncation
        .map_or(String::new(), |t| format!(", truncation ≤ {}", percent(t)));
    format!(
        "{what} at {} spp ({:.1} s): own noise {}{truncation}, floor {}",
        r.spp,
        r.seconds,
        percent(noise),
        percent(r.floor().unwrap_or(noise))
    )
}

/// The text of `report.md`: per section, its reference, the time one run takes to reach each of
/// [`TARGETS`] for each estimator, the bias floor at each estimator's largest spp, and the ratio of
/// `fd`'s time to the complete derivative's.
pub fn markdown(report: &Report) -> String {
    let mut t = String::from("# Speed against error\n\n");
    let _ = writeln!(
        t,
        "Budget {:.1} s in all, {:.2} s per estimator and parameter. Errors: relative L2 over R, G, B \
         after a 5×5 box blur, mean of two seeds. A time is one run's at the first spp (1, 2, 4, …) \
         whose error is below the target. The bias floor is the error at the largest spp less the \
         seed-to-seed noise (in quadrature); it cannot be told apart from zero below the reference's \
         floor, and it counts as reached only when that noise is at most half of it (otherwise the \
         budget ran out while the error was still mostly noise: \"not reached within the budget\").\n",
        report.budget, report.share
    );
    for section in &report.sections {
        let name = section_name(section.parameter.as_deref());
        let _ = writeln!(
            t,
            "## `{name}`\n\nReference: {}.\n",
            describe_reference(section)
        );
        let headers: Vec<String> = TARGETS
            .iter()
            .map(|x| format!("to {}", percent(*x)))
            .collect();
        let _ = writeln!(
            t,
            "| estimator | {} | largest spp | bias floor |",
            headers.join(" | ")
        );
        let _ = writeln!(t, "|---|{}---|---|", "---|".repeat(TARGETS.len()));
        for e in estimators(section) {
            let pts = points(section, e);
            let times: Vec<String> = (TARGETS.iter())
                .map(|x| show_time(time_to(&pts, *x)))
                .collect();
            let last = pts.last().expect("a series has a point");
            let _ = writeln!(
                t,
                "| {} | {} | {} | {} |",
                e.name(),
                times.join(" | "),
                last.spp,
                describe_floor(last)
            );
        }
        let ratio = |target: f64| {
            let time = |e| time_to(&points(section, e), target).map(|(s, _)| s);
            match (time(Estimator::Fd), time(Estimator::Complete)) {
                (Some(f), Some(c)) if c > 0.0 => format!("{:.1}", f / c),
                _ => "–".into(),
            }
        };
        if section.parameter.is_some() {
            let ratios: Vec<String> = (TARGETS.iter())
                .map(|x| format!("{} at {}", ratio(*x), percent(*x)))
                .collect();
            let _ = writeln!(t, "\n`fd` / complete: {}.", ratios.join(", "));
        }
        t.push('\n');
    }
    if !report.skipped.is_empty() {
        t += "## Skipped\n\n";
        for s in &report.skipped {
            let name = section_name(s.parameter.as_deref());
            let _ = writeln!(t, "- `{name}`, {}: {}", s.estimator.name(), s.reason);
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::Image;
    use crate::report::{Reference, Section};

    fn run(estimator: Estimator, spp: u32, seed: u64, seconds: f64, blurred: f64) -> Run {
        Run {
            parameter: Some("p.x".into()),
            estimator,
            spp,
            seed,
            seconds,
            raw_error: 2.0 * blurred,
            blurred_error: blurred,
            noise: 0.01,
            bias_floor: 0.0,
        }
    }

    fn section() -> Section {
        let mut runs = Vec::new();
        // Complete: 0.3, 0.12 / 0.06, 0.04; fd: 0.2, 0.08, 0.045 at twice the time.
        for (k, (a, b)) in [(0.3, 0.3), (0.13, 0.11), (0.07, 0.05), (0.04, 0.04)]
            .into_iter()
            .enumerate()
        {
            let spp = 1 << k;
            runs.push(run(Estimator::Complete, spp, 1, 0.1 * spp as f64, a));
            runs.push(run(Estimator::Complete, spp, 2, 0.1 * spp as f64 + 0.02, b));
        }
        for (k, e) in [0.2, 0.08, 0.045].into_iter().enumerate() {
            let spp = 1 << k;
            runs.push(run(Estimator::Fd, spp, 1, 0.2 * spp as f64, e));
            runs.push(run(Estimator::Fd, spp, 2, 0.2 * spp as f64, e));
        }
        Section {
            parameter: Some("p.x".into()),
            reference: Reference::given(Image::new(1, 1)),
            runs,
        }
    }

    #[test]
    fn points_average_the_seeds_and_time_to_takes_the_first_point_below() {
        let s = section();
        let complete = points(&s, Estimator::Complete);
        assert_eq!(complete.len(), 4);
        assert_eq!(complete[1].spp, 2);
        assert!((complete[1].seconds - 0.21).abs() < 1e-12);
        assert!((complete[1].blurred_error - 0.12).abs() < 1e-12);
        // √(0.04² − 0.01²)
        assert!((complete[3].bias_floor - 0.0015f64.sqrt()).abs() < 1e-12);
        // Noise 0.01 against a floor of 0.039: reached. At 1 spp, an error of 0.3 with the same noise
        // is a floor too; with noise 0.25 it is not (√(0.3² − 0.25²) = 0.166 < 2 · 0.25).
        assert!(floor_reached(&complete[3]));
        assert_eq!(describe_floor(&complete[3]), percent(0.0015f64.sqrt()));
        let noisy = Point {
            noise: 0.25,
            bias_floor: super::super::bias_floor(0.3, 0.25),
            ..complete[0]
        };
        assert!(!floor_reached(&noisy));
        assert_eq!(
            describe_floor(&noisy),
            "not reached within the budget (error 30%, noise 25% at 1 spp)"
        );
        let near = |t: Option<(f64, u32)>, (s, spp): (f64, u32)| {
            let (a, b) = t.expect("reached");
            assert!((a - s).abs() < 1e-9 && b == spp, "{a} s at {b} spp");
        };
        near(time_to(&complete, 0.10), (0.41, 4));
        near(time_to(&complete, 0.05), (0.81, 8));
        assert_eq!(time_to(&complete, 0.02), None);
        let fd = points(&s, Estimator::Fd);
        near(time_to(&fd, 0.05), (0.8, 4));
        assert_eq!(estimators(&s), [Estimator::Complete, Estimator::Fd]);
    }

    #[test]
    fn texts_hold_every_run_and_the_ratio() {
        let s = section();
        let report = Report {
            sections: vec![s],
            skipped: Vec::new(),
            budget: 2.0,
            share: 1.0,
        };
        let csv = csv(&report);
        let mut lines = csv.lines();
        assert_eq!(lines.next().unwrap(), CSV_COLUMNS.join(","));
        assert_eq!(lines.clone().count(), 14);
        // A given reference: the reference columns are empty.
        assert!(lines.all(|l| l.split(',').count() == 11 && l.ends_with(",,")));
        let md = markdown(&report);
        assert!(
            md.contains("| complete | 0.410 s (4 spp) | 0.810 s (8 spp) | not reached |"),
            "{md}"
        );
        // fd / complete at 5%: 0.8 / 0.81.
        assert!(md.contains("1.0 at 5%"), "{md}");
    }

    #[test]
    fn percentages_and_durations_read_well() {
        assert_eq!(percent(0.05), "5%");
        assert_eq!(percent(0.123), "12%");
        assert_eq!(percent(0.0123), "1.2%");
        assert_eq!(percent(0.00123), "0.12%");
        assert_eq!(seconds(2.346), "2.35 s");
        assert_eq!(seconds(0.0456), "0.046 s");
        assert_eq!(seconds(0.00123), "1.23 ms");
    }
}
