//! Baselines, import and the real-data figure through the `murk` binary: synthetic confocal points
//! and planes for every method, `.mat` import (orientation, bad files), and checks on the real CDT
//! captures in `../shared/data/real/cdt_lindell2020` (ignored by default; `.ci/run` runs them where
//! the folder exists).

use std::path::{Path, PathBuf};

#[path = "common/cli.rs"]
mod cli;
use cli::murk;

fn ok(args: &[&str]) -> String {
    let (code, out, err) = murk(args);
    assert_eq!(code, 0, "murk {args:?} failed:\n{err}");
    out
}

/// One-line error, exit code 1, no panic.
fn fails(args: &[&str]) -> String {
    let (code, _, err) = murk(args);
    assert_eq!(code, 1, "murk {args:?}: {err}");
    assert!(
        err.starts_with("murk: error: ") && err.trim_end().lines().count() == 1,
        "{err}"
    );
    err
}

fn tmpdir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("murk-cli-baselines-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// (shape, data) of an .npy volume.
fn npy(p: &Path) -> ([usize; 3], Vec<f32>) {
    let (shape, data) = murk_io::read_npy_f32(p).unwrap();
    (shape.try_into().unwrap(), data)
}

fn argmax(shape: [usize; 3], v: &[f32]) -> [usize; 3] {
    let i = (0..v.len()).fold(0, |b, i| if v[i] > v[b] { i } else { b });
    [
        i / (shape[1] * shape[2]),
        i / shape[2] % shape[1],
        i % shape[2],
    ]
}

/// The 32 × 32 confocal wall (pixel centres −0.31 … 0.31 m, step 0.02 m), 512 bins of 4.8 mm.
fn synth(dir: &Path, name: &str, target: &str) -> PathBuf {
    let p = dir.join(name);
    ok(&[
        "synth",
        "-q",
        "--out",
        s(&p),
        "--kind",
        "confocal",
        "--wall-size",
        "0.64",
        "--grid",
        "32",
        "--bins",
        "512",
        "--bin-width",
        "0.0048",
        "--target",
        target,
    ]);
    p
}

/// Per method: extra flags, the depth step of its output (m) and its first depth, and whether it
/// reconstructs the capture as seen through the default foam slab (CDT) rather than free space.
fn methods() -> Vec<(&'static str, Vec<&'static str>, f64, f64, bool)> {
    let vol = "--volume=-0.31:0.31:32,-0.31:0.31:32,0.2:0.6:41";
    vec![
        // λ = 4Δc of path: the confocal default (4Δc of depth) is twice as long, and the depth of a
        // finite plane's peak drifts deeper with the pulse length.
        ("pf", vec![vol, "--wavefactor", "4"], 0.01, 0.2, false),
        ("bp", vec![vol], 0.01, 0.2, false),
        ("fbp", vec![vol], 0.01, 0.2, false),
        // Own grid: depth k·Δs/2 from the wall.
        ("lct", vec![], 0.0024, 0.0, false),
        ("fk", vec![], 0.0024, 0.0, false),
        // CDT resamples 2 m of path to 128 samples.
        ("cdt", vec!["--snr", "1e6"], 1.0 / 128.0, 0.0, true),
    ]
}

/// Reconstructs `cap` (or its through-slab version) with each method; (name, shape, data, z axis).
/// A method's name, volume shape, intensities and depth axis.
type MethodOut = (&'static str, [usize; 3], Vec<f32>, Vec<f64>);

fn each_method(dir: &Path, cap: &Path) -> Vec<MethodOut> {
    let slab = cap.with_extension("slab.h5");
    let free = murk_io::read_capture(cap).unwrap();
    let blurred = murk_baselines::through_slab(&free, &Default::default()).unwrap();
    murk_io::write_capture(&slab, &blurred).unwrap();
    methods()
        .into_iter()
        .map(|(m, flags, dz, z0, through)| {
            let out = dir.join(format!("{m}.npy"));
            let input = if through { &slab } else { cap };
            let mut args = vec![
                "reconstruct",
                "-q",
                s(input),
                "--method",
                m,
                "--out",
                s(&out),
            ];
            args.extend(flags);
            ok(&args);
            let (shape, v) = npy(&out);
            let z = (0..shape[2]).map(|k| z0 + dz * k as f64).collect();
            (m, shape, v, z)
        })
        .collect()
}

#[test]
fn every_method_puts_a_point_at_its_voxel() {
    let dir = tmpdir("point");
    // Grid point (21, 13) is at (0.11, −0.05).
    let cap = synth(&dir, "point.h5", "point:0.11,-0.05,0.4");
    for (m, shape, v, z) in each_method(&dir, &cap) {
        let [ix, iy, iz] = argmax(shape, &v);
        let want = (0..z.len()).fold(0, |b, k| {
            if (z[k] - 0.4).abs() < (z[b] - 0.4).abs() {
                k
            } else {
                b
            }
        });
        assert!(
            ix.abs_diff(21) <= 1 && iy.abs_diff(13) <= 1 && iz.abs_diff(want) <= 1,
            "{m}: peak at {:?}, want (21, 13, {want}) ± 1",
            [ix, iy, iz]
        );
    }
}

#[test]
fn every_method_puts_a_plane_at_its_depth() {
    let dir = tmpdir("plane");
    let cap = synth(
        &dir,
        "plane.h5",
        "polygon:0.35:-0.2,-0.2;0.2,-0.2;0.2,0.2;-0.2,0.2",
    );
    for (m, shape, v, z) in each_method(&dir, &cap) {
        // Median over the central 10 × 10 columns of each column's brightest depth (FBP's filter
        // makes the volume's first depths bright, so a lateral sum would find them instead).
        let mut zs: Vec<f64> = (11..21)
            .flat_map(|ix| (11..21).map(move |iy| ix * shape[1] + iy))
            .map(|col| {
                let c = &v[col * shape[2]..][..shape[2]];
                z[(0..c.len()).fold(0, |b, k| if c[k] > c[b] { k } else { b })]
            })
            .collect();
        zs.sort_by(f64::total_cmp);
        let depth = zs[zs.len() / 2];
        // 1 cm: one PF/BP voxel, about one CDT voxel, four LCT/f-k voxels.
        assert!(
            (depth - 0.35).abs() <= 0.01,
            "{m}: plane at {depth:.4} m, want 0.35"
        );
    }
}

#[test]
fn own_grid_methods_reject_non_confocal_captures() {
    let dir = tmpdir("kind");
    let p = dir.join("lg.h5");
    ok(&[
        "synth",
        "-q",
        "--out",
        s(&p),
        "--grid",
        "8",
        "--bins",
        "256",
        "--target",
        "point:0,0,0.3",
    ]);
    for m in ["lct", "fk", "cdt"] {
        let e = fails(&[
            "reconstruct",
            s(&p),
            "--method",
            m,
            "--out",
            s(&dir.join("x.npy")),
        ]);
        assert!(e.contains("confocal"), "{m}: {e}");
    }
}

/// A MATLAB v5 file (uncompressed) with uint16 or double variables, as MATLAB's `save -v6` writes.
fn write_mat_v5(path: &Path, vars: &[(&str, &[usize], &[f64], bool)]) {
    let arrays: Vec<murk_io::MatArray> = vars
        .iter()
        .map(|&(name, dims, values, uint16)| murk_io::MatArray {
            name,
            dims,
            values,
            class: if uint16 {
                murk_io::MatClass::UInt16
            } else {
                murk_io::MatClass::Double
            },
        })
        .collect();
    murk_io::write_mat_v5(path, &arrays, false).unwrap();
}

/// `murk info`'s "max at illumination I, …, bin B".
fn max_at(info: &str) -> (usize, usize) {
    let line = info.lines().find(|l| l.starts_with("H: ")).unwrap();
    let num = |key: &str| -> usize {
        line.split(key)
            .nth(1)
            .unwrap()
            .split([',', ' '])
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    (num("illumination "), num("bin "))
}

#[test]
fn lct_import_follows_the_reference_front_view() {
    let dir = tmpdir("lct");
    let (n, t) = (4usize, 700usize);
    // One count at row i = 0, column j = 1, bin 650 (after the 600 gated bins), column-major.
    let mut v = vec![0f64; n * n * t];
    v[650 * n * n + n] = 7.0;
    v[10 * n * n] = 9.0; // direct light, gated away
    let mat = dir.join("scan.mat");
    write_mat_v5(
        &mat,
        &[
            ("rect_data", &[n, n, t], &v, true),
            ("width", &[1, 1], &[0.4], false),
        ],
    );
    let cap = dir.join("scan.h5");
    ok(&["import", "-q", s(&mat), "--format", "lct", "--out", s(&cap)]);
    let info = ok(&["info", s(&cap)]);
    // O'Toole's front view shows j as the row (top → bottom) and i reversed as the column, so
    // (i, j) = (0, 1) is row 1 (second from the top: y index n − 2) and the rightmost column
    // (x index 0, murk's front view having +x on the left): grid point (0, 2).
    assert_eq!(max_at(&info), (2, 650), "{info}");
    assert!(
        info.contains("x -0.400..+0.400") && info.contains("bins of 0.001200 m"),
        "{info}"
    );
    assert!(info.contains("scene_info.scan_side_m: 0.8"), "{info}");

    // Bad files: wrong shape, wrong variable, truncated, the other MATLAB version.
    write_mat_v5(
        &mat,
        &[
            ("rect_data", &[n, n], &v[..n * n], true),
            ("width", &[1, 1], &[0.4], false),
        ],
    );
    let e = fails(&["import", s(&mat), "--format", "lct", "--out", s(&cap)]);
    assert!(e.contains("N × N × T"), "{e}");
    write_mat_v5(&mat, &[("data", &[n, n, t], &v, true)]);
    let e = fails(&["import", s(&mat), "--format", "lct", "--out", s(&cap)]);
    assert!(
        e.contains("no variable 'rect_data'") && e.contains("data"),
        "{e}"
    );
    let bytes = std::fs::read(&mat).unwrap();
    std::fs::write(&mat, &bytes[..bytes.len() / 2]).unwrap();
    let e = fails(&["import", s(&mat), "--format", "lct", "--out", s(&cap)]);
    assert!(e.contains("truncated"), "{e}");
    std::fs::write(&mat, &bytes).unwrap();
    let e = fails(&["import", s(&mat), "--format", "cdt", "--out", s(&cap)]);
    assert!(e.contains("MATLAB v5") && e.contains("--format lct"), "{e}");
    // An HDF5 file without `meas` (a murk capture), as cdt.
    let e = fails(&[
        "import",
        s(&cap),
        "--format",
        "cdt",
        "--wall-size",
        "1",
        "--out",
        s(&dir.join("y.h5")),
    ]);
    assert!(e.contains("no variable 'meas'"), "{e}");
}

// ---- real data -------------------------------------------------------------------------------

/// The real captures; the tests that read them are ignored by default, so a missing folder fails.
fn real_data() -> PathBuf {
    let d = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/real/cdt_lindell2020");
    assert!(
        d.join("letters_ut.mat").exists(),
        "no real CDT captures at {}",
        d.display()
    );
    d
}

/// Imports scene `name` and reconstructs it with CDT (its own grid: 32² × 128 depths of 7.8 mm)
/// and PF (the confocal default λ = 4Δc of depth, 8 cycles, from the back of the slab, depths 0.1–1 m
/// in 1 cm steps).
fn real(dir: &Path, data: &Path, name: &str) -> [([usize; 3], Vec<f32>, Vec<f64>); 2] {
    let mat = data.join(format!("{name}.mat"));
    let cap = dir.join(format!("{name}.h5"));
    ok(&["import", "-q", s(&mat), "--format", "cdt", "--out", s(&cap)]);
    let (c, p) = (
        dir.join(format!("{name}.cdt.npy")),
        dir.join(format!("{name}.pf.npy")),
    );
    ok(&[
        "reconstruct",
        "-q",
        s(&cap),
        "--method",
        "cdt",
        "--out",
        s(&c),
    ]);
    ok(&[
        "reconstruct",
        "-q",
        s(&cap),
        "--method",
        "pf",
        "--cycles",
        "8",
        "--t-offset",
        "slab",
        "--volume=-0.35:0.35:32,-0.35:0.35:32,0.1:1:91",
        "--out",
        s(&p),
    ]);
    let (cs, cv) = npy(&c);
    let (ps, pv) = npy(&p);
    let cz = (0..cs[2]).map(|k| k as f64 / 128.0).collect();
    let pz = (0..ps[2]).map(|k| 0.1 + 0.01 * k as f64).collect();
    [(cs, cv, cz), (ps, pv, pz)]
}

/// Maximum along depth, [ix][iy].
fn mip(shape: [usize; 3], v: &[f32]) -> Vec<f32> {
    v.chunks(shape[2])
        .map(|c| c.iter().copied().fold(f32::MIN, f32::max))
        .collect()
}

/// Depth of the largest total over the columns (ix, iy) where `mask` holds.
fn region_depth(
    shape: [usize; 3],
    v: &[f32],
    z: &[f64],
    mask: impl Fn(usize, usize) -> bool,
) -> f64 {
    let mut prof = vec![0f64; shape[2]];
    for (col, c) in v.chunks(shape[2]).enumerate() {
        if mask(col / shape[1], col % shape[1]) {
            prof.iter_mut().zip(c).for_each(|(p, &x)| *p += x as f64);
        }
    }
    z[(0..prof.len()).fold(0, |b, k| if prof[k] > prof[b] { k } else { b })]
}

/// Sum of a 32 × 32 MIP over ix ∈ `xs`, iy ∈ `ys`.
fn sum_box(m: &[f32], xs: std::ops::Range<usize>, ys: std::ops::Range<usize>) -> f32 {
    xs.map(|ix| ys.clone().map(|iy| m[ix * 32 + iy]).sum::<f32>())
        .sum()
}

/// Median per-column argmax depth over columns whose MIP exceeds half its maximum.
fn median_depth(shape: [usize; 3], v: &[f32], z: &[f64]) -> f64 {
    let m = mip(shape, v);
    let max = m.iter().copied().fold(f32::MIN, f32::max);
    let mut zs: Vec<f64> = v
        .chunks(shape[2])
        .zip(&m)
        .filter(|(_, &mx)| mx > 0.5 * max)
        .map(|(c, &mx)| z[c.iter().position(|&x| x == mx).unwrap()])
        .collect();
    zs.sort_by(f64::total_cmp);
    zs[zs.len() / 2]
}

#[test]
#[ignore = "reads the real capture ../shared/data/real/cdt_lindell2020 (slow); .ci/run runs these with --ignored when that folder is there"]
fn real_letters_ut_two_depths_letter_s_agrees_and_reads_upright() {
    let data = real_data();
    let dir = tmpdir("real");

    // U+T: in the front view (+x on the left) the U is on the left (ix ≥ 16), the T on the right.
    // CDT puts the T about 11 cm behind the U; PF, without deconvolving the slab, only ~2 cm.
    let [cdt, pf] = real(&dir, &data, "letters_ut");
    let mut gaps = Vec::new();
    for (label, (shape, v, z), min_gap) in [("cdt", &cdt, 0.05), ("pf", &pf, 0.01)] {
        let u = region_depth(*shape, v, z, |ix, _| ix >= 16);
        let t = region_depth(*shape, v, z, |ix, _| ix < 16);
        assert!(t - u >= min_gap, "{label}: U at {u:.3} m, T at {t:.3} m");
        gaps.push(t - u);
    }
    println!(
        "letters_ut: T behind U by {:.3} m (CDT), {:.3} m (PF)",
        gaps[0], gaps[1]
    );

    // Letter S: CDT and PF depths within 3 cm; upright, not mirrored: the S's strokes are upper-left
    // and lower-right in the front view (image upper-left = high ix, high iy).
    let [cdt, pf] = real(&dir, &data, "letter_s");
    let (zc, zp) = (
        median_depth(cdt.0, &cdt.1, &cdt.2),
        median_depth(pf.0, &pf.1, &pf.2),
    );
    assert!(
        (zc - zp).abs() <= 0.03,
        "letter S: CDT {zc:.3} m, PF {zp:.3} m"
    );
    let m = mip(cdt.0, &cdt.1);
    let q = |x, y| sum_box(&m, x, y);
    let upright = q(20..32, 16..32) + q(0..12, 0..16);
    let mirrored = q(0..12, 16..32) + q(20..32, 0..16);
    assert!(
        upright > 1.4 * mirrored,
        "S strokes: {upright} vs mirrored {mirrored}"
    );

    // Letter T: its bar (top rows, high iy) is brighter than the bottom rows, so not upside down.
    let [cdt, _] = real(&dir, &data, "letter_t");
    let m = mip(cdt.0, &cdt.1);
    let band = |y| sum_box(&m, 0..32, y);
    assert!(
        band(24..32) > 1.2 * band(0..8),
        "T: top {} vs bottom {}",
        band(24..32),
        band(0..8)
    );
}

#[test]
#[ignore = "reads the real capture ../shared/data/real/cdt_lindell2020 (slow); .ci/run runs these with --ignored when that folder is there"]
fn real_cdt_bad_inputs_fail_cleanly() {
    let data = real_data();
    let dir = tmpdir("realbad");
    let mat = data.join("letter_s.mat");
    let out = dir.join("x.h5");
    let e = fails(&["import", s(&mat), "--format", "lct", "--out", s(&out)]);
    assert!(e.contains("v7.3") && e.contains("--format cdt"), "{e}");
    let bytes = std::fs::read(&mat).unwrap();
    let cut = dir.join("letter_s.mat");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let e = fails(&["import", s(&cut), "--format", "cdt", "--out", s(&out)]);
    assert!(e.contains("EOF") || e.contains("truncated"), "{e}");
    let other = dir.join("other.mat");
    std::fs::write(&other, &bytes).unwrap();
    let e = fails(&["import", s(&other), "--format", "cdt", "--out", s(&out)]);
    assert!(e.contains("--wall-size"), "{e}");
    ok(&[
        "import",
        "-q",
        s(&other),
        "--format",
        "cdt",
        "--wall-size",
        "0.6",
        "--out",
        s(&out),
    ]);
}

#[test]
#[ignore = "reads the real capture ../shared/data/real/cdt_lindell2020 (slow); .ci/run runs these with --ignored when that folder is there"]
fn figure_real_writes_the_grid_and_page() {
    let data = real_data();
    let out = tmpdir("figure");
    let stdout = ok(&[
        "figure",
        "real",
        "--data",
        s(&data),
        "--out",
        s(&out),
        "--runs",
        "1",
    ]);
    assert_eq!(
        stdout.lines().filter(|l| l.contains("peak depth")).count(),
        15,
        "{stdout}"
    );
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(
        html.contains("letters_ut PF") && html.contains("grid.png"),
        "{html}"
    );
    let png = std::fs::read(out.join("grid.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
}

/// LCT's weighting: t⁴ (diffuse, the default) or t² (retroreflective). A point seen by both keeps its
/// place; the weights differ by t², so the volumes differ, and the summary names the choice.
#[test]
fn lct_weighting_is_a_choice() {
    let dir = tmpdir("weighting");
    let cap = dir.join("p.h5");
    ok(&[
        "synth",
        "-q",
        "--out",
        s(&cap),
        "--kind",
        "confocal",
        "--grid",
        "16",
        "--bins",
        "512",
        "--bin-width",
        "0.005",
        "--target",
        "point:0.05,-0.1,0.6",
    ]);
    let run = |w: &str| {
        let out = dir.join(format!("{w}.npy"));
        let summary = ok(&[
            "reconstruct",
            s(&cap),
            "--method",
            "lct",
            "--weighting",
            w,
            "--out",
            s(&out),
        ]);
        let (shape, v) = npy(&out);
        (summary, argmax(shape, &v), v)
    };
    let (sd, pd, vd) = run("diffuse");
    let (sr, pr, vr) = run("retroreflective");
    assert!(sd.contains("reflectance: diffuse") && sr.contains("reflectance: retroreflective"));
    assert_eq!(pd, pr);
    let top = |v: &[f32]| v.iter().cloned().fold(f32::MIN, f32::max);
    let (nd, nr) = (top(&vd), top(&vr));
    assert!(vd
        .iter()
        .zip(&vr)
        .any(|(a, b)| (a / nd - b / nr).abs() > 1e-3));
    std::fs::remove_dir_all(&dir).ok();
}
