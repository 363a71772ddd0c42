//! Efficiency measurement, the protocol of docs/benchmarks.md: relative L2 error over an object time
//! window, CPU time of the process (all threads) and paths per CPU-second. Used by `murk-bench --render`
//! and the `bench_error` example.

use crate::render::{Plan, RenderOptions};
use murk_core::{Result, TimeAxis};
use std::time::{Duration, Instant};

/// User + system CPU seconds of this process, all threads (Linux /proc, 100 ticks per second); `None`
/// elsewhere.
pub fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let fields: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    let ticks = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// Peak resident memory of this process so far (Linux), in MiB.
pub fn peak_rss_mib() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace()
        .nth(1)?
        .parse::<f64>()
        .ok()
        .map(|kb| kb / 1024.0)
}

/// One timed render.
pub struct Run {
    pub h: Vec<f32>,
    pub cpu_s: f64,
    pub wall_s: f64,
    /// Traced paths: rendered units × spp.
    pub paths: f64,
}

/// Renders `plan` (or one shard of it) with `spp` and `seed`, timing it.
pub fn timed_render(
    plan: &Plan,
    spp: u64,
    seed: u64,
    shard: Option<(usize, usize)>,
) -> Result<Run> {
    let opt = RenderOptions {
        spp,
        seed,
        shard,
        checkpoint: None,
        checkpoint_every: Duration::ZERO,
    };
    let (c0, t0) = (cpu_seconds(), Instant::now());
    let cap = plan.render(&opt, &|_, _| {})?;
    let wall_s = t0.elapsed().as_secs_f64();
    Ok(Run {
        h: cap.h,
        cpu_s: cpu_seconds().zip(c0).map_or(wall_s, |(c1, c0)| c1 - c0),
        wall_s,
        paths: plan.shard_points(shard) as f64 * spp as f64,
    })
}

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
