//! Phasor Fields reconstruction: the paper's virtual time-gated camera (Liu et al. 2019, as used by
//! Luesia et al.), exact for any voxel set and fast (per-frequency RSD by linear FFT convolution) for
//! depth planes parallel to a planar wall grid, plus the paper's medium compensation K(x_v).
//!
//! U(x_v) = Σ_{l,s} a_l a_s (H_ls ∗ P0)(e_l + d_l + d_s + e_s), I = |U|²·K, with the virtual pulse
//! P0(s) = exp(i2πs/λ)·exp(−s²/2σ²) normalised so its spectrum is 1 at 1/λ, and σ = cycles·λ/6.
//! Phases are computed in f64, fields stored in f32.
//!
//! ```
//! use murk_core::{DVec3, NoProgress};
//! use murk_recon::{reconstruct, PfForm, PfParams, Wavelength};
//! use murk_synth::testutil::{aligned_volume, point_capture};
//! use murk_synth::LayoutKind;
//!
//! // A point 0.5 m behind a 1 m wall scanned confocally on 32² points; PF on the wall's lattice.
//! let point = DVec3::new(0.1, -0.2, 0.5);
//! let cap = point_capture(LayoutKind::Confocal, 0.0, false, point);
//! let params = PfParams {
//!     wavelength: Wavelength::default_for(cap.kind()),
//!     ..PfParams::default()
//! };
//! let rec = reconstruct(&cap, &aligned_volume(), &params, PfForm::Fast, &NoProgress)?;
//! let (peak, _) = rec.peak();
//! assert!((DVec3::from_array(peak) - point).length() < 0.04, "{peak:?}");
//! # Ok::<(), murk_core::Error>(())
//! ```

mod cmul;
mod compensation;
mod fft2;
pub mod medium;
mod params;
mod pf_exact;
mod pf_fast;
mod phase;
mod resample;
pub mod spectrum;

pub use compensation::{Compensation, PathDensity};
pub use params::{nyquist_factor, Falloff, Lateral, PfForm, PfParams, Wavelength};
pub use pf_fast::Slab;

use murk_core::{Capture, CaptureKind, DVec3, Error, Reconstruction, Result, Volume};
use rayon::prelude::*;
use rustfft::num_complex::Complex32;
use std::sync::Arc;

pub use murk_core::{NoProgress, Progress};

/// What was computed and how, for logs and file attributes.
#[derive(Clone, Debug)]
pub struct ReconInfo {
    pub wavelength_m: f64,
    pub sigma_m: f64,
    pub wall_spacing_m: Option<f64>,
    pub frequencies: usize,
    pub dft_len: usize,
    /// The fast form's depth slabs, each with its own time window: (planes, frequencies, DFT length).
    /// Their planes are the ones evaluated, which may be every other one (see [`Lateral::Propagating`]).
    pub slabs: Vec<Slab>,
    /// The form evaluated: the fast one falls back to the exact one when the capture is not a planar
    /// grid.
    pub evaluated_with: PfForm,
    pub warnings: Vec<String>,
}

impl ReconInfo {
    /// How the field was computed, as (key, value) rows for summaries and file attributes.
    pub fn rows(&self) -> Vec<(String, String)> {
        let frequencies = if self.slabs.len() > 1 {
            format!(
                "{:.1} per evaluated plane over {} depth slabs with their own time windows (the whole volume's window: {} of a {}-point DFT)",
                self.frequencies_per_plane(),
                self.slabs.len(),
                self.frequencies,
                self.dft_len
            )
        } else {
            format!("{} of a {}-point DFT", self.frequencies, self.dft_len)
        };
        vec![
            (
                "method".into(),
                format!(
                    "Phasor Fields ({} form)",
                    murk_core::Named::name(self.evaluated_with)
                ),
            ),
            ("wavelength_m".into(), format!("{:.6}", self.wavelength_m)),
            ("sigma_m".into(), format!("{:.6}", self.sigma_m)),
            (
                "wall_spacing_m".into(),
                self.wall_spacing_m
                    .map(|d| format!("{d:.6}"))
                    .unwrap_or_else(|| "n/a".into()),
            ),
            ("frequencies".into(), frequencies),
        ]
    }

