//! Pictures meant to be read: the derivative commands' panels with a title (the parameter) above each
//! and a colour bar with its scale below, and titled columns (`views.png`).
//!
//! Small images are magnified by an integer factor (nearest neighbour, so a pixel stays a visible
//! square) until a panel is [`MIN_PANEL_WIDTH`] pixels wide: a 16-pixel test render would otherwise
//! leave no room for a title or the scale's numbers. The text is set in DejaVu Sans, shipped reduced
//! to ASCII in `assets/fonts/` (its licence is beside it), so pictures do not depend on the machine's
//! fonts.

use super::Image;
use super::colormap::{self, GAP_COLOUR, PANEL_GAP};
use crate::error::{Error, Result};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// The font of every picture's text (DejaVu Sans, ASCII subset).
pub const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans-subset.ttf");
/// Panels narrower than this many pixels are magnified by an integer factor.
pub const MIN_PANEL_WIDTH: u32 = 192;
/// Height of the title strip above each panel, pixels.
pub const TITLE_HEIGHT: u32 = 22;
/// Height of the colour-bar strip below each panel, pixels.
pub const BAR_HEIGHT: u32 = 34;
/// Size of the text, pixels.
const TEXT_SIZE: f64 = 13.0;

/// Registers [`FONT`] as plotters' `sans-serif` once per process.
pub fn register_font() -> Result<()> {
    static RESULT: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *RESULT.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(Error::Unsupported(
            "the pictures' font does not load".into(),
        ))
    }
}

/// The integer magnification that makes a panel `width` pixels wide at least [`MIN_PANEL_WIDTH`].
pub fn magnification(width: u32) -> u32 {
    MIN_PANEL_WIDTH.div_ceil(width.max(1)).max(1)
}

/// `image` magnified `k` times by repeating pixels.
pub fn magnify(image: &Image, k: u32) -> Image {
    if k == 1 {
        return image.clone();
    }
    let mut out = Image::new(image.width * k, image.height * k);
    for y in 0..out.height {
        for x in 0..out.width {
            let p = image.pixel(x / k, y / k);
            let i = 3 * (y * out.width + x) as usize;
            out.rgb[i..i + 3].copy_from_slice(&p);
        }
    }
    out
}

/// A column of a figure ([`compose`]): a panel under its title, with an optional colour bar below it.
#[derive(Clone, Debug)]
pub struct Column {
    /// The text above the panel (shortened from the left if it does not fit).
    pub title: String,
    /// The panel, linear RGB.
    pub panel: Image,
    /// The colour bar's scale: the panel maps `[-scale, scale]` onto [`colormap::diverging`]; `None`
    /// for a panel without a bar (an image).
    pub scale: Option<f32>,
}

/// The picture of a derivative command: the image beside one colour-mapped panel per derivative
/// ([`colormap::derivative_panel`]), each under its title (`"image"`, then the parameter's name) and each
/// derivative above a colour bar labelled with its scale. Returns the picture and the scales.
pub fn derivative_figure(
    image: &Image,
    params: &[String],
    derivatives: &[&Image],
) -> Result<(Image, Vec<f32>)> {
    let k = magnification(image.width);
    let mut columns = vec![Column {
        title: "image".into(),
        panel: magnify(image, k),
        scale: None,
    }];
    let mut scales = Vec::new();
    for (param, d) in params.iter().zip(derivatives) {
        let (panel, scale) = colormap::derivative_panel(d);
        columns.push(Column {
            title: format!("d/d {param}"),
            panel: magnify(&panel, k),
            scale: Some(scale),
        });
        scales.push(scale);
    }
    Ok((compose(&columns, true)?, scales))
}

/// Images of one size side by side, each under its title, [`PANEL_GAP`] pixels apart.
pub fn titled_columns(titles: &[String], images: &[Image]) -> Result<Image> {
    let columns: Vec<Column> = (titles.iter().zip(images))
        .map(|(title, panel)| Column {
            title: title.clone(),
            panel: panel.clone(),
            scale: None,
        })
        .collect();
    compose(&columns, false)
}

