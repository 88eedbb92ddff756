//! Coarse-to-fine image resolution: the views of a grid stage (before the first refinement, between
//! two, after the last) may render at a half or a quarter of the film's width and height.
//!
//! While a grid is coarse, a lattice cell projects to many pixels, and every term of an iteration
//! (the loss pass, the interior, primary and secondary terms) costs in proportion to the pixels: a
//! reduced image resolves the cells as well at a fraction of the cost. The loss then compares the
//! reduced render against the target reduced by averaging its blocks of `d × d` pixels
//! ([`reduce`]); targets are rendered once, at full resolution.
//!
//! The block average is exactly the reduced film's pixel for a box pixel filter (a box of `d × d`
//! pixels is the union of their boxes). For the tent and the Gaussian filters (separable, centred on
//! the pixel centre, integral 1) the block average and the reduced film's pixel share their centre and
//! weight but not their width: along an axis, in reduced pixels, the tent of a reduced pixel has
//! variance 1/6, the block of `d` full-resolution tents `1/12 + 1/(6d²)` (0.125 at `d = 2`, 0.094 at
//! `d = 4`). The reduced target is slightly sharper than the reduced render: a symmetric blur of less
//! than a reduced pixel, which does not move a silhouette's place and which the last, full-resolution
//! stage does not have.

use super::View;
use crate::error::{Error, Result};
use crate::film::Image;
use crate::integrator::gradient::loss::downsample;
use crate::scene::json::{Obj, describe};
use crate::scene::{BlockKind, Scene};
use serde_json::Value;

/// The divisors of the film's width and height that a stage may use (full, half, quarter).
pub const DIVISORS: [u32; 3] = [1, 2, 4];

/// With [`ImageScale::Auto`], the fewest pixels (of the reduced film) a lattice cell must project to
/// in every view: about 3; 2.5 leaves room for views a little farther than the rest.
pub const AUTO_MIN_CELL_PIXELS: f32 = 2.5;

/// The image resolution of each grid stage (`image_scale` in `OPT.json`).
#[derive(Clone, Debug, Default, PartialEq)]
pub enum ImageScale {
    /// The film's resolution throughout (the default when no SDF grid is optimised, or when a texture
    /// or an environment map is: their texels are seen at the film's resolution).
    #[default]
    Full,
    /// One divisor per stage, in [`DIVISORS`]: the stage's views render at `width / d × height / d`.
    Stages(Vec<u32>),
    /// Per stage, the largest divisor (at most 4) at which a lattice cell of every optimised grid
    /// still projects to at least [`AUTO_MIN_CELL_PIXELS`] in every view ([`auto_divisors`]); the
    /// default when the optimised blocks are SDF grids (named parameters may come with them).
    Auto,
}

/// `image_scale`: a list of one scale per stage (`stages` of them; each 1, 0.5 or 0.25) or `"auto"`
/// (only with grids to optimise). `size` is the film's `(width, height)`, which each scale must
/// divide. Absent, it is `default` ([`default_scale`]).
pub(crate) fn parse(
    o: &Obj,
    stages: usize,
    has_grids: bool,
    default: ImageScale,
    size: (u32, u32),
) -> Result<ImageScale> {
    let field = o.at("image_scale");
    match o.get("image_scale") {
        None => Ok(default),
        Some(Value::String(s)) if s == "auto" => {
            if has_grids {
                Ok(ImageScale::Auto)
            } else {
                Err(Error::field(
                    field,
                    "\"auto\" follows the grids' cells, but optimize.grids names no grid",
                ))
            }
        }
        Some(Value::Array(list)) => {
            if list.len() != stages {
                return Err(Error::field(
                    field,
                    format!(
                        "needs one scale per grid stage ({stages}: upsample_at has {} \
                         iterations), got {}",
                        stages - 1,
                        list.len()
                    ),
                ));
            }
            let mut divisors = Vec::with_capacity(stages);
            for (i, v) in list.iter().enumerate() {
                let at = format!("{field}[{i}]");
                let divisor = v
                    .as_f64()
                    .and_then(|x| DIVISORS.into_iter().find(|&d| x == 1.0 / d as f64));
                let Some(d) = divisor else {
                    return Err(Error::field(
                        at,
                        format!("expected 1, 0.5 or 0.25, got {}", describe(v)),
                    ));
                };
                if !size.0.is_multiple_of(d) || !size.1.is_multiple_of(d) {
                    return Err(Error::field(
                        at,
                        format!(
                            "1/{d} of the {}x{} film is not a whole number of pixels",
                            size.0, size.1
                        ),
                    ));
                }
                divisors.push(d);
            }
            Ok(ImageScale::Stages(divisors))
        }
        Some(v) => Err(Error::field(
            field,
            format!(
                "expected a list of scales (1, 0.5 or 0.25), one per grid stage, or \"auto\", got {}",
                describe(v)
            ),
        )),
    }
}