    /// Depth planes the fast form evaluated (every plane, or every other one and a few past the ends;
    /// see [`Lateral::Propagating`]); 0 for the exact form.
    pub fn planes_evaluated(&self) -> usize {
        self.slabs.iter().map(|s| s.planes.len()).sum()
    }

    /// Band frequencies per evaluated depth plane: the mean over the fast form's slabs, else the whole
    /// window's.
    pub fn frequencies_per_plane(&self) -> f64 {
        let planes = self.planes_evaluated();
        if planes == 0 {
            return self.frequencies as f64;
        }
        let work: usize = self
            .slabs
            .iter()
            .map(|s| s.planes.len() * s.frequencies)
            .sum();
        work as f64 / planes as f64
    }
}

/// The complex field of a Phasor Fields reconstruction, before |U|²·K, and how it was computed.
#[derive(Debug)]
pub struct Field {
    pub volume: Volume,
    /// U, volume C order [nx, ny, nz].
    pub values: Vec<Complex32>,
    pub info: ReconInfo,
}

/// Spacing of the wall sampling (Δc): the regular grid's step, else the median nearest-neighbour
/// distance of up to 512 points of the larger side.
pub fn wall_spacing_m(cap: &Capture) -> Option<f64> {
    let side = if cap.illum.len() >= cap.sensor.len() {
        &cap.illum
    } else {
        &cap.sensor
    };
    if let Some(d) = side.spacing_m() {
        return Some(d);
    }
    if side.len() < 2 {
        return None;
    }
    let stride = side.len().div_ceil(512);
    let mut nn: Vec<f64> = (0..side.len())
        .step_by(stride)
        .map(|i| {
            side.points
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, p)| (*p - side.points[i]).length())
                .fold(f64::MAX, f64::min)
        })
        .filter(|d| *d > 0.0)
        .collect();
    nn.sort_by(f64::total_cmp);
    nn.get(nn.len() / 2).copied()
}

/// Phasor Fields on one volume for captures of one geometry: the checks, the time window and the fast
/// form's FFT plans and resamplers are made once and serve every capture [`Capture::same_geometry`]
/// as the one it was built for.
pub struct PfPlan {
    geometry: Capture,
    volume: Volume,
    params: PfParams,
    wavelength_m: f64,
    sigma_m: f64,
    spacing_m: Option<f64>,
    window: spectrum::Window,
    /// The fast form's plan; `None` when the exact form is asked for or the fast one does not apply.
    fast: Option<pf_fast::FastPlan>,
    /// The medium's density along the compensation's legs; `None`: density 1 everywhere.
    density: Option<Arc<dyn PathDensity>>,
    warnings: Vec<String>,
}

impl PfPlan {
    /// Checks `params` against the geometry of `cap` and plans the evaluation in `form`.
    pub fn new(cap: &Capture, volume: &Volume, params: &PfParams, form: PfForm) -> Result<PfPlan> {
        PfPlan::new_along(cap, volume, params, form, None)
    }

