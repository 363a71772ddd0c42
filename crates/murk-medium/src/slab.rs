//! A foam slab's μa and μs′ from transmission captures through slabs of several thicknesses (the
//! CDT calibration of Lindell & Wetzstein 2020): the diffusion model of a slab's time-resolved
//! transmittance (extrapolated boundaries, image dipoles: murk-baselines' [`SlabParams`]),
//! convolved with the measured laser response without the slab, fitted to every capture at once by
//! a grid search whose posterior gives each parameter and its uncertainty.
//!
//! Time zero is the hardware's: without the slab the laser pulse crosses the slab's place in air,
//! so light enters the slab's front face `d / c` before the direct capture's pulse arrives. Each
//! capture has its own amplitude (the exposures differ) and a background, measured before the
//! laser's pulse; n is fixed (it sets the speed inside and the boundary's reflectance).

use murk_baselines::SlabParams;
use murk_core::{Error, Progress, Result, SPEED_OF_LIGHT_M_PER_S};
use rayon::prelude::*;
use realfft::num_complex::Complex;
use realfft::RealFftPlanner;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::fit::Parameter;
use crate::posterior;

const INCH_M: f64 = 0.0254;
/// About how many times the slab's series is evaluated over a capture's bins.
const SAMPLES_PER_CAPTURE: usize = 160;

/// One histogram of the calibration folder.
#[derive(Clone, Debug)]
pub struct Histogram {
    pub file: PathBuf,
    /// Photon counts per bin.
    pub counts: Vec<f64>,
}

/// A transmission capture through a slab.
#[derive(Clone, Debug)]
pub struct SlabCapture {
    pub thickness_m: f64,
    pub histogram: Histogram,
}

/// The calibration captures: the laser's response without a slab and one capture per thickness,
/// all on the same time bins.
#[derive(Clone, Debug)]
pub struct Calibration {
    pub bin_s: f64,
    pub direct: Histogram,
    pub slabs: Vec<SlabCapture>,
}

/// The CDT calibration's bin width (its PicoQuant header: Binning = 1).
pub const CDT_BIN_S: f64 = 8e-12;

/// Reads a CDT calibration folder: `capture_direct.mat` and `capture_<a>_<b>_inch.mat` (a slab
/// a.b inches thick), each with the summed histogram `out`.
pub fn read_calibration(dir: &Path) -> Result<Calibration> {
    let entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
    let mut slabs = Vec::new();
    for entry in entries {
        let path = entry.map_err(|e| Error::io(dir, e))?.path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if let Some(inches) = name
            .strip_prefix("capture_")
            .and_then(|s| s.strip_suffix("_inch.mat"))
        {
            let inches: f64 = inches.replacen('_', ".", 1).parse().map_err(|_| {
                Error::format(
                    &path,
                    "expected capture_<a>_<b>_inch.mat, a thickness in inches",
                )
            })?;
            slabs.push(SlabCapture {
                thickness_m: inches * INCH_M,
                histogram: read_histogram(&path)?,
            });
        }
    }
    let direct_path = dir.join("capture_direct.mat");
    if !direct_path.exists() {
        return Err(Error::format(
            &direct_path,
            "missing: the laser's response without a slab is needed",
        ));
    }
    let direct = read_histogram(&direct_path)?;
    if slabs.is_empty() {
        return Err(Error::format(
            dir,
            "no slab captures (capture_<a>_<b>_inch.mat) in this folder",
        ));
    }
    slabs.sort_by(|a, b| a.thickness_m.total_cmp(&b.thickness_m));
    let cal = Calibration {
        bin_s: CDT_BIN_S,
        direct,
        slabs,
    };
    cal.validate()?;
    Ok(cal)
}

/// A histogram `out`: one column of counts.
fn read_histogram(path: &Path) -> Result<Histogram> {
    let (shape, values) = murk_io::ArrayFile::open(path)?.require(path, "out")?;
    if shape.iter().filter(|&&n| n > 1).count() != 1 {
        return Err(Error::format(
            path,
            format!("'out' has shape {shape:?}: expected one histogram (a single column)"),
        ));
    }
    Ok(Histogram {
        file: path.to_path_buf(),
        counts: values.iter().map(|&v| v as f64).collect(),
    })
}

