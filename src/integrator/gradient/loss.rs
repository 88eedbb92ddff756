//! Image losses and their pixel adjoints `g = ∂L/∂I`.

use crate::error::{Error, Result};
use crate::film::Image;

/// A loss between a rendered image `I` and a target `T` of the same size.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum Loss {
    /// `mean over pixels and R, G, B of (I − T)²` (the default).
    #[default]
    L2,
    /// `mean over pixels and R, G, B of |I − T|` (its adjoint is 0 where `I = T`).
    L1,
}

impl std::str::FromStr for Loss {
    type Err = String;
    /// `"l2"` or `"l1"`.
    fn from_str(text: &str) -> std::result::Result<Self, String> {
        match text {
            "l2" => Ok(Loss::L2),
            "l1" => Ok(Loss::L1),
            _ => Err(format!("unknown loss {text:?} (expected l2 or l1)")),
        }
    }
}

impl Loss {
    /// The loss of `image` against `target` and its pixel adjoint `∂L/∂I` (an image of the same size).
    /// Errors: the sizes differ (`what` names the target in the message).
    pub fn evaluate(self, image: &Image, target: &Image, what: &str) -> Result<(f64, Image)> {
        if (image.width, image.height) != (target.width, target.height) {
            return Err(Error::field(
                what,
                format!(
                    "the target is {}x{}, the image {}x{}",
                    target.width, target.height, image.width, image.height
                ),
            ));
        }
        let n = image.rgb.len().max(1) as f64;
        let mut adjoint = Image::new(image.width, image.height);
        let mut sum = 0.0f64;
        for ((g, &i), &t) in adjoint.rgb.iter_mut().zip(&image.rgb).zip(&target.rgb) {
            let d = i as f64 - t as f64;
            let (value, slope) = match self {
                Loss::L2 => (d * d, 2.0 * d),
                Loss::L1 => (d.abs(), if d == 0.0 { 0.0 } else { d.signum() }),
            };
            sum += value;
            *g = (slope / n) as f32;
        }
        Ok((sum / n, adjoint))
    }
}
