//! Physics checks of the renderer against analytic results and numerical quadrature, each with its
//! tolerance. Sample counts are chosen so each test runs in a few seconds at opt-level 1.

mod common;

use common::{gauss_legendre, render, scene};
use murk_core::DVec3;
use murk_render::{Overrides, Scene};
use std::f64::consts::PI;

/// A 5 cm Lambertian patch 1 m in front of a confocal point: H = ∫ ρ z⁴ / (π³ r⁸) dA, all of it arriving
/// at path 2r ∈ [2.0, 2.0013] m, i.e. in the one bin [1.999, 2.002).
#[test]
fn first_bounce_of_a_small_patch() {
    let s = scene(
        r#"
        [relay]
        kind = "wall"
        size = [1.0, 1.0]
        [capture]
        kind = "confocal"
        grid = [1, 1]
        extent = [0.001, 0.001]
        bins = 8
        bin_width = 0.003
        start = 1.996
        [render]
        max_depth = 1
        [[object]]
        shape = "quad"
        center = [0.0, 0.0, 1.0]
        size = [0.05, 0.05]
        albedo = 0.7
        "#,
    );
    let h = render(&s, 40_000, 1).h;
    let n = 200;
    let analytic: f64 = (0..n * n)
        .map(|k| {
            let (x, y) = ((k / n) as f64 + 0.5, (k % n) as f64 + 0.5);
            let (x, y) = (x / n as f64 * 0.05 - 0.025, y / n as f64 * 0.05 - 0.025);
            let r2 = x * x + y * y + 1.0;
            0.7 / (PI.powi(3) * r2.powi(4)) * (0.05 / n as f64).powi(2)
        })
        .sum();
    let total: f64 = h.iter().map(|v| *v as f64).sum();
    assert!(
        (total / analytic - 1.0).abs() < 0.02,
        "H = {total:e}, analytic {analytic:e}"
    );
    // Arrival bin: everything in bin 1 = [1.999, 2.002).
    assert!(h[1] as f64 >= 0.999 * total, "bins {h:?}");
}

/// One laser point and one SPAD point 0.4 m apart under an unbounded (40 m) medium, single scattering only:
/// the histogram summed over 0.2 m windows against a Gauss–Legendre quadrature of
/// H = ∫ (cos_s/π) σs e^{−σt t} p(ω·w) e^{−σt r_l} cos_l/(π r_l²) dt dω, within 3 %; with the default
/// techniques and with equiangular and stratified time-window distances added.
#[test]
fn single_scattering_matches_quadrature() {
    for (time_samples, equiangular) in [(0, false), (3, true)] {
        single_scattering_case(time_samples, equiangular);
    }
}

fn single_scattering_case(time_samples: u32, equiangular: bool) {
    let (mu_t, alb, g) = (1.0, 0.5, 0.3);
    let s = scene(&format!(
        r#"
        [relay]
        kind = "wall"
        size = [2.0, 2.0]
        albedo = 0.0
        [capture]
        kind = "laser-grid"
        grid = [1, 1]
        center = [-0.2, 0.0]
        extent = [0.001, 0.001]
        spad_point = [0.2, 0.0]
        bins = 40
        bin_width = 0.05
        start = 0.4
        [render]
        max_depth = 1
        time_samples = {time_samples}
        equiangular = {equiangular}
        [medium]
        mu_t = {mu_t}
        albedo = {alb}
        g = {g}
        min = [-20.0, -20.0, 0.0]
        max = [20.0, 20.0, 20.0]
        "#
    ));
    let h = render(&s, 300_000, 2).h;
    let (xs, xl) = (DVec3::new(-0.2, 0.0, 0.0), DVec3::new(0.2, 0.0, 0.0));
    let phase = murk_render::Phase::new(g);
    let window = |a: f64, b: f64| -> f64 {
        let mut sum = 0.0;
        for (u, wu) in gauss_legendre(48, 0.0, 1.0) {
            for (phi, wp) in gauss_legendre(96, 0.0, 2.0 * PI) {
                let st = (1.0 - u * u).sqrt();
                let om = DVec3::new(st * phi.cos(), st * phi.sin(), u);
                let c = om.dot(xs - xl);
                let d2 = (xs - xl).length_squared();
                let t_of = |l: f64| (l * l - d2) / (2.0 * (l + c));
                for (t, wt) in gauss_legendre(12, t_of(a), t_of(b)) {
                    let y = xs + om * t;
                    let v = xl - y;
                    let rl = v.length();
                    let w = v / rl;
                    let cos_l = -w.z;
                    let f = (u / PI)
                        * mu_t
                        * alb
                        * (-mu_t * (t + rl)).exp()
                        * phase.eval(om.dot(w))
                        * cos_l
                        / (PI * rl * rl);
                    sum += wu * wp * wt * f;
                }
            }
        }
        sum
    };
    // Bins 4..40 = paths 0.6..2.4 m in nine 0.2 m windows (the singular start near 0.4 m is left out).
    for k in 0..9 {
        let (a, b) = (0.6 + 0.2 * k as f64, 0.8 + 0.2 * k as f64);
        let mc: f64 = h[4 + 4 * k..8 + 4 * k].iter().map(|v| *v as f64).sum();
        let q = window(a, b);
        assert!(
            (mc / q - 1.0).abs() < 0.03,
            "time_samples {time_samples}, window [{a:.1}, {b:.1}]: MC {mc:e} vs quadrature {q:e}"
        );
    }
}

