//! `murk.estimate_medium`: `murk_medium::estimate`, the call behind `murk medium`.

use crate::capture::Source;
use crate::compute;
use murk_medium::{EstimateOptions, FitParams, Fixed};
use pyo3::prelude::*;

/// Estimates the medium; returns the JSON object `murk medium --json` prints.
#[pyfunction]
#[pyo3(signature = (capture, fit, mu_t, albedo, g, until, threads, progress))]
#[allow(clippy::too_many_arguments)]
pub fn estimate_medium<'py>(
    py: Python<'py>,
    capture: &Bound<'py, PyAny>,
    fit: String,
    mu_t: f64,
    albedo: f64,
    g: f64,
    until: Option<f64>,
    threads: Option<i64>,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<String> {
    let source = Source::of(capture)?;
    compute(py, progress, threads, |t| {
        let cap = source.owned()?;
        let opt = EstimateOptions {
            fit: FitParams::parse(&fit)?,
            fixed: Fixed {
                mu_t_per_m: mu_t,
                albedo,
                g,
            },
            until_m: until,
            ..EstimateOptions::default()
        };
        let outcome = murk_medium::estimate(&cap, &opt, &|done, total| {
            t.count(done as u64, total as u64)
        })?;
        Ok(outcome.to_json())
    })
}