impl Calibration {
    /// Every histogram finite, non-negative and as long as the direct one.
    pub fn validate(&self) -> Result<()> {
        let len = self.direct.counts.len();
        for h in std::iter::once(&self.direct).chain(self.slabs.iter().map(|s| &s.histogram)) {
            if let Some(i) = h.counts.iter().position(|v| !v.is_finite() || *v < 0.0) {
                return Err(Error::format(
                    &h.file,
                    format!(
                        "bin {i} holds {}: counts must be finite and ≥ 0",
                        h.counts[i]
                    ),
                ));
            }
            if h.counts.len() != len {
                return Err(Error::format(
                    &h.file,
                    format!("{} bins where the direct capture has {len}", h.counts.len()),
                ));
            }
        }
        Ok(())
    }
}

/// What is fitted and how.
#[derive(Clone, Debug, PartialEq)]
pub struct SlabOptions {
    /// Refractive index of the slab (the CDT paper's foam: 1.12).
    pub n: f64,
    /// The thicknesses (m) to fit; empty: all.
    pub thicknesses_m: Vec<f64>,
    /// Each capture's bins from where its signal first exceeds this share of its peak to where it
    /// last does.
    pub level: f64,
    /// Searched ranges: μa (1/m, linear) and μs′ (1/m, logarithmic).
    pub mu_a_range: (f64, f64),
    pub mu_s_prime_range: (f64, f64),
}

impl Default for SlabOptions {
    fn default() -> SlabOptions {
        SlabOptions {
            n: 1.12,
            thicknesses_m: Vec::new(),
            level: 0.01,
            mu_a_range: (0.0, 10.0),
            mu_s_prime_range: (20.0, 2000.0),
        }
    }
}

/// How one capture was fitted.
#[derive(Clone, Debug, PartialEq)]
pub struct CaptureFit {
    pub file: PathBuf,
    pub thickness_m: f64,
    /// The bins used, [first, last).
    pub bins: (usize, usize),
    pub background: f64,
    /// Counts per unit of the model (the capture's exposure and coupling).
    pub amplitude: f64,
    /// RMS of data − model over the bins used, as a share of the capture's peak.
    pub residual_rms_of_peak: f64,
}

/// The fit's answer.
#[derive(Clone, Debug, PartialEq)]
pub struct SlabEstimate {
    pub mu_a_per_m: Parameter,
    pub mu_s_prime_per_m: Parameter,
    pub n: f64,
    /// The extrapolation length used (from n and μs′, Zhu, Pine & Weitz 1991).
    pub ze_m: f64,
    pub captures: Vec<CaptureFit>,
    /// RMS over all bins used of (data − model) / √counts: 1 for a model as good as photon noise.
    pub reduced_chi: f64,
    /// RMS over all bins used of (data − model) as a share of each capture's peak.
    pub residual_rms_of_peak: f64,
    pub bins_used: usize,
    pub grid_points: usize,
}

impl SlabEstimate {
    /// One JSON object (the keys `murk medium --slab-transmission --json` documents).
    pub fn to_json(&self) -> String {
        let captures: Vec<serde_json::Value> = self
            .captures
            .iter()
            .map(|c| {
                serde_json::json!({
                    "file": c.file.display().to_string(),
                    "thickness_m": c.thickness_m,
                    "first_bin": c.bins.0,
                    "end_bin": c.bins.1,
                    "background": c.background,
                    "residual_rms_of_peak": c.residual_rms_of_peak,
                })
            })
            .collect();
        serde_json::json!({
            "mu_a_per_m": self.mu_a_per_m.value,
            "mu_a_per_m_uncertainty": self.mu_a_per_m.uncertainty,
            "mu_s_prime_per_m": self.mu_s_prime_per_m.value,
            "mu_s_prime_per_m_uncertainty": self.mu_s_prime_per_m.uncertainty,
            "n": self.n,
            "ze_m": self.ze_m,
            "reduced_chi": self.reduced_chi,
            "residual_rms_of_peak": self.residual_rms_of_peak,
            "bins_used": self.bins_used,
            "grid_points": self.grid_points,
            "captures": captures,
        })
        .to_string()
    }