const T_LETTER: &str = r#"
[[object]]
shape = "quad"
center = [0.0, 0.20, 1.0]
size = [0.5, 0.1]
[[object]]
shape = "quad"
center = [0.0, -0.05, 1.0]
size = [0.1, 0.4]
"#;

/// A pure absorber (α = 0) filling the hidden side multiplies every object return by exp(−μt·path).
/// Same seed, same random numbers: per bin the ratio differs from exp(−μt·bin centre) only by the
/// bin width (μt·3 mm/2 = 0.08 %); tolerance 0.3 %.
#[test]
fn pure_absorber_scales_by_transmittance() {
    let base = r#"
        [relay]
        kind = "wall"
        size = [1.0, 1.0]
        [capture]
        kind = "single"
        grid = [3, 3]
        bins = 400
        bin_width = 0.003
        start = 1.9
        [render]
        max_depth = 1
    "#;
    let clear = scene(&format!("{base}{T_LETTER}"));
    let fog = scene(&format!(
        "{base}\n[medium]\nmu_t = 0.5\nalbedo = 0.0\nmin = [-5.0, -5.0, 0.0]\nmax = [5.0, 5.0, 5.0]\n{T_LETTER}"
    ));
    let (a, b) = (render(&clear, 2000, 3).h, render(&fog, 2000, 3).h);
    let peak = a.iter().cloned().fold(0.0f32, f32::max);
    let mut checked = 0;
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        if *x > 0.01 * peak {
            let path = 1.9 + ((i % 400) as f64 + 0.5) * 0.003;
            let ratio = *y as f64 / *x as f64;
            let want = (-0.5 * path).exp();
            assert!(
                (ratio / want - 1.0).abs() < 0.003,
                "bin {i}: ratio {ratio} vs {want}"
            );
            checked += 1;
        }
    }
    assert!(checked > 100, "only {checked} bins with signal");
}

/// Reciprocity: tracing from the 3 × 3 laser points (one connection to the SPAD per vertex) and tracing
/// from the SPAD point (nine connections per vertex) estimate the same H, with the same paths per histogram.
/// Scene: T letter, relay albedo 0.5 (multi-bounce), anisotropic fog. Per-histogram totals agree within 6 %
/// (their seed-to-seed spread here is 2–4 %: connections near the wall points are heavy-tailed), and the
/// squared difference over 0.15 m bins is below 9× that between two seeds of laser tracing (expected ≈ 1×).
#[test]
fn reciprocity_laser_and_sensor_tracing_agree() {
    let mk = |from: &str| {
        fog_t_scene(
            0.5,
            "grid = [3, 3]\nextent = [0.8, 0.8]\nspad_point = [0.1, 0.05]\nbin_width = 0.15",
            &format!("trace_from = \"{from}\""),
            "mu_t = 0.5\nalbedo = 0.8\ng = 0.3",
        )
    };
    let (la, se) = (mk("laser"), mk("sensor"));
    let a = render(&la, 80_000, 4).h;
    let a2 = render(&la, 20_000, 5).h;
    let b = render(&se, 720_000, 6).h;
    assert_same_expectation(
        &a,
        &a2,
        &b,
        30,
        0.06,
        9.0,
        ("laser-traced", "sensor-traced"),
    );
}

