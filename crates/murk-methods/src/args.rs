//! `murk reconstruct`'s flags and `murk.reconstruct`'s keywords, as given: the one place they become
//! a [`Request`]. The CLI and Python each fill a [`RequestArgs`] (the CLI from its parsed flags,
//! Python from its keywords) and call [`RequestArgs::request`].

use crate::{Gate, Method, Options, Request, TOffset, VolumeSpec};
use murk_baselines::{BmmParams, Reflectance, SlabParams};
use murk_core::window::WindowEnd;
use murk_core::{Error, Named, Result, Volume};
use murk_recon::medium::{DepthSearch, MediumAware, MediumRemoval};
use murk_recon::{Compensation, Falloff, Lateral, Wavelength};

/// A reconstruction as the front ends take it: choices by the library's names ([`Named`]), the
/// volume and the time offset as text. The gate comes parsed, since the CLI names its flag in its
/// message.
#[derive(Clone, Debug, PartialEq)]
pub struct RequestArgs {
    pub method: String,
    /// `x0:x1:nx,y0:y1:ny,z0:z1:nz`; `None`: the default volume.
    pub volume: Option<String>,
    pub wavelength_m: Option<f64>,
    /// λ as a multiple of the wall spacing; refused together with `wavelength_m`.
    pub wavefactor: Option<f64>,
    pub cycles: f64,
    /// A [`Compensation`] name; `None` or `"none"`: no compensation.
    pub compensate: Option<String>,
    /// μt for the compensation (it needs one).
    pub mu_t_per_m: Option<f64>,
    pub albedo: Option<f64>,
    pub falloff: String,
    pub lateral: String,
    pub snr: Option<f64>,
    /// A [`Reflectance`] name.
    pub weighting: String,
    pub slab: SlabParams,
    pub medium: BmmParams,
    /// Metres or `slab`.
    pub t_offset: Option<String>,
    pub gate: Gate,
    pub window_end: String,
    pub medium_removal: String,
    pub depth_search: String,
}

impl RequestArgs {
    /// The request these arguments make.
    pub fn request(&self) -> Result<Request> {
        let o = self.options()?;
        let method = Method::named(&self.method, &o)?;
        Ok(Request {
            method,
            volume: match &self.volume {
                Some(spec) => VolumeSpec::Given(Volume::parse(spec)?),
                None => VolumeSpec::Default,
            },
            t_offset: TOffset::parse(self.t_offset.as_deref(), &o, &method)?,
            gate: self.gate,
            window_end: WindowEnd::named(&self.window_end)?,
            medium: MediumAware {
                removal: MediumRemoval::named(&self.medium_removal)?,
                depth_search: DepthSearch::named(&self.depth_search)?,
            },
        })
    }

    /// The method options these arguments set.
    pub fn options(&self) -> Result<Options> {
        let wavelength = match (self.wavelength_m, self.wavefactor) {
            (Some(_), Some(_)) => {
                return Err(Error::param("give wavelength or wavefactor, not both"))
            }
            (Some(m), None) => Some(Wavelength::Metres(m)),
            (None, Some(f)) => Some(Wavelength::WallFactor(f)),
            (None, None) => None,
        };
        let compensation = match (self.compensate.as_deref(), self.mu_t_per_m) {
            (None | Some("none"), _) => Compensation::None,
            (Some(c), None) => {
                // An unknown name is named first.
                Compensation::named(c, 0.0, self.albedo)?;
                return Err(Error::param("compensate needs mu_t"));
            }
            (Some(c), Some(mu_t)) => Compensation::named(c, mu_t, self.albedo)?,
        };
        Ok(Options {
            wavelength,
            cycles: self.cycles,
            falloff: Falloff::named(&self.falloff)?,
            compensation,
            lateral: Lateral::named(&self.lateral)?,
            snr: self.snr,
            reflectance: Reflectance::named(&self.weighting)?,
            slab: self.slab,
            medium: self.medium,
        })
    }
}
