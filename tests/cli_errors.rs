//! Bad input through the real `murk` binary: one line on stderr naming the problem (and the file),
//! a non-zero exit code, no panic, and no output file left behind.

use std::path::{Path, PathBuf};
use std::process::Command;

fn murk(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_murk"))
        .args(args)
        .arg("--quiet")
        .output()
        .expect("run murk");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

fn dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("murk-cli-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Asserts a clean failure whose single stderr line contains every `needle`.
fn fails(args: &[&str], needles: &[&str]) {
    let (code, _, err) = murk(args);
    assert_ne!(code, 0, "{args:?} succeeded");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "{args:?}: expected one line, got:\n{err}");
    assert!(lines[0].starts_with("murk: error: "), "{args:?}: {err}");
    assert!(
        !err.contains("panicked") && !err.contains("RUST_BACKTRACE"),
        "{args:?}: {err}"
    );
    for n in needles {
        assert!(lines[0].contains(n), "{args:?}: '{n}' not in: {}", lines[0]);
    }
}

/// A small valid capture with a distinctive H value and bin width, so tests can corrupt them in place.
fn good_capture(d: &Path) -> PathBuf {
    let p = d.join("good.h5");
    let (code, _, err) = murk(&[
        "synth",
        "--out",
        p.to_str().unwrap(),
        "--grid",
        "8",
        "--bins",
        "256",
        "--bin-width",
        "0.0123",
        "--target",
        "point:0.1,0.1,0.8",
    ]);
    assert_eq!(code, 0, "{err}");
    p
}

/// Replaces the first occurrence of `from` in the file's bytes by `to`.
fn patch(src: &Path, dst: &Path, from: &[u8], to: &[u8]) {
    let mut bytes = std::fs::read(src).unwrap();
    let at = bytes
        .windows(from.len())
        .position(|w| w == from)
        .expect("pattern present");
    bytes[at..at + to.len()].copy_from_slice(to);
    std::fs::write(dst, bytes).unwrap();
}

fn no_leftovers(d: &Path, keep: &[&str]) {
    for e in std::fs::read_dir(d).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(keep.contains(&name.as_str()), "left behind: {name}");
    }
}

