//! The datasets that carry their own wall points (Ahn et al. 2019, Z-NLOS): the coordinates place
//! the scan, so murk only reorders the histograms into its grid order (+x, +y) when the points form
//! an axis-aligned regular grid on a plane z = const, and keeps them as a list otherwise.

use super::presets::{check_container, positive, scalar};
use super::{info_head, Dim, Flip, ImportOptions, Preset, Scan};
use crate::mat::ArrayFile;
use murk_core::{
    short, Capture, DVec3, Error, Limits, Opt, Pairing, PointLayout, PointSet, Result, TimeAxis,
};
use std::path::Path;

pub(super) fn import(path: &Path, p: Preset, o: &ImportOptions) -> Result<Capture> {
    if o.wall_size_m.is_some() && p == Preset::Znlos {
        return Err(Error::param(format!(
            "Z-NLOS files carry their wall points; {} does not apply",
            Opt::WallSize
        )));
    }
    let file = ArrayFile::open(path)?;
    check_container(path, p, &file)?;
    let walls = if p == Preset::Znlos {
        znlos(path, &file)?
    } else {
        ahn(path, &file, o)?
    };
    walls.capture(path, o)
}

/// A scan whose histograms (file order) go with wall points given in the same order.
struct Walls {
    scan: Scan,
    illum: Vec<DVec3>,
    sensor: Vec<DVec3>,
    normals: Vec<DVec3>,
    /// Path at the start of bin 0 and the bin width, as the file states them.
    start_m: f64,
    bin_width_m: Option<f64>,
    /// Laser and SPAD device positions when the times include the legs to and from the wall.
    devices: Option<(DVec3, DVec3)>,
    format: &'static str,
    var: &'static str,
    /// Further `scene_info` lines.
    extra: String,
}

impl Walls {
    fn capture(mut self, path: &Path, o: &ImportOptions) -> Result<Capture> {
        let bin_width_m = match (o.bin_width, self.bin_width_m) {
            (Some(b), _) => b.metres(),
            (None, Some(m)) => m,
            (None, None) => {
                return Err(Error::format(
                    path,
                    format!(
                        "no bin width in the file; give it with {} or {}",
                        Opt::BinWidthPs,
                        Opt::BinWidthM
                    ),
                ))
            }
        };
        if !(bin_width_m.is_finite() && bin_width_m > 0.0) {
            return Err(Error::param(format!(
                "the bin width must be positive, got {} m",
                short(bin_width_m)
            )));
        }
        mirror(&mut self, o.flip);
        let gate = o.gate_bins.unwrap_or(0);
        self.scan.gate(path, gate)?;
        let (nx, ny, nt) = (self.scan.nx, self.scan.ny, self.scan.nt);
        let (layout, order) = arrange(&self.sensor, nx, ny);
        let pick = |v: &[DVec3]| order.iter().map(|&i| v[i]).collect::<Vec<_>>();
        let h: Vec<f32> = order
            .iter()
            .flat_map(|&i| &self.scan.h[i * nt..(i + 1) * nt])
            .copied()
            .collect();
        let set = |points| PointSet {
            points,
            normals: pick(&self.normals),
            layout,
        };
        let t0 = o.t0_bin.unwrap_or(0);
        let time = TimeAxis {
            start_m: self.start_m - t0 as f64 * bin_width_m,
            bin_width_m,
            bins: nt,
        };
        if time.end_m() <= 0.0 {
            return Err(Error::param(format!(
                "{}: bin {t0} as path 0 puts the whole window before the wall (it ends at {} m)",
                path.display(),
                short(time.end_m())
            )));
        }
        let arranged = match layout {
            PointLayout::Grid { nx, ny } => format!("grid {nx} × {ny} along +x, +y"),
            PointLayout::List => "list in the file's order (not an axis-aligned grid)".into(),
        };
        let scene_info = format!(
            "{}bin_width_m: {bin_width_m}\nt_start_m: {}\ngated_bins: {gate}\nt0_bin: {t0}\npoints: 'the file''s, {arranged}'\n{}{}",
            info_head(path, self.format, self.var),
            time.start_m,
            self.extra,
            super::flip_line(o.flip),
        );
        let cap = Capture {
            laser_xyz: self.devices.map(|d| d.0),
            sensor_xyz: self.devices.map(|d| d.1),
            t_accounts_first_and_last_bounces: self.devices.is_some(),
            scene_info,
            ..Capture::new(
                set(pick(&self.illum)),
                set(pick(&self.sensor)),
                Pairing::Paired,
                time,
                h,
            )
        };
        super::checked(path, cap)
    }
}

