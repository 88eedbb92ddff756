//! The protocol: which estimator runs on what, for how long, and what each run measures.

use super::Estimator;
use super::measure::{bias_floor, blurred_error, raw_error, seed_noise};
use super::reference::Reference;
use super::subject::Subject;
use crate::error::{Error, Result};
use crate::film::Image;
use crate::scene::Scene;
use std::time::Instant;

/// The default budget of a report: seconds of estimator runs in all.
pub const DEFAULT_BUDGET: f64 = 60.0;
/// The two seeds of every point (spp) of a series; the references' seeds are apart from them.
pub const RUN_SEEDS: [u64; 2] = [1, 2];
/// No series goes past this many samples per pixel, however fast it runs.
pub const MAX_SPP: u32 = 1 << 16;
/// A computed reference costs about this many times one series' share of the budget.
const REFERENCE_COST: f64 = 8.0;
/// Bounds of the references' samples per pixel.
const REFERENCE_SPP: (u32, u32) = (256, 1 << 16);

/// An estimator left out, and why.
#[derive(Clone, Debug)]
pub struct Skip {
    /// The parameter, `None` for the image.
    pub parameter: Option<String>,
    /// The estimator.
    pub estimator: Estimator,
    /// Why it does not apply (one line).
    pub reason: String,
}

/// What a report will run: checked and costed before anything long is rendered.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The parameters' subjects, in the order given, then the image's when `primal` runs.
    pub subjects: Vec<Subject>,
    /// `(subject index, estimator)` of every series, in the order they run.
    pub series: Vec<(usize, Estimator)>,
    /// The estimators that do not apply.
    pub skipped: Vec<Skip>,
    /// The budget in all, seconds.
    pub budget: f64,
    /// One series' share of it: `budget / series.len()`.
    pub share: f64,
    /// Samples per pixel of the computed references.
    pub reference_spp: u32,
}

/// Checks every parameter and estimator of a report of `scene` and shares `budget` (seconds) between
/// the series that apply. The image (`primal`) is one series, however many parameters.
///
/// Derivative estimators that cannot run (e.g. under a box pixel filter) are skipped with the
/// integrator's message, so are the boundary-budget variants of a parameter whose boundary terms are
/// all zero (it moves no edge: the variants would repeat `complete`), and `fd` where its step takes
/// the parameter out of its range. With `computed_references`, a parameter whose half-step finite
/// differences cannot run is an error. Errors also: an unknown parameter, a parameter given twice, a
/// budget that is not a finite number > 0, nothing left to run.
pub fn plan(
    scene: &Scene,
    parameters: &[String],
    estimators: &[Estimator],
    budget: f64,
    computed_references: bool,
) -> Result<Plan> {
    if !(budget.is_finite() && budget > 0.0) {
        return Err(Error::field(
            "budget",
            format!("expected a finite number of seconds > 0, got {budget}"),
        ));
    }
    let mut subjects = Vec::new();
    for (k, p) in parameters.iter().enumerate() {
        if parameters[..k].contains(p) {
            return Err(Error::field(
                "params",
                format!("parameter {p:?} is given twice"),
            ));
        }
        subjects.push(Subject::derivative(scene, p)?);
    }
    let mut series = Vec::new();
    let mut skipped = Vec::new();
    for (k, subject) in subjects.iter().enumerate() {
        let p = subject.parameter().unwrap_or_default();
        if computed_references
            && let Some(why) = subject.finite_difference_refused(subject.step() / 2.0)
        {
            return Err(Error::field(
                "params",
                format!(
                    "{p}: no reference: finite differences cannot run ({why}); give a reference"
                ),
            ));
        }
        let derivatives =
            (estimators.iter()).any(|e| e.boundary_scale().is_some() || *e == Estimator::Interior);
        let vanish = if derivatives {
            subject.boundary_terms_vanish(4, RUN_SEEDS[0])
        } else {
            Ok(false)
        };
        for &e in estimators.iter().filter(|e| e.is_derivative()) {
            let reason = match (e, &vanish) {
                (Estimator::Fd, _) => subject.finite_difference_refused(subject.step()),
                (_, Err(err)) => Some(err.to_string()),
                (Estimator::CompleteBoundaryX4 | Estimator::CompleteBoundaryDiv4, Ok(true)) => {
                    Some(format!(
                        "the boundary terms of {p} are zero (it moves no edge): the budgets change \
                         nothing"
                    ))
                }
                _ => None,
            };
            match reason {
                Some(reason) => skipped.push(Skip {
                    parameter: Some(p.to_string()),
                    estimator: e,
                    reason,
                }),
                None => series.push((k, e)),
            }
        }
    }
    if estimators.contains(&Estimator::Primal) {
        subjects.push(Subject::image(scene));
        series.push((subjects.len() - 1, Estimator::Primal));
    }
    if series.is_empty() {
        let reasons: Vec<String> = (skipped.iter())
            .map(|s| format!("{}: {}", s.estimator.name(), s.reason))
            .collect();
        return Err(Error::Unsupported(format!(
            "no estimator applies ({})",
            reasons.join("; ")
        )));
    }
    let share = budget / series.len() as f64;
    let reference_spp = reference_spp(scene, share);
    Ok(Plan {
        subjects,
        series,
        skipped,
        budget,
        share,
        reference_spp,
    })
}

