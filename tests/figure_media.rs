//! `murk figure media`: every foam capture of a folder by BMM, CDT, PF (medium-aware off and on),
//! LCT and f-k, as grid.png, depths.csv and index.html.

#[path = "common/cli.rs"]
mod cli;
use cli::{murk, ok, s, temp_dir};
use std::path::Path;

/// Runs `murk figure media` on `data` into `out`; returns depths.csv's rows past its header, split
/// at commas.
fn figure(data: &Path, out: &Path) -> Vec<Vec<String>> {
    ok(&["figure", "media", "-q", "--data", s(data), "--out", s(out)]);
    let text = std::fs::read_to_string(out.join("depths.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("capture,object_depth_m,transport_mfp,method,surface_depth_m,peak_depth_m,error")
    );
    lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

/// A 16 × 16 × 256 scan named as the 4 cm BMM capture (55 ps bins, its 0.2 m side by name): a
/// surface return everywhere and a later, longer one over a patch, as an object inside the medium
/// gives. Every method writes a cell; the row carries the object's depth and its 4 cm × 313 /m =
/// 12.52 transport mean free paths.
#[test]
fn synthetic_foam_folder_gives_a_row_of_six_methods() {
    let d = temp_dir("figure-media");
    let data = d.join("data");
    std::fs::create_dir_all(&data).unwrap();
    let (n, nt) = (16, 256);
    let mut raw = vec![0.0; n * n * nt];
    for t in 0..nt {
        for b in 0..n {
            for a in 0..n {
                let tf = t as f64;
                let surface = if t >= 20 {
                    (tf - 19.0) * (-(tf - 20.0) / 10.0).exp()
                } else {
                    0.0
                };
                let deep = if t >= 30 && (5..9).contains(&a) && (3..8).contains(&b) {
                    (tf - 29.0).powi(2) * (-(tf - 30.0) / 15.0).exp()
                } else {
                    0.0
                };
                // Column-major (a, b, t), as MATLAB stores raw_data.
                raw[(t * n + b) * n + a] = 50.0 * surface + 5.0 * deep + 1.0;
            }
        }
    }
    murk_io::write_mat_v5(
        &data.join("4cmFoam_LambertianT_7cmFoam.mat"),
        &[murk_io::MatArray {
            name: "raw_data",
            dims: &[n, n, nt],
            values: &raw,
            class: murk_io::MatClass::Double,
        }],
        false,
    )
    .unwrap();
    let out = d.join("fig");
    let rows = figure(&data, &out);
    let methods: Vec<&str> = rows.iter().map(|r| r[3].as_str()).collect();
    assert_eq!(
        methods,
        ["BMM", "CDT", "PF", "PF medium-aware", "LCT", "f-k"]
    );
    for r in &rows {
        assert_eq!(
            (r[0].as_str(), r[1].as_str(), r[2].as_str()),
            ("4cmFoam_LambertianT_7cmFoam", "0.040", "12.52")
        );
        // A depth, or the reason the method failed.
        assert!(r[4].parse::<f64>().is_ok() == r[6].is_empty(), "{r:?}");
    }
    let bmm: f64 = rows[0][4].parse().unwrap();
    assert!((0.0..=0.2).contains(&bmm), "BMM surface at {bmm} m");
    let page = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(
        page.contains("object 4 cm deep in the foam, 12.5 transport mean free paths")
            && page.contains("grid.png"),
        "{page}"
    );
    assert!(std::fs::metadata(out.join("grid.png")).unwrap().len() > 1000);

    // The data folder as the output, a folder without captures, --runs: one line each, exit ≠ 0.
    for (args, want) in [
        (vec!["--out", s(&data)], "is the --data folder"),
        (
            vec!["--out", s(&d.join("x")), "--runs", "3"],
            "--runs applies to figure real",
        ),
    ] {
        let mut all = vec!["figure", "media", "--data", s(&data)];
        all.extend(args);
        let (code, _, err) = murk(&all);
        assert!(
            code != 0 && err.contains(want) && err.trim().lines().count() == 1,
            "{err}"
        );
    }
    let (code, _, err) = murk(&[
        "figure",
        "media",
        "--data",
        s(&out),
        "--out",
        s(&d.join("y")),
    ]);
    assert!(code != 0 && err.contains("no foam captures"), "{err}");
    std::fs::remove_dir_all(&d).ok();
}

/// The four shared BMM captures: BMM's surface within 1 cm of the T at 2 and 4 cm (measured 2.86
/// and 3.24 cm; it stays near 3 cm at 6 and 8 cm, as tests/bmm_foam.rs states), the transport mean
/// free paths 6.26 / 12.52 / 18.78 / 25.04, and all 24 cells reconstructed.
#[test]
#[ignore = "reads the real captures ../shared/data/real/bmm_du2022 (slow); .ci/run runs it with --ignored when that folder is there"]
fn real_foam_captures() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/real/bmm_du2022");
    let out = temp_dir("figure-media-real");
    let rows = figure(&data, &out);
    assert_eq!(rows.len(), 24);
    assert!(rows.iter().all(|r| r[6].is_empty()), "{rows:?}");
    for (cm, mfp) in [(2, "6.26"), (4, "12.52"), (6, "18.78"), (8, "25.04")] {
        let name = format!("{cm}cmFoam_LambertianT_7cmFoam");
        let row = rows.iter().find(|r| r[0] == name && r[3] == "BMM").unwrap();
        assert_eq!(row[2], mfp);
        let depth: f64 = row[4].parse().unwrap();
        println!("{name}: BMM surface at {depth:.4} m");
        if cm <= 4 {
            assert!(
                (depth - cm as f64 / 100.0).abs() <= 0.01,
                "{name}: {depth} m"
            );
        }
    }
    std::fs::remove_dir_all(&out).ok();
}
