//! The table's response at the grid search's candidates (μt, α, g): linear in albedo (a polynomial of
//! low order there); between μt and g nodes, ln of the response divided by the once-scattered light's
//! μt·exp(−μt·L)·phase factor ([`Angles`]) bilinear in ln μt and g, times that factor at (μt, g).
//! Once-scattered light, the part that tells g from α, is then exact between the nodes, value by
//! value, at the angles each ring and path sees: HG varies with g differently at each angle, so
//! weights taken from backscatter alone would bend α between the g nodes. Linear where a corner is
//! not positive.

use crate::single::Angles;
use crate::table::ResponseTable;
use rayon::prelude::*;

/// The once-scattered light's phase factor (ln, per used value) at the table's g nodes and at the
/// searched g values; empty when g is not fitted (one node, nothing to interpolate).
pub(super) struct Phase {
    nodes: Vec<Vec<f64>>,
    searched: Vec<Vec<f64>>,
}

impl Phase {
    pub(super) fn new(angles: &Angles, nodes: &[f64], searched: &[f64]) -> Phase {
        if nodes.len() < 2 {
            return Phase {
                nodes: Vec::new(),
                searched: Vec::new(),
            };
        }
        let mut all = angles.ln_phases(&[nodes, searched].concat());
        let searched = all.split_off(nodes.len());
        Phase {
            nodes: all,
            searched,
        }
    }
}

/// The candidates' grid over the table for the reduced values `used`. What does not change from
/// candidate to candidate is computed once: the brackets, and the once-scattered light's correction
/// per (μt, g); the table's nodes at one albedo and their ln are kept per worker ([`Corners`]). A
/// candidate then costs no exp or ln where its corners are positive (the model comes as its ln, which
/// the fit compares) and allocates nothing.
pub(super) struct Interpolation<'a> {
    table: &'a ResponseTable,
    used: &'a [usize],
    mus: Vec<(usize, usize, f64)>,
    albedos: Vec<(usize, usize, f64)>,
    gs: Vec<(usize, usize, f64)>,
    /// The attenuation's and the phase factor's corrections (ln) per `[mu][g][value]`: the factors
    /// of once-scattered light that the nodes' bracket does not interpolate exactly, exp(−μt·L) (not
    /// linear in ln μt, so the bracket's weights miss it on long paths between widely spaced nodes)
    /// and the phase factor.
    ln_factor: Vec<f64>,
}

