//! Median run times of every method on a 32 × 32 × 512 synthetic confocal capture (16 ps bins,
//! 0.64 m scan, a plane and a few points), plan time separate.
//!
//! cargo run --release -p murk-baselines --example timing [-- RUNS [N [METHOD]]]
//! (N × N × 512 capture, default 32; METHOD runs only that method, e.g. to measure its memory.)

use murk_baselines::*;
use murk_core::{Axis, Capture, DVec3, NoProgress, PointSet, TimeAxis, Volume};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let runs: usize = args.get(1).map_or(15, |s| s.parse().unwrap());
    let n: usize = args.get(2).map_or(32, |s| s.parse().unwrap());
    let only = args.get(3).cloned().unwrap_or_default();
    let c = capture(n, 512);
    println!(
        "{n}×{n}×512 confocal capture, {runs} runs, {} rayon threads",
        rayon::current_num_threads()
    );
    let time = |name: &str, f: &dyn Fn()| {
        if only.is_empty() || name == only {
            f()
        }
    };
    // BP/FBP volume: the scan grid's own columns (as `murk reconstruct` defaults to) × 128 depths
    // over 0.1–1.0 m.
    let edge = 0.32 - 0.32 / n as f64;
    let vol = Volume {
        x: Axis::new(-edge, edge, n),
        y: Axis::new(-edge, edge, n),
        z: Axis::new(0.1, 1.0, 128),
    };
    let bp_name = format!("bp ({n}×{n}×128 voxels)");
    time("bp", &|| {
        measure(
            &bp_name,
            runs,
            || (),
            |_| backproject(&c, &vol, BpOptions::default()).unwrap(),
        )
    });
    time("fbp", &|| {
        measure(
            "fbp (LoG)",
            runs,
            || (),
            |_| fbp(&c, &vol, FbpOptions::default()).unwrap(),
        )
    });
    time("lct", &|| {
        measure(
            "lct (M = 512)",
            runs,
            || LctPlan::new(&c, LctParams::default(), &NoProgress).unwrap(),
            |p| p.run(&c, &murk_core::NoProgress).unwrap(),
        )
    });
    time("dlct", &|| {
        measure(
            "dlct (M = 512)",
            runs,
            || DlctPlan::new(&c, DlctParams::default(), &NoProgress).unwrap(),
            |p| p.run(&c, &murk_core::NoProgress).unwrap(),
        )
    });
    time("fk", &|| {
        measure(
            "fk (M = 512)",
            runs,
            || FkPlan::new(&c, FkParams::default()).unwrap(),
            |p| p.run(&c, &murk_core::NoProgress).unwrap(),
        )
    });
    time("cdt", &|| {
        measure(
            "cdt (reference grid, 128 samples)",
            runs,
            || CdtPlan::new(&c, CdtParams::default(), &NoProgress).unwrap(),
            |p| p.run(&c, &murk_core::NoProgress).unwrap(),
        )
    });
    let native = CdtParams {
        grid: TimeGrid::Native,
        ..Default::default()
    };
    time("cdt-native", &|| {
        measure(
            "cdt (native, 512 samples)",
            runs,
            || CdtPlan::new(&c, native, &NoProgress).unwrap(),
            |p| p.run(&c, &murk_core::NoProgress).unwrap(),
        )
    });
}

fn measure<P>(name: &str, runs: usize, plan: impl Fn() -> P, run: impl Fn(&P) -> Reconstruction) {
    let t0 = Instant::now();
    let p = plan();
    let plan_ms = t0.elapsed().as_secs_f64() * 1e3;
    let mut ms: Vec<f64> = (0..runs)
        .map(|_| {
            let t0 = Instant::now();
            std::hint::black_box(run(&p));
            t0.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    ms.sort_by(f64::total_cmp);
    println!(
        "{name:36} median {:7.1} ms  (min {:6.1}, max {:6.1}; plan {plan_ms:6.1} ms)",
        ms[runs / 2],
        ms[0],
        ms[runs - 1]
    );
}

fn capture(n: usize, bins: usize) -> Capture {
    let grid = PointSet::wall_grid(DVec3::ZERO, 0.64, 0.64, n, n);
    let time = TimeAxis {
        start_m: 0.0,
        bin_width_m: 299_792_458.0 * 16e-12,
        bins,
    };
    let mut h = vec![0.0f32; n * n * bins];
    let mut targets: Vec<DVec3> = (0..24 * 24)
        .map(|i| {
            DVec3::new(
                -0.2 + 0.4 * (i / 24) as f64 / 23.0,
                -0.2 + 0.4 * (i % 24) as f64 / 23.0,
                0.5,
            )
        })
        .collect();
    targets.extend([DVec3::new(0.1, -0.15, 0.35), DVec3::new(-0.2, 0.2, 0.8)]);
    for (i, hist) in h.chunks_mut(bins).enumerate() {
        for p in &targets {
            let d = (grid.points[i] - *p).length();
            let u = 2.0 * d / time.bin_width_m - 0.5;
            let k = u.floor() as usize;
            if k + 1 < bins {
                let f = (u - k as f64) as f32;
                let w = (1.0 / d.powi(4)) as f32;
                hist[k] += w * (1.0 - f);
                hist[k + 1] += w * f;
            }
        }
    }
    Capture::confocal(grid, time, h, String::new())
}
