//! Helpers shared by the renderer's physics tests.
// Each test binary compiles this module and uses a part of it.
#![allow(dead_code)]

use murk_core::Capture;
use murk_render::{Overrides, Plan, RenderOptions, Scene};
use std::f64::consts::PI;
use std::path::Path;
use std::time::Duration;

pub fn scene(toml: &str) -> Scene {
    Scene::from_str(toml, Path::new("test.toml"), &Overrides::default()).expect("valid scene")
}

/// One laser point `xl` and one SPAD point `xs` (wall coordinates) on a black 6 m × 6 m relay wall, `bins`
/// bins of `bin_m` from path 0, and the given `[render]` and `[medium]` lines.
pub fn laser_and_spad(
    xl: [f64; 2],
    xs: [f64; 2],
    (bins, bin_m): (usize, f64),
    render: &str,
    medium: &str,
) -> Scene {
    scene(&format!(
        "[relay]\nkind = \"wall\"\nsize = [6.0, 6.0]\nalbedo = 0.0\n\
         [capture]\nkind = \"laser-grid\"\ngrid = [1, 1]\ncenter = [{}, {}]\nextent = [0.001, 0.001]\n\
         spad_point = [{}, {}]\nbins = {bins}\nbin_width = {bin_m}\nstart = 0.0\n\
         [render]\n{render}\n[medium]\n{medium}\n",
        xl[0], xl[1], xs[0], xs[1]
    ))
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
