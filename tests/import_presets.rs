//! `murk import` through the binary: the help names every preset with its published parameters,
//! the generic form reads a `.npy` scan with a flip and a time origin, and wrong combinations fail
//! with one line. The presets' layouts are tested on synthetic files in `murk_io::import`.

#[path = "common/cli.rs"]
mod cli;

use cli::murk;
use murk_io::import::Preset;
use std::path::{Path, PathBuf};

fn tmpdir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("murk-import-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// One-line error, exit code 1 or 2 (clap's), no panic.
fn fails(args: &[&str]) -> String {
    let (code, _, err) = murk(args);
    assert!(code == 1 || code == 2, "murk {args:?}: {code} {err}");
    assert!(
        err.starts_with("murk: error: ") && err.trim_end().lines().count() == 1,
        "{err}"
    );
    err
}

#[test]
fn help_lists_every_preset() {
    let (code, out, _) = murk(&["import", "--help"]);
    assert_eq!(code, 0);
    for p in Preset::ALL {
        assert!(
            out.contains(&format!("- {}:", p.name())) && out.contains(p.summary()),
            "{} missing from:\n{out}",
            p.name()
        );
    }
    assert!(out.contains("Examples:") && out.contains("--axes"), "{out}");
}

/// A confocal 6 × 6 scan stored (t, x, y) with its x axis reversed and path 0 at bin 10: the bright
/// point at x index 1 of the file (ix 4 after the flip), y index 5, comes back at its place.
#[test]
fn generic_npy_with_flip_and_t0() {
    let dir = tmpdir("generic");
    let (nt, nx, ny) = (64, 6, 6);
    let mut v = vec![0f32; nt * nx * ny];
    v[(30 * nx + 1) * ny + 5] = 5.0;
    let npy = dir.join("scan.npy");
    murk_io::write_npy_f32(&npy, &[nt, nx, ny], &v).unwrap();
    let out = dir.join("scan.h5");
    let (code, _, err) = murk(&[
        "import",
        "-q",
        s(&npy),
        "--axes",
        "t,x,y",
        "--flip",
        "x",
        "--bin-width-m",
        "0.01",
        "--wall-size",
        "0.5",
        "--confocal",
        "--t0-bin",
        "10",
        "--out",
        s(&out),
    ]);
    assert_eq!(code, 0, "{err}");
    let cap = murk_io::read_capture(&out).unwrap();
    let k = (0..cap.h.len()).fold(0, |b, k| if cap.h[k] > cap.h[b] { k } else { b });
    assert_eq!((k / nt, k % nt), (4 * ny + 5, 30));
    let p = cap.sensor.points[k / nt];
    assert!(
        (p.x - 0.15).abs() < 1e-6 && (p.y - 0.25).abs() < 1e-6,
        "{p}"
    );
    assert!((cap.time.start_m + 0.1).abs() < 1e-6, "{:?}", cap.time);
    assert!(cap.scene_info.contains("flip: 'x'"), "{}", cap.scene_info);

    // Wrong combinations: one line each.
    let other = dir.join("x.h5");
    let base = |extra: &[&str]| {
        let mut a = vec!["import", s(&npy), "--out", s(&other)];
        a.extend(extra);
        fails(&a)
    };
    let e = base(&[
        "--axes",
        "t,x,x",
        "--bin-width-m",
        "0.01",
        "--wall-size",
        "1",
        "--confocal",
    ]);
    assert!(e.contains("t, x and y once each"), "{e}");
    // Everything but --confocal.
    let framed = [
        "--axes",
        "t,x,y",
        "--bin-width-m",
        "0.01",
        "--wall-size",
        "1",
    ];
    let e = base(&framed);
    assert!(e.contains("confocal"), "{e}");
    let e = base(&["--axes", "t,x,y", "--confocal"]);
    assert!(
        e.contains("--wall-size") && e.contains("--bin-width"),
        "{e}"
    );
    let e = base(&["--format", "lct", "--tof", s(&npy)]);
    assert!(e.contains("--format fk"), "{e}");
    let e = base(&["--format", "abp"]);
    assert!(e.contains(".npy") && e.contains("--axes"), "{e}");
    let e = base(&[]);
    assert!(e.contains("--format") || e.contains("--axes"), "{e}");
    // A gate or a path-0 bin that leaves nothing to reconstruct.
    let e = base(&[&framed[..], &["--confocal", "--gate-bins", "64"]].concat());
    assert!(e.contains("a gate of 64 bins leaves nothing"), "{e}");
    let e = base(&[&framed[..], &["--confocal", "--t0-bin", "64"]].concat());
    assert!(e.contains("before the wall"), "{e}");
    // One --wall-size cannot describe a 6 × 4 scan.
    let oblong = dir.join("oblong.npy");
    murk_io::write_npy_f32(&oblong, &[nt, 6, 4], &v[..nt * 24]).unwrap();
    let e = fails(
        &[
            &["import", s(&oblong), "--out", s(&other)],
            &framed[..],
            &["--confocal"],
        ]
        .concat(),
    );
    assert!(e.contains("6 × 4 scan") && e.contains("square"), "{e}");
    std::fs::remove_dir_all(dir).ok();
}
