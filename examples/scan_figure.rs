//! The figures of a reconstruction measured against a scanned mesh (docs/inverse-rendering.md,
//! "A scanned shape"): from two `optimize` runs of the same example, one with the complete gradient and
//! one with the interior term alone (`"terms": "interior"`), both with `reference_mesh`,
//!
//! - a plot of the Chamfer distance, the normal consistency and the IoU against the mesh over seconds
//!   of optimisation, both runs on each panel;
//! - a picture of the reference beside both reconstructions, rendered by the renderer: the display
//!   scene `SHOW.json` as written (its shape is the reference's grid), then with its shape's `sdf`
//!   replaced by each run's fitted grid (`result.json`);
//! - on stdout, the table of both runs at 60, 300, 600 s and at their end.
//!
//! `cargo run --release --example scan_figure -- SHOW.json COMPLETE_DIR INTERIOR_DIR PLOT.png PICTURE.png [SPP]`

use implicit_psdr::film::figure::{self, register_font, titled_columns};
use implicit_psdr::film::write_png;
use implicit_psdr::integrator::{RenderOptions, render};
use implicit_psdr::optimize::progress::read_columns;
use implicit_psdr::scene;
use plotters::prelude::*;
use serde_json::Value;
use std::error::Error;
use std::path::Path;

/// The columns read from each run: seconds, then the measures against the mesh.
const COLUMNS: [&str; 4] = [
    "seconds",
    "mesh_chamfer",
    "mesh_normal_consistency",
    "mesh_iou",
];
/// Seconds of optimisation at which the table compares the runs (then their ends).
const CHECKPOINTS: [f64; 3] = [60.0, 300.0, 600.0];
const COMPLETE: RGBColor = RGBColor(31, 119, 180);
const INTERIOR: RGBColor = RGBColor(255, 127, 14);

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (show, complete, interior, plot, picture) = match args.as_slice() {
        [s, c, i, p, q] | [s, c, i, p, q, _] => (s, c, i, p, q),
        _ => {
            return Err(
                "usage: scan_figure SHOW.json COMPLETE_DIR INTERIOR_DIR PLOT.png PICTURE.png [SPP]"
                    .into(),
            );
        }
    };
    let spp: u32 = args.get(5).map_or(Ok(128), |s| s.parse())?;
    let runs = [
        ("complete", Path::new(complete)),
        ("interior alone", Path::new(interior)),
    ];
    let mut rows = Vec::new();
    for (_, dir) in runs {
        rows.push(read_columns(&dir.join("progress.csv"), &COLUMNS)?);
    }
    print_table(&runs.map(|r| r.0), &rows);

    register_font()?;
    let (w, h) = (1200u32, 380u32);
    let mut buffer = vec![255u8; 3 * (w * h) as usize];
    draw(&mut buffer, (w, h), &rows)?;
    write_png(
        Path::new(plot),
        w,
        h,
        &figure::from_srgb_bytes(w, h, &buffer).rgb,
    )?;
    println!("wrote {plot}");

    let show = Path::new(show);
    let document: Value = serde_json::from_str(&std::fs::read_to_string(show)?)?;
    let base = show.parent().unwrap_or(Path::new("."));
    let mut titles = vec!["reference".to_string()];
    let mut images = vec![render_show(&document, base, spp)?];
    for ((title, dir), rows) in runs.iter().zip(&rows) {
        let fitted = with_fitted_shape(&document, dir)?;
        images.push(render_show(&fitted, base, spp)?);
        titles.push(format!(
            "{title}, {:.0} s",
            rows.last().map_or(0.0, |r| r[0])
        ));
    }
    let picture_image = titled_columns(&titles, &images)?;
    write_png(
        Path::new(picture),
        picture_image.width,
        picture_image.height,
        &picture_image.rgb,
    )?;
    println!("wrote {picture}");
    Ok(())
}

