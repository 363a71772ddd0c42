//! Each preset on a small synthetic file in its published layout: one bright scan point at a known
//! (x, y) and path 2z must come back at that wall position (upright, not mirrored) and depth.
//! The files are written from the datasets' documented conventions, not from murk's mapping.

use super::*;
use crate::mat5::write::{counts, doubles, file, structure};
use crate::testutil::tmpdir;
use hdf5_pure::FileBuilder;

/// The bright point: left of centre (+x) and above it (+y) in murk's front view, z behind the wall.
const X0: f64 = 0.21;
const Y0: f64 = 0.12;

/// Values of an array of MATLAB shape `dims` in column-major order, element (i0, i1, …) = f(&[i…]).
fn col_major(dims: &[usize], f: impl Fn(&[usize]) -> f64) -> Vec<f64> {
    let n: usize = dims.iter().product();
    let mut idx = vec![0usize; dims.len()];
    (0..n)
        .map(|k| {
            let mut rest = k;
            for (i, &d) in idx.iter_mut().zip(dims) {
                *i = rest % d;
                rest /= d;
            }
            f(&idx)
        })
        .collect()
}

/// The index of the scan point nearest `v` among `n` points over [−side/2, side/2], counted from
/// the low end (`up`) or the high end.
fn nearest(v: f64, n: usize, side: f64, up: bool) -> usize {
    let step = side / (n - 1) as f64;
    let from_low = ((v + side / 2.0) / step).round() as usize;
    if up {
        from_low
    } else {
        n - 1 - from_low
    }
}

fn write_v5(path: &Path, vars: &[Vec<u8>]) {
    std::fs::write(path, file(vars, true)).unwrap();
}

