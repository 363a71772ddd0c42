//! Phase functions: the angular distribution of light scattered in a medium.

use murk_core::DVec3;
use std::f64::consts::PI;

/// Phase functions, dispatched statically. Angles are between the propagation directions before
/// and after scattering, so g > 0 scatters forward.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Phase {
    Isotropic,
    HenyeyGreenstein { g: f64 },
}

impl Phase {
    pub fn new(g: f64) -> Self {
        if g == 0.0 {
            Phase::Isotropic
        } else {
            Phase::HenyeyGreenstein { g }
        }
    }

    /// Density per steradian for the cosine between the two propagation directions.
    pub fn eval(&self, cos: f64) -> f64 {
        match *self {
            Phase::Isotropic => 1.0 / (4.0 * PI),
            Phase::HenyeyGreenstein { g } => {
                let den = 1.0 + g * g - 2.0 * g * cos;
                (1.0 - g * g) / (4.0 * PI * den * den.sqrt())
            }
        }
    }

    /// The concentration ρ of the wrapped Cauchy density ∝ 1/(1 + ρ² − 2ρ cos ψ) over scattering angles
    /// ψ that importance-samples this phase function's density in ψ best (the phase-angle distances):
    /// a fit of the ρ that minimises the second moment of p/q under q (1 where q = p), close to the
    /// optimum's at |g| ≤ 0.95 (docs/renderer-sampling.md). Isotropic: 0 (uniform in ψ).
    pub fn cauchy_rho(&self) -> f64 {
        match *self {
            Phase::Isotropic => 0.0,
            Phase::HenyeyGreenstein { g } => g * (1.55 - 0.55 * g.abs()),
        }
    }

    /// The cosine of a scattering angle drawn from the phase function (inverse CDF).
    pub fn sample_cos(&self, u: f64) -> f64 {
        match *self {
            Phase::Isotropic => 1.0 - 2.0 * u,
            Phase::HenyeyGreenstein { g } => {
                let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
                ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
            }
        }
    }

    /// A new propagation direction around `dir`; its pdf is exactly `eval`.
    pub fn sample(&self, dir: DVec3, u1: f64, u2: f64) -> DVec3 {
        let cos = self.sample_cos(u1);
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let (a, b) = dir.any_orthonormal_pair();
        let phi = 2.0 * PI * u2;
        (dir * cos + a * (sin * phi.cos()) + b * (sin * phi.sin())).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// HG sampling against its own pdf: a chi-square test over 40 bins of cos θ, and the mean cosine = g.
    #[test]
    fn hg_sampling_matches_pdf() {
        use rand_core::Rng;
        let mut rng = rand_pcg::Pcg64::new(7, 1);
        for g in [-0.7, 0.0, 0.3, 0.9] {
            let ph = Phase::new(g);
            const N: usize = 200_000;
            const BINS: usize = 40;
            let mut counts = [0usize; BINS];
            let mut mean = 0.0;
            for _ in 0..N {
                let u = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
                let c = ph.sample_cos(u);
                mean += c / N as f64;
                counts[(((c + 1.0) / 2.0 * BINS as f64) as usize).min(BINS - 1)] += 1;
            }
            // Expected counts from the pdf of cos θ (2π·p), integrated per bin by Simpson's rule.
            let pdf_cos = |c: f64| 2.0 * PI * ph.eval(c);
            let mut chi2 = 0.0;
            for (k, &obs) in counts.iter().enumerate() {
                let (a, b) = (
                    -1.0 + 2.0 * k as f64 / BINS as f64,
                    -1.0 + 2.0 * (k + 1) as f64 / BINS as f64,
                );
                let m = 64;
                let h = (b - a) / m as f64;
                let simpson: f64 = (0..=m)
                    .map(|i| {
                        let w = if i == 0 || i == m {
                            1.0
                        } else if i % 2 == 1 {
                            4.0
                        } else {
                            2.0
                        };
                        w * pdf_cos(a + i as f64 * h)
                    })
                    .sum::<f64>()
                    * h
                    / 3.0;
                let exp = simpson * N as f64;
                chi2 += (obs as f64 - exp).powi(2) / exp;
            }
            // 39 degrees of freedom: the 0.1 % critical value is 72.1.
            assert!(chi2 < 72.1, "g = {g}: chi2 = {chi2}");
            // Standard error of the mean cosine is below 1/sqrt(N) = 0.0022; allow 4σ.
            assert!((mean - g).abs() < 0.009, "g = {g}: mean cos {mean}");
        }
    }
}
