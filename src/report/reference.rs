//! The images every run is measured against, and how far they themselves can be trusted.
//!
//! - **Derivatives, computed:** central differences ([`crate::integrator::fd`]) with half `fd`'s
//!   default step, at `spp` samples per pixel split into two halves with seeds no run uses; the
//!   reference is the mean of the halves. Its **noise** is their seed-to-seed difference
//!   ([`seed_noise`]) divided by √2 (the mean of two halves has half the variance of one). Its
//!   **truncation** (the `O(h²)` bias of central differences) is estimated from the first half and
//!   the same samples at the full step `h`: the errors are `c·h²` and `c·h²/4`, so their difference is
//!   three times the error of the half step. That difference also holds what common random numbers do
//!   not cancel, so the estimate is an upper bound. The **floor** is `√(noise² + truncation²)`: no
//!   error below it can be resolved.
//! - **Derivatives, given:** the channels `d.P.R`, `d.P.G`, `d.P.B` of the user's EXR; its floor is
//!   unknown.
//! - **The image:** always a long render (two halves, as above; no truncation), even when an EXR is
//!   given: the `R`, `G`, `B` of a derivative command's EXR were rendered at that command's spp, which
//!   says nothing about their accuracy.

use super::measure::{blurred_error, seed_noise};
use super::subject::Subject;
use crate::error::{Error, Result};
use crate::film::{Image, read_exr, rgb_from_channels};
use std::path::Path;
use std::time::Instant;

/// Seeds of the two halves of a computed reference: apart from the runs' seeds (small numbers).
pub const REFERENCE_SEEDS: [u64; 2] = [0x5EF0_0000_0001, 0x5EF0_0000_0002];

/// An image to measure against, and what is known of its own error.
#[derive(Clone, Debug)]
pub struct Reference {
    /// The reference image (derivative or image).
    pub image: Image,
    /// Samples per pixel of the whole reference (both halves); 0 for an EXR.
    pub spp: u32,
    /// The finite-difference step of a computed derivative reference.
    pub step: Option<f32>,
    /// The reference's own noise, relative and blurred like the errors; `None` for an EXR.
    pub noise: Option<f64>,
    /// The estimated truncation error of the finite differences, relative and blurred.
    pub truncation: Option<f64>,
    /// Wall time spent computing it, in seconds.
    pub seconds: f64,
}

impl Reference {
    /// `√(noise² + truncation²)`: the error below which the report cannot tell estimators apart;
    /// `None` when unknown (an EXR reference).
    pub fn floor(&self) -> Option<f64> {
        let noise = self.noise?;
        let t = self.truncation.unwrap_or(0.0);
        Some((noise * noise + t * t).sqrt())
    }

    /// A reference read from an EXR, without an estimate of its error.
    pub fn given(image: Image) -> Self {
        Self {
            image,
            spp: 0,
            step: None,
            noise: None,
            truncation: None,
            seconds: 0.0,
        }
    }

    /// The reference of `subject` at `spp` samples per pixel (two halves): central differences with
    /// half `fd`'s step for a parameter, a render for the image. Errors: those of the integrators.
    pub fn compute(subject: &Subject, spp: u32) -> Result<Self> {
        let start = Instant::now();
        let half = (spp / 2).max(1);
        let [a, b] = REFERENCE_SEEDS;
        let (first, second, step) = match subject.parameter() {
            Some(_) => {
                let h = subject.step() / 2.0;
                let first = subject.finite_difference(h, half, a)?;
                (first, subject.finite_difference(h, half, b)?, Some(h))
            }
            None => {
                let run = |seed| subject.run(super::Estimator::Primal, half, seed);
                (run(a)?, run(b)?, None)
            }
        };
        let mut image = first.clone();
        for (m, x) in image.rgb.iter_mut().zip(&second.rgb) {
            *m = 0.5 * (*m + x);
        }
        let noise = seed_noise(&first, &second, &image) / std::f64::consts::SQRT_2;
        let truncation = match step {
            Some(h) => {
                let full = subject.finite_difference(2.0 * h, half, a)?;
                Some(blurred_error(&full, &first) / 3.0)
            }
            None => None,
        };
        Ok(Self {
            image,
            spp: 2 * half,
            step,
            noise: Some(noise),
            truncation,
            seconds: start.elapsed().as_secs_f64(),
        })
    }
}

/// The derivative images `d.P.R|G|B` of every parameter of `parameters` in the EXR at `path`, which
/// must be `width × height`. Errors (one line, naming the file and what is wrong): an unreadable file,
/// another size, a missing channel (with the derivative channels the file has), a non-finite value.
pub fn read_reference(
    path: &Path,
    parameters: &[String],
    (width, height): (u32, u32),
) -> Result<Vec<Image>> {
    let (w, h, channels) = read_exr(path)?;
    if (w, h) != (width, height) {
        return Err(Error::file(
            path,
            format!("is {w}x{h}, the scene renders {width}x{height}"),
        ));
    }
    let mut images = Vec::new();
    for p in parameters {
        let image = rgb_from_channels(path, (w, h), &channels, &format!("d.{p}."), |name| {
            let derivatives: Vec<&str> = (channels.iter().map(|(n, _)| n.as_str()))
                .filter(|n| n.starts_with("d."))
                .collect();
            let has = if derivatives.is_empty() {
                "no derivative channels".to_string()
            } else {
                format!("derivative channels: {}", derivatives.join(", "))
            };
            format!("no channel {name} for parameter {p} ({has})")
        })?;
        images.push(image);
    }
    Ok(images)
}
