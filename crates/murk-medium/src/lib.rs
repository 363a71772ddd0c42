//! The medium from the capture: estimates a homogeneous medium's extinction μt, single-scattering
//! albedo α and Henyey–Greenstein g from the bins of a capture that only the medium lit.
//!
//! The forward model is murk's own renderer ("renderer in the loop", see `docs/medium.md` for why it
//! was chosen over an analytic single-scattering term with a calibrated multiple-scattering part): the
//! capture's own geometry with every object removed is rendered once per (μt, g) of a grid, each render
//! an albedo sweep ([`table`]), and the capture's ring-averaged medium response is fitted by
//! interpolating in that table ([`fit`]). A table is built once per geometry and serves any number of
//! captures of it (the study fits every cell from one table).

pub mod fit;
pub mod posterior;
pub mod scene;
pub mod slab;
pub mod table;

pub use fit::{Estimate, FitParams, Parameter};
pub use table::{ResponseTable, TableSpec};

use murk_core::{Capture, Error, Result};
use murk_recon::medium::detect::Signature;

/// What to estimate and how finely.
#[derive(Clone, Debug, PartialEq)]
pub struct EstimateOptions {
    /// Which parameters are fitted; the others keep `fixed`'s values.
    pub fit: FitParams,
    /// Values of the parameters that are not fitted.
    pub fixed: Fixed,
    /// The last path (m) of the medium-only bins; `None`: found from where the scene's signal begins.
    pub until_m: Option<f64>,
    pub table: TableSpec,
}

/// The values of parameters held fixed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fixed {
    pub mu_t_per_m: f64,
    pub albedo: f64,
    pub g: f64,
}

impl Default for EstimateOptions {
    fn default() -> EstimateOptions {
        EstimateOptions {
            fit: FitParams::ALL,
            fixed: Fixed {
                mu_t_per_m: 1.0,
                albedo: 0.5,
                g: 0.0,
            },
            until_m: None,
            table: TableSpec::default(),
        }
    }
}

/// The answer of [`estimate`]: a fit, or no medium.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    NoMedium(Signature),
    Fitted(Box<Estimate>),
}

/// Estimates the medium of `cap`. `progress(done, total)` follows the table's renders.
pub fn estimate(
    cap: &Capture,
    opt: &EstimateOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Outcome> {
    cap.validate_data()?;
    let signature = Signature::measure(cap);
    if !signature.is_medium() {
        return Ok(Outcome::NoMedium(signature));
    }
    let scene_text = scene::medium_only(cap)?;
    let table = ResponseTable::build(&scene_text, cap, &opt.table, &opt.fit, &opt.fixed, progress)?;
    let until_m = match opt.until_m {
        Some(u) if u > cap.time.start_m => u,
        Some(u) => {
            return Err(Error::param(format!(
                "the medium-only bins end at {u} m, before the capture's window starts ({} m)",
                murk_core::short(cap.time.start_m)
            )))
        }
        None => fit::scene_onset_m(cap)?,
    };
    Ok(Outcome::Fitted(Box::new(fit::fit(
        cap, &table, until_m, &opt.fit, &opt.fixed, signature,
    )?)))
}