    /// Rows for a summary.
    pub fn rows(&self) -> Vec<(String, String)> {
        let p = |q: &Parameter, unit: &str| {
            format!(
                "{} ± {} {unit}{}",
                murk_core::short(q.value),
                murk_core::short(q.uncertainty),
                if q.constrained {
                    ""
                } else {
                    " (not constrained by these captures)"
                }
            )
        };
        let mut rows = vec![
            ("mu_a".into(), p(&self.mu_a_per_m, "/m")),
            ("mu_s_prime".into(), p(&self.mu_s_prime_per_m, "/m")),
            (
                "n".into(),
                format!(
                    "{} (given); extrapolation length {:.2} mm",
                    murk_core::short(self.n),
                    1e3 * self.ze_m
                ),
            ),
            (
                "fit".into(),
                format!(
                    "residual {:.1} % of each capture's peak (rms over {} bins); {:.1}× photon noise",
                    100.0 * self.residual_rms_of_peak,
                    self.bins_used,
                    self.reduced_chi
                ),
            ),
        ];
        for c in &self.captures {
            rows.push((
                format!("{:.1} inch", c.thickness_m / INCH_M),
                format!(
                    "bins {}–{}, residual {:.1} % of peak ({})",
                    c.bins.0,
                    c.bins.1 - 1,
                    100.0 * c.residual_rms_of_peak,
                    c.file
                        .file_name()
                        .map(|f| f.to_string_lossy())
                        .unwrap_or_default()
                ),
            ));
        }
        rows
    }
}

/// The extrapolation length (m) of a diffusing medium of index `n` in air: ze = 2/(3μs′)·(1 +
/// R)/(1 − R), with R the diffuse internal reflectance of Zhu, Pine & Weitz (1991).
pub fn extrapolation_length_m(n: f64, mu_s_prime_per_m: f64) -> f64 {
    2.0 / (3.0 * mu_s_prime_per_m) * boundary_factor(n)
}

/// (1 + R)/(1 − R) with R = (3c₂ + 2c₁)/(3c₂ − 2c₁ + 2) from the Fresnel moments
/// cₖ = ∫₀^{π/2} R_F(θ) sin θ cosᵏθ dθ of light leaving a medium of index `n` into air.
fn boundary_factor(n: f64) -> f64 {
    // Midpoint rule: the integrands are smooth but for the kink at the critical angle, which
    // 20 000 steps resolve to better than 1e-7 of R.
    let steps = 20_000;
    let h = std::f64::consts::FRAC_PI_2 / steps as f64;
    let (mut c1, mut c2) = (0.0, 0.0);
    for k in 0..steps {
        let theta = (k as f64 + 0.5) * h;
        let r = fresnel_from_inside(n, theta);
        c1 += r * theta.sin() * theta.cos() * h;
        c2 += r * theta.sin() * theta.cos().powi(2) * h;
    }
    let r = (3.0 * c2 + 2.0 * c1) / (3.0 * c2 - 2.0 * c1 + 2.0);
    (1.0 + r) / (1.0 - r)
}

/// Unpolarised Fresnel reflectance for light inside a medium of index `n` meeting air at `theta`.
fn fresnel_from_inside(n: f64, theta: f64) -> f64 {
    let sin_t = n * theta.sin();
    if sin_t >= 1.0 {
        return 1.0;
    }
    let (ci, ct) = (theta.cos(), (1.0 - sin_t * sin_t).sqrt());
    let rs = ((n * ci - ct) / (n * ci + ct)).powi(2);
    let rp = ((n * ct - ci) / (n * ct + ci)).powi(2);
    0.5 * (rs + rp)
}

