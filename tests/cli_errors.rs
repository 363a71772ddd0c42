//! Bad input through the real `murk` binary: one line on stderr naming the problem (and the file),
//! a non-zero exit code, no panic, and no output file left behind.

use std::path::{Path, PathBuf};
use std::process::Command;

#[path = "common/cli.rs"]
mod cli;

/// murk with `--quiet`: a failure must still say, on its one line, what went wrong.
fn murk(args: &[&str]) -> (i32, String, String) {
    cli::murk(&[args, &["--quiet"]].concat())
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
    synth_capture(d, "good.h5", &[])
}

/// `murk synth` of a point on an 8² laser grid with 256 bins of 0.0123 m, plus `extra` arguments.
fn synth_capture(d: &Path, name: &str, extra: &[&str]) -> PathBuf {
    let p = d.join(name);
    let mut args = vec![
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
    ];
    args.extend(extra);
    let (code, _, err) = murk(&args);
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
    // A FIFO is refused before it is opened (opening it would wait for a writer), as input and as
    // output (the rename would turn it into a plain file). `timeout` bounds a regression's hang.
    let fifo = d.join("pipe.h5");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(made.success());
    let f = fifo.to_str().unwrap();
    let info = std::process::Command::new("timeout")
        .args(["10", env!("CARGO_BIN_EXE_murk"), "info", f])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&info.stderr);
    assert_eq!(info.status.code(), Some(1), "{err}");
    assert!(err.contains("pipe.h5: is not a regular file"), "{err}");
    fails(
        &["synth", "--target", "z:1", "--grid", "16", "--out", f],
        &["pipe.h5: is not a regular file"],
    );
    let kind = std::fs::symlink_metadata(&fifo).unwrap().file_type();
    assert!(std::os::unix::fs::FileTypeExt::is_fifo(&kind));
    // So is a scene's mesh that is a FIFO (it used to block; /dev/zero filled memory).
    std::fs::create_dir_all(d.join("meshes")).unwrap();
    std::fs::rename(&fifo, d.join("meshes/vase.obj")).unwrap();
    let shelf = d.join("shelf.toml").to_str().unwrap().to_string();
    std::fs::copy(
        concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/shelf.toml"),
        &shelf,
    )
    .unwrap();
    fails(
        &[
            "render",
            &shelf,
            "--grid",
            "4",
            "--out",
            d.join("s.h5").to_str().unwrap(),
        ],
        &["shelf.toml", "vase.obj", "not a regular file"],
    );
    std::fs::remove_dir_all(d.join("meshes")).unwrap();
    std::fs::remove_file(&shelf).unwrap();
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
    // Histograms of zeros, or of values that underflow, give no volume but say why (lct, fk and
    // cdt used to write a volume of zeros).
    let conf = synth_capture(&d, "conf.h5", &["--kind", "confocal"]);
    for (name, scale, needle, methods) in [
        (
            "zeros.h5",
            0.0f32,
            "the capture's histograms are all zeros",
            &["pf", "lct", "cdt"][..],
        ),
        // cdt scales its input and still finds these.
        (
            "tiny.h5",
            1e-44,
            "no signal of the capture's window",
            &["pf", "lct"],
        ),
    ] {
        let mut c = murk_io::read_capture(&conf).unwrap();
        let peak = c.h.iter().cloned().fold(0.0f32, f32::max);
        c.h.iter_mut().for_each(|v| *v = *v / peak * scale);
        let p = d.join(name);
        murk_io::write_capture(&p, &c).unwrap();
        for &method in methods {
            fails(
                &[
                    "reconstruct",
                    p.to_str().unwrap(),
                    "--method",
                    method,
                    "--out",
                    out,
                ],
                &[name, "all zeros", needle],
            );
        }
    }
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
    no_leftovers(
        &d,
        &[
            "good.h5", "nan.h5", "inf.h5", "zero.h5", "conf.h5", "zeros.h5", "tiny.h5",
        ],
    );
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn nonsense_parameters() {
    let d = dir("params");
    let good = good_capture(&d);
    let g = good.to_str().unwrap();
    let out = d.join("v.npy");
    let out = out.to_str().unwrap();
    let synth_out = d.join("s.h5");
    let synth_out = synth_out.to_str().unwrap();
    // Magnitudes that used to give all-zero volumes or a Debug dump, each named.
    let conf = synth_capture(&d, "conf.h5", &["--kind", "confocal"]);
    let c = conf.to_str().unwrap();
    for (extra, want) in [
        (&["--wavelength", "1e300"][..], "the wavelength is 1e300 m"),
        (&["--cycles", "1e300"], "the virtual pulse's σ"),
        (
            &["--method", "lct", "--snr", "1e-300"],
            "LCT snr must be within",
        ),
        (
            &["--method", "cdt", "--slab-n", "0"],
            "slab refractive index",
        ),
        (
            &["--method", "cdt", "--slab-thickness", "100"],
            "slab thickness",
        ),
        (
            &["--method", "fk", "--t-offset", "4"],
            "before any depth behind the wall",
        ),
        (
            &["--method", "pf", "--slab-thickness", "0.02"],
            "slab parameters are read only by cdt and by t-offset 'slab'; pf would ignore them",
        ),
        (&["--t-offset", "4m"], "t-offset '4m': expected metres"),
    ] {
        fails(
            &[&["reconstruct", c, "--out", out][..], extra].concat(),
            &[want],
        );
    }
    fails(
        &[
            "synth", "--out", synth_out, "--target", "z:1", "--jitter", "1e300",
        ],
        &["the jitter is 1e300 m"],
    );
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
        &["volume 'garbage'", "three comma-separated axes"],
    );
    // Reversed bounds would draw the scene mirrored: refused, naming the axis.
    fails(
        &[
            "reconstruct",
            g,
            "--out",
            out,
            "--volume",
            "1:0:10,-0.5:0.5:8,0.5:1.5:8",
        ],
        &["axis '1:0:10' runs from 1 down to 0"],
    );
    fails(
        &["reconstruct", g, "--out", out, "--wavefactor", "1"],
        &["Nyquist"],
    );
    fails(
        &["reconstruct", g, "--out", out, "--cycles", "-1"],
        &["cycles"],
    );
    let compensated = |extra: &[&str], needles: &[&str]| {
        let mut args = vec!["reconstruct", g, "--out", out, "--compensate"];
        args.extend_from_slice(extra);
        fails(&args, needles);
    };
    compensated(&["paper", "--mu-t", "1", "--albedo", "2"], &["albedo"]);
    compensated(
        &["ballistic", "--mu-t", "1", "--albedo", "0.5"],
        &["'ballistic' does not read an albedo"],
    );
    fails(
        &["reconstruct", g, "--out", d.join("v.txt").to_str().unwrap()],
        &["v.txt"],
    );
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/z-letter.toml");
    let r = d.join("r.h5");
    let r = r.to_str().unwrap();
    let sweep = |extra: &[&str], needles: &[&str]| {
        let mut args = vec!["render", scene, "--out", r, "--grid", "4", "--spp", "1"];
        args.extend_from_slice(extra);
        fails(&args, needles);
    };
    sweep(&["--albedos", "0.5,1.5"], &["albedo 1.5", "(0, 1]"]);
    sweep(&["--albedos", "0.5,nan"], &["albedo NaN"]);
    sweep(&["--albedos", "0.5,0.5"], &["albedo 0.5 appears twice"]);
    sweep(&["--albedos", "0.5,zero"], &["--albedos", "zero"]);
    sweep(
        &["--albedos", "0.5", "--set", "medium.mu_t=0"],
        &["scattering medium"],
    );
    // A refused sweep writes no ground truth either; a truth file named like one of its captures
    // is refused before anything is written.
    let truth = d.join("truth.h5");
    let t = truth.to_str().unwrap();
    sweep(
        &["--albedos", "0.5,0.5", "--truth", t],
        &["albedo 0.5 appears twice"],
    );
    assert!(!truth.exists(), "a refused sweep left its truth file");
    let own = d.join("r-albedo0.5.h5");
    sweep(
        &["--albedos", "0.3,0.5", "--truth", own.to_str().unwrap()],
        &[
            "r-albedo0.5.h5",
            "--truth and the capture name the same file",
        ],
    );
    assert!(!own.exists());
    fails(
        &["synth", "--out", synth_out, "--target", "point:0,0,-1"],
        &["not behind the wall"],
    );
    fails(
        &["synth", "--out", synth_out, "--target", "point:0,0,50"],
        &["time window"],
    );
    fails(
        &[
            "import", g, "--format", "cdt", "--flip", "x,x", "--out", out,
        ],
        &["'x' is named twice"],
    );
    fails(
        &[
            "synth", "--out", synth_out, "--target", "z:1", "--mu-t", "60",
        ],
        &["attenuation", "μt = 60 /m"],
    );
    // An extinction beyond radiative transfer's range is refused alike by every command that reads one.
    let past = "a mean free path below the 1 µm where radiative transfer holds";
    fails(
        &[
            "synth", "--out", synth_out, "--target", "z:1", "--mu-t", "1e300",
        ],
        &["μt is 1e300 /m", past],
    );
    compensated(&["ballistic", "--mu-t", "2e6"], &["μt is 2e6 /m", past]);
    // Objects that could return no light, or whose error blamed something else.
    let shelf = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/shelf.toml");
    for (set, says) in [
        (
            "object[0].scale=1e-320",
            "object[0].shape: is 8.00386e-321 m across; murk needs at least 1e-7 m",
        ),
        (
            "object[0].omit=[\"-x\", \"+x\", \"-y\", \"+y\", \"-z\", \"+z\"]",
            "leaves no face to reflect light",
        ),
        (
            "object[13].scale=1e-300",
            "object[13].scale (from --set object[13].scale=1e-300): 1e-300: every one of the OBJ's 312 triangles has zero area once scaled",
        ),
        (
            "object[13].translate=[nan, 0, 1]",
            "object[13].translate (from --set object[13].translate=[nan, 0, 1]): its offset is NaN",
        ),
    ] {
        let file = if set.starts_with("object[0].scale") {
            scene
        } else {
            shelf
        };
        fails(
            &[
                "render", file, "--out", r, "--grid", "4", "--spp", "1", "--set", set,
            ],
            &[says],
        );
    }
    sweep(
        &["--set", "medium.mu_t=1e300"],
        &[
            "medium.mu_t (from --set medium.mu_t=1e300): is 1e300 /m",
            past,
        ],
    );
    fails(
        &["synth", "--out", synth_out, "--target", "point:0,0,1e-19"],
        &["depth 1e-19 m is closer to the wall than"],
    );
    fails(
        &[
            "synth",
            "--out",
            synth_out,
            "--target",
            "polygon:1:1e300,0;1,0;0,1",
        ],
        &["polygon vertex's coordinate is 1e300 m"],
    );
    fails(
        &[
            "synth", "--out", synth_out, "--target", "z:1", "--bins", "0",
        ],
        &["bins must be at least 1"],
    );
    fails(
        &[
            "synth",
            "--out",
            synth_out,
            "--target",
            "polygon:1:0,0;1,0;2,0",
        ],
        &["the polygon covers no sample"],
    );
    // Options that would do nothing without --compensate, and outputs that are not files.
    fails(
        &["reconstruct", g, "--out", out, "--mu-t", "1"],
        &["--compensate"],
    );
    fails(
        &["reconstruct", g, "--out", d.to_str().unwrap()],
        &["is a folder"],
    );
    fails(
        &["reconstruct", g, "--out", "/dev/null"],
        &["not a regular file"],
    );
    let file = d.join("a-file");
    std::fs::write(&file, b"x").unwrap();
    fails(
        &["demo", "--out", file.to_str().unwrap()],
        &["a-file: exists and is not a folder"],
    );
    std::fs::remove_file(&file).unwrap();
    fails(
        &[
            "synth",
            "--out",
            synth_out,
            "--target",
            "z:1",
            "--bin-width",
            "0",
        ],
        &["bin width must be a positive number of metres, got 0"],
    );
    // A gate past the window would leave a volume of zeros that looks like a result.
    fails(
        &["reconstruct", g, "--out", out, "--gate", "100"],
        &["good.h5", "gate at 100.000 m", "window ends"],
    );
    fails(
        &["reconstruct", g, "--out", out, "--gate", "1e30"],
        &["gate '1e30'", "100000 m"],
    );
    // A window cut at the T's return: the end's trim would clear every voxel, a volume of zeros.
    let cut = d.join("cut.h5");
    let cut = cut.to_str().unwrap();
    let (code, _, err) = murk(&[
        "synth",
        "--out",
        cut,
        "--kind",
        "confocal",
        "--wall-size",
        "0.8",
        "--grid",
        "8",
        "--bins",
        "128",
        "--bin-width",
        "0.0096",
        "--target",
        "t:0.6",
    ]);
    assert_eq!(code, 0, "{err}");
    fails(
        &["reconstruct", cut, "--out", out],
        &[
            "cut.h5",
            "the window-end handling cleared every voxel",
            "window-end keep",
        ],
    );
    let (code, _, err) = murk(&["reconstruct", cut, "--out", out, "--window-end", "keep"]);
    assert_eq!(code, 0, "{err}");
    std::fs::remove_file(out).unwrap();
    no_leftovers(&d, &["good.h5", "conf.h5", "cut.h5"]);
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn help_teaches_and_demo_runs() {
    for command in [
        "demo",
        "info",
        "synth",
        "reconstruct",
        "render",
        "import",
        "figure",
        "experiment",
        "merge",
    ] {
        let (code, out, _) = murk(&[command, "--help"]);
        assert_eq!(code, 0);
        assert!(
            out.contains("Examples:\n  murk ") || out.contains("Example:\n  murk "),
            "{command} --help has no examples:\n{out}"
        );
    }
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
        "front-axes.png",
        "top-axes.png",
        "side-axes.png",
    ] {
        assert!(d.join(f).exists(), "{f} missing");
    }
    // The page names murk's version once, in its provenance.
    let page = std::fs::read_to_string(d.join("index.html")).unwrap();
    // The study report's look: its page style, the provenance first, the projections as figure
    // grids with named metre axes, the parameters after them.
    let at = |s: &str| {
        page.find(s)
            .unwrap_or_else(|| panic!("{s} not in the page:\n{page}"))
    };
    assert!(page.contains(murk_view::PAGE_STYLE) && page.contains("#controls{position:sticky"));
    assert!(
        at("id=\"provenance\"") < at("front-axes.png")
            && at("side-axes.png") < at("id=\"parameters\"")
    );
    let axes = std::fs::read(d.join("front-axes.png")).unwrap();
    let front = std::fs::read(d.join("front.png")).unwrap();
    assert!(
        axes.windows(11).any(|w| w == b"murk:layout")
            && !front.windows(11).any(|w| w == b"murk:layout")
    );
    assert_eq!(
        page.matches("murk version").count() + page.matches("murk_version").count(),
        1,
        "{page}"
    );
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

