//! Evaluation of a band-limited field sampled on the wall's lattice at arbitrary positions along one axis.
//! Aligned positions read one sample; others use a Kaiser-windowed sinc. The field the fast Phasor
//! Fields path produces at a depth plane is band-limited by k·sinθ < π/Δ whenever λ_min > 2Δ, so the
//! interpolation is accurate away from that limit.

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
        let aligned = positions.iter().all(|t| (t - t.round()).abs() < 1e-6);
        let taps = if aligned { 1 } else { (2 * HALF_TAPS) as usize };
        let firsts: Vec<i64> = positions
            .iter()
            .map(|&t| {
                if aligned {
                    t.round() as i64
                } else if t > centre && (t - t.round()).abs() < 1e-9 {
                    t.round() as i64 - HALF_TAPS
                } else {
                    t.floor() as i64 - HALF_TAPS + 1
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
                weights.extend((0..taps as i64).map(|k| windowed_sinc(t - (f + k) as f64) as f32));
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
}

fn windowed_sinc(x: f64) -> f64 {
    let u = x / HALF_TAPS as f64;
    if u.abs() >= 1.0 {
        return 0.0;
    }
    let sinc = if x.abs() < 1e-12 {
        1.0
    } else {
        (std::f64::consts::PI * x).sin() / (std::f64::consts::PI * x)
    };
    sinc * bessel_i0(KAISER_BETA * (1.0 - u * u).sqrt()) / bessel_i0(KAISER_BETA)
}

/// Modified Bessel function of the first kind, order 0 (power series; converges fast for x < 20).
fn bessel_i0(x: f64) -> f64 {
    let (mut sum, mut term, q) = (1.0, 1.0, x * x / 4.0);
    for k in 1..60 {
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
}
