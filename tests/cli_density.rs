//! Bad density grids (`[medium] kind = "grid"`) through the real `murk` binary: one line on stderr
//! naming the density file and the problem, a non-zero exit code, no panic; and bad medium fields
//! named by the scene file.

use std::path::{Path, PathBuf};

#[path = "common/cli.rs"]
mod cli;

/// A fresh folder for the test `name` (the tests run in parallel).
fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("murk-cli-density-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A small fog scene in `d` whose `[medium]` has the lines `medium`; its path.
fn scene(d: &Path, name: &str, medium: &str) -> PathBuf {
    let p = d.join(name);
    std::fs::write(
        &p,
        format!(
            "[relay]\nkind = \"wall\"\nsize = [1.0, 1.0]\n[capture]\nkind = \"laser-grid\"\n\
             grid = [2, 2]\nbins = 64\nbin_width = 0.05\n[medium]\nalbedo = 0.5\nmu_t = 1.0\n\
             min = [-1.5, -1.5, 0.001]\nmax = [1.5, 1.5, 2.5]\n{medium}\n"
        ),
    )
    .unwrap();
    p
}

/// A `.npy` header (version 1) for `descr` and `shape`, padded as numpy pads it.
fn npy_header(descr: &str, shape: &str) -> Vec<u8> {
    let mut h = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    h.push_str(&" ".repeat((64 - (10 + h.len() + 1) % 64) % 64));
    h.push('\n');
    let mut b = b"\x93NUMPY\x01\x00".to_vec();
    b.extend((h.len() as u16).to_le_bytes());
    b.extend(h.as_bytes());
    b
}

/// Renders `scene` and asserts a clean one-line failure containing every `needle`.
fn fails(d: &Path, scene: &Path, needles: &[&str]) {
    let out = d.join("r.h5");
    let args = [
        "render",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--spp",
        "1",
        "--quiet",
    ];
    fails_with(&args, needles);
    assert!(!out.exists());
}

#[test]
fn bad_density_grids_are_one_line_naming_the_file() {
    let d = dir("render");
    let grid = |name: &str| format!("kind = \"grid\"\ndensity = \"{name}\"");
    let write = |name: &str, shape: &[usize], v: &[f32]| {
        murk_io::write_npy_f32(&d.join(name), shape, v).unwrap();
    };
    let mut nan = vec![0.5f32; 8];
    nan[5] = f32::NAN;
    write("nan.npy", &[2, 2, 2], &nan);
    write(
        "negative.npy",
        &[2, 2, 2],
        &[0.5, 0.5, -0.1, 0.5, 0.5, 0.5, 0.5, 0.5],
    );
    write("flat.npy", &[4, 2], &[0.5; 8]);
    write("zero.npy", &[2, 2, 2], &[0.0; 8]);
    // A header claiming 10⁵ cells a side, over a few bytes of data: refused before allocating.
    let mut absurd = npy_header("<f4", "(100000, 100000, 100000)");
    absurd.extend([0u8; 16]);
    std::fs::write(d.join("absurd.npy"), absurd).unwrap();
    // A 2 × 2 × 2 header whose data stops after five values.
    let mut cut = npy_header("<f4", "(2, 2, 2)");
    cut.extend([0u8; 20]);
    std::fs::write(d.join("cut.npy"), cut).unwrap();
    for (file, needles) in [
        ("nan.npy", &["nan.npy", "density[1, 0, 1] = NaN"][..]),
        (
            "negative.npy",
            &["negative.npy", "density[0, 1, 0] = -0.1", "≥ 0"],
        ),
        ("flat.npy", &["flat.npy", "3 dimensions", "[4, 2]"]),
        ("zero.npy", &["zero.npy", "every density is 0"]),
        ("absurd.npy", &["absurd.npy", "read limit"]),
        ("cut.npy", &["cut.npy", "truncated"]),
        ("missing.npy", &["missing.npy"]),
    ] {
        let s = scene(&d, &format!("{file}.toml"), &grid(file));
        fails(&d, &s, needles);
    }
    // Fields of one kind given to another, and a kind without its field: named by the scene file.
    for (medium, needles) in [
        (
            "density = \"nan.npy\"",
            &["medium.density", "kind = \"grid\""][..],
        ),
        (
            "kind = \"grid\"",
            &["medium.density", "needs a density grid"],
        ),
        ("kind = \"height\"", &["medium.height_scale", "got none"]),
        (
            "kind = \"height\"\nheight_scale = 0.0",
            &["medium.height_scale", "got 0"],
        ),
        (
            "kind = \"grid\"\nheight_scale = 1.0\ndensity = \"nan.npy\"",
            &["medium.height_scale"],
        ),
    ] {
        let s = scene(&d, "fields.toml", medium);
        let mut all = vec!["fields.toml"];
        all.extend(needles);
        fails(&d, &s, &all);
    }
    std::fs::remove_dir_all(&d).unwrap();
}

/// Runs `murk` with `args` and asserts a clean one-line failure containing every `needle`.
fn fails_with(args: &[&str], needles: &[&str]) {
    let (code, _, err) = cli::murk(args);
    assert_ne!(code, 0, "{args:?} succeeded");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "expected one line, got:\n{err}");
    assert!(
        lines[0].starts_with("murk: error: ") && !err.contains("panicked"),
        "{err}"
    );
    for n in needles {
        assert!(lines[0].contains(n), "'{n}' not in: {}", lines[0]);
    }
}