/// Samples per pixel of the computed references: the power of two nearest to where a derivative
/// reference (three renders' worth at that spp: two half references of two renders each, and the
/// full step's half for the truncation) costs [`REFERENCE_COST`] times one series' share, within
/// [`REFERENCE_SPP`]. Tying it to the share keeps the reference's noise below what the estimators reach
/// in their time. The cost of a sample is timed on renders long enough (20 ms) that fixed costs do
/// not dominate.
fn reference_spp(scene: &Scene, share: f64) -> u32 {
    let image = Subject::image(scene);
    // The first render pays one-off costs (threads, bounds).
    let _ = image.run(Estimator::Primal, 1, 0);
    let mut spp = 8;
    let per_spp = loop {
        let start = Instant::now();
        let _ = image.run(Estimator::Primal, spp, 0);
        let seconds = start.elapsed().as_secs_f64();
        if seconds >= 0.02 || spp >= 1024 {
            break (seconds / spp as f64).max(1e-9);
        }
        spp *= 2;
    };
    let spp = REFERENCE_COST * share / (3.0 * per_spp);
    let power = 2f64.powf(spp.max(1.0).log2().round());
    power.clamp(REFERENCE_SPP.0 as f64, REFERENCE_SPP.1 as f64) as u32
}

/// One run of one estimator: a row of `report.csv`.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    /// The parameter, `None` for the image.
    pub parameter: Option<String>,
    /// The estimator.
    pub estimator: Estimator,
    /// Samples per pixel.
    pub spp: u32,
    /// The sampler's seed.
    pub seed: u64,
    /// Wall time of the run, seconds.
    pub seconds: f64,
    /// Relative L2 error against the reference, per pixel.
    pub raw_error: f64,
    /// Relative L2 error against the reference after a 5×5 box blur.
    pub blurred_error: f64,
    /// One run's own noise at this spp, from the two seeds' difference (blurred, relative).
    pub noise: f64,
    /// `√max(blurred_error² − noise², 0)`: the bias left (with the reference's own error).
    pub bias_floor: f64,
}

/// The runs of one parameter (or of the image), against its reference.
#[derive(Clone, Debug)]
pub struct Section {
    /// The parameter, `None` for the image.
    pub parameter: Option<String>,
    /// What the runs were measured against.
    pub reference: Reference,
    /// Every run, series after series, each by increasing spp, the two seeds of a point together.
    pub runs: Vec<Run>,
}

/// A finished report: one section per parameter, then the image's when `primal` ran.
#[derive(Clone, Debug)]
pub struct Report {
    /// The sections.
    pub sections: Vec<Section>,
    /// The estimators that did not apply.
    pub skipped: Vec<Skip>,
    /// The budget in all, seconds.
    pub budget: f64,
    /// One series' share of it.
    pub share: f64,
}