/// Mirrors the wall (points, normals, devices) across its centre along the flipped axes.
fn mirror(w: &mut Walls, flip: Flip) {
    if flip == Flip::default() {
        return;
    }
    let c = w.sensor.iter().copied().sum::<DVec3>() / w.sensor.len().max(1) as f64;
    let across = |p: &mut DVec3| {
        if flip.x {
            p.x = 2.0 * c.x - p.x;
        }
        if flip.y {
            p.y = 2.0 * c.y - p.y;
        }
    };
    w.illum.iter_mut().chain(&mut w.sensor).for_each(across);
    if let Some((l, s)) = &mut w.devices {
        across(l);
        across(s);
    }
    for n in &mut w.normals {
        if flip.x {
            n.x = -n.x;
        }
        if flip.y {
            n.y = -n.y;
        }
    }
}

/// murk's grid order for a P × Q scan whose point (p, q) is `points[p·Q + q]`: when the points
/// form a regular grid on a plane z = const with one index along x and the other along y, the grid
/// (ix, iy) with ix along +x and iy along +y, and for each murk index the file's; otherwise a list
/// in the file's order.
fn arrange(points: &[DVec3], np: usize, nq: usize) -> (PointLayout, Vec<usize>) {
    let identity = (PointLayout::List, (0..points.len()).collect());
    let set = PointSet {
        points: points.to_vec(),
        normals: vec![DVec3::Z; points.len()],
        layout: PointLayout::Grid { nx: np, ny: nq },
    };
    let Some(g) = set.regular_grid() else {
        return identity;
    };
    // The world axis a step runs along (0 = x, 1 = y) and its sign, if it runs along one.
    let along = |s: DVec3| {
        let tol = 1e-6 * s.length();
        if s.z.abs() > tol {
            None
        } else if s.y.abs() <= tol {
            Some((0, s.x > 0.0))
        } else if s.x.abs() <= tol {
            Some((1, s.y > 0.0))
        } else {
            None
        }
    };
    let index = |forward: bool, n: usize, i: usize| if forward { i } else { n - 1 - i };
    match (along(g.step_x), along(g.step_y)) {
        (Some((0, fp)), Some((1, fq))) => (
            PointLayout::Grid { nx: np, ny: nq },
            (0..np * nq)
                .map(|i| index(fp, np, i / nq) * nq + index(fq, nq, i % nq))
                .collect(),
        ),
        (Some((1, fp)), Some((0, fq))) => (
            PointLayout::Grid { nx: nq, ny: np },
            (0..np * nq)
                .map(|i| index(fp, np, i % np) * nq + index(fq, nq, i / np))
                .collect(),
        ),
        _ => identity,
    }
}

/// `var` as a list of N points (N × 3, or 3 × N).
fn points(path: &Path, file: &ArrayFile, var: &str, n: usize) -> Result<Option<Vec<DVec3>>> {
    let Some((shape, v)) = file.get(path, var)? else {
        return Ok(None);
    };
    let xyz: Vec<DVec3> = match shape[..] {
        [rows, 3] if rows == n => v
            .chunks_exact(3)
            .map(|c| DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64))
            .collect(),
        [3, cols] if cols == n => (0..n)
            .map(|i| DVec3::new(v[i] as f64, v[n + i] as f64, v[2 * n + i] as f64))
            .collect(),
        _ => {
            return Err(Error::format(
                path,
                format!("'{var}' should be {n} × 3 wall points, got shape {shape:?}"),
            ))
        }
    };
    if xyz.iter().any(|p| !p.is_finite()) {
        return Err(Error::format(
            path,
            format!("'{var}' holds a non-finite coordinate"),
        ));
    }
    Ok(Some(xyz))
}

