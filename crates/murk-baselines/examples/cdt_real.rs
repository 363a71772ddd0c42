//! CDT and f-k on a Lindell & Wetzstein (2020) capture, from the lossless `.npy` copy of `meas`
//! (uint16, C order (t, a, b) = (512, 32, 32), 16 ps bins, t = 0 at slab entry).
//!
//! cargo run --release -p murk-baselines --example cdt_real -- NPY SCAN_SIDE_M SNR OUT.png
//! Writes the two depth-maximum projections side by side (CDT left, f-k right), image row = a
//! (top → bottom), column = b (left → right), the reference code's display convention.

use murk_baselines::{cdt, fk, CdtParams, FkParams, Reconstruction, TimeGrid};
use murk_core::{Capture, DVec3, Pairing, PointSet, TimeAxis};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let [_, npy, side, snr, out] = &args[..] else {
        panic!("usage: cdt_real NPY SCAN_SIDE_M SNR OUT.png");
    };
    let side: f64 = side.parse().expect("scan side in metres");
    let snr: f64 = snr.parse().expect("snr");
    let (shape, meas) = read_npy_u16(npy);
    let [nt, na, nb] = shape[..] else {
        panic!("expected a 3-D array, got {shape:?}")
    };
    // Scan point (a, b) is grid point (ix, iy) = (a, b): x along a, y along b, pitch side/(n − 1).
    let pts = |n: usize, i: usize| -side / 2.0 + side * i as f64 / (n - 1) as f64;
    let points: Vec<DVec3> = (0..na * nb)
        .map(|i| DVec3::new(pts(na, i / nb), pts(nb, i % nb), 0.0))
        .collect();
    let grid = PointSet {
        normals: vec![DVec3::Z; points.len()],
        points,
        layout: murk_core::PointLayout::Grid { nx: na, ny: nb },
    };
    let mut h = vec![0.0f32; na * nb * nt];
    for t in 0..nt {
        for i in 0..na * nb {
            h[i * nt + t] = meas[t * na * nb + i] as f32;
        }
    }
    let capture = Capture {
        illum: grid.clone(),
        sensor: grid,
        laser_xyz: None,
        sensor_xyz: None,
        // 16 ps at the 3e8 m/s the data's authors use: 4.8 mm of path per bin.
        time: TimeAxis {
            start_m: 0.0,
            bin_width_m: 3e8 * 16e-12,
            bins: nt,
        },
        t_accounts_first_and_last_bounces: false,
        pairing: Pairing::Paired,
        h,
        scene_info: String::new(),
    };
    let params = CdtParams {
        snr,
        ..Default::default()
    };
    let t0 = Instant::now();
    let r_cdt = cdt(&capture, params).unwrap();
    let t_cdt = t0.elapsed();
    let TimeGrid::Resample { .. } = params.grid else {
        unreachable!()
    };
    let t0 = Instant::now();
    let r_fk = fk(&capture, FkParams { grid: params.grid }).unwrap();
    let t_fk = t0.elapsed();
    for (name, r, t) in [("cdt", &r_cdt, t_cdt), ("fk", &r_fk, t_fk)] {
        let (peak, median) = depths(r);
        println!(
            "{name}: {:.1} ms, peak depth {peak:.3} m, median depth of bright pixels {median:.3} m",
            t.as_secs_f64() * 1e3
        );
    }
    write_png(out, &[&r_cdt, &r_fk], 8);
}

/// Depth of the global maximum, and the median argmax depth over pixels whose projection exceeds half
/// of its maximum.
fn depths(r: &Reconstruction) -> (f64, f64) {
    let peak = r.volume.z.at(r.argmax()[2]);
    let mip = r.max_projection();
    let max = mip.iter().copied().fold(0.0, f32::max);
    let nz = r.volume.z.n;
    let mut zs: Vec<f64> = r
        .data
        .chunks(nz)
        .zip(&mip)
        .filter(|(_, &m)| m > 0.5 * max)
        .map(|(c, &m)| r.volume.z.at(c.iter().position(|&v| v == m).unwrap()))
        .collect();
    zs.sort_by(f64::total_cmp);
    (peak, zs[zs.len() / 2])
}

fn write_png(path: &str, recs: &[&Reconstruction], scale: usize) {
    let [nx, ny, _] = recs[0].volume.shape();
    let gap = 4;
    let (w, hgt) = (recs.len() * (ny * scale + gap) - gap, nx * scale);
    let mut img = vec![255u8; w * hgt];
    for (k, r) in recs.iter().enumerate() {
        let mip = r.max_projection();
        let max = mip.iter().copied().fold(f32::MIN, f32::max);
        let min = mip.iter().copied().fold(f32::MAX, f32::min);
        for row in 0..hgt {
            for col in 0..ny * scale {
                let v = (mip[(row / scale) * ny + col / scale] - min) / (max - min);
                img[row * w + k * (ny * scale + gap) + col] = (v * 255.0) as u8;
            }
        }
    }
    let f = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut enc = png::Encoder::new(f, w as u32, hgt as u32);
    enc.set_color(png::ColorType::Grayscale);
    enc.write_header().unwrap().write_image_data(&img).unwrap();
}

/// Minimal reader for little-endian uint16 C-order `.npy` (format 1.0).
fn read_npy_u16(path: &str) -> (Vec<usize>, Vec<u16>) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[..6], b"\x93NUMPY", "not an .npy file");
    let hlen = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(&bytes[10..10 + hlen]).unwrap();
    assert!(
        header.contains("'<u2'") && header.contains("'fortran_order': False"),
        "{header}"
    );
    let dims = header
        .split("'shape': (")
        .nth(1)
        .unwrap()
        .split(')')
        .next()
        .unwrap();
    let shape: Vec<usize> = dims
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|s| s.trim().parse().unwrap())
        .collect();
    let data = bytes[10 + hlen..]
        .chunks_exact(2)
        .map(|b| u16::from_le_bytes([b[0], b[1]]))
        .collect();
    (shape, data)
}