/// Where a report stands, for a progress display.
#[derive(Clone, Copy, Debug)]
pub enum Status<'a> {
    /// A reference is being computed for the parameter (`None`: the image) at `spp`.
    Reference {
        /// The parameter, `None` for the image.
        parameter: Option<&'a str>,
        /// Its samples per pixel.
        spp: u32,
    },
    /// A point of a series is running.
    Run {
        /// The parameter, `None` for the image.
        parameter: Option<&'a str>,
        /// The estimator.
        estimator: Estimator,
        /// Samples per pixel of the point.
        spp: u32,
        /// Seconds of the budget used so far (each finished series counting at most its share).
        spent: f64,
    },
}

/// Runs `plan`: computes each subject's reference (or takes `given[k]` for parameter `k`), then each
/// series at spp 1, 2, 4, … with both [`RUN_SEEDS`] per point, until the series' run time passes its
/// share (or [`MAX_SPP`]). `status` is told where the report stands. Errors: those of the integrators.
pub fn run(
    plan: &Plan,
    given: Option<Vec<Image>>,
    status: &mut dyn FnMut(Status<'_>),
) -> Result<Report> {
    let mut sections = Vec::new();
    let mut given = given.map(Vec::into_iter);
    for subject in &plan.subjects {
        let parameter = subject.parameter();
        let reference = match (parameter, given.as_mut().and_then(Iterator::next)) {
            (Some(_), Some(image)) => Reference::given(image),
            _ => {
                let spp = plan.reference_spp;
                status(Status::Reference { parameter, spp });
                Reference::compute(subject, spp)?
            }
        };
        sections.push(Section {
            parameter: parameter.map(str::to_string),
            reference,
            runs: Vec::new(),
        });
    }
    let mut done = 0.0;
    for &(k, estimator) in &plan.series {
        let (subject, section) = (&plan.subjects[k], &mut sections[k]);
        let parameter = subject.parameter();
        let mut spent = 0.0;
        let mut spp = 1;
        while spent < plan.share && spp <= MAX_SPP {
            let used = done + spent.min(plan.share);
            status(Status::Run {
                parameter,
                estimator,
                spp,
                spent: used,
            });
            let mut point = Vec::new();
            for seed in RUN_SEEDS {
                let start = Instant::now();
                let image = subject.run(estimator, spp, seed)?;
                let seconds = start.elapsed().as_secs_f64();
                spent += seconds;
                point.push((seed, seconds, image));
            }
            let reference = &section.reference.image;
            let noise = seed_noise(&point[0].2, &point[1].2, reference);
            for (seed, seconds, image) in point {
                let blurred = blurred_error(&image, reference);
                section.runs.push(Run {
                    parameter: parameter.map(str::to_string),
                    estimator,
                    spp,
                    seed,
                    seconds,
                    raw_error: raw_error(&image, reference),
                    blurred_error: blurred,
                    noise,
                    bias_floor: bias_floor(blurred, noise),
                });
            }
            spp *= 2;
        }
        done += spent.min(plan.share);
    }
    Ok(Report {
        sections,
        skipped: plan.skipped.clone(),
        budget: plan.budget,
        share: plan.share,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::parse;
    use std::path::Path;

    /// A ball over a floor under a small light, 8×8 pixels.
    fn tiny() -> Scene {
        let json = r#"{
          "camera": {"origin": [0, 3, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 45.0,
                     "width": 8, "height": 8, "filter": "tent"},
          "integrator": {"type": "direct"}, "spp": 4,
          "shapes": [
            {"name": "ball", "sdf": {"type": "sphere", "center": [0, 0, 0], "radius": 1.0},
             "bsdf": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}},
            {"name": "floor", "sdf": {"type": "box", "center": [0, -2, 0],
             "half_size": [50, 0.5, 50], "rounding": 0.25},
             "bsdf": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}],
          "emitters": [{"name": "light", "type": "rectangle", "center": [1.5, 4, 2],
            "normal": [0, -1, 0], "u": [1, 0, 0], "size": [1, 1], "radiance": [40, 40, 40]}]
        }"#;
        parse(json, Path::new(".")).unwrap()
    }

    #[test]
    fn the_budget_is_shared_between_the_series_that_apply() {
        let scene = tiny();
        let names = ["ball.radius".to_string(), "ball.albedo.r".to_string()];
        let plan = plan(&scene, &names, &Estimator::ALL, 11.0, true).unwrap();
        // An albedo moves no edge: its boundary-budget variants are skipped, with the reason.
        let skipped: Vec<(&str, Estimator)> = (plan.skipped.iter())
            .map(|s| (s.parameter.as_deref().unwrap(), s.estimator))
            .collect();
        assert_eq!(
            skipped,
            [
                ("ball.albedo.r", Estimator::CompleteBoundaryX4),
                ("ball.albedo.r", Estimator::CompleteBoundaryDiv4)
            ]
        );
        assert!(plan.skipped[0].reason.contains("moves no edge"));
        // 5 series for the radius, 3 for the albedo, 1 for the image.
        assert_eq!(plan.series.len(), 9);
        assert_eq!(plan.series.last(), Some(&(2, Estimator::Primal)));
        assert!((plan.share - 11.0 / 9.0).abs() < 1e-12);
        assert!(plan.reference_spp.is_power_of_two());
        assert!((REFERENCE_SPP.0..=REFERENCE_SPP.1).contains(&plan.reference_spp));
    }

    #[test]
    fn bad_plans_are_refused_with_what_is_wrong() {
        let scene = tiny();
        let radius = ["ball.radius".to_string()];
        for budget in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let e = plan(&scene, &radius, &Estimator::ALL, budget, true).unwrap_err();
            assert!(e.to_string().starts_with("budget: "), "{e}");
        }
        let twice = ["ball.radius".to_string(), "ball.radius".to_string()];
        let e = plan(&scene, &twice, &Estimator::ALL, 1.0, true).unwrap_err();
        assert!(e.to_string().contains("twice"), "{e}");
        let unknown = ["ball.radus".to_string()];
        let e = plan(&scene, &unknown, &Estimator::ALL, 1.0, true).unwrap_err();
        assert!(e.to_string().contains("ball.radus"), "{e}");
    }

    #[test]
    fn a_series_doubles_its_spp_with_two_seeds_until_its_share_is_spent() {
        let scene = tiny();
        let names = ["ball.albedo.r".to_string()];
        // A share that an 8×8 image spends over several doublings even on a loaded machine (one
        // point at spp 1 only would compare the two seeds, not the spp).
        let mut plan = plan(&scene, &names, &[Estimator::Fd], 0.5, true).unwrap();
        plan.reference_spp = 256;
        let mut statuses = 0;
        let report = run(&plan, None, &mut |_| statuses += 1).unwrap();
        let runs = &report.sections[0].runs;
        assert!(runs.len() >= 2 && runs.len().is_multiple_of(2));
        for (k, pair) in runs.chunks(2).enumerate() {
            assert_eq!((pair[0].spp, pair[1].spp), (1 << k, 1 << k));
            assert_eq!([pair[0].seed, pair[1].seed], RUN_SEEDS);
            assert_eq!(pair[0].noise, pair[1].noise);
        }
        // Every point but the last started within the share.
        let points: Vec<f64> = runs
            .chunks(2)
            .map(|p| p[0].seconds + p[1].seconds)
            .collect();
        let before_last: f64 = points[..points.len() - 1].iter().sum();
        assert!(before_last < plan.share);
        assert_eq!(statuses, 1 + points.len());
        // The albedo is linear: fd's error is noise alone and falls with the samples.
        assert!(points.len() >= 4, "{} points", points.len());
        assert!(runs.last().unwrap().raw_error < runs[0].raw_error);
    }
}