/// A MATLAB v7.3 file: HDF5 behind MATLAB's 512-byte header, each array stored with its
/// dimensions reversed (what h5py shows), i.e. its column-major values in HDF5's C order.
fn write_v73(path: &Path, vars: &[(&str, &[usize], &[f64])]) {
    let mut fb = FileBuilder::new();
    fb.with_userblock(512);
    fb.with_userblock_content(b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created by murk's tests");
    for (name, dims, v) in vars {
        let h5_shape: Vec<u64> = dims.iter().rev().map(|&d| d as u64).collect();
        fb.create_dataset(name)
            .with_shape(&h5_shape)
            .with_f64_data(v);
    }
    fb.write(path).unwrap();
}

/// Checks that the brightest sample of `cap` lies at the scan point nearest (X0, Y0), on a grid
/// running along +x and +y, at path 2z (plus the legs to and from the devices, if timed).
fn assert_point(cap: &Capture, z: f64, what: &str) {
    let g = cap.sensor.regular_grid().expect("a regular grid");
    assert!(
        g.step_x.x > 0.0 && g.step_y.y > 0.0,
        "{what}: grid steps {:?} {:?}",
        g.step_x,
        g.step_y
    );
    assert_eq!(cap.kind(), murk_core::CaptureKind::Confocal, "{what}");
    let k = (0..cap.h.len()).fold(0, |b, k| if cap.h[k] > cap.h[b] { k } else { b });
    let (i, bin) = (k / cap.time.bins, k % cap.time.bins);
    let p = cap.sensor.points[i];
    let half = 0.5 * g.step_x.length().max(g.step_y.length()) + 1e-9;
    assert!(
        (p.x - X0).abs() <= half && (p.y - Y0).abs() <= half,
        "{what}: brightest at ({:.3}, {:.3}), want ({X0}, {Y0})",
        p.x,
        p.y
    );
    let w = cap.time.bin_width_m;
    let path = cap.time.start_m + bin as f64 * w;
    let want = 2.0 * z + cap.first_bounce_m(i) + cap.last_bounce_m(i);
    assert!(
        (path - want).abs() <= w,
        "{what}: peak path {path:.4} m, want {want:.4} (bins of {w})"
    );
}

/// The bin of path `path_m` in bins of `bin_m`.
fn bin(path_m: f64, bin_m: f64) -> usize {
    (path_m / bin_m).round() as usize
}

const PS: f64 = REFERENCE_C_M_PER_S * 1e-12;

#[test]
fn cdt_meas_t_a_b() {
    let dir = tmpdir("imp-cdt");
    let (n, nt, side, z) = (8, 256, 0.7, 0.6);
    // meas(t, a, b): row a top → bottom (y falls), column b left → right (x falls).
    let (a0, b0) = (nearest(Y0, n, side, false), nearest(X0, n, side, false));
    let peak = bin(2.0 * z, 16.0 * PS);
    let v = col_major(&[nt, n, n], |i| {
        if (i[1], i[2]) == (a0, b0) && i[0] == peak {
            50.0
        } else {
            (i[0] == 3) as u8 as f64
        }
    });
    let p = dir.join("cones.mat");
    write_v73(&p, &[("meas", &[nt, n, n], &v)]);
    let cap = import(&p, &ImportOptions::preset(Preset::Cdt)).unwrap();
    assert_point(&cap, z, "cdt");
    assert!(cap.scene_info.contains("scan_side_m: 0.7"));
    // The same file read as f-k's (a, b, t) is a 256 × 8 scan of 8 bins: refused as another dataset's.
    let e = import(&p, &ImportOptions::preset(Preset::Fk))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("cones.mat") && e.contains("a 256 × 8 scan of 8 bins, but fk scans are square"),
        "{e}"
    );
    // A scan side that makes every point coincide is refused naming the file.
    let tiny = ImportOptions {
        wall_size_m: Some(1e-300),
        ..ImportOptions::preset(Preset::Cdt)
    };
    let e = import(&p, &tiny).unwrap_err().to_string();
    assert!(
        e.starts_with(&format!("{}: ", p.display())) && e.contains("span 1e-300 m"),
        "{e}"
    );
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn lct_rect_data_i_j_t() {
    let dir = tmpdir("imp-lct");
    let (n, nt, side, z) = (8, 1000, 0.8, 0.5);
    // rect_data(i, j, t) is shown with row j (y falls) and column N − 1 − i (x rises with i).
    let (i0, j0) = (nearest(X0, n, side, true), nearest(Y0, n, side, false));
    let peak = bin(2.0 * z, 4.0 * PS);
    let v = col_major(&[n, n, nt], |i| {
        // Direct light at bin 100 is brighter, but gated (the first 600 bins).
        match ((i[0], i[1]) == (i0, j0), i[2]) {
            (true, t) if t == peak => 50.0,
            (_, 100) => 90.0,
            _ => 0.0,
        }
    });
    let p = dir.join("s_u.mat");
    write_v5(
        &p,
        &[
            counts("rect_data", &[n, n, nt], &v, true),
            doubles("width", &[1, 1], &[side / 2.0]),
        ],
    );
    let cap = import(&p, &ImportOptions::preset(Preset::Lct)).unwrap();
    assert_point(&cap, z, "lct");
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn lct_transient_reshapes_column_major() {
    let dir = tmpdir("imp-lctt");
    let (n, nt, side, z) = (8, 1000, 0.7, 0.45);
    let (i0, j0) = (nearest(X0, n, side, true), nearest(Y0, n, side, false));
    let peak = bin(2.0 * z, 4.0 * PS);
    // transient(k, t) with k = i + N·j (MATLAB's reshape to N × N × T is rect_data(i, j, t)).
    let v = col_major(&[n * n, nt], |i| {
        (i[0] == i0 + n * j0 && i[1] == peak) as u8 as f64 * 200.0
    });
    let step = side / (n - 1) as f64;
    let lighting = col_major(&[n * n, 3], |i| match i[1] {
        0 => -side / 2.0 + (i[0] % n) as f64 * step,
        1 => side / 2.0 - (i[0] / n) as f64 * step,
        _ => 0.0,
    });
    let p = dir.join("mannequin.mat");
    write_v5(
        &p,
        &[
            counts("transient", &[n * n, nt], &v, false),
            doubles("lighting", &[n * n, 3], &lighting),
        ],
    );
    let cap = import(&p, &ImportOptions::preset(Preset::LctTransient)).unwrap();
    assert_point(&cap, z, "lct-transient");
    // The side is `lighting`'s x extent (f32 values in the file's reading).
    let xs = cap.sensor.points.iter().map(|p| p.x);
    let extent = xs.clone().fold(f64::MIN, f64::max) - xs.fold(f64::MAX, f64::min);
    assert!((extent - side).abs() < 1e-6, "{extent}");
    // A point list of another scan (5 points; its extent was taken as the side), or with NaN or
    // a single x, is named with the variable, as is a width that is not a positive length.
    let five = col_major(&[5, 3], |i| i[0] as f64 * 0.1);
    let nan = vec![f64::NAN; n * n * 3];
    let flat = vec![0.0; n * n * 3];
    for (var, shape, values, says) in [
        (
            "lighting",
            [5, 3],
            &five,
            "'lighting' should be the 64 × 3 scan points, got shape [5, 3]",
        ),
        (
            "lighting",
            [n * n, 3],
            &nan,
            "'lighting' holds a coordinate that is NaN",
        ),
        (
            "lighting",
            [n * n, 3],
            &flat,
            "'lighting' (the scan's x extent) must be positive and finite, got 0 m",
        ),
    ] {
        write_v5(
            &p,
            &[
                counts("transient", &[n * n, nt], &v, false),
                doubles(var, &shape, values),
            ],
        );
        let e = import(&p, &ImportOptions::preset(Preset::LctTransient)).unwrap_err();
        assert_eq!(e.to_string(), format!("{}: {says}", p.display()));
    }
    let rect = col_major(&[n, n, nt], |_| 0.0);
    for (width, says) in [
        (
            f64::NAN,
            "'width' (half the scan side) must be positive and finite, got NaN m",
        ),
        (
            1e300,
            "'width' (half the scan side) must be positive and finite, got inf m",
        ),
        (
            -1.0,
            "'width' (half the scan side) must be positive and finite, got -1 m",
        ),
    ] {
        write_v5(
            &p,
            &[
                doubles("rect_data", &[n, n, nt], &rect),
                doubles("width", &[1, 1], &[width]),
            ],
        );
        let e = import(&p, &ImportOptions::preset(Preset::Lct))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with(&format!("{}: {says}", p.display())), "{e}");
    }
    std::fs::remove_dir_all(dir).ok();
}

/// f-k's meas(a, b, t) in v7.3 and v5, and rectified by a tof grid that differs at every pixel.
#[test]
fn fk_meas_a_b_t_and_tof() {
    let dir = tmpdir("imp-fk");
    let (n, nt, side, z) = (8, 256, 2.0, 1.1);
    let (a0, b0) = (
        nearest(Y0 * 4.0, n, side, false),
        nearest(X0 * 4.0, n, side, false),
    );
    let bin_m = 32.0 * PS;
    let tof_ps = |a: usize, b: usize| 32.0 * (a + 2 * b) as f64 + 5.0;
    let write = |p: &Path, delay: bool, v73: bool| {
        let v = col_major(&[n, n, nt], |i| {
            let shift = if delay {
                (tof_ps(i[0], i[1]) / 32.0).floor() as usize
            } else {
                0
            };
            ((i[0], i[1]) == (a0, b0) && i[2] == bin(2.0 * z, bin_m) + shift) as u8 as f64
        });
        if v73 {
            write_v73(p, &[("meas", &[n, n, nt], &v)]);
        } else {
            write_v5(p, &[doubles("meas", &[n, n, nt], &v)]);
        }
    };
    // The scene sits 4× further out on f-k's 2 m wall.
    let scaled = |cap: &mut Capture| {
        for p in cap.sensor.points.iter_mut() {
            *p /= 4.0;
        }
        cap.illum = cap.sensor.clone();
    };
    // The capture's format line and `murk info`'s depth axis.
    let says = |cap: &Capture, format: &str, depth_axis: &str| {
        assert!(cap.scene_info.contains(format), "{}", cap.scene_info);
        let info = crate::describe(cap).join("\n");
        assert!(info.contains(depth_axis), "{info}");
    };
    for v73 in [true, false] {
        let p = dir.join("meas.mat");
        write(&p, false, v73);
        let mut cap = import(&p, &ImportOptions::preset(Preset::Fk)).unwrap();
        // Without tofgrid the capture says its t = 0 is not the wall (nlos-fk's README).
        says(&cap, "not rectified", "depth axis: t = 0 is not the wall");
        scaled(&mut cap);
        assert_point(&cap, z, "fk");
    }
    let p = dir.join("meas_delayed.mat");
    write(&p, true, false);
    let tof = dir.join("tof.mat");
    write_v5(
        &tof,
        &[doubles(
            "tofgrid",
            &[n, n],
            &col_major(&[n, n], |i| tof_ps(i[0], i[1])),
        )],
    );
    let mut o = ImportOptions::preset(Preset::Fk);
    o.tof = Some(tof);
    let mut cap = import(&p, &o).unwrap();
    says(&cap, "rectified by --tof", "comes from depth p/2");
    scaled(&mut cap);
    assert_point(&cap, z, "fk with tof");
    std::fs::remove_dir_all(dir).ok();
}

/// Ahn 2019's struct in the dataset's own frame (`loadNLOSDATA.m`): the wall at z = target_dist,
/// the scene around the origin on the wall's −z side, `times` the round-trip path of each bin
/// (their confocal backprojection reads bin (2|p − l| − times(1)) / delta). Seen from the wall,
/// their +x is murk's −x. The wall points' first index runs along their −x: the points, not the
/// indices, place the scan.
#[test]
fn ahn2019_struct_with_wall_points() {
    let dir = tmpdir("imp-ahn");
    let (nx, ny, nt, side, z, delta, tbin1, target_dist) =
        (8, 6, 300, 0.8, 0.5, 0.0192, 0.0012, 1.08);
    let (sx, sy) = (side / (nx - 1) as f64, side / (ny - 1) as f64);
    let pos = |ix: usize, iy: usize| (side / 2.0 - ix as f64 * sx, -side / 2.0 + iy as f64 * sy);
    // murk's (X0, Y0) is their (−X0, Y0): index ix counts down their x, so up from murk's −X0.
    let (ix0, iy0) = (nearest(-X0, nx, side, false), nearest(Y0, ny, side, true));
    let p = DVec3::new(pos(ix0, iy0).0, pos(ix0, iy0).1, target_dist - z);
    let wall = DVec3::new(p.x, p.y, target_dist);
    let k = ((2.0 * (p - wall).length() - tbin1) / delta).round() as usize;
    let v = col_major(&[nx, ny, nt], |i| {
        ((i[0], i[1]) == (ix0, iy0) && i[2] == k) as u8 as f64
    });
    // Point k = ix·Ny + iy (the second coordinate fastest).
    let pts = col_major(&[nx * ny, 3], |i| {
        let (x, y) = pos(i[0] / ny, i[0] % ny);
        [x, y, target_dist][i[1]]
    });
    let times = col_major(&[1, nt], |i| tbin1 + i[1] as f64 * delta);
    let p = dir.join("ahn.mat");
    write_v5(
        &p,
        &[structure(
            "NLOSDATA",
            &[
                ("transient", doubles("", &[nx, ny, nt], &v)),
                ("l", doubles("", &[nx * ny, 3], &pts)),
                ("s", doubles("", &[nx * ny, 3], &pts)),
                ("times", doubles("", &[1, nt], &times)),
                ("delta", doubles("", &[1, 1], &[delta])),
                ("is_confocal", doubles("", &[1, 1], &[1.0])),
                ("target_dist", doubles("", &[1, 1], &[target_dist])),
            ],
        )],
    );
    let cap = import(&p, &ImportOptions::preset(Preset::Ahn2019)).unwrap();
    assert_eq!(cap.sensor.layout, PointLayout::Grid { nx, ny });
    assert!(cap.sensor.points.iter().all(|q| q.z == 0.0));
    assert_point(&cap, z, "ahn2019");
    let info = crate::describe(&cap).join("\n");
    assert!(
        info.contains("z > +0.000 m (the wall); a return at path p comes from depth p/2, so this window reaches depths 0.001..2.881 m"),
        "{info}"
    );
    std::fs::remove_dir_all(dir).ok();
}

/// Xiao 2024 (float, small negatives) and Wu 2021 (uint8, with its own timeRes and width). Wu's
/// solver plots index b upwards and index a leftwards seen from the wall (sp1400.m permutes
/// sig_in to (b, a, t); draw3D.m plots b on the vertical axis): a runs along +x, b along +y.
#[test]
fn xiao2024_and_wu2021_sig_a_b_t() {
    let dir = tmpdir("imp-xw");
    let (n, nt, z) = (8, 300, 0.7);
    let sig = |side: f64, bin_m: f64, floor: f64, displayed_row_a: bool| {
        let (a0, b0) = if displayed_row_a {
            (nearest(Y0, n, side, false), nearest(X0, n, side, false))
        } else {
            (nearest(X0, n, side, true), nearest(Y0, n, side, true))
        };
        col_major(&[n, n, nt], move |i| {
            if (i[0], i[1]) == (a0, b0) && i[2] == bin(2.0 * z, bin_m) {
                1.0
            } else {
                floor
            }
        })
    };
    let p = dir.join("xiao.mat");
    write_v5(
        &p,
        &[doubles(
            "sig",
            &[n, n, nt],
            &sig(0.82, 32.0 * PS, -0.01, true),
        )],
    );
    let cap = import(&p, &ImportOptions::preset(Preset::Xiao2024)).unwrap();
    assert_point(&cap, z, "xiao2024");

    let (side, time_res_s) = (0.9, 16e-12);
    let v: Vec<f64> = sig(side, time_res_s * REFERENCE_C_M_PER_S, 0.0, false)
        .iter()
        .map(|v| v * 255.0)
        .collect();
    let p = dir.join("wu.mat");
    write_v5(
        &p,
        &[
            counts("sig_in", &[n, n, nt], &v, false),
            doubles("timeRes", &[1, 1], &[time_res_s]),
            doubles("width", &[1, 1], &[side / 2.0]),
            doubles("pulsewidth", &[1, 1], &[50e-12]),
        ],
    );
    let cap = import(&p, &ImportOptions::preset(Preset::Wu2021)).unwrap();
    assert_point(&cap, z, "wu2021");
    assert!((cap.time.bin_width_m - 0.0048).abs() < 1e-9);
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn abp_tof_data_gates_500_bins() {
    let dir = tmpdir("imp-abp");
    let (n, nt, side, z) = (8, 1000, 0.8, 0.6);
    let (a0, b0) = (nearest(Y0, n, side, false), nearest(X0, n, side, false));
    let v = col_major(&[n, n, nt], |i| match i[2] {
        t if (i[0], i[1]) == (a0, b0) && t == bin(2.0 * z, 5.0 * PS) => 10.0,
        20 => 99.0,
        _ => 0.0,
    });
    let p = dir.join("abp.mat");
    write_v73(&p, &[("tof_data", &[n, n, nt], &v)]);
    let cap = import(&p, &ImportOptions::preset(Preset::Abp)).unwrap();
    assert_point(&cap, z, "abp");
    std::fs::remove_dir_all(dir).ok();
}

/// Z-NLOS in both of y-tal's layouts, with a grid whose first index runs along −y and second
/// along +x, two bounce orders and three colours to sum, and times that include the device legs.
#[test]
fn znlos_both_layouts() {
    let dir = tmpdir("imp-znlos");
    let (np, nq, nt, side, z) = (6, 8, 400, 1.0, 0.4);
    let (t0, dt) = (0.5, 0.008);
    let laser = DVec3::new(-0.3, 0.1, 1.2);
    let camera = DVec3::new(0.4, -0.2, 0.9);
    let at = |p: usize, q: usize| {
        DVec3::new(
            -side / 2.0 + q as f64 * side / (nq - 1) as f64,
            side / 2.0 - p as f64 * side / (np - 1) as f64,
            0.0,
        )
    };
    let (p0, q0) = (nearest(Y0, np, side, false), nearest(X0, nq, side, true));
    let w = at(p0, q0);
    let peak = bin(
        (laser - w).length() + 2.0 * z + (w - camera).length() - t0,
        dt,
    );
    // (P, Q, bounces, t, colours) in C order; half the signal in each of two bounce orders.
    let value = |p: usize, q: usize, t: usize| ((p, q, t) == (p0, q0, peak)) as u8 as f64 * 0.5;
    let (nb, nc) = (2, 3);
    for reversed in [false, true] {
        let mut fb = FileBuilder::new();
        let (data, shape, grid, grid_shape): (Vec<f64>, Vec<u64>, Vec<f64>, Vec<u64>) = if reversed
        {
            let mut d = Vec::new();
            for _c in 0..nc {
                for t in 0..nt {
                    for _b in 0..nb {
                        for q in 0..nq {
                            for p in 0..np {
                                d.push(value(p, q, t));
                            }
                        }
                    }
                }
            }
            let mut g = Vec::new();
            for c in 0..3 {
                for q in 0..nq {
                    for p in 0..np {
                        g.push(at(p, q)[c]);
                    }
                }
            }
            let s = [nc, nt, nb, nq, np].map(|v| v as u64).to_vec();
            (d, s, g, vec![3, nq as u64, np as u64])
        } else {
            let mut d = Vec::new();
            for p in 0..np {
                for q in 0..nq {
                    for _b in 0..nb {
                        for t in 0..nt {
                            d.extend([value(p, q, t); 3]);
                        }
                    }
                }
            }
            let g: Vec<f64> = (0..np * nq)
                .flat_map(|i| at(i / nq, i % nq).to_array())
                .collect();
            let s = [np, nq, nb, nt, nc].map(|v| v as u64).to_vec();
            (d, s, g, vec![np as u64, nq as u64, 3])
        };
        fb.create_dataset("data")
            .with_shape(&shape)
            .with_f64_data(&data);
        for name in ["cameraGridPositions", "laserGridPositions"] {
            fb.create_dataset(name)
                .with_shape(&grid_shape)
                .with_f64_data(&grid);
        }
        fb.create_dataset("cameraPosition")
            .with_f64_data(&camera.to_array());
        fb.create_dataset("laserPosition")
            .with_f64_data(&laser.to_array());
        fb.create_dataset("deltaT")
            .with_shape(&[])
            .with_f64_data(&[dt]);
        fb.create_dataset("t0").with_shape(&[]).with_f64_data(&[t0]);
        let p = dir.join("bunny.hdf5");
        fb.write(&p).unwrap();
        let cap = import(&p, &ImportOptions::preset(Preset::Znlos)).unwrap();
        assert_eq!(cap.sensor.layout, PointLayout::Grid { nx: nq, ny: np });
        assert!(cap.t_accounts_first_and_last_bounces);
        assert_point(&cap, z, &format!("znlos (reversed {reversed})"));
        let k = (0..cap.h.len()).fold(0, |b, k| if cap.h[k] > cap.h[b] { k } else { b });
        assert_eq!(cap.h[k], 3.0, "two bounces × three colours of 0.5");
    }
    std::fs::remove_dir_all(dir).ok();
}

/// The generic form over .npy (x, y, t as stored), a v5 struct field (t, y, x with both axes
/// reversed, as CDT's) and a v7.3 array; --t0-bin moves the time origin.
#[test]
fn generic_npy_struct_field_and_v73() {
    let dir = tmpdir("imp-generic");
    let (n, nt, side, z, bin_m) = (8, 200, 0.6, 0.3, 0.005);
    let (ix, iy) = (nearest(X0, n, side, true), nearest(Y0, n, side, true));
    let t0 = 20;
    let hit =
        |x: usize, y: usize, t: usize| ((x, y, t) == (ix, iy, bin(2.0 * z, bin_m) + t0)) as u8;
    let mut o = ImportOptions {
        layout: Layout::Generic(Generic {
            var: String::new(),
            axes: [Dim::X, Dim::Y, Dim::T],
            confocal: true,
        }),
        wall_size_m: Some(side),
        bin_width: Some(BinWidth::M(bin_m)),
        gate_bins: None,
        flip: Flip::default(),
        t0_bin: Some(t0),
        tof: None,
    };
    let npy: Vec<f32> = (0..n * n * nt)
        .map(|k| hit(k / (n * nt), k / nt % n, k % nt) as f32)
        .collect();
    let p = dir.join("scan.npy");
    crate::write_npy_f32(&p, &[n, n, nt], &npy).unwrap();
    assert_point(&import(&p, &o).unwrap(), z, "generic npy");

    // MATLAB (t, a, b) with a = n − 1 − y and b = n − 1 − x, as field `hist` of struct `capture`.
    let v = col_major(&[nt, n, n], |i| {
        hit(n - 1 - i[2], n - 1 - i[1], i[0]) as f64
    });
    let p = dir.join("scan.mat");
    write_v5(
        &p,
        &[structure(
            "capture",
            &[("hist", doubles("", &[nt, n, n], &v))],
        )],
    );
    o.layout = Layout::Generic(Generic {
        var: "capture.hist".into(),
        axes: [Dim::T, Dim::Y, Dim::X],
        confocal: true,
    });
    o.flip = Flip { x: true, y: true };
    assert_point(&import(&p, &o).unwrap(), z, "generic v5 struct field");

    let p = dir.join("scan73.mat");
    write_v73(&p, &[("hist", &[nt, n, n], &v)]);
    o.layout = Layout::Generic(Generic {
        var: "hist".into(),
        axes: [Dim::T, Dim::Y, Dim::X],
        confocal: true,
    });
    assert_point(&import(&p, &o).unwrap(), z, "generic v7.3");
    std::fs::remove_dir_all(dir).ok();
}

/// Bad inputs: one line naming the file and the problem, never a panic.
#[test]
fn bad_inputs_fail_with_one_line() {
    let dir = tmpdir("imp-bad");
    let err = |p: &Path, o: &ImportOptions| {
        let e = import(p, o).unwrap_err().to_string();
        assert!(!e.contains('\n'), "{e}");
        e
    };
    let p = dir.join("x.mat");
    write_v5(&p, &[doubles("sigg", &[2, 2, 4], &[0.0; 16])]);
    let e = err(&p, &ImportOptions::preset(Preset::Xiao2024));
    assert!(
        e.contains("x.mat")
            && e.contains("no variable 'sig'")
            && e.contains("sigg (numeric 2×2×4)"),
        "{e}"
    );
    write_v5(&p, &[doubles("sig", &[4, 4], &[0.0; 16])]);
    let e = err(&p, &ImportOptions::preset(Preset::Xiao2024));
    assert!(
        e.contains("'sig' should be N × N × T") && e.contains("[4, 4]"),
        "{e}"
    );
    let e = err(&p, &ImportOptions::preset(Preset::Abp));
    assert!(e.contains("MATLAB v5") && e.contains("--format lct"), "{e}");
    write_v5(
        &p,
        &[structure(
            "NLOSDATA",
            &[("l", doubles("", &[1, 3], &[0.0; 3]))],
        )],
    );
    let e = err(&p, &ImportOptions::preset(Preset::Ahn2019));
    assert!(e.contains("no variable 'NLOSDATA.transient'"), "{e}");

    // A .npy header declaring 10^15 values over no data: refused before allocating.
    let mut header =
        "{'descr': '<f4', 'fortran_order': False, 'shape': (100000, 100000, 100000), }".to_string();
    header.push_str(&" ".repeat(128 - 10 - header.len() - 1));
    header.push('\n');
    let mut b = b"\x93NUMPY\x01\x00".to_vec();
    b.extend((header.len() as u16).to_le_bytes());
    b.extend(header.as_bytes());
    let huge = dir.join("huge.npy");
    std::fs::write(&huge, &b).unwrap();
    let generic = ImportOptions {
        layout: Layout::Generic(Generic {
            var: String::new(),
            axes: [Dim::T, Dim::X, Dim::Y],
            confocal: true,
        }),
        wall_size_m: Some(1.0),
        bin_width: Some(BinWidth::Ps(10.0)),
        ..ImportOptions::preset(Preset::Cdt)
    };
    let e = err(&huge, &generic);
    assert!(e.contains("huge.npy") && e.contains("read limit"), "{e}");
    // MATLAB v5 dimensions claiming 2^30 × 2^30 × 2 values over 16 bytes.
    write_v5(&p, &[doubles("sig", &[1 << 30, 1 << 30, 2], &[0.0; 2])]);
    let e = err(&p, &ImportOptions::preset(Preset::Xiao2024));
    assert!(e.contains("x.mat"), "{e}");

    let non_confocal = ImportOptions {
        layout: Layout::Generic(Generic {
            var: String::new(),
            axes: [Dim::T, Dim::X, Dim::Y],
            confocal: false,
        }),
        ..generic.clone()
    };
    let e = err(&huge, &non_confocal);
    assert!(e.contains("confocal"), "{e}");

    // A .npy with bytes past its array, --var on a .npy, a bin width that is inf in metres, and a
    // wrong rank, which names "the array" (a .npy's has no name).
    let small = dir.join("small.npy");
    crate::write_npy_f32(&small, &[4, 2, 2], &[0.0; 16]).unwrap();
    let mut bytes = std::fs::read(&small).unwrap();
    bytes.extend_from_slice(b"junk");
    let extra = dir.join("extra.npy");
    std::fs::write(&extra, &bytes).unwrap();
    let e = err(&extra, &generic);
    assert!(
        e.contains("extra.npy: 4 bytes after the array's data"),
        "{e}"
    );
    let named = ImportOptions {
        layout: Layout::Generic(Generic {
            var: "meas".into(),
            axes: [Dim::T, Dim::X, Dim::Y],
            confocal: true,
        }),
        ..generic.clone()
    };
    let e = err(&small, &named);
    assert!(
        e.contains("small.npy: a .npy file holds one unnamed array"),
        "{e}"
    );
    let inf_bins = ImportOptions {
        bin_width: Some(BinWidth::Ps(1e300)),
        ..generic.clone()
    };
    let e = err(&small, &inf_bins);
    assert!(e.contains("positive, finite length, got 1e300 ps"), "{e}");
    // Histograms of zeros have nothing to reconstruct.
    let e = err(&small, &generic);
    assert!(
        e.contains("small.npy: the histograms hold only zeros"),
        "{e}"
    );
    // A scan that is not square has no one --wall-size.
    let oblong = dir.join("oblong.npy");
    crate::write_npy_f32(&oblong, &[4, 2, 3], &[0.0; 24]).unwrap();
    let e = err(&oblong, &generic);
    assert!(
        e.contains("oblong.npy: the array of shape [4, 2, 3] is a 2 × 3 scan of 4 bins, but a generic import reads square scans"),
        "{e}"
    );
    let flat = dir.join("flat.npy");
    crate::write_npy_f32(&flat, &[4, 4], &[0.0; 16]).unwrap();
    let e = err(&flat, &generic);
    assert!(e.contains("flat.npy: the array should be T × N × N"), "{e}");
    std::fs::remove_dir_all(dir).ok();
}

/// scene_info keeps a single-precision value's short form, and a double's every digit.
#[test]
fn info_numbers_drop_only_what_f32_added() {
    assert_eq!(super::info_num(0.85f32 as f64), "0.85");
    assert_eq!(super::info_num(0.85), "0.85");
    assert_eq!(super::info_num(1.0 / 3.0), "0.3333333333333333");
}

/// The boundary migration model's `raw_data` (a, b, t): row a top → bottom, column b left → right
/// (the reference code shows the letter T's bar on top), 55 ps bins, the side by file name and the
/// foam's constants in `scene_info`; its bad inputs are one line naming the file.
#[test]
fn bmm_raw_data_a_b_t() {
    let dir = tmpdir("imp-bmm");
    let (n, nt, side, z) = (8, 256, 0.2, 0.4);
    let (a0, b0) = (
        nearest(Y0 / 3.0, n, side, false),
        nearest(X0 / 3.0, n, side, false),
    );
    let raw = |f: &dyn Fn(&[usize]) -> f64| col_major(&[n, n, nt], f);
    let v = raw(&|i| ((i[0], i[1]) == (a0, b0) && i[2] == bin(2.0 * z, 55.0 * PS)) as u8 as f64);
    let p = dir.join("4cmFoam_LambertianT_7cmFoam.mat");
    write_v5(&p, &[doubles("raw_data", &[n, n, nt], &v)]);
    let cap = import(&p, &ImportOptions::preset(Preset::Bmm)).unwrap();
    // assert_point's target is (X0, Y0); this scan is a third of the size.
    let k = (0..cap.h.len()).fold(0, |b, k| if cap.h[k] > cap.h[b] { k } else { b });
    let pt = cap.sensor.points[k / nt];
    let half = 0.5 * side / (n - 1) as f64 + 1e-9;
    assert!(
        (pt.x - X0 / 3.0).abs() <= half && (pt.y - Y0 / 3.0).abs() <= half,
        "brightest at {pt:?}"
    );
    let path = cap.time.start_m + (k % nt) as f64 * cap.time.bin_width_m;
    assert!((path - 2.0 * z).abs() <= cap.time.bin_width_m, "{path}");
    assert!((cap.time.bin_width_m - 0.0165).abs() < 1e-12);
    assert!(cap.scene_info.contains(BMM_MEDIUM), "{}", cap.scene_info);
    assert!(crate::describe(&cap)
        .iter()
        .any(|l| l.contains("depth is not path/2")));
    assert!(cap.scene_info.contains("scan_side_m: 0.2\n"));

    let err = |p: &Path| {
        let e = import(p, &ImportOptions::preset(Preset::Bmm))
            .unwrap_err()
            .to_string();
        assert!(
            !e.contains('\n') && e.contains(&p.display().to_string()),
            "{e}"
        );
        e
    };
    write_v5(&p, &[doubles("raw", &[n, n, nt], &v)]);
    assert!(err(&p).contains("no variable 'raw_data'"));
    write_v5(
        &p,
        &[doubles(
            "raw_data",
            &[n, n + 1, 4],
            &vec![1.0; n * (n + 1) * 4],
        )],
    );
    assert!(err(&p).contains("bmm scans are square"));
    write_v5(
        &p,
        &[doubles("raw_data", &[n, n * nt], &vec![1.0; n * n * nt])],
    );
    assert!(err(&p).contains("should be N × N × T"));
    write_v5(
        &p,
        &[doubles("raw_data", &[n, n, nt], &vec![0.0; n * n * nt])],
    );
    assert!(err(&p).contains("only zeros"));
    let mut nan = v.clone();
    nan[7] = f64::NAN;
    write_v5(&p, &[doubles("raw_data", &[n, n, nt], &nan)]);
    assert!(err(&p).contains("non-finite"));
    let other = dir.join("foam.mat");
    write_v5(&other, &[doubles("raw_data", &[n, n, nt], &v)]);
    assert!(err(&other).contains("give its scan side with --wall-size"));
    std::fs::remove_dir_all(dir).ok();
}
