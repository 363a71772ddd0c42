//! Efficiency benchmark: object-window relative L2 error against a long reference render, CPU time and
//! paths per CPU-second, median of several seeds (the protocol of mitransient.md §7.4).
//!
//! `cargo run --release -p murk-render --example bench_error -- SCENE.toml SPP REF_SPP RUNS [WIN_START WIN_END]`

use murk_render::{Overrides, Plan, RenderOptions, Scene};
use std::path::Path;
use std::time::{Duration, Instant};

/// User + system CPU seconds of this process, all threads (Linux /proc, 100 ticks per second).
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").expect("/proc/self/stat");
    let fields: Vec<&str> = stat
        .rsplit_once(')')
        .expect("comm")
        .1
        .split_whitespace()
        .collect();
    let ticks: f64 = fields[11].parse::<f64>().unwrap() + fields[12].parse::<f64>().unwrap();
    ticks / 100.0
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    if a.len() < 5 {
        eprintln!("usage: bench_error SCENE.toml SPP REF_SPP RUNS [WIN_START WIN_END]");
        std::process::exit(2);
    }
    let scene =
        Scene::load(Path::new(&a[1]), &Overrides::default()).unwrap_or_else(|e| panic!("{e}"));
    let (spp, ref_spp, runs): (u64, u64, usize) = (
        a[2].parse().unwrap(),
        a[3].parse().unwrap(),
        a[4].parse().unwrap(),
    );
    let (w0, w1): (f64, f64) = match (a.get(5), a.get(6)) {
        (Some(x), Some(y)) => (x.parse().unwrap(), y.parse().unwrap()),
        _ => (1.98, 2.70),
    };
    let plan = Plan::new(&scene);
    let t = scene.capture.time;
    let nt = t.bins;
    let in_window = |i: usize| {
        let s = t.start_m + ((i % nt) as f64 + 0.5) * t.bin_width_m;
        s >= w0 && s < w1
    };
    let go = |spp: u64, seed: u64| {
        let opt = RenderOptions {
            spp,
            seed,
            shard: None,
            checkpoint: None,
            checkpoint_every: Duration::ZERO,
        };
        let (c0, t0) = (cpu_seconds(), Instant::now());
        let cap = plan.render(&opt, &|_, _| {}).unwrap();
        (cap.h, cpu_seconds() - c0, t0.elapsed().as_secs_f64())
    };
    let (reference, ref_cpu, _) = go(ref_spp, 1_000_000);
    eprintln!("reference: {ref_spp} spp in {ref_cpu:.1} CPU s");
    let den: f64 = reference
        .iter()
        .enumerate()
        .filter(|(i, _)| in_window(*i))
        .map(|(_, r)| (*r as f64).powi(2))
        .sum();
    let mut rows = Vec::new();
    for seed in 0..runs as u64 {
        let (h, cpu, wall) = go(spp, seed);
        let num: f64 = h
            .iter()
            .zip(&reference)
            .enumerate()
            .filter(|(i, _)| in_window(*i))
            .map(|(_, (x, r))| ((x - r) as f64).powi(2))
            .sum();
        let paths = plan.n_units() as f64 * spp as f64;
        rows.push(((num / den).sqrt(), cpu, wall, paths / cpu));
    }
    let median = |k: fn(&(f64, f64, f64, f64)) -> f64| {
        let mut v: Vec<f64> = rows.iter().map(k).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!(
        "{}: {} points × {spp} spp, {runs} runs (median): object-window [{w0}, {w1}] m relL2 {:.4}, CPU {:.2} s, wall {:.2} s, {:.2} M paths/CPU-s",
        a[1],
        plan.n_units(),
        median(|r| r.0),
        median(|r| r.1),
        median(|r| r.2),
        median(|r| r.3) / 1e6
    );
}
