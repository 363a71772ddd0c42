//! Whether a capture's early bins are a medium's response.
//!
//! A medium filling the hidden side answers every histogram from the shortest path any scatterer can
//! give (the laser spot to the sensor point, |x_l − x_s|), decaying as the paths lengthen; a scene in
//! clear air answers nothing before its nearest surface, and a sensor's background is flat. So a
//! medium is detected when nearly every histogram holds signal just after its own earliest path, and
//! the summed histogram starts near its peak and decays from there. A closed room around the scene
//! does that too (its walls meet the relay and pass light around), but its early response depends on
//! where each laser point sits against the walls, while a homogeneous medium's depends only on the
//! laser–sensor separation: histograms of equal separation must agree. The room also fails to fade:
//! light from a medium next to the relay spreads as it travels, so past the largest separation the
//! summed response falls at least as fast as 1/path², while a room's walls, at a fixed distance, keep
//! returning light far more slowly.

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
/// The least fall of the summed response over [`SPREADING_SPAN_M`] of path, as a share of 1/path²'s
/// fall over it. Measured (64² and 32² renders, 64–256 spp, window from 1 or 2 m): 1.00–2.32 in fog
/// (μt 0.25–2, α 0.15–0.83, g −0.7–0.7; lowest for g = −0.7, α = 0.83 and for μt = 0.25, α = 0.15),
/// the shelf's closed room in fog 1.14 (μt = 1) and 1.34 (μt = 1.5), the room without fog 0.74–0.76
/// at 16² and 64², 256 and 1 024 spp (docs/medium.md).
const MIN_SPREADING_FALL: f64 = 0.88;
/// The path (m) over which the fall is measured: short, so that a hidden object seldom enters it.
const SPREADING_SPAN_M: f64 = 0.5;

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
    /// How much the summed response falls over 0.5 m of path from 10 cm past the largest separation,
    /// as a share of 1/path²'s fall (path counted from the relay); `None` where the window is too short.
    pub spreading_fall: Option<f64>,
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
            spreading_fall: spreading_fall(cap, &summed, early_bins),
            early_m,
        }
    }

    /// Whether the early bins are a medium's response.
    pub fn is_medium(&self) -> bool {
        self.share_with_signal >= MIN_SHARE_WITH_SIGNAL
            && self.early_level >= MIN_EARLY_LEVEL
            && self.decay >= MIN_DECAY
            && self.ring_spread <= MAX_RING_SPREAD
            && self.spreading_fall.is_none_or(|f| f >= MIN_SPREADING_FALL)
    }

    /// One line for a summary.
    pub fn describe(&self) -> String {
        let fall = match self.spreading_fall {
            Some(f) => format!(
                "; over {SPREADING_SPAN_M} m of path past the largest separation the summed response falls {:.0} % as fast as 1/path²",
                100.0 * f
            ),
            None => String::new(),
        };
        format!(
            "{:.0} % of histograms hold signal within {} m of their earliest path; the first bins reach {:.0} % of the summed peak and {:.0}× the last quarter's level; histograms of equal laser–sensor separation agree within {:.0} %{fall}",
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

/// The fall of `summed` (mean over `bins` bins) from 10 cm past the largest earliest path (or the
/// window's start) to [`SPREADING_SPAN_M`] later, over (path_late / path_early)², the paths at the
/// segments' middles less the device legs; `None` where the window ends first or the late segment is
/// dark.
fn spreading_fall(cap: &Capture, summed: &[f64], bins: usize) -> Option<f64> {
    let (dt, start) = (cap.time.bin_width_m, cap.time.start_m);
    let earliest_m = (0..cap.n_hist())
        .map(|i| {
            let (l, s) = cap.hist_pair(i);
            cap.illum.points[l].distance(cap.sensor.points[s])
                + cap.first_bounce_m(l)
                + cap.last_bounce_m(s)
        })
        .fold(0.0, f64::max);
    let legs_m = (0..cap.n_hist())
        .map(|i| {
            let (l, s) = cap.hist_pair(i);
            cap.first_bounce_m(l) + cap.last_bounce_m(s)
        })
        .fold(f64::INFINITY, f64::min);
    let first = ((earliest_m + 0.1).max(start) - start) / dt;
    if !first.is_finite() {
        return None;
    }
    let first = first.ceil() as usize;
    let late = first + (SPREADING_SPAN_M / dt).round() as usize;
    if late + bins > summed.len() {
        return None;
    }
    let mean = |a: usize| summed[a..a + bins].iter().sum::<f64>() / bins as f64;
    let path = |a: usize| start + (a as f64 + bins as f64 / 2.0) * dt - legs_m;
    let (early, later) = (mean(first), mean(late));
    (later > 0.0 && path(first) > 0.0).then(|| early / later / (path(late) / path(first)).powi(2))
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

#[cfg(test)]
mod tests {
    use super::*;
    use murk_core::{DVec3, PointSet, TimeAxis};

    /// A confocal 4 × 4 capture of `bins` bins of 1 cm from 1 m of path whose every histogram is
    /// `f(path)` at its bins' middles: the segments compared are 1.0–1.2 m and 1.5–1.7 m.
    fn capture(bins: usize, f: impl Fn(f64) -> f64) -> Capture {
        let time = TimeAxis {
            start_m: 1.0,
            bin_width_m: 0.01,
            bins,
        };
        let h: Vec<f32> = (0..bins)
            .map(|b| f(time.start_m + (b as f64 + 0.5) * time.bin_width_m) as f32)
            .collect();
        Capture::confocal(
            PointSet::wall_grid(DVec3::ZERO, 1.0, 1.0, 4, 4),
            time,
            h.repeat(16),
            String::new(),
        )
    }

    /// Once-scattered light next to the relay, exp(−μt·path)/path², falls faster than 1/path² by
    /// exp(μt · 0.5 m) (to the segments' width: within 2 %). A wall at a fixed distance whose return
    /// fades as 1/path falls at 69 % of 1/path²'s pace (ln 1.2 / ln(1.7/1.5) over (1.6/1.1)²) and is
    /// no medium, though it passes every other test.
    #[test]
    fn a_medium_falls_at_least_as_fast_as_its_spreading() {
        let fog = Signature::measure(&capture(400, |t| (-t).exp() / (t * t)));
        let fall = fog.spreading_fall.unwrap();
        assert!((fall / 0.5f64.exp() - 1.0).abs() < 0.02, "{fall}");
        assert!(fog.is_medium(), "{fog:?}");
        let room = Signature::measure(&capture(400, |t| 1.0 / t));
        let fall = room.spreading_fall.unwrap();
        assert!((fall - 0.689).abs() < 0.005, "{fall}");
        assert!(!room.is_medium(), "{room:?}");
        let passes_the_rest = Signature {
            spreading_fall: None,
            ..room
        };
        assert!(passes_the_rest.is_medium(), "{room:?}");
        assert!(
            room.describe()
                .ends_with("the summed response falls 69 % as fast as 1/path²"),
            "{}",
            room.describe()
        );
        // A window that ends before the second segment cannot tell: the other tests decide.
        assert_eq!(
            Signature::measure(&capture(55, |t| 1.0 / t)).spreading_fall,
            None
        );
    }
}
