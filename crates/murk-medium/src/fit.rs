//! The fit: the capture's ring-averaged medium-only bins against the table, interpolated, by a grid
//! search over (μt, α, g) that also gives each parameter's profile and so its uncertainty.

use crate::posterior;
use crate::single::Angles;
use crate::table::ResponseTable;
use crate::Fixed;
use interpolate::{Interpolation, Phase};
use murk_core::{Capture, Error, Result};
use murk_methods::{Method, Options, Request, Searched};
use murk_recon::medium::detect::Signature;
use rayon::prelude::*;

mod interpolate;
mod noise;

/// Which parameters are fitted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FitParams {
    pub mu_t: bool,
    pub albedo: bool,
    pub g: bool,
}

impl FitParams {
    pub const ALL: FitParams = FitParams {
        mu_t: true,
        albedo: true,
        g: true,
    };

    /// Reads a comma-separated list of `mu_t`, `albedo`, `g`.
    pub fn parse(text: &str) -> Result<FitParams> {
        let mut p = FitParams {
            mu_t: false,
            albedo: false,
            g: false,
        };
        for name in text.split(',').map(str::trim) {
            match name {
                "mu_t" => p.mu_t = true,
                "albedo" => p.albedo = true,
                "g" => p.g = true,
                other => {
                    return Err(Error::param(format!(
                        "fit '{other}': expected a list of mu_t, albedo, g"
                    )))
                }
            }
        }
        Ok(p)
    }
}

/// One estimated parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Parameter {
    pub value: f64,
    /// The posterior's standard deviation over the searched grid (flat priors; the noise taken from
    /// the residual, with neighbouring bins' correlation counted). 0 when fixed.
    pub uncertainty: f64,
    pub fitted: bool,
    /// Whether the data tell the value: its uncertainty is under a sixth of the searched range (for
    /// μt, in ln μt).
    pub constrained: bool,
}

/// The fit's answer.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    pub mu_t_per_m: Parameter,
    pub albedo: Parameter,
    pub g: Parameter,
    /// Whether the capture's intensity scale is the renderer's (a murk render) or was fitted.
    pub absolute: bool,
    /// The medium-only bins: from the window's start to this path (m).
    pub from_m: f64,
    pub until_m: f64,
    /// Ring × coarse-bin values fitted.
    pub values_used: usize,
    pub rings: usize,
    /// RMS of ln(data / model) over the values used.
    pub residual_rms: f64,
    pub signature: Signature,
    pub table_nodes: (usize, usize, usize),
    /// What μt means where the capture's medium is heterogeneous and the forward model kept its
    /// shape ([`crate::scene::Modelled::describe`]); `None` for a homogeneous model.
    pub density: Option<String>,
    /// The depth search that found where the scene's signal begins (`None` where the medium-only
    /// bins' end was given): a reconstruction of the capture takes it instead of searching again.
    pub searched: Option<Searched>,
}

impl Estimate {
    /// One JSON object (the keys `murk medium --json` documents).
    pub fn to_json(&self) -> String {
        let p = |name: &str, q: &Parameter| {
            format!(
                "\"{name}\": {}, \"{name}_uncertainty\": {}, \"{name}_fitted\": {}, \"{name}_constrained\": {}",
                num(q.value),
                num(q.uncertainty),
                q.fitted,
                q.constrained
            )
        };
        // Only a heterogeneous model names its density: homogeneous estimates keep their bytes.
        let density = self
            .density
            .as_ref()
            .map_or_else(String::new, |d| format!(", \"density\": \"{d}\""));
        format!(
            "{{\"medium\": true, {}, {}, {}{density}, \"amplitude\": \"{}\", \"bins_from_m\": {}, \"bins_until_m\": {}, \"values_used\": {}, \"rings\": {}, \"residual_rms_ln\": {}, \"forward_model\": \"murk render, medium only, {}×{}×{} (μt × g × albedo) nodes\"}}",
            p("mu_t_per_m", &self.mu_t_per_m),
            p("albedo", &self.albedo),
            p("g", &self.g),
            if self.absolute { "absolute" } else { "fitted scale" },
            num(self.from_m),
            num(self.until_m),
            self.values_used,
            self.rings,
            num(self.residual_rms),
            self.table_nodes.0,
            self.table_nodes.1,
            self.table_nodes.2
        )
    }

