//! `report.png` and `report.svg`: per section (parameter, or the image) a log-log panel of the blurred
//! error against the seconds of one run, one line per estimator (a point per spp, the mean of the two
//! seeds), with the reference's floor as a dashed horizontal line when it is known.
//!
//! The text is set in DejaVu Sans, shipped reduced to ASCII in `assets/fonts/` (its license is
//! beside it), so the PNG does not depend on the fonts of the machine; the SVG names the
//! `sans-serif` family and leaves the glyphs to its viewer.

use super::Estimator;
use super::protocol::{Report, Section};
use super::summary::{estimators, points, section_name};
use crate::error::{Error, Result};
use crate::film::figure::register_font;
use plotters::coord::Shift;
use plotters::prelude::*;

/// Size of one panel, pixels.
pub const PANEL_SIZE: (u32, u32) = (600, 440);
/// Panels per row.
const COLUMNS: usize = 2;

/// The line colour of an estimator, the same in every panel.
fn colour(e: Estimator) -> RGBColor {
    match e {
        Estimator::Complete => RGBColor(0, 90, 190),
        Estimator::Interior => RGBColor(215, 95, 0),
        Estimator::CompleteBoundaryX4 => RGBColor(110, 160, 235),
        Estimator::CompleteBoundaryDiv4 => RGBColor(0, 40, 100),
        Estimator::Fd => RGBColor(190, 20, 40),
        Estimator::Primal => RGBColor(0, 135, 70),
    }
}

/// Width and height of the figure of `report`.
pub fn figure_size(report: &Report) -> (u32, u32) {
    let n = report.sections.len().max(1);
    let columns = n.min(COLUMNS);
    let rows = n.div_ceil(COLUMNS);
    (PANEL_SIZE.0 * columns as u32, PANEL_SIZE.1 * rows as u32)
}

/// The figure as an 8-bit RGB PNG file's bytes.
pub fn png(report: &Report) -> Result<Vec<u8>> {
    register_font()?;
    let (w, h) = figure_size(report);
    let mut buffer = vec![255u8; 3 * (w * h) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (w, h)).into_drawing_area();
        draw(&root, report)?;
        root.present().map_err(plot_error)?;
    }
    let mut bytes = Vec::new();
    let err = |e: png::EncodingError| Error::Unsupported(format!("cannot encode the PNG: {e}"));
    let mut encoder = png::Encoder::new(&mut bytes, w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(err)?;
    writer.write_image_data(&buffer).map_err(err)?;
    writer.finish().map_err(err)?;
    Ok(bytes)
}

/// The figure as an SVG document.
pub fn svg(report: &Report) -> Result<String> {
    register_font()?;
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, figure_size(report)).into_drawing_area();
        draw(&root, report)?;
        root.present().map_err(plot_error)?;
    }
    Ok(text)
}

fn plot_error(e: impl std::fmt::Display) -> Error {
    Error::Unsupported(format!("cannot draw the plot: {e}"))
}

/// Every panel of `report` on `root`.
fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, report: &Report) -> Result<()> {
    root.fill(&WHITE).map_err(plot_error)?;
    let n = report.sections.len().max(1);
    let areas = root.split_evenly((n.div_ceil(COLUMNS), n.min(COLUMNS)));
    for (section, area) in report.sections.iter().zip(&areas) {
        panel(area, section).map_err(plot_error)?;
    }
    Ok(())
}

/// `[lo, hi]` of the positive finite values, widened by a margin on the log scale (and to a factor of
/// ten at least, so a single point sits inside a readable decade).
fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for v in values.filter(|v| v.is_finite() && *v > 0.0) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if hi == 0.0 {
        return (0.1, 1.0);
    }
    let (lo, hi) = (lo / 1.5, hi * 1.5);
    let widen = (10.0 * lo / hi).max(1.0).sqrt();
    (lo / widen, hi * widen)
}

/// The label of a tick of a log axis, at `v` = log10 of the value: the values 1, 2 and 5 times a power
/// of ten, in plain decimals (`0.05`, `20`); other positions stay unlabelled. The axes step by a
/// tenth of a decade, so 2 and 5 sit at `k + 0.3` and `k + 0.7`, 0.001 decade from `log10 2` and
/// `log10 5` (well under a pixel).
fn tick(v: f64) -> String {
    if !v.is_finite() {
        return String::new();
    }
    let k = (v + 0.02).floor();
    let fraction = v - k;
    let Some(m) = [
        (1.0, 0.0),
        (2.0, std::f64::consts::LOG10_2),
        (5.0, 1.0 - std::f64::consts::LOG10_2),
    ]
    .iter()
    .find(|(_, at)| (fraction - at).abs() < 0.02)
    .map(|(m, _)| m) else {
        return String::new();
    };
    let decimals = (-k).max(0.0) as usize;
    format!("{:.decimals$}", m * 10f64.powf(k))
}

