//! `murk.reconstruct`: `murk_recon::pipeline::run`, the call behind `murk reconstruct`.

use crate::capture::Source;
use crate::compute;
use murk_baselines::{CdtParams, FbpOptions, FkParams, LctParams, Reflectance, SlabParams};
use murk_core::window::WindowEnd;
use murk_core::{Capture, Volume};
use murk_recon::pipeline::{self, Gate, Method, Request, TOffset, VolumeSpec};
use murk_recon::{Compensation, Falloff, Lateral, PfParams, Wavelength};
use numpy::{PyArray1, PyArrayDyn, PyArrayMethods};
use pyo3::prelude::*;

type Rows = Vec<(String, String)>;
type Axes<'py> = [Bound<'py, PyArray1<f64>>; 3];
/// What `reconstruct` returns: intensity, axes, rows, warnings.
type Out<'py> = (Bound<'py, PyArrayDyn<f32>>, Axes<'py>, Rows, Vec<String>);

fn bad(msg: String) -> murk_core::Error {
    murk_core::Error::param(msg)
}

/// The keywords of `murk.reconstruct`, which are `murk reconstruct`'s flags.
struct Args {
    method: String,
    volume: Option<String>,
    wavelength: Option<f64>,
    wavefactor: Option<f64>,
    cycles: f64,
    compensate: Option<String>,
    mu_t: Option<f64>,
    albedo: f64,
    falloff: String,
    lateral: String,
    gate: String,
    window_end: String,
    t_offset: Option<String>,
    snr: Option<f64>,
    weighting: String,
    slab: (f64, f64, f64, f64),
}

impl Args {
    /// The library request these keywords make for `cap`, as `murk reconstruct` builds it.
    fn request(&self, cap: &Capture) -> murk_core::Result<Request> {
        let (thickness_m, mu_a, mu_s_prime, n) = self.slab;
        let slab = SlabParams {
            thickness_m,
            mu_a,
            mu_s_prime,
            n,
            ..Default::default()
        };
        let method = match self.method.as_str() {
            "pf" => Method::Pf(self.pf(cap)?),
            "pf-exact" => Method::PfExact(self.pf(cap)?),
            "bp" => Method::Bp,
            "fbp" => Method::Fbp(FbpOptions::default()),
            "lct" => Method::Lct(LctParams {
                snr: self.snr.unwrap_or(LctParams::default().snr),
                reflectance: match self.weighting.as_str() {
                    "diffuse" => Reflectance::Diffuse,
                    "retroreflective" => Reflectance::Retroreflective,
                    w => {
                        return Err(bad(format!(
                            "weighting '{w}': expected diffuse or retroreflective"
                        )))
                    }
                },
                ..Default::default()
            }),
            "fk" => Method::Fk(FkParams::default()),
            "cdt" => Method::Cdt(CdtParams {
                slab,
                snr: self.snr.unwrap_or(CdtParams::default().snr),
                ..Default::default()
            }),
            m => {
                return Err(bad(format!(
                    "unknown method '{m}'; expected one of pf, pf-exact, bp, fbp, lct, fk, cdt"
                )))
            }
        };
        Ok(Request {
            method,
            volume: match &self.volume {
                Some(spec) => VolumeSpec::Given(Volume::parse(spec)?),
                None => VolumeSpec::Default,
            },
            t_offset: match self.t_offset.as_deref() {
                None => TOffset::None,
                Some("slab") => TOffset::Slab(slab),
                Some(s) => match s.parse::<f64>() {
                    Ok(v) if v.is_finite() => TOffset::Metres(v),
                    _ => return Err(bad(format!("t_offset '{s}': expected metres or 'slab'"))),
                },
            },
            gate: match self.gate.as_str() {
                "off" => Gate::Off,
                "auto" => Gate::Auto,
                t => match t.parse::<f64>() {
                    Ok(p) if p.is_finite() => Gate::At(p),
                    _ => {
                        return Err(bad(format!(
                            "gate {t}: expected a path in metres, auto or off"
                        )))
                    }
                },
            },
            window_end: match self.window_end.as_str() {
                "auto" => WindowEnd::Auto,
                "taper" => WindowEnd::Taper,
                "keep" => WindowEnd::Keep,
                w => {
                    return Err(bad(format!(
                        "window_end '{w}': expected auto, taper or keep"
                    )))
                }
            },
        })
    }