impl<'a> Interpolation<'a> {
    /// The searched values `mus`, `albedos` and `gs`; `paths_m` is each used value's path.
    pub(super) fn new(
        table: &'a ResponseTable,
        used: &'a [usize],
        paths_m: &[f64],
        phase: &Phase,
        (mus, albedos, gs): (&[f64], &[f64], &[f64]),
    ) -> Interpolation<'a> {
        let mu_brackets: Vec<_> = mus
            .iter()
            .map(|&mu| bracket(&table.mu_t_per_m, mu, true))
            .collect();
        let g_brackets: Vec<_> = gs.iter().map(|&g| bracket(&table.g, g, false)).collect();
        let mut ln_factor = vec![0.0; mus.len() * gs.len() * used.len()];
        ln_factor
            .par_chunks_mut(gs.len() * used.len())
            .zip(mus.par_iter().zip(&mu_brackets))
            .for_each(|(row, (&mu, &(m0, m1, wm)))| {
                let (mu0, mu1) = (table.mu_t_per_m[m0], table.mu_t_per_m[m1]);
                let chunks = row.chunks_mut(used.len());
                for ((out, &(g0, g1, wg)), here) in chunks.zip(&g_brackets).zip(0..) {
                    for (k, f) in out.iter_mut().enumerate() {
                        let attenuation_ln = -paths_m[k] * (mu - (1.0 - wm) * mu0 - wm * mu1);
                        let phase_ln = match phase.searched.get(here) {
                            None => 0.0,
                            Some(at) => {
                                at[k] - (1.0 - wg) * phase.nodes[g0][k] - wg * phase.nodes[g1][k]
                            }
                        };
                        *f = attenuation_ln + phase_ln;
                    }
                }
            });
        Interpolation {
            table,
            used,
            mus: mu_brackets,
            albedos: albedos
                .iter()
                .map(|&a| bracket(&table.albedos, a, false))
                .collect(),
            gs: g_brackets,
            ln_factor,
        }
    }

    /// The searched values' counts: (μt, albedo, g).
    pub(super) fn shape(&self) -> (usize, usize, usize) {
        (self.mus.len(), self.albedos.len(), self.gs.len())
    }

    /// A worker's scratch for [`Interpolation::ln_model`].
    pub(super) fn corners(&self) -> Corners {
        let len = self.table.mu_t_per_m.len() * self.table.g.len() * self.used.len();
        Corners {
            albedo: None,
            filled: vec![false; self.table.mu_t_per_m.len()],
            value: vec![0.0; len],
            ln: vec![0.0; len],
        }
    }

    /// ln of the model at candidate (`mu`, `albedo`, `g`) (indices of the searched values) into
    /// `out`, one value per used value; −∞ where the model has no signal.
    pub(super) fn ln_model(
        &self,
        corners: &mut Corners,
        (mu, albedo, g): (usize, usize, usize),
        out: &mut [f64],
    ) {
        let (m0, m1, wm) = self.mus[mu];
        let (g0, g1, wg) = self.gs[g];
        corners.prepare(self, albedo, m0);
        corners.prepare(self, albedo, m1);
        let nu = self.used.len();
        let at = |m: usize, g: usize| (m * self.table.g.len() + g) * nu;
        let offsets = [at(m0, g0), at(m0, g1), at(m1, g0), at(m1, g1)];
        let w = [
            (1.0 - wm) * (1.0 - wg),
            (1.0 - wm) * wg,
            wm * (1.0 - wg),
            wm * wg,
        ];
        let ln_factor = &self.ln_factor[(mu * self.gs.len() + g) * nu..][..nu];
        let (value, ln) = (&corners.value, &corners.ln);
        for (k, (o, f)) in out.iter_mut().zip(ln_factor).enumerate() {
            let v = offsets.map(|c| value[c + k]);
            let ln_blend = if v.iter().all(|&x| x > 0.0) {
                let l = offsets.map(|c| ln[c + k]);
                w[0] * l[0] + w[1] * l[1] + w[2] * l[2] + w[3] * l[3]
            } else {
                // ln of a value ≤ 0 is −∞ or NaN: no signal either way.
                (w[0] * v[0] + w[1] * v[1] + w[2] * v[2] + w[3] * v[3]).ln()
            };
            *o = f + ln_blend;
        }
    }
}

/// A worker's scratch: the table's nodes interpolated at one searched albedo, `[mu][g][value]`, and
/// their ln, filled μt node by μt node as candidates need them.
pub(super) struct Corners {
    albedo: Option<usize>,
    filled: Vec<bool>,
    value: Vec<f64>,
    ln: Vec<f64>,
}

impl Corners {
    /// The nodes of μt node `m` at the `albedo`-th searched albedo, all g nodes.
    fn prepare(&mut self, grid: &Interpolation, albedo: usize, m: usize) {
        if self.albedo != Some(albedo) {
            self.albedo = Some(albedo);
            self.filled.fill(false);
        }
        if self.filled[m] {
            return;
        }
        self.filled[m] = true;
        let (a0, a1, wa) = grid.albedos[albedo];
        let (table, nu) = (grid.table, grid.used.len());
        for g in 0..table.g.len() {
            let (lo, hi) = (table.node(m, g, a0), table.node(m, g, a1));
            let at = (m * table.g.len() + g) * nu;
            let value = &mut self.value[at..at + nu];
            let ln = &mut self.ln[at..at + nu];
            for ((v, l), &i) in value.iter_mut().zip(ln.iter_mut()).zip(grid.used) {
                *v = (1.0 - wa) * lo[i] + wa * hi[i];
                *l = v.ln();
            }
        }
    }
}