#[test]
fn missing_truncated_and_foreign_files() {
    let d = dir("files");
    let good = good_capture(&d);
    let out = d.join("v.npy");
    let out = out.to_str().unwrap();
    fails(&["info", d.join("nope.h5").to_str().unwrap()], &["nope.h5"]);
    fails(
        &[
            "reconstruct",
            d.join("nope.h5").to_str().unwrap(),
            "--out",
            out,
        ],
        &["nope.h5"],
    );

    let bytes = std::fs::read(&good).unwrap();
    let cut = d.join("cut.h5");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    fails(
        &["reconstruct", cut.to_str().unwrap(), "--out", out],
        &["cut.h5"],
    );

    let text = d.join("notes.h5");
    std::fs::write(&text, "not an HDF5 file at all\n").unwrap();
    fails(&["info", text.to_str().unwrap()], &["notes.h5"]);

    // An HDF5 file that is not a capture: murk's own volume output.
    let vol = d.join("volume.h5");
    let (code, _, err) = murk(&[
        "reconstruct",
        good.to_str().unwrap(),
        "--out",
        vol.to_str().unwrap(),
        "--volume",
        "-0.4:0.4:5,-0.4:0.4:5,0.6:1.0:5",
    ]);
    assert_eq!(code, 0, "{err}");
    fails(&["info", vol.to_str().unwrap()], &["volume.h5"]);
    no_leftovers(&d, &["good.h5", "cut.h5", "notes.h5", "volume.h5"]);
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn non_finite_h_and_zero_bin_width() {
    let d = dir("values");
    let good = good_capture(&d);
    let out = d.join("v.npy");
    let out = out.to_str().unwrap();
    // The capture's largest H value, stored as little-endian f32 in the uncompressed file.
    let cap = murk_io::read_capture(&good).unwrap();
    let max = cap.h.iter().cloned().fold(0.0f32, f32::max);
    let nan = d.join("nan.h5");
    patch(&good, &nan, &max.to_le_bytes(), &f32::NAN.to_le_bytes());
    fails(
        &["reconstruct", nan.to_str().unwrap(), "--out", out],
        &["nan.h5", "non-finite"],
    );
    let inf = d.join("inf.h5");
    patch(
        &good,
        &inf,
        &max.to_le_bytes(),
        &f32::INFINITY.to_le_bytes(),
    );
    fails(
        &["reconstruct", inf.to_str().unwrap(), "--out", out],
        &["inf.h5", "non-finite"],
    );
    let zero = d.join("zero.h5");
    patch(
        &good,
        &zero,
        &0.0123f32.to_le_bytes(),
        &0.0f32.to_le_bytes(),
    );
    fails(
        &["reconstruct", zero.to_str().unwrap(), "--out", out],
        &["zero.h5", "bin width"],
    );
    no_leftovers(&d, &["good.h5", "nan.h5", "inf.h5", "zero.h5"]);
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn nonsense_parameters() {
    let d = dir("params");
    let good = good_capture(&d);
    let g = good.to_str().unwrap();
    let out = d.join("v.npy");
    let out = out.to_str().unwrap();
    fails(
        &[
            "reconstruct",
            g,
            "--out",
            out,
            "--volume",
            "-0.5:0.5:4,-0.5:0.5:4,-0.2:0.5:4",
        ],
        &["behind the relay wall"],
    );
    fails(
        &["reconstruct", g, "--out", out, "--volume", "garbage"],
        &["--volume"],
    );
    fails(
        &["reconstruct", g, "--out", out, "--wavefactor", "1"],
        &["Nyquist"],
    );
    fails(
        &["reconstruct", g, "--out", out, "--cycles", "-1"],
        &["cycles"],
    );
    fails(
        &[
            "reconstruct",
            g,
            "--out",
            out,
            "--compensate",
            "paper",
            "--mu-t",
            "1",
            "--albedo",
            "2",
        ],
        &["albedo"],
    );
    fails(
        &["reconstruct", g, "--out", d.join("v.txt").to_str().unwrap()],
        &["v.txt"],
    );
    fails(
        &["synth", "--out", out, "--target", "point:0,0,-1"],
        &["not behind the wall"],
    );
    fails(
        &["synth", "--out", out, "--target", "point:0,0,50"],
        &["time window"],
    );
    fails(
        &["synth", "--out", out, "--target", "z:1", "--bin-width", "0"],
        &["bin-width"],
    );
    no_leftovers(&d, &["good.h5"]);
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn help_teaches_and_demo_runs() {
    let (code, out, _) = murk(&["reconstruct", "--help"]);
    assert_eq!(code, 0);
    assert!(
        out.contains("--wavefactor") && out.contains("Examples"),
        "{out}"
    );
    let d = dir("demo");
    let (code, out, err) = murk(&["demo", "--out", d.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(out.is_empty(), "--quiet printed: {out}");
    for f in [
        "capture.h5",
        "volume.npy",
        "front.png",
        "top.png",
        "side.png",
        "depth.png",
        "index.html",
    ] {
        assert!(d.join(f).exists(), "{f} missing");
    }
    let (_, v) = murk_io::read_npy_f32(&d.join("volume.npy")).unwrap();
    let (vol_shape, _) = murk_io::read_npy_f32(&d.join("volume.npy")).unwrap();
    // The demo's Z is 1 m deep; depth axis 0.5..1.5 m in 51 planes → plane 25.
    let nz = vol_shape[2];
    let i = v
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .unwrap()
        .0;
    assert!((i % nz).abs_diff(25) <= 1, "peak at plane {}", i % nz);
    std::fs::remove_dir_all(&d).ok();
}
