//! Confocal diffuse tomography (Lindell & Wetzstein 2020), confocal captures through a scattering
//! slab only: Wiener deconvolution of the slab's round trip, then f-k migration.
//!
//! The capture is modelled as the free-space confocal transient at the slab's far face, convolved in
//! (x, y, t) with K ⊛ K, where K is the slab's time-resolved transmittance (one crossing in, one out):
//! the extrapolated-boundary diffusion dipole model with image dipoles i = −20..20 (Patterson, Chance
//! & Wilson 1989; Contini et al. 1997). Unlike the reference code, the kernel is sampled on the data's
//! own grid (its time step there is n = 1.12 times the data's, and its lateral step differs).
//! Depth is measured behind the slab.

use crate::confocal::{ConfocalGeometry, TimeGrid};
use crate::fft3::{Fft3, Steps, C32};
use crate::fk::Stolt;
use crate::Reconstruction;
use murk_core::{Capture, Error, NoProgress, Progress, Result, SPEED_OF_LIGHT_M_PER_S};
use rayon::prelude::*;

/// Optical parameters of the slab (defaults: the 2.54 cm polyurethane foam fitted in the paper).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlabParams {
    pub thickness_m: f64,
    /// Absorption coefficient μa (1/m).
    pub mu_a_per_m: f64,
    /// Reduced scattering coefficient μs′ (1/m).
    pub mu_s_prime_per_m: f64,
    /// Refractive index (light moves at c/n inside).
    pub n: f64,
    /// Extrapolation length of the boundary condition (m).
    pub ze_m: f64,
}

impl Default for SlabParams {
    fn default() -> Self {
        SlabParams {
            thickness_m: 0.0254,
            mu_a_per_m: 0.53,
            mu_s_prime_per_m: 262.0,
            n: 1.12,
            ze_m: 0.0036,
        }
    }
}

/// PF's virtual pulse on the path axis: carrier wavelength and envelope σ (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pulse {
    pub wavelength_m: f64,
    pub sigma_m: f64,
}

impl SlabParams {
    /// Where a point just behind the slab shows up late in a confocal capture (m of path): the
    /// peak of the round trip's response K ⊛ K integrated over the lateral plane or, with a `pulse`,
    /// the peak of that response's envelope after Phasor Fields' band-pass, which is where PF puts
    /// the point. The response rises sharply and decays slowly, so the band-pass (weighing its
    /// rise) peaks earlier than the response does. A slab whose response does not peak inside the
    /// model's 4 ns is refused.
    pub fn round_trip_delay_m(&self, pulse: Option<Pulse>) -> Result<f64> {
        self.validate()?;
        // 1 ps steps over 4 ns cover the foam's response (its peak is near 0.3 ns).
        let dt_s = 1e-12;
        let n = 4000;
        let step_m = dt_s * SPEED_OF_LIGHT_M_PER_S;
        // ∫K(ρ, t) 2πρ dρ = a(t)·4πDvt ∝ K(0, t)·t.
        let k: Vec<f64> = (0..n)
            .map(|i| self.transmittance(0.0, i as f64 * dt_s) * i as f64)
            .collect();
        let response: Vec<f64> = (0..n)
            .map(|m| (0..=m).map(|j| k[j] * k[m - j]).sum::<f64>())
            .collect();
        let envelope: Vec<f64> = match pulse {
            None => response,
            Some(p) => {
                // |Σ_j R(j)·P0(m − j)| with P0(s) = e^{i2πs/λ}·e^{−s²/2σ²}, over ±5σ.
                let half = (5.0 * p.sigma_m / step_m).ceil() as i64;
                let taps: Vec<(i64, f64, f64)> = (-half..=half)
                    .map(|o| {
                        let s = o as f64 * step_m;
                        let w = (-s * s / (2.0 * p.sigma_m * p.sigma_m)).exp();
                        let ph = 2.0 * std::f64::consts::PI * s / p.wavelength_m;
                        (o, w * ph.cos(), w * ph.sin())
                    })
                    .collect();
                (0..n as i64)
                    .map(|m| {
                        let (mut re, mut im) = (0.0, 0.0);
                        for &(o, c, s) in &taps {
                            let j = m - o;
                            if (0..n as i64).contains(&j) {
                                re += response[j as usize] * c;
                                im += response[j as usize] * s;
                            }
                        }
                        re.hypot(im)
                    })
                    .collect()
            }
        };
        let best = envelope
            .iter()
            .enumerate()
            .fold((0, f64::MIN), |a, (i, &v)| if v > a.1 { (i, v) } else { a });
        if best.1 <= 0.0 || best.0 + 1 >= n {
            return Err(Error::param(format!(
                "the slab ({} m, μs′ {} /m, μa {} /m, n {}) does not return its light within 4 ns, the span its delay is modelled over",
                murk_core::short(self.thickness_m),
                murk_core::short(self.mu_s_prime_per_m),
                murk_core::short(self.mu_a_per_m),
                murk_core::short(self.n)
            )));
        }
        Ok(best.0 as f64 * step_m)
    }