/// The columns laid out left to right, [`PANEL_GAP`] pixels apart, each under a [`TITLE_HEIGHT`]
/// strip with its title; below them a [`BAR_HEIGHT`] strip when `bars`, holding the colour bar of
/// each column that has a scale. Panels of different heights are padded below with grey.
pub fn compose(columns: &[Column], bars: bool) -> Result<Image> {
    register_font()?;
    let panels: Vec<Image> = columns.iter().map(|c| c.panel.clone()).collect();
    let row = colormap::side_by_side(&panels);
    let below = if bars { BAR_HEIGHT } else { 0 };
    let (w, h) = (row.width, TITLE_HEIGHT + row.height + below);
    // The strips are white, the gaps between columns grey, as between panels.
    let mut canvas = Image::new(w, h);
    canvas.rgb.fill(1.0);
    let mut x0 = 0;
    for (i, column) in columns.iter().enumerate() {
        if i > 0 {
            fill(&mut canvas, x0 - PANEL_GAP, 0, PANEL_GAP, h, GAP_COLOUR);
        }
        x0 += column.panel.width + PANEL_GAP;
    }
    for y in 0..row.height {
        let n = 3 * w as usize;
        let start = n * (TITLE_HEIGHT + y) as usize;
        canvas.rgb[start..start + n]
            .copy_from_slice(&row.rgb[n * y as usize..n * (y + 1) as usize]);
    }
    let mut bytes: Vec<u8> = (canvas.rgb.iter())
        .map(|&v| (crate::io::srgb_encode(v) * 255.0 + 0.5) as u8)
        .collect();
    draw_text(&mut bytes, (w, h), columns, row.height)
        .map_err(|e| Error::Unsupported(format!("cannot draw the picture's text: {e}")))?;
    Ok(from_srgb_bytes(w, h, &bytes))
}

/// The titles, colour bars and their numbers, drawn into the sRGB bytes of the canvas.
fn draw_text(
    bytes: &mut [u8],
    size: (u32, u32),
    columns: &[Column],
    panel_height: u32,
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    let root = BitMapBackend::with_buffer(bytes, size).into_drawing_area();
    let font = ("sans-serif", TEXT_SIZE).into_font();
    let mut x0 = 0i32;
    for column in columns {
        let width = column.panel.width as i32;
        let centre = Pos::new(HPos::Center, VPos::Center);
        let title = fit(&root, &column.title, width - 6)?;
        let style = font.clone().color(&BLACK).pos(centre);
        root.draw_text(&title, &style, (x0 + width / 2, TITLE_HEIGHT as i32 / 2))?;
        if let Some(scale) = column.scale {
            let top = (TITLE_HEIGHT + panel_height) as i32;
            let (left, right) = (x0 + 6, x0 + width - 6);
            for x in left..=right {
                let t = 2.0 * (x - left) as f32 / (right - left).max(1) as f32 - 1.0;
                let [r, g, b] = colormap::diverging(t).map(|c| (c * 255.0 + 0.5) as u8);
                root.draw(&PathElement::new(
                    [(x, top + 5), (x, top + 14)],
                    RGBColor(r, g, b),
                ))?;
            }
            let frame = [(left, top + 5), (right, top + 14)];
            root.draw(&Rectangle::new(frame, BLACK))?;
            let y = top + 24;
            let label = scale_label;
            let at = |h: HPos| font.clone().color(&BLACK).pos(Pos::new(h, VPos::Center));
            root.draw_text(&format!("-{}", label(scale)), &at(HPos::Left), (left, y))?;
            root.draw_text("0", &at(HPos::Center), (x0 + width / 2, y))?;
            root.draw_text(&format!("+{}", label(scale)), &at(HPos::Right), (right, y))?;
        }
        x0 += width + PANEL_GAP as i32;
    }
    root.present()?;
    Ok(())
}

/// A colour scale's number, three significant digits: plain between 0.01 and 10,000, else
/// scientific (`2.43`, `0.0512`, `1.20e-4`).
pub fn scale_label(s: f32) -> String {
    if (0.01..10_000.0).contains(&s) {
        let digits = (2 - s.log10().floor() as i32).max(0) as usize;
        format!("{s:.digits$}")
    } else {
        format!("{s:.2e}")
    }
}

/// `text`, shortened from the left with `...` until it is at most `width` pixels wide.
fn fit<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    text: &str,
    width: i32,
) -> std::result::Result<String, Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let font = ("sans-serif", TEXT_SIZE).into_font();
    let fits = |s: &str| -> std::result::Result<bool, Box<dyn std::error::Error>> {
        let (w, _) = root.estimate_text_size(s, &TextStyle::from(font.clone()))?;
        Ok(w as i32 <= width)
    };
    if fits(text)? {
        return Ok(text.to_string());
    }
    let chars: Vec<char> = text.chars().collect();
    for skip in 1..chars.len() {
        let shorter = format!("...{}", chars[skip..].iter().collect::<String>());
        if fits(&shorter)? {
            return Ok(shorter);
        }
    }
    Ok(String::new())
}

