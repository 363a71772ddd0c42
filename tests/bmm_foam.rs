//! The boundary migration model on the real foam captures (Du et al. 2022, a letter T 2–8 cm deep in
//! polyethylene foam): `murk import --format bmm` then `murk reconstruct --method bmm`, and the
//! front view compared with a T mask (docs/reconstruction.md, "bmm").

#[path = "common/cli.rs"]
mod cli;
use cli::murk;
use std::path::{Path, PathBuf};

const DATA: &str = "../shared/data/real/bmm_du2022";

/// A fresh folder per test (`tag`) and process.
fn dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("murk-bmm-foam-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn ok(args: &[&str]) -> String {
    let (code, out, err) = murk(args);
    assert_eq!(code, 0, "{args:?}: {err}");
    out
}

/// The letter T as the capture repository's object panel draws it (fig/results.png, on the ±0.1 m
/// scan): a bar |x| ≤ 4.2 cm, 2.0 ≤ y ≤ 4.4 cm, and a stem |x| ≤ 1.1 cm, −4.4 ≤ y < 2.0 cm. With
/// `upside_down` the same T mirrored in y (bar at the bottom).
fn t_mask(x: f64, y: f64, upside_down: bool) -> bool {
    let y = if upside_down { -y } else { y };
    (x.abs() <= 0.042 && (0.020..=0.044).contains(&y))
        || (x.abs() <= 0.011 && (-0.044..0.020).contains(&y))
}

/// (the best-threshold IoU of the front view with the upright T, with the upside-down T, the median
/// depth of the brightest voxel over the upright mask).
fn score(v: &murk_io::VolumeData) -> (f64, f64, f64) {
    let nz = v.z.len();
    let ny = v.y.len();
    let mut front = Vec::new();
    let mut depth = Vec::new();
    for col in v.intensity.chunks_exact(nz) {
        let (k, m) = col
            .iter()
            .enumerate()
            .fold((0, f32::MIN), |b, (k, &x)| if x > b.1 { (k, x) } else { b });
        front.push(m);
        depth.push(v.z[k]);
    }
    let top = front.iter().cloned().fold(f32::MIN, f32::max);
    let at = |i: usize| (v.x[i / ny], v.y[i % ny]);
    let iou = |upside_down: bool| {
        (1..20)
            .map(|t| {
                let level = top * t as f32 / 20.0;
                let (mut both, mut either) = (0, 0);
                for (i, &f) in front.iter().enumerate() {
                    let (x, y) = at(i);
                    let (a, b) = (f >= level, t_mask(x, y, upside_down));
                    both += (a && b) as usize;
                    either += (a || b) as usize;
                }
                both as f64 / either as f64
            })
            .fold(0.0, f64::max)
    };
    let mut d: Vec<f64> = (0..front.len())
        .filter(|&i| {
            let (x, y) = at(i);
            t_mask(x, y, false)
        })
        .map(|i| depth[i])
        .collect();
    d.sort_by(f64::total_cmp);
    (iou(false), iou(true), d[d.len() / 2])
}

/// Imports the capture of the T `depth_cm` deep into `out`; returns its path.
fn import(out: &Path, depth_cm: u32) -> PathBuf {
    let src = format!("{DATA}/{depth_cm}cmFoam_LambertianT_7cmFoam.mat");
    let cap = out.join(format!("t{depth_cm}.h5"));
    ok(&[
        "import",
        &src,
        "--format",
        "bmm",
        "--out",
        cap.to_str().unwrap(),
        "-q",
    ]);
    cap
}

fn reconstruct(out: &Path, depth_cm: u32) -> murk_io::VolumeData {
    let cap = import(out, depth_cm);
    let vol = out.join(format!("v{depth_cm}.h5"));
    let info = ok(&["info", cap.to_str().unwrap()]);
    assert!(info.contains("medium_n: 1.23"), "{info}");
    ok(&[
        "reconstruct",
        cap.to_str().unwrap(),
        "--method",
        "bmm",
        "--out",
        vol.to_str().unwrap(),
        "-q",
    ]);
    murk_io::read_volume_h5(&vol).unwrap()
}

/// The T upright at 2, 4 and 6 cm: its IoU with the upright mask at least 0.4 and 0.15 above the
/// upside-down one's (measured 0.46/0.25, 0.50/0.25, 0.47/0.21). Its depth within 1 cm at 2 and
/// 4 cm (measured 2.86 and 3.24 cm). At 6 cm the depth comes out at 3.46 cm, and at 8 cm no T
/// (IoU 0.29 against 0.27): both are asserted as measured, so that a change shows. Why 6 cm cannot
/// reach 1 cm: [`foam_t_perturbation_time_course`] and docs/reconstruction.md, "Why deep objects
/// come out shallow".
#[test]
#[ignore = "reads the real captures ../shared/data/real/bmm_du2022 (slow); .ci/run runs it with --ignored when that folder is there"]
fn foam_t_found_upright() {
    let out = dir("upright");
    for (depth_cm, depth_tol_m) in [(2, 0.01), (4, 0.01), (6, 0.03)] {
        let (upright, upside_down, depth_m) = score(&reconstruct(&out, depth_cm));
        eprintln!(
            "{depth_cm} cm: IoU {upright:.2} (upside down {upside_down:.2}), depth {depth_m:.4} m"
        );
        assert!(
            upright >= 0.4 && upright >= upside_down + 0.15,
            "{depth_cm} cm: IoU {upright:.2}, upside down {upside_down:.2}"
        );
        let want = depth_cm as f64 / 100.0;
        assert!(
            (depth_m - want).abs() <= depth_tol_m,
            "{depth_cm} cm: depth {depth_m:.4} m"
        );
    }
    let (upright, upside_down, _) = score(&reconstruct(&out, 8));
    eprintln!("8 cm: IoU {upright:.2} (upside down {upside_down:.2})");
    assert!(
        upright < upside_down + 0.15,
        "8 cm now shows the T: {upright:.2} vs {upside_down:.2}; update docs/reconstruction.md"
    );
    std::fs::remove_dir_all(out).ok();
}

