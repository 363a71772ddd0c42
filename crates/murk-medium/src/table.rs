//! The medium-only responses that the fit interpolates: the capture's geometry without objects,
//! rendered once per (μt, g) of a grid, each render an albedo sweep, reduced to ring means.

use crate::EstimateOptions;
use murk_core::{Capture, Error, Result};
use murk_render::{Overrides, Plan, RenderOptions, Scene};
use rayon::prelude::*;
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Duration;

mod store;
pub use store::load_or_build;

/// How the table is rendered.
#[derive(Clone, Debug, PartialEq)]
pub struct TableSpec {
    /// The render's grid side (the capture's own extent, fewer points: rings average them).
    pub grid: usize,
    pub spp: u64,
    /// Samples per point of the nodes at g ≥ [`FORWARD_G`]: forward fog's renders are the noisiest
    /// (its late bins), and the table's noise there decides a free g.
    pub forward_spp: u64,
    pub seed: u64,
    /// μt nodes (1/m), ascending; the fit interpolates ln(response) linearly in ln μt.
    pub mu_t_per_m: Vec<f64>,
    /// g nodes, ascending.
    pub g: Vec<f64>,
    /// Albedo nodes of each render's sweep, ascending (at most 16).
    pub albedos: Vec<f64>,
    /// Rings of laser–sensor separation the capture and the renders are reduced to (equal shares of
    /// the capture's histograms).
    pub rings: usize,
}

impl Default for TableSpec {
    fn default() -> TableSpec {
        TableSpec {
            grid: 8,
            spp: 256,
            forward_spp: 1024,
            seed: 0,
            mu_t_per_m: (0..12).map(|i| 0.25 * 1.35f64.powi(i)).collect(),
            g: vec![-0.8, -0.4, 0.0, 0.4, 0.8],
            albedos: (0..16).map(|i| 0.04 + 0.063 * i as f64).collect(),
            rings: RINGS,
        }
    }
}

/// Rings of laser–sensor separation and coarse bins: how a capture is reduced before fitting.
#[derive(Clone, Debug, PartialEq)]
pub struct Reduction {
    /// Upper separation (m) of each ring but the last.
    pub edges: Vec<f64>,
    /// Capture bins per coarse bin.
    pub per_bin: usize,
    pub coarse_bins: usize,
    /// The capture's laser–sensor separation (m) per histogram.
    separations: Vec<f64>,
}

/// The g from which a node is rendered at [`TableSpec::forward_spp`].
pub const FORWARD_G: f64 = 0.6;

impl TableSpec {
    /// The samples per point of a node at `g`.
    pub fn spp_at(&self, g: f64) -> u64 {
        if g >= FORWARD_G {
            self.forward_spp
        } else {
            self.spp
        }
    }
}

/// Rings of separation by default, and the path (m) a coarse bin spans at least.
const RINGS: usize = 4;
const COARSE_M: f64 = 0.05;

impl Reduction {
    /// `rings` rings at quantiles of `cap`'s separations; coarse bins of at least 5 cm of path.
    pub fn of(cap: &Capture, rings: usize) -> Reduction {
        let all = separations(cap);
        let mut sep = all.clone();
        sep.sort_by(f64::total_cmp);
        let rings = rings.max(1);
        let mut edges: Vec<f64> = (1..rings).map(|r| sep[r * sep.len() / rings]).collect();
        edges.dedup();
        let per_bin = ((COARSE_M / cap.time.bin_width_m).ceil() as usize).max(1);
        Reduction {
            edges,
            per_bin,
            coarse_bins: cap.time.bins / per_bin,
            separations: all,
        }
    }

    fn ring_of(&self, d: f64) -> usize {
        self.edges.iter().take_while(|&&e| d >= e).count()
    }

    /// The coarse bins of histogram `i` of `cap`, added to `out`.
    fn add_coarse(&self, cap: &Capture, i: usize, out: &mut [f64]) {
        let h = cap.histogram(i);
        for (b, s) in out.iter_mut().enumerate() {
            *s += h[b * self.per_bin..(b + 1) * self.per_bin]
                .iter()
                .map(|&v| v as f64)
                .sum::<f64>();
        }
    }

