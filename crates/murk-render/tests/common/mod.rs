//! Helpers shared by the renderer's physics tests.

use murk_core::Capture;
use murk_render::{Overrides, Plan, RenderOptions, Scene};
use std::f64::consts::PI;
use std::path::Path;
use std::time::Duration;

pub fn scene(toml: &str) -> Scene {
    Scene::from_str(toml, Path::new("test.toml"), &Overrides::default()).expect("valid scene")
}

pub fn render(s: &Scene, spp: u64, seed: u64) -> Capture {
    let opt = RenderOptions {
        spp,
        seed,
        shard: None,
        checkpoint: None,
        checkpoint_every: Duration::ZERO,
    };
    Plan::new(s).render(&opt, &|_, _| {}).expect("render")
}

/// Gauss–Legendre nodes and weights on [a, b] (Newton on the Legendre recurrence).
pub fn gauss_legendre(n: usize, a: f64, b: f64) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 0.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                    p0 = p1;
                    p1 = p2;
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-15 {
                    break;
                }
            }
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            (0.5 * (b - a) * x + 0.5 * (a + b), 0.5 * (b - a) * w)
        })
        .collect()
}