/// The background: the median of the bins more than 15 ns before the direct pulse's onset (the
/// laser has a weak pre-pulse 13 ns before its main one, which the slabs spread out).
fn background(counts: &[f64], onset: usize, bin_s: f64) -> Option<f64> {
    let end = onset.checked_sub((15e-9 / bin_s).round() as usize)?;
    let mut v: Vec<f64> = counts[..end].iter().copied().filter(|&c| c > 0.0).collect();
    if v.len() < 100 {
        return None;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    Some(v[v.len() / 2])
}

fn peak(values: &[f64]) -> (usize, f64) {
    values
        .iter()
        .enumerate()
        .fold((0, f64::MIN), |a, (i, &v)| if v > a.1 { (i, v) } else { a })
}

/// The laser's response without the slab, background removed, normalised to unit sum: from
/// its first bin above 1 % of its peak to where it last exceeds 1e-4 of it (its slow tail).
struct Irf {
    first: usize,
    values: Vec<f64>,
}

impl Irf {
    fn measure(direct: &Histogram, bin_s: f64) -> Result<Irf> {
        let c = &direct.counts;
        let (p, top) = peak(c);
        let onset = c.iter().position(|&v| v > 0.01 * top).unwrap_or(p);
        let bg = background(c, onset, bin_s).ok_or_else(|| {
            Error::format(
                &direct.file,
                "the pulse comes less than 15 ns after the histogram's start: no background bins before it",
            )
        })?;
        let net: Vec<f64> = c.iter().map(|v| v - bg).collect();
        let height = net[p];
        if height < 100.0 * bg.max(1.0).sqrt() {
            return Err(Error::format(
                &direct.file,
                "no laser pulse above the background's noise",
            ));
        }
        let first = net.iter().position(|&v| v > 0.01 * height).unwrap_or(p);
        let last = net.iter().rposition(|&v| v > 1e-4 * height).unwrap_or(p);
        let values: Vec<f64> = net[first..=last].iter().map(|v| v.max(0.0)).collect();
        let total: f64 = values.iter().sum();
        Ok(Irf {
            first,
            values: values.iter().map(|v| v / total).collect(),
        })
    }
}

/// A capture ready to fit: its bins, their noise, and the FFT of the laser response at the size
/// its convolution needs.
struct Prepared {
    file: PathBuf,
    thickness_m: f64,
    first: usize,
    data: Vec<f64>,
    weight: Vec<f64>,
    background: f64,
    peak: f64,
    /// Model index u (time u·bin + d/c after the direct pulse's first bin) of the first sample.
    u0: i64,
    /// Bins between evaluations of the slab's series.
    step: usize,
    fft_len: usize,
    irf_spectrum: Vec<Complex<f64>>,
    fft: Arc<dyn realfft::RealToComplex<f64>>,
    ifft: Arc<dyn realfft::ComplexToReal<f64>>,
}

struct Problem {
    bin_s: f64,
    n: f64,
    /// ze·μs′ for this n.
    ze_times_mu_s_prime: f64,
    captures: Vec<Prepared>,
    irf_len: usize,
}

impl Problem {
    fn new(cal: &Calibration, opt: &SlabOptions) -> Result<Problem> {
        cal.validate()?;
        let irf = Irf::measure(&cal.direct, cal.bin_s)?;
        let chosen: Vec<&SlabCapture> = cal
            .slabs
            .iter()
            .filter(|s| {
                opt.thicknesses_m.is_empty()
                    || opt
                        .thicknesses_m
                        .iter()
                        .any(|&t| (t - s.thickness_m).abs() < 1e-4)
            })
            .collect();
        if chosen.is_empty() {
            return Err(Error::param(
                "none of the chosen thicknesses has a capture in the folder",
            ));
        }
        let l = irf.values.len();
        let mut planner = RealFftPlanner::<f64>::new();
        let mut prepared = Vec::new();
        for s in chosen {
            let h = &s.histogram;
            let bg = background(&h.counts, irf.first, cal.bin_s).ok_or_else(|| {
                Error::format(&h.file, "no background bins 15 ns before the laser's pulse")
            })?;
            let net: Vec<f64> = h.counts.iter().map(|v| v - bg).collect();
            let (p, height) = peak(&net[irf.first..]);
            let p = p + irf.first;
            if height < 20.0 * bg.max(1.0).sqrt() {
                return Err(Error::format(
                    &h.file,
                    "no transmitted pulse above the background's noise",
                ));
            }
            let th = opt.level * height;
            let first = (irf.first..p).find(|&i| net[i] > th).unwrap_or(p);
            let last = (p..net.len()).rev().find(|&i| net[i] > th).unwrap_or(p) + 1;
            let data = net[first..last].to_vec();
            let weight = h.counts[first..last]
                .iter()
                .map(|&c| 1.0 / c.max(1.0))
                .collect();
            // model(i) = Σ_k irf[k]·K((i − irf.first − k)·bin + d/c): u = i − irf.first − k.
            let u0 = first as i64 - irf.first as i64 - (l as i64 - 1);
            let fft_len = (data.len() + l - 1).next_power_of_two();
            let fft = planner.plan_fft_forward(fft_len);
            let ifft = planner.plan_fft_inverse(fft_len);
            let mut buf = vec![0.0; fft_len];
            buf[..l].copy_from_slice(&irf.values);
            let mut irf_spectrum = fft.make_output_vec();
            fft.process(&mut buf, &mut irf_spectrum)
                .map_err(|e| Error::param(format!("FFT: {e}")))?;
            let step = (data.len() / SAMPLES_PER_CAPTURE).max(1);
            prepared.push(Prepared {
                file: h.file.clone(),
                thickness_m: s.thickness_m,
                first,
                data,
                weight,
                background: bg,
                peak: height,
                u0,
                step,
                fft_len,
                irf_spectrum,
                fft,
                ifft,
            });
        }
        Ok(Problem {
            bin_s: cal.bin_s,
            n: opt.n,
            ze_times_mu_s_prime: 2.0 / 3.0 * boundary_factor(opt.n),
            captures: prepared,
            irf_len: l,
        })
    }

    fn slab(&self, d: f64, mu_a: f64, mu_s_prime: f64) -> SlabParams {
        SlabParams {
            thickness_m: d,
            mu_a_per_m: mu_a,
            mu_s_prime_per_m: mu_s_prime,
            n: self.n,
            ze_m: self.ze_times_mu_s_prime / mu_s_prime,
        }
    }

    /// The model (before its amplitude) over capture `c`'s bins.
    fn model(&self, c: &Prepared, slab: &SlabParams) -> Vec<f64> {
        let mut buf = self.transmittance(c, slab);
        buf.resize(c.fft_len, 0.0);
        let mut spectrum = c.fft.make_output_vec();
        c.fft
            .process(&mut buf, &mut spectrum)
            .expect("FFT sizes are planned");
        for (s, h) in spectrum.iter_mut().zip(&c.irf_spectrum) {
            *s *= h / c.fft_len as f64;
        }
        c.ifft
            .process(&mut spectrum, &mut buf)
            .expect("FFT sizes are planned");
        buf[self.irf_len - 1..self.irf_len - 1 + c.data.len()].to_vec()
    }

    /// The slab's transmittance at the times the convolution for capture `c` needs. The series
    /// is evaluated every `c.step` bins and ln K interpolated between (cubic, Catmull–Rom): a
    /// thick slab's response is smooth over many bins, and its 41 image dipoles per sample are
    /// the fit's whole cost.
    fn transmittance(&self, c: &Prepared, slab: &SlabParams) -> Vec<f64> {
        let m = c.data.len() + self.irf_len - 1;
        let air_s = c.thickness_m / SPEED_OF_LIGHT_M_PER_S;
        let t = |j: i64| (c.u0 + j) as f64 * self.bin_s + air_s;
        let mut out = vec![0.0; m];
        let Some(start) = (0..m as i64).find(|&j| t(j) > 0.0) else {
            return out;
        };
        let r = c.step as i64;
        let nodes = (m as i64 - start) / r + 3;
        let ln_k: Vec<f64> = (0..nodes)
            .map(|q| slab.transmittance(0.0, t(start + q * r)).max(0.0).ln())
            .collect();
        let k = |v: f64| if v.is_finite() { v.exp() } else { 0.0 };
        // Below e^-20 of the peak the cubic can overshoot on ln K's steep rise (−z²/4Dvt):
        // linear there.
        let steep = ln_k.iter().copied().fold(f64::NEG_INFINITY, f64::max) - 20.0;
        for (j, o) in out.iter_mut().enumerate().skip(start as usize) {
            let x = (j as i64 - start) as f64 / r as f64;
            let q = x.floor() as usize;
            let f = x - q as f64;
            if f == 0.0 {
                *o = k(ln_k[q]);
                continue;
            }
            let p1 = ln_k[q];
            let p2 = ln_k[q + 1];
            let p0 = if q > 0 { ln_k[q - 1] } else { 2.0 * p1 - p2 };
            let p3 = ln_k[q + 2];
            *o = if [p0, p1, p2, p3].iter().all(|&v| v > steep) {
                k(p1 + 0.5
                    * f
                    * (p2 - p0
                        + f * (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3
                            + f * (3.0 * (p1 - p2) + p3 - p0))))
            } else {
                k((1.0 - f) * p1 + f * p2)
            };
        }
        out
    }

    /// The best amplitude of `model` for capture `c` and the weighted sum of squares left.
    fn amplitude(c: &Prepared, model: &[f64]) -> (f64, f64) {
        let (mut dm, mut mm) = (0.0, 0.0);
        for ((d, m), w) in c.data.iter().zip(model).zip(&c.weight) {
            dm += w * d * m;
            mm += w * m * m;
        }
        if mm.is_nan() || mm <= 0.0 {
            let ssr = c.data.iter().zip(&c.weight).map(|(d, w)| w * d * d).sum();
            return (0.0, ssr);
        }
        let a = dm / mm;
        let ssr = c
            .data
            .iter()
            .zip(model)
            .zip(&c.weight)
            .map(|((d, m), w)| w * (d - a * m).powi(2))
            .sum();
        (a, ssr)
    }

    /// Σ over captures of the weighted sum of squares at (μa, μs′).
    fn ssr(&self, mu_a: f64, mu_s_prime: f64) -> f64 {
        self.captures
            .iter()
            .map(|c| {
                let model = self.model(c, &self.slab(c.thickness_m, mu_a, mu_s_prime));
                Self::amplitude(c, &model).1
            })
            .sum()
    }
}

/// The posterior's mean and standard deviation along (μa, ln μs′).
struct Summary {
    mean: [f64; 2],
    sd: [f64; 2],
}

impl Problem {
    /// The weighted residuals (data − model)·√weight at (μa, μs′), capture after capture.
    fn residuals(&self, mu_a: f64, mu_s_prime: f64) -> Vec<f64> {
        let mut out = Vec::new();
        for c in &self.captures {
            let model = self.model(c, &self.slab(c.thickness_m, mu_a, mu_s_prime));
            let (a, _) = Self::amplitude(c, &model);
            out.extend(
                c.data
                    .iter()
                    .zip(&model)
                    .zip(&c.weight)
                    .map(|((d, m), w)| (d - a * m) * w.sqrt()),
            );
        }
        out
    }

    /// The posterior over `nodes` (μa, ln μs′) from their sums of squares; the residual's
    /// correlation between neighbouring bins (model error is smooth in time) sets how many
    /// independent values the bins are worth.
    fn posterior(&self, nodes: &[(f64, f64)], ssr: &[f64]) -> Result<Summary> {
        let (best, _) = ssr
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1))
            .ok_or_else(|| Error::param("an empty grid"))?;
        let residual = self.residuals(nodes[best].0, nodes[best].1.exp());
        let mut starts = Vec::new();
        let mut at = 0;
        for c in &self.captures {
            starts.push(at);
            at += c.data.len();
        }
        let rho = posterior::lag_one_correlation(&residual, |k| !starts.contains(&k));
        let w = posterior::weights(ssr, posterior::effective_count(residual.len(), rho))?;
        let (ma, sa) = posterior::moments(&w, |i| nodes[i].0);
        let (ms, ss) = posterior::moments(&w, |i| nodes[i].1);
        Ok(Summary {
            mean: [ma, ms],
            sd: [sa, ss],
        })
    }
}

