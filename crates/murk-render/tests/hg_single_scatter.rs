//! Single scattering in anisotropic (Henyey–Greenstein) fog against an independent quadrature, in
//! homogeneous fog and in two layers of a density grid.
//!
//! One laser point x_l and one SPAD point x_s on a reflective relay wall (z = 0, normal +z), fog filling
//! z ∈ [0.001, 3] m, no hidden objects and `max_depth = 1`: the histogram is single scattering alone,
//! H(L) = ∫ (cos_l / π r_l²) T_l σs p_g(cos θ) T_s (cos_s / π r_s²) δ(L − r_l − r_s) dV
//! in murk's normalisation (unit-power laser spot of intensity cos/π, SPAD importance cos/π, see
//! `integrator/mod.rs`; a bin holds the integral of H over its path lengths, as in `correctness.rs`). The
//! reference integrates that over the ellipsoids r_l + r_s = L with its own HG formula, so a wrong phase
//! sign, angle convention or normalisation in any of the renderer's medium techniques moves the sums of
//! whole time windows: with x_l = x_s every path scatters straight back, where the sign of g matters
//! most; with x_l and x_s apart the scattering angle sweeps with the path length.

mod common;

use common::{gauss_legendre, laser_and_spad, render as render_scene};
use murk_core::DVec3;
use std::f64::consts::PI;

const MU_T: f64 = 0.5;
const ALBEDO: f64 = 0.5;
/// Where the fog starts, as in the other fog tests: just off the wall, so transmittance counts only the
/// part of each leg above it.
const Z0: f64 = 0.001;
const BIN: f64 = 0.05;
const BINS: usize = 42;
/// g = 0 (index 1) is the isotropic baseline the anisotropic cases are also compared with; g = 0.7 and 0.9
/// take the forward phase lobe of the target-side draws and the phase-angle distances by default.
const GS: [f64; 4] = [0.7, 0.0, -0.7, 0.9];
/// Several times the seed spread of one window's sum at the spp used (measured spread: docs/study.md).
const TOL_WINDOW: f64 = 0.03;
/// The ratio of g ≠ 0 to g = 0 in one window: the same seed draws the same vertices for every g (at
/// `max_depth = 1` no direction comes from the phase function), so most of the noise cancels.
const TOL_RATIO: f64 = 0.01;

/// The histogram of laser point `xl` and SPAD point `xs` (wall coordinates) in the fog of the `[medium]`
/// lines `medium`, with the `[render]` lines `techniques`.
fn render(
    xl: [f64; 2],
    xs: [f64; 2],
    medium: &str,
    techniques: &str,
    spp: u64,
    seed: u64,
) -> Vec<f64> {
    // Relay albedo 0, and a fog box far wider than the last bin's ellipsoid (1.05 m from the wall points'
    // midpoint): nothing but the fog's first vertex, in fog the reference may treat as unbounded.
    let render = format!("max_depth = 1\n{techniques}");
    let s = laser_and_spad(xl, xs, (BINS, BIN), &render, medium);
    render_scene(&s, spp, seed)
        .h
        .iter()
        .map(|v| *v as f64)
        .collect()
}

/// Henyey–Greenstein density per steradian for the cosine between the propagation directions before and
/// after scattering (g > 0 forward).
fn hg(g: f64, cos: f64) -> f64 {
    (1.0 - g * g) / (4.0 * PI * (1.0 + g * g - 2.0 * g * cos).powf(1.5))
}

/// ∫ f(x) δ(L − r_l − r_s) dV dL over the path lengths [l0, l1] and the half-space z ≥ `z0`, for wall
/// points `xl`, `xs` (z = 0): Gauss–Legendre in prolate spheroidal coordinates L, τ, φ.
///
/// On the ellipsoid r_l + r_s = L (foci x_l, x_s at half-separation c; semi-axes a = L/2 and
/// b = √(a² − c²)) the point m + aτ·e + b√(1 − τ²)(cos φ·e₁ + sin φ·ẑ), with m the foci's midpoint and e
/// their axis, has volume element dV = (r_l r_s / 2) dL dτ dφ. As c → 0 it is the sphere of radius L/2
/// (τ = cos ϑ), so x_l = x_s needs no special case. Only z ≥ z0 counts, which bounds τ and φ; `f` must be
/// even about φ = π/2 (as any integrand of the wall points, which lie on the wall, is), so φ runs over
/// [φ₀, π/2], counted twice. For the single-scattering integrand of `hg_single_scatter.rs`, doubling
/// every node count changes no window's value by more than 2e-6 (relative).
fn ellipsoid_integral(
    xl: DVec3,
    xs: DVec3,
    z0: f64,
    (l0, l1): (f64, f64),
    f: impl Fn(DVec3) -> f64,
) -> f64 {
    let m = 0.5 * (xl + xs);
    let c = 0.5 * (xs - xl).length();
    let e = if c > 0.0 {
        (xs - xl).normalize()
    } else {
        DVec3::X
    };
    let e1 = DVec3::Z.cross(e);
    let mut sum = 0.0;
    for (l, wl) in gauss_legendre(12, l0, l1) {
        let a = 0.5 * l;
        let b = (a * a - c * c).sqrt();
        if b <= z0 {
            continue;
        }
        let tau_max = (1.0 - (z0 / b).powi(2)).sqrt();
        for (tau, wt) in gauss_legendre(64, -tau_max, tau_max) {
            let s = (1.0 - tau * tau).sqrt();
            let phi0 = (z0 / (b * s)).min(1.0).asin();
            for (phi, wp) in gauss_legendre(32, phi0, 0.5 * PI) {
                let x = m + e * (a * tau) + (e1 * phi.cos() + DVec3::Z * phi.sin()) * (b * s);
                let (rl, rs) = ((x - xl).length(), (xs - x).length());
                sum += 2.0 * wl * wt * wp * (0.5 * rl * rs) * f(x);
            }
        }
    }
    sum
}

