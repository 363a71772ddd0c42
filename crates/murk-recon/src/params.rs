//! What a Phasor Fields reconstruction is asked for: the virtual wavelength, the pulse length, the
//! falloff, the lateral band, the form, and the parameters that gather them ([`PfParams`]).

use crate::{wall_spacing_m, Compensation};
use murk_core::{Capture, CaptureKind, Error, Result};

/// Virtual wavelength λ of the phasor pulse.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Wavelength {
    /// λ in metres.
    Metres(f64),
    /// λ = factor × the wall's point spacing Δc (the paper uses 4).
    WallFactor(f64),
}

impl Wavelength {
    /// The default for a capture of `kind`: 4Δc of one-way distance, the paper's choice. Confocal
    /// data's round-trip kernel e^{2ikr} reads λ on the path, twice the distance, so it is 8Δc there.
    pub fn default_for(kind: CaptureKind) -> Wavelength {
        Wavelength::WallFactor(2.0 * nyquist_factor(kind))
    }
}

/// The smallest wavefactor a wall sampled every Δc supports: 2, or 4 for confocal data, whose
/// round-trip kernel e^{2ikr} halves the effective wavelength.
pub fn nyquist_factor(kind: CaptureKind) -> f64 {
    if kind == CaptureKind::Confocal {
        4.0
    } else {
        2.0
    }
}

/// Amplitude factor a(d) applied to each leg (changes brightness with depth, not focus).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Falloff {
    /// a = 1 (tal pf_dev's default).
    None,
    /// a = 1/d, the paper's RSD kernel e^{ikd}/d.
    InvR,
}

impl murk_core::Named for Falloff {
    const WHAT: &'static str = "falloff";
    const CHOICES: &'static [(&'static str, Self)] = &[("none", Self::None), ("inv-r", Self::InvR)];
}

impl murk_core::Named for Lateral {
    const WHAT: &'static str = "lateral";
    const CHOICES: &'static [(&'static str, Self)] =
        &[("propagating", Self::Propagating), ("full", Self::Full)];
}

/// Which lateral (wall-plane) frequencies the fast form keeps, per depth plane and band frequency.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Lateral {
    /// The waves that reach the plane: |κ| ≤ √(k² + (ln 10⁴ / z)²) for the kernel's wavenumber k
    /// (round trip for confocal data) at depth z, plus six FFT lines. The RSD kernel propagates
    /// |κ| ≤ k and damps |κ| > k by e^{−z·√(κ² − k²)}; past this bound the sampled, truncated kernel
    /// and data hold leakage of the aperture's edges, and skipping those spectrum lines halves the
    /// product, the kernel's and the inverse's FFTs along x and their transposes on average over the
    /// band. Along each axis where the voxels sit off the wall's lattice (not for confocal data) the
    /// band is cut the same way and read by a 6–12-tap Kaiser–Bessel kernel whose spectrum the data
    /// were divided by, instead of `Full`'s 16-tap windowed sinc: less aliasing, fewer taps. How far it
    /// stays from `Full` is measured in docs/reconstruction.md.
    /// Where the depth step is fine against the field's depth band, only every other plane is
    /// evaluated and the others interpolated by a 28-tap least-squares filter ("Depth planes" there).
    #[default]
    Propagating,
    /// Every frequency of the FFT grid and every depth plane: the fast form equals the exact discrete
    /// sum to rounding.
    Full,
}

/// How to evaluate the camera.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PfForm {
    /// Planar FFT convolution when the capture allows it, otherwise the exact form.
    Fast,
    /// Time-domain filtered backprojection with exact per-voxel paths (any geometry; slow).
    Exact,
}

impl murk_core::Named for PfForm {
    const WHAT: &'static str = "form";
    const CHOICES: &'static [(&'static str, Self)] =
        &[("fast", Self::Fast), ("exact", Self::Exact)];
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PfParams {
    pub wavelength: Wavelength,
    /// Pulse length in wavelengths: σ = cycles·λ/6 (the paper: 4 synthetic, 8 real).
    pub cycles: f64,
    pub falloff: Falloff,
    pub compensation: Compensation,
    pub lateral: Lateral,
}

impl Default for PfParams {
    fn default() -> Self {
        PfParams {
            wavelength: Wavelength::WallFactor(4.0),
            cycles: 4.0,
            falloff: Falloff::None,
            compensation: Compensation::None,
            lateral: Lateral::Propagating,
        }
    }
}

impl PfParams {
    pub fn sigma_m(&self, wavelength_m: f64) -> f64 {
        self.cycles * wavelength_m / 6.0
    }

    /// λ in metres for this capture (a wall factor times its grid spacing).
    pub fn wavelength_m(&self, cap: &Capture) -> Result<f64> {
        self.wavelength_for_spacing(wall_spacing_m(cap))
    }

    /// λ in metres for a wall sampled every `spacing_m` (`None`: not a grid).
    pub(crate) fn wavelength_for_spacing(&self, spacing_m: Option<f64>) -> Result<f64> {
        let l = match self.wavelength {
            Wavelength::Metres(l) => l,
            Wavelength::WallFactor(f) => {
                let d = spacing_m.ok_or_else(|| {
                    Error::param(
                        "a wavelength factor needs a wall grid; give the wavelength in metres",
                    )
                })?;
                f * d
            }
        };
        if !(l.is_finite() && l > 0.0) {
            return Err(Error::param(format!(
                "wavelength must be > 0 m, got {}",
                murk_core::short(l)
            )));
        }
        murk_core::Limits::get().length("the wavelength", l)?;
        Ok(l)
    }
}
