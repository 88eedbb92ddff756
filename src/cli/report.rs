//! The `report` command: speed against error of the estimators for the scene's parameters, as a CSV,
//! a Markdown table and a plot (PNG and SVG) in one folder. The protocol is the library's
//! ([`crate::report`]); this prints, shows progress and writes.
//!
//! Everything is checked (scene, parameters, estimators, budget, reference) before anything long is
//! rendered and before the folder is touched; the four files are written to temporary names and
//! renamed only when all are written.

use crate::cli::args::ReportArgs;
use crate::cli::load_scene;
use crate::cli::records::Records;
use crate::integrator::fd;
use crate::io::{Writer, write_all_or_nothing};
use crate::report::{self, Estimator, Status, plot, summary};
use anyhow::{Context, Result, bail};
use std::cell::{Cell, RefCell};

pub(crate) fn report(args: &ReportArgs) -> Result<()> {
    let scene = load_scene(&args.scene)?;
    let estimators = match &args.estimators {
        // The library names the list `estimators`; here it is the option's value.
        Some(list) => Estimator::parse_list(list).map_err(|e| anyhow::anyhow!("--{e}"))?,
        None => Estimator::ALL.to_vec(),
    };
    for p in &args.params {
        // The error names `--param` and the parameter itself, as `fd`'s does.
        fd::parameter_value(&scene, p)
            .map_err(crate::cli::flagged)
            .with_context(|| args.scene.display().to_string())?;
    }
    let out = &args.out;
    if out.exists() && !out.is_dir() {
        bail!("--out {}: is not a folder", out.display());
    }
    crate::io::check_output_folder(out, "--out")?;
    let given = match &args.reference {
        Some(path) => {
            let size = (scene.camera.width, scene.camera.height);
            Some(report::read_reference(path, &args.params, size).context("--reference")?)
        }
        None => None,
    };
    let plan = report::plan(
        &scene,
        &args.params,
        &estimators,
        args.budget,
        given.is_none(),
    )
    .map_err(crate::cli::flagged)?;
    for s in &plan.skipped {
        let name = summary::section_name(s.parameter.as_deref());
        outln!("skipped {} for {name}: {}", s.estimator.name(), s.reason)?;
    }
    outln!(
        "{} series of {:.2} s each ({:.1} s in all); references at {} spp",
        plan.series.len(),
        plan.share,
        plan.budget,
        plan.reference_spp
    )?;
    let bar = Bar::new(plan.budget);
    let result = report::run(&plan, given, &mut |status| bar.show(status));
    bar.finish();
    let result = result?;

    for section in &result.sections {
        let name = summary::section_name(section.parameter.as_deref());
        outln!("{name}: reference {}", summary::describe_reference(section))?;
        for e in summary::estimators(section) {
            let points = summary::points(section, e);
            let to5 = match summary::time_to(&points, 0.05) {
                Some((s, spp)) => format!("{} ({spp} spp)", summary::seconds(s)),
                None => "not reached".into(),
            };
            let last = points.last().expect("a series has a point");
            let floor = match summary::floor_reached(last) {
                true => format!("bias floor {:.4} at {} spp", last.bias_floor, last.spp),
                false => format!("bias floor {}", summary::describe_floor(last)),
            };
            outln!("  {:24} to 5%: {to5:20} {floor}", e.name())?;
        }
    }

    let (csv, md) = (summary::csv(&result), summary::markdown(&result));
    let png = plot::png(&result)?;
    let svg = plot::svg(&result)?;
    std::fs::create_dir_all(out)
        .with_context(|| format!("--out {}: cannot create", out.display()))?;
    let text = |t: String| -> Writer {
        Box::new(move |tmp| std::fs::write(tmp, t).map_err(|e| e.to_string()))
    };
    let bytes = |b: Vec<u8>| -> Writer {
        Box::new(move |tmp| std::fs::write(tmp, b).map_err(|e| e.to_string()))
    };
    write_all_or_nothing(vec![
        (out.join("report.csv"), text(csv)),
        (out.join("report.md"), text(md)),
        (out.join("report.png"), bytes(png)),
        (out.join("report.svg"), text(svg)),
    ])?;
    outln!(
        "wrote report.csv, report.md, report.png and report.svg in {}",
        out.display()
    )?;
    Ok(())
}

/// The progress of a report on stderr, over the budget's seconds with the series and spp running: a
/// bar on a terminal, one-line records elsewhere.
enum Bar {
    Terminal(indicatif::ProgressBar),
    Records {
        records: RefCell<Records>,
        budget: f64,
        spent: Cell<f64>,
    },
}

impl Bar {
    fn new(budget: f64) -> Self {
        if let Some(records) = Records::new() {
            return Self::Records {
                records: RefCell::new(records),
                budget,
                spent: Cell::new(0.0),
            };
        }
        let bar = indicatif::ProgressBar::new((budget * 1e3) as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template("{bar:40} {msg} {elapsed}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        Self::Terminal(bar)
    }

    fn show(&self, status: Status<'_>) {
        let bar = match self {
            Self::Terminal(bar) => bar,
            Self::Records {
                records,
                budget,
                spent,
            } => {
                if let Status::Run { spent: s, .. } = status {
                    spent.set(s);
                }
                let what = || {
                    let now = match status {
                        Status::Reference { parameter, spp } => {
                            let name = summary::section_name(parameter);
                            format!("reference of {name} at {spp} spp")
                        }
                        Status::Run {
                            parameter,
                            estimator,
                            spp,
                            ..
                        } => {
                            let name = summary::section_name(parameter);
                            format!("{name}: {} at {spp} spp", estimator.name())
                        }
                    };
                    format!("{:.1} of {budget:.1} s of budget spent; {now}", spent.get())
                };
                records.borrow_mut().record(spent.get(), *budget, what);
                return;
            }
        };
        match status {
            Status::Reference { parameter, spp } => {
                let name = summary::section_name(parameter);
                bar.set_message(format!("reference of {name} at {spp} spp"));
            }
            Status::Run {
                parameter,
                estimator,
                spp,
                spent,
            } => {
                let name = summary::section_name(parameter);
                bar.set_position((spent * 1e3) as u64);
                bar.set_message(format!("{name}: {} at {spp} spp", estimator.name()));
            }
        }
    }

    fn finish(&self) {
        match self {
            Self::Terminal(bar) => bar.finish_and_clear(),
            Self::Records {
                records,
                budget,
                spent,
            } => records.borrow_mut().record(*budget, *budget, || {
                format!("{:.1} of {budget:.1} s of budget spent; done", spent.get())
            }),
        }
    }
}