    /// A render of the same extent on a coarser grid, reduced to the capture's rings: each of the
    /// capture's histograms takes the render's response at its own separation (linear between the
    /// render's distinct separations, the nearest beyond them), and a ring averages those. A plain
    /// ring mean of the render would weigh its few separations, not the capture's, and the response
    /// changes with the separation.
    pub fn reduce_model(&self, render: &Capture) -> Vec<f64> {
        let n = self.coarse_bins;
        let (distinct, curves) = by_separation(render, n, |i, out| self.add_coarse(render, i, out));
        let mut weights = vec![vec![0.0f64; distinct.len()]; self.rings()];
        let mut members = vec![0usize; self.rings()];
        for &d in &self.separations {
            let r = self.ring_of(d);
            members[r] += 1;
            let k = distinct.partition_point(|&x| x <= d);
            if k == 0 {
                weights[r][0] += 1.0;
            } else if k == distinct.len() {
                weights[r][k - 1] += 1.0;
            } else {
                let w = (d - distinct[k - 1]) / (distinct[k] - distinct[k - 1]);
                weights[r][k - 1] += 1.0 - w;
                weights[r][k] += w;
            }
        }
        let mut out = vec![0.0f64; self.rings() * n];
        for (r, w) in weights.iter().enumerate() {
            for (c, &wk) in curves.iter().zip(w) {
                for (o, &v) in out[r * n..(r + 1) * n].iter_mut().zip(c) {
                    *o += wk * v / members[r].max(1) as f64;
                }
            }
        }
        out
    }

    pub fn rings(&self) -> usize {
        self.edges.len() + 1
    }

    /// Ring means over coarse bins, `[ring][bin]` flattened; NaN for a ring without histograms.
    pub fn reduce(&self, cap: &Capture) -> Vec<f64> {
        let n = self.coarse_bins;
        let mut sum = vec![0.0f64; self.rings() * n];
        let mut count = vec![0usize; self.rings()];
        for (i, d) in separations(cap).into_iter().enumerate() {
            let r = self.ring_of(d);
            count[r] += 1;
            self.add_coarse(cap, i, &mut sum[r * n..(r + 1) * n]);
        }
        for (r, &c) in count.iter().enumerate() {
            for s in &mut sum[r * n..(r + 1) * n] {
                *s = if c > 0 { *s / c as f64 } else { f64::NAN };
            }
        }
        sum
    }

    /// `k` separations (m) per ring, at the middles of equal shares of the ring's histograms.
    pub fn ring_separations(&self, k: usize) -> Vec<Vec<f64>> {
        let mut by_ring = vec![Vec::new(); self.rings()];
        for &d in &self.separations {
            by_ring[self.ring_of(d)].push(d);
        }
        by_ring
            .into_iter()
            .map(|mut ring| {
                ring.sort_by(f64::total_cmp);
                (0..k)
                    .filter_map(|q| ring.get((2 * q + 1) * ring.len() / (2 * k)).copied())
                    .collect()
            })
            .collect()
    }

    /// The largest separation (m) of `cap`'s histograms in each ring.
    pub fn ring_max_separations(&self, cap: &Capture) -> Vec<f64> {
        let mut max = vec![0.0f64; self.rings()];
        for d in separations(cap) {
            let r = self.ring_of(d);
            max[r] = max[r].max(d);
        }
        max
    }

    /// The path (m) at the middle of coarse bin `b` of `cap`.
    pub fn path_m(&self, cap: &Capture, b: usize) -> f64 {
        cap.time.start_m + (b as f64 + 0.5) * self.per_bin as f64 * cap.time.bin_width_m
    }
}

/// The distinct laser–sensor separations of `render` (to a micrometre), ascending, each with the
/// mean of its histograms as `add(histogram, curve)` accumulates them into curves of `n` values.
pub(crate) fn by_separation(
    render: &Capture,
    n: usize,
    add: impl Fn(usize, &mut [f64]),
) -> (Vec<f64>, Vec<Vec<f64>>) {
    let mut by_sep: Vec<(f64, usize)> = separations(render)
        .into_iter()
        .enumerate()
        .map(|(i, d)| (d, i))
        .collect();
    by_sep.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut distinct: Vec<f64> = Vec::new();
    let mut curves: Vec<Vec<f64>> = Vec::new();
    let mut counts: Vec<usize> = Vec::new();
    for (d, i) in by_sep {
        if distinct.last().is_none_or(|&last| d - last > 1e-6) {
            distinct.push(d);
            curves.push(vec![0.0; n]);
            counts.push(0);
        }
        let k = distinct.len() - 1;
        add(i, &mut curves[k]);
        counts[k] += 1;
    }
    for (c, &k) in curves.iter_mut().zip(&counts) {
        c.iter_mut().for_each(|v| *v /= k as f64);
    }
    (distinct, curves)
}