/// Magnitudes no capture can have (a time offset of 1e20 m, a wall 1e18 m wide, a SPAD 2e15 m behind
/// the wall, bins of 1e-30 m) used to panic in the spectrum, hang in the FFT-length search or overflow
/// a size: now every method refuses them with one line naming the file and the value.
#[test]
fn absurd_magnitudes_in_a_capture() {
    let d = dir("absurd");
    let src = synth_capture(&d, "src.h5", &["--start", "0.0456", "--point", "0.0789,0"]);
    let out = d.join("v.npy");
    let cases: [(&str, f32, f32, &str); 5] = [
        ("start20.h5", 0.0456, 1e20, "1e20 m"),
        ("start12.h5", 0.0456, 1e12, "1e12 m"),
        ("bin.h5", 0.0123, 1e-30, "1e-30 m"),
        ("binwide.h5", 0.0123, 1e30, "window's end"),
        ("spad.h5", 0.0789, -2e15, "2e15 m"),
    ];
    let mut keep = vec!["src.h5".to_string()];
    for (name, from, to, needle) in cases {
        let p = d.join(name);
        patch(&src, &p, &from.to_le_bytes(), &to.to_le_bytes());
        for method in ["pf", "pf-exact", "bp", "fbp"] {
            let args = [
                "reconstruct",
                p.to_str().unwrap(),
                "--method",
                method,
                "--out",
                out.to_str().unwrap(),
            ];
            fails(&args, &[name, needle]);
        }
        keep.push(name.to_string());
    }
    // Finite values so large that the reconstruction's sums overflow f32: refused, not a volume of
    // inf and NaN.
    let npy = d.join("huge.npy");
    let (nt, n) = (128, 8);
    let mut h = vec![0f32; nt * n * n];
    for (i, v) in h.iter_mut().enumerate() {
        *v = if i / (n * n) == 60 { 1e36 } else { 0.0 };
    }
    murk_io::write_npy_f32(&npy, &[nt, n, n], &h).unwrap();
    let huge = d.join("huge.h5");
    let (code, _, err) = murk(&[
        "import",
        npy.to_str().unwrap(),
        "--axes",
        "t,x,y",
        "--bin-width-ps",
        "32",
        "--wall-size",
        "0.8",
        "--confocal",
        "--out",
        huge.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    // CDT's √ of the deconvolved transient clamped the overflow's NaN to 0 ("all zeros").
    for method in ["pf", "cdt"] {
        fails(
            &[
                "reconstruct",
                huge.to_str().unwrap(),
                "--method",
                method,
                "--out",
                out.to_str().unwrap(),
            ],
            &["huge.h5", "overflows 32-bit floats"],
        );
    }
    keep.extend(["huge.npy".to_string(), "huge.h5".to_string()]);
    let keep: Vec<&str> = keep.iter().map(|s| s.as_str()).collect();
    no_leftovers(&d, &keep);
    std::fs::remove_dir_all(&d).ok();
}

/// Sizes beyond memory are refused before allocating (they aborted with SIGABRT), and absurd volume
/// bounds fail with one line.
#[test]
fn sizes_beyond_memory() {
    let d = dir("sizes");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/z-letter.toml");
    let out = d.join("r.h5");
    let out = out.to_str().unwrap();
    fails(
        &[
            "render", scene, "--out", out, "--grid", "100000", "--spp", "1",
        ],
        &["z-letter.toml", "capture.grid", "would take"],
    );
    fails(
        &[
            "render",
            scene,
            "--out",
            out,
            "--bins",
            "1000000000",
            "--spp",
            "1",
        ],
        &["z-letter.toml", "capture.bins", "would take"],
    );
    let good = good_capture(&d);
    let g = good.to_str().unwrap();
    let v = d.join("v.npy");
    let v = v.to_str().unwrap();
    fails(
        &[
            "reconstruct",
            g,
            "--out",
            v,
            "--volume",
            "0:1:100000,0:1:100000,0.5:1:100000",
        ],
        &["volume", "would take"],
    );
    fails(
        &[
            "reconstruct",
            g,
            "--out",
            v,
            "--volume",
            "0:1:4,0:1:4,0.5:1e30:4",
        ],
        &["z end", "1e30 m"],
    );
    // Under an address-space limit (as a cluster's worker may run), the budget is that limit, not the
    // machine's memory: a 4 GiB H (8 GiB with the written copy) is refused instead of aborting.
    for args in [
        vec![
            "synth",
            "--out",
            out,
            "--target",
            "z:1",
            "--grid",
            "128",
            "--bins",
            "65536",
            "--bin-width",
            "0.001",
        ],
        vec![
            "render", scene, "--out", out, "--grid", "128", "--bins", "65536", "--spp", "1",
        ],
    ] {
        let run = Command::new("sh")
            .arg("-c")
            .arg("ulimit -v 3000000 && exec \"$@\"")
            .arg("sh")
            .arg(env!("CARGO_BIN_EXE_murk"))
            .args(&args)
            .arg("--quiet")
            .output()
            .expect("run sh");
        let err = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.trim_end().lines().count() == 1
                && err.contains("H (and the copy a file write makes) of 16384 × 65536 values would take 8.0 GiB")
                && err.contains("this process may use"),
            "{args:?}: {err}"
        );
    }
    no_leftovers(&d, &["good.h5"]);
    std::fs::remove_dir_all(&d).ok();
}

/// An output that names an input is refused and the input keeps its bytes.
#[test]
fn outputs_never_replace_inputs() {
    let d = dir("same");
    let good = good_capture(&d);
    let g = good.to_str().unwrap();
    let before = std::fs::read(&good).unwrap();
    fails(
        &["reconstruct", g, "--out", g],
        &["good.h5", "replace the input"],
    );
    // The same file through another spelling of its path.
    let other = format!(
        "{}/../{}/good.h5",
        d.display(),
        d.file_name().unwrap().to_str().unwrap()
    );
    fails(&["reconstruct", g, "--out", &other], &["replace the input"]);
    fails(&["merge", g, "--out", g], &["replace the input"]);
    assert_eq!(std::fs::read(&good).unwrap(), before);
    // --png naming a file is refused before anything is reconstructed or written.
    let note = d.join("note.txt");
    std::fs::write(&note, "keep").unwrap();
    let v = d.join("v.npy");
    fails(
        &[
            "reconstruct",
            g,
            "--out",
            v.to_str().unwrap(),
            "--png",
            note.to_str().unwrap(),
        ],
        &["note.txt", "the pictures need a folder"],
    );
    // A capture inside the pictures' folder under a picture's name, and a volume named like the
    // pictures' folder, are refused before anything is written.
    let pics = d.join("pics");
    std::fs::create_dir_all(&pics).unwrap();
    let inside = pics.join("front.png");
    std::fs::copy(&good, &inside).unwrap();
    let p = pics.to_str().unwrap();
    fails(
        &[
            "reconstruct",
            inside.to_str().unwrap(),
            "--out",
            v.to_str().unwrap(),
            "--png",
            p,
        ],
        &["front.png", "replace the input"],
    );
    assert_eq!(std::fs::read(&inside).unwrap(), before);
    let clash = d.join("v.h5");
    let c = clash.to_str().unwrap();
    fails(
        &["reconstruct", g, "--out", c, "--png", c],
        &["v.h5", "is the output"],
    );
    std::fs::remove_dir_all(&pics).unwrap();
    // A pictures' folder that cannot be made is refused before the volume is written (it was
    // written, then the pictures failed).
    let under_note = d.join("note.txt/pics");
    for (png, why) in [
        (under_note.to_str().unwrap(), "note.txt is not a folder"),
        ("/proc/murk-pics", "cannot be made in /proc"),
    ] {
        fails(
            &["reconstruct", g, "--out", v.to_str().unwrap(), "--png", png],
            &[why],
        );
    }
    fails(
        &[
            "synth",
            "--target",
            "z:1",
            "--out",
            d.join("note.txt/x.h5").to_str().unwrap(),
        ],
        &["note.txt is not a folder"],
    );
    // A mesh the scene reads is an input too: --out and --truth over it were written with rc 0.
    let mesh = d.join("mesh.h5");
    std::fs::write(&mesh, "v 0 0 1\nv 0.3 0 1\nv 0 0.3 1\nf 1 2 3\n").unwrap();
    let scene = d.join("mesh.toml");
    let text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/z-letter.toml"))
            .unwrap()
            .replace(
                "shape = \"z-letter\"\ncenter = [0.0, 0.0, 2.0]",
                "shape = \"mesh\"\nfile = \"mesh.h5\"",
            );
    std::fs::write(&scene, &text).unwrap();
    let m = mesh.to_str().unwrap();
    let tiny = |extra: &[&str], needles: &[&str]| {
        let mut args = vec![
            "render",
            scene.to_str().unwrap(),
            "--grid",
            "2",
            "--spp",
            "1",
        ];
        args.extend_from_slice(extra);
        fails(&args, needles);
    };
    for flag in ["--out", "--truth"] {
        let mut args = vec![];
        if flag == "--truth" {
            args.extend(["--out", c]);
        }
        args.extend([flag, m]);
        tiny(&args, &["mesh.h5", "replace the input"]);
    }
    // Nor may the render's checkpoint (OUT.ckpt, removed before a fresh render) be a mesh.
    let ck_mesh = d.join("r.h5.ckpt");
    std::fs::copy(&mesh, &ck_mesh).unwrap();
    std::fs::write(&scene, text.replace("mesh.h5", "r.h5.ckpt")).unwrap();
    let r = d.join("r.h5");
    tiny(
        &["--out", r.to_str().unwrap()],
        &["r.h5.ckpt: is the render's checkpoint for --out"],
    );
    assert!(std::fs::read_to_string(&ck_mesh)
        .unwrap()
        .starts_with("v 0 0 1"));
    std::fs::remove_file(&ck_mesh).unwrap();
    assert!(std::fs::read_to_string(&mesh)
        .unwrap()
        .starts_with("v 0 0 1"));
    std::fs::remove_file(&mesh).unwrap();
    std::fs::remove_file(&scene).unwrap();
    no_leftovers(&d, &["good.h5", "note.txt"]);
    std::fs::remove_dir_all(&d).ok();
}

/// Output paths that cannot be written, or that name the capture twice, are refused before a render
/// starts, and so is a checkpoint interval no `Duration` can hold.
#[test]
fn render_refuses_bad_outputs_up_front() {
    let d = dir("outs");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/z-letter.toml");
    let at = |name: &str| d.join(name).to_str().unwrap().to_string();
    let render = |extra: &[&str]| {
        let mut args = vec!["render", scene, "--grid", "8", "--spp", "1"];
        args.extend_from_slice(extra);
        args.iter().map(|s| s.to_string()).collect::<Vec<_>>()
    };
    let run = |extra: &[&str], needles: &[&str]| {
        let args = render(extra);
        fails(
            &args.iter().map(String::as_str).collect::<Vec<_>>(),
            needles,
        );
    };
    run(&["--out", d.to_str().unwrap()], &["is a folder"]);
    // The checkpoint (OUT.ckpt) is not the scene, which the render would remove.
    let scene_copy = at("r.h5.ckpt");
    std::fs::copy(scene, &scene_copy).unwrap();
    fails(
        &["render", &scene_copy, "--grid", "8", "--out", &at("r.h5")],
        &["r.h5.ckpt", "checkpoint"],
    );
    assert!(std::fs::metadata(&scene_copy).is_ok());
    std::fs::remove_file(&scene_copy).unwrap();
    // A checkpoint that is a FIFO (would block) is refused before it is opened.
    let fifo = at("f.h5.ckpt");
    assert!(std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    run(
        &["--out", &at("f.h5"), "--resume"],
        &["f.h5.ckpt", "not a regular file"],
    );
    std::fs::remove_file(&fifo).unwrap();
    // Captures and truths are HDF5 whatever the name, so another extension is refused.
    run(&["--out", &at("q.mat")], &["q.mat", ".h5 or .hdf5"]);
    run(
        &["--out", &at("q.h5"), "--truth", &at("t.npy")],
        &["t.npy", ".h5 or .hdf5"],
    );
    fails(
        &["synth", "--out", &at("s.npy"), "--target", "z:1"],
        &["s.npy", ".h5 or .hdf5"],
    );
    run(&["--out", &at("no/such/q.h5")], &["does not exist"]);
    let spelled = format!(
        "{}/../{}/q.h5",
        d.display(),
        d.file_name().unwrap().to_str().unwrap()
    );
    run(
        &["--out", &at("q.h5"), "--truth", &spelled],
        &["the same file"],
    );
    for every in ["inf", "1e300", "NaN"] {
        run(
            &["--out", &at("q.h5"), "--checkpoint-every", every],
            &["one year"],
        );
    }
    // Magnitudes that would run for ever or start more threads than the OS holds.
    run(
        &["--out", &at("q.h5"), "--threads", "100000"],
        &["at most 1024"],
    );
    for budget in ["1e300", "0", "inf"] {
        let args = ["render", scene, "--grid", "8", "--out", &at("q.h5")];
        fails(
            &[&args[..], &["--time-budget", budget]].concat(),
            &["one year"],
        );
    }
    // --spp beyond 2^40, and a time budget with --resume (each run would pick another spp).
    let q = at("q.h5");
    let base = ["render", scene, "--grid", "8", "--out", q.as_str()];
    fails(
        &[&base[..], &["--spp", "2000000000000"]].concat(),
        &["--spp", "2000000000000"],
    );
    fails(
        &[&base[..], &["--time-budget", "5", "--resume"]].concat(),
        &["--time-budget", "--resume"],
    );
    no_leftovers(&d, &[]);
    std::fs::remove_dir_all(&d).ok();
}

/// clap's whole message, on one line: which argument is missing, which values are valid.
#[test]
fn usage_errors_say_what_is_wrong() {
    // Without arguments clap's text is the help, whose first line is no error.
    let (code, _, err) = cli::murk(&[]);
    assert_eq!(
        (code, err.trim()),
        (2, "murk: error: no command given (see murk --help)")
    );
    // A newline in a path stays inside the one line.
    fails(&["info", "/nonexistent/a\nb.h5"], &["a\\nb.h5"]);
    // So does one in a value that clap itself refuses.
    fails(
        &["reconstruct", "x.h5", "--method", "a\nb"],
        &["invalid value 'a\\nb' for '--method"],
    );
    let never = std::env::temp_dir().join(format!("murk-usage-{}.h5", std::process::id()));
    for flag in ["--grid", "--bins"] {
        fails(
            &[
                "render",
                concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/z-letter.toml"),
                "--out",
                never.to_str().unwrap(),
                flag,
                "18446744073709551615",
            ],
            &[&format!("{flag} 18446744073709551615: too large")],
        );
    }
    fails(
        &["reconstruct"],
        &[
            "required arguments were not provided",
            "--out <OUT>",
            "<FILE>",
        ],
    );
    fails(
        &["reconstruct", "x.h5", "--out", "v.npy", "--method", "foo"],
        &["'foo'", "possible values", "pf-exact", "cdt"],
    );
    for runs in ["0", "1001", "18446744073709551615"] {
        fails(
            &[
                "figure", "real", "--data", "d", "--out", "f", "--runs", runs,
            ],
            &["--runs", runs],
        );
    }
    // The figure's folder may not be the folder of captures it reads (it wrote grid.png there).
    let data = std::env::temp_dir().join(format!("murk-cli-figdata-{}", std::process::id()));
    std::fs::create_dir_all(&data).unwrap();
    let d = data.to_str().unwrap();
    fails(
        &[
            "figure",
            "real",
            "--data",
            d,
            "--out",
            &format!("{d}/."),
            "--runs",
            "1",
        ],
        &["is the --data folder"],
    );
    assert_eq!(std::fs::read_dir(&data).unwrap().count(), 0);
    std::fs::remove_dir_all(&data).unwrap();
    // A memory budget that is set but meaningless (or not UTF-8) is refused, not silently replaced
    // by the machine's.
    use std::os::unix::ffi::OsStrExt;
    for (value, shown) in [
        (std::ffi::OsStr::new("abc"), "'abc'"),
        (std::ffi::OsStr::from_bytes(b"1\xff"), "'1\u{fffd}'"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_murk"))
            .env("MURK_MAX_BYTES", value)
            .args(["info", "x.h5"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains(&format!("MURK_MAX_BYTES is {shown}")), "{err}");
    }
}

/// `murk info x.h5 | head -1`: the closed pipe ends murk quietly, without a panic message.
#[test]
fn closed_stdout_ends_quietly() {
    use std::io::Read;
    use std::process::Stdio;
    let d = dir("pipe");
    let good = good_capture(&d);
    let mut child = Command::new(env!("CARGO_BIN_EXE_murk"))
        .args(["info", good.to_str().unwrap()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Close the read end before murk writes.
    drop(child.stdout.take());
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    child.wait().unwrap();
    assert!(err.is_empty(), "stderr: {err}");
    std::fs::remove_dir_all(&d).ok();
}

/// SIGTERM in the middle of writing leaves no temporary behind; the checkpoint stays and the resumed
/// render equals an uninterrupted one byte for byte.
#[test]
fn terminated_render_leaves_no_temporaries_and_resumes() {
    let d = dir("sigterm");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/z-letter.toml");
    let out = d.join("r.h5");
    let args = |extra: &[&str]| {
        // One unit per laser point, so the checkpoint fills as the render goes.
        let mut v: Vec<String> = [
            "render",
            scene,
            "--grid",
            "8",
            "--spp",
            "10000",
            "--set",
            "render.share_tile=1",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        v.extend(extra.iter().map(|s| s.to_string()));
        v
    };
    let child = Command::new(env!("CARGO_BIN_EXE_murk"))
        .args(args(&[
            "--out",
            out.to_str().unwrap(),
            "--checkpoint-every",
            "0.01",
        ]))
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let ckpt = d.join("r.h5.ckpt");
    let t0 = std::time::Instant::now();
    while std::fs::metadata(&ckpt).map_or(0, |m| m.len()) < 4096 && t0.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    // SAFETY: kill(2) on our own child's pid.
    unsafe {
        libc::kill(child.id() as i32, libc::SIGTERM);
    }
    let ended = child.wait_with_output().unwrap();
    for e in std::fs::read_dir(&d).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!name.ends_with(".tmp"), "left behind: {name}");
    }
    assert_eq!(
        ended.status.code(),
        Some(130),
        "the render ended before SIGTERM"
    );
    let err = String::from_utf8_lossy(&ended.stderr);
    // The signal stops the render after its units in progress, whose checkpoint keeps them all.
    assert!(
        err.contains("murk: stopping after the work units in progress")
            && err.ends_with(&format!(
                "murk: interrupted: {} keeps the finished work units; the same command with --resume goes on from them\n",
                ckpt.display()
            )),
        "{err}"
    );
    {
        assert!(ckpt.exists());
        // Not quiet, so that it says what it reused.
        let (code, _, err) = cli::murk(
            &args(&["--out", out.to_str().unwrap(), "--resume"])
                .iter()
                .map(|s| s.as_str())
                .collect::<Vec<_>>(),
        );
        assert_eq!(code, 0, "{err}");
        // It says how much of the checkpoint it reused: some, not all, of the 64 units.
        let reused: usize = err
            .split("murk: --resume: ")
            .nth(1)
            .and_then(|s| s.split(" of 64 units reused from ").next())
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("no reuse line: {err}"));
        assert!((1..64).contains(&reused), "{err}");
    }
    let whole = d.join("whole.h5");
    let (code, _, err) = murk(
        &args(&["--out", whole.to_str().unwrap()])
            .iter()
            .map(|s| s.as_str())
            .collect::<Vec<_>>(),
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&whole).unwrap());
    // With an interval too long for any periodic save, Ctrl-C still leaves every finished unit in
    // the checkpoint (each holds 4 096 bins of f32). 10× the paths: the render (about 20 s on two
    // cores) is still running when the signal comes.
    let late = d.join("late.h5");
    let mut child = Command::new(env!("CARGO_BIN_EXE_murk"))
        .args(["render", scene, "--grid", "8", "--spp", "100000"])
        .args(["--set", "render.share_tile=1", "--checkpoint-every", "3600"])
        .arg("--out")
        .arg(&late)
        .arg("--quiet")
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_secs(2));
    // SAFETY: kill(2) on our own child's pid.
    unsafe {
        libc::kill(child.id() as i32, libc::SIGINT);
    }
    assert_eq!(child.wait().unwrap().code(), Some(130));
    let kept = std::fs::metadata(d.join("late.h5.ckpt")).unwrap().len();
    assert!(
        kept > 4096 * 4,
        "the checkpoint holds no unit: {kept} bytes"
    );
    std::fs::remove_dir_all(&d).ok();
}
