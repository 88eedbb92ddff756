//! The race figure of docs/inverse-rendering.md: IoU and Chamfer distance against seconds of
//! optimisation for `scenes/inverse/race` (from the run's `progress.csv`), beside the figures of the
//! reconstruction pipeline of Vicini et al. 2022 ("Differentiable Signed Distance Function Rendering")
//! measured on the same machine with the matched setup, and the table of both at 60, 120, 300, 600 and
//! 1200 s on stdout.
//!
//! `cargo run --release --example race_figure -- PROGRESS.csv OUT.png`

use implicit_psdr::film::figure::{self, register_font};
use implicit_psdr::film::write_png;
use plotters::prelude::*;
use std::error::Error;
use std::path::Path;

/// Seconds of optimisation at which both runs are compared.
const CHECKPOINTS: [f64; 5] = [60.0, 120.0, 300.0, 600.0, 1200.0];
/// Vicini et al. 2022 at [`CHECKPOINTS`]: IoU (64³ lattice), and symmetric Chamfer distance in units
/// of the cube's side (Mitsuba 3.9.1 `llvm_ad_rgb`, on the machine of today's figures, measured on
/// 29 November 2026): at each time the better of their two results, the optimised parameter itself
/// (ahead in the first minutes) and its moving average, which their code saves (ahead later).
const THEIRS: [(f64, f64); 5] = [
    (0.920, 8.7e-3),
    (0.930, 7.5e-3),
    (0.940, 6.1e-3),
    (0.942, 5.5e-3),
    (0.944, 5.6e-3),
];
const OURS_COLOUR: RGBColor = RGBColor(31, 119, 180);
const THEIRS_COLOUR: RGBColor = RGBColor(190, 20, 40);

/// `(seconds, iou, chamfer)` of every row of a `progress.csv` with a single shape's columns.
fn read_progress(path: &Path) -> Result<Vec<[f64; 3]>, Box<dyn Error>> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    let column = |name: &str| {
        (header.iter().position(|h| *h == name))
            .ok_or_else(|| format!("{}: no column {name:?}", path.display()))
    };
    let columns = [column("seconds")?, column("iou")?, column("chamfer")?];
    let mut rows = Vec::new();
    for (k, line) in lines.enumerate() {
        let cells: Vec<&str> = line.split(',').collect();
        let mut row = [0.0; 3];
        for (value, &c) in row.iter_mut().zip(&columns) {
            let cell = cells
                .get(c)
                .ok_or_else(|| format!("row {}: short", k + 2))?;
            *value = (cell.parse::<f64>())
                .map_err(|e| format!("{}: row {}: {e}", path.display(), k + 2))?;
        }
        rows.push(row);
    }
    Ok(rows)
}

/// The last row at or before `seconds` (the state a run stopped then would return); `None` before the
/// first row and after the run's end.
fn at(rows: &[[f64; 3]], seconds: f64) -> Option<[f64; 3]> {
    if rows.last().is_none_or(|r| r[0] < seconds) {
        return None;
    }
    rows.iter().rev().find(|r| r[0] <= seconds).copied()
}

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [progress, out] = args.as_slice() else {
        return Err("usage: race_figure PROGRESS.csv OUT.png".into());
    };
    let rows = read_progress(Path::new(progress))?;
    println!("| seconds of optimisation | 60 | 120 | 300 | 600 | 1200 |");
    println!("|---|---|---|---|---|---|");
    let theirs: Vec<String> = (THEIRS.iter())
        .map(|(iou, c)| format!("{iou:.3} / {:.1}", c * 1e3))
        .collect();
    println!(
        "| Vicini 2022, IoU / Chamfer (×10⁻³) | {} |",
        theirs.join(" | ")
    );
    // A run that ended before a checkpoint keeps its result there.
    let end = rows.last().map_or(0.0, |r| r[0]);
    let ours: Vec<String> = (CHECKPOINTS.iter())
        .map(|&t| match (at(&rows, t), rows.last()) {
            (Some(r), _) => format!("{:.3} / {:.1}", r[1], r[2] * 1e3),
            (None, Some(r)) if t > end => {
                format!("{:.3} / {:.1} (done at {end:.0} s)", r[1], r[2] * 1e3)
            }
            _ => "–".into(),
        })
        .collect();
    println!("| implicit-psdr, IoU / Chamfer | {} |", ours.join(" | "));

    register_font()?;
    let last = rows.last().map_or(1.0, |r| r[0]).max(CHECKPOINTS[4]);
    let (w, h) = (1000u32, 420u32);
    let mut buffer = vec![255u8; 3 * (w * h) as usize];
    draw(&mut buffer, (w, h), &rows, last)?;
    let picture = figure::from_srgb_bytes(w, h, &buffer);
    write_png(Path::new(out), w, h, &picture.rgb)?;
    println!("wrote {out}");
    Ok(())
}

/// Both panels into the sRGB bytes `buffer` of a `size` picture.
fn draw(
    buffer: &mut [u8],
    size: (u32, u32),
    rows: &[[f64; 3]],
    last: f64,
) -> Result<(), Box<dyn Error>> {
    let root = BitMapBackend::with_buffer(buffer, size).into_drawing_area();
    root.fill(&WHITE)?;
    let (left, right) = root.split_horizontally(size.0 / 2);
    let font = ("sans-serif", 15).into_font();
    let panels = [
        (&left, "IoU", 1, (0.5, 1.0)),
        (&right, "Chamfer (side = 1)", 2, (1e-3, 0.1)),
    ];
    for (area, name, column, (lo, hi)) in panels {
        let x = (10.0..last).log_scale();
        let mut chart = ChartBuilder::on(area);
        (chart.caption(format!("{name} against seconds"), font.clone()))
            .margin(14)
            .x_label_area_size(40)
            .y_label_area_size(60);
        let ours = rows
            .iter()
            .filter(|r| r[0] >= 10.0)
            .map(|r| (r[0], r[column]));
        let theirs = (CHECKPOINTS.iter().zip(THEIRS))
            .map(|(&t, (iou, c))| (t, if column == 1 { iou } else { c }));
        // Two charts with different y coordinates: IoU linear, Chamfer logarithmic.
        if column == 1 {
            let mut chart = chart.build_cartesian_2d(x, lo..hi)?;
            chart
                .configure_mesh()
                .x_desc("seconds of optimisation")
                .x_labels(6)
                .x_label_formatter(&|x| format!("{x:.0}"))
                .label_style(font.clone())
                .draw()?;
            chart.draw_series(LineSeries::new(ours, OURS_COLOUR.stroke_width(2)))?;
            chart.draw_series(LineSeries::new(theirs, THEIRS_COLOUR.stroke_width(2)))?;
        } else {
            let mut chart = chart.build_cartesian_2d(x, (lo..hi).log_scale())?;
            chart
                .configure_mesh()
                .x_desc("seconds of optimisation")
                .x_labels(6)
                .x_label_formatter(&|x| format!("{x:.0}"))
                .label_style(font.clone())
                .draw()?;
            chart
                .draw_series(LineSeries::new(ours, OURS_COLOUR.stroke_width(2)))?
                .label("implicit-psdr")
                .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], OURS_COLOUR));
            chart
                .draw_series(LineSeries::new(theirs, THEIRS_COLOUR.stroke_width(2)))?
                .label("Vicini et al. 2022")
                .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], THEIRS_COLOUR));
            chart
                .configure_series_labels()
                .background_style(WHITE)
                .border_style(BLACK)
                .label_font(font.clone())
                .draw()?;
        }
    }
    root.present()?;
    Ok(())
}