    /// Rows for a summary.
    pub fn rows(&self) -> Vec<(String, String)> {
        let p = |q: &Parameter| match (q.fitted, q.constrained) {
            (false, _) => format!("{} (given)", murk_core::short(q.value)),
            (true, true) => format!(
                "{} ± {}",
                murk_core::short(q.value),
                murk_core::short(q.uncertainty)
            ),
            (true, false) => format!(
                "{} ± {} (not constrained by these bins)",
                murk_core::short(q.value),
                murk_core::short(q.uncertainty)
            ),
        };
        let mut rows = vec![
            ("mu_t_per_m".into(), p(&self.mu_t_per_m)),
            ("albedo".into(), p(&self.albedo)),
            ("g".into(), p(&self.g)),
        ];
        rows.extend(self.density.iter().map(|d| ("density".into(), d.clone())));
        rows.extend([
            (
                "bins".into(),
                format!(
                    "{} to {} m of path ({} ring × bin values, {} rings of laser–sensor separation)",
                    murk_core::short(self.from_m),
                    murk_core::short(self.until_m),
                    self.values_used,
                    self.rings
                ),
            ),
            (
                "fit".into(),
                format!(
                    "residual {:.1} % rms; intensity scale {}",
                    100.0 * self.residual_rms,
                    if self.absolute {
                        "the renderer's (a murk render)"
                    } else {
                        "fitted"
                    }
                ),
            ),
            ("medium detected".into(), self.signature.describe()),
        ]);
        rows
    }
}

fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.6}")
    } else {
        "null".into()
    }
}

/// The medium-aware depth search that [`scene_onset_m`] reads: `murk reconstruct`'s with no flags.
pub fn onset_search(cap: &Capture) -> Result<Searched> {
    let method = Method::named("pf", &Options::default())?;
    Searched::new(cap, &Request::new(method), &murk_core::NoProgress)
}

/// Where the scene's own signal begins: the shortest path to the plane where the medium-aware depth
/// search ([`onset_search`]) finds the signal focused, less three pulse widths (as `--gate auto` opens
/// before a volume), but no earlier than a fifth into the window: in dense media the search can stop
/// at an artefact near the wall, and a fit needs the bins. Without a plane, 30 % into the window.
pub fn scene_onset_m(cap: &Capture, searched: &Searched) -> Result<f64> {
    let method = Method::named("pf", &Options::default())?;
    let (start, span) = (cap.time.start_m, cap.time.end_m() - cap.time.start_m);
    let found = searched.found().filter(|(f, _)| f.volume.is_some());
    let plane = found.map(|(f, _)| {
        let v = murk_methods::default_volume(cap).map(|v| murk_core::Volume {
            z: murk_core::Axis::new(f.z_m, f.z_m, 1),
            ..v
        });
        let sigma_m = method.pulse(cap).ok().flatten().map_or(0.0, |p| p.sigma_m);
        v.map(|v| murk_core::window::shortest_path_m(cap, &v) - 3.0 * sigma_m)
    });
    Ok(match plane {
        Some(onset) => onset?.max(start + 0.2 * span).min(cap.time.end_m()),
        None => start + 0.3 * span,
    })
}

/// How far off a model without signal at a value counts (its ratio to the data there).
const NO_SIGNAL_RATIO: f64 = 1e3;

/// Candidate values searched per parameter.
const MU_STEPS: usize = 72;
const ALBEDO_STEP: f64 = 0.01;
const G_STEP: f64 = 0.05;

