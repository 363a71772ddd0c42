//! The medium's response predicted for given parameters, for `--medium-removal model`: the capture's
//! own geometry with every object removed but the medium's room, its heterogeneous density kept
//! where murk knows its shape ([`crate::scene::medium_only`]), rendered by murk's renderer on a coarse grid at the
//! capture's full time resolution, one curve per laser–sensor separation. The reconstruction
//! subtracts it from each histogram at that histogram's separation
//! ([`murk_recon::medium::removal::subtract_predicted`]).

use crate::table::{by_separation, render_medium_only};
use crate::{Estimate, Fixed, TableSpec};
use murk_core::{short, Capture, Error, Result};
use murk_recon::medium::removal::{moving_average, Predicted};

/// How the prediction is rendered.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelSpec {
    /// The render's grid side (the capture's extent, fewer points: the response depends only on the
    /// separation, which the capture's histograms take by interpolation).
    pub grid: usize,
    pub spp: u64,
    pub seed: u64,
    /// The width over which each curve is smoothed, as a share of the bin's path: the render's own
    /// Monte Carlo noise would otherwise be subtracted into every histogram. The medium's response
    /// holds no object, so only its sharp onset limits this.
    pub smooth_share: f64,
}

impl Default for ModelSpec {
    fn default() -> ModelSpec {
        ModelSpec {
            grid: 8,
            spp: 1024,
            seed: 0,
            smooth_share: 0.05,
        }
    }
}

/// The prediction that `--medium-removal model` subtracts: μt and α as given, what is not given from
/// `estimate` (g too: 0, an isotropic medium, where μt and α are given and nothing was estimated).
pub fn for_removal(
    cap: &Capture,
    mu_t_per_m: Option<f64>,
    albedo: Option<f64>,
    estimate: Option<&Estimate>,
) -> Result<Predicted> {
    let from_estimate = |f: fn(&Estimate) -> f64, what: &str| {
        estimate.map(f).ok_or_else(|| {
            Error::param(format!(
                "model removal needs the medium's {what}: give it, or let it be estimated"
            ))
        })
    };
    let medium = Fixed {
        mu_t_per_m: match mu_t_per_m {
            Some(v) => v,
            None => from_estimate(|e| e.mu_t_per_m.value, "μt")?,
        },
        albedo: match albedo {
            Some(v) => v,
            None => from_estimate(|e| e.albedo.value, "albedo")?,
        },
        g: estimate.map_or(0.0, |e| e.g.value),
    };
    predict(cap, &medium, &ModelSpec::default())
}

/// The response of `medium` in `cap`'s geometry (which its scene description gives), per separation.
pub fn predict(cap: &Capture, medium: &Fixed, spec: &ModelSpec) -> Result<Predicted> {
    medium.validate()?;
    let scene_text = crate::scene::medium_only(cap)?;
    let table = TableSpec {
        grid: spec.grid,
        spp: spec.spp,
        seed: spec.seed,
        ..TableSpec::default()
    };
    let render = render_medium_only(
        &scene_text,
        cap,
        &table,
        &[medium.albedo],
        medium.mu_t_per_m,
        medium.g,
    )?
    .remove(0);
    let bins = render.time.bins;
    let (separations_m, curves) = by_separation(&render, bins, |i, out| {
        for (o, &v) in out.iter_mut().zip(render.histogram(i)) {
            *o += v as f64;
        }
    });
    let dt = render.time.bin_width_m;
    let half: Vec<usize> = (0..bins)
        .map(|b| {
            let path_m = (render.time.start_m + (b as f64 + 0.5) * dt).max(0.0);
            ((spec.smooth_share * path_m / dt / 2.0).round() as usize).max(1)
        })
        .collect();
    let curves = curves
        .iter()
        .map(|c| {
            moving_average(c, &half)
                .into_iter()
                .map(|v| v as f32)
                .collect()
        })
        .collect();
    Ok(Predicted {
        separations_m,
        curves,
        source: format!(
            "rendered for μt {} /m, albedo {}, g {} ({}² points, {} spp, smoothed over {:.0} % of the path){}",
            short(medium.mu_t_per_m),
            short(medium.albedo),
            short(medium.g),
            spec.grid,
            spec.spp,
            100.0 * spec.smooth_share,
            crate::scene::modelled(cap).map_or_else(String::new, |m| format!("; {}", m.describe()))
        ),
    })
}
