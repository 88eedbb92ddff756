//! Which light-transport estimator a scene asks for.

/// Which estimator renders the image.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum IntegratorKind {
    /// Emission seen directly plus next-event estimation at the first hit, combined with BSDF sampling
    /// by multiple importance sampling.
    Direct,
    /// Path tracing with next-event estimation and MIS, up to `max_depth` bounces.
    Path {
        /// Longest path in segments after the camera (1 = direct lighting only).
        ///
        /// Counted as scattering vertices: `max_depth = d` scatters at `x1 … xd`, each with a light
        /// sample and a BSDF sample, so `1` is exactly [`IntegratorKind::Direct`] and `0` shows emitters
        /// only. No Russian roulette: the estimate of the `d`-bounce truncation is unbiased.
        max_depth: u32,
    },
}

impl IntegratorKind {
    /// Number of scattering vertices of the longest path.
    pub fn max_scatter(&self) -> u32 {
        match self {
            IntegratorKind::Direct => 1,
            IntegratorKind::Path { max_depth } => *max_depth,
        }
    }
}
