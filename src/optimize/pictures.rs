//! The pictures of a run: `views.png` (each view's target beside its current image) and `loss.png`
//! (the loss, and the IoU when the target shape is known, against the iteration).

use super::Optimization;
use crate::error::{Error, Result};
use crate::film::{Image, colormap};

/// The current images of `views.png` use seeds `seed + PREVIEW_SEED + k` (the same at every snapshot).
pub const PREVIEW_SEED: u64 = 0x5EE0_0000_0000;
/// Size of `loss.png`'s loss panel (an IoU panel below it adds half the height).
pub const PLOT_SIZE: (u32, u32) = (640, 400);

/// One row per view: its target beside its current image (at `spp`, seeds `seed + PREVIEW_SEED + k`),
/// rows [`colormap::PANEL_GAP`] pixels apart.
pub fn views_picture(opt: &Optimization, spp: u32, seed: u64) -> Result<Image> {
    let mut rows = Vec::with_capacity(opt.views.len());
    for (k, target) in opt.targets.iter().enumerate() {
        let seed = seed.wrapping_add(PREVIEW_SEED).wrapping_add(k as u64);
        let current = opt.render_view(k, spp, seed)?;
        rows.push(colormap::side_by_side(&[target.clone(), current]));
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

/// The loss against the iteration on a log scale, with light grey lines at the powers of ten and every
/// tenth of the iterations; below it, when `ious` holds finite values, the IoU on `[0, 1]` with grey lines
/// every 0.1 (no text: the numbers are in progress.csv). Non-finite and zero losses are left out.
pub fn loss_plot(losses: &[f64], ious: &[f64]) -> Result<Image> {
    use plotters::prelude::*;
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
    let mut draw = || -> Result<(), Box<dyn std::error::Error + '_>> {
        let root = BitMapBackend::with_buffer(&mut buffer, (w, h)).into_drawing_area();
        root.fill(&WHITE)?;
        let (top, bottom) = root.split_vertically(PLOT_SIZE.1);
        let frame = |lo: f64, hi: f64| [(0.0, lo), (last, lo), (last, hi), (0.0, hi), (0.0, lo)];
        if !points.is_empty() {
            let lo = points.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
            let hi = points.iter().map(|p| p.1).fold(0.0, f64::max);
            // At least a factor of 2 above and below, so a flat curve sits in the middle.
            let (lo, hi) = (lo.min(hi / 2.0), hi.max(lo * 2.0));
            let mut chart = ChartBuilder::on(&top)
                .margin(16)
                .build_cartesian_2d(0.0..last, (lo..hi).log_scale())?;
            let (e0, e1) = (lo.log10().ceil() as i32, hi.log10().floor() as i32);
            for e in e0..=e1 {
                let y = 10f64.powi(e);
                chart.draw_series(LineSeries::new([(0.0, y), (last, y)], grey))?;
            }
            for i in 0..=10 {
                let x = last * i as f64 / 10.0;
                chart.draw_series(LineSeries::new([(x, lo), (x, hi)], grey))?;
            }
            chart.draw_series(LineSeries::new(frame(lo, hi), BLACK))?;
            chart.draw_series(LineSeries::new(points.clone(), BLUE.stroke_width(2)))?;
        }
        if with_iou {
            let mut chart = ChartBuilder::on(&bottom)
                .margin(16)
                .build_cartesian_2d(0.0..last, 0.0..1.0)?;
            for i in 0..=10 {
                let (x, y) = (last * i as f64 / 10.0, i as f64 / 10.0);
                chart.draw_series(LineSeries::new([(x, 0.0), (x, 1.0)], grey))?;
                chart.draw_series(LineSeries::new([(0.0, y), (last, y)], grey))?;
            }
            chart.draw_series(LineSeries::new(frame(0.0, 1.0), BLACK))?;
            let green = RGBColor(0, 140, 60);
            chart.draw_series(LineSeries::new(iou_points.clone(), green.stroke_width(2)))?;
        }
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| Error::file("loss.png", format!("cannot draw the plot: {e}")))?;
    let mut image = Image::new(w, h);
    for (v, b) in image.rgb.iter_mut().zip(&buffer) {
        *v = colormap::srgb_decode(*b as f32 / 255.0);
    }
    Ok(image)
}