/// The nodes around `x` (clamped to the range) and the weight of the upper one; `log`: in ln x.
pub(super) fn bracket(nodes: &[f64], x: f64, log: bool) -> (usize, usize, f64) {
    if nodes.len() == 1 {
        return (0, 0, 0.0);
    }
    let k = nodes
        .iter()
        .position(|&v| v > x)
        .unwrap_or(nodes.len())
        .clamp(1, nodes.len() - 1);
    let (a, b) = (nodes[k - 1], nodes[k]);
    let f = |v: f64| if log { v.ln() } else { v };
    let w = ((f(x) - f(a)) / (f(b) - f(a))).clamp(0.0, 1.0);
    (k - 1, k, w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bracket_finds_neighbours_and_weights() {
        let n = [1.0, 2.0, 4.0];
        assert_eq!(bracket(&n, 3.0, false), (1, 2, 0.5));
        let (a, b, w) = bracket(&n, 2.0f64.sqrt() * 2.0, true);
        assert_eq!((a, b), (1, 2));
        assert!((w - 0.5).abs() < 1e-12);
        assert_eq!(bracket(&n, 9.0, false), (1, 2, 1.0));
        assert_eq!(bracket(&n, 0.1, false), (0, 1, 0.0));
        assert_eq!(bracket(&[0.5], 3.0, false), (0, 0, 0.0));
    }

    /// A table of once-scattered light alone, α·μt·exp(−μt·L)·phase factor, interpolated between
    /// its nodes: exact at any (μt, α, g). Weights by the phase at backscatter alone are not: the
    /// outer ring's phase factor differs from HG at backscatter by more than a third.
    #[test]
    fn once_scattered_light_is_exact_between_nodes() {
        use murk_synth::{CaptureLayout, LayoutKind};
        let layout = CaptureLayout {
            kind: LayoutKind::LaserGridSinglePoint,
            wall_size_m: 2.0,
            grid: 16,
            point: murk_core::DVec3::ZERO,
            time: murk_core::TimeAxis {
                start_m: 2.0,
                bin_width_m: 0.05,
                bins: 40,
            },
            laser_xyz: None,
            sensor_xyz: None,
        };
        let cap = layout.empty_capture().unwrap();
        let red = crate::table::Reduction::of(&cap, 4);
        let n = red.coarse_bins;
        let all: Vec<usize> = (0..red.rings() * n).collect();
        let paths: Vec<f64> = all.iter().map(|&i| red.path_m(&cap, i % n)).collect();
        let angles = Angles::new(&red, &cap, &all);
        let (mus, gs, albedos) = (
            vec![1.0, 1.35, 1.8225],
            vec![-0.8, -0.4, 0.0, 0.4, 0.8],
            vec![0.1, 0.9],
        );
        let model = |mu: f64, a: f64, g: f64| -> Vec<f64> {
            let phase = angles.ln_phases(&[g]).remove(0);
            (0..all.len())
                .map(|k| a * mu * (-mu * paths[k] + phase[k]).exp())
                .collect()
        };
        let mut values = Vec::new();
        for &mu in &mus {
            for &g in &gs {
                for &a in &albedos {
                    values.extend(model(mu, a, g));
                }
            }
        }
        let table = ResponseTable::from_values(mus, gs.clone(), albedos, red, values);
        // Two candidates of each parameter, so that a worker's scratch serves several of them.
        let (searched_mu, searched_a, searched_g) = ([1.1, 1.6], [0.37, 0.8], [-0.1, 0.7]);
        let phase = Phase::new(&angles, &gs, &searched_g);
        let grid = Interpolation::new(
            &table,
            &all,
            &paths,
            &phase,
            (&searched_mu, &searched_a, &searched_g),
        );
        let mut corners = grid.corners();
        let mut got = vec![0.0; all.len()];
        for (m, &mu) in searched_mu.iter().enumerate() {
            for (a, &albedo) in searched_a.iter().enumerate() {
                for (k, &g) in searched_g.iter().enumerate() {
                    grid.ln_model(&mut corners, (m, a, k), &mut got);
                    let want = model(mu, albedo, g);
                    let worst = got
                        .iter()
                        .zip(&want)
                        .map(|(x, y)| (x.exp() / y - 1.0).abs())
                        .fold(0.0, f64::max);
                    assert!(worst < 1e-9, "({mu}, {albedo}, {g}): worst {worst}");
                }
            }
        }
        // The outer ring's angles differ from backscatter: its phase factor is not HG at π.
        let phase = angles.ln_phases(&[0.7, 0.0]);
        let outer = phase[0][3 * n + 5] - phase[1][3 * n + 5];
        let back = ((1.0f64 - 0.7) / 1.7 / 1.7).ln();
        assert!(
            outer - back > 0.3,
            "outer ring {outer} vs backscatter {back}"
        );
    }
}
