//! Evaluation of a band-limited field sampled on the wall's lattice at arbitrary positions along one axis.
//! Aligned positions read one sample; others use a Kaiser-windowed sinc, or, where the field's band is
//! known and its spectrum can be divided by the kernel's beforehand, a shorter Kaiser–Bessel kernel
//! (the interpolation step of a non-uniform FFT). The field the fast Phasor Fields path produces at a
//! depth plane is band-limited by k·sinθ < π/Δ whenever λ_min > 2Δ, so the interpolation is accurate
//! away from that limit.

use std::f64::consts::PI;

/// Half-width of the windowed sinc in samples (16 taps).
pub const HALF_TAPS: i64 = 8;
/// Kaiser shape: trades main-lobe width (passband droop near Nyquist) for side-lobe leakage.
const KAISER_BETA: f64 = 6.5;

/// For each output position, the first lattice index (relative to `lo`) and the tap weights.
#[derive(Clone, Debug)]
pub struct Resampler {
    /// Lowest lattice index any output reads.
    pub lo: i64,
    /// Number of lattice samples spanned.
    pub len: usize,
    pub starts: Vec<usize>,
    pub taps: usize,
    pub weights: Vec<f32>,
}

impl Resampler {
    /// `positions` in lattice units (lattice sample j sits at position j). On-lattice positions above
    /// `centre` take their taps one sample lower (the extra tap has weight 0 either way), so positions
    /// symmetric about `centre` read a lattice span symmetric about it: the fast Phasor Fields' kernel
    /// support is then symmetric and its spectrum needs about half the FFT work.
    pub fn new(positions: &[f64], centre: f64) -> Resampler {
        Self::with(positions, centre, HALF_TAPS, windowed_sinc)
    }

    /// Weights of `kernel` instead of the windowed sinc: the field read must have had its spectrum
    /// divided by [`KaiserBessel::spectrum`] along this axis.
    pub fn kaiser_bessel(positions: &[f64], centre: f64, kernel: &KaiserBessel) -> Resampler {
        Self::with(positions, centre, kernel.taps as i64 / 2, |t| {
            kernel.value(t)
        })
    }

    fn with(positions: &[f64], centre: f64, half: i64, weight: impl Fn(f64) -> f64) -> Resampler {
        let aligned = positions.iter().all(|t| (t - t.round()).abs() < 1e-6);
        let taps = if aligned { 1 } else { (2 * half) as usize };
        let firsts: Vec<i64> = positions
            .iter()
            .map(|&t| {
                if aligned {
                    t.round() as i64
                } else if t > centre && (t - t.round()).abs() < 1e-9 {
                    t.round() as i64 - half
                } else {
                    t.floor() as i64 - half + 1
                }
            })
            .collect();
        let lo = firsts.iter().copied().min().unwrap_or(0);
        let hi = firsts.iter().copied().max().unwrap_or(0) + taps as i64 - 1;
        let mut weights = Vec::with_capacity(positions.len() * taps);
        for (&t, &f) in positions.iter().zip(&firsts) {
            if aligned {
                weights.push(1.0);
            } else {
                weights.extend((0..taps as i64).map(|k| weight(t - (f + k) as f64) as f32));
            }
        }
        Resampler {
            lo,
            len: (hi - lo + 1) as usize,
            starts: firsts.iter().map(|f| (f - lo) as usize).collect(),
            taps,
            weights,
        }
    }

    pub fn weights_of(&self, out: usize) -> &[f32] {
        &self.weights[out * self.taps..(out + 1) * self.taps]
    }

    /// The same weights with indices relative to `lo` over `len` samples, a span that holds this
    /// resampler's (so that resamplers of several widths read one lattice).
    pub fn rebased(mut self, lo: i64, len: usize) -> Resampler {
        assert!(lo <= self.lo && self.lo + self.len as i64 <= lo + len as i64);
        let shift = (self.lo - lo) as usize;
        self.starts.iter_mut().for_each(|s| *s += shift);
        self.lo = lo;
        self.len = len;
        self
    }
}

/// A Kaiser–Bessel kernel φ of `taps` samples for a field whose spectrum was divided by φ̂: the
/// interpolant Σ g_n·φ(t − n) then has the field's spectrum in its band |ω| ≤ b·π, and only the band's
/// images at |ω| ≥ (2 − b)·π, weighed by φ̂ there against φ̂ in the band, err. Per tap that suppresses
/// far more than a windowed sinc, which must also keep its passband flat: 6 taps alias less at
/// b = 0.65 than 16 sinc taps at b = 0.5.
#[derive(Clone, Debug)]
pub struct KaiserBessel {
    pub taps: usize,
    beta: f64,
    i0_beta: f64,
    /// The widest band fraction b this kernel interpolates within the tolerance it was made for.
    pub band: f64,
}

