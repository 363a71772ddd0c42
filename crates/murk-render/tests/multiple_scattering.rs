//! Multiple scattering in homogeneous isotropic fog against an independent analog random walk, in
//! absolute units.
//!
//! One laser point and one SPAD point 0.3 m apart on a black relay wall (z = 0), fog of μt 2 /m, α 0.5,
//! g 0 from z = 0.001 to 3 m, at most 8 vertices. The reference shares nothing with the renderer but the
//! normalisation (unit-power laser spot of intensity cos/π, SPAD importance cos/π; a bin holds the integral
//! of H over its path lengths): it leaves the laser spot in a cosine direction, flies exponential distances,
//! weights each scattering by α, turns isotropically and connects every vertex to the SPAD point with
//! p = 1/4π, the leg's transmittance and cos_s/(π r²). The single-scattering quadratures
//! (`hg_single_scatter.rs`, `correctness.rs`) do not reach orders 2–8, which carry 19–84 % of the windows
//! here; this test checks them, with murk's default techniques.

use murk_core::DVec3;
use rand_core::Rng;
use std::f64::consts::PI;

mod common;

const MU_T: f64 = 2.0;
const ALBEDO: f64 = 0.5;
const Z0: f64 = 0.001;
const TOP: f64 = 3.0;
const HALF: f64 = 3.0;
const MAX_DEPTH: usize = 8;
const BIN_M: f64 = 0.1;
const BINS: usize = 30;
const LASER: [f64; 2] = [0.0, 0.0];
const SPAD: [f64; 2] = [0.3, 0.0];
/// Windows (bin ranges) from the onset at 0.3 m to 3 m.
const WINDOWS: [(usize, usize); 5] = [(3, 6), (6, 9), (9, 12), (12, 19), (19, 30)];

/// Per window, the walk's means of all orders and of the orders 2–8, and their standard errors.
struct Walk {
    all: [f64; 5],
    multiple: [f64; 5],
    all_se: [f64; 5],
    multiple_se: [f64; 5],
}

fn window_of(bin: usize) -> Option<usize> {
    WINDOWS.iter().position(|&(i, j)| (i..j).contains(&bin))
}

fn walk(n: u64, seed: u64) -> Walk {
    let mut rng = rand_pcg::Pcg64::new(seed as u128, 0xda3e_39cb_94b9_5bdb);
    let mut u = move || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
    let spad = DVec3::new(SPAD[0], SPAD[1], 0.0);
    let l_max = BIN_M * BINS as f64;
    // Sums and sums of squares of each path's contribution to each window: all orders, orders 2–8.
    let (mut s, mut s2) = ([[0.0; 5]; 2], [[0.0; 5]; 2]);
    for _ in 0..n {
        let mut own = [[0.0; 5]; 2];
        let (u1, phi) = (u(), 2.0 * PI * u());
        let r = u1.sqrt();
        let mut d = DVec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).sqrt());
        let t_in = Z0 / d.z;
        let mut p = DVec3::new(LASER[0], LASER[1], 0.0) + d * t_in;
        let mut path = t_in;
        let mut w = 1.0;
        for order in 0..MAX_DEPTH {
            let s_m = -(1.0 - u()).ln() / MU_T;
            // Leaving through the fog's floor ends on the black wall; through its top or sides, in the void.
            let exit = if d.z < 0.0 {
                (Z0 - p.z) / d.z
            } else {
                (TOP - p.z) / d.z
            };
            p += d * s_m;
            path += s_m;
            if s_m >= exit || p.x.abs() > HALF || p.y.abs() > HALF || path >= l_max {
                break;
            }
            w *= ALBEDO;
            let to_spad = spad - p;
            let rs = to_spad.length();
            let tr = (-MU_T * rs * (1.0 - Z0 / p.z)).exp();
            let c = w / (4.0 * PI) * tr * (p.z / rs) / (PI * rs * rs);
            if let Some(k) = window_of(((path + rs) / BIN_M) as usize) {
                own[0][k] += c;
                if order > 0 {
                    own[1][k] += c;
                }
            }
            let (cz, phi) = (2.0 * u() - 1.0, 2.0 * PI * u());
            let sz = (1.0 - cz * cz).sqrt();
            d = DVec3::new(sz * phi.cos(), sz * phi.sin(), cz);
        }
        for part in 0..2 {
            for k in 0..5 {
                s[part][k] += own[part][k];
                s2[part][k] += own[part][k] * own[part][k];
            }
        }
    }
    let nf = n as f64;
    let mean = |part: usize| s[part].map(|v| v / nf);
    let se = |part: usize| {
        let m = mean(part);
        std::array::from_fn(|k| ((s2[part][k] / nf - m[k] * m[k]) / nf).sqrt())
    };
    Walk {
        all: mean(0),
        multiple: mean(1),
        all_se: se(0),
        multiple_se: se(1),
    }
}

/// murk's window sums with at most `max_depth` vertices.
fn murk_windows(max_depth: usize, spp: u64, seed: u64) -> [f64; 5] {
    let medium = format!(
        "mu_t = {MU_T}\nalbedo = {ALBEDO}\ng = 0.0\nmin = [-{HALF}, -{HALF}, {Z0}]\nmax = [{HALF}, {HALF}, {TOP}]"
    );
    let s = common::laser_and_spad(
        LASER,
        SPAD,
        (BINS, BIN_M),
        &format!("max_depth = {max_depth}"),
        &medium,
    );
    let h = common::render(&s, spp, seed).h;
    WINDOWS.map(|(i, j)| h[i..j].iter().map(|v| *v as f64).sum())
}

/// Per window, murk at 8 vertices against the walk's orders 1–8 within 2 %, and murk's orders 2–8 (8
/// vertices minus 1) against the walk's within 3 %. Measured: within 1.0 % and 1.9 %, where the walk's
/// standard errors are 0.3–0.8 % and 0.5–1.4 % (murk's noise adds to them). An error in how the orders
/// build up moves the multiple part first: mitransient with an opaque laser spot, whose shadow rays are
/// partly blocked (docs/media-heterogeneous.md), is 8–12 % low on such windows.
#[test]
fn multiple_scattering_matches_an_analog_walk() {
    let reference = walk(4_000_000, 11);
    let all = murk_windows(MAX_DEPTH, 400_000, 5);
    let single = murk_windows(1, 400_000, 6);
    let mut failures = Vec::new();
    for (k, &(i, j)) in WINDOWS.iter().enumerate() {
        let walk_all = reference.all[k];
        let ratio_all = all[k] / walk_all;
        let ratio_multiple = (all[k] - single[k]) / reference.multiple[k];
        let line = format!(
            "paths [{:.1}, {:.1}) m: murk {:.4e}, walk {walk_all:.4e} (SE {:.2} %), ratio {ratio_all:.4}; \
             orders 2-8: murk {:.4e}, walk {:.4e} (SE {:.2} %), ratio {ratio_multiple:.4}",
            i as f64 * BIN_M,
            j as f64 * BIN_M,
            all[k],
            100.0 * reference.all_se[k] / walk_all,
            all[k] - single[k],
            reference.multiple[k],
            100.0 * reference.multiple_se[k] / reference.multiple[k],
        );
        eprintln!("{line}");
        if (ratio_all - 1.0).abs() > 0.02 || (ratio_multiple - 1.0).abs() > 0.03 {
            failures.push(line);
        }
    }
    assert!(
        failures.is_empty(),
        "windows off the walk:\n{}",
        failures.join("\n")
    );
}
