//! Speed against error of the derivative estimators (and of the primal image), for any scene and
//! parameter: the library behind the `report` command and `benches/complete.rs`.
//!
//! ## Protocol
//!
//! [`plan`] checks the parameters and estimators and shares the budget; [`run`] measures. Every
//! applicable `(parameter, estimator)` pair is one *series*, and so is the image (`primal`, which does
//! not depend on a parameter): the budget (default [`DEFAULT_BUDGET`], seconds of runs in all) is
//! split evenly between the series, so each gets `budget / series`. A series runs at spp 1, 2, 4, …
//! with the two seeds [`RUN_SEEDS`] per point until its run time passes its share (the last point
//! may take as long as all before it, so a report takes up to about twice its budget, plus the
//! references). Each run is measured against the section's [`Reference`] ([`mod@reference`] says how it
//! is made and what its floor is) with the measures of [`measure`].
//!
//! ## `report.csv`
//!
//! One row per run, columns [`summary::CSV_COLUMNS`]:
//!
//! | column | meaning |
//! |---|---|
//! | `parameter` | the parameter, or `image` for `primal` (parameter names hold a dot, so never clash) |
//! | `estimator` | [`Estimator::name`] |
//! | `spp` | samples per pixel (1, 2, 4, …) |
//! | `seed` | the sampler's seed ([`RUN_SEEDS`]) |
//! | `seconds` | wall time of the run |
//! | `raw_error` | relative L2 error against the reference over R, G, B, per pixel |
//! | `blurred_error` | the same after a 5×5 box blur of both |
//! | `noise` | one run's noise at this spp, from the two seeds' difference (blurred) |
//! | `bias_floor` | `√max(blurred_error² − noise², 0)` |
//! | `reference_noise` | the reference's own noise (blurred, relative); empty for a given EXR |
//! | `reference_floor` | the reference's floor: noise and `fd` truncation in quadrature; empty if unknown |

pub mod estimator;
pub mod measure;
pub mod plot;
pub mod protocol;
pub mod reference;
pub mod subject;
pub mod summary;

pub use estimator::Estimator;
pub use measure::{bias_floor, blurred_error, raw_error, seed_noise};
pub use protocol::{
    DEFAULT_BUDGET, Plan, RUN_SEEDS, Report, Run, Section, Skip, Status, plan, run,
};
pub use reference::{Reference, read_reference};
pub use subject::Subject;