    /// As [`PfPlan::new`], with the compensation integrating the attenuation through `density`
    /// along each leg ([`Compensation::gain_along`]).
    pub fn new_along(
        cap: &Capture,
        volume: &Volume,
        params: &PfParams,
        form: PfForm,
        density: Option<Arc<dyn PathDensity>>,
    ) -> Result<PfPlan> {
        cap.validate_geometry()?;
        volume.validate()?;
        if !(params.cycles.is_finite() && params.cycles > 0.0) {
            return Err(Error::param(format!(
                "cycles must be > 0, got {}",
                params.cycles
            )));
        }
        params.compensation.validate()?;
        let kind = cap.kind();
        let spacing_m = wall_spacing_m(cap);
        let wavelength_m = params.wavelength_for_spacing(spacing_m)?;
        let nyquist_factor = nyquist_factor(kind);
        let mut warnings = Vec::new();
        if let Some(d) = spacing_m {
            let limit = nyquist_factor * d;
            if wavelength_m < limit * (1.0 - 1e-9) {
                return Err(Error::param(format!(
                    "wavelength {wavelength_m:.4} m is below the Nyquist limit {limit:.4} m of a {}wall sampled every {d:.4} m; use at least {limit:.4} m (wavefactor {nyquist_factor})",
                    if kind == CaptureKind::Confocal { "confocal " } else { "" }
                )));
            }
        }
        let sigma_m = params.sigma_m(wavelength_m);
        murk_core::Limits::get().length("the virtual pulse's σ (cycles × λ / 6)", sigma_m)?;
        if 2.0 * sigma_m < cap.time.bin_width_m {
            return Err(Error::param(format!(
                "the virtual pulse (σ = {} m) is shorter than one time bin ({} m); use more cycles or a longer wavelength",
                murk_core::short(sigma_m),
                murk_core::short(cap.time.bin_width_m)
            )));
        }
        let window = spectrum::Window::new(
            cap,
            spectrum::path_range(cap, volume),
            sigma_m,
            wavelength_m,
        )?;
        if let Some(d) = spacing_m {
            let lmin = window.band.min_wavelength_m();
            if lmin < nyquist_factor * d {
                warnings.push(format!(
                    "the pulse band reaches λ = {lmin:.4} m, below the {:.4} m Nyquist limit of the wall sampling: steep angles may alias",
                    nyquist_factor * d
                ));
            }
        }
        if window.empty {
            warnings.push(
                "the capture's time window does not reach the volume: the result is zero".into(),
            );
        } else if window.truncated {
            warnings.push("the capture's time window covers only part of the paths through the volume (zeros assumed beyond it)".into());
        }
        let fast = match form {
            PfForm::Exact => None,
            PfForm::Fast => {
                match pf_fast::FastPlan::new(cap, kind, volume, params.falloff, params.lateral) {
                    Ok(plan) => Some(plan),
                    Err(why) => {
                        warnings.push(format!(
                            "fast form not applicable ({why}); used the exact form"
                        ));
                        None
                    }
                }
            }
        };
        let along = Along {
            compensation: params.compensation,
            density: density.as_deref(),
        };
        warnings.extend(clamped_gain_warning(cap, volume, along));
        Ok(PfPlan {
            geometry: cap.geometry(),
            volume: *volume,
            params: *params,
            wavelength_m,
            sigma_m,
            spacing_m,
            window,
            fast,
            density,
            warnings,
        })
    }

    /// The complex field U from `cap`, before any compensation.
    pub fn field(&self, cap: &Capture, progress: &dyn Progress) -> Result<Field> {
        if !self.geometry.same_geometry(cap) {
            return Err(Error::param(
                "the capture's points or time axis differ from the ones the plan was made for",
            ));
        }
        cap.validate()?;
        let (values, evaluated_with, slabs) = match &self.fast {
            Some(plan) => {
                let (values, slabs) = plan.run(cap, self.sigma_m, self.wavelength_m, progress)?;
                (values, PfForm::Fast, slabs)
            }
            None => {
                let spectra = spectrum::spectra(cap, std::slice::from_ref(&self.window));
                let values = pf_exact::run(
                    cap,
                    &self.volume,
                    &spectra.part(0),
                    self.params.falloff,
                    progress,
                );
                (values, PfForm::Exact, Vec::new())
            }
        };
        Ok(Field {
            volume: self.volume,
            values,
            info: ReconInfo {
                wavelength_m: self.wavelength_m,
                sigma_m: self.sigma_m,
                wall_spacing_m: self.spacing_m,
                frequencies: self.window.band.len(),
                dft_len: self.window.band.nf,
                slabs,
                evaluated_with,
                warnings: self.warnings.clone(),
            },
        })
    }

    /// |U|²·K from `cap`, with the rows that say how it was made.
    pub fn run(&self, cap: &Capture, progress: &dyn Progress) -> Result<Reconstruction> {
        let f = self.field(cap, progress)?;
        let mut rows = f.info.rows();
        if f.info.evaluated_with == PfForm::Fast {
            rows.push((
                "lateral".into(),
                murk_core::Named::name(self.params.lateral).to_string(),
            ));
            let evaluated = f.info.planes_evaluated();
            if evaluated != f.volume.z.n {
                rows.push((
                    "depth_planes".into(),
                    format!(
                        "{evaluated} evaluated for {} (every other one and a few past the ends; the others interpolated)",
                        f.volume.z.n
                    ),
                ));
            }
        }
        Ok(Reconstruction {
            volume: self.volume,
            intensity: intensity_along(
                cap,
                &self.volume,
                &f.values,
                Along {
                    compensation: self.params.compensation,
                    density: self.density.as_deref(),
                },
            ),
            normals: None,
            rows,
            warnings: f.info.warnings,
        })
    }
}

