//! Fixtures the crate's tests share: captures of every kind with exactly representable values, a
//! scratch folder, and a field-by-field comparison.

use murk_core::{Capture, DVec3, Pairing, PointLayout, PointSet, TimeAxis};

/// Coordinates on a 1/64 m lattice so that their f32 copies are exact.
pub fn grid(nx: usize, ny: usize, z: f64) -> PointSet {
    let mut points = Vec::new();
    for ix in 0..nx {
        for iy in 0..ny {
            points.push(DVec3::new(ix as f64 * 0.125 - 0.25, iy as f64 * 0.0625, z));
        }
    }
    PointSet {
        normals: (0..points.len())
            .map(|i| DVec3::new(0.0, 0.0, if i % 2 == 0 { 1.0 } else { -1.0 }))
            .collect(),
        points,
        layout: PointLayout::Grid { nx, ny },
    }
}

pub fn list(n: usize) -> PointSet {
    PointSet {
        points: (0..n)
            .map(|i| DVec3::new(i as f64 * 0.125, -0.0625 * i as f64, 0.5))
            .collect(),
        normals: vec![DVec3::Z; n],
        layout: PointLayout::List,
    }
}

pub fn capture(illum: PointSet, sensor: PointSet, pairing: Pairing) -> Capture {
    let bins = 7;
    let time = TimeAxis {
        start_m: 0.75,
        bin_width_m: 0.0078125,
        bins,
    };
    let mut c = Capture {
        laser_xyz: Some(DVec3::new(-1.5, 0.25, 2.0)),
        scene_info: "name: test\nvalues:\n- 1\n- 2\n".into(),
        ..Capture::new(illum, sensor, pairing, time, Vec::new())
    };
    c.h = (0..c.n_hist() * bins)
        .map(|i| (i as f32 * 0.37).sin())
        .collect();
    c
}

/// One capture of every kind murk distinguishes, with every layout the writer chooses.
pub fn all_kinds() -> Vec<(&'static str, Capture)> {
    let mut confocal = capture(grid(3, 4, 0.0), grid(3, 4, 0.0), Pairing::Paired);
    confocal.t_accounts_first_and_last_bounces = true;
    confocal.sensor_xyz = Some(DVec3::new(1.0, 2.0, 3.0));
    vec![
        ("confocal", confocal),
        (
            "paired",
            capture(grid(2, 3, 0.0), grid(2, 3, 0.125), Pairing::Paired),
        ),
        ("paired_list", capture(list(5), list(5), Pairing::Paired)),
        (
            "single",
            capture(
                PointSet::single(DVec3::new(0.5, 0.5, 0.0)),
                grid(4, 2, 0.0),
                Pairing::Product,
            ),
        ),
        (
            "single_list",
            capture(PointSet::single(DVec3::ZERO), list(6), Pairing::Product),
        ),
        (
            "laser_grid_one_spad",
            capture(
                grid(3, 2, 0.0),
                PointSet::single(DVec3::new(0.0, 0.25, 0.0)),
                Pairing::Product,
            ),
        ),
        (
            "exhaustive",
            capture(grid(2, 3, 0.0), grid(3, 2, 0.0), Pairing::Product),
        ),
        (
            "exhaustive_list",
            capture(list(3), list(4), Pairing::Product),
        ),
        (
            "exhaustive_mixed",
            capture(grid(2, 2, 0.0), list(3), Pairing::Product),
        ),
    ]
}

pub fn tmpdir(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("murk-io-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

pub fn assert_same(a: &Capture, b: &Capture, what: &str) {
    assert_eq!(a.illum, b.illum, "{what}: illum");
    assert_eq!(a.sensor, b.sensor, "{what}: sensor");
    assert_eq!(a.laser_xyz, b.laser_xyz, "{what}: laser_xyz");
    assert_eq!(a.sensor_xyz, b.sensor_xyz, "{what}: sensor_xyz");
    assert_eq!(a.time, b.time, "{what}: time");
    assert_eq!(
        a.t_accounts_first_and_last_bounces, b.t_accounts_first_and_last_bounces,
        "{what}: t_accounts"
    );
    assert_eq!(a.pairing, b.pairing, "{what}: pairing");
    assert_eq!(
        a.h.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
        b.h.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
        "{what}: H"
    );
    assert_eq!(a.scene_info, b.scene_info, "{what}: scene_info");
    assert_eq!(a.medium_density, b.medium_density, "{what}: medium_density");
}
