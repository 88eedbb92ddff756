//! Central finite differences with common random numbers: the reference every derivative is checked
//! against.

use super::RenderOptions;
use crate::error::{Error, Result};
use crate::film::{Channels, Image};
use crate::integrator::driver::RenderStats;
use crate::scene::Scene;

/// Relative step of [`default_step`].
pub const RELATIVE_STEP: f32 = 1e-2;

/// The default finite-difference step for a parameter of value `value`: `1e-2 · max(|value|, 1)`.
///
/// Relative to the value for large values (a radiance of 40, a camera 4 units away), and absolute (0.01)
/// for values near zero (positions at the origin, translations), where a relative step would vanish. The
/// central difference's truncation error is `O(h²)`; in `f32`, a smaller `h` makes the rounding noise
/// `ε · I / h` of the two images dominate.
pub fn default_step(value: f32) -> f32 {
    RELATIVE_STEP * value.abs().max(1.0)
}

/// The current value of parameter `name`. Errors: an unknown name (the registry's message, with near
/// matches).
pub fn parameter_value(scene: &Scene, name: &str) -> Result<f32> {
    match scene.parameters().into_iter().find(|(n, _)| n == name) {
        Some((_, value)) => Ok(value),
        // The registry's own message lists the near matches.
        None => Err(scene
            .with_parameter(name, 0.0)
            .err()
            .unwrap_or_else(|| Error::Unsupported(format!("unknown parameter {name:?}")))),
    }
}

/// `(I(π + h) − I(π − h)) / 2h` for parameter `name`, both renders with the same seed and samples.
///
/// Common random numbers: both renders use `options` unchanged, so every pixel sample draws the same
/// random numbers at `π ± h`, and the difference holds only the change of the integrand (plus the
/// discontinuities its paths cross). The divisor is the difference of the two values as rounded in `f32`,
/// `(π + h) − (π − h)`, not `2h`, so that rounding of the parameter itself costs no accuracy.
///
/// Errors (before anything is rendered): `h` not finite and positive; an unknown parameter (with near
/// matches); a value `π ± h` the parameter does not accept (e.g. a radius `≤ 0`; the error names the
/// parameter, the step and both values); `h` too small to change the parameter in `f32`.
pub fn finite_difference(
    scene: &Scene,
    name: &str,
    h: f32,
    options: &RenderOptions,
) -> Result<Image> {
    Ok(difference(scene, name, h, options)?.0)
}

/// [`finite_difference`] and the counters of its two renders.
fn difference(
    scene: &Scene,
    name: &str,
    h: f32,
    options: &RenderOptions,
) -> Result<(Image, RenderStats)> {
    let pair = Pair::new(scene, name, h)?;
    Ok(pair.render(options))
}

/// The two scenes of a central difference, checked: `π + h` and `π − h`, and their difference in
/// `f32`.
struct Pair {
    plus: Scene,
    minus: Scene,
    step: f32,
}

impl Pair {
    /// Errors: those of [`finite_difference`].
    fn new(scene: &Scene, name: &str, h: f32) -> Result<Self> {
        if !(h.is_finite() && h > 0.0) {
            return Err(Error::Unsupported(format!(
                "finite-difference step must be a positive number, got {h}"
            )));
        }
        let value = parameter_value(scene, name)?;
        let (high, low) = (value + h, value - h);
        let step = high - low;
        if !(step.is_finite() && step > 0.0) {
            return Err(Error::Unsupported(format!(
                "finite-difference step {h} does not change {name} = {value} in f32"
            )));
        }
        let with_step = |e| match e {
            Error::Field { field, message } => Error::Field {
                field,
                message: format!(
                    "{message} (the step h = {h} takes {name} = {value} to {high} and {low})"
                ),
            },
            e => e,
        };
        let plus = scene.with_parameter(name, high).map_err(with_step)?;
        let minus = scene.with_parameter(name, low).map_err(with_step)?;
        Ok(Self { plus, minus, step })
    }

    /// The central difference and the counters of its two renders.
    fn render(&self, options: &RenderOptions) -> (Image, RenderStats) {
        let (image_plus, mut stats) = super::render(&self.plus, options);
        let (image_minus, stats_minus) = super::render(&self.minus, options);
        stats.absorb(stats_minus);
        let mut derivative = image_plus;
        for (d, m) in derivative.rgb.iter_mut().zip(&image_minus.rgb) {
            *d = (*d - m) / self.step;
        }
        (derivative, stats)
    }
}

/// The image at a parameter's value and its central difference, as the `fd` command writes them.
#[derive(Clone, Debug)]
pub struct FiniteDifference {
    /// The image at the parameter's current value.
    pub image: Image,
    /// The central difference ([`finite_difference`]), per unit of the parameter.
    pub derivative: Image,
    /// The parameter's current value.
    pub value: f32,
    /// The step used.
    pub h: f32,
    /// Counters of the three renders; `seconds` is their total time.
    pub stats: RenderStats,
}

/// The image and the central difference of parameter `name` with step `h` (default [`default_step`]
/// of its value), all three renders with `options`. Errors: those of [`finite_difference`].
pub fn render_with_difference(
    scene: &Scene,
    name: &str,
    h: Option<f32>,
    options: &RenderOptions,
) -> Result<FiniteDifference> {
    let mut all = render_with_differences(scene, std::slice::from_ref(&name), h, options)?;
    let one = all.differences.pop().expect("one difference per name");
    Ok(FiniteDifference {
        image: all.image,
        derivative: one.derivative,
        value: one.value,
        h: one.h,
        stats: all.stats,
    })
}

