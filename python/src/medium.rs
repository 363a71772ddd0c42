//! `murk.estimate_medium`: `murk_medium::estimate`, the call behind `murk medium`.

use crate::capture::Source;
use crate::compute;
use murk_medium::{EstimateOptions, FitParams, Fixed};
use pyo3::prelude::*;

/// The keywords of `murk.estimate_medium` that are `murk medium`'s flags (the capture, threads and
/// progress aside).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct MediumArgs {
    /// The parameters to fit, comma-separated.
    fit: String,
    mu_t: f64,
    albedo: f64,
    g: f64,
    until: Option<f64>,
}

impl MediumArgs {
    /// The library's options, as `murk medium` builds them from its flags.
    fn options(&self) -> murk_core::Result<EstimateOptions> {
        Ok(EstimateOptions {
            fit: FitParams::parse(&self.fit)?,
            fixed: Fixed {
                mu_t_per_m: self.mu_t,
                albedo: self.albedo,
                g: self.g,
            },
            until_m: self.until,
            ..EstimateOptions::default()
        })
    }
}

/// Estimates the medium; returns the JSON object `murk medium --json` prints.
#[pyfunction]
pub fn estimate_medium<'py>(
    py: Python<'py>,
    capture: &Bound<'py, PyAny>,
    args: MediumArgs,
    threads: Option<i64>,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<String> {
    let source = Source::of(capture)?;
    compute(py, progress, threads, |t| {
        let cap = source.owned()?;
        let opt = args.options()?;
        let outcome = murk_medium::estimate(&cap, &opt, &|done, total| {
            t.count(done as u64, total as u64)
        })?;
        Ok(outcome.to_json())
    })
}
