//! Analytic forward model: the first hidden bounce only, exact geometry, no Monte Carlo noise.
//!
//! H(x_l → x_s, s) = Σ_k w_k · δ(s − (e_l + d_lk + d_ks + e_s)), with
//! w_k = ρ_k·A_k / (d_lk² d_ks²) · \[cosines\] · \[exp(−μt (d_lk + d_ks))\]. Each delta is deposited with
//! a linear splat between the two nearest bin centres (bin n represents path start + (n + ½)·Δs), which
//! keeps its first moment exactly, or with a Gaussian jitter integrated over the bin edges.
//! This is the oracle the reconstruction tests use and what `murk synth` and `murk demo` build.
//!
//! ```
//! use murk_core::{DVec3, TimeAxis};
//! use murk_synth::{add_first_bounce, CaptureLayout, LayoutKind, SynthOptions, Target};
//!
//! // A confocal scan (8² points over a 1 m wall, 1 cm bins) of one point 0.5 m behind the wall.
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
//! // The brightest bin holds the shortest round trip: 2 × 0.508 m from the four central points.
//! let brightest = (0..cap.h.len()).max_by(|&a, &b| cap.h[a].total_cmp(&cap.h[b])).unwrap();
//! let path_m = cap.time.start_m + (brightest % cap.time.bins) as f64 * cap.time.bin_width_m;
//! assert!((path_m - 1.0156).abs() < 0.01, "{path_m}");
//! # Ok::<(), murk_core::Error>(())
//! ```

mod layout;
mod request;
mod targets;
pub mod testutil;

pub use layout::{CaptureLayout, LayoutKind};
pub use request::{floats, synthesize, Synthesis};
pub use targets::{t_letter_outline, z_letter_outline, Scatterer, Target};

use murk_core::{Capture, DVec3, Error, Result};
use rayon::prelude::*;

/// Physical options of the forward model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SynthOptions {
    /// Lambertian cosines at the wall points and at the hidden surface (point targets have none).
    pub cosines: bool,
    /// Extinction of a homogeneous medium filling the hidden side (1/m); ballistic light only.
    pub mu_t_per_m: f64,
    /// Standard deviation of a Gaussian timing jitter (metres of path); 0 = linear splat.
    pub jitter_sigma_m: f64,
}

impl Default for SynthOptions {
    fn default() -> Self {
        SynthOptions {
            cosines: false,
            mu_t_per_m: 0.0,
            jitter_sigma_m: 0.0,
        }
    }
}

/// Adds the first-bounce response of `scatterers` into `cap.h` (which must already have the right size).
pub fn add_first_bounce(
    cap: &mut Capture,
    scatterers: &[Scatterer],
    opts: &SynthOptions,
) -> Result<()> {
    murk_core::Limits::extinction(opts.mu_t_per_m).map_err(|e| Error::param(format!("μt {e}")))?;
    if opts.jitter_sigma_m.is_nan() || opts.jitter_sigma_m < 0.0 {
        return Err(Error::param(format!(
            "jitter must be ≥ 0 m, got {}",
            opts.jitter_sigma_m
        )));
    }
    murk_core::Limits::get().length("the jitter", opts.jitter_sigma_m)?;
    let nt = cap.time.bins;
    if cap.h.len() != cap.n_hist() * nt {
        return Err(Error::param(
            "capture H has the wrong size for its point sets",
        ));
    }
    let time = cap.time;
    let (illum, sensor) = (&cap.illum, &cap.sensor);
    let e_l: Vec<f64> = (0..illum.len()).map(|l| cap.first_bounce_m(l)).collect();
    let e_s: Vec<f64> = (0..sensor.len()).map(|s| cap.last_bounce_m(s)).collect();
    let pairs: Vec<(usize, usize)> = (0..cap.n_hist()).map(|i| cap.hist_pair(i)).collect();
    cap.h
        .par_chunks_mut(nt)
        .zip(pairs.par_iter())
        .for_each(|(hist, &(l, s))| {
            let (xl, nl) = (illum.points[l], illum.normals[l]);
            let (xs, ns) = (sensor.points[s], sensor.normals[s]);
            for sc in scatterers {
                let (vl, vs) = (sc.pos - xl, sc.pos - xs);
                let (dl, ds) = (vl.length(), vs.length());
                if dl <= 0.0 || ds <= 0.0 {
                    continue;
                }
                let mut w = sc.weight / (dl * dl * ds * ds);
                if opts.cosines {
                    w *= lambert(nl, vl / dl) * lambert(ns, vs / ds);
                    if let Some(n) = sc.normal {
                        w *= lambert(n, -vl / dl) * lambert(n, -vs / ds) / std::f64::consts::PI;
                    }
                }
                if opts.mu_t_per_m > 0.0 {
                    w *= (-opts.mu_t_per_m * (dl + ds)).exp();
                }
                if w == 0.0 {
                    continue;
                }
                let path = e_l[l] + dl + ds + e_s[s];
                deposit(hist, &time, path, w, opts.jitter_sigma_m);
            }
        });
    Ok(())
}