fn separations(cap: &Capture) -> Vec<f64> {
    (0..cap.n_hist())
        .map(|i| {
            let (l, s) = cap.hist_pair(i);
            cap.illum.points[l].distance(cap.sensor.points[s])
        })
        .collect()
}

/// Reduced medium-only responses on the (μt, g, albedo) grid.
#[derive(Clone, Debug, PartialEq)]
pub struct ResponseTable {
    pub mu_t_per_m: Vec<f64>,
    pub g: Vec<f64>,
    pub albedos: Vec<f64>,
    pub reduction: Reduction,
    pub spec: TableSpec,
    /// What it was built for: the medium-only scene, the capture's time axis and the options.
    built_for: (String, murk_core::TimeAxis, EstimateOptions),
    /// `[mu][g][albedo][ring][bin]` flattened.
    values: Vec<f64>,
}

impl ResponseTable {
    /// Renders `scene_text` (a medium-only scene of `cap`'s geometry) at every node (`node_values`).
    pub fn build(
        scene_text: &str,
        cap: &Capture,
        opt: &EstimateOptions,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<ResponseTable> {
        let spec = &opt.table;
        let (mu_t, g, albedos) = node_values(opt);
        let reduction = Reduction::of(cap, spec.rings);
        let nodes: Vec<(f64, f64)> = mu_t
            .iter()
            .flat_map(|&m| g.iter().map(move |&g| (m, g)))
            .collect();
        let done = AtomicUsize::new(0);
        progress(0, nodes.len());
        let rendered: Vec<Vec<f64>> = nodes
            .par_iter()
            .map(|&(m, gv)| {
                let out = render_node(scene_text, cap, spec, &albedos, m, gv, &reduction);
                progress(done.fetch_add(1, Ordering::Relaxed) + 1, nodes.len());
                out
            })
            .collect::<Result<_>>()?;
        Ok(ResponseTable {
            mu_t_per_m: mu_t,
            g,
            albedos,
            reduction,
            spec: spec.clone(),
            built_for: (scene_text.to_string(), cap.time, opt.clone()),
            values: rendered.concat(),
        })
    }

    /// Whether the table serves `cap` (same medium-only scene, time axis and options; a capture of the
    /// same scene on the same points).
    pub fn serves(&self, scene_text: &str, cap: &Capture, opt: &EstimateOptions) -> bool {
        let (s, t, o) = &self.built_for;
        s == scene_text
            && *t == cap.time
            && o.fit == opt.fit
            && o.fixed == opt.fixed
            && o.table == opt.table
            && self.reduction == Reduction::of(cap, o.table.rings)
    }

    /// Whether reduced value `i` has signal at nine in ten of the table's nodes or more: where the
    /// renders hold no paths the model cannot be compared.
    pub fn covers(&self, i: usize) -> bool {
        let per = self.reduction.rings() * self.reduction.coarse_bins;
        let nodes = self.values.len() / per;
        let lit = (0..nodes)
            .filter(|k| self.values[k * per + i] > 0.0)
            .count();
        lit * 10 >= nodes * 9
    }

    /// The number of values a table of these nodes and reduction holds.
    fn expected_len(&self) -> usize {
        self.mu_t_per_m.len()
            * self.g.len()
            * self.albedos.len()
            * self.reduction.rings()
            * self.reduction.coarse_bins
    }

    /// A table of the given nodes and values (`[mu][g][albedo][ring][bin]`), for tests of the fit.
    #[cfg(test)]
    pub(crate) fn from_values(
        mu_t_per_m: Vec<f64>,
        g: Vec<f64>,
        albedos: Vec<f64>,
        reduction: Reduction,
        values: Vec<f64>,
    ) -> ResponseTable {
        let time = murk_core::TimeAxis {
            start_m: 0.0,
            bin_width_m: 1.0,
            bins: 1,
        };
        ResponseTable {
            mu_t_per_m,
            g,
            albedos,
            reduction,
            spec: TableSpec::default(),
            built_for: (String::new(), time, EstimateOptions::default()),
            values,
        }
    }

    /// The reduced response at node (mu, g, albedo): `[ring][bin]`.
    pub fn node(&self, mu: usize, g: usize, albedo: usize) -> &[f64] {
        let per = self.reduction.rings() * self.reduction.coarse_bins;
        let i = (mu * self.g.len() + g) * self.albedos.len() + albedo;
        &self.values[i * per..(i + 1) * per]
    }
}

/// The table's nodes for `opt`: μt, g and albedo; a parameter that is not fitted gets one node, its
/// fixed value, except a given g inside the g nodes' range, which is interpolated between them as a
/// fitted one is: one node's Monte Carlo noise is then averaged with its neighbours', and one table
/// serves every g.
fn node_values(opt: &EstimateOptions) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let (spec, fit, fixed) = (&opt.table, &opt.fit, &opt.fixed);
    let pick = |fitted: bool, nodes: &[f64], value: f64| {
        if fitted {
            nodes.to_vec()
        } else {
            vec![value]
        }
    };
    (
        pick(fit.mu_t, &spec.mu_t_per_m, fixed.mu_t_per_m),
        pick(
            fit.g
                || matches!((spec.g.first(), spec.g.last()),
                    (Some(lo), Some(hi)) if (*lo..=*hi).contains(&fixed.g)),
            &spec.g,
            fixed.g,
        ),
        pick(fit.albedo, &spec.albedos, fixed.albedo),
    )
}