/// Fits `cap`'s bins before `until_m` with `table`.
pub fn fit(
    cap: &Capture,
    table: &ResponseTable,
    until_m: f64,
    which: &FitParams,
    fixed: &Fixed,
    signature: Signature,
) -> Result<Estimate> {
    let red = &table.reduction;
    let data = red.reduce(cap);
    let n = red.coarse_bins;
    // The table's coarser grid stands in for the capture's separations only where the response no
    // longer changes fast with the separation: from 10 cm past the ring's largest one.
    let ring_max = red.ring_max_separations(cap);
    let used: Vec<usize> = (0..red.rings())
        .flat_map(|r| (0..n).map(move |b| (r, b)))
        .filter(|&(r, b)| {
            let path_m = red.path_m(cap, b);
            path_m < until_m && path_m >= ring_max[r] + 0.1
        })
        .map(|(r, b)| r * n + b)
        .filter(|&i| data[i] > 0.0 && data[i].is_finite() && table.covers(i))
        .collect();
    if used.len() < 8 {
        return Err(Error::param(format!(
            "only {} medium-only values before {} m of path: too few to fit a medium (the window starts at {} m)",
            used.len(),
            murk_core::short(until_m),
            murk_core::short(cap.time.start_m)
        )));
    }
    let ln_data: Vec<f64> = used.iter().map(|&i| data[i].ln()).collect();
    let absolute = cap.scene_info.contains("generator: murk render");
    let range = |nodes: &[f64]| (nodes[0], nodes[nodes.len() - 1]);
    let (mu_lo, mu_hi) = range(&table.mu_t_per_m);
    let mus: Vec<f64> = if which.mu_t {
        (0..MU_STEPS)
            .map(|k| mu_lo * (mu_hi / mu_lo).powf(k as f64 / (MU_STEPS - 1) as f64))
            .collect()
    } else {
        vec![fixed.mu_t_per_m]
    };
    let steps = |lo: f64, hi: f64, step: f64| -> Vec<f64> {
        let k = ((hi - lo) / step).floor() as usize;
        (0..=k).map(|i| lo + i as f64 * step).collect()
    };
    let albedos = if which.albedo {
        let (lo, hi) = range(&table.albedos);
        steps(lo, hi, ALBEDO_STEP)
    } else {
        vec![fixed.albedo]
    };
    let gs = if which.g {
        let (lo, hi) = range(&table.g);
        steps(lo, hi, G_STEP)
    } else {
        vec![fixed.g]
    };
    let phase = Phase::new(&Angles::new(red, cap, &used), &table.g, &gs);
    let paths_m: Vec<f64> = used.iter().map(|&i| red.path_m(cap, i % n)).collect();
    let grid = Interpolation::new(table, &used, &paths_m, &phase, (&mus, &albedos, &gs));
    let (nm, na, ng) = grid.shape();
    // Sum of squares at every candidate, [mu][albedo][g], each value weighed by `weight`.
    let search = |weight: &[f64]| -> Vec<f64> {
        // [albedo][mu][g] first: a worker's candidates then share its albedo, so the table's nodes
        // there and their ln are taken once per worker and albedo.
        let mut by_albedo = vec![0.0; na * nm * ng];
        by_albedo.par_chunks_mut(ng).enumerate().for_each_init(
            || (grid.corners(), vec![0.0; used.len()]),
            |(corners, ln_model), (j, out)| {
                for (k, s) in out.iter_mut().enumerate() {
                    grid.ln_model(corners, (j % nm, j / nm, k), ln_model);
                    *s = sum_of_squares(&ln_data, ln_model, weight, absolute);
                }
            },
        );
        (0..nm * na)
            .flat_map(|j| {
                let (mu, a) = (j / na, j % na);
                by_albedo[(a * nm + mu) * ng..][..ng].iter().copied()
            })
            .collect()
    };
    let best_of = |ssr: &[f64]| -> Result<usize> {
        let (best, &min) = ssr
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1))
            .ok_or_else(|| Error::param("no candidate to fit"))?;
        if !min.is_finite() {
            return Err(Error::param(
                "the medium's model has no signal where the capture has: no fit (is the medium inside the scene's extent?)",
            ));
        }
        Ok(best)
    };
    // Uniform weights first; then each value weighed by its noise, the table's taken where that fit
    // landed (the table's noise changes slowly from node to node).
    let first = best_of(&search(&vec![1.0; used.len()]))?;
    let weight = noise::weights(
        table,
        &data,
        &used,
        n,
        (
            mus[first / (na * ng)],
            albedos[(first / ng) % na],
            gs[first % ng],
        ),
    );
    let ssr = search(&weight);
    let best = best_of(&ssr)?;
    let (bm, ba, bg) = (best / (na * ng), (best / ng) % na, best % ng);
    // The residuals of neighbouring bins are correlated (the table's Monte Carlo noise is smooth over
    // a few bins, and so are model errors): the likelihood counts the effective number of
    // independent values, N·(1 − ρ)/(1 + ρ) for a lag-one correlation ρ.
    let mut best_model = vec![0.0; used.len()];
    grid.ln_model(&mut grid.corners(), (bm, ba, bg), &mut best_model);
    let residual = residuals(&ln_data, &best_model, &weight, absolute);
    let rho = posterior::lag_one_correlation(&residual, |k| {
        used[k] == used[k - 1] + 1 && !used[k].is_multiple_of(n)
    });
    // The posterior over the candidate grid (flat in ln μt, α and g): its mean and standard
    // deviation, which follow a valley of equally good fits instead of the noise's choice in it.
    let posterior = posterior::weights(&ssr, posterior::effective_count(used.len(), rho))?;
    let moments = |value: &dyn Fn(usize) -> f64| posterior::moments(&posterior, value);
    let parameter = |fitted: bool, values: &[f64], axis: usize, log: bool| -> Parameter {
        if !fitted {
            return Parameter {
                value: values[0],
                uncertainty: 0.0,
                fitted: false,
                constrained: true,
            };
        }
        let index = |i: usize| [i / (na * ng), (i / ng) % na, i % ng][axis];
        let (value, uncertainty) = if log {
            let (m, sd) = moments(&|i| values[index(i)].ln());
            (m.exp(), m.exp() * sd)
        } else {
            moments(&|i| values[index(i)])
        };
        let span = if log {
            values[values.len() - 1].ln() - values[0].ln()
        } else {
            values[values.len() - 1] - values[0]
        };
        // No finer than the searched grid: half its step.
        let step = if values.len() > 1 {
            if log {
                value * (values[1] / values[0] - 1.0)
            } else {
                values[1] - values[0]
            }
        } else {
            0.0
        };
        let uncertainty = uncertainty.max(step / 2.0);
        let relative = if log {
            uncertainty / value
        } else {
            uncertainty
        };
        Parameter {
            value,
            uncertainty,
            fitted: true,
            constrained: relative < span / 6.0,
        }
    };
    Ok(Estimate {
        mu_t_per_m: parameter(which.mu_t, &mus, 0, true),
        albedo: parameter(which.albedo, &albedos, 1, false),
        g: parameter(which.g, &gs, 2, false),
        absolute,
        from_m: cap.time.start_m,
        until_m: until_m.min(cap.time.end_m()),
        values_used: used.len(),
        rings: red.rings(),
        residual_rms: (residuals(&ln_data, &best_model, &vec![1.0; used.len()], absolute)
            .iter()
            .map(|r| r * r)
            .sum::<f64>()
            / used.len() as f64)
            .sqrt(),
        signature,
        table_nodes: (table.mu_t_per_m.len(), table.g.len(), table.albedos.len()),
        density: crate::scene::modelled(cap).map(|m| m.describe()),
        searched: None,
    })
}