    /// Time-resolved transmittance at lateral distance `rho` (m) and time `t` (s) after entry.
    pub fn transmittance(&self, rho: f64, t: f64) -> f64 {
        let (a, four_dvt) = self.temporal(t);
        a * (-rho * rho / four_dvt).exp()
    }

    /// K(ρ, t) = a(t)·exp(−ρ²/(4Dvt)): returns (a(t), 4Dvt), the part shared by all ρ.
    fn temporal(&self, t: f64) -> (f64, f64) {
        let v = SPEED_OF_LIGHT_M_PER_S / self.n;
        let d_coef = 1.0 / (3.0 * (self.mu_a_per_m + self.mu_s_prime_per_m));
        let four_dvt = 4.0 * d_coef * v * t;
        if t <= 0.0 {
            return (0.0, 1.0);
        }
        let z0 = 1.0 / self.mu_s_prime_per_m;
        let (d, ze) = (self.thickness_m, self.ze_m);
        let dipoles: f64 = (-20..=20)
            .map(|i| {
                let i = i as f64;
                let z1 = d * (1.0 - 2.0 * i) - 4.0 * i * ze - z0;
                let z2 = d * (1.0 - 2.0 * i) - (4.0 * i - 2.0) * ze + z0;
                z1 * (-z1 * z1 / four_dvt).exp() - z2 * (-z2 * z2 / four_dvt).exp()
            })
            .sum();
        let a = (4.0 * std::f64::consts::PI * d_coef * v).powf(-1.5)
            * t.powf(-2.5)
            * (-self.mu_a_per_m * v * t).exp()
            * dipoles;
        (a, four_dvt)
    }