/// `murk reconstruct --medium-density`: a bad grid is one line naming it, the flag without the
/// compensation and μt it is read by is refused, and a good grid reconstructs.
#[test]
fn reconstruct_reads_the_density_for_the_compensation() {
    let d = dir("reconstruct");
    murk_io::write_npy_f32(
        &d.join("good.npy"),
        &[2, 2, 2],
        &[0.5, 0.5, 0.5, 0.5, 2.0, 2.0, 2.0, 2.0],
    )
    .unwrap();
    let mut nan = vec![0.5f32; 8];
    nan[5] = f32::NAN;
    murk_io::write_npy_f32(&d.join("nan.npy"), &[2, 2, 2], &nan).unwrap();
    // The scene's 2 × 2 sensor grid is too coarse for Phasor Fields' wavelength: 8 × 8.
    let s = scene(&d, "grid.toml", "kind = \"grid\"\ndensity = \"good.npy\"");
    let text = std::fs::read_to_string(&s)
        .unwrap()
        .replace("grid = [2, 2]", "grid = [8, 8]");
    std::fs::write(&s, text).unwrap();
    let cap = d.join("grid.h5");
    let (code, _, err) = cli::murk(&[
        "render",
        s.to_str().unwrap(),
        "--out",
        cap.to_str().unwrap(),
        "--spp",
        "2",
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    let out = d.join("v.npy");
    let file = |n: &str| d.join(n).to_str().unwrap().to_string();
    let recon = |extra: &[&str]| -> Vec<String> {
        let mut a = vec![
            "reconstruct".to_string(),
            file("grid.h5"),
            "--out".into(),
            out.to_str().unwrap().into(),
            "--quiet".into(),
        ];
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    fn run(a: &[String]) -> Vec<&str> {
        a.iter().map(String::as_str).collect()
    }
    murk_io::write_npy_f32(
        &d.join("negative.npy"),
        &[2, 2, 2],
        &[0.5, -0.5, 0.5, 0.5, 1.0, 1.0, 1.0, 1.0],
    )
    .unwrap();
    murk_io::write_npy_f32(&d.join("flat.npy"), &[4, 2], &[0.5; 8]).unwrap();
    let mut absurd = npy_header("<f4", "(100000, 100000, 100000)");
    absurd.extend([0u8; 16]);
    std::fs::write(d.join("absurd.npy"), absurd).unwrap();
    for (name, needles) in [
        ("nan.npy", &["nan.npy", "density[1, 0, 1] = NaN"][..]),
        ("negative.npy", &["negative.npy", "density[0, 0, 1] = -0.5"]),
        ("flat.npy", &["flat.npy", "3 dimensions", "[4, 2]"]),
        ("absurd.npy", &["absurd.npy", "read limit"]),
    ] {
        let args = recon(&[
            "--compensate",
            "ballistic",
            "--mu-t",
            "1",
            "--medium-density",
            &file(name),
        ]);
        fails_with(&run(&args), needles);
    }
    // A height fog's scale out of the scene's range, or beside a grid.
    for scale in ["0", "-1", "nan", "1e-4"] {
        let args = recon(&[
            "--compensate",
            "ballistic",
            "--mu-t",
            "1",
            "--height-scale",
            scale,
        ]);
        fails_with(
            &run(&args),
            &["grid.h5", "--height-scale must be in [0.001, 1e6] m"],
        );
    }
    let both = recon(&[
        "--compensate",
        "ballistic",
        "--mu-t",
        "1",
        "--height-scale",
        "0.5",
        "--medium-density",
        &file("good.npy"),
    ]);
    fails_with(&run(&both), &["cannot be used with"]);
    let no_mu_t = recon(&["--compensate", "ballistic", "--height-scale", "0.5"]);
    fails_with(
        &run(&no_mu_t),
        &["--height-scale is read by --compensate with --mu-t"],
    );
    // The capture holds its grid's cells, as the file has them.
    let stored = murk_io::read_capture(&cap).unwrap();
    let cells = stored.medium_density.as_deref().unwrap();
    assert_eq!(cells.dims(), [2, 2, 2]);
    assert_eq!(cells.values(), [0.5, 0.5, 0.5, 0.5, 2.0, 2.0, 2.0, 2.0]);
    // Compensated along them unasked, and said so.
    let mut own = recon(&["--compensate", "ballistic", "--mu-t", "1"]);
    own.retain(|a| a != "--quiet");
    let (code, said, err) = cli::murk(&run(&own));
    assert_eq!(code, 0, "{err}");
    assert!(
        said.contains("density from the capture's own grid (2 × 2 × 2 cells)")
            && !err.contains("homogeneous"),
        "{said}\n{err}"
    );
    let from_capture = std::fs::read(&out).unwrap();
    // A capture without the cells (rendered before murk stored them): homogeneous, and said so.
    let old = d.join("old.h5");
    let without = murk_core::Capture {
        medium_density: None,
        ..stored
    };
    murk_io::write_capture(&old, &without).unwrap();
    let mut homogeneous = recon(&["--compensate", "ballistic", "--mu-t", "1"]);
    homogeneous.retain(|a| a != "--quiet");
    homogeneous[1] = old.to_str().unwrap().into();
    let (code, _, err) = cli::murk(&run(&homogeneous));
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains(
            "murk: warning: the capture's medium is a density grid (density = \"good.npy\")"
        ) && err.contains("give --medium-density FILE.npy"),
        "{err}"
    );
    // The cells make a difference the test can see.
    assert_ne!(std::fs::read(&out).unwrap(), from_capture);
    let alone = recon(&["--medium-density", &file("good.npy")]);
    fails_with(
        &run(&alone),
        &["--medium-density is read by --compensate with --mu-t"],
    );
    let good = recon(&[
        "--compensate",
        "ballistic",
        "--mu-t",
        "1",
        "--medium-density",
        &file("good.npy"),
    ]);
    let (code, _, err) = cli::murk(&run(&good));
    assert_eq!(code, 0, "{err}");
    // The capture's own grid and the same grid given by hand compensate alike, byte for byte.
    assert_eq!(std::fs::read(&out).unwrap(), from_capture);
    std::fs::remove_dir_all(&d).unwrap();
}
