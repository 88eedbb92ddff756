//! Speed against error of derivative estimators (and of the primal image): the error measures shared
//! by the `report` protocol and `benches/complete.rs`.

pub mod estimator;
pub mod measure;

pub use estimator::Estimator;
pub use measure::{bias_floor, blurred_error, raw_error, seed_noise};