/// Next-event estimation through the hidden geometry from medium vertices (`object_connections`) keeps
/// the expectation. A fog cube (0.8 m, μs = 1/m) in front of the wall and a 3 m × 3 m backdrop 1.5 m
/// away, one scattering event at most: from 2.8 m of path on, H is the backdrop's direct return plus its
/// return after scattering (~10 % of it: dropping either technique's weight moves the sums by 8–11 %;
/// their seed spread is 0.2 %). Per histogram within 3 %, the difference within the seed noise.
#[test]
fn object_connections_keep_the_expectation() {
    let mk = |on: bool| {
        scene(&format!(
            r#"
            [relay]
            kind = "wall"
            size = [1.0, 1.0]
            albedo = 0.0
            [capture]
            kind = "laser-grid"
            grid = [2, 2]
            extent = [0.4, 0.4]
            spad_point = [0.0, 0.0]
            bins = 32
            bin_width = 0.2
            start = 0.0
            [render]
            max_depth = 2
            object_connections = {on}
            [medium]
            mu_t = 1.0
            albedo = 1.0
            g = 0.5
            min = [-0.4, -0.4, 0.001]
            max = [0.4, 0.4, 0.4]
            [[object]]
            shape = "quad"
            center = [0.0, 0.0, 1.5]
            size = [3.0, 3.0]
            "#
        ))
    };
    // Bins 14..32 of each of the four histograms.
    let window =
        |h: Vec<f32>| -> Vec<f32> { h.chunks(32).flat_map(|c| c[14..].to_vec()).collect() };
    let (off, on) = (mk(false), mk(true));
    let a = window(render(&off, 50_000, 21).h);
    let a2 = window(render(&off, 50_000, 22).h);
    let b = window(render(&on, 50_000, 23).h);
    assert_same_expectation(&a, &a2, &b, 18, 0.03, 3.0, ("without", "with"));
}

/// The T letter 1 m behind a 1 m × 1 m relay wall of `relay_albedo`, in fog filling the box of
/// docs/benchmarks.md; a laser grid with one SPAD point, 30 bins from 0. The other keys are TOML lines.
fn fog_t_scene(relay_albedo: f64, capture: &str, render: &str, medium: &str) -> Scene {
    scene(&fog_t_text(relay_albedo, capture, render, medium))
}

fn fog_t_text(relay_albedo: f64, capture: &str, render: &str, medium: &str) -> String {
    format!(
        r#"
        [relay]
        kind = "wall"
        size = [1.0, 1.0]
        albedo = {relay_albedo}
        [capture]
        kind = "laser-grid"
        bins = 30
        start = 0.0
        {capture}
        [render]
        {render}
        [medium]
        min = [-1.5, -1.5, 0.001]
        max = [1.5, 1.5, 2.5]
        {medium}
        {T_LETTER}
        "#
    )
}

/// Two estimators of one H: every histogram's sum agrees within `tol`, and the squared difference
/// between `a` and `b` is below `k`× that between two seeds `a`, `a2` of the first.
fn assert_same_expectation(
    a: &[f32],
    a2: &[f32],
    b: &[f32],
    bins: usize,
    tol: f64,
    k: f64,
    (name_a, name_b): (&str, &str),
) {
    for hist in 0..a.len() / bins {
        let sum = |h: &[f32]| {
            h[hist * bins..(hist + 1) * bins]
                .iter()
                .map(|v| *v as f64)
                .sum::<f64>()
        };
        let (x, y) = (sum(a), sum(b));
        assert!(
            (x / y - 1.0).abs() < tol,
            "histogram {hist}: {name_a} {x:e}, {name_b} {y:e}"
        );
    }
    let dist2 = |u: &[f32], v: &[f32]| -> f64 {
        u.iter().zip(v).map(|(x, y)| ((x - y) as f64).powi(2)).sum()
    };
    let (d2, n2) = (dist2(a, b), dist2(a, a2));
    assert!(
        d2 < k * n2,
        "{name_a} vs {name_b} difference² {d2:e} vs seed noise² {n2:e}"
    );
}

