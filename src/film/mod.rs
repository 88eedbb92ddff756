//! Pixel filters, accumulation and images, and the colour maps of the derivative pictures; the image
//! files themselves (EXR, PNG) are [`crate::io`]'s.

pub mod accumulate;
mod adjoint;
pub mod colormap;
pub mod figure;
mod filter;

pub use accumulate::{Film, Normalization, PixelFilm, SampleSink, SplatFilm, splat_filtered};
pub use adjoint::{AdjointFilm, AdjointTile};
pub use filter::{Filter, Footprint};
// The image files' old home, kept for the paths users and the integrators name.
pub use crate::io::{
    Channels, check_output_path, read_exr, read_exr_rgb, rgb_from_channels, srgb_encode, write_exr,
    write_exr_and_png, write_png,
};

/// A linear-RGB image, row-major from the top row, three `f32` per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `rgb[3 * (y * width + x) + c]`.
    pub rgb: Vec<f32>,
}

impl Image {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            rgb: vec![0.0; 3 * width as usize * height as usize],
        }
    }
    /// The colour of pixel `(x, y)`.
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 3] {
        let i = 3 * (y * self.width + x) as usize;
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }
    /// The EXR channels `{prefix}R`, `{prefix}G`, `{prefix}B` of the image.
    pub fn rgb_channels(&self, prefix: &str) -> Channels {
        ["R", "G", "B"]
            .iter()
            .enumerate()
            .map(|(c, name)| (format!("{prefix}{name}"), self.channel(c)))
            .collect()
    }
    /// One channel (0 = R, 1 = G, 2 = B) as a plane of `width · height` values.
    pub fn channel(&self, c: usize) -> Vec<f32> {
        self.rgb.iter().skip(c).step_by(3).copied().collect()
    }
}
