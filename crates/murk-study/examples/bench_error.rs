//! Efficiency benchmark: object-window relative L2 error against a long reference render, CPU time and
//! paths per CPU-second, median of several seeds (the protocol of docs/benchmarks.md).
//!
//! `cargo run --release -p murk-study --example bench_error -- SCENE.toml SPP REF_SPP RUNS [WIN_START WIN_END]`

use murk_core::median;
use murk_render::bench::timed_render;
use murk_render::{Overrides, Plan, Scene};
use murk_study::render_error::{rel_l2, window_mask};
use std::path::Path;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    if a.len() < 5 {
        eprintln!("usage: bench_error SCENE.toml SPP REF_SPP RUNS [WIN_START WIN_END]");
        std::process::exit(2);
    }
    let scene =
        Scene::load(Path::new(&a[1]), &Overrides::default()).unwrap_or_else(|e| panic!("{e}"));
    let (spp, ref_spp, runs): (u64, u64, u64) = (
        a[2].parse().unwrap(),
        a[3].parse().unwrap(),
        a[4].parse().unwrap(),
    );
    let window: (f64, f64) = match (a.get(5), a.get(6)) {
        (Some(x), Some(y)) => (x.parse().unwrap(), y.parse().unwrap()),
        _ => (1.98, 2.70),
    };
    let plan = Plan::new(&scene);
    let reference = timed_render(&plan, ref_spp, 1_000_000, None).unwrap();
    eprintln!("reference: {ref_spp} spp in {:.1} CPU s", reference.cpu_s);
    let mask = window_mask(&scene.capture.time, reference.h.len(), window);
    let rows: Vec<_> = (0..runs)
        .map(|seed| {
            let r = timed_render(&plan, spp, seed, None).unwrap();
            (
                rel_l2(&r.h, &reference.h, &mask),
                r.cpu_s,
                r.wall_s,
                r.paths / r.cpu_s,
            )
        })
        .collect();
    let med = |k: fn(&(f64, f64, f64, f64)) -> f64| median(&rows.iter().map(k).collect::<Vec<_>>());
    println!(
        "{}: {} points × {spp} spp, {runs} runs (median): object-window [{}, {}] m relL2 {:.4}, CPU {:.2} s, wall {:.2} s, {:.2} M paths/CPU-s",
        a[1],
        plan.n_points(),
        window.0,
        window.1,
        med(|r| r.0),
        med(|r| r.1),
        med(|r| r.2),
        med(|r| r.3) / 1e6
    );
}