/// More target-side draws for segments starting near a target (`target_split`) keep the expectation:
/// in a fog scene where relay vertices land near both wall points, every histogram's sum with and without
/// them agrees within 3 %, and their difference stays within the seed noise of the unsplit render.
#[test]
fn target_split_keeps_the_expectation() {
    assert_setting_keeps_the_expectation(
        "grid = [2, 2]",
        |split| format!("target_split = {split}\ntarget_split_radius = 0.5"),
        FOG,
        (1, 64),
        (200_000, 11),
        0.03,
        ("unsplit", "split"),
    );
}

/// Direct object-return draws from each traced point (`object_draws`) keep the expectation: on the T scene
/// in thin fog (μt = 0.2/m, α = 0.2), where the T's direct return is a large part of every histogram, sums
/// with 4 draws per path and without agree within 3 % (the path's own return counted at full weight next
/// to the draws: 19 % off), and the difference stays within the seed noise of rendering without.
#[test]
fn object_draws_keep_the_expectation() {
    assert_setting_keeps_the_expectation(
        "grid = [2, 2]",
        |n| format!("object_draws = {n}\nhidden_geometry_sampling = 0.3"),
        "mu_t = 0.2\nalbedo = 0.2",
        (0, 4),
        (100_000, 41),
        0.03,
        ("without object draws", "with them"),
    );
}

/// Time-window draws on the segment leaving each traced point (`first_time_samples`) keep the expectation
/// (single scattering is a large part of every histogram): sums with 8 draws and without agree within
/// 3 % (the target-side draws' weight without them: 17 % off), and the difference stays within the seed
/// noise of rendering without.
#[test]
fn first_time_samples_keep_the_expectation() {
    assert_setting_keeps_the_expectation(
        "grid = [2, 2]",
        |n| format!("first_time_samples = {n}"),
        FOG,
        (0, 8),
        (100_000, 51),
        0.03,
        ("without first-segment time draws", "with them"),
    );
}

/// The medium of most expectation checks: μt = 1/m, α = 0.8.
const FOG: &str = "mu_t = 1.0\nalbedo = 0.8";

/// On the fog T scene (a laser grid over 0.4 m, SPAD at the centre, reflective relay, at most 4 vertices)
/// in `medium`, the render setting `setting(off)` and `setting(on)` give the same expectation:
/// two seeds of `off` and one of `on` at `spp` (seeds from `seed`) through `assert_same_expectation`.
fn assert_setting_keeps_the_expectation(
    grid: &str,
    setting: impl Fn(u32) -> String,
    medium: &str,
    (off, on): (u32, u32),
    (spp, seed): (u64, u64),
    tol: f64,
    names: (&str, &str),
) {
    let mk = |v: u32| {
        fog_t_scene(
            1.0,
            &format!("{grid}\nextent = [0.4, 0.4]\nspad_point = [0.0, 0.0]\nbin_width = 0.1"),
            &format!("max_depth = 4\n{}", setting(v)),
            medium,
        )
    };
    let (off, on) = (mk(off), mk(on));
    let a = render(&off, spp, seed).h;
    let a2 = render(&off, spp, seed + 1).h;
    let b = render(&on, spp, seed + 2).h;
    assert_same_expectation(&a, &a2, &b, 30, tol, 2.0, names);
}

/// Tiles of laser points that share their paths past the first hidden vertex (`share_tile`) keep every
/// histogram's expectation: a 4 × 4 laser grid in forward-scattering fog (the phase function enters the
/// tile's weights at the first vertex), with first vertices in the fog and on the T letter and a
/// reflective relay; sums agree within 5 % (seed noise of one sum: ~1 %; at 60 000 spp, 5 % failed for
/// about one seed in three; at 480 000 spp every sum agreed within 1.2 %) and the difference stays
/// within the seed noise of unshared rendering.
#[test]
fn shared_tails_keep_the_expectation() {
    assert_setting_keeps_the_expectation(
        "grid = [4, 4]",
        |side| format!("share_tile = {side}"),
        &format!("{FOG}\ng = 0.6"),
        (1, 4),
        (240_000, 31),
        0.05,
        ("unshared", "shared"),
    );
}