impl KaiserBessel {
    /// Kernels of 4, 6, … 16 taps, each shaped for the widest band it serves with relative error at
    /// most `tol`: its aliasing plus the f32 rounding of the field's samples, which the division by
    /// φ̂ amplifies by φ̂(0)/φ̂(b·π) (7e5 for 16 taps at b = 0.94). A kernel that serves no band, or no
    /// wider one than a shorter kernel, is left out.
    pub fn family(tol: f64) -> Vec<KaiserBessel> {
        let mut family: Vec<KaiserBessel> = Vec::new();
        let kernels = (2..=8).filter_map(|half| {
            let taps = 2 * half;
            let fits = |b: f64| {
                let k = Self::shaped(taps, b);
                let rounding = f32::EPSILON as f64 * k.spectrum(0.0) / k.spectrum(b * PI);
                k.aliasing(b) + rounding <= tol
            };
            if !fits(0.0) {
                return None;
            }
            let (mut lo, mut hi) = (0.0, 1.0);
            for _ in 0..30 {
                let mid = 0.5 * (lo + hi);
                if fits(mid) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            Some(Self::shaped(taps, lo))
        });
        for kernel in kernels {
            if family.last().is_none_or(|k| kernel.band > k.band) {
                family.push(kernel);
            }
        }
        family
    }

    /// β = π·taps·(1 − b/2) balances the band's edge against its first image (within a few per
    /// cent of the β that minimises the aliasing, searched numerically for 4–12 taps).
    fn shaped(taps: usize, band: f64) -> KaiserBessel {
        let beta = PI * taps as f64 * (1.0 - band / 2.0);
        KaiserBessel {
            taps,
            beta,
            i0_beta: bessel_i0(beta),
            band,
        }
    }

    /// φ(t), t in samples: I0(β√(1 − (2t/taps)²)) / I0(β) inside the support, 0 outside.
    pub fn value(&self, t: f64) -> f64 {
        kaiser(2.0 * t / self.taps as f64, self.beta, self.i0_beta)
    }

    /// φ̂(ω) = ∫ φ(t)·e^{−iωt} dt, ω in radians per sample (real and even).
    pub fn spectrum(&self, omega: f64) -> f64 {
        let w = self.taps as f64;
        let a = self.beta * self.beta - (omega * w / 2.0).powi(2);
        let s = a.abs().sqrt();
        let shape = if s < 1e-9 {
            1.0
        } else if a > 0.0 {
            s.sinh() / s
        } else {
            s.sin() / s
        };
        w * shape / self.i0_beta
    }

    /// Largest Σ_{l≠0} |φ̂(ω + 2πl)| / φ̂(ω) over |ω| ≤ b·π: the error of reading a unit complex
    /// exponential of the band, relative to its amplitude.
    fn aliasing(&self, band: f64) -> f64 {
        (0..=64)
            .map(|i| {
                let omega = band * PI * i as f64 / 64.0;
                let images: f64 = (1..=4)
                    .flat_map(|l| [-1.0, 1.0].map(|s| s * l as f64))
                    .map(|l| self.spectrum(omega + 2.0 * PI * l).abs())
                    .sum();
                images / self.spectrum(omega)
            })
            .fold(0.0, f64::max)
    }
}

fn windowed_sinc(x: f64) -> f64 {
    let sinc = if x.abs() < 1e-12 {
        1.0
    } else {
        (PI * x).sin() / (PI * x)
    };
    sinc * kaiser(x / HALF_TAPS as f64, KAISER_BETA, bessel_i0(KAISER_BETA))
}

/// The Kaiser window I0(β√(1 − u²)) / I0(β) at u (1 at u = 0), zero for |u| ≥ 1; `i0_beta` = I0(β).
fn kaiser(u: f64, beta: f64, i0_beta: f64) -> f64 {
    if u.abs() >= 1.0 {
        return 0.0;
    }
    bessel_i0(beta * (1.0 - u * u).sqrt()) / i0_beta
}

/// Modified Bessel function of the first kind, order 0 (power series: its terms peak near k = x/2, so
/// 200 of them cover the β ≤ 16π of the kernels here).
fn bessel_i0(x: f64) -> f64 {
    let (mut sum, mut term, q) = (1.0, 1.0, x * x / 4.0);
    for k in 1..200 {
        term *= q / (k * k) as f64;
        sum += term;
        if term < sum * 1e-17 {
            break;
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aligned_positions_read_one_sample() {
        let r = Resampler::new(&[3.0, 5.0, 7.0], 5.0);
        assert_eq!((r.lo, r.len, r.taps), (3, 5, 1));
        assert_eq!(r.starts, vec![0, 2, 4]);
    }

    /// Off-lattice positions symmetric about the centre, on-lattice ends included, span a symmetric
    /// range; the shifted end still reads exactly its sample.
    #[test]
    fn symmetric_positions_span_a_symmetric_range() {
        let pos: Vec<f64> = (0..73).map(|i| i as f64 * 127.0 / 72.0).collect();
        let r = Resampler::new(&pos, 63.5);
        assert_eq!(
            2 * r.lo + r.len as i64 - 1,
            127,
            "lo {} len {}",
            r.lo,
            r.len
        );
        let plain = Resampler::new(&pos, f64::INFINITY);
        assert_eq!(plain.len, r.len + 1);
        let last = r.weights_of(72);
        assert_eq!(r.lo + (r.starts[72] + HALF_TAPS as usize) as i64, 127);
        assert!((last[HALF_TAPS as usize] - 1.0).abs() < 1e-6);
        assert!(last
            .iter()
            .enumerate()
            .all(|(k, w)| k == HALF_TAPS as usize || w.abs() < 1e-6));
    }

    #[test]
    fn interpolates_complex_exponentials_below_nyquist() {
        // A complex exponential of ν cycles/sample sampled on the lattice, read at fractional positions.
        for nu in [0.05, 0.2, 0.3, 0.35] {
            let pos: Vec<f64> = (0..40).map(|i| 10.3 + i as f64 * 0.731).collect();
            let r = Resampler::new(&pos, f64::INFINITY);
            let mut worst: f64 = 0.0;
            for (o, &t) in pos.iter().enumerate() {
                let w = r.weights_of(o);
                let (mut re, mut im) = (0.0, 0.0);
                for (k, wk) in w.iter().enumerate() {
                    let j = (r.lo + (r.starts[o] + k) as i64) as f64;
                    let ph = 2.0 * std::f64::consts::PI * nu * j;
                    re += *wk as f64 * ph.cos();
                    im += *wk as f64 * ph.sin();
                }
                let ph = 2.0 * std::f64::consts::PI * nu * t;
                worst = worst.max(((re - ph.cos()).powi(2) + (im - ph.sin()).powi(2)).sqrt());
            }
            let tol = if nu <= 0.3 { 3e-3 } else { 1.5e-2 };
            assert!(worst < tol, "ν = {nu}: error {worst}");
        }
    }

    /// φ̂ against a midpoint quadrature of φ, inside and past the band.
    #[test]
    fn kaiser_bessel_spectrum_is_the_kernels_fourier_transform() {
        for kernel in KaiserBessel::family(1e-4) {
            let n = 20_000;
            let h = kernel.taps as f64 / n as f64;
            for omega in [0.0, 0.7, 2.0, 3.5, 5.0, 9.0] {
                let quad: f64 = (0..n)
                    .map(|i| {
                        let t = -(kernel.taps as f64) / 2.0 + (i as f64 + 0.5) * h;
                        kernel.value(t) * (omega * t).cos() * h
                    })
                    .sum();
                let want = kernel.spectrum(omega);
                assert!(
                    (quad - want).abs() <= 1e-7 * kernel.spectrum(0.0),
                    "{} taps, ω {omega}: {quad} against {want}",
                    kernel.taps
                );
            }
        }
    }

    /// At 1e-4, kernels of 6–12 taps, each wider one serving a wider band: 4 taps alias more than
    /// that at any band, and past 12 taps the rounding that the division amplifies takes more of the
    /// budget than the extra taps save.
    #[test]
    fn kaiser_bessel_family_widens_with_taps() {
        let family = KaiserBessel::family(1e-4);
        let taps: Vec<usize> = family.iter().map(|k| k.taps).collect();
        assert_eq!(taps, vec![6, 8, 10, 12]);
        assert!(family.windows(2).all(|w| w[0].band < w[1].band));
        assert!((0.5..0.6).contains(&family[0].band), "{}", family[0].band);
        assert!(family[3].band > 0.8, "{}", family[3].band);
    }

    /// A complex exponential of the kernel's band, divided by φ̂ on the lattice and read at
    /// fractional positions, comes back within the aliasing the kernel was shaped for. Without the
    /// division it errs by the kernel's passband droop (measured: > 0.1 at the band's edge).
    #[test]
    fn kaiser_bessel_interpolates_deconvolved_exponentials() {
        let pos: Vec<f64> = (0..40).map(|i| 20.3 + i as f64 * 0.731).collect();
        for kernel in KaiserBessel::family(1e-4) {
            let r = Resampler::kaiser_bessel(&pos, f64::INFINITY, &kernel);
            for fraction in [0.1, 0.5, 1.0] {
                let omega = fraction * kernel.band * PI;
                let read = |divide: bool| {
                    let scale = if divide {
                        1.0 / kernel.spectrum(omega)
                    } else {
                        1.0
                    };
                    pos.iter()
                        .enumerate()
                        .map(|(o, &t)| {
                            let (mut re, mut im) = (0.0, 0.0);
                            for (k, wk) in r.weights_of(o).iter().enumerate() {
                                let j = (r.lo + (r.starts[o] + k) as i64) as f64;
                                re += *wk as f64 * scale * (omega * j).cos();
                                im += *wk as f64 * scale * (omega * j).sin();
                            }
                            ((re - (omega * t).cos()).powi(2) + (im - (omega * t).sin()).powi(2))
                                .sqrt()
                        })
                        .fold(0.0, f64::max)
                };
                // The bound samples ω on a grid of 65 points: 1.03e-4 measured at the edge of the
                // 8 taps' band.
                let err = read(true);
                assert!(
                    err < 1.1e-4,
                    "{} taps at {fraction} of the band: {err}",
                    kernel.taps
                );
                if fraction == 1.0 {
                    assert!(read(false) > 0.1, "{} taps undivided", kernel.taps);
                }
            }
        }
    }
}