/// ∫ H(L) dL over the path lengths [l0, l1] ([`ellipsoid_integral`]).
fn reference(xl: DVec3, xs: DVec3, g: f64, (l0, l1): (f64, f64)) -> f64 {
    // The part of a leg from the wall up to height z that runs through fog.
    let in_fog = |r: f64, z: f64| r * (1.0 - Z0 / z);
    ellipsoid_integral(xl, xs, Z0, (l0, l1), |x| {
        let (to_x, to_s) = (x - xl, xs - x);
        let (rl, rs) = (to_x.length(), to_s.length());
        let cos_theta = to_x.dot(to_s) / (rl * rs);
        let emit = (x.z / rl) / (PI * rl * rl);
        let sense = (x.z / rs) / (PI * rs * rs);
        let tr = (-MU_T * (in_fog(rl, x.z) + in_fog(rs, x.z))).exp();
        emit * tr * ALBEDO * MU_T * hg(g, cos_theta) * sense
    })
}

/// The medium techniques of the first segment: free flight and target-side draws, with equiangular and
/// time-window distances added, as `z-letter.toml` and `t-wall-medium.toml` use, and with phase-angle
/// distances on both sides (the default at g ≥ 0.6). Each set draws alike at every g (phase-angle
/// distances at g = 0 too, uniform in angle there), so that the ratio to g = 0 keeps its correlated noise.
const TECHNIQUES: [&str; 3] = [
    "phase_distances = 0\ntarget_phase_distances = 0",
    "equiangular = true\nfirst_time_samples = 4\nphase_distances = 0\ntarget_phase_distances = 0",
    "phase_distances = 2\ntarget_phase_distances = 0.5",
];

/// Renders `xl`, `xs` for every g of `GS` with each of `TECHNIQUES` and compares the sums over `windows`
/// (bin ranges) with the quadrature: each within `TOL_WINDOW`, and each g ≠ 0 relative to g = 0 within
/// `TOL_RATIO`.
fn check(xl: [f64; 2], xs: [f64; 2], windows: &[(usize, usize)], spp: u64, seed: u64) {
    let at = |v: [f64; 2]| DVec3::new(v[0], v[1], 0.0);
    let path = |i: usize| i as f64 * BIN;
    let quad: Vec<Vec<f64>> = GS
        .iter()
        .map(|&g| {
            windows
                .iter()
                .map(|&(i, j)| reference(at(xl), at(xs), g, (path(i), path(j))))
                .collect()
        })
        .collect();
    for techniques in TECHNIQUES {
        let mc: Vec<Vec<f64>> = GS
            .iter()
            .map(|&g| {
                let medium = format!(
                    "mu_t = {MU_T}\nalbedo = {ALBEDO}\ng = {g}\nmin = [-3.0, -3.0, {Z0}]\nmax = [3.0, 3.0, 3.0]"
                );
                let h = render(xl, xs, &medium, techniques, spp, seed);
                windows.iter().map(|&(i, j)| h[i..j].iter().sum()).collect()
            })
            .collect();
        let label = format!("laser {xl:?}, SPAD {xs:?}, techniques {techniques:?}");
        let mut table = String::new();
        let mut failures = Vec::new();
        for (k, g) in GS.iter().enumerate() {
            for (w, &(i, j)) in windows.iter().enumerate() {
                let ratio = mc[k][w] / quad[k][w];
                let relative = (mc[k][w] / mc[1][w]) / (quad[k][w] / quad[1][w]);
                let line = format!(
                    "g {g:+.1}, paths [{:.2}, {:.2}] m: MC {:.4e}, quadrature {:.4e}, \
                     ratio {ratio:.4}, relative to g = 0 {relative:.4}",
                    path(i),
                    path(j),
                    mc[k][w],
                    quad[k][w],
                );
                if (ratio - 1.0).abs() > TOL_WINDOW || (relative - 1.0).abs() > TOL_RATIO {
                    failures.push(line.clone());
                }
                table.push_str(&line);
                table.push('\n');
            }
        }
        eprint!("{label}:\n{table}");
        assert!(
            failures.is_empty(),
            "{label}: {} windows off the quadrature:\n{}",
            failures.len(),
            failures.join("\n")
        );
    }
}