/// The display scene with its first shape's `sdf` replaced by the same-named shape's `sdf` of
/// `dir/result.json`, whose grid file is made absolute (it lives in `dir`).
fn with_fitted_shape(document: &Value, dir: &Path) -> Result<Value, Box<dyn Error>> {
    let result_path = dir.join("result.json");
    let result: Value = serde_json::from_str(&std::fs::read_to_string(&result_path)?)?;
    let name = &document["shapes"][0]["name"];
    let shape = (result["shapes"].as_array().into_iter().flatten())
        .find(|s| &s["name"] == name)
        .ok_or_else(|| format!("{}: no shape {name}", result_path.display()))?;
    let mut sdf = shape["sdf"].clone();
    if let Some(file) = sdf["file"].as_str() {
        let absolute = std::fs::canonicalize(dir.join(file))?;
        sdf["file"] = Value::String(absolute.to_string_lossy().into_owned());
    }
    let mut fitted = document.clone();
    fitted["shapes"][0]["sdf"] = sdf;
    Ok(fitted)
}

/// The display scene `document` (paths relative to `base`) rendered at `spp`.
fn render_show(
    document: &Value,
    base: &Path,
    spp: u32,
) -> Result<implicit_psdr::film::Image, Box<dyn Error>> {
    let scene = scene::parse(&document.to_string(), base)?;
    let options = RenderOptions {
        spp,
        seed: 0,
        progress: Default::default(),
    };
    Ok(render(&scene, &options).0)
}

/// The last row at or before `seconds` (what a run stopped then would return).
fn at(rows: &[Vec<f64>], seconds: f64) -> Option<&Vec<f64>> {
    if rows.last().is_none_or(|r| r[0] < seconds) {
        return None;
    }
    rows.iter().rev().find(|r| r[0] <= seconds)
}

fn print_table(titles: &[&str; 2], rows: &[Vec<Vec<f64>>]) {
    let cell = |r: Option<&Vec<f64>>| {
        r.map_or("–".to_string(), |r| {
            format!("{:.4} / {:.3} / {:.3}", r[1], r[2], r[3])
        })
    };
    println!("| gradient | at 60 s | at 300 s | at 600 s | end | seconds, iterations |");
    println!("|---|---|---|---|---|---|");
    for (title, rows) in titles.iter().zip(rows) {
        let checkpoints: Vec<String> = CHECKPOINTS.iter().map(|&t| cell(at(rows, t))).collect();
        let end = rows.last().map_or(0.0, |r| r[0]);
        println!(
            "| {title} | {} | {} | {end:.0}, {} |",
            checkpoints.join(" | "),
            cell(rows.last()),
            rows.len()
        );
    }
    println!(
        "(each cell: Chamfer as a fraction of the mesh's box diagonal / normal consistency / IoU)"
    );
}

/// The three panels into the sRGB bytes `buffer` of a `size` picture.
fn draw(buffer: &mut [u8], size: (u32, u32), rows: &[Vec<Vec<f64>>]) -> Result<(), Box<dyn Error>> {
    let root = BitMapBackend::with_buffer(buffer, size).into_drawing_area();
    root.fill(&WHITE)?;
    let panels = root.split_evenly((1, 3));
    let font = ("sans-serif", 15).into_font();
    let last = (rows.iter())
        .filter_map(|r| r.last().map(|r| r[0]))
        .fold(1.0f64, f64::max);
    let names = ["Chamfer (of the box diagonal)", "normal consistency", "IoU"];
    for (k, (area, name)) in panels.iter().zip(names).enumerate() {
        let column = k + 1;
        let values = rows.iter().flatten().map(|r| r[column]);
        let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
        let pad = 0.05 * (hi - lo).max(1e-6);
        let mut chart = ChartBuilder::on(area)
            .caption(format!("{name} against seconds"), font.clone())
            .margin(14)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..last, (lo - pad)..(hi + pad))?;
        chart
            .configure_mesh()
            .x_desc("seconds of optimisation")
            .x_labels(6)
            .x_label_formatter(&|x| format!("{x:.0}"))
            .label_style(font.clone())
            .draw()?;
        for (run, (colour, label)) in rows
            .iter()
            .zip([(COMPLETE, "complete"), (INTERIOR, "interior alone")])
        {
            chart
                .draw_series(LineSeries::new(
                    run.iter().map(|r| (r[0], r[column])),
                    colour.stroke_width(2),
                ))?
                .label(label)
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour));
        }
        if column == 3 {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::LowerRight)
                .background_style(WHITE)
                .border_style(BLACK)
                .label_font(font.clone())
                .draw()?;
        }
    }
    root.present()?;
    Ok(())
}
