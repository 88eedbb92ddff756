//! The ablation figure of docs/inverse-rendering.md: IoU and Chamfer distance against the iteration,
//! the complete gradient against the interior term alone, one row per example, from the runs' `progress.csv`.
//!
//! `cargo run --release --example ablation_figure -- OUT.png ROW [ROW ...] [--font FILE.ttf]`, each
//! `ROW` as `TITLE=DIAGONAL=COMPLETE.csv=INTERIOR.csv`: the Chamfer distance is drawn in percent of
//! `DIAGONAL` (the grid box's diagonal). The labels need a TrueType font (default: DejaVu Sans where
//! Debian puts it).

use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};
use std::error::Error;
use std::path::Path;

const DEFAULT_FONT: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
const COMPLETE: RGBColor = RGBColor(31, 119, 180);
const INTERIOR: RGBColor = RGBColor(255, 127, 14);

/// One example: its title, the diagonal the Chamfer distance is measured against, and the two runs'
/// `(iteration, IoU, Chamfer)` rows.
struct Row {
    title: String,
    diagonal: f64,
    complete: Vec<[f64; 3]>,
    interior: Vec<[f64; 3]>,
}

/// `(iteration, iou, chamfer)` of every row of a `progress.csv` with a single shape's columns.
fn read_progress(path: &Path) -> Result<Vec<[f64; 3]>, Box<dyn Error>> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    let column = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .ok_or_else(|| format!("{}: no column {name:?}", path.display()))
    };
    let (it, iou, chamfer) = (column("iteration")?, column("iou")?, column("chamfer")?);
    let mut out = Vec::new();
    for (k, line) in lines.enumerate() {
        let cells: Vec<&str> = line.split(',').collect();
        let get = |c: usize| -> Result<f64, Box<dyn Error>> {
            let cell = cells.get(c).ok_or("short row")?;
            cell.parse::<f64>()
                .map_err(|e| format!("{}: row {}: {e}", path.display(), k + 2).into())
        };
        out.push([get(it)?, get(iou)?, get(chamfer)?]);
    }
    Ok(out)
}

fn parse_row(arg: &str) -> Result<Row, Box<dyn Error>> {
    let parts: Vec<&str> = arg.split('=').collect();
    let [title, diagonal, complete, interior] = parts.as_slice() else {
        return Err(format!("{arg}: expected TITLE=DIAGONAL=COMPLETE.csv=INTERIOR.csv").into());
    };
    Ok(Row {
        title: title.to_string(),
        diagonal: diagonal.parse()?,
        complete: read_progress(Path::new(complete))?,
        interior: read_progress(Path::new(interior))?,
    })
}

fn main() -> Result<(), Box<dyn Error>> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut font = DEFAULT_FONT.to_string();
    if let Some(k) = args.iter().position(|a| a == "--font") {
        font = args.get(k + 1).ok_or("--font needs a file")?.clone();
        args.drain(k..k + 2);
    }
    let Some((out, rows)) = args.split_first() else {
        eprintln!("usage: ablation_figure OUT.png TITLE=DIAGONAL=COMPLETE.csv=INTERIOR.csv ...");
        std::process::exit(2);
    };
    let rows: Vec<Row> = rows
        .iter()
        .map(|r| parse_row(r))
        .collect::<Result<_, _>>()?;
    let bytes = std::fs::read(&font).map_err(|e| format!("--font {font}: {e}"))?;
    register_font(
        "sans-serif",
        FontStyle::Normal,
        Box::leak(bytes.into_boxed_slice()),
    )
    .map_err(|_| format!("--font {font}: not a usable TrueType font"))?;

    let (w, h) = (900u32, 300 * rows.len() as u32 + 40);
    let mut buffer = vec![255u8; 3 * (w * h) as usize];
    draw(&mut buffer, (w, h), &rows).map_err(|e| e.to_string())?;
    let file = std::fs::File::create(out).map_err(|e| format!("{out}: {e}"))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.write_header()?.write_image_data(&buffer)?;
    println!("wrote {out}");
    Ok(())
}

/// The figure into an RGB8 buffer of size `(w, h)`.
fn draw<'a>(
    buffer: &'a mut [u8],
    (w, h): (u32, u32),
    rows: &[Row],
) -> Result<(), Box<dyn Error + 'a>> {
    let root = BitMapBackend::with_buffer(buffer, (w, h)).into_drawing_area();
    root.fill(&WHITE)?;
    let (legend, body) = root.split_vertically(40);
    legend.draw(&Text::new(
        "complete gradient",
        (120, 12),
        ("sans-serif", 18).into_font().color(&COMPLETE),
    ))?;
    legend.draw(&Text::new(
        "interior term alone (as renderers without boundary terms)",
        (320, 12),
        ("sans-serif", 18).into_font().color(&INTERIOR),
    ))?;
    let cells = body.split_evenly((rows.len(), 2));
    for (k, row) in rows.iter().enumerate() {
        let last = row
            .complete
            .iter()
            .chain(&row.interior)
            .map(|r| r[0])
            .fold(1.0, f64::max);
        let mut iou = ChartBuilder::on(&cells[2 * k])
            .caption(format!("{}: IoU", row.title), ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(30)
            .y_label_area_size(45)
            .build_cartesian_2d(0.0..last, 0.0..1.0)?;
        iou.configure_mesh()
            .x_desc("iteration")
            .light_line_style(WHITE)
            .x_label_formatter(&|x| format!("{x:.0}"))
            .draw()?;
        let chamfer_max = row
            .complete
            .iter()
            .chain(&row.interior)
            .map(|r| 100.0 * r[2] / row.diagonal)
            .filter(|c| c.is_finite())
            .fold(0.0, f64::max)
            * 1.05;
        let mut chamfer = ChartBuilder::on(&cells[2 * k + 1])
            .caption(
                format!("{}: Chamfer, % of box diagonal", row.title),
                ("sans-serif", 18),
            )
            .margin(10)
            .x_label_area_size(30)
            .y_label_area_size(45)
            .build_cartesian_2d(0.0..last, 0.0..chamfer_max.max(1e-3))?;
        chamfer
            .configure_mesh()
            .x_desc("iteration")
            .light_line_style(WHITE)
            .x_label_formatter(&|x| format!("{x:.0}"))
            .draw()?;
        for (run, color) in [(&row.complete, COMPLETE), (&row.interior, INTERIOR)] {
            iou.draw_series(LineSeries::new(
                run.iter().map(|r| (r[0], r[1])),
                color.stroke_width(2),
            ))?;
            chamfer.draw_series(LineSeries::new(
                run.iter().map(|r| (r[0], 100.0 * r[2] / row.diagonal)),
                color.stroke_width(2),
            ))?;
        }
    }
    root.present()?;
    Ok(())
}