/// The round trip of the extrapolated-boundary half-space (foam: n 1.23, μs′ 313 /m) to a point
/// `z` below the scan point, t seconds after the surface return, up to a constant: each leg is a
/// source 1/μs′ deep minus its image beyond the extrapolated boundary, and two legs of distances
/// a, b convolve in closed form to (1/a + 1/b)·t^{−3/2}·e^{−(a+b)²/(4κt)}.
fn half_space_round_trip(z: f64, t: f64) -> f64 {
    let (n, musp) = (1.23, 313.0);
    let kappa = 299_792_458.0 / n / (3.0 * musp);
    let r = -1.440 / (n * n) + 0.710 / n + 0.668 + 0.0636 * n;
    let (z0, ze) = (1.0 / musp, 2.0 * (1.0 + r) / (1.0 - r) / (3.0 * musp));
    let (r1, r2) = (z - z0, z + z0 + 2.0 * ze);
    let pair = |a: f64, b: f64| (1.0 / a + 1.0 / b) * (-(a + b).powi(2) / (4.0 * kappa * t)).exp();
    t.powf(-1.5) * (pair(r1, r1) - 2.0 * pair(r1, r2) + pair(r2, r2))
}

/// What the captures themselves say about depth, whatever the method: the T's perturbation (the
/// mean over the T mask of each histogram minus the scan's median histogram, from the surface
/// return to the end of the recorded data, 62 bins = 3.4 ns later) fitted by the half-space round
/// trip of a point, the depth maximising the normalised correlation over 0.5–15 cm. Measured:
/// 2.75, 4.50, 1.75 and 1.50 cm for 2, 4, 6, 8 cm (correlations 0.92, 0.93, 0.98, 0.99). In the
/// README's foam the 6 and 8 cm captures' T signal has the time course of a T 1.5–2 cm deep: their
/// contrast is strongest 1–20 bins after the surface, where a 6 cm object has not yet been reached
/// (its round trip peaks 84 bins after the surface, past the recorded data).
#[test]
#[ignore = "reads the real captures ../shared/data/real/bmm_du2022 (slow); .ci/run runs it with --ignored when that folder is there"]
fn foam_t_perturbation_time_course() {
    let out = dir("time-course");
    for (depth_cm, lo_m, hi_m) in [
        (2, 0.02, 0.035),
        (4, 0.035, 0.05),
        (6, 0.01, 0.025),
        (8, 0.01, 0.025),
    ] {
        let c = murk_io::read_capture(&import(&out, depth_cm)).unwrap();
        let bins = c.time.bins;
        let mut sum = vec![0f64; bins];
        for h in c.h.chunks(bins) {
            sum.iter_mut().zip(h).for_each(|(s, &v)| *s += v as f64);
        }
        let k0 = (0..bins)
            .max_by(|&a, &b| sum[a].total_cmp(&sum[b]))
            .unwrap();
        let end = 1 + (0..bins).rposition(|k| sum[k] > 0.0).unwrap();
        let in_t: Vec<bool> = c
            .illum
            .points
            .iter()
            .map(|p| t_mask(p.x, p.y, false))
            .collect();
        let pert: Vec<f64> = (k0 + 1..end)
            .map(|k| {
                let mut col: Vec<f32> = c.h.chunks(bins).map(|h| h[k]).collect();
                let mid = col.len() / 2;
                let median = *col.select_nth_unstable_by(mid, f32::total_cmp).1 as f64;
                let (s, n) =
                    c.h.chunks(bins)
                        .zip(&in_t)
                        .filter(|(_, &m)| m)
                        .fold((0.0, 0), |(s, n), (h, _)| (s + h[k] as f64 - median, n + 1));
                s / n as f64
            })
            .collect();
        let dt_s = c.time.bin_width_m / 299_792_458.0;
        let fit = |z: f64| {
            let k: Vec<f64> = (1..=pert.len())
                .map(|i| half_space_round_trip(z, i as f64 * dt_s))
                .collect();
            let dot: f64 = k.iter().zip(&pert).map(|(a, b)| a * b).sum();
            let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
            // A shadow: the object takes light from the medium's response.
            -dot / norm(&k) / norm(&pert)
        };
        let (z, corr) = (2..60)
            .map(|i| i as f64 * 0.0025)
            .map(|z| (z, fit(z)))
            .fold((0.0, f64::MIN), |b, x| if x.1 > b.1 { x } else { b });
        eprintln!(
            "{depth_cm} cm: recorded bins {k0}–{}, perturbation's depth {z:.4} m (correlation {corr:.3})",
            end - 1
        );
        assert_eq!((k0, end), (16, 79), "{depth_cm} cm");
        assert!(
            (lo_m..=hi_m).contains(&z) && corr > 0.85,
            "{depth_cm} cm: {z} m, {corr}"
        );
    }
    std::fs::remove_dir_all(out).ok();
}
