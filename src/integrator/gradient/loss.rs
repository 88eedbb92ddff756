//! Image losses and their pixel adjoints `g = ∂L/∂I`, on the image alone or summed over an image
//! pyramid (a multi-scale loss).

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
    /// A multi-scale loss: `Σ_{k < levels} ℓ(Dᵏ I, Dᵏ T)`, `ℓ` the L1 (`l1`) or L2 loss above (each
    /// level's a mean over its own pixels, so that every level weighs alike) and `D` the 2×2 box
    /// average (a `w × h` image becomes `⌈w/2⌉ × ⌈h/2⌉`, a last odd row or column averaging the pixels
    /// it has); levels stop early at a 1×1 image. Its adjoint is `Σ_k (Dᵀ)ᵏ gₖ`: each level's adjoint
    /// spread back over the pixels it averages. Coarse levels see a whole silhouette's offset where
    /// the fine level sees only the thin band of pixels it covers.
    MultiScale {
        /// The L1 loss at each level (else L2).
        l1: bool,
        /// Levels, ≥ 1 (1 is the plain loss).
        levels: u32,
    },
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
    /// This loss summed over a pyramid of `levels` images ([`Loss::MultiScale`]); `levels ≤ 1` gives
    /// the plain loss back.
    pub fn multiscale(self, levels: u32) -> Loss {
        let l1 = match self {
            Loss::L2 => false,
            Loss::L1 => true,
            Loss::MultiScale { l1, .. } => l1,
        };
        match (levels <= 1, l1) {
            (true, false) => Loss::L2,
            (true, true) => Loss::L1,
            (false, l1) => Loss::MultiScale { l1, levels },
        }
    }

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
        let (l1, levels) = match self {
            Loss::L2 => return Ok(pixel_loss(false, image, target)),
            Loss::L1 => return Ok(pixel_loss(true, image, target)),
            Loss::MultiScale { l1, levels } => (l1, levels.max(1)),
        };
        let (mut value, mut adjoint) = pixel_loss(l1, image, target);
        // The pyramids of both images, level by level, and each level's adjoint spread back down.
        let mut chain = vec![(image.clone(), target.clone())];
        for _ in 1..levels {
            let (i, t) = chain.last().expect("at least the image");
            if i.width == 1 && i.height == 1 {
                break;
            }
            let next = (downsample(i), downsample(t));
            let (v, mut g) = pixel_loss(l1, &next.0, &next.1);
            value += v;
            for k in (0..chain.len()).rev() {
                g = downsample_adjoint(&g, chain[k].0.width, chain[k].0.height);
            }
            for (a, g) in adjoint.rgb.iter_mut().zip(&g.rgb) {
                *a += g;
            }
            chain.push(next);
        }
        Ok((value, adjoint))
    }
}

/// The L1 or L2 loss (mean over pixels and channels) and its adjoint.
fn pixel_loss(l1: bool, image: &Image, target: &Image) -> (f64, Image) {
    let n = image.rgb.len().max(1) as f64;
    let mut adjoint = Image::new(image.width, image.height);
    let mut sum = 0.0f64;
    for ((g, &i), &t) in adjoint.rgb.iter_mut().zip(&image.rgb).zip(&target.rgb) {
        let d = i as f64 - t as f64;
        let (value, slope) = if l1 {
            (d.abs(), if d == 0.0 { 0.0 } else { d.signum() })
        } else {
            (d * d, 2.0 * d)
        };
        sum += value;
        *g = (slope / n) as f32;
    }
    (sum / n, adjoint)
}

/// The 2×2 box average of `image`: `⌈w/2⌉ × ⌈h/2⌉`, each pixel the mean of the 1, 2 or 4 pixels of
/// its block.
pub fn downsample(image: &Image) -> Image {
    let (w, h) = (image.width as usize, image.height as usize);
    let (cw, ch) = (w.div_ceil(2), h.div_ceil(2));
    let mut out = Image::new(cw as u32, ch as u32);
    for y in 0..h {
        for x in 0..w {
            let (cx, cy) = (x / 2, y / 2);
            let count = block_count(cx, cy, w, h) as f32;
            for c in 0..3 {
                out.rgb[3 * (cy * cw + cx) + c] += image.rgb[3 * (y * w + x) + c] / count;
            }
        }
    }
    out
}

