//! 8-bit sRGB PNG files of linear RGB values, written whole or not at all.

use super::files::write_atomically;
use crate::error::{Error, Result};
use std::path::Path;

/// The sRGB transfer function (IEC 61966-2-1) of a linear value, clamped to `[0, 1]` (NaN maps to 0).
#[inline]
pub fn srgb_encode(linear: f32) -> f32 {
    // Not `clamp`: that keeps NaN, while `NaN.max(0)` is 0.
    #[allow(clippy::manual_clamp)]
    let v = linear.max(0.0).min(1.0);
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// Writes an 8-bit sRGB PNG of linear RGB values (`3 · width · height`, clamped to `[0, 1]`).
/// Written to a temporary file and renamed, so a failure leaves no partial file.
pub fn write_png(path: &Path, width: u32, height: u32, rgb: &[f32]) -> Result<()> {
    let n = 3 * width as usize * height as usize;
    if n == 0 {
        return Err(Error::file(path, format!("empty image {width}x{height}")));
    }
    if rgb.len() != n {
        return Err(Error::file(
            path,
            format!(
                "{} values for a {width}x{height} RGB image, expected {n}",
                rgb.len()
            ),
        ));
    }
    let bytes: Vec<u8> = rgb
        .iter()
        .map(|&v| (srgb_encode(v) * 255.0 + 0.5) as u8)
        .collect();
    write_atomically(path, |tmp| {
        let err = |e: &dyn std::fmt::Display| Error::file(path, e);
        let file = std::fs::File::create(tmp).map_err(|e| err(&e))?;
        let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let mut writer = encoder.write_header().map_err(|e| err(&e))?;
        writer.write_image_data(&bytes).map_err(|e| err(&e))?;
        writer.finish().map_err(|e| err(&e))
    })
}
