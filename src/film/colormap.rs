//! A diverging colour map for derivative images (blue negative, white zero, red positive), the panel of
//! one derivative, and panels side by side; [`super::figure`] titles them and adds the colour bars.

use super::Image;

/// Control colours of [`diverging`], in sRGB, at `t = -1, -2/3, -1/3, 0, 1/3, 2/3, 1`: ColorBrewer's
/// 7-class RdBu (Brewer, colorbrewer2.org) with its off-white centre replaced by pure white, so that a
/// zero derivative is exactly white. Lightness falls monotonically away from the centre on both sides.
const CONTROL: [[u8; 3]; 7] = [
    [0x21, 0x66, 0xac],
    [0x67, 0xa9, 0xcf],
    [0xd1, 0xe5, 0xf0],
    [0xff, 0xff, 0xff],
    [0xfd, 0xdb, 0xc7],
    [0xef, 0x8a, 0x62],
    [0xb2, 0x18, 0x2b],
];

/// The diverging map at `t ∈ [-1, 1]` as sRGB components in `[0, 1]`: `-1` blue, `0` white, `+1` red,
/// piecewise linear in sRGB between the `CONTROL` colours (ColorBrewer RdBu, white centre). `t` outside `[-1, 1]` is clamped (the end
/// colours); NaN maps to black so that it stands out from every value of the map.
pub fn diverging(t: f32) -> [f32; 3] {
    if t.is_nan() {
        return [0.0; 3];
    }
    let segments = (CONTROL.len() - 1) as f32;
    let x = (t.clamp(-1.0, 1.0) + 1.0) * 0.5 * segments;
    let i = (x.floor() as usize).min(CONTROL.len() - 2);
    let f = x - i as f32;
    let (a, b) = (CONTROL[i], CONTROL[i + 1]);
    std::array::from_fn(|c| (a[c] as f32 + f * (b[c] as f32 - a[c] as f32)) / 255.0)
}

/// The inverse of the sRGB transfer function (IEC 61966-2-1): a linear value from an sRGB one in
/// `[0, 1]`. Used to hand colour-map colours to [`super::write_png`], which encodes linear values.
pub fn srgb_decode(encoded: f32) -> f32 {
    if encoded <= 0.040_45 {
        encoded / 12.92
    } else {
        ((encoded + 0.055) / 1.055).powf(2.4)
    }
}

/// The percentile of `|v|` over the finite values, used as a robust maximum.
pub const SCALE_PERCENTILE: f32 = 0.99;

/// A robust maximum of `|v|`: the [`SCALE_PERCENTILE`] (99th) percentile of the finite `|v|` (nearest
/// rank), so that a few firefly pixels do not wash the panel out. Falls back to the largest finite `|v|`
/// when the percentile is 0 (sparse derivatives), and to 1 when every value is 0 or not finite (the panel
/// is then white, or black for NaN, whatever the scale).
pub fn robust_scale(values: &[f32]) -> f32 {
    let mut abs: Vec<f32> = values
        .iter()
        .filter(|v| v.is_finite())
        .map(|v| v.abs())
        .collect();
    if abs.is_empty() {
        return 1.0;
    }
    abs.sort_unstable_by(f32::total_cmp);
    let rank = ((SCALE_PERCENTILE * abs.len() as f32).ceil() as usize).clamp(1, abs.len());
    let percentile = abs[rank - 1];
    let max = abs[abs.len() - 1];
    if percentile > 0.0 {
        percentile
    } else if max > 0.0 {
        max
    } else {
        1.0
    }
}

/// The panel of one derivative image: each pixel's mean of `R`, `G`, `B` (so a parameter acting on one
/// colour channel still shows), mapped by [`diverging`] at `mean / scale` with `scale =`
/// [`robust_scale`] of the means. Returns the panel in linear RGB (for [`super::write_png`]) and the scale.
pub fn derivative_panel(derivative: &Image) -> (Image, f32) {
    let means: Vec<f32> = derivative
        .rgb
        .chunks_exact(3)
        .map(|p| (p[0] + p[1] + p[2]) / 3.0)
        .collect();
    let scale = robust_scale(&means);
    let mut panel = Image::new(derivative.width, derivative.height);
    for (pixel, mean) in panel.rgb.chunks_exact_mut(3).zip(&means) {
        let srgb = diverging(mean / scale);
        for (out, c) in pixel.iter_mut().zip(srgb) {
            *out = srgb_decode(c);
        }
    }
    (panel, scale)
}

/// Gap between panels, in pixels.
pub const PANEL_GAP: u32 = 4;
/// Colour of the gap (linear; mid grey in sRGB), distinct from the white of a zero derivative.
pub const GAP_COLOUR: f32 = 0.2;

