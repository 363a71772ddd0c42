//! The boundary migration model on the real foam captures (Du et al. 2022, a letter T 2–8 cm deep in
//! polyethylene foam): `murk import --format bmm` then `murk reconstruct --method bmm`, and the
//! front view compared with a T mask (docs/reconstruction.md, "bmm").

#[path = "common/cli.rs"]
mod cli;
use cli::murk;
use std::path::{Path, PathBuf};

const DATA: &str = "../shared/data/real/bmm_du2022";

fn dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("murk-bmm-foam-{}", std::process::id()));
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

fn reconstruct(out: &Path, depth_cm: u32) -> murk_io::VolumeData {
    let src = format!("{DATA}/{depth_cm}cmFoam_LambertianT_7cmFoam.mat");
    let cap = out.join(format!("t{depth_cm}.h5"));
    let vol = out.join(format!("v{depth_cm}.h5"));
    ok(&[
        "import",
        &src,
        "--format",
        "bmm",
        "--out",
        cap.to_str().unwrap(),
        "-q",
    ]);
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
/// (IoU 0.29 against 0.27): both are asserted as measured, so that a change shows.
#[test]
#[ignore = "needs ../shared/data/real/bmm_du2022"]
fn foam_t_found_upright() {
    let out = dir();
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
