//! `murk.reconstruct`: `murk_methods::run_given`, the call behind `murk reconstruct`.

use crate::capture::Source;
use crate::compute;
use murk_baselines::{BmmParams, SlabParams};
use murk_core::{Error, Named, Result};
use murk_medium::density::{Along, DensityGiven};
use murk_medium::scene::homogeneous_assumed;
use murk_methods::{Gate, MediumGiven, Request, RequestArgs, Searched};
use murk_recon::medium::removal::Predicted;
use murk_recon::medium::MediumRemoval;
use murk_render::Spelling;
use numpy::{PyArray1, PyArrayDyn, PyArrayMethods};
use pyo3::prelude::*;
use std::path::PathBuf;

type Rows = Vec<(String, String)>;
type Axes<'py> = [Bound<'py, PyArray1<f64>>; 3];
type Array<'py> = Bound<'py, PyArrayDyn<f32>>;
/// What `reconstruct` returns: intensity, axes, rows, warnings, normals.
type Out<'py> = (Array<'py>, Axes<'py>, Rows, Vec<String>, Option<Array<'py>>);

/// The keywords of `murk.reconstruct` (its capture, threads and progress aside), which are
/// `murk reconstruct`'s flags.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct Args {
    method: String,
    volume: Option<String>,
    wavelength: Option<f64>,
    wavefactor: Option<f64>,
    cycles: f64,
    compensate: Option<String>,
    mu_t: Option<f64>,
    albedo: Option<f64>,
    falloff: String,
    lateral: String,
    gate: String,
    window_end: String,
    medium_removal: String,
    depth_search: String,
    t_offset: Option<String>,
    snr: Option<f64>,
    weighting: String,
    slab: (f64, f64, f64, f64),
    /// bmm's medium: (n, μs′, μa); unset ones come from the capture.
    medium: (Option<f64>, Option<f64>, Option<f64>),
    /// The compensation's density along each leg: a grid file or a height fog's scale.
    medium_density: Option<PathBuf>,
    height_scale: Option<f64>,
}

impl Args {
    /// The library request, as `murk reconstruct` builds it from its flags.
    fn request(&self) -> Result<Request> {
        // As the CLI's --mu-t and --albedo: read by a compensation or the model removal, else refused.
        let uncompensated = matches!(self.compensate.as_deref(), None | Some("none"));
        if uncompensated && (self.mu_t.is_some() || self.albedo.is_some()) && !self.model()? {
            return Err(Error::param(
                "mu_t and albedo are read by a compensation (paper or ballistic) or medium_removal='model' only; they would be ignored",
            ));
        }
        let (thickness_m, mu_a_per_m, mu_s_prime_per_m, n) = self.slab;
        RequestArgs {
            method: self.method.clone(),
            volume: self.volume.clone(),
            wavelength_m: self.wavelength,
            wavefactor: self.wavefactor,
            cycles: self.cycles,
            compensate: self.compensate.clone(),
            mu_t_per_m: self.mu_t,
            albedo: self.albedo,
            falloff: self.falloff.clone(),
            lateral: self.lateral.clone(),
            snr: self.snr,
            weighting: self.weighting.clone(),
            slab: SlabParams {
                thickness_m,
                mu_a_per_m,
                mu_s_prime_per_m,
                n,
                ..Default::default()
            },
            medium: BmmParams {
                n: self.medium.0,
                mu_s_prime_per_m: self.medium.1,
                mu_a_per_m: self.medium.2,
            },
            t_offset: self.t_offset.clone(),
            gate: self.gate.parse::<Gate>()?,
            window_end: self.window_end.clone(),
            medium_removal: self.medium_removal.clone(),
            depth_search: self.depth_search.clone(),
        }
        .request()
    }

    /// The density the compensation reads along each leg of `cap`, as `murk reconstruct` finds it.
    fn along(&self, cap: &murk_core::Capture) -> Result<Along> {
        let compensates = !matches!(self.compensate.as_deref(), None | Some("none"));
        DensityGiven {
            file: self.medium_density.clone(),
            height_scale_m: self.height_scale,
        }
        .along(cap, compensates, self.mu_t.is_some(), Spelling::Python)
    }

    fn model(&self) -> Result<bool> {
        Ok(MediumRemoval::named(&self.medium_removal)? == MediumRemoval::Model)
    }

    /// The medium response that medium_removal='model' subtracts: for mu_t and albedo as given, what
    /// is not given estimated from `cap` as `murk.estimate_medium` does; with the estimate's depth
    /// search, which the reconstruction then takes instead of searching again.
    fn predicted(&self, cap: &murk_core::Capture) -> Result<(Option<Predicted>, Option<Searched>)> {
        if !self.model()? {
            return Ok((None, None));
        }
        let estimate = match (self.mu_t, self.albedo) {
            (Some(_), Some(_)) => None,
            _ => match murk_medium::estimate(cap, &Default::default(), &|_, _| {})? {
                murk_medium::Outcome::Fitted(e) => Some(e),
                murk_medium::Outcome::NoMedium(s) => {
                    return Err(Error::param(format!(
                        "medium_removal='model': no medium detected to estimate it from ({}); give mu_t and albedo",
                        s.describe()
                    )))
                }
            },
        };
        let predicted =
            murk_medium::model::for_removal(cap, self.mu_t, self.albedo, estimate.as_deref())?;
        Ok((Some(predicted), estimate.and_then(|e| e.searched)))
    }
}

/// Every method `reconstruct` takes, with a line about it: the library's table, as `murk
/// reconstruct --help` lists it.
#[pyfunction]
pub fn methods() -> Vec<(&'static str, &'static str)> {
    murk_methods::METHODS
        .iter()
        .map(|m| (m.name, m.help))
        .collect()
}

/// Runs one reconstruction; returns (intensity [nx, ny, nz] float32 without a copy, (x, y, z), rows,
/// warnings, the normals [nx, ny, nz, 3] float32 of the methods that give them). See
/// `murk.reconstruct`.
#[pyfunction]
#[pyo3(signature = (capture, args, threads, progress))]
pub fn reconstruct<'py>(
    py: Python<'py>,
    capture: &Bound<'py, PyAny>,
    args: Args,
    threads: Option<i64>,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<Out<'py>> {
    let source = Source::of(capture)?;
    let out = compute(py, progress, threads, |t| {
        let cap = source.owned()?;
        let req = args.request()?;
        let mut along = args.along(&cap)?;
        let (predicted, searched) = args.predicted(&cap)?;
        let given = MediumGiven {
            predicted,
            density: along.density.take(),
            searched,
        };
        let assumed = match args.model()? {
            true => homogeneous_assumed(&cap, "medium_removal='model'"),
            false => None,
        };
        let mut out = murk_methods::run_given(cap, &req, &given, t)?;
        along.note(&mut out);
        out.warnings.extend(assumed);
        Ok(out)
    })?;
    let v = out.volume;
    let shape = v.shape().to_vec();
    let intensity = PyArray1::from_vec(py, out.intensity).reshape(shape.clone())?;
    let normals = out
        .normals
        .map(|n| {
            let flat = n.into_iter().flatten().collect();
            PyArray1::from_vec(py, flat).reshape([shape, vec![3]].concat())
        })
        .transpose()?;
    let axis = |a: &murk_core::Axis| PyArray1::from_vec(py, a.values());
    Ok((
        intensity,
        [axis(&v.x), axis(&v.y), axis(&v.z)],
        out.rows,
        out.warnings,
        normals,
    ))
}