/// Images of one height placed left to right with [`PANEL_GAP`] pixels of [`GAP_COLOUR`] between them.
/// Panels shorter than the tallest are padded below with the gap colour.
pub fn side_by_side(panels: &[Image]) -> Image {
    let height = panels.iter().map(|p| p.height).max().unwrap_or(0);
    let width = panels.iter().map(|p| p.width).sum::<u32>()
        + PANEL_GAP * (panels.len() as u32).saturating_sub(1);
    let mut out = Image::new(width, height);
    out.rgb.fill(GAP_COLOUR);
    let mut x0 = 0usize;
    for panel in panels {
        let w = panel.width as usize;
        for y in 0..panel.height as usize {
            let src = &panel.rgb[3 * y * w..3 * (y + 1) * w];
            let start = 3 * (y * width as usize + x0);
            out.rgb[start..start + 3 * w].copy_from_slice(src);
        }
        x0 += w + PANEL_GAP as usize;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lightness(c: [f32; 3]) -> f32 {
        // Rec. 709 luma of the sRGB components: monotone in perceived lightness for this purpose.
        0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
    }

    #[test]
    fn ends_and_centre() {
        assert_eq!(diverging(0.0), [1.0, 1.0, 1.0]);
        let blue = diverging(-1.0);
        assert!(blue[2] > 0.6 && blue[2] > 2.0 * blue[0], "{blue:?}");
        let red = diverging(1.0);
        assert!(red[0] > 0.6 && red[0] > 2.0 * red[2], "{red:?}");
        // Clamped beyond ±1; NaN black.
        assert_eq!(diverging(-7.0), blue);
        assert_eq!(diverging(f32::INFINITY), red);
        assert_eq!(diverging(f32::NAN), [0.0; 3]);
    }

    #[test]
    fn monotone_and_continuous() {
        let n = 2000;
        let mut previous = diverging(-1.0);
        for k in 1..=n {
            let t = -1.0 + 2.0 * k as f32 / n as f32;
            let c = diverging(t);
            // Lightness rises towards white, then falls.
            if t <= 0.0 {
                assert!(lightness(c) >= lightness(previous) - 1e-6, "t = {t}");
                assert!(c[2] >= c[0], "blue side at t = {t}: {c:?}");
            } else {
                assert!(lightness(c) <= lightness(previous) + 1e-6, "t = {t}");
                assert!(c[0] >= c[2], "red side at t = {t}: {c:?}");
            }
            // No jumps: steps of 1/1000 move each component by at most 1/100.
            for i in 0..3 {
                assert!((c[i] - previous[i]).abs() < 0.01, "t = {t}");
            }
            previous = c;
        }
    }

    #[test]
    fn srgb_round_trip() {
        for k in 0..=100 {
            let v = k as f32 / 100.0;
            assert!(
                (super::super::srgb_encode(srgb_decode(v)) - v).abs() < 1e-5,
                "{v}"
            );
        }
    }

    #[test]
    fn robust_scale_ignores_outliers() {
        // 1000 values of magnitude up to 1, and 5 fireflies of 1e6: the 99th percentile is about 1.
        let mut v: Vec<f32> = (0..1000)
            .map(|i| (i as f32 / 999.0) * if i % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        v.extend([1e6; 5]);
        let s = robust_scale(&v);
        assert!((0.97..=1.0).contains(&s), "{s}");
        // Sparse: 99% zeros, then the maximum.
        let mut sparse = vec![0.0; 1000];
        sparse[3] = -2.5;
        assert_eq!(robust_scale(&sparse), 2.5);
        assert_eq!(robust_scale(&[0.0; 10]), 1.0);
        assert_eq!(robust_scale(&[f32::NAN, 0.0]), 1.0);
    }

    #[test]
    fn panel_maps_scale_to_ends() {
        let mut d = Image::new(3, 1);
        d.rgb = vec![-3.0, -3.0, -3.0, 0.0, 0.0, 0.0, 1.0, 2.0, 3.0];
        let (panel, scale) = derivative_panel(&d);
        assert_eq!(scale, 3.0);
        let srgb = |i: usize| -> [f32; 3] {
            std::array::from_fn(|c| super::super::srgb_encode(panel.rgb[3 * i + c]))
        };
        let close = |a: [f32; 3], b: [f32; 3]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-4);
        assert!(close(srgb(0), diverging(-1.0)));
        assert!(close(srgb(1), [1.0; 3]));
        assert!(close(srgb(2), diverging(2.0 / 3.0)));
    }

    #[test]
    fn panels_side_by_side() {
        let mut a = Image::new(2, 2);
        a.rgb.fill(1.0);
        let b = Image::new(3, 1);
        let out = side_by_side(&[a, b]);
        assert_eq!((out.width, out.height), (2 + PANEL_GAP + 3, 2));
        assert_eq!(out.pixel(1, 1), [1.0; 3]);
        assert_eq!(out.pixel(2, 0), [GAP_COLOUR; 3]);
        assert_eq!(out.pixel(2 + PANEL_GAP, 0), [0.0; 3]);
        assert_eq!(out.pixel(2 + PANEL_GAP, 1), [GAP_COLOUR; 3]);
    }
}