/// Nodes per axis of each level of the grid search.
const NODES: usize = 13;
/// Levels of zoom: each centres a finer grid on the last one's posterior.
const LEVELS: usize = 10;

/// Fits μa and μs′ to the calibration captures. `progress` counts grid levels.
pub fn fit_slab(
    cal: &Calibration,
    opt: &SlabOptions,
    progress: &dyn Progress,
) -> Result<SlabEstimate> {
    if !(opt.n >= 1.0 && opt.n <= 4.0) {
        return Err(Error::param(format!(
            "slab refractive index {} is outside 1–4",
            opt.n
        )));
    }
    let (a, s) = (opt.mu_a_range, opt.mu_s_prime_range);
    if !(opt.level > 0.0 && opt.level < 1.0 && a.0 >= 0.0 && a.1 > a.0 && s.0 > 0.0 && s.1 > s.0) {
        return Err(Error::param(format!(
            "slab fit: level {} must lie in (0, 1), μa range {a:?} in [0, ∞), μs′ range {s:?} in (0, ∞), each increasing",
            opt.level
        )));
    }
    let problem = Problem::new(cal, opt)?;
    let bins_used: usize = problem.captures.iter().map(|c| c.data.len()).sum();
    // Grid axes: μa linear, ln μs′.
    let full = [
        opt.mu_a_range,
        (opt.mu_s_prime_range.0.ln(), opt.mu_s_prime_range.1.ln()),
    ];
    let mut bounds = full;
    let mut grid_points = 0;
    let mut post = None;
    progress.start(LEVELS as u64);
    for _ in 0..LEVELS {
        let axis = |(lo, hi): (f64, f64)| -> Vec<f64> {
            (0..NODES)
                .map(|k| lo + (hi - lo) * k as f64 / (NODES - 1) as f64)
                .collect()
        };
        let (xa, xs) = (axis(bounds[0]), axis(bounds[1]));
        let nodes: Vec<(f64, f64)> = xa
            .iter()
            .flat_map(|&a| xs.iter().map(move |&s| (a, s)))
            .collect();
        let ssr: Vec<f64> = nodes
            .par_iter()
            .map(|&(a, ls)| problem.ssr(a, ls.exp()))
            .collect();
        grid_points += nodes.len();
        let p = problem.posterior(&nodes, &ssr)?;
        progress.advance(1);
        let steps = [
            (bounds[0].1 - bounds[0].0) / (NODES - 1) as f64,
            (bounds[1].1 - bounds[1].0) / (NODES - 1) as f64,
        ];
        // Resolved: the posterior spans several nodes (±4σ at 13 nodes is 0.67σ a step).
        let resolved = (0..2).all(|k| steps[k] < 0.7 * p.sd[k]);
        post = Some(p);
        let p = post.as_ref().expect("just set");
        if resolved {
            break;
        }
        // The next level: ±4 standard deviations, at least ±1.5 of this level's steps.
        for k in 0..2 {
            let half = (4.0 * p.sd[k]).max(1.5 * steps[k]);
            bounds[k] = (
                (p.mean[k] - half).max(full[k].0),
                (p.mean[k] + half).min(full[k].1),
            );
        }
    }
    let p = post.ok_or_else(|| Error::param("no grid level ran"))?;
    let span = |k: usize| full[k].1 - full[k].0;
    let mu_a = Parameter {
        value: p.mean[0],
        uncertainty: p.sd[0],
        fitted: true,
        constrained: p.sd[0] < span(0) / 6.0,
    };
    let mu_s = p.mean[1].exp();
    let mu_s_prime = Parameter {
        value: mu_s,
        uncertainty: mu_s * p.sd[1],
        fitted: true,
        constrained: p.sd[1] < span(1) / 6.0,
    };
    // The residuals at the posterior mean.
    let (mut chi2, mut rel2) = (0.0, 0.0);
    let mut captures = Vec::new();
    for c in &problem.captures {
        let model = problem.model(c, &problem.slab(c.thickness_m, mu_a.value, mu_s));
        let (amp, _) = Problem::amplitude(c, &model);
        let mut r2 = 0.0;
        for ((d, m), w) in c.data.iter().zip(&model).zip(&c.weight) {
            let r = d - amp * m;
            chi2 += w * r * r;
            r2 += (r / c.peak).powi(2);
        }
        rel2 += r2;
        captures.push(CaptureFit {
            file: c.file.clone(),
            thickness_m: c.thickness_m,
            bins: (c.first, c.first + c.data.len()),
            background: c.background,
            amplitude: amp,
            residual_rms_of_peak: (r2 / c.data.len() as f64).sqrt(),
        });
    }
    Ok(SlabEstimate {
        mu_a_per_m: mu_a,
        mu_s_prime_per_m: mu_s_prime,
        n: opt.n,
        ze_m: extrapolation_length_m(opt.n, mu_s),
        captures,
        reduced_chi: (chi2 / bins_used as f64).sqrt(),
        residual_rms_of_peak: (rel2 / bins_used as f64).sqrt(),
        bins_used,
        grid_points,
    })
}

#[cfg(test)]
mod tests;