/// A path stops once everything it can still add lands past the capture window, shared tails included
/// (their replay moves entries earlier by up to the tile's spread): on the fog T (4 × 4 laser grid in
/// tiles of 4 × 4, g = 0.6, reflective relay), a window ending at 2.5 m, which cuts most fog paths
/// after their first vertices, gives its last metre the expectation of the same bins of a window ending
/// at 9 m, where paths end only by their depth (every histogram's sum over those bins within 5 %, the
/// difference within the seed noise, as for `shared_tails_keep_the_expectation`). A cut made 0.3 m
/// too early fails it (sums 6 % low); leaving out the tile's slack (up to 0.6 m here) does not, so
/// that part rests on the triangle inequality alone.
#[test]
fn paths_past_the_window_stop_without_bias() {
    let text = fog_t_text(
        1.0,
        "grid = [4, 4]\nextent = [0.4, 0.4]\nspad_point = [0.0, 0.0]\nbin_width = 0.1",
        "max_depth = 4\nshare_tile = 4",
        &format!("{FOG}\ng = 0.6"),
    );
    let with_bins = |bins: usize| {
        let ov = Overrides {
            bins: Some(bins),
            ..Overrides::default()
        };
        Scene::from_str(&text, std::path::Path::new("window.toml"), &ov).expect("valid scene")
    };
    // The window's last metre (bins 15–24), where a cut made too early would show first.
    let late = |s: &Scene, bins: usize, seed: u64| -> Vec<f32> {
        render(s, 240_000, seed)
            .h
            .chunks(bins)
            .flat_map(|h| h[15..25].to_vec())
            .collect()
    };
    let (short, long) = (with_bins(25), with_bins(90));
    let (a, a2, b) = (
        late(&short, 25, 61),
        late(&short, 25, 62),
        late(&long, 90, 63),
    );
    assert_same_expectation(
        &a,
        &a2,
        &b,
        10,
        0.05,
        2.0,
        ("window to 2.5 m", "window to 9 m"),
    );
}

/// Target-side draws in the phase function's lobe toward the path vertex (`target_lobe`) keep every
/// histogram's expectation: the fog T in forward-scattering fog (g = 0.7), none against 0.8 of the draws
/// in the lobe; sums agree within 5 % (seed noise of one sum: ~1 %). The medium lobe is off, so that
/// only the target lobe differs between the two.
#[test]
fn target_lobe_keeps_the_expectation() {
    assert_setting_keeps_the_expectation(
        "grid = [2, 2]",
        |tenths| format!("medium_lobe = 0\ntarget_lobe = {}", tenths as f64 / 10.0),
        &format!("{FOG}\ng = 0.7"),
        (0, 8),
        (240_000, 41),
        0.05,
        ("cosine lobe", "phase lobe"),
    );
}

/// Phase-angle distances on every segment (`phase_distances`) keep every histogram's expectation: the
/// fog T in strongly forward fog (g = 0.9), none against two draws per segment and target; sums agree
/// within 5 % (seed noise of one sum: ~1 %) and the difference stays within the seed noise.
#[test]
fn phase_distances_keep_the_expectation() {
    assert_setting_keeps_the_expectation(
        "grid = [2, 2]",
        |n| format!("phase_distances = {n}"),
        &format!("{FOG}\ng = 0.9"),
        (0, 2),
        (240_000, 71),
        0.05,
        ("without phase-angle distances", "with them"),
    );
}

/// Target-side distances drawn in the phase angle (`target_phase_distances`) keep every histogram's
/// expectation: the fog T at g = 0.9 and at g = −0.7 (the lobe backwards), equiangular alone against
/// half the draws in the phase angle; as `phase_distances_keep_the_expectation`.
#[test]
fn target_phase_distances_keep_the_expectation() {
    assert_share_keeps_the_expectation(
        "target_phase_distances",
        [81, 91],
        ("equiangular target-side distances", "phase-angle ones"),
    );
}

