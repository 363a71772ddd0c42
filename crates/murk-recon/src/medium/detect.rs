//! Whether a capture's early bins are a medium's response.
//!
//! A medium filling the hidden side answers every histogram from the shortest path any scatterer can
//! give (the laser spot to the sensor point, |x_l − x_s|), decaying as the paths lengthen; a scene in
//! clear air answers nothing before its nearest surface, and a sensor's background is flat. So a
//! medium is detected when nearly every histogram holds signal just after its own earliest path, and
//! the summed histogram starts near its peak and decays from there. A closed room around the scene
//! does that too (its walls meet the relay and pass light around), but its early response depends on
//! where each laser point sits against the walls, while a homogeneous medium's depends only on the
//! laser–sensor separation: histograms of equal separation must agree.

use murk_core::Capture;

/// Share of histograms that must hold signal right after their earliest path.
const MIN_SHARE_WITH_SIGNAL: f64 = 0.95;
/// The early level, relative to the summed histogram's peak, from which the early bins count as the
/// medium's (its response peaks at the start; an object's return in clear air is zero there).
const MIN_EARLY_LEVEL: f64 = 0.25;
/// How much the early level must exceed the late one (a flat background does not decay).
const MIN_DECAY: f64 = 3.0;
/// The largest spread of the early signal among histograms of equal separation (coefficient of
/// variation within rings). Measured at 0.04–0.15 in renders of fog (64² points, 64–256 spp, μt 0.5–2,
/// g −0.7–0.7, the T and the Z) but 0.22 for g = 0.7, α = 0.83 at 128 spp, and in the shelf's closed
/// room without fog at 0.40 (64 spp) and 0.24 (512 spp): the room's spread shrinks with the Monte
/// Carlo noise, so this test separates it from fog only at low sample counts (docs/medium.md).
const MAX_RING_SPREAD: f64 = 0.25;

/// What [`Signature::measure`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Signature {
    /// Share of histograms with signal within `early_m` of their earliest path.
    pub share_with_signal: f64,
    /// The summed histogram's mean over its early bins, relative to its peak.
    pub early_level: f64,
    /// Early mean over the mean of the window's last quarter.
    pub decay: f64,
    /// Coefficient of variation of each histogram's early signal within rings of equal separation,
    /// over `early_m` from 10 cm past the largest separation (or the window's start).
    pub ring_spread: f64,
    /// Length of the early segment (m of path).
    pub early_m: f64,
}

impl Signature {
    /// Measures the capture's early bins. The early segment is 5 % of the window, at least 10 bins.
    pub fn measure(cap: &Capture) -> Signature {
        let bins = cap.time.bins;
        let dt = cap.time.bin_width_m;
        let early_bins = (bins / 20).max(10).min(bins);
        let early_m = early_bins as f64 * dt;
        let mut with_signal = 0usize;
        for i in 0..cap.n_hist() {
            let first = first_bin(cap, i);
            let h = cap.histogram(i);
            let end = (first + early_bins).min(bins);
            if h[first.min(bins)..end].iter().any(|&v| v > 0.0) {
                with_signal += 1;
            }
        }
        let summed = summed(cap);
        let peak = summed.iter().copied().fold(0.0, f64::max);
        let start = (0..cap.n_hist())
            .map(|i| first_bin(cap, i))
            .min()
            .unwrap_or(0)
            .min(bins.saturating_sub(1));
        let mean = |a: usize, b: usize| summed[a..b].iter().sum::<f64>() / (b - a).max(1) as f64;
        let early = mean(start, (start + early_bins).min(bins));
        let late = mean(bins - bins / 4, bins);
        Signature {
            share_with_signal: with_signal as f64 / cap.n_hist().max(1) as f64,
            early_level: if peak > 0.0 { early / peak } else { 0.0 },
            decay: if late > 0.0 {
                early / late
            } else {
                f64::INFINITY
            },
            ring_spread: ring_spread(cap, early_bins),
            early_m,
        }
    }

    /// Whether the early bins are a medium's response.
    pub fn is_medium(&self) -> bool {
        self.share_with_signal >= MIN_SHARE_WITH_SIGNAL
            && self.early_level >= MIN_EARLY_LEVEL
            && self.decay >= MIN_DECAY
            && self.ring_spread <= MAX_RING_SPREAD
    }

    /// One line for a summary.
    pub fn describe(&self) -> String {
        format!(
            "{:.0} % of histograms hold signal within {} m of their earliest path; the first bins reach {:.0} % of the summed peak and {:.0}× the last quarter's level; histograms of equal laser–sensor separation agree within {:.0} %",
            100.0 * self.share_with_signal,
            murk_core::short(self.early_m),
            100.0 * self.early_level,
            self.decay.min(1e6),
            100.0 * self.ring_spread
        )
    }
}

/// The bin of histogram `i`'s earliest path through a medium: its laser spot to its sensor point
/// (plus the device legs where the time stamps include them), or the window's start.
fn first_bin(cap: &Capture, i: usize) -> usize {
    let (l, s) = cap.hist_pair(i);
    let path_m = cap.illum.points[l].distance(cap.sensor.points[s])
        + cap.first_bounce_m(l)
        + cap.last_bounce_m(s);
    let bin = ((path_m - cap.time.start_m) / cap.time.bin_width_m).floor();
    if bin.is_finite() && bin > 0.0 {
        (bin as usize).min(cap.time.bins)
    } else {
        0
    }
}

/// The coefficient of variation of each histogram's signal over `bins` bins from 10 cm past the
/// largest separation (or the window's start), within rings of equal separation.
fn ring_spread(cap: &Capture, bins: usize) -> f64 {
    let sep = super::removal::separations(cap);
    let largest = sep.iter().copied().fold(0.0, f64::max);
    let from_m = (largest + 0.1).max(cap.time.start_m);
    let first = (((from_m - cap.time.start_m) / cap.time.bin_width_m).ceil() as usize)
        .min(cap.time.bins.saturating_sub(bins));
    let energy: Vec<f64> = (0..cap.n_hist())
        .map(|i| {
            cap.histogram(i)[first..(first + bins).min(cap.time.bins)]
                .iter()
                .map(|&v| v as f64)
                .sum()
        })
        .collect();
    let ring = super::removal::rings(&sep);
    let n_rings = ring.iter().copied().max().map_or(0, |r| r + 1);
    let (mut sum, mut count) = (vec![0.0f64; n_rings], vec![0usize; n_rings]);
    for (&r, &e) in ring.iter().zip(&energy) {
        sum[r] += e;
        count[r] += 1;
    }
    let squares: f64 = ring
        .iter()
        .zip(&energy)
        .map(|(&r, &e)| (e - sum[r] / count[r] as f64).powi(2))
        .sum();
    let mean = energy.iter().sum::<f64>() / energy.len().max(1) as f64;
    if mean > 0.0 {
        (squares / energy.len() as f64).sqrt() / mean
    } else {
        f64::INFINITY
    }
}

/// The sum of every histogram, per bin.
pub(crate) fn summed(cap: &Capture) -> Vec<f64> {
    let mut out = vec![0.0f64; cap.time.bins];
    for i in 0..cap.n_hist() {
        for (o, &v) in out.iter_mut().zip(cap.histogram(i)) {
            *o += v as f64;
        }
    }
    out
}