/// Ahn et al. 2019: struct `NLOSDATA` (see [`Preset::Ahn2019`]).
fn ahn(path: &Path, file: &ArrayFile, o: &ImportOptions) -> Result<Walls> {
    const VAR: &str = "NLOSDATA.transient";
    let (shape, data) = file.require(path, VAR)?;
    // Point ix·Ny + iy measures transient(ix, iy, :): the (x, y, t) order as stored.
    let scan = Scan::new(
        path,
        VAR,
        &shape,
        &data,
        [Dim::X, Dim::Y, Dim::T],
        Flip::default(),
    )?;
    let n = scan.nx * scan.ny;
    let laser = points(path, file, "NLOSDATA.l", n)?;
    let sensor = points(path, file, "NLOSDATA.s", n)?;
    let confocal = scalar(path, file, "NLOSDATA.is_confocal")?;
    let (illum, sensor, where_from) = match (laser, sensor, o.wall_size_m) {
        (Some(l), Some(s), _) => {
            let z_wall = s.iter().map(|p| p.z).sum::<f64>() / s.len() as f64;
            (
                facing_the_scene(&l, z_wall),
                facing_the_scene(&s, z_wall),
                "l, s",
            )
        }
        (Some(p), None, _) | (None, Some(p), _) if confocal != Some(0.0) => {
            let z_wall = p.iter().map(|p| p.z).sum::<f64>() / p.len() as f64;
            let p = facing_the_scene(&p, z_wall);
            (p.clone(), p, "one of l, s (confocal)")
        }
        (None, None, Some(side)) if confocal != Some(0.0) => {
            let grid = super::square_grid(scan.nx, scan.ny, side);
            (grid.clone(), grid, "--wall-size (x, y as stored)")
        }
        _ => {
            return Err(Error::format(
                path,
                format!("NLOSDATA has no usable l/s wall points; for a confocal scan give the scan side with {}", Opt::WallSize),
            ))
        }
    };
    let times = file.get(path, "NLOSDATA.times")?.map(|t| t.1);
    if let Some(t) = &times {
        if t.len() != scan.nt {
            return Err(Error::format(
                path,
                format!(
                    "'NLOSDATA.times' has {} entries for {} bins",
                    t.len(),
                    scan.nt
                ),
            ));
        }
    }
    let delta = match scalar(path, file, "NLOSDATA.delta")? {
        Some(d) => Some(positive(path, "NLOSDATA.delta", "the bin width", d, "m")?),
        None => times.as_ref().map(|t| (t[1] - t[0]) as f64),
    };
    let mut extra = format!("points_from: '{where_from}'\n");
    for (field, v) in [
        ("is_confocal", confocal),
        ("target_dist", scalar(path, file, "NLOSDATA.target_dist")?),
    ] {
        if let Some(v) = v {
            extra += &format!("{field}: {v}\n");
        }
    }
    Ok(Walls {
        normals: vec![DVec3::Z; n],
        illum,
        sensor,
        start_m: times.map_or(0.0, |t| t[0] as f64),
        bin_width_m: delta,
        devices: None,
        format: "ahn2019 (path length from the wall; wall turned to z = 0, x reversed)",
        var: VAR,
        extra,
        scan,
    })
}

/// Ahn et al.'s files put the wall at z = target_dist and the hidden scene around the origin, on
/// the wall's −z side (their `loadNLOSDATA.m`; the 2019, TX and toy files have l, s at z = 1.08 m
/// and voxels at z ∈ [−0.5, 0.5] m). murk's wall is at z = 0 with the scene at z > 0, so the points
/// are turned half a turn about the y axis through the wall: (x, y, z) → (−x, y, z_wall − z), a
/// rotation, so the scene is not mirrored.
fn facing_the_scene(points: &[DVec3], z_wall: f64) -> Vec<DVec3> {
    points
        .iter()
        .map(|p| DVec3::new(-p.x, p.y, z_wall - p.z))
        .collect()
}

/// A Z-NLOS grid variable, stored (P, Q, 3) or (3, Q, P), as P × Q points (y-tal's reading).
fn znlos_grid(path: &Path, file: &ArrayFile, var: &str) -> Result<(usize, usize, Vec<DVec3>)> {
    let (shape, v) = file.require(path, var)?;
    match shape[..] {
        [np, nq, 3] => Ok((
            np,
            nq,
            v.chunks_exact(3)
                .map(|c| DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64))
                .collect(),
        )),
        [3, nq, np] => {
            let at = |c: usize, q: usize, p: usize| v[(c * nq + q) * np + p] as f64;
            Ok((
                np,
                nq,
                (0..np * nq)
                    .map(|i| {
                        let (p, q) = (i / nq, i % nq);
                        DVec3::new(at(0, q, p), at(1, q, p), at(2, q, p))
                    })
                    .collect(),
            ))
        }
        _ => Err(Error::format(
            path,
            format!("'{var}' should be a P × Q × 3 grid (or 3 × Q × P), got shape {shape:?}"),
        )),
    }
}