/// `image_scale` when `OPT.json` leaves it out: [`ImageScale::Auto`] when the optimised blocks
/// `grids` include an SDF grid and no texture or environment map (whose texels the film must
/// resolve), else [`ImageScale::Full`].
pub fn default_scale(scene: &Scene, grids: &[String]) -> ImageScale {
    let kinds: Vec<BlockKind> = (grids.iter())
        .filter_map(|node| scene.block_kind(node))
        .collect();
    if kinds.contains(&BlockKind::Grid) && kinds.iter().all(|&k| k == BlockKind::Grid) {
        ImageScale::Auto
    } else {
        ImageScale::Full
    }
}

/// The divisor of each of the `stages` grid stages: [`ImageScale::Auto`] resolved against `scene`
/// (its grids `grids` at their current dimensions, each refined `n → 2n − 1` per stage) and `views`.
/// Errors: a list of another length, or a divisor that does not divide the film.
pub fn divisors(
    scale: &ImageScale,
    scene: &Scene,
    views: &[View],
    grids: &[String],
    stages: usize,
) -> Result<Vec<u32>> {
    let (w, h) = (scene.camera.width, scene.camera.height);
    match scale {
        ImageScale::Full => Ok(vec![1; stages]),
        ImageScale::Stages(d) => {
            if d.len() != stages {
                return Err(Error::field(
                    "image_scale",
                    format!("needs one scale per grid stage ({stages}), got {}", d.len()),
                ));
            }
            if let Some(&bad) = d
                .iter()
                .find(|&&d| !DIVISORS.contains(&d) || !w.is_multiple_of(d) || !h.is_multiple_of(d))
            {
                return Err(Error::field(
                    "image_scale",
                    format!("1/{bad} of the {w}x{h} film is not a whole number of pixels"),
                ));
            }
            Ok(d.clone())
        }
        ImageScale::Auto => auto_divisors(scene, views, grids, stages),
    }
}

/// For each stage, the largest divisor `d` of [`DIVISORS`] dividing the film's width and height at
/// which `min over views and grids of f · c / (r · d) ≥` [`AUTO_MIN_CELL_PIXELS`]: `f` the view's
/// focal length in pixels (`(height / 2) / tan(fov_y / 2)`), `c` the grid's smallest lattice spacing
/// at that stage (its box's side over `n − 1`, the box in the grid node's own units), `r` the
/// distance from the view's eye to the box's centre. Grids that are not in `grids` (or not grids) are
/// ignored; with none, every stage is at full resolution.
pub fn auto_divisors(
    scene: &Scene,
    views: &[View],
    grids: &[String],
    stages: usize,
) -> Result<Vec<u32>> {
    let (w, h) = (scene.camera.width, scene.camera.height);
    let mut cells = Vec::new(); // (centre, smallest spacing at stage 0, dims)
    for block in scene.grid_blocks() {
        if !grids.contains(&block.node) {
            continue;
        }
        let [lo, hi] = scene.grid_box(&block.node)?;
        let dims = scene.grid_values(&block.node)?.dims;
        cells.push(((lo + hi) * 0.5, hi - lo, dims));
    }
    if cells.is_empty() {
        return Ok(vec![1; stages]);
    }
    let mut out = Vec::with_capacity(stages);
    for stage in 0..stages {
        let mut pixels = f32::INFINITY;
        for &(centre, side, dims) in &cells {
            let spacing = (0..3)
                .map(|a| {
                    let mut n = dims[a];
                    for _ in 0..stage {
                        n = 2 * n - 1;
                    }
                    side[a] / (n.max(2) - 1) as f32
                })
                .fold(f32::INFINITY, f32::min);
            for view in views {
                let focal = 0.5 * h as f32 / (0.5 * view.fov_y.to_radians()).tan();
                let distance = (view.origin - centre).length().max(1e-6);
                pixels = pixels.min(focal * spacing / distance);
            }
        }
        let d = DIVISORS
            .into_iter()
            .rev()
            .find(|&d| {
                w.is_multiple_of(d)
                    && h.is_multiple_of(d)
                    && pixels / d as f32 >= AUTO_MIN_CELL_PIXELS
            })
            .unwrap_or(1);
        out.push(d);
    }
    Ok(out)
}

/// The stage of iteration `index`: how many of the refinements `upsample_at` come at or before it.
pub fn stage_of(index: u32, upsample_at: &[u32]) -> usize {
    upsample_at.iter().filter(|&&u| u <= index).count()
}

