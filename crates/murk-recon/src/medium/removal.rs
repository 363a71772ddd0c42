//! The medium's response estimated from the capture itself and subtracted (model-free, in the spirit
//! of Satat et al.'s per-pixel fog fit for line-of-sight imaging), or predicted by a forward model
//! elsewhere ([`Predicted`], which murk-medium renders) and subtracted as it is.
//!
//! In a homogeneous medium filling the hidden side, the medium's response to a histogram depends on
//! the distance between its laser spot and its sensor point, not on where they are on the wall. So the
//! histograms are grouped into rings of equal separation, and a ring's mean histogram, smoothed over
//! [`SMOOTH_SHARE`] of each bin's path, is its medium response. The smoothing keeps an object's return
//! (short, and different at each point of a ring) out of the estimate; the medium's response varies
//! on a scale that grows with the path (it is sharp near its earliest path and slow later).

use super::detect::Signature;
use murk_core::{Capture, Error, Result};

/// The width over which a ring's mean histogram is smoothed, as a share of the bin's optical path:
/// much longer than an object's return at one point, shorter than the medium's decay. On the 64² Z in
/// fog (μt = 1, α = 0.5) a fixed 45 mm took the Z's return with it (front-view IoU 0.69 → 0.54) and a
/// fixed 0.5 m did not, but left the sharp early response of a wall-side medium in the residual.
pub const SMOOTH_SHARE: f64 = 0.25;
/// At most this many rings, each of at least [`MIN_RING`] histograms.
const MAX_RINGS: usize = 16;
const MIN_RING: usize = 16;

/// What was removed, for a reconstruction's summary.
#[derive(Clone, Debug, PartialEq)]
pub struct Removed {
    /// The detector's measurement (`None` when removal was asked for without detection).
    pub signature: Option<Signature>,
    /// Where the subtracted response came from, in words.
    pub source: String,
    /// The share of the capture's energy (sum of squares) that the subtraction removed.
    pub share: f64,
}

impl Removed {
    /// One line for a summary.
    pub fn describe(&self) -> String {
        let why = self.signature.map_or("asked for".to_string(), |s| {
            format!("detected: {}", s.describe())
        });
        format!(
            "{why}; its response {} and subtracted: {:.1} % of the signal's energy",
            self.source,
            100.0 * self.share
        )
    }
}

/// A medium's response predicted per laser–sensor separation at a capture's own bins.
#[derive(Clone, Debug, PartialEq)]
pub struct Predicted {
    /// The separations (m) the curves were predicted at, ascending.
    pub separations_m: Vec<f64>,
    /// One response per separation, each as long as the capture's time axis.
    pub curves: Vec<Vec<f32>>,
    /// How it was predicted, for the summary ("rendered for μt 1 /m, …").
    pub source: String,
}

impl Predicted {
    /// The response at separation `d` (m): linear between the two nearest separations predicted, the
    /// nearest one beyond them.
    fn at(&self, d: f64, out: &mut [f32]) {
        let s = &self.separations_m;
        let k = s.partition_point(|&x| x <= d);
        let (a, b, w) = match k {
            0 => (0, 0, 0.0),
            k if k == s.len() => (k - 1, k - 1, 0.0),
            k => (k - 1, k, ((d - s[k - 1]) / (s[k] - s[k - 1])) as f32),
        };
        for ((o, &x), &y) in out.iter_mut().zip(&self.curves[a]).zip(&self.curves[b]) {
            *o = x + w * (y - x);
        }
    }
}

/// Subtracts `predicted` from every histogram of `cap`, each at its own separation.
pub fn subtract_predicted(
    cap: &mut Capture,
    predicted: &Predicted,
    signature: Option<Signature>,
) -> Result<Removed> {
    let bins = cap.time.bins;
    if predicted.separations_m.is_empty()
        || predicted.curves.len() != predicted.separations_m.len()
        || predicted.curves.iter().any(|c| c.len() != bins)
    {
        return Err(Error::param(format!(
            "the predicted medium response does not match the capture ({} separations, {} curves, the capture has {bins} bins)",
            predicted.separations_m.len(),
            predicted.curves.len()
        )));
    }
    let mut model = vec![0.0f32; bins];
    let (mut total, mut left) = (0.0f64, 0.0f64);
    for (i, d) in separations(cap).into_iter().enumerate() {
        predicted.at(d, &mut model);
        for (v, &m) in cap.h[i * bins..(i + 1) * bins].iter_mut().zip(&model) {
            total += (*v as f64).powi(2);
            *v -= m;
            left += (*v as f64).powi(2);
        }
    }
    Ok(Removed {
        signature,
        source: predicted.source.clone(),
        share: energy_share(total, left),
    })
}

fn energy_share(total: f64, left: f64) -> f64 {
    if total > 0.0 {
        1.0 - left / total
    } else {
        0.0
    }
}