/// `(w, h, bytes)` of an 8-bit sRGB buffer as a linear image (the inverse of the PNG encoding).
pub fn from_srgb_bytes(w: u32, h: u32, bytes: &[u8]) -> Image {
    let mut image = Image::new(w, h);
    for (v, b) in image.rgb.iter_mut().zip(bytes) {
        *v = colormap::srgb_decode(*b as f32 / 255.0);
    }
    image
}

/// Fills a rectangle of `image` with the grey `value`.
fn fill(image: &mut Image, x0: u32, y0: u32, w: u32, h: u32, value: f32) {
    for y in y0..(y0 + h).min(image.height) {
        for x in x0..(x0 + w).min(image.width) {
            let i = 3 * (y * image.width + x) as usize;
            image.rgb[i..i + 3].fill(value);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_panels_are_magnified_to_the_minimum_width() {
        assert_eq!(magnification(16), 12);
        assert_eq!(magnification(MIN_PANEL_WIDTH), 1);
        assert_eq!(magnification(1000), 1);
        let mut image = Image::new(2, 1);
        image.rgb = vec![0.1, 0.2, 0.3, 0.4, 0.5, 0.6];
        let big = magnify(&image, 3);
        assert_eq!((big.width, big.height), (6, 3));
        assert_eq!(big.pixel(2, 2), [0.1, 0.2, 0.3]);
        assert_eq!(big.pixel(3, 0), [0.4, 0.5, 0.6]);
    }

    #[test]
    fn derivative_figure_layout_and_bar() {
        let image = Image::new(200, 100);
        let mut d = Image::new(200, 100);
        d.rgb
            .iter_mut()
            .enumerate()
            .for_each(|(i, v)| *v = i as f32);
        let params = vec!["ball.radius".to_string()];
        let (picture, scales) = derivative_figure(&image, &params, &[&d]).unwrap();
        assert_eq!(scales.len(), 1);
        let w = 2 * 200 + PANEL_GAP;
        assert_eq!(
            (picture.width, picture.height),
            (w, TITLE_HEIGHT + 100 + BAR_HEIGHT)
        );
        // The bar runs blue to red across the derivative's column, white in its middle.
        let y = TITLE_HEIGHT + 100 + 9;
        let x0 = 200 + PANEL_GAP;
        let srgb = |x: u32| picture.pixel(x, y).map(crate::io::srgb_encode);
        let (left, mid, right) = (srgb(x0 + 8), srgb(x0 + 100), srgb(x0 + 192));
        assert!(left[2] > left[0] + 0.3, "{left:?}");
        assert!(right[0] > right[2] + 0.3, "{right:?}");
        assert!(mid.iter().all(|c| *c > 0.95), "{mid:?}");
        // Text is drawn: the title strip holds dark pixels over the derivative's column only where
        // the title is, and some over the image's.
        let dark = |x0: u32, x1: u32| {
            (0..TITLE_HEIGHT)
                .flat_map(|y| (x0..x1).map(move |x| (x, y)))
                .filter(|&(x, y)| picture.pixel(x, y)[1] < 0.2)
                .count()
        };
        assert!(dark(0, 200) > 10);
        assert!(dark(x0, x0 + 200) > 10);
    }

    #[test]
    fn scale_labels_have_three_significant_digits() {
        assert_eq!(scale_label(2.4309), "2.43");
        assert_eq!(scale_label(0.05123), "0.0512");
        assert_eq!(scale_label(123.4), "123");
        assert_eq!(scale_label(1.2e-4), "1.20e-4");
        assert_eq!(scale_label(3.0e6), "3.00e6");
    }

    #[test]
    fn long_titles_are_shortened_to_fit() {
        let image = Image::new(16, 16);
        let d = Image::new(16, 16);
        let long = vec!["a.very.long.parameter.name.that.cannot.fit.in.the.panel".to_string()];
        let (picture, _) = derivative_figure(&image, &long, &[&d]).unwrap();
        assert_eq!(picture.width, 2 * 16 * 12 + PANEL_GAP);
        // Nothing is drawn into the gap between the columns.
        for y in 0..TITLE_HEIGHT {
            let p = picture.pixel(16 * 12 + 1, y);
            assert!(p.iter().all(|c| (c - GAP_COLOUR).abs() < 0.01), "{p:?}");
        }
    }
}