/// The adjoint of [`downsample`] for a fine image of `width × height`: each fine pixel gets its
/// block's adjoint divided by the block's pixel count.
fn downsample_adjoint(coarse: &Image, width: u32, height: u32) -> Image {
    let (w, h) = (width as usize, height as usize);
    let cw = coarse.width as usize;
    let mut out = Image::new(width, height);
    for y in 0..h {
        for x in 0..w {
            let (cx, cy) = (x / 2, y / 2);
            let count = block_count(cx, cy, w, h) as f32;
            for c in 0..3 {
                out.rgb[3 * (y * w + x) + c] = coarse.rgb[3 * (cy * cw + cx) + c] / count;
            }
        }
    }
    out
}

/// Pixels of a `w × h` image in the 2×2 block of coarse pixel `(cx, cy)`.
fn block_count(cx: usize, cy: usize, w: usize, h: usize) -> usize {
    (w.min(2 * cx + 2) - 2 * cx) * (h.min(2 * cy + 2) - 2 * cy)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(width: u32, height: u32, salt: u32) -> Image {
        let mut out = Image::new(width, height);
        for (k, v) in out.rgb.iter_mut().enumerate() {
            let h = (k as u32)
                .wrapping_mul(2_654_435_761)
                .wrapping_add(salt * 97);
            *v = (h % 1000) as f32 / 1000.0;
        }
        out
    }

    /// The box average of a 3×3 image: corners of 4, 2 (edges) and 1 pixels.
    #[test]
    fn downsample_of_an_odd_image() {
        let mut i = Image::new(3, 3);
        for (k, v) in i.rgb.iter_mut().enumerate() {
            *v = (k / 3) as f32; // pixel index
        }
        let d = downsample(&i);
        assert_eq!((d.width, d.height), (2, 2));
        let px = |x: usize, y: usize| d.rgb[3 * (y * 2 + x)];
        assert_eq!(px(0, 0), (0.0 + 1.0 + 3.0 + 4.0) / 4.0);
        assert_eq!(px(1, 0), (2.0 + 5.0) / 2.0);
        assert_eq!(px(0, 1), (6.0 + 7.0) / 2.0);
        assert_eq!(px(1, 1), 8.0);
    }

    /// One level is the plain loss, bit for bit.
    #[test]
    fn one_level_is_the_plain_loss() {
        let (i, t) = (image(7, 5, 1), image(7, 5, 2));
        for base in [Loss::L2, Loss::L1] {
            assert_eq!(base.multiscale(1), base);
            let plain = base.evaluate(&i, &t, "t").unwrap();
            let one = Loss::MultiScale {
                l1: base == Loss::L1,
                levels: 1,
            }
            .evaluate(&i, &t, "t")
            .unwrap();
            assert_eq!(plain.0, one.0);
            assert_eq!(plain.1.rgb, one.1.rgb);
        }
    }

    /// The multi-scale loss's adjoint against central differences of its value, for L2 (smooth) and
    /// L1 (away from its kinks: the steps are far smaller than any |I − T| at every level), on an
    /// image of odd size whose pyramid reaches 1×1 (13×6 → 7×3 → 4×2 → 2×1 → 1×1).
    #[test]
    fn multiscale_adjoint_matches_differences() {
        let (i, t) = (image(13, 6, 3), image(13, 6, 4));
        for l1 in [false, true] {
            let loss = Loss::MultiScale { l1, levels: 8 };
            let (value, adjoint) = loss.evaluate(&i, &t, "t").unwrap();
            let plain = Loss::L2.multiscale(1).evaluate(&i, &t, "t").unwrap().0;
            assert!(l1 || value > plain, "{value} vs {plain}");
            for k in [0, 5, 40, 77, 100, 233] {
                let at = |d: f32| {
                    let mut j = i.clone();
                    j.rgb[k] += d;
                    loss.evaluate(&j, &t, "t").unwrap().0
                };
                let h = 1e-4f32;
                let fd = (at(h) - at(-h)) / (2.0 * h as f64);
                let g = adjoint.rgb[k] as f64;
                // L1's differences carry the f32 rounding of the coarse levels' means, where the
                // step is h/78: 1.5% (a level left out or counted twice is ~20% of the adjoint).
                let bound = if l1 { 1.5e-2 } else { 2e-3 };
                assert!(
                    (g - fd).abs() < bound * fd.abs().max(1e-3),
                    "l1 {l1}, entry {k}: adjoint {g} vs difference {fd}"
                );
            }
        }
    }
}
