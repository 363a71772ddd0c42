//! The angles of once-scattered light in each reduced value: what the phase function weighs in it.
//!
//! A path laser point → medium → sensor point of length L scatters once on the ellipsoid with those
//! foci, at an angle that runs from backscatter (on its axis) to π − 2·atan(d/√(L² − d²)) (above the
//! foci's midpoint, d their separation): 160° at d = 0.35 m and 92° at d = 1.39 m for L = 2 m. The
//! table's renders are exact only at its g nodes; between them the fit carries the once-scattered
//! light's change with g through these angles, value by value.

use crate::table::Reduction;
use murk_core::Capture;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Separations sampled per ring, and quadrature nodes over each ellipsoid (polar, azimuth).
const SEPARATIONS: usize = 16;
const POLAR: usize = 32;
const AZIMUTH: usize = 12;

/// For each reduced value, the cosines of the scattering angles on its ellipsoids with the weight of
/// each in the once-scattered response.
pub struct Angles {
    per_value: Vec<Vec<(f64, f64)>>,
}

impl Angles {
    /// The angles of `cap`'s reduced values `used` (ring × coarse bin indices of `reduction`): each
    /// ring's separations at 16 quantiles, the coarse bin's middle path, the medium filling the
    /// half-space before the relay plane.
    pub fn new(reduction: &Reduction, cap: &Capture, used: &[usize]) -> Angles {
        let n = reduction.coarse_bins;
        let rings = reduction.ring_separations(SEPARATIONS);
        let per_value = used
            .par_iter()
            .map(|&i| {
                let path_m = reduction.path_m(cap, i % n);
                rings[i / n]
                    .iter()
                    .flat_map(|&d| ellipsoid(d, path_m))
                    .collect()
            })
            .collect();
        Angles { per_value }
    }

    /// ln of the once-scattered response's phase factor per value at each of `gs`, `[g][value]`:
    /// Σ weight · HG(cos θ, g), HG relative to isotropic (g > 0 forward). The fit takes it at every g
    /// node and searched g: each value's angles are read once for all of them, and what HG takes
    /// from g alone is computed once per g.
    pub fn ln_phases(&self, gs: &[f64]) -> Vec<Vec<f64>> {
        let numerator: Vec<f64> = gs.iter().map(|&g| 1.0 - g * g).collect();
        let (base, slope): (Vec<f64>, Vec<f64>) =
            gs.iter().map(|&g| (1.0 + g * g, 2.0 * g)).unzip();
        let per_value: Vec<Vec<f64>> = self
            .per_value
            .par_iter()
            .map(|points| {
                let mut sum = vec![0.0f64; gs.len()];
                for &(w, cos) in points {
                    let terms = numerator.iter().zip(&base).zip(&slope);
                    for (s, ((&n, &b), &k)) in sum.iter_mut().zip(terms) {
                        // d^1.5 as d·√d: powf cost most of the phase factors.
                        let d = b - k * cos;
                        *s += w * (n / (d * d.sqrt()));
                    }
                }
                sum.into_iter().map(f64::ln).collect()
            })
            .collect();
        (0..gs.len())
            .map(|j| per_value.iter().map(|v| v[j]).collect())
            .collect()
    }
}

/// (weight, cos θ) on the half-ellipsoid of path `path_m` between two relay points `d` apart: the
/// midpoint rule in prolate spheroidal coordinates (τ = cos ϑ, φ), weighted by the laser point's
/// emission cos_l/r_l², the sensor's cos_s/r_s² and the volume element r_l·r_s/2 dL dτ dφ (the
/// renderer's normalisation, `murk-render/tests/hg_single_scatter.rs`). Empty when the path cannot
/// join the points.
fn ellipsoid(d: f64, path_m: f64) -> Vec<(f64, f64)> {
    let (a, c) = (0.5 * path_m, 0.5 * d);
    if a <= c {
        return Vec::new();
    }
    let b = (a * a - c * c).sqrt();
    let mut out = Vec::with_capacity(POLAR * AZIMUTH);
    for i in 0..POLAR {
        let theta = PI * (i as f64 + 0.5) / POLAR as f64;
        let (tau, s) = (theta.cos(), theta.sin());
        for j in 0..AZIMUTH {
            let phi = 0.5 * PI * (j as f64 + 0.5) / AZIMUTH as f64;
            // Foci at x = ∓c on the relay plane z = 0; the medium at z > 0.
            let (x, y, z) = (a * tau, b * s * phi.cos(), b * s * phi.sin());
            let to_x = [x + c, y, z];
            let to_s = [c - x, -y, -z];
            let rl = (to_x[0] * to_x[0] + y * y + z * z).sqrt();
            let rs = (to_s[0] * to_s[0] + y * y + z * z).sqrt();
            let cos = (to_x[0] * to_s[0] + to_x[1] * to_s[1] + to_x[2] * to_s[2]) / (rl * rs);
            let weight = (z / rl) / (rl * rl) * (z / rs) / (rs * rs) * (rl * rs) * s;
            out.push((weight, cos));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angles_run_from_the_midpoint_angle_to_backscatter() {
        // d = 1.39 m, L = 2 m: above the midpoint the path turns by 92°; on the axis by 180°.
        let points = ellipsoid(1.39, 2.0);
        let cos_min = points.iter().map(|p| p.1).fold(1.0, f64::min);
        let cos_max = points.iter().map(|p| p.1).fold(-1.0, f64::max);
        assert!(cos_min < -0.99, "{cos_min}");
        let mid = (PI - 2.0 * (1.39f64 / (4.0f64 - 1.39 * 1.39).sqrt()).atan()).cos();
        assert!((cos_max - mid).abs() < 0.02, "{cos_max} vs {mid}");
        assert!(ellipsoid(2.0, 1.9).is_empty());
    }

    #[test]
    fn colocated_points_see_backscatter_only() {
        // d = 0: every once-scattered path returns along itself, so the factor is HG at π.
        let angles = Angles {
            per_value: vec![ellipsoid(0.0, 2.0)],
        };
        for g in [-0.7, 0.0, 0.4, 0.8] {
            let back = (1.0 - g) / (1.0 + g) / (1.0 + g);
            let total: f64 = angles.per_value[0].iter().map(|p| p.0).sum();
            let got = angles.ln_phases(&[g])[0][0] - total.ln();
            assert!(
                (got - back.ln()).abs() < 1e-9,
                "g {g}: {got} vs {}",
                back.ln()
            );
        }
    }
}
