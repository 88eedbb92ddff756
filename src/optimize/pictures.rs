//! The pictures of a run: `views.png` (each view's target beside its current image) and `loss.png`
//! (the loss, and the IoU when the target shape is known, against the iteration).

use super::Optimization;
use crate::error::{Error, Result};
use crate::film::{Image, colormap, figure};

/// The current images of `views.png` use seeds `seed + PREVIEW_SEED + k` (the same at every snapshot).
pub const PREVIEW_SEED: u64 = 0x5EE0_0000_0000;
/// Size of `loss.png`'s loss panel (an IoU panel below it adds half the height).
pub const PLOT_SIZE: (u32, u32) = (640, 400);

/// Samples per pixel of `views.png`'s current images at least: enough to show the shape, whatever the
/// optimisation's own (often 8 or 16) samples.
pub const VIEWS_MIN_SPP: u32 = 64;

/// Views narrower than this many pixels are magnified by an integer factor in `views.png`, so that
/// the column titles fit.
pub const VIEWS_MIN_WIDTH: u32 = 96;

/// The samples per pixel of `views.png`'s current images for an optimisation at `spp`.
pub fn views_spp(spp: u32) -> u32 {
    spp.max(VIEWS_MIN_SPP)
}

/// One row per view: its target beside its current image (at [`views_spp`], seeds
/// `seed + PREVIEW_SEED + k`), magnified to [`VIEWS_MIN_WIDTH`], under the titles `target` and `now, N spp`, rows
/// [`colormap::PANEL_GAP`] pixels apart.
pub fn views_picture(opt: &Optimization, spp: u32, seed: u64) -> Result<Image> {
    let spp = views_spp(spp);
    let zoom = (opt.targets.first()).map_or(1, |t| VIEWS_MIN_WIDTH.div_ceil(t.width).max(1));
    let mut rows = Vec::with_capacity(opt.views.len() + 1);
    for (k, target) in opt.targets.iter().enumerate() {
        let seed = seed.wrapping_add(PREVIEW_SEED).wrapping_add(k as u64);
        let current = opt.render_view(k, spp, seed)?;
        let panels = [target, &current].map(|p| figure::magnify(p, zoom));
        let row = if k == 0 {
            let titles = ["target".to_string(), format!("now, {spp} spp")];
            figure::titled_columns(&titles, &panels)?
        } else {
            colormap::side_by_side(&panels)
        };
        rows.push(row);
    }
    let gap = colormap::PANEL_GAP;
    let width = rows.iter().map(|r| r.width).max().unwrap_or(0);
    let height = rows.iter().map(|r| r.height).sum::<u32>() + gap * (rows.len() as u32 - 1);
    let mut picture = Image::new(width, height);
    picture.rgb.fill(colormap::GAP_COLOUR);
    let mut y0 = 0usize;
    for row in &rows {
        let n = 3 * row.width as usize;
        for y in 0..row.height as usize {
            let start = 3 * (y0 + y) * width as usize;
            picture.rgb[start..start + n].copy_from_slice(&row.rgb[y * n..(y + 1) * n]);
        }
        y0 += (row.height + gap) as usize;
    }
    Ok(picture)
}

/// The loss against the iteration on a log scale (plotted as its logarithm, so that the numbered
/// ticks fall evenly whatever the range), with numbered axes and light grey grid lines; below it,
/// when `ious` holds finite values, the IoU on `[0, 1]` against the same iterations. Non-finite and zero
/// losses are left out.
pub fn loss_plot(losses: &[f64], ious: &[f64]) -> Result<Image> {
    use plotters::prelude::*;
    figure::register_font()?;
    let (w, h) = PLOT_SIZE;
    let with_iou = ious.iter().any(|v| v.is_finite());
    let h = if with_iou { h + h / 2 } else { h };
    let mut buffer = vec![255u8; 3 * (w * h) as usize];
    let points: Vec<(f64, f64)> = (losses.iter().enumerate())
        .filter(|(_, l)| l.is_finite() && **l > 0.0)
        .map(|(i, l)| (i as f64, *l))
        .collect();
    let iou_points: Vec<(f64, f64)> = (ious.iter().enumerate())
        .filter(|(_, v)| v.is_finite())
        .map(|(i, v)| (i as f64, *v))
        .collect();
    let last = (losses.len().max(1) - 1).max(1) as f64;
    let grey = RGBColor(215, 215, 215);
    let font = ("sans-serif", 14).into_font();
    let iteration = |x: &f64| format!("{x:.0}");
    // No more labels than iterations, so that every label is a whole iteration.
    let x_labels = (last as usize + 1).min(11);
    let mut draw = || -> Result<(), Box<dyn std::error::Error + '_>> {
        let root = BitMapBackend::with_buffer(&mut buffer, (w, h)).into_drawing_area();
        root.fill(&WHITE)?;
        let (top, bottom) = root.split_vertically(PLOT_SIZE.1);
        if !points.is_empty() {
            let lo = points.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
            let hi = points.iter().map(|p| p.1).fold(0.0, f64::max);
            // At least a factor of 2 above and below, so a flat curve sits in the middle.
            let (lo, hi) = (lo.min(hi / 2.0), hi.max(lo * 2.0));
            let mut chart = ChartBuilder::on(&top)
                .margin(12)
                .x_label_area_size(36)
                .y_label_area_size(64)
                .build_cartesian_2d(0.0..last, lo.log10()..hi.log10())?;
            chart
                .configure_mesh()
                .light_line_style(WHITE)
                .bold_line_style(grey)
                .label_style(font.clone())
                .axis_desc_style(font.clone())
                .x_desc("iteration")
                .y_desc("loss")
                .x_labels(x_labels)
                .x_label_formatter(&iteration)
                .y_labels(8)
                .y_label_formatter(&|y| format!("{:.1e}", 10f64.powf(*y)))
                .draw()?;
            let log_points = points.iter().map(|&(x, y)| (x, y.log10()));
            chart.draw_series(LineSeries::new(log_points, BLUE.stroke_width(2)))?;
        }
        if with_iou {
            let mut chart = ChartBuilder::on(&bottom)
                .margin(12)
                .x_label_area_size(36)
                .y_label_area_size(64)
                .build_cartesian_2d(0.0..last, 0.0..1.0)?;
            chart
                .configure_mesh()
                .light_line_style(WHITE)
                .bold_line_style(grey)
                .label_style(font.clone())
                .axis_desc_style(font.clone())
                .x_desc("iteration")
                .y_desc("IoU")
                .x_labels(x_labels)
                .x_label_formatter(&iteration)
                .y_labels(11)
                .y_label_formatter(&|y| format!("{y:.1}"))
                .draw()?;
            let green = RGBColor(0, 140, 60);
            chart.draw_series(LineSeries::new(iou_points.clone(), green.stroke_width(2)))?;
        }
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| Error::file("loss.png", format!("cannot draw the plot: {e}")))?;
    Ok(figure::from_srgb_bytes(w, h, &buffer))
}