/// ln(data / model) per used value, less the best (weighted) common offset when the scale is free,
/// times the square root of its weight; `ln_model` is the model's ln.
fn residuals(ln_data: &[f64], ln_model: &[f64], weight: &[f64], absolute: bool) -> Vec<f64> {
    let diff: Vec<f64> = ln_data
        .iter()
        .zip(ln_model)
        .map(|(d, &m)| {
            if m.is_finite() {
                d - m
            } else {
                NO_SIGNAL_RATIO.ln()
            }
        })
        .collect();
    let offset = if absolute {
        0.0
    } else {
        diff.iter().zip(weight).map(|(x, w)| w * x).sum::<f64>() / weight.iter().sum::<f64>()
    };
    diff.iter()
        .zip(weight)
        .map(|(x, w)| w.sqrt() * (x - offset))
        .collect()
}

/// Σ weight·(ln data − ln model)², less the best (weighted) common offset when the scale is free; a
/// model without signal at a value counts as off by a factor of [`NO_SIGNAL_RATIO`] there.
fn sum_of_squares(ln_data: &[f64], ln_model: &[f64], weight: &[f64], absolute: bool) -> f64 {
    let floor = NO_SIGNAL_RATIO.ln();
    let diff = ln_data
        .iter()
        .zip(ln_model)
        .map(|(d, &m)| if m.is_finite() { d - m } else { floor });
    let offset = if absolute {
        0.0
    } else {
        diff.clone().zip(weight).map(|(x, w)| w * x).sum::<f64>() / weight.iter().sum::<f64>()
    };
    diff.zip(weight)
        .map(|(x, w)| w * (x - offset).powi(2))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_params_parse() {
        assert_eq!(FitParams::parse("mu_t,albedo,g").unwrap(), FitParams::ALL);
        let p = FitParams::parse("mu_t").unwrap();
        assert!(p.mu_t && !p.albedo && !p.g);
        assert!(FitParams::parse("mu_s").is_err());
    }
}