/// A 3-vector variable (device positions).
fn vec3(path: &Path, file: &ArrayFile, var: &str) -> Result<DVec3> {
    match file.require(path, var)? {
        (_, v) if v.len() == 3 => Ok(DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64)),
        (shape, _) => Err(Error::format(
            path,
            format!("'{var}' should hold 3 coordinates, got shape {shape:?}"),
        )),
    }
}

/// Z-NLOS (Galindo et al. 2019), confocal renders; see [`Preset::Znlos`].
fn znlos(path: &Path, file: &ArrayFile) -> Result<Walls> {
    const VAR: &str = "data";
    let (shape, data) = file.require(path, VAR)?;
    let (np, nq, sensor) = znlos_grid(path, file, "cameraGridPositions")?;
    let (lp, lq, illum) = znlos_grid(path, file, "laserGridPositions")?;
    let normals = match file.get(path, "cameraGridNormals")? {
        Some(_) => znlos_grid(path, file, "cameraGridNormals")?.2,
        None => vec![DVec3::Z; np * nq],
    };
    if (lp, lq) != (np, nq) || normals.len() != np * nq {
        return Err(Error::Unsupported(format!(
            "{}: laser grid {lp} × {lq} and camera grid {np} × {nq} differ; murk reads confocal Z-NLOS renders only",
            path.display()
        )));
    }
    // y-tal's two layouts of a confocal render, with the stored axis of p, q, bounces, t, colours.
    let axes = match shape[..] {
        [a, b, _, _, _] if (a, b) == (np, nq) => [0, 1, 2, 3, 4],
        [_, _, _, b, a] if (a, b) == (np, nq) => [4, 3, 2, 1, 0],
        _ => {
            return Err(Error::Unsupported(format!(
                "{}: 'data' has shape {shape:?}; murk reads confocal Z-NLOS renders, (P, Q, bounces, t, colours) or its reverse, with the camera grid's P × Q = {np} × {nq}",
                path.display()
            )))
        }
    };
    let nt = shape[axes[3]];
    if nt < 1 || np * nq < 1 {
        return Err(Error::format(path, format!("'data' has shape {shape:?}")));
    }
    if let Some(v) = data.iter().find(|v| !v.is_finite()) {
        return Err(Error::format(
            path,
            format!(
                "'data' holds a non-finite value ({})",
                murk_core::non_finite(*v)
            ),
        ));
    }
    Limits::get().elements(&format!("{}: 'data'", path.display()), &[np, nq, nt], 4)?;
    // C-order strides of the stored axes; bounces and colours are summed, as y-tal does.
    let mut strides = [1usize; 5];
    for k in (0..4).rev() {
        strides[k] = strides[k + 1] * shape[k + 1];
    }
    let s = axes.map(|a| strides[a]);
    let (nb, nc) = (shape[axes[2]], shape[axes[4]]);
    let mut h = vec![0f32; np * nq * nt];
    for (i, hist) in h.chunks_mut(nt).enumerate() {
        let base = (i / nq) * s[0] + (i % nq) * s[1];
        for (t, v) in hist.iter_mut().enumerate() {
            let at = base + t * s[3];
            *v = (0..nb)
                .flat_map(|b| (0..nc).map(move |c| at + b * s[2] + c * s[4]))
                .map(|k| data[k])
                .sum();
        }
    }
    let scalar_m = |var| {
        scalar(path, file, var)?.ok_or_else(|| {
            Error::format(
                path,
                format!(
                    "no '{var}' (variables present: {})",
                    file.names(path).unwrap_or_default().join(", ")
                ),
            )
        })
    };
    Ok(Walls {
        scan: Scan {
            nx: np,
            ny: nq,
            nt,
            h,
        },
        illum,
        sensor,
        normals,
        start_m: scalar_m("t0")?,
        bin_width_m: Some(positive(
            path,
            "deltaT",
            "the bin width",
            scalar_m("deltaT")?,
            "m",
        )?),
        devices: Some((
            vec3(path, file, "laserPosition")?,
            vec3(path, file, "cameraPosition")?,
        )),
        format: "znlos (path from the laser to the camera)",
        var: VAR,
        extra: String::new(),
    })
}
