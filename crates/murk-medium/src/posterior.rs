//! The posterior over a grid of candidates from their sums of squares (flat priors, Gaussian noise
//! whose variance is taken from the best candidate's residual), shared by the fits.

use murk_core::{Error, Result};

/// Weights ∝ exp(−(SSR − min)/(2σ²)) with σ² = min / `n_eff`: the residual's variance per
/// independent value. Errors when no candidate has a finite sum.
pub fn weights(ssr: &[f64], n_eff: f64) -> Result<Vec<f64>> {
    let min = ssr.iter().copied().fold(f64::INFINITY, f64::min);
    if !min.is_finite() {
        return Err(Error::param("no candidate of the grid has a finite misfit"));
    }
    let spread = (min / n_eff.max(1.0)).max(f64::MIN_POSITIVE);
    Ok(ssr
        .iter()
        .map(|&x| (-(x - min) / (2.0 * spread)).exp())
        .collect())
}

/// Mean and standard deviation of `value(i)` under `weights`.
pub fn moments(weights: &[f64], value: impl Fn(usize) -> f64) -> (f64, f64) {
    let total: f64 = weights.iter().sum();
    let mean = weights
        .iter()
        .enumerate()
        .map(|(i, w)| w * value(i))
        .sum::<f64>()
        / total;
    let var = weights
        .iter()
        .enumerate()
        .map(|(i, w)| w * (value(i) - mean).powi(2))
        .sum::<f64>()
        / total;
    (mean, var.sqrt())
}

/// The number of independent values among `count` residuals whose neighbours correlate at lag
/// one by `rho`: N·(1 − ρ)/(1 + ρ), ρ clamped to 0–0.95.
pub fn effective_count(count: usize, rho: f64) -> f64 {
    let rho = rho.clamp(0.0, 0.95);
    (count as f64 * (1.0 - rho) / (1.0 + rho)).max(1.0)
}

/// The lag-one correlation of `residual`, counting the pairs (k − 1, k) where `adjacent(k)`.
pub fn lag_one_correlation(residual: &[f64], adjacent: impl Fn(usize) -> bool) -> f64 {
    let mean = residual.iter().sum::<f64>() / residual.len() as f64;
    let var: f64 = residual.iter().map(|r| (r - mean).powi(2)).sum();
    let cov: f64 = (1..residual.len())
        .filter(|&k| adjacent(k))
        .map(|k| (residual[k] - mean) * (residual[k - 1] - mean))
        .sum();
    if var > 0.0 {
        cov / var
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaussian_misfit_gives_its_mean_and_sd() {
        // SSR(x) = min + n_eff·(x − 2)²/σ_x² · (min/n_eff) … with min = 10, n_eff = 10 the
        // variance per value is 1, so SSR = 10 + (x − 2)²/0.3² gives a posterior N(2, 0.3²).
        let xs: Vec<f64> = (0..4001).map(|k| k as f64 * 0.001).collect();
        let ssr: Vec<f64> = xs
            .iter()
            .map(|x| 10.0 + ((x - 2.0) / 0.3).powi(2))
            .collect();
        let w = weights(&ssr, 10.0).unwrap();
        let (m, sd) = moments(&w, |i| xs[i]);
        assert!((m - 2.0).abs() < 1e-6, "{m}");
        assert!((sd - 0.3).abs() < 1e-3, "{sd}");
        assert!(weights(&[f64::NAN, f64::INFINITY], 3.0).is_err());
    }

    #[test]
    fn correlation_and_effective_count() {
        let alternating = [1.0, -1.0, 1.0, -1.0, 1.0, -1.0];
        assert!(lag_one_correlation(&alternating, |_| true) < -0.8);
        let smooth = [1.0, 1.0, 1.0, -1.0, -1.0, -1.0];
        assert!(lag_one_correlation(&smooth, |_| true) > 0.3);
        assert_eq!(lag_one_correlation(&smooth, |_| false), 0.0);
        assert_eq!(effective_count(100, 0.0), 100.0);
        assert!((effective_count(100, 0.5) - 100.0 / 3.0).abs() < 1e-9);
        assert!((effective_count(100, 0.99) - 100.0 * 0.05 / 1.95).abs() < 1e-9);
    }
}
