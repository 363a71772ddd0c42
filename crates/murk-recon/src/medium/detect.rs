//! Whether a capture's early bins are a medium's response.
//!
//! A medium filling the hidden side answers every histogram from the shortest path any scatterer can
//! give (the laser spot to the sensor point, |x_l − x_s|), decaying as the paths lengthen; a scene in
//! clear air answers nothing before its nearest surface, and a sensor's background is flat. So a
//! medium is detected when nearly every histogram holds signal just after its own earliest path, and
//! the summed histogram starts near its peak and decays from there.

use murk_core::Capture;

/// Share of histograms that must hold signal right after their earliest path.
const MIN_SHARE_WITH_SIGNAL: f64 = 0.95;
/// The early level, relative to the summed histogram's peak, from which the early bins count as the
/// medium's (its response peaks at the start; an object's return in clear air is zero there).
const MIN_EARLY_LEVEL: f64 = 0.25;
/// How much the early level must exceed the late one (a flat background does not decay).
const MIN_DECAY: f64 = 3.0;

/// What [`Signature::measure`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Signature {
    /// Share of histograms with signal within `early_m` of their earliest path.
    pub share_with_signal: f64,
    /// The summed histogram's mean over its early bins, relative to its peak.
    pub early_level: f64,
    /// Early mean over the mean of the window's last quarter.
    pub decay: f64,
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
            early_m,
        }
    }

    /// Whether the early bins are a medium's response.
    pub fn is_medium(&self) -> bool {
        self.share_with_signal >= MIN_SHARE_WITH_SIGNAL
            && self.early_level >= MIN_EARLY_LEVEL
            && self.decay >= MIN_DECAY
    }

    /// One line for a summary.
    pub fn describe(&self) -> String {
        format!(
            "{:.0} % of histograms hold signal within {} m of their earliest path; the first bins reach {:.0} % of the summed peak and {:.0}× the last quarter's level",
            100.0 * self.share_with_signal,
            murk_core::short(self.early_m),
            100.0 * self.early_level,
            self.decay.min(1e6)
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
