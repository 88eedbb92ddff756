use crate::scalar::Scalar;

/// Pixel reconstruction filter, centred on the pixel centre, in pixel units. Each is normalised
/// (integrates to 1) and sampled exactly, so a sample's filter weight divided by its density is 1.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Default)]
pub enum Filter {
    /// Box of half-width 0.5 (discontinuous: derivatives through it need pixel-edge terms).
    Box,
    /// Tent of radius 1 pixel (the default).
    #[default]
    Tent,
    /// Gaussian, σ = 0.5 pixel, truncated at radius 1.5 and renormalised.
    Gaussian,
}

impl Filter {
    /// Support half-width in pixels.
    pub fn radius(&self) -> f32 {
        todo!("filter: radius")
    }
    /// A film offset from the pixel centre, distributed exactly as the filter, from `u ∈ [0,1)²`.
    pub fn sample(&self, u: glam::Vec2) -> glam::Vec2 {
        let _ = u;
        todo!("filter: sample")
    }
    /// Filter value at offset `(dx, dy)` from the pixel centre (generic: the offset may move).
    pub fn eval<S: Scalar>(&self, dx: S, dy: S) -> S {
        let _ = (dx, dy);
        todo!("filter: eval")
    }
}
