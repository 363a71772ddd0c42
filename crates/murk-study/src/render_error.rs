//! A render's error, the protocol of docs/benchmarks.md: relative L2 error over an object time window,
//! against a reference render or estimated from two independent ones. Used by the study's render
//! error column, `murk-bench --render` and the `bench_error` example.

use murk_core::TimeAxis;

/// Which entries of a histogram array (bins fastest) have their bin centre in `[w0, w1)` metres.
pub fn window_mask(t: &TimeAxis, n: usize, (w0, w1): (f64, f64)) -> Vec<bool> {
    (0..n)
        .map(|i| {
            let c = t.start_m + ((i % t.bins) as f64 + 0.5) * t.bin_width_m;
            c >= w0 && c < w1
        })
        .collect()
}

/// ‖h − reference‖₂ / ‖reference‖₂ over the masked entries.
pub fn rel_l2(h: &[f32], reference: &[f32], mask: &[bool]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for ((x, r), _) in h.iter().zip(reference).zip(mask).filter(|(_, m)| **m) {
        num += ((x - r) as f64).powi(2);
        den += (*r as f64).powi(2);
    }
    (num / den).sqrt()
}

/// One run's relative L2 error over the masked entries estimated from two independent runs, without a
/// reference: E‖a − b‖² = 2·Σ var, and ‖(a + b)/2‖² overestimates Σ mean² by Σ var / 2.
pub fn split_rel_l2(a: &[f32], b: &[f32], mask: &[bool]) -> f64 {
    let (mut diff, mut mean) = (0.0, 0.0);
    for ((x, y), _) in a.iter().zip(b).zip(mask).filter(|(_, m)| **m) {
        diff += ((x - y) as f64).powi(2);
        mean += ((x + y) as f64 / 2.0).powi(2);
    }
    let var = diff / 2.0;
    (var / (mean - var / 2.0)).sqrt()
}