/// Key points to ask plotters for on an axis spanning `span` decades, so that it steps by a tenth.
fn tenths(span: f64) -> usize {
    (10.0 * span).ceil() as usize + 2
}

/// One section's panel. Plotted in log10 of both values on linear axes, so that the ticks and the
/// grid lines (at 1 to 9 times each power of ten) are the report's own rather than plotters' choice.
fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    section: &Section,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let series: Vec<(Estimator, Vec<(f64, f64)>)> = (estimators(section).into_iter())
        .map(|e| {
            let pts = points(section, e).into_iter();
            let line = pts.map(|p| (p.seconds, p.blurred_error));
            let positive = line.filter(|(x, y)| *x > 0.0 && *y > 0.0 && y.is_finite());
            (e, positive.map(|(x, y)| (x.log10(), y.log10())).collect())
        })
        .collect();
    let floor = section.reference.floor().filter(|f| *f > 0.0);
    let all = || series.iter().flat_map(|(_, l)| l.iter());
    let (x0, x1) = log_range(all().map(|p| 10f64.powf(p.0)));
    let (y0, y1) = log_range(all().map(|p| 10f64.powf(p.1)).chain(floor));
    let (x0, x1, y0, y1) = (x0.log10(), x1.log10(), y0.log10(), y1.log10());
    let title = format!(
        "{}: blurred error against time",
        section_name(section.parameter.as_deref())
    );
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    let grid = |lo: f64, hi: f64| {
        let decades = lo.floor() as i32..=hi.ceil() as i32;
        decades
            .flat_map(|k| (1..10).map(move |m| (m, k as f64 + (m as f64).log10())))
            .filter(move |(_, v)| *v > lo && *v < hi)
    };
    let shade = |m: i32| {
        let g = if m == 1 { 200 } else { 232 };
        RGBColor(g, g, g)
    };
    for (m, x) in grid(x0, x1) {
        chart.draw_series(LineSeries::new([(x, y0), (x, y1)], shade(m)))?;
    }
    for (m, y) in grid(y0, y1) {
        chart.draw_series(LineSeries::new([(x0, y), (x1, y)], shade(m)))?;
    }
    chart
        .configure_mesh()
        .disable_mesh()
        .x_labels(tenths(x1 - x0))
        .y_labels(tenths(y1 - y0))
        .x_desc("seconds per run")
        .y_desc("relative L2 error, 5x5 blur")
        .axis_desc_style(("sans-serif", 16))
        .label_style(("sans-serif", 13))
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .draw()?;
    if let Some(f) = floor {
        let (grey, f) = (RGBColor(120, 120, 120), f.log10());
        chart
            .draw_series(DashedLineSeries::new(
                [(x0, f), (x1, f)],
                8,
                5,
                grey.stroke_width(2),
            ))?
            .label("reference floor")
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], grey.stroke_width(2)));
    }
    for (e, line) in &series {
        let c = colour(*e);
        chart
            .draw_series(LineSeries::new(line.clone(), c.stroke_width(2)))?
            .label(e.name())
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], c.stroke_width(2)));
        chart.draw_series(line.iter().map(|p| Circle::new(*p, 3, c.filled())))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(180, 180, 180))
        .label_font(("sans-serif", 13))
        .draw()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_label_one_two_five_per_decade() {
        assert_eq!(tick(-1.0), "0.1");
        assert_eq!(tick(-2.0 + 0.7), "0.05");
        assert_eq!(tick(1.3), "20");
        assert_eq!(tick(-0.0000001), "1");
        assert_eq!(tick(-2.0 + 0.5), "");
        assert_eq!(tick(f64::NAN), "");
    }

    #[test]
    fn log_ranges_hold_their_values_and_a_decade() {
        let (lo, hi) = log_range([0.02, 0.5, f64::INFINITY, 0.0].into_iter());
        assert!(lo < 0.02 && hi > 0.5);
        let (lo, hi) = log_range([0.3].into_iter());
        assert!(hi / lo >= 10.0 - 1e-9 && lo < 0.3 && hi > 0.3);
        assert_eq!(log_range(std::iter::empty()), (0.1, 1.0));
    }
}
