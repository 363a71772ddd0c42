//! How far each reduced value can be trusted: the Monte Carlo noise of the capture's ring means and
//! of the table's renders, in ln(intensity). The fit weighs each value by the inverse of their sum,
//! so that the noisy late bins of a dense or forward-scattering medium (and of the table's renders
//! of one) do not outvote the clean early ones.

use super::interpolate::bracket;
use crate::table::ResponseTable;

/// Coarse bins on either side over which a value's noise is averaged: one bin's second difference is
/// too few samples of a heavy-tailed noise to weigh by.
const HALF_WINDOW: usize = 2;

/// The variance of ln(value) the model cannot follow anyway (its interpolation between nodes): no
/// value weighs more than this allows, however clean its bins look.
const FLOOR_LN_VARIANCE: f64 = 0.02 * 0.02;

/// Weights of the values `used` ([ring][bin] indices, `n` bins per ring), mean 1: the inverse of the
/// capture's (`data`, its ring means) and the table's noise variance there, the table's taken at the
/// nodes around (`mu_t_per_m`, `albedo`, `g`), weighed as they are interpolated.
pub(super) fn weights(
    table: &ResponseTable,
    data: &[f64],
    used: &[usize],
    n: usize,
    (mu_t_per_m, albedo, g): (f64, f64, f64),
) -> Vec<f64> {
    let capture = ln_variance(data, n);
    let mut model = vec![0.0; used.len()];
    for (m, wm) in around(&table.mu_t_per_m, mu_t_per_m, true) {
        for (k, wg) in around(&table.g, g, false) {
            for (a, wa) in around(&table.albedos, albedo, false) {
                let node = ln_variance(table.node(m, k, a), n);
                for (v, &i) in model.iter_mut().zip(used) {
                    *v += wm * wg * wa * node[i];
                }
            }
        }
    }
    let inverse: Vec<f64> = used
        .iter()
        .zip(&model)
        .map(|(&i, &t)| 1.0 / (capture[i] + t + FLOOR_LN_VARIANCE))
        .collect();
    let mean = inverse.iter().sum::<f64>() / inverse.len() as f64;
    inverse.iter().map(|w| w / mean).collect()
}

/// The two nodes around `x` with their interpolation weights.
fn around(nodes: &[f64], x: f64, log: bool) -> [(usize, f64); 2] {
    let (lo, hi, w) = bracket(nodes, x, log);
    [(lo, 1.0 - w), (hi, w)]
}

/// The variance of ln of each value of `values` ([ring][bin], `n` bins per ring) from its second
/// differences along the bins, which a smooth response hardly has and white noise of variance σ² has
/// at 1.5·σ², averaged over ±[`HALF_WINDOW`] bins. Values without a positive neighbourhood get an
/// infinite variance (no weight).
fn ln_variance(values: &[f64], n: usize) -> Vec<f64> {
    let mut out = vec![f64::INFINITY; values.len()];
    for (ring, out) in values.chunks(n).zip(out.chunks_mut(n)) {
        let ln: Vec<f64> = ring
            .iter()
            .map(|&v| if v > 0.0 { v.ln() } else { f64::NAN })
            .collect();
        let second: Vec<f64> = (0..n)
            .map(|b| {
                if b == 0 || b + 1 == n {
                    return f64::NAN;
                }
                (ln[b] - 0.5 * (ln[b - 1] + ln[b + 1])).powi(2) / 1.5
            })
            .collect();
        for (b, o) in out.iter_mut().enumerate() {
            let window = &second[b.saturating_sub(HALF_WINDOW)..(b + HALF_WINDOW + 1).min(n)];
            let finite: Vec<f64> = window.iter().copied().filter(|v| v.is_finite()).collect();
            if !finite.is_empty() {
                *o = finite.iter().sum::<f64>() / finite.len() as f64;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth exponential decay has no noise; one with ln-noise of a known spread gives it back.
    #[test]
    fn ln_variance_measures_the_noise_not_the_decay() {
        let n = 400;
        let smooth: Vec<f64> = (0..n).map(|b| (-0.02 * b as f64).exp()).collect();
        assert!(ln_variance(&smooth, n)[1..n - 1].iter().all(|&v| v < 1e-12));
        // A fixed ±σ pattern that is not smooth: alternating signs give second differences of 2σ.
        let sigma: f64 = 0.1;
        let noisy: Vec<f64> = smooth
            .iter()
            .enumerate()
            .map(|(b, v)| v * (if b % 2 == 0 { sigma } else { -sigma }).exp())
            .collect();
        let got = ln_variance(&noisy, n)[n / 2];
        assert!((got - 4.0 * sigma * sigma / 1.5).abs() < 1e-9, "{got}");
        // No signal: no weight.
        assert!(ln_variance(&[0.0; 8], 8).iter().all(|v| v.is_infinite()));
    }
}