/// One (μt, g) node: the sweep's captures reduced, albedo after albedo.
fn render_node(
    scene_text: &str,
    cap: &Capture,
    spec: &TableSpec,
    albedos: &[f64],
    mu_t: f64,
    g: f64,
    reduction: &Reduction,
) -> Result<Vec<f64>> {
    let spec = TableSpec {
        spp: spec.spp_at(g),
        ..spec.clone()
    };
    let caps = render_medium_only(scene_text, cap, &spec, albedos, mu_t, g)?;
    Ok(caps
        .iter()
        .flat_map(|c| reduction.reduce_model(c))
        .collect())
}

/// `scene_text` (a medium-only scene of `cap`'s geometry) rendered on `spec`'s grid for μt and g, one
/// capture per albedo (an albedo sweep: one set of paths).
pub(crate) fn render_medium_only(
    scene_text: &str,
    cap: &Capture,
    spec: &TableSpec,
    albedos: &[f64],
    mu_t: f64,
    g: f64,
) -> Result<Vec<Capture>> {
    let top = albedos.iter().copied().fold(0.0, f64::max);
    let scene = table_scene(
        scene_text,
        cap,
        spec,
        vec![
            format!("medium.mu_t={mu_t}"),
            format!("medium.g={g}"),
            format!("medium.albedo={top}"),
        ],
    )?;
    if !scene.capture.time.same_as_stored(&cap.time) {
        return Err(Error::param(
            "scene_info.scene's time axis differs from the capture's: the capture was changed after rendering",
        ));
    }
    let plan = Plan::sweep(&scene, albedos)?;
    let opt = RenderOptions {
        spp: spec.spp,
        seed: spec.seed,
        shard: None,
        checkpoint: None,
        checkpoint_every: Duration::from_secs(3600),
    };
    plan.render_all_until(&opt, &|_, _| {}, &AtomicBool::new(false))
}

/// `scene_text` (a medium-only scene of `cap`'s geometry) on `spec`'s grid, with the scene
/// overrides `set`. A density grid is the capture's own cells, held in memory: the scene's `density`
/// only names them ([`crate::scene::medium_only`]).
fn table_scene(
    scene_text: &str,
    cap: &Capture,
    spec: &TableSpec,
    set: Vec<String>,
) -> Result<Scene> {
    let ov = Overrides {
        grid: Some(spec.grid),
        bins: None,
        set,
        ..Overrides::default()
    };
    let path = Path::new("scene_info.scene");
    Scene::from_str_with_density(scene_text, path, &ov, cap.medium_density.as_deref())
}
