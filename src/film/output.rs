use crate::error::{Error, Result};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// A fresh temporary path in the directory of `path` (a rename within one directory is atomic on POSIX
/// file systems, so readers never see a partial file).
fn temporary_path(path: &Path) -> PathBuf {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let unique = COUNTER.fetch_add(1, Ordering::Relaxed);
    path.with_file_name(format!(".{name}.{}.{unique}.tmp", std::process::id()))
}

/// Runs `write` on a temporary file next to `path`, then renames it to `path`; removes the temporary file
/// if anything fails.
fn write_atomically(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let tmp = temporary_path(path);
    let result =
        write(&tmp).and_then(|()| std::fs::rename(&tmp, path).map_err(|e| Error::file(path, e)));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Named float32 planes, each `width · height` values row-major from the top.
pub type Channels = Vec<(String, Vec<f32>)>;

/// Writes float32 channels (each `width · height` values, row-major from the top) to an EXR file.
/// Written to a temporary file and renamed, so a failure leaves no partial file.
///
/// Channel names are free-form ASCII/Latin-1 (`R`, `G`, `B`, `d.ball.radius.R`, ...); the file stores
/// them sorted by name, as the format requires. Compression: lossless ZIP.
pub fn write_exr(
    path: &Path,
    width: u32,
    height: u32,
    channels: &[(String, Vec<f32>)],
) -> crate::Result<()> {
    use exr::prelude::*;
    let n = width as usize * height as usize;
    if n == 0 {
        return Err(crate::Error::file(
            path,
            format!("empty image {width}x{height}"),
        ));
    }
    if channels.is_empty() {
        return Err(crate::Error::file(path, "no channels to write"));
    }
    let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for (name, values) in channels {
        if values.len() != n {
            return Err(crate::Error::file(
                path,
                format!(
                    "channel {name:?} has {} values, expected {width}x{height} = {n}",
                    values.len()
                ),
            ));
        }
        let text = Text::new_or_none(name).ok_or_else(|| {
            crate::Error::file(path, format!("channel name {name:?} is not Latin-1"))
        })?;
        list.push(AnyChannel::new(text, FlatSamples::F32(values.clone())));
    }
    let image = Image::from_encoded_channels(
        (width as usize, height as usize),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list),
    );
    write_atomically(path, |tmp| {
        image
            .write()
            .to_file(tmp)
            .map_err(|e| crate::Error::file(path, e))
    })
}

/// Reads every channel of the first valid layer of an EXR file as `f32` (row-major from the top), with
/// the image size: `(width, height, [(name, values)])`, channels in the file's (sorted) order.
pub fn read_exr(path: &Path) -> crate::Result<(u32, u32, Channels)> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| crate::Error::file(path, e))?;
    let layer = &image.layer_data;
    let (w, h) = (layer.size.width(), layer.size.height());
    let channels = layer
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect();
    Ok((w as u32, h as u32, channels))
}

/// The image in the `R`, `G`, `B` channels of an EXR file (e.g. a target image). Errors: an unreadable
/// file, a missing channel (the message lists the file's channels), a non-finite value.
pub fn read_exr_rgb(path: &Path) -> crate::Result<super::Image> {
    let (width, height, channels) = read_exr(path)?;
    rgb_from_channels(path, (width, height), &channels, "", |name| {
        let names: Vec<&str> = channels.iter().map(|(n, _)| n.as_str()).collect();
        format!("no channel {name} (channels: {})", names.join(", "))
    })
}

/// The image in the channels `{prefix}R`, `{prefix}G`, `{prefix}B` of an EXR read with [`read_exr`]
/// (`width × height` planes). Errors name `path`: a missing channel (worded by `missing`, given the
/// channel's name), a non-finite value.
pub fn rgb_from_channels(
    path: &Path,
    (width, height): (u32, u32),
    channels: &[(String, Vec<f32>)],
    prefix: &str,
    missing: impl Fn(&str) -> String,
) -> crate::Result<super::Image> {
    let mut image = super::Image::new(width, height);
    for (c, suffix) in ["R", "G", "B"].iter().enumerate() {
        let name = format!("{prefix}{suffix}");
        let Some((_, plane)) = channels.iter().find(|(n, _)| *n == name) else {
            return Err(Error::file(path, missing(&name)));
        };
        if let Some(i) = plane.iter().position(|v| !v.is_finite()) {
            return Err(Error::file(
                path,
                format!(
                    "non-finite value {} in channel {name} at pixel {i}",
                    plane[i]
                ),
            ));
        }
        for (px, v) in image.rgb.chunks_exact_mut(3).zip(plane) {
            px[c] = *v;
        }
    }
    Ok(image)
}

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

/// Checks, before anything is rendered, that `path` can be an output file: its folder exists, it is
/// not a folder, and it ends in `.extension` (case-insensitive). `what` names it in the error
/// (e.g. `--out`).
pub fn check_output_path(path: &Path, what: &str, extension: &str) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let problem = if !dir.is_dir() {
        format!("folder {} does not exist", dir.display())
    } else if path.is_dir() {
        "is a folder".to_string()
    } else if !path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case(extension))
    {
        format!("must end in .{extension}")
    } else {
        return Ok(());
    };
    Err(Error::Unsupported(format!(
        "{what} {}: {problem}",
        path.display()
    )))
}

/// Writes `channels` (planes of `width × height`) to the EXR `exr`, then `picture` to the PNG `png`;
/// removes the EXR if the PNG fails, so the pair is written all or nothing.
pub fn write_exr_and_png(
    exr: &Path,
    png: &Path,
    (width, height): (u32, u32),
    channels: &Channels,
    picture: &super::Image,
) -> Result<()> {
    write_exr(exr, width, height, channels)?;
    if let Err(e) = write_png(png, picture.width, picture.height, &picture.rgb) {
        let _ = std::fs::remove_file(exr);
        return Err(e);
    }
    Ok(())
}