/// `image` reduced by `divisor` (1, 2 or 4): each pixel the mean of a block of `divisor × divisor`
/// pixels (repeated 2 × 2 box averages). The image's sides must be multiples of `divisor`.
pub fn reduce(image: &Image, divisor: u32) -> Image {
    debug_assert!(DIVISORS.contains(&divisor));
    debug_assert!(image.width.is_multiple_of(divisor) && image.height.is_multiple_of(divisor));
    let mut out = image.clone();
    let mut d = divisor;
    while d > 1 {
        out = downsample(&out);
        d /= 2;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reduced image's pixels are the means of their blocks.
    #[test]
    fn reduce_averages_blocks() {
        let (w, h) = (8u32, 12u32);
        let mut image = Image::new(w, h);
        for (k, v) in image.rgb.iter_mut().enumerate() {
            *v = ((k * 37 % 101) as f32).sqrt();
        }
        for d in DIVISORS {
            let r = reduce(&image, d);
            assert_eq!((r.width, r.height), (w / d, h / d));
            for y in 0..h / d {
                for x in 0..w / d {
                    for c in 0..3 {
                        let mut sum = 0.0f64;
                        for j in 0..d {
                            for i in 0..d {
                                let k = 3 * ((y * d + j) * w + x * d + i) + c;
                                sum += image.rgb[k as usize] as f64;
                            }
                        }
                        let mean = sum / (d * d) as f64;
                        let got = r.rgb[(3 * (y * (w / d) + x) + c) as usize] as f64;
                        assert!(
                            (got - mean).abs() < 1e-5 * mean.max(1.0),
                            "{d} {x} {y}: {got} vs {mean}"
                        );
                    }
                }
            }
        }
    }

    /// `image_scale` as `parse` reads it, for a `size` film with `stages` stages and grids.
    fn parsed(v: serde_json::Value, stages: usize, size: (u32, u32)) -> Result<ImageScale> {
        let root = serde_json::json!({ "image_scale": v });
        let o = Obj::new(&root, String::new(), &["image_scale"]).unwrap();
        parse(&o, stages, true, ImageScale::Full, size)
    }

    #[test]
    fn image_scale_parses_lists_and_auto_and_names_the_field_of_bad_values() {
        use serde_json::json;
        let root = json!({});
        let o = Obj::new(&root, String::new(), &["image_scale"]).unwrap();
        assert_eq!(
            parse(&o, 3, true, ImageScale::Full, (128, 128)).unwrap(),
            ImageScale::Full
        );
        assert_eq!(
            parse(&o, 3, true, ImageScale::Auto, (128, 128)).unwrap(),
            ImageScale::Auto
        );
        assert_eq!(
            parsed(json!([0.5, 1, 0.25]), 3, (128, 64)).unwrap(),
            ImageScale::Stages(vec![2, 1, 4])
        );
        assert_eq!(
            parsed(json!("auto"), 2, (128, 128)).unwrap(),
            ImageScale::Auto
        );
        let root = json!({"image_scale": "auto"});
        let o = Obj::new(&root, String::new(), &["image_scale"]).unwrap();
        let no_grids = parse(&o, 1, false, ImageScale::Full, (128, 128))
            .unwrap_err()
            .to_string();
        assert!(
            no_grids.starts_with("image_scale: \"auto\" follows"),
            "{no_grids}"
        );
        for (v, stages, size, expected) in [
            (
                json!([1, 0.5]),
                3,
                (128, 128),
                "image_scale: needs one scale per grid stage (3",
            ),
            (
                json!([1, 0.3]),
                2,
                (128, 128),
                "image_scale[1]: expected 1, 0.5 or 0.25, got",
            ),
            (
                json!([0.125]),
                1,
                (128, 128),
                "image_scale[0]: expected 1, 0.5 or 0.25",
            ),
            (
                json!(["half"]),
                1,
                (128, 128),
                "image_scale[0]: expected 1, 0.5 or 0.25",
            ),
            (
                json!([0.25]),
                1,
                (128, 90),
                "image_scale[0]: 1/4 of the 128x90 film",
            ),
            (
                json!(0.5),
                1,
                (128, 128),
                "image_scale: expected a list of scales",
            ),
            (
                json!("half"),
                1,
                (128, 128),
                "image_scale: expected a list of scales",
            ),
        ] {
            let e = parsed(v, stages, size).unwrap_err().to_string();
            assert!(e.starts_with(expected), "{e}");
            assert!(!e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn stages_follow_upsample_at() {
        assert_eq!(stage_of(0, &[40, 100]), 0);
        assert_eq!(stage_of(39, &[40, 100]), 0);
        assert_eq!(stage_of(40, &[40, 100]), 1);
        assert_eq!(stage_of(100, &[40, 100]), 2);
        assert_eq!(stage_of(7, &[]), 0);
    }
}
