//! Arguments in Python's words: counts and seeds checked with the argument's name (`spp=-1` raises
//! `ValueError: spp: must be >= 1, got -1`, not an `OverflowError` of the conversion), and names
//! given as one string or a list of them.

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyString;

/// An optional count argument `name` of at least `least` (`spp` 1, a boundary budget 0).
pub(crate) fn count(name: &str, value: Option<i64>, least: u32) -> PyResult<Option<u32>> {
    let Some(v) = value else { return Ok(None) };
    match u32::try_from(v) {
        Ok(n) if n >= least => Ok(Some(n)),
        _ if v < i64::from(least) => Err(PyValueError::new_err(format!(
            "{name}: must be >= {least}, got {v}"
        ))),
        _ => Err(PyValueError::new_err(format!(
            "{name}: must be at most {}, got {v}",
            u32::MAX
        ))),
    }
}

/// An optional rate argument `name` (a boundary budget in samples per pixel): a finite number ≥ 0.
pub(crate) fn rate(name: &str, value: Option<f64>) -> PyResult<Option<f32>> {
    match value {
        None => Ok(None),
        Some(v) if v.is_finite() && v >= 0.0 && v <= f32::MAX as f64 => Ok(Some(v as f32)),
        Some(v) => Err(PyValueError::new_err(format!(
            "{name}: must be a finite number >= 0, got {v}"
        ))),
    }
}

/// The `seed` argument: an integer in `[0, 2⁶⁴)`.
pub(crate) fn seed(value: i128) -> PyResult<u64> {
    u64::try_from(value)
        .map_err(|_| PyValueError::new_err(format!("seed: must be in [0, 2**64), got {value}")))
}

/// The `threads` argument: a count of at least 1, or `None` (every core).
pub(crate) fn threads(value: Option<i64>) -> PyResult<Option<usize>> {
    Ok(count("threads", value, 1)?.map(|n| n as usize))
}

/// A names argument `name` (`params`, `grids`): one string, or an iterable of strings, or `None`
/// (none).
pub(crate) fn names(name: &str, value: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<String>> {
    let Some(value) = value else {
        return Ok(Vec::new());
    };
    if let Ok(one) = value.cast::<PyString>() {
        return Ok(vec![one.to_string()]);
    }
    let wrong = || {
        PyTypeError::new_err(format!(
            "{name}: expected a name or a list of names (str), got {}",
            value
                .get_type()
                .name()
                .map_or("?".into(), |n| n.to_string())
        ))
    };
    let mut out = Vec::new();
    for item in value.try_iter().map_err(|_| wrong())? {
        let item = item?;
        match item.cast::<PyString>() {
            Ok(s) => out.push(s.to_string()),
            Err(_) => return Err(wrong()),
        }
    }
    Ok(out)
}
