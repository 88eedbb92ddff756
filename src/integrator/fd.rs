//! Central finite differences with common random numbers: the reference every derivative is checked
//! against.

use super::RenderOptions;
use crate::error::Result;
use crate::film::Image;
use crate::scene::Scene;

/// `(I(π + h) − I(π − h)) / 2h` for parameter `name`, both renders with the same seed and samples.
pub fn finite_difference(
    scene: &Scene,
    name: &str,
    h: f32,
    options: &RenderOptions,
) -> Result<Image> {
    let _ = (scene, name, h, options);
    todo!("fd: finite_difference")
}
