//! The medium from the capture: estimates a homogeneous medium's extinction μt, single-scattering
//! albedo α and Henyey–Greenstein g from the bins of a capture that only the medium lit.
//!
//! The forward model is murk's own renderer ("renderer in the loop", see `docs/medium.md` for why it
//! was chosen over an analytic single-scattering term with a calibrated multiple-scattering part): the
//! capture's own geometry with every object removed (but a room around the medium) is rendered once per (μt, g) of a grid, each render
//! an albedo sweep ([`table`]), and the capture's ring-averaged medium response is fitted by
//! interpolating in that table ([`fit`]). A table is built once per geometry and serves any number of
//! captures of it (the study fits every cell from one table).
//!
//! ```
//! use murk_core::{DVec3, TimeAxis};
//! use murk_medium::{estimate, EstimateOptions, FitParams, Outcome};
//! use murk_synth::{add_first_bounce, CaptureLayout, LayoutKind, SynthOptions, Target};
//!
//! // Fit μt and α (as `murk medium --fit mu_t,albedo` spells them); g keeps `fixed`'s value.
//! let opt = EstimateOptions {
//!     fit: FitParams::parse("mu_t,albedo")?,
//!     ..EstimateOptions::default()
//! };
//! // A clear capture: a point 0.5 m behind a 1 m wall, no medium in front of it.
//! let layout = CaptureLayout {
//!     kind: LayoutKind::Confocal,
//!     wall_size_m: 1.0,
//!     grid: 8,
//!     point: DVec3::ZERO,
//!     time: TimeAxis { start_m: 0.0, bin_width_m: 0.01, bins: 200 },
//!     laser_xyz: None,
//!     sensor_xyz: None,
//! };
//! let mut cap = layout.empty_capture()?;
//! let point = Target::Point { pos: DVec3::new(0.0, 0.0, 0.5), albedo: 1.0 };
//! add_first_bounce(&mut cap, &point.scatterers()?, &SynthOptions::default())?;
//! // No light before the scene's own: no medium is detected, and nothing is rendered to say so.
//! let outcome = estimate(&cap, &opt, &|_, _| {})?;
//! assert!(matches!(outcome, Outcome::NoMedium(_)));
//! assert!(outcome.to_json().starts_with("{\"medium\": false"));
//! # Ok::<(), murk_core::Error>(())
//! ```

pub mod density;
pub mod fit;
pub mod model;
pub mod posterior;
pub mod scene;
pub mod single;
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
    /// A folder where tables are kept ([`table::load_or_build`]): a capture whose geometry has a
    /// table there is fitted without rendering. `None`: tables live only in memory.
    pub table_cache: Option<std::path::PathBuf>,
}

/// The values of parameters held fixed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fixed {
    pub mu_t_per_m: f64,
    pub albedo: f64,
    pub g: f64,
}

impl Fixed {
    /// Refuses values no medium has: μt ≤ 0 or beyond murk's limit, an albedo outside (0, 1], |g| ≥ 1.
    pub fn validate(&self) -> Result<()> {
        murk_core::Limits::extinction(self.mu_t_per_m)
            .map_err(|e| Error::param(format!("μt {e}")))?;
        if self.mu_t_per_m.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(Error::param(format!(
                "μt must be > 0, got {}",
                self.mu_t_per_m
            )));
        }
        if !(self.albedo > 0.0 && self.albedo <= 1.0) {
            return Err(Error::param(format!(
                "albedo must be in (0, 1], got {}",
                self.albedo
            )));
        }
        if self.g.abs().partial_cmp(&1.0) != Some(std::cmp::Ordering::Less) {
            return Err(Error::param(format!(
                "g must be in (−1, 1), got {}",
                self.g
            )));
        }
        Ok(())
    }
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
            table_cache: None,
        }
    }
}

/// The answer of [`estimate`]: a fit, or no medium.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    NoMedium(Signature),
    Fitted(Box<Estimate>),
}

impl Outcome {
    /// One JSON object: `murk medium --json` and `murk.estimate_medium`.
    pub fn to_json(&self) -> String {
        match self {
            Outcome::NoMedium(s) => format!(
                "{{\"medium\": false, \"reason\": \"no medium detected: {}\"}}",
                s.describe()
            ),
            Outcome::Fitted(e) => e.to_json(),
        }
    }
}

/// Estimates the medium of `cap`. `progress(done, total)` follows the table's renders.
pub fn estimate(
    cap: &Capture,
    opt: &EstimateOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Outcome> {
    Ok(estimate_with(cap, opt, None, progress)?.0)
}

/// As [`estimate`], with a table built before for captures of the same geometry (plan once, fit
/// many): `table` is used when it matches `cap`'s geometry and `opt`, else a new one is built. The
/// table used comes back for the next capture.
pub fn estimate_with(
    cap: &Capture,
    opt: &EstimateOptions,
    table: Option<ResponseTable>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(Outcome, Option<ResponseTable>)> {
    cap.validate_data()?;
    opt.fixed.validate()?;
    if let Some(u) = opt.until_m.filter(|&u| u.is_nan() || u <= cap.time.start_m) {
        return Err(Error::param(format!(
            "the medium-only bins end at {u} m, before the capture's window starts ({} m)",
            murk_core::short(cap.time.start_m)
        )));
    }
    let signature = Signature::measure(cap);
    if !signature.is_medium() {
        return Ok((Outcome::NoMedium(signature), table));
    }
    let (until_m, searched) = match opt.until_m {
        Some(u) => (u, None),
        None => {
            let searched = fit::onset_search(cap)?;
            (fit::scene_onset_m(cap, &searched)?, Some(searched))
        }
    };
    let scene_text = scene::medium_only(cap)?;
    let table = match (
        table.filter(|t| t.serves(&scene_text, cap, opt)),
        &opt.table_cache,
    ) {
        (Some(t), _) => t,
        (None, Some(dir)) => table::load_or_build(dir, &scene_text, cap, opt, progress)?,
        (None, None) => ResponseTable::build(&scene_text, cap, opt, progress)?,
    };
    let fitted = fit::Estimate {
        searched,
        ..fit::fit(cap, &table, until_m, &opt.fit, &opt.fixed, signature)?
    };
    Ok((Outcome::Fitted(Box::new(fitted)), Some(table)))
}