/// The image and the central differences of several parameters, as the `fd` command writes them.
#[derive(Clone, Debug)]
pub struct FiniteDifferences {
    /// The image at the parameters' current values.
    pub image: Image,
    /// One central difference per parameter, in the order asked.
    pub differences: Vec<Difference>,
    /// Counters of every render (the image and two per parameter); `seconds` is their total time.
    pub stats: RenderStats,
}

/// The central difference of one parameter in [`FiniteDifferences`].
#[derive(Clone, Debug)]
pub struct Difference {
    /// The parameter's name.
    pub name: String,
    /// The central difference ([`finite_difference`]), per unit of the parameter.
    pub derivative: Image,
    /// The parameter's current value.
    pub value: f32,
    /// The step used.
    pub h: f32,
}

/// The image and the central difference of each parameter of `names`, each a pair of renders with
/// the image's samples (`options`), with step `h` (default [`default_step`] of each value). Every
/// name and both values of every parameter are checked before anything is rendered; errors: those
/// of [`finite_difference`].
pub fn render_with_differences(
    scene: &Scene,
    names: &[impl AsRef<str>],
    h: Option<f32>,
    options: &RenderOptions,
) -> Result<FiniteDifferences> {
    let start = std::time::Instant::now();
    let mut pairs = Vec::with_capacity(names.len());
    for name in names {
        let name = name.as_ref();
        let value = parameter_value(scene, name)?;
        let h = h.unwrap_or_else(|| default_step(value));
        pairs.push((name, value, h, Pair::new(scene, name, h)?));
    }
    let mut differences = Vec::with_capacity(pairs.len());
    let mut all = RenderStats::default();
    for (name, value, h, pair) in pairs {
        let (derivative, stats) = pair.render(options);
        all.absorb(stats);
        differences.push(Difference {
            name: name.to_string(),
            derivative,
            value,
            h,
        });
    }
    let (image, mut stats) = super::render(scene, options);
    stats.absorb(all);
    stats.seconds = start.elapsed().as_secs_f64();
    Ok(FiniteDifferences {
        image,
        differences,
        stats,
    })
}

impl FiniteDifferences {
    /// The EXR channels of the `fd` command: `R`, `G`, `B` (the image) and `d.P.R|G|B` per parameter
    /// `P`, the same names as the derivative commands'.
    pub fn channels(&self) -> Channels {
        let mut channels = self.image.rgb_channels("");
        for d in &self.differences {
            channels.extend(d.derivative.rgb_channels(&format!("d.{}.", d.name)));
        }
        channels
    }
}

impl FiniteDifference {
    /// The EXR channels of the `fd` command: `R`, `G`, `B` (the image) and `d.P.R|G|B` for parameter
    /// `P` = `name`, the same names as the derivative commands'.
    pub fn channels(&self, name: &str) -> Channels {
        let mut channels = self.image.rgb_channels("");
        channels.extend(self.derivative.rgb_channels(&format!("d.{name}.")));
        channels
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_steps() {
        let close = |a: f32, b: f32| (a - b).abs() <= 1e-6 * b;
        assert!(close(default_step(0.0), 0.01));
        assert!(close(default_step(-0.5), 0.01));
        assert!(close(default_step(40.0), 0.4));
        assert!(close(default_step(-4.0), 0.04));
    }

    /// The image of a sphere under a constant sky alone is linear and homogeneous in the sky's red
    /// radiance: `∂R/∂L_r = R / L_r`, and the green and blue channels do not depend on it at all.
    #[test]
    fn linear_parameter_matches_closed_form() {
        let json = r#"{
            "camera": {"origin": [0, 3, 4], "target": [0, 0, 0], "up": [0, 1, 0],
                       "fov_y": 45.0, "width": 8, "height": 8},
            "spp": 4,
            "shapes": [{"name": "ball", "sdf": {"type": "sphere", "center": [0, 0, 0], "radius": 1.0},
                        "bsdf": {"type": "diffuse", "albedo": [0.8, 0.6, 0.4]}}],
            "emitters": [{"name": "sky", "type": "constant", "radiance": [2, 1, 1]}]
        }"#;
        let scene = crate::scene::parse(json, std::path::Path::new(".")).unwrap();
        let options = RenderOptions {
            spp: 4,
            seed: 3,
            progress: Default::default(),
        };
        let (image, _) = super::super::render(&scene, &options);
        let h = default_step(2.0);
        let d = finite_difference(&scene, "sky.radiance.r", h, &options).unwrap();
        for (i, (&di, &v)) in d.rgb.iter().zip(&image.rgb).enumerate() {
            let expected = if i % 3 == 0 { v / 2.0 } else { 0.0 };
            assert!(
                (di - expected).abs() <= 1e-3 * expected.abs() + 1e-5,
                "value {i}: {di} vs {expected}"
            );
        }
        let error = finite_difference(&scene, "sky.radiance.q", h, &options).unwrap_err();
        assert!(error.to_string().contains("sky.radiance"), "{error}");
        assert!(finite_difference(&scene, "sky.radiance.r", -1.0, &options).is_err());
        let error = finite_difference(&scene, "ball.radius", 2.0, &options).unwrap_err();
        let expected = "the step h = 2 takes ball.radius = 1 to 3 and -1";
        assert!(error.to_string().contains(expected), "{error}");
    }
}