impl murk_core::Reconstructor for PfPlan {
    fn reconstruct(&self, capture: &Capture, progress: &dyn Progress) -> Result<Reconstruction> {
        self.run(capture, progress)
    }
}

/// Reconstructs `volume` from `cap` with Phasor Fields (plans and runs).
pub fn reconstruct(
    cap: &Capture,
    volume: &Volume,
    params: &PfParams,
    form: PfForm,
    progress: &dyn Progress,
) -> Result<Reconstruction> {
    PfPlan::new(cap, volume, params, form)?.run(cap, progress)
}

/// The complex field U of `volume` from `cap`, before any compensation (plans and runs).
pub fn field(
    cap: &Capture,
    volume: &Volume,
    params: &PfParams,
    form: PfForm,
    progress: &dyn Progress,
) -> Result<Field> {
    PfPlan::new(cap, volume, params, form)?.field(cap, progress)
}

/// |U|²·K of a field on `volume` reconstructed from `cap`, so that one field serves every compensation.
pub fn intensity(
    cap: &Capture,
    volume: &Volume,
    field: &[Complex32],
    compensation: Compensation,
) -> Vec<f32> {
    let along = Along {
        compensation,
        density: None,
    };
    intensity_along(cap, volume, field, along)
}

/// A compensation with the medium's density along its legs (`None`: density 1 everywhere).
#[derive(Clone, Copy)]
pub struct Along<'a> {
    pub compensation: Compensation,
    pub density: Option<&'a dyn PathDensity>,
}

impl Along<'_> {
    /// The gain at every voxel of `volume` for captures of `cap`'s geometry, in C order.
    fn gains(
        &self,
        cap: &Capture,
        volume: &Volume,
    ) -> impl IndexedParallelIterator<Item = f64> + '_ {
        let confocal = cap.kind() == CaptureKind::Confocal;
        let (point, aperture) = compensation_points(cap);
        let volume = *volume;
        (0..volume.len()).into_par_iter().map(move |i| {
            let (ix, iy, iz) = volume.unravel(i);
            let v = volume.centre(ix, iy, iz);
            self.compensation
                .gain_along(v, point, aperture, confocal, self.density)
        })
    }
}

/// As [`intensity`], with the compensation's attenuation integrated through `along`'s density.
pub fn intensity_along(
    cap: &Capture,
    volume: &Volume,
    field: &[Complex32],
    along: Along,
) -> Vec<f32> {
    if along.compensation == Compensation::None {
        return field.par_iter().map(|u| u.norm_sqr()).collect();
    }
    field
        .par_iter()
        .zip(along.gains(cap, volume))
        .map(|(u, k)| (u.norm_sqr() as f64 * k) as f32)
        .collect()
}

/// A warning when `along`'s gain reaches its cap at some voxels of `volume`: there the
/// intensity is scaled by the cap, not by the gain the formula gives, so depths are not comparable.
fn clamped_gain_warning(cap: &Capture, volume: &Volume, along: Along) -> Option<String> {
    if along.compensation == Compensation::None {
        return None;
    }
    let clamped = along
        .gains(cap, volume)
        .filter(|&k| k >= Compensation::MAX_GAIN)
        .count();
    (clamped > 0).then(|| {
        format!(
            "the compensation's gain reaches its cap of {} at {:.1} % of the voxels (μt too large for their distance); there it no longer follows the formula",
            Compensation::MAX_GAIN,
            100.0 * clamped as f64 / volume.len() as f64
        )
    })
}

/// The paper's x_c for K(x_v) (the single wall point of a one-point capture, else the sensor centroid)
/// and the centroid of the other side (the virtual aperture).
fn compensation_points(cap: &Capture) -> (DVec3, DVec3) {
    match cap.kind() {
        CaptureKind::LaserGridSinglePoint => (cap.sensor.points[0], cap.illum.centroid()),
        CaptureKind::SinglePointSensorGrid => (cap.illum.points[0], cap.sensor.centroid()),
        _ => (cap.sensor.centroid(), cap.illum.centroid()),
    }
}

#[cfg(test)]
mod tests;
