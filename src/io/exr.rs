//! OpenEXR files: float32 channels with free-form names (`R`, `G`, `B`, `d.ball.radius.R`, ...), written
//! whole or not at all, and read back as planes or as an image.

use super::files::write_atomically;
use crate::error::Error;
use crate::film::Image;
use std::path::Path;

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
    use ::exr::prelude::*;
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
    use ::exr::prelude::*;
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
pub fn read_exr_rgb(path: &Path) -> crate::Result<Image> {
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
) -> crate::Result<Image> {
    let mut image = Image::new(width, height);
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