    fn pf(&self, cap: &Capture) -> murk_core::Result<PfParams> {
        if self.wavelength.is_some() && self.wavefactor.is_some() {
            return Err(bad("give wavelength or wavefactor, not both".into()));
        }
        let wavelength = match (self.wavelength, self.wavefactor) {
            (Some(m), _) => Wavelength::Metres(m),
            (None, Some(f)) => Wavelength::WallFactor(f),
            (None, None) => Wavelength::default_for(cap.kind()),
        };
        let mu = self.mu_t.unwrap_or(0.0);
        let compensation = match (self.compensate.as_deref(), self.mu_t) {
            (None, _) => Compensation::None,
            (Some(_), None) => return Err(bad("compensate needs mu_t".into())),
            (Some("paper"), _) => Compensation::Paper {
                mu_t_per_m: mu,
                albedo: self.albedo,
            },
            (Some("ballistic"), _) => Compensation::Ballistic { mu_t_per_m: mu },
            (Some(c), _) => {
                return Err(bad(format!(
                    "compensate '{c}': expected paper or ballistic"
                )))
            }
        };
        Ok(PfParams {
            wavelength,
            cycles: self.cycles,
            falloff: match self.falloff.as_str() {
                "none" => Falloff::None,
                "inv-r" => Falloff::InvR,
                f => return Err(bad(format!("falloff '{f}': expected none or inv-r"))),
            },
            compensation,
            lateral: match self.lateral.as_str() {
                "propagating" => Lateral::Propagating,
                "full" => Lateral::Full,
                l => return Err(bad(format!("lateral '{l}': expected propagating or full"))),
            },
        })
    }
}

/// Runs one reconstruction; returns (intensity [nx, ny, nz] float32 without a copy, (x, y, z), rows,
/// warnings). See `murk.reconstruct`.
#[pyfunction]
#[pyo3(signature = (capture, method, volume, wavelength, wavefactor, cycles, compensate, mu_t, albedo, falloff, lateral, gate, window_end, t_offset, snr, weighting, slab, threads, progress))]
#[allow(clippy::too_many_arguments)]
pub fn reconstruct<'py>(
    py: Python<'py>,
    capture: &Bound<'py, PyAny>,
    method: String,
    volume: Option<String>,
    wavelength: Option<f64>,
    wavefactor: Option<f64>,
    cycles: f64,
    compensate: Option<String>,
    mu_t: Option<f64>,
    albedo: f64,
    falloff: String,
    lateral: String,
    gate: String,
    window_end: String,
    t_offset: Option<String>,
    snr: Option<f64>,
    weighting: String,
    slab: (f64, f64, f64, f64),
    threads: Option<usize>,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<Out<'py>> {
    let args = Args {
        method,
        volume,
        wavelength,
        wavefactor,
        cycles,
        compensate,
        mu_t,
        albedo,
        falloff,
        lateral,
        gate,
        window_end,
        t_offset,
        snr,
        weighting,
        slab,
    };
    let source = Source::of(capture)?;
    let out = compute(py, progress, threads, |t| {
        let cap = source.owned()?;
        let req = args.request(&cap)?;
        pipeline::run(cap, &req, t)
    })?;
    let v = out.volume;
    let intensity = PyArray1::from_vec(py, out.intensity).reshape(v.shape().to_vec())?;
    let axis = |a: &murk_core::Axis| PyArray1::from_vec(py, a.values());
    Ok((
        intensity,
        [axis(&v.x), axis(&v.y), axis(&v.z)],
        out.rows,
        out.warnings,
    ))
}
