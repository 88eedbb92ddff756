use crate::error::Result;
use std::path::Path;

/// Writes float32 channels (each `width · height` values, row-major from the top) to an EXR file.
/// Written to a temporary file and renamed, so a failure leaves no partial file.
pub fn write_exr(
    path: &Path,
    width: u32,
    height: u32,
    channels: &[(String, Vec<f32>)],
) -> Result<()> {
    let _ = (path, width, height, channels);
    todo!("output: write_exr")
}

/// Writes an 8-bit sRGB PNG of linear RGB values (`3 · width · height`, clamped to `[0, 1]`).
/// Written to a temporary file and renamed, so a failure leaves no partial file.
pub fn write_png(path: &Path, width: u32, height: u32, rgb: &[f32]) -> Result<()> {
    let _ = (path, width, height, rgb);
    todo!("output: write_png")
}