    /// Each parameter within what the diffusion model describes: a slab up to 1 m thick of a
    /// medium whose transport length (1/μs′) lies between 1 µm and 1 m, with a refractive index of
    /// 1 to 4; outside these the model's response underflows to nothing or stops being diffusion.
    fn validate(&self) -> Result<()> {
        let checks = [
            ("slab thickness (m)", self.thickness_m, 0.0, 1.0, false),
            ("slab μa (1/m)", self.mu_a_per_m, 0.0, 1e4, true),
            ("slab μs′ (1/m)", self.mu_s_prime_per_m, 1.0, 1e6, true),
            ("slab refractive index", self.n, 1.0, 4.0, true),
            ("slab extrapolation length (m)", self.ze_m, 0.0, 1.0, true),
        ];
        for (what, v, lo, hi, closed) in checks {
            let low_ok = if closed { v >= lo } else { v > lo };
            if !(low_ok && v <= hi) {
                let open = if closed { "≤" } else { "<" };
                return Err(Error::param(format!(
                    "{what} must be {lo} {open} value ≤ {hi}, got {}",
                    murk_core::short(v)
                )));
            }
        }
        Ok(())
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CdtParams {
    pub slab: SlabParams,
    /// Wiener signal-to-noise ratio; the reference uses 1e4 (letter S, U+T), 2e4 (mannequin, cones),
    /// 2.5e3 (diffuse T).
    pub snr: f64,
    /// The reference keeps 2.0 m of path at 128 samples (depth 0–1 m in 7.8 mm steps).
    pub grid: TimeGrid,
}

impl Default for CdtParams {
    fn default() -> Self {
        CdtParams {
            slab: SlabParams::default(),
            snr: 1e4,
            grid: TimeGrid::Resample {
                max_path_m: 2.0,
                bins: 128,
            },
        }
    }
}

pub struct CdtPlan {
    geom: ConfocalGeometry,
    params: CdtParams,
    stolt: Stolt,
    /// Wiener filter of the slab round trip, conj(H)/(|H|² + 1/snr), on the padded grid's
    /// spectrum (Hermitian, as H is that of a real kernel).
    filter: Vec<C32>,
}

impl CdtPlan {
    /// Plans for captures of `capture`'s geometry, reporting the kernel's transforms to `progress`
    /// (stopped when it asks).
    pub fn new(capture: &Capture, params: CdtParams, progress: &dyn Progress) -> Result<Self> {
        params.slab.validate()?;
        crate::lct::check_snr("CDT", params.snr)?;
        let geom = ConfocalGeometry::new(capture, params.grid)?;
        let stolt = Stolt::new(&geom);
        let steps = Steps::start(progress, Fft3::FORWARD_PASSES + Fft3::MAP_REAL_PASSES);
        let mut h = round_trip_spectrum(&geom, &params.slab, &stolt.fft, &steps);
        steps.finish("confocal diffuse tomography")?;
        let inv_snr = (1.0 / params.snr) as f32;
        h.par_iter_mut()
            .for_each(|f| *f = f.conj() / (f.norm_sqr() + inv_snr));
        Ok(CdtPlan {
            geom,
            params,
            stolt,
            filter: h,
        })
    }

    /// Reconstructs on the scan grid: [nx, ny, nt], depth k·Δs′/2 behind the slab.
    pub fn run(&self, capture: &Capture, progress: &dyn Progress) -> Result<Reconstruction> {
        self.geom.check_same(capture, self.params.grid)?;
        let g = &self.geom;
        let steps = Steps::start(
            progress,
            Fft3::FORWARD_PASSES + Fft3::MAP_REAL_PASSES + Stolt::MIGRATE_PASSES,
        );
        let mut spec = self.stolt.transform(&g.sample(capture), |_, v| v, &steps);
        spec.par_iter_mut()
            .zip(&self.filter)
            .for_each(|(b, f)| *b *= f);
        // The deconvolved transient spills out of the first octant (the kernel is acausal after
        // regularisation), so the whole padded volume is kept and migrated, as the reference does.
        // Wavefield amplitude √τ. No t² scaling: the reference CDT omits it. A NaN (sums that
        // overflowed f32) stays NaN so that the overflow is reported, not clamped to zero.
        self.stolt.fft.map_real(
            &mut spec,
            |v| if v.is_nan() { v } else { v.max(0.0).sqrt() },
            &steps,
        );
        let volume = self.stolt.migrate_and_crop(spec, &steps);
        steps.finish("confocal diffuse tomography")?;
        let (p, s) = (&self.params, &self.params.slab);
        Ok(g.reconstruction(
            g.nt,
            volume,
            "confocal diffuse tomography (slab Wiener + f-k)",
        )
        .row(
            "slab",
            format!(
                "{} m, μa {} /m, μs′ {} /m, n {}, ze {} m",
                s.thickness_m, s.mu_a_per_m, s.mu_s_prime_per_m, s.n, s.ze_m
            ),
        )
        .row("snr", p.snr)
        .row("time grid", p.grid))
    }
}

/// One-shot CDT (plans and runs).
pub fn cdt(capture: &Capture, params: CdtParams) -> Result<Reconstruction> {
    CdtPlan::new(capture, params, &NoProgress)?.run(capture, &NoProgress)
}

/// The CDT forward model: a free-space confocal capture as seen through `slab`, i.e. convolved in
/// (x, y, t) with the slab's round trip K ⊛ K on the capture's own bins (linear convolution; what
/// is pushed past the last bin is dropped). For tests and simulations.
pub fn through_slab(capture: &Capture, slab: &SlabParams) -> Result<Capture> {
    slab.validate()?;
    let mut c = capture.clone();
    let g = ConfocalGeometry::new(&c, TimeGrid::Native)?;
    if g.nt != c.time.bins {
        return Err(Error::Unsupported(
            "through_slab needs a capture whose time axis starts at the wall (no start offset or wall legs)".into(),
        ));
    }
    let stolt = Stolt::new(&g);
    let h = round_trip_spectrum(&g, slab, &stolt.fft, &Steps::none());
    let mut spec = stolt.transform(&g.sample(&c), |_, v| v, &Steps::none());
    spec.par_iter_mut().zip(&h).for_each(|(b, h)| *b *= h);
    // The histograms are [nx][ny][nt] in scan order, the shape of the kept octant.
    stolt
        .fft
        .inverse(&mut spec, [g.nx, g.ny], &mut c.h, &Steps::none());
    Ok(c)
}

/// Spectrum of K ⊛ K (circular) on the padded grid of `fft`.
fn round_trip_spectrum(
    g: &ConfocalGeometry,
    slab: &SlabParams,
    fft: &Fft3,
    steps: &Steps,
) -> Vec<C32> {
    let [nx2, ny2, m2] = fft.dims;
    let k = slab_kernel(g, slab, fft.dims);
    let fill = |ix: usize, iy: usize, line: &mut [f32]| {
        line.copy_from_slice(&k[(ix * ny2 + iy) * m2..][..m2])
    };
    let mut h = fft.forward([nx2, ny2], fill, steps);
    h.par_iter_mut().for_each(|v| *v = *v * *v);
    // |·| as the reference: removes the rounding noise's sign.
    fft.map_real(&mut h, f32::abs, steps);
    h
}

/// K on the padded grid, lateral origin at index 0 (negative offsets wrap), normalised to sum 1.
fn slab_kernel(g: &ConfocalGeometry, slab: &SlabParams, dims: [usize; 3]) -> Vec<f32> {
    let [nx2, ny2, m2] = dims;
    let [dx, dy] = g.spacing();
    let dt = g.ds / SPEED_OF_LIGHT_M_PER_S;
    let offset = |j: usize, n2: usize| {
        if j < n2 / 2 {
            j as f64
        } else {
            j as f64 - n2 as f64
        }
    };
    // In f64 until normalised: the raw values span far more than f32's range.
    let temporal: Vec<(f64, f64)> = (0..m2).map(|t| slab.temporal(t as f64 * dt)).collect();
    let mut k = vec![0.0f64; nx2 * ny2 * m2];
    k.par_chunks_mut(m2).enumerate().for_each(|(i, col)| {
        let rho2 = (offset(i / ny2, nx2) * dx).powi(2) + (offset(i % ny2, ny2) * dy).powi(2);
        for (v, &(a, four_dvt)) in col.iter_mut().zip(&temporal) {
            *v = a * (-rho2 / four_dvt).exp();
        }
    });
    let s = 1.0 / k.iter().sum::<f64>();
    k.into_par_iter().map(|v| (v * s) as f32).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fk::{fk, FkParams};
    use crate::testutil::{add_plane, add_point, assert_plane_depth, axis, confocal};
    use murk_core::DVec3;

    fn native() -> CdtParams {
        CdtParams {
            grid: TimeGrid::Native,
            snr: 1e6,
            ..Default::default()
        }
    }

    #[test]
    fn kernel_is_causal_and_delays_light() {
        let slab = SlabParams::default();
        assert_eq!(slab.transmittance(0.0, 0.0), 0.0);
        // Ballistic-free diffusion: almost nothing in the first 10 ps, the peak after ~100 ps.
        let early = slab.transmittance(0.0, 10e-12);
        let later = slab.transmittance(0.0, 200e-12);
        assert!(early < 1e-6 * later, "{early} vs {later}");
        assert!(slab.transmittance(0.05, 200e-12) < later);
    }

    #[test]
    fn point_behind_the_slab_is_restored_where_fk_alone_sees_it_too_deep() {
        // Scan point (8, 8) of 16² over 0.64 m is at (0.02, 0.02); z = 0.3 m is depth index 60.
        let mut c = confocal(16, 0.64, axis(0.0, 0.01, 128));
        add_point(&mut c, DVec3::new(0.02, 0.02, 0.3));
        let c = through_slab(&c, &SlabParams::default()).unwrap();
        let r = cdt(&c, native()).unwrap();
        let [ix, iy, k] = r.argmax();
        assert!(
            ix.abs_diff(8) <= 1 && iy.abs_diff(8) <= 1 && k.abs_diff(60) <= 1,
            "{:?}",
            r.argmax()
        );
        let k_fk = fk(&c, FkParams::default()).unwrap().argmax()[2];
        assert!(k_fk >= 65, "f-k without deconvolution: depth index {k_fk}");
    }

    #[test]
    fn plane_behind_the_slab_comes_out_at_its_depth() {
        // 192 bins hold the whole blurred transient: a window that cuts it off leaves a step that
        // the deconvolution turns into ringing at the far end of the volume.
        let mut c = confocal(16, 0.64, axis(0.0, 0.01, 192));
        add_plane(&mut c, 0.3, 0.48, 24);
        let r = cdt(&through_slab(&c, &SlabParams::default()).unwrap(), native()).unwrap();
        assert_plane_depth(&r, 60, 4);
    }
}