/// The share `key` at 0 and 0.5 keeps every histogram's expectation on the fog T at g = 0.9 and at
/// g = −0.7 (seeds from `seeds`), as `phase_distances_keep_the_expectation`.
fn assert_share_keeps_the_expectation(key: &str, seeds: [u64; 2], names: (&str, &str)) {
    for (g, seed) in [(0.9, seeds[0]), (-0.7, seeds[1])] {
        assert_setting_keeps_the_expectation(
            "grid = [2, 2]",
            |tenths| format!("{key} = {}", tenths as f64 / 10.0),
            &format!("{FOG}\ng = {g}"),
            (0, 5),
            (240_000, seed),
            0.05,
            names,
        );
    }
}

/// Directions leaving the T in the phase function's lobe toward the target (`surface_lobe`) keep every
/// histogram's expectation: the fog T at g = 0.9 and at g = −0.7 (the lobe pointing away from the
/// target), the cosine lobe alone against half the directions in the phase lobe; as
/// `phase_distances_keep_the_expectation`.
#[test]
fn surface_lobe_keeps_the_expectation() {
    assert_share_keeps_the_expectation(
        "surface_lobe",
        [101, 111],
        ("cosine lobe", "phase lobe toward the target"),
    );
}

/// Vertices drawn around the line from each medium vertex to the target (`spindle_draws`) keep every
/// histogram's expectation: the fog T at g = 0.9 and at g = −0.7 (where the line is the phase
/// function's trough), none against two draws per vertex; as `phase_distances_keep_the_expectation`.
#[test]
fn spindle_draws_keep_the_expectation() {
    for (g, seed) in [(0.9, 121), (-0.7, 131)] {
        assert_setting_keeps_the_expectation(
            "grid = [2, 2]",
            |n| format!("spindle_draws = {n}"),
            &format!("{FOG}\ng = {g}"),
            (0, 2),
            (240_000, seed),
            0.05,
            ("without spindle draws", "with them"),
        );
    }
}

/// Directions leaving medium vertices in the phase function's lobe toward the target (`medium_lobe`)
/// keep every histogram's expectation: the fog T at g = 0.9 and at g = −0.7 (the lobe around the target
/// pointing away from most arriving directions), the phase lobe alone against half the directions
/// toward the target, with shared tails (the tile's first vertex keeps the phase lobe alone) and object
/// connections from medium vertices (their balance weight takes the mixture's density); as
/// `phase_distances_keep_the_expectation`.
#[test]
fn medium_lobe_keeps_the_expectation() {
    assert_share_keeps_the_expectation(
        "medium_lobe",
        [121, 131],
        ("phase lobe", "phase lobe toward the target"),
    );
}

/// `medium_lobe` without shared tails, where the first medium vertex draws from the mixture too: the
/// fog T at g = 0.9, as `medium_lobe_keeps_the_expectation`.
#[test]
fn medium_lobe_keeps_the_expectation_unshared() {
    assert_setting_keeps_the_expectation(
        "grid = [2, 2]",
        |tenths| format!("share_tile = 1\nmedium_lobe = {}", tenths as f64 / 10.0),
        &format!("{FOG}\ng = 0.9"),
        (0, 5),
        (240_000, 141),
        0.05,
        ("phase lobe", "phase lobe toward the target"),
    );
}

/// Error falls as spp^−½: 16× the paths gives 4× less relative L2 error against a 64 000-spp reference
/// (expected 3.9 with the reference's own noise; accepted: 3.2–5.0).
#[test]
fn error_falls_as_inverse_sqrt_spp() {
    let s = scene(&format!(
        r#"
        [relay]
        kind = "wall"
        size = [1.0, 1.0]
        [capture]
        kind = "single"
        grid = [2, 2]
        bins = 60
        bin_width = 0.05
        [render]
        max_depth = 3
        [medium]
        mu_t = 1.0
        albedo = 0.5
        min = [-1.5, -1.5, 0.001]
        max = [1.5, 1.5, 2.5]
        {T_LETTER}
        "#
    ));
    let reference = render(&s, 64_000, 7).h;
    let err = |spp: u64, seed: u64| {
        let h = render(&s, spp, seed).h;
        let num: f64 = h
            .iter()
            .zip(&reference)
            .map(|(x, r)| ((x - r) as f64).powi(2))
            .sum();
        let den: f64 = reference.iter().map(|r| (*r as f64).powi(2)).sum();
        (num / den).sqrt()
    };
    // Medians of five seeds: one run's error of a path tracer in fog has a skewed spread (measured for
    // single runs at 250 spp: 0.29–0.76).
    let median = |spp: u64, seed0: u64| {
        let mut e: Vec<f64> = (seed0..seed0 + 5).map(|seed| err(spp, seed)).collect();
        e.sort_by(f64::total_cmp);
        e[2]
    };
    let (e1, e16) = (median(250, 8), median(4000, 20));
    let ratio = e1 / e16;
    assert!(
        (3.2..5.0).contains(&ratio),
        "errors {e1:.4} (250 spp) and {e16:.4} (4000 spp): ratio {ratio:.2}"
    );
}

