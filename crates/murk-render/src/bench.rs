//! A timed render, for the efficiency protocol of docs/benchmarks.md (the error side is
//! `murk_study::render_error`): CPU time of the process (all threads) and paths traced. Used by
//! `murk-bench --render` and the `bench_error` example.

use crate::render::{Plan, RenderOptions};
use murk_core::process::cpu_seconds;
use murk_core::Result;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

/// One timed render.
pub struct Run {
    /// The first capture's histograms (a plain plan's only one).
    pub h: Vec<f32>,
    /// The other captures' of an albedo sweep ([`Plan::sweep`]), in its albedos' order.
    pub rest: Vec<Vec<f32>>,
    pub cpu_s: f64,
    pub wall_s: f64,
    /// Traced paths: rendered units × spp.
    pub paths: f64,
}

/// Renders `plan` (or one shard of it; a plain render or an albedo sweep) with `spp` and `seed`,
/// timing it.
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
    let mut caps = plan
        .render_all_until(&opt, &|_, _| {}, &AtomicBool::new(false))?
        .into_iter()
        .map(|c| c.h);
    let wall_s = t0.elapsed().as_secs_f64();
    Ok(Run {
        h: caps.next().unwrap_or_default(),
        rest: caps.collect(),
        cpu_s: cpu_seconds().zip(c0).map_or(wall_s, |(c1, c0)| c1 - c0),
        wall_s,
        paths: plan.shard_points(shard) as f64 * spp as f64,
    })
}
