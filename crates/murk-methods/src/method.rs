//! A method chosen by name with the options it reads ([`Method`]), and the options themselves.

use crate::table::{Knob, MethodSpec, Setup, METHODS};
use murk_baselines::{BmmParams, Pulse, Reflectance, SlabParams};
use murk_core::{Capture, CaptureKind, Error, Progress, Reconstructor, Result, Volume};
use murk_recon::{Compensation, Falloff, Lateral, PathDensity, PfParams, Wavelength};
use std::sync::Arc;

/// The knobs the methods read, by name: what `murk reconstruct`'s flags and Python's keywords fill.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// `None`: [`Wavelength::default_for`] the capture's kind.
    pub wavelength: Option<Wavelength>,
    /// Pulse length in wavelengths (PF).
    pub cycles: f64,
    pub falloff: Falloff,
    pub compensation: Compensation,
    pub lateral: Lateral,
    /// Wiener signal-to-noise ratio (lct, cdt); `None`: each method's default.
    pub snr: Option<f64>,
    pub reflectance: Reflectance,
    /// The scattering slab in front of the scene (cdt; [`crate::TOffset::Slab`]).
    pub slab: SlabParams,
    /// The medium the scene is inside (bmm); unset constants come from the capture.
    pub medium: BmmParams,
}

impl Default for Options {
    fn default() -> Options {
        let pf = PfParams::default();
        Options {
            wavelength: None,
            cycles: pf.cycles,
            falloff: pf.falloff,
            compensation: pf.compensation,
            lateral: pf.lateral,
            snr: None,
            reflectance: Reflectance::Diffuse,
            slab: SlabParams::default(),
            medium: BmmParams::default(),
        }
    }
}

impl Options {
    /// The options that give Phasor Fields `pf`, the others at their defaults.
    pub fn from_pf(pf: &PfParams) -> Options {
        Options {
            wavelength: Some(pf.wavelength),
            cycles: pf.cycles,
            falloff: pf.falloff,
            compensation: pf.compensation,
            lateral: pf.lateral,
            ..Options::default()
        }
    }

    /// Phasor Fields' parameters for a capture of `kind`.
    pub fn pf(&self, kind: CaptureKind) -> PfParams {
        PfParams {
            wavelength: self
                .wavelength
                .unwrap_or_else(|| Wavelength::default_for(kind)),
            cycles: self.cycles,
            falloff: self.falloff,
            compensation: self.compensation,
            lateral: self.lateral,
        }
    }
}

/// A reconstruction method ([`METHODS`]' entry) with the options it reads.
#[derive(Clone, Copy)]
pub struct Method {
    spec: &'static MethodSpec,
    options: Options,
}

impl Method {
    /// The method called `name`, with its parameters from `o`. A knob of `o` set away from its
    /// default that this method does not read is refused, naming it.
    pub fn named(name: &str, o: &Options) -> Result<Method> {
        let Some(spec) = METHODS.iter().find(|m| m.name == name) else {
            let names: Vec<&str> = METHODS.iter().map(|m| m.name).collect();
            return Err(Error::param(format!(
                "unknown method '{name}'; expected one of {}",
                names.join(", ")
            )));
        };
        // The slab is refused by `TOffset::parse`, since the offset reads it too.
        let ignored = Knob::ALL
            .into_iter()
            .filter(|&k| k != Knob::Slab)
            .find(|&k| k.is_set(o) && !spec.reads.contains(&k));
        if let Some(k) = ignored {
            return Err(Error::param(format!(
                "{} does not apply to {name}, which would ignore it (it applies to {})",
                k.what(),
                k.readers()
            )));
        }
        Ok(Method { spec, options: *o })
    }

    /// The name [`Method::named`] reads.
    pub fn name(&self) -> &'static str {
        self.spec.name
    }

    /// Its entry in [`METHODS`].
    pub fn spec(&self) -> &'static MethodSpec {
        self.spec
    }

    pub fn options(&self) -> &Options {
        &self.options
    }

    /// Whether it reconstructs on the confocal scan grid and ignores the requested volume.
    pub fn own_grid(&self) -> bool {
        self.spec.own_grid
    }

    /// Whether it reads `knob`.
    pub fn reads(&self, knob: Knob) -> bool {
        self.spec.reads.contains(&knob)
    }

    /// PF's virtual pulse on this capture; `None` for the other methods.
    pub fn pulse(&self, cap: &Capture) -> Result<Option<Pulse>> {
        if !self.spec.pulsed {
            return Ok(None);
        }
        let p = self.options.pf(cap.kind());
        let wavelength_m = p.wavelength_m(cap)?;
        Ok(Some(Pulse {
            wavelength_m,
            sigma_m: p.sigma_m(wavelength_m),
        }))
    }

    /// The method's plan for captures of `geometry`'s geometry.
    pub(crate) fn plan(
        &self,
        geometry: &Capture,
        volume: Option<&Volume>,
        density: Option<&Arc<dyn PathDensity>>,
        progress: &dyn Progress,
    ) -> Result<Box<dyn Reconstructor>> {
        if density.is_some()
            && !(self.reads(Knob::Compensation) && Knob::Compensation.is_set(&self.options))
        {
            return Err(Error::param(format!(
                "a medium density is read only by the compensation ({}), and {} has none to apply it to",
                Knob::Compensation.readers(),
                self.name()
            )));
        }
        (self.spec.plan)(&Setup {
            geometry,
            options: &self.options,
            volume,
            density,
            progress,
        })
    }
}

impl PartialEq for Method {
    fn eq(&self, other: &Method) -> bool {
        self.name() == other.name() && self.options == other.options
    }
}

impl std::fmt::Debug for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Method")
            .field("name", &self.name())
            .field("options", &self.options)
            .finish()
    }
}