fn lambert(normal: DVec3, dir: DVec3) -> f64 {
    normal.dot(dir).max(0.0)
}

fn deposit(hist: &mut [f32], time: &murk_core::TimeAxis, path: f64, w: f64, jitter: f64) {
    let nt = hist.len() as isize;
    if jitter > 0.0 {
        // Integrate the Gaussian over bin edges [start + nΔs, start + (n+1)Δs) within ±5σ.
        let lo = ((path - 5.0 * jitter - time.start_m) / time.bin_width_m).floor() as isize;
        let hi = ((path + 5.0 * jitter - time.start_m) / time.bin_width_m).floor() as isize;
        let cdf = |x: f64| 0.5 * (1.0 + erf((x - path) / (jitter * std::f64::consts::SQRT_2)));
        for n in lo.max(0)..=hi.min(nt - 1) {
            let a = time.start_m + n as f64 * time.bin_width_m;
            // A bin's share is never negative, even where erf's rounding is not monotonic.
            hist[n as usize] += (w * (cdf(a + time.bin_width_m) - cdf(a)).max(0.0)) as f32;
        }
        return;
    }
    let u = (path - time.start_m) / time.bin_width_m - 0.5;
    let n0 = u.floor();
    let frac = u - n0;
    let n0 = n0 as isize;
    if (0..nt).contains(&n0) {
        hist[n0 as usize] += (w * (1.0 - frac)) as f32;
    }
    if (0..nt).contains(&(n0 + 1)) {
        hist[(n0 + 1) as usize] += (w * frac) as f32;
    }
}

/// Error function from the Chebyshev-fitted erfc of Numerical Recipes (relative error < 1.2e-7),
/// accurate enough that bin masses sum to 1 within 1e-6.
fn erf(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    // Horner form of the fit's polynomial in t (a flat loop: nested parentheses make rustfmt crawl).
    const C: [f64; 10] = [
        -1.265_512_23,
        1.000_023_68,
        0.374_091_96,
        0.096_784_18,
        -0.186_288_06,
        0.278_868_07,
        -1.135_203_98,
        1.488_515_87,
        -0.822_152_23,
        0.170_872_77,
    ];
    let poly = C.iter().rev().fold(0.0, |acc, c| acc * t + c);
    let r = t * (-z * z + poly).exp();
    if x >= 0.0 {
        1.0 - r
    } else {
        r - 1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use murk_core::TimeAxis;

    #[test]
    fn linear_splat_keeps_first_moment() {
        let time = TimeAxis {
            start_m: 0.1,
            bin_width_m: 0.01,
            bins: 100,
        };
        let mut h = vec![0f32; 100];
        let path = 0.5234;
        deposit(&mut h, &time, path, 2.0, 0.0);
        let sum: f64 = h.iter().map(|&v| v as f64).sum();
        let mean: f64 = h
            .iter()
            .enumerate()
            .map(|(n, &v)| v as f64 * (0.1 + (n as f64 + 0.5) * 0.01))
            .sum::<f64>()
            / sum;
        assert!((sum - 2.0).abs() < 1e-6);
        assert!((mean - path).abs() < 1e-7, "{mean}");
    }

    #[test]
    fn jitter_conserves_mass_and_mean() {
        let time = TimeAxis {
            start_m: 0.0,
            bin_width_m: 0.003,
            bins: 400,
        };
        let mut h = vec![0f32; 400];
        deposit(&mut h, &time, 0.6001, 1.0, 0.01);
        let sum: f64 = h.iter().map(|&v| v as f64).sum();
        let mean: f64 = h
            .iter()
            .enumerate()
            .map(|(n, &v)| v as f64 * (n as f64 + 0.5) * 0.003)
            .sum::<f64>()
            / sum;
        assert!((sum - 1.0).abs() < 1e-5, "{sum}");
        assert!((mean - 0.6001).abs() < 1e-5, "{mean}");
        assert!((erf(0.5) - 0.520_499_877_8).abs() < 2e-7);
    }
}
