//! `murk medium --slab-transmission DIR`: bad calibration folders fail with one line naming the
//! file; the CDT calibration captures (when present) give the foam's μa and μs′.

use std::path::{Path, PathBuf};

#[path = "common/cli.rs"]
mod cli;

fn folder(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("murk-slab-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A histogram `out` as the reader takes it (a .npy array under the .mat name: the reader goes by
/// the file's first bytes): a pulse at bin 3900 on a background of 50.
fn histogram(path: &Path, shape: &[usize], nan: bool) {
    let n: usize = shape.iter().product();
    let mut v: Vec<f32> = (0..n)
        .map(|i| {
            let u = i as f32 - 3900.0;
            50.0 + if u >= 0.0 {
                1e5 * (-u / 20.0).exp()
            } else {
                0.0
            }
        })
        .collect();
    if nan {
        v[4000] = f32::NAN;
    }
    murk_io::write_npy_f32(path, shape, &v).unwrap();
}

fn fails(dir: &Path, needles: &[&str]) {
    let (code, _, err) = cli::murk(&[
        "medium",
        "--slab-transmission",
        dir.to_str().unwrap(),
        "--quiet",
    ]);
    assert_ne!(code, 0, "{err}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "expected one line, got:\n{err}");
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(lines[0].contains(n), "'{n}' not in: {}", lines[0]);
    }
}

#[test]
fn bad_calibration_folders_fail_naming_the_file() {
    fails(
        Path::new("/nonexistent/calibration"),
        &["/nonexistent/calibration"],
    );

    let d = folder("nodirect");
    histogram(&d.join("capture_1_0_inch.mat"), &[1, 12_000], false);
    fails(&d, &["capture_direct.mat", "missing"]);

    let d = folder("noslab");
    histogram(&d.join("capture_direct.mat"), &[1, 12_000], false);
    fails(&d, &["no slab captures"]);

    // A good direct capture and one bad slab capture: (tag, file, shape, NaN, what the line says).
    let bad: [(&str, &str, &[usize], bool, &str); 3] = [
        ("nan", "capture_2_5_inch.mat", &[1, 12_000], true, "NaN"),
        ("shape", "capture_1_0_inch.mat", &[2, 6_000], false, "shape"),
        (
            "length",
            "capture_1_0_inch.mat",
            &[1, 11_000],
            false,
            "11000 bins",
        ),
    ];
    for (tag, file, shape, nan, says) in bad {
        let d = folder(tag);
        histogram(&d.join("capture_direct.mat"), &[1, 12_000], false);
        histogram(&d.join(file), shape, nan);
        fails(&d, &[file, says]);
    }

    let d = folder("flat");
    histogram(&d.join("capture_direct.mat"), &[1, 12_000], false);
    murk_io::write_npy_f32(&d.join("capture_1_0_inch.mat"), &[12_000], &[50.0; 12_000]).unwrap();
    fails(&d, &["capture_1_0_inch.mat", "no transmitted pulse"]);
}

/// The example of `murk medium --help` and docs/medium.md on the real captures: μa and μs′ near
/// the published 0.53 /m and 262 /m (the library's test states the tolerances and why).
#[test]
#[ignore = "reads the real calibration captures ../shared/data/real/cdt_lindell2020; .ci/run runs it with --ignored when that folder is there"]
fn cdt_calibration_folder_through_the_cli() {
    let dir = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../shared/data/real/cdt_lindell2020/calibration"
    );
    let (code, out, err) = cli::murk(&["medium", "--slab-transmission", dir, "--json"]);
    assert_eq!(code, 0, "{err}");
    let mu_a = number(&out, "mu_a_per_m");
    let mu_s = number(&out, "mu_s_prime_per_m");
    assert!((mu_a - 0.53).abs() < 0.08, "{out}");
    assert!((mu_s - 262.0).abs() < 13.0, "{out}");
    assert_eq!(out.matches("\"thickness_m\"").count(), 15, "{out}");
    let (code, out, err) = cli::murk(&["medium", "--slab-transmission", dir]);
    assert_eq!(code, 0, "{err}");
    for key in [
        "mu_a:",
        "mu_s_prime:",
        "n: 1.12 (given)",
        "fit: residual",
        "8.0 inch: bins",
    ] {
        assert!(out.contains(key), "'{key}' not in:\n{out}");
    }
}

/// The number after `"key":` in one line of JSON.
fn number(json: &str, key: &str) -> f64 {
    let at = json
        .find(&format!("\"{key}\":"))
        .unwrap_or_else(|| panic!("no {key} in {json}"));
    let rest = &json[at + key.len() + 3..];
    let end = rest.find([',', '}']).unwrap();
    rest[..end].trim().parse().unwrap()
}