/// Laser and SPAD 0.3 m apart: the scattering angle sweeps from sideways to nearly backwards as the path
/// grows, so each g weighs the windows differently. Five windows over 0.35–2 m of path.
#[test]
fn hg_single_scattering_matches_quadrature_laser_and_spad_apart() {
    check(
        [-0.15, 0.0],
        [0.15, 0.0],
        &[(7, 10), (10, 14), (14, 20), (20, 28), (28, 40)],
        400_000,
        1,
    );
}

/// Laser and SPAD at one point: pure backscatter (cos θ = −1), where g = ±0.7 differ most from isotropic
/// fog. Six windows over 0.1–2 m of path.
#[test]
fn hg_single_scattering_matches_quadrature_colocated() {
    check(
        [0.0, 0.0],
        [0.0, 0.0],
        &[(2, 4), (4, 7), (7, 12), (12, 20), (20, 30), (30, 40)],
        400_000,
        2,
    );
}

/// Two layers of a density grid (shape (1, 1, 2) over z ∈ [Z0, Z0 + 0.9]: σt 1.2/m below z = Z0 + 0.45,
/// 0.3/m above, nothing past the box's top), laser and SPAD 0.3 m apart, g = 0.5: delta-tracked free
/// flights (null collisions in the upper layer), the cell walk's transmittance and every distance
/// technique's balance weights against the quadrature of the same integral with each leg's optical
/// depth split at the layer boundary. Six windows over 0.35–2.1 m of path: the late ones reach the upper
/// layer and the empty space above the box.
#[test]
fn two_layer_grid_single_scattering_matches_quadrature() {
    const G: f64 = 0.5;
    const MU: f64 = 1.2;
    const LAYERS: [f64; 2] = [1.0, 0.25];
    let (zb, top) = (Z0 + 0.45, Z0 + 0.9);
    let dir = std::env::temp_dir().join(format!("murk-two-layer-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let npy = dir.join("layers.npy");
    murk_io::write_npy_f32(&npy, &[1, 1, 2], &LAYERS.map(|d| d as f32)).unwrap();
    let medium = format!(
        "kind = \"grid\"\ndensity = {:?}\nmu_t = {MU}\nalbedo = {ALBEDO}\ng = {G}\n\
         min = [-3.0, -3.0, {Z0}]\nmax = [3.0, 3.0, {top}]",
        npy.to_str().unwrap()
    );
    let (xl, xs) = ([-0.15, 0.0], [0.15, 0.0]);
    let windows = [(7, 10), (10, 14), (14, 20), (20, 28), (28, 36), (36, 42)];
    let at = |v: [f64; 2]| DVec3::new(v[0], v[1], 0.0);
    let (pl, ps) = (at(xl), at(xs));
    // Optical depth of a leg of length r from the wall (z = 0) up to height z: its share of each layer
    // is its share of the height.
    let tau = |r: f64, z: f64| {
        MU * r / z * (LAYERS[0] * (z.min(zb) - Z0) + LAYERS[1] * (z - zb).max(0.0))
    };
    let quad: Vec<f64> = windows
        .iter()
        .map(|&(i, j)| {
            ellipsoid_integral(pl, ps, Z0, (i as f64 * BIN, j as f64 * BIN), |x| {
                if x.z > top {
                    return 0.0;
                }
                let (to_x, to_s) = (x - pl, ps - x);
                let (rl, rs) = (to_x.length(), to_s.length());
                let cos_theta = to_x.dot(to_s) / (rl * rs);
                let density = if x.z < zb { LAYERS[0] } else { LAYERS[1] };
                let emit = (x.z / rl) / (PI * rl * rl);
                let sense = (x.z / rs) / (PI * rs * rs);
                let tr = (-(tau(rl, x.z) + tau(rs, x.z))).exp();
                emit * tr * ALBEDO * MU * density * hg(G, cos_theta) * sense
            })
        })
        .collect();
    for techniques in TECHNIQUES {
        let h = render(xl, xs, &medium, techniques, 400_000, 3);
        for (&(i, j), q) in windows.iter().zip(&quad) {
            let mc: f64 = h[i..j].iter().sum();
            eprintln!("techniques {techniques:?}, bins {i}..{j}: MC {mc:.4e}, quadrature {q:.4e}, ratio {:.4}", mc / q);
            assert!(
                (mc / q - 1.0).abs() < TOL_WINDOW,
                "techniques {techniques:?}, bins {i}..{j}: MC {mc:.4e}, quadrature {q:.4e}"
            );
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