/// Subtracts the fitted medium response from every histogram of `cap`.
pub fn subtract(cap: &mut Capture, signature: Option<Signature>) -> Removed {
    let bins = cap.time.bins;
    let ring = rings(&separations(cap));
    let n_rings = ring.iter().copied().max().map_or(0, |r| r + 1);
    let mut mean = vec![0.0f64; n_rings * bins];
    let mut count = vec![0usize; n_rings];
    for (i, &r) in ring.iter().enumerate() {
        count[r] += 1;
        for (m, &v) in mean[r * bins..(r + 1) * bins]
            .iter_mut()
            .zip(cap.histogram(i))
        {
            *m += v as f64;
        }
    }
    let dt = cap.time.bin_width_m;
    let half: Vec<usize> = (0..bins)
        .map(|b| {
            let path_m = (cap.time.start_m + (b as f64 + 0.5) * dt).max(0.0);
            ((SMOOTH_SHARE * path_m / dt / 2.0).round() as usize).max(1)
        })
        .collect();
    let model: Vec<Vec<f32>> = (0..n_rings)
        .map(|r| {
            let m: Vec<f64> = mean[r * bins..(r + 1) * bins]
                .iter()
                .map(|v| v / count[r].max(1) as f64)
                .collect();
            moving_average(&m, &half)
                .into_iter()
                .map(|v| v as f32)
                .collect()
        })
        .collect();
    let (mut total, mut left) = (0.0f64, 0.0f64);
    for (i, &r) in ring.iter().enumerate() {
        let h = &mut cap.h[i * bins..(i + 1) * bins];
        for (v, &m) in h.iter_mut().zip(&model[r]) {
            total += (*v as f64).powi(2);
            *v -= m;
            left += (*v as f64).powi(2);
        }
    }
    Removed {
        signature,
        source: format!(
            "fitted from the capture ({n_rings} rings of equal laser–sensor separation, smoothed over {:.0} % of the path)",
            100.0 * SMOOTH_SHARE
        ),
        share: energy_share(total, left),
    }
}

/// Each histogram's laser–sensor separation (m).
pub(super) fn separations(cap: &Capture) -> Vec<f64> {
    (0..cap.n_hist())
        .map(|i| {
            let (l, s) = cap.hist_pair(i);
            cap.illum.points[l].distance(cap.sensor.points[s])
        })
        .collect()
}

/// Each histogram's ring: quantiles of the separation, so that rings hold equal numbers of histograms;
/// histograms of equal separation always share a ring.
pub(super) fn rings(separation: &[f64]) -> Vec<usize> {
    let n = separation.len();
    let n_rings = (n / MIN_RING).clamp(1, MAX_RINGS);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| separation[a].total_cmp(&separation[b]));
    let mut ring = vec![0usize; n];
    let mut current = 0;
    for (rank, &i) in order.iter().enumerate() {
        let wanted = rank * n_rings / n;
        // A new ring starts only where the separation changes.
        if wanted > current && separation[i] > separation[order[rank - 1]] {
            current = wanted;
        }
        ring[i] = current;
    }
    // Rings left empty by ties are closed up.
    let mut used: Vec<usize> = ring.clone();
    used.sort_unstable();
    used.dedup();
    ring.iter()
        .map(|r| used.binary_search(r).unwrap_or(0))
        .collect()
}

/// The mean over `2·half[i] + 1` bins centred on each bin `i`, shrinking symmetrically at the ends so
/// that a decaying response is not pulled toward the window's edge.
pub fn moving_average(v: &[f64], half: &[usize]) -> Vec<f64> {
    let mut prefix = vec![0.0f64; v.len() + 1];
    for (i, x) in v.iter().enumerate() {
        prefix[i + 1] = prefix[i] + x;
    }
    (0..v.len())
        .map(|i| {
            let h = half[i].min(i).min(v.len() - 1 - i);
            (prefix[i + h + 1] - prefix[i - h]) / (2 * h + 1) as f64
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moving_average_keeps_a_line_and_shrinks_at_the_ends() {
        let line: Vec<f64> = (0..50).map(|i| 2.0 + 0.5 * i as f64).collect();
        let half: Vec<usize> = (0..50).map(|i| 1 + i / 5).collect();
        let avg = moving_average(&line, &half);
        for (a, b) in avg.iter().zip(&line) {
            assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        }
        assert_eq!(
            moving_average(&[1.0, 5.0, 3.0], &[4; 3]),
            vec![1.0, 3.0, 3.0]
        );
    }

    #[test]
    fn a_prediction_is_subtracted_at_each_histograms_separation() {
        use murk_core::{DVec3, PointSet, TimeAxis};
        // One SPAD point at the origin, laser points 0, 0.5 and 1 m away.
        let lasers = PointSet::wall_grid(DVec3::new(0.5, 0.0, 0.0), 1.5, 0.1, 3, 1);
        let time = TimeAxis {
            start_m: 0.0,
            bin_width_m: 0.1,
            bins: 2,
        };
        let mut cap = Capture {
            sensor: PointSet::single(DVec3::ZERO),
            pairing: murk_core::Pairing::Product,
            ..Capture::confocal(lasers, time, vec![10.0; 6], String::new())
        };
        let predicted = Predicted {
            separations_m: vec![0.0, 1.0],
            curves: vec![vec![2.0, 4.0], vec![4.0, 8.0]],
            source: "test".into(),
        };
        let removed = subtract_predicted(&mut cap, &predicted, None).unwrap();
        assert_eq!(cap.h, vec![8.0, 6.0, 7.0, 4.0, 6.0, 2.0]);
        assert_eq!(removed.source, "test");
        let short = Predicted {
            curves: vec![vec![1.0]; 2],
            ..predicted
        };
        let e = subtract_predicted(&mut cap, &short, None).unwrap_err();
        assert!(e.to_string().contains("does not match the capture"), "{e}");
    }

    #[test]
    fn rings_split_by_separation_and_keep_ties_together() {
        let sep: Vec<f64> = (0..64).map(|i| (i / 4) as f64).collect();
        let r = rings(&sep);
        assert_eq!(r.iter().max(), Some(&3));
        for (i, j) in (0..64).zip(1..64) {
            if sep[i] == sep[j] {
                assert_eq!(r[i], r[j]);
            }
            assert!(r[j] >= r[i]);
        }
        // All equal (confocal): one ring.
        assert!(rings(&[0.0; 100]).iter().all(|&r| r == 0));
    }
}