/// A closed white box (the 1 m × 1 m relay wall and a 0.15 m-deep white box behind it, albedo 1) gains
/// no energy: the power reaching the relay at each scattering order, π·Σ H·ΔA over a 32² sensor grid,
/// is at most the unit laser power (+3 % for noise and the grid sum). Measured: 0.86, 0.07, 0.73 for
/// orders 1–3 (a second relay bounce is coplanar with the sensor, hence the small order 2); a
/// double-counting estimator would give ≈ 1.7 at order 1. Checked without and with an α = 1 medium.
#[test]
fn closed_white_box_never_gains_energy() {
    for medium in ["", "[medium]\nmu_t = 2.0\nalbedo = 1.0\ng = 0.5\nmin = [-0.5, -0.5, 0.0]\nmax = [0.5, 0.5, 0.15]\n"] {
        let power = |depth: u32| {
            let s = scene(&format!(
                r#"
                [relay]
                kind = "wall"
                size = [1.0, 1.0]
                albedo = 1.0
                [capture]
                kind = "single"
                grid = [32, 32]
                bins = 50
                bin_width = 0.2
                [render]
                max_depth = {depth}
                hidden_geometry_sampling = 0.0
                {medium}
                [[object]]
                shape = "box"
                min = [-0.5, -0.5, 0.0]
                max = [0.5, 0.5, 0.15]
                omit = ["-z"]
                "#
            ));
            let h = render(&s, 100, 10).h;
            PI * h.iter().map(|v| *v as f64).sum::<f64>() / (32.0 * 32.0)
        };
        let mut prev = 0.0;
        for depth in 1..=3 {
            let e = power(depth);
            let order = e - prev;
            assert!(order <= 1.03, "medium {medium:?}: order {depth} delivers {order:.3} of the laser power");
            // The relay sees most first-order light (0.86 without, 0.41 with the medium): the bound has teeth.
            if depth == 1 {
                assert!(order > 0.3, "medium {medium:?}: order 1 delivers only {order:.3}");
            }
            prev = e;
        }
    }
}

/// Thinning past the first hidden vertex (default `first_vertex_survival` 0.1 without a medium) and pure
/// hidden-geometry sampling (default 1) are unbiased: in the closed white box, the power of orders 1–3 (half
/// of it from past the first vertex) agrees with unthinned, cosine-mixed sampling within 5 % (measured over
/// seeds: −0.7 to +2.3 %, the thinned paths' rare large contributions; dropping the 1/q weight gives about −43 %).
#[test]
fn first_vertex_thinning_keeps_multibounce_power() {
    let power = |settings: &str| {
        let s = scene(&format!(
            r#"
            [relay]
            kind = "wall"
            size = [1.0, 1.0]
            albedo = 1.0
            [capture]
            kind = "single"
            grid = [16, 16]
            bins = 50
            bin_width = 0.2
            [render]
            max_depth = 3
            {settings}
            [[object]]
            shape = "box"
            min = [-0.5, -0.5, 0.0]
            max = [0.5, 0.5, 0.15]
            omit = ["-z"]
            "#
        ));
        let h = render(&s, 3200, 3).h;
        PI * h.iter().map(|v| *v as f64).sum::<f64>() / (16.0 * 16.0)
    };
    let thinned = power("");
    let full = power("first_vertex_survival = 1.0\nhidden_geometry_sampling = 0.5");
    assert!(
        (thinned / full - 1.0).abs() < 0.05,
        "thinned {thinned:.4} vs full {full:.4}"
    );
}
