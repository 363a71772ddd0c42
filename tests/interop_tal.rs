//! Interoperability with the real y-tal package (PyPI `y-tal`, read for behaviour only).
//!
//! Python is `$MURK_PYTHON` or `<repo>/.venv/bin/python` (`.ci/run` creates it). The tests are
//! `#[ignore]`d because they need it; `.ci/run` runs them with `--ignored`, and without a Python that
//! imports `tal` and `h5py` they fail saying so.
//!
//! Python and Rust exchange values as text lines `key shape values...`: floats are printed with
//! `repr`, which round-trips f32 and f64 exactly, so every comparison below is exact.

use murk_core::{Capture, DVec3, Pairing, PointLayout, PointSet, TimeAxis};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

#[path = "common/tal.rs"]
mod tal;
use tal::python;

fn run_python(py: &Path, script: &str, args: &[&Path]) -> String {
    let out = Command::new(py)
        .arg("-c")
        .arg(script)
        .args(args)
        .output()
        .expect("run python");
    assert!(
        out.status.success(),
        "python failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("utf-8")
}

fn tmpdir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("murk-interop-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Values Python printed for one file: numeric fields (shape, values) and word fields.
#[derive(Default, Debug)]
struct Fields {
    num: HashMap<String, (Vec<usize>, Vec<f64>)>,
    word: HashMap<String, String>,
}

impl Fields {
    fn num(&self, k: &str) -> &(Vec<usize>, Vec<f64>) {
        self.num
            .get(k)
            .unwrap_or_else(|| panic!("python printed no {k}"))
    }
    fn word(&self, k: &str) -> &str {
        self.word
            .get(k)
            .unwrap_or_else(|| panic!("python printed no {k}"))
    }
}

/// Parses blocks `FILE <name>` followed by `N <key> <shape,csv> <v>...` and `W <key> <word>` lines.
fn parse(out: &str) -> HashMap<String, Fields> {
    let mut all: HashMap<String, Fields> = HashMap::new();
    let mut cur = String::new();
    for line in out.lines() {
        let mut it = line.splitn(3, ' ');
        match (it.next(), it.next(), it.next()) {
            (Some("FILE"), Some(name), _) => {
                cur = name.to_string();
                all.entry(cur.clone()).or_default();
            }
            (Some("N"), Some(k), Some(rest)) => {
                let mut parts = rest.split(' ');
                let shape = parts
                    .next()
                    .unwrap()
                    .split(',')
                    .filter(|s| !s.is_empty())
                    .map(|s| s.parse().unwrap())
                    .collect();
                let vals = parts.map(|v| v.parse().unwrap()).collect();
                all.get_mut(&cur)
                    .unwrap()
                    .num
                    .insert(k.into(), (shape, vals));
            }
            (Some("W"), Some(k), Some(w)) => {
                all.get_mut(&cur).unwrap().word.insert(k.into(), w.into());
            }
            _ => panic!("unexpected python output line: {line}"),
        }
    }
    all
}

const EMIT: &str = r#"
import sys, json, numpy as np, h5py
def N(k, a):
    a = np.asarray(a)
    print('N', k, ','.join(map(str, a.shape)), *[repr(float(v)) for v in a.ravel()])
def W(k, w):
    print('W', k, w)
"#;

fn points_of(set: &PointSet) -> Vec<f64> {
    set.points
        .iter()
        .flat_map(|p| [p.x as f32 as f64, p.y as f32 as f64, p.z as f32 as f64])
        .collect()
}

fn normals_of(set: &PointSet) -> Vec<f64> {
    set.normals
        .iter()
        .flat_map(|p| [p.x as f32 as f64, p.y as f32 as f64, p.z as f32 as f64])
        .collect()
}

/// murk's H (histogram-major) in tal's time-first order.
fn h_time_first(c: &Capture) -> Vec<f64> {
    let (nt, nh) = (c.time.bins, c.n_hist());
    (0..nt * nh)
        .map(|j| c.h[(j % nh) * nt + j / nh] as f64)
        .collect()
}

/// (a) y-tal writes captures of every layout; murk reads every field.
#[test]
#[ignore = "needs a Python with y-tal and h5py (MURK_PYTHON or .venv; .ci/run makes .venv and runs these with --ignored)"]
fn murk_reads_captures_written_by_tal() {
    let py = python();
    let dir = tmpdir("a");
    let script = format!(
        "{EMIT}{}",
        r#"
import tal, tal.enums as E
from tal.io.capture_data import NLOSCaptureData
out = sys.argv[1]
rng = np.random.default_rng(7)
def grid(nx, ny, z=0.0):
    x, y = np.meshgrid(np.linspace(-1, 1, nx), np.linspace(-0.5, 0.5, ny), indexing='ij')
    return np.stack([x, y, np.full_like(x, z)], axis=-1).astype(np.float32)
def normals(shape):
    n = np.zeros(shape, np.float32); n[..., 2] = 1; n[..., 0] = 0.25
    return n
def make(name, H, hf, sgrid, lgrid, level=0, t_acc=False, t_start=0.0, xyz=False):
    d = NLOSCaptureData()
    d.H = H.astype(np.float32); d.H_format = hf
    d.sensor_grid_xyz = sgrid; d.sensor_grid_normals = normals(sgrid.shape)
    d.sensor_grid_format = E.GridFormat.X_Y_3 if sgrid.ndim == 3 else E.GridFormat.N_3
    d.laser_grid_xyz = lgrid; d.laser_grid_normals = normals(lgrid.shape)
    d.laser_grid_format = E.GridFormat.X_Y_3 if lgrid.ndim == 3 else E.GridFormat.N_3
    if xyz:
        d.laser_xyz = np.array([-0.5, 0.25, 1.5], np.float32)
        d.sensor_xyz = np.array([0.75, -0.125, 2.0], np.float32)
    d.delta_t = np.float32(0.0031); d.t_start = np.float32(t_start)
    d.t_accounts_first_and_last_bounces = t_acc
    d.scene_info = {'name': name, 'shape': np.arange(3), 'fmt': E.GroundTruthFormat.X_Y,
                    'config': {'num_bins': int(H.shape[0]), 'scan': name}}
    path = f'{out}/{name}.hdf5'
    tal.io.write_capture(path, d, compression_level=level)
    r = h5py.File(path, 'r')
    print('FILE', name)
    N('H', r['H'][()])
    for side in ('sensor', 'laser'):
        N(side + '_grid_xyz', r[side + '_grid_xyz'][()])
        N(side + '_grid_normals', r[side + '_grid_normals'][()])
    for k in ('laser_xyz', 'sensor_xyz'):
        if isinstance(r[k][()], h5py.Empty): W(k, 'none')
        else: N(k, r[k][()])
    N('delta_t', r['delta_t'][()]); N('t_start', r['t_start'][()])
    W('t_acc', str(bool(r['t_accounts_first_and_last_bounces'][()])))
    W('scene_info_hex', r['scene_info'][()].hex())
g = grid(4, 3)
make('single', rng.random((9, 4, 3)), E.HFormat.T_Sx_Sy, g, np.array([[[0.1, 0.2, 0.0]]], np.float32))
make('confocal', rng.random((9, 4, 3)), E.HFormat.T_Sx_Sy, g, g.copy(), t_acc=True, t_start=1.25, xyz=True)
make('exhaustive', rng.random((8, 2, 3, 4, 3)), E.HFormat.T_Lx_Ly_Sx_Sy, g, grid(2, 3, 0.0))
make('exhaustive_gzip', rng.random((8, 2, 3, 4, 3)), E.HFormat.T_Lx_Ly_Sx_Sy, g, grid(2, 3, 0.0), level=4)
make('laser_grid_one_spad', rng.random((8, 2, 3, 1, 1)), E.HFormat.T_Lx_Ly_Sx_Sy, grid(1, 1), grid(2, 3))
u = rng.random((5, 3)).astype(np.float32)
make('unstructured_confocal', rng.random((6, 5)), E.HFormat.T_Si, u, u.copy(), level=4, t_start=-0.5)
make('unstructured_single', rng.random((6, 5)), E.HFormat.T_Si, u, np.zeros((1, 3), np.float32))
make('unstructured_exhaustive', rng.random((6, 2, 5)), E.HFormat.T_Li_Si, u, rng.random((2, 3)).astype(np.float32))
"#
    );
    let printed = parse(&run_python(&py, &script, &[&dir]));
    let expect: [(&str, Pairing, bool, bool); 8] = [
        // name, pairing, illum is a grid, sensor is a grid
        ("single", Pairing::Product, true, true),
        ("confocal", Pairing::Paired, true, true),
        ("exhaustive", Pairing::Product, true, true),
        ("exhaustive_gzip", Pairing::Product, true, true),
        ("laser_grid_one_spad", Pairing::Product, true, true),
        ("unstructured_confocal", Pairing::Paired, false, false),
        ("unstructured_single", Pairing::Product, false, false),
        ("unstructured_exhaustive", Pairing::Product, false, false),
    ];
    assert_eq!(printed.len(), expect.len());
    for (name, pairing, illum_grid, sensor_grid) in expect {
        let f = &printed[name];
        let c = murk_io::read_capture(&dir.join(format!("{name}.hdf5")))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let (hs, hv) = f.num("H");
        assert_eq!(c.time.bins, hs[0], "{name}: bins");
        assert_eq!(h_time_first(&c), *hv, "{name}: H");
        assert_eq!(c.pairing, pairing, "{name}: pairing");
        for (set, side, is_grid) in [
            (&c.sensor, "sensor", sensor_grid),
            (&c.illum, "laser", illum_grid),
        ] {
            let (gs, gv) = f.num(&format!("{side}_grid_xyz"));
            assert_eq!(points_of(set), *gv, "{name}: {side} points");
            assert_eq!(
                normals_of(set),
                f.num(&format!("{side}_grid_normals")).1,
                "{name}"
            );
            match set.layout {
                PointLayout::Grid { nx, ny } => {
                    assert!(is_grid, "{name}: {side}");
                    assert_eq!(gs[..], [nx, ny, 3], "{name}: {side} grid shape");
                }
                PointLayout::List => {
                    assert!(!is_grid, "{name}: {side}");
                    assert_eq!(gs[..], [set.len(), 3], "{name}: {side} list shape");
                }
            }
        }
        for (k, v) in [("laser_xyz", c.laser_xyz), ("sensor_xyz", c.sensor_xyz)] {
            match v {
                None => assert_eq!(f.word(k), "none", "{name}: {k}"),
                Some(p) => assert_eq!(f.num(k).1, vec![p.x, p.y, p.z], "{name}: {k}"),
            }
        }
        assert_eq!(c.time.bin_width_m, f.num("delta_t").1[0], "{name}: delta_t");
        assert_eq!(c.time.start_m, f.num("t_start").1[0], "{name}: t_start");
        assert_eq!(
            c.t_accounts_first_and_last_bounces.to_string(),
            f.word("t_acc").to_lowercase(),
            "{name}: t_accounts"
        );
        let hex: String = c.scene_info.bytes().map(|b| format!("{b:02x}")).collect();
        assert_eq!(hex, f.word("scene_info_hex"), "{name}: scene_info");
        let summary = murk_io::scene_info_summary(&c.scene_info);
        let keys: Vec<&str> = summary.iter().map(|(k, _)| k.as_str()).collect();
        assert_eq!(
            keys,
            ["config", "fmt", "name", "shape"],
            "{name}: {summary:?}"
        );
        assert_eq!(summary[2].1, name, "{name}");
        c.validate().unwrap();
    }
    std::fs::remove_dir_all(dir).ok();
}

fn grid(nx: usize, ny: usize, z: f64) -> PointSet {
    let mut points = Vec::new();
    for ix in 0..nx {
        for iy in 0..ny {
            points.push(DVec3::new(ix as f64 * 0.25 - 0.5, iy as f64 * 0.125, z));
        }
    }
    PointSet {
        normals: vec![DVec3::new(0.0, 0.5, 1.0); points.len()],
        points,
        layout: PointLayout::Grid { nx, ny },
    }
}

fn list(n: usize) -> PointSet {
    PointSet {
        points: (0..n)
            .map(|i| DVec3::new(i as f64 * 0.375, 0.0625 * i as f64, 0.5))
            .collect(),
        normals: vec![DVec3::Z; n],
        layout: PointLayout::List,
    }
}

fn capture(illum: PointSet, sensor: PointSet, pairing: Pairing) -> Capture {
    let time = TimeAxis {
        start_m: 0.5,
        bin_width_m: 0.00390625,
        bins: 6,
    };
    let mut c = Capture {
        scene_info: "name: murk\nvalues:\n- 1\n- 2.5\n".into(),
        ..Capture::new(illum, sensor, pairing, time, Vec::new())
    };
    c.h = (0..c.n_hist() * c.time.bins)
        .map(|i| (i as f32 * 0.73).cos())
        .collect();
    c
}

/// (b) murk writes captures of every kind; y-tal reads every field.
#[test]
#[ignore = "needs a Python with y-tal and h5py (MURK_PYTHON or .venv; .ci/run makes .venv and runs these with --ignored)"]
fn tal_reads_captures_written_by_murk() {
    let py = python();
    let dir = tmpdir("b");
    let mut confocal = capture(grid(3, 2, 0.0), grid(3, 2, 0.0), Pairing::Paired);
    confocal.t_accounts_first_and_last_bounces = true;
    confocal.laser_xyz = Some(DVec3::new(-1.0, 0.5, 2.0));
    confocal.sensor_xyz = Some(DVec3::new(1.0, 0.25, 2.5));
    confocal.time.start_m = -0.75;
    // (name, capture, H_format, laser grid format, sensor grid format, is_confocal, paired)
    let cases: Vec<(&str, Capture, &str, &str, &str, bool, bool)> = vec![
        (
            "confocal", confocal, "T_Sx_Sy", "X_Y_3", "X_Y_3", true, true,
        ),
        (
            "paired",
            capture(grid(3, 2, 0.0), grid(3, 2, 0.25), Pairing::Paired),
            "T_Sx_Sy",
            "X_Y_3",
            "X_Y_3",
            false,
            true,
        ),
        (
            "single",
            capture(
                PointSet::single(DVec3::new(0.25, 0.5, 0.0)),
                grid(4, 3, 0.0),
                Pairing::Product,
            ),
            "T_Sx_Sy",
            "X_Y_3",
            "X_Y_3",
            false,
            false,
        ),
        (
            "laser_grid_one_spad",
            capture(
                grid(3, 2, 0.0),
                PointSet::single(DVec3::ZERO),
                Pairing::Product,
            ),
            "T_Lx_Ly_Sx_Sy",
            "X_Y_3",
            "X_Y_3",
            false,
            false,
        ),
        (
            "exhaustive",
            capture(grid(2, 3, 0.0), grid(3, 2, 0.0), Pairing::Product),
            "T_Lx_Ly_Sx_Sy",
            "X_Y_3",
            "X_Y_3",
            false,
            false,
        ),
        (
            "unstructured_confocal",
            capture(list(5), list(5), Pairing::Paired),
            "T_Si",
            "N_3",
            "N_3",
            true,
            true,
        ),
        (
            "unstructured_single",
            capture(list(1), list(5), Pairing::Product),
            "T_Si",
            "N_3",
            "N_3",
            false,
            false,
        ),
        (
            "unstructured_exhaustive",
            capture(list(2), list(4), Pairing::Product),
            "T_Li_Si",
            "N_3",
            "N_3",
            false,
            false,
        ),
    ];
    let mut paths = Vec::new();
    for (i, (name, c, ..)) in cases.iter().enumerate() {
        let p = dir.join(format!("{name}.hdf5"));
        murk_io::write_capture_compressed(&p, c, if i % 2 == 0 { 0 } else { 4 }).unwrap();
        paths.push(p);
    }
    let script = format!(
        "{EMIT}{}",
        r#"
import os, tal, warnings
for path in sys.argv[1:]:
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        d = tal.io.read_capture(path)
    print('FILE', os.path.basename(path)[:-5])
    r = h5py.File(path, 'r')
    W('H_dtype', r['H'].dtype)
    W('H_format_enum', json.dumps(h5py.check_enum_dtype(r['H_format'].dtype), sort_keys=True).replace(' ', ''))
    W('grid_enum', json.dumps(h5py.check_enum_dtype(r['laser_grid_format'].dtype), sort_keys=True).replace(' ', ''))
    W('bool_dtype', r['t_accounts_first_and_last_bounces'].dtype)
    W('keys', ','.join(sorted(r.keys())))
    N('H', d.H)
    W('H_format', d.H_format.name)
    for side in ('sensor', 'laser'):
        N(side + '_grid_xyz', d.__dict__[side + '_grid_xyz'])
        N(side + '_grid_normals', d.__dict__[side + '_grid_normals'])
        W(side + '_grid_format', d.__dict__[side + '_grid_format'].name)
    for k in ('laser_xyz', 'sensor_xyz'):
        v = getattr(d, k, None)
        if v is None: W(k, 'none')
        else: N(k, v)
    N('delta_t', d.delta_t); N('t_start', d.t_start)
    W('t_acc', type(d.t_accounts_first_and_last_bounces).__name__ + ':' + str(d.t_accounts_first_and_last_bounces))
    W('scene_info', json.dumps(d.scene_info, sort_keys=True).replace(' ', ''))
    W('is_confocal', d.is_confocal())
    W('paired', d.is_laser_paired_to_sensor())
"#
    );
    let args: Vec<&Path> = paths.iter().map(|p| p.as_path()).collect();
    let printed = parse(&run_python(&py, &script, &args));
    for (name, c, hf, lf, sf, confocal, paired) in &cases {
        let f = &printed[*name];
        assert_eq!(f.word("H_dtype"), "float32", "{name}");
        assert_eq!(
            f.word("H_format_enum"),
            r#"{"T_Li_Si":4,"T_Lx_Ly_Sx_Sy":2,"T_Si":3,"T_Sx_Sy":1,"UNKNOWN":0}"#,
            "{name}"
        );
        assert_eq!(f.word("grid_enum"), r#"{"N_3":1,"UNKNOWN":0,"X_Y_3":2}"#);
        assert_eq!(f.word("bool_dtype"), "bool", "{name}");
        for k in f.word("keys").split(',') {
            assert!(murk_io::TAL_FIELDS.contains(&k), "{name}: extra key {k}");
        }
        let (hs, hv) = f.num("H");
        assert_eq!(hs[0], c.time.bins, "{name}");
        assert_eq!(*hv, h_time_first(c), "{name}: H");
        assert_eq!(f.word("H_format"), *hf, "{name}");
        assert_eq!(f.word("laser_grid_format"), *lf, "{name}");
        assert_eq!(f.word("sensor_grid_format"), *sf, "{name}");
        for (set, side) in [(&c.sensor, "sensor"), (&c.illum, "laser")] {
            let (gs, gv) = f.num(&format!("{side}_grid_xyz"));
            assert_eq!(*gv, points_of(set), "{name}: {side}");
            let want_shape = match set.layout {
                PointLayout::Grid { nx, ny } => vec![nx, ny, 3],
                PointLayout::List => vec![set.len(), 3],
            };
            assert_eq!(*gs, want_shape, "{name}: {side} shape");
            assert_eq!(f.num(&format!("{side}_grid_normals")).1, normals_of(set));
        }
        for (k, v) in [("laser_xyz", c.laser_xyz), ("sensor_xyz", c.sensor_xyz)] {
            match v {
                None => assert_eq!(f.word(k), "none", "{name}: {k}"),
                Some(p) => assert_eq!(f.num(k).1, vec![p.x, p.y, p.z], "{name}: {k}"),
            }
        }
        assert_eq!(f.num("delta_t").1, vec![c.time.bin_width_m], "{name}");
        assert_eq!(f.num("t_start").1, vec![c.time.start_m], "{name}");
        let want_bool = if c.t_accounts_first_and_last_bounces {
            "bool_:True"
        } else {
            "bool_:False"
        };
        assert_eq!(f.word("t_acc"), want_bool, "{name}");
        assert_eq!(
            f.word("scene_info"),
            r#"{"name":"murk","values":[1,2.5]}"#,
            "{name}"
        );
        assert_eq!(
            f.word("is_confocal"),
            if *confocal { "True" } else { "False" },
            "{name}"
        );
        assert_eq!(
            f.word("paired"),
            if *paired { "True" } else { "False" },
            "{name}"
        );
    }
    std::fs::remove_dir_all(dir).ok();
}

/// Volumes and `.npy` files murk writes open in h5py/numpy; `.npy` files numpy writes (other
/// dtypes, Fortran order) and MATLAB v5 files scipy writes open in murk.
#[test]
#[ignore = "needs a Python with y-tal and h5py (MURK_PYTHON or .venv; .ci/run makes .venv and runs these with --ignored)"]
fn volumes_npy_and_mat_v5_with_numpy_scipy() {
    let py = python();
    let dir = tmpdir("c");
    let vol: Vec<f32> = (0..2 * 3 * 4).map(|i| i as f32 * 0.25).collect();
    let attrs = [
        ("method", murk_io::AttrValue::Text("phasor fields".into())),
        ("wavelength_m", murk_io::AttrValue::Num(0.0625)),
    ];
    let (x, y, z) = ([0.0, 0.5], [-1.0, 0.0, 1.0], [1.0, 1.25, 1.5, 1.75]);
    let volume = murk_core::Volume {
        x: murk_core::Axis::new(0.0, 0.5, 2),
        y: murk_core::Axis::new(-1.0, 1.0, 3),
        z: murk_core::Axis::new(1.0, 1.75, 4),
    };
    assert_eq!(
        (volume.x.values(), volume.y.values()),
        (x.to_vec(), y.to_vec())
    );
    assert_eq!(volume.z.values(), z);
    murk_io::write_volume_h5(&dir.join("v.h5"), &volume, &vol, None, &attrs).unwrap();
    murk_io::write_npy_f32(&dir.join("v.npy"), &[2, 3, 4], &vol).unwrap();
    let script = format!(
        "{EMIT}{}",
        r#"
import scipy.io
d = sys.argv[1]
print('FILE volume')
f = h5py.File(d + '/v.h5', 'r')
N('intensity', f['intensity'][()]); W('dtype', f['intensity'].dtype)
N('x', f['x'][()]); N('y', f['y'][()]); N('z', f['z'][()])
W('method', f.attrs['method'].replace(' ', '_') if isinstance(f.attrs['method'], str) else f.attrs['method'].decode().replace(' ', '_'))
N('wavelength_m', f.attrs['wavelength_m'])
a = np.load(d + '/v.npy'); N('npy', a); W('npy_dtype', a.dtype)
a = np.arange(24, dtype=np.float64).reshape(2, 3, 4) / 8
np.save(d + '/f64.npy', a); np.save(d + '/fortran_u16.npy', np.asfortranarray((a * 8).astype('>u2')))
np.save(d + '/i32.npy', (a * -8).astype(np.int32))
rect = (np.arange(4 * 4 * 6) % 7).astype(np.uint16).reshape(4, 4, 6)
scipy.io.savemat(d + '/lct.mat', {'rect_data': rect, 'width': 0.4})
scipy.io.savemat(d + '/lct_c.mat', {'rect_data': rect, 'width': 0.4}, do_compression=True)
print('FILE rect'); N('rect_data', rect)
"#
    );
    let printed = parse(&run_python(&py, &script, &[&dir]));
    let f = &printed["volume"];
    let as64 = |v: &[f32]| v.iter().map(|&a| a as f64).collect::<Vec<_>>();
    assert_eq!(*f.num("intensity"), (vec![2, 3, 4], as64(&vol)));
    assert_eq!(f.word("dtype"), "float32");
    assert_eq!(f.num("x").1, x);
    assert_eq!(f.num("y").1, y);
    assert_eq!(f.num("z").1, z);
    assert_eq!(f.word("method"), "phasor_fields");
    assert_eq!(f.num("wavelength_m").1, vec![0.0625]);
    assert_eq!(*f.num("npy"), (vec![2, 3, 4], as64(&vol)));
    assert_eq!(f.word("npy_dtype"), "float32");

    let want: Vec<f32> = (0..24).map(|i| i as f32 / 8.0).collect();
    let (s, v) = murk_io::read_npy_f32(&dir.join("f64.npy")).unwrap();
    assert_eq!((s, v), (vec![2, 3, 4], want.clone()));
    let (s, v) = murk_io::read_npy_f32(&dir.join("fortran_u16.npy")).unwrap();
    assert_eq!(s, vec![2, 3, 4]);
    assert_eq!(v, (0..24).map(|i| i as f32).collect::<Vec<_>>());
    let (_, v) = murk_io::read_npy_f32(&dir.join("i32.npy")).unwrap();
    assert_eq!(v, (0..24).map(|i| -(i as f32)).collect::<Vec<_>>());

    let (rs, rv) = printed["rect"].num("rect_data");
    for file in ["lct.mat", "lct_c.mat"] {
        let p = dir.join(file);
        let (s, v) = murk_io::read_mat_v5_array(&p, "rect_data").unwrap();
        assert_eq!((&s, &as64(&v)), (rs, rv), "{file}");
        let (s, v) = murk_io::read_mat_v5_array(&p, "width").unwrap();
        assert_eq!((s, v), (vec![1, 1], vec![0.4f32]), "{file}");
        let e = murk_io::read_mat_v5_array(&p, "meas")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("variables present") && e.contains("rect_data") && e.contains("width"),
            "{e}"
        );
        let e = murk_io::read_mat_v73_array(&p, "rect_data")
            .unwrap_err()
            .to_string();
        assert!(e.contains("use read_mat_v5_array"), "{e}");
        let bytes = std::fs::read(&p).unwrap();
        let cut = dir.join("cut.mat");
        std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
        let e = murk_io::read_mat_v5_array(&cut, "rect_data")
            .unwrap_err()
            .to_string();
        assert!(e.contains("cut.mat") && !e.contains('\n'), "{e}");
    }
    std::fs::remove_dir_all(dir).ok();
}

/// murk's Phasor Fields against y-tal's `fbp` (the same virtual pulse, then backprojection) on one
/// synthetic capture and the same voxels: the intensities must correlate at ≥ 0.99.
#[test]
#[ignore = "needs a Python with y-tal and h5py (MURK_PYTHON or .venv; .ci/run makes .venv and runs these with --ignored)"]
fn phasor_fields_match_tal_fbp() {
    let py = python();
    use murk_synth::{add_first_bounce, CaptureLayout, LayoutKind, SynthOptions, Target};
    let layout = CaptureLayout {
        kind: LayoutKind::SinglePointSensorGrid,
        wall_size_m: 1.0,
        grid: 32,
        point: DVec3::ZERO,
        time: TimeAxis {
            start_m: 0.0,
            bin_width_m: 0.005,
            bins: 512,
        },
        laser_xyz: None,
        sensor_xyz: None,
    };
    let mut cap = layout.empty_capture().unwrap();
    let t_letter = murk_synth::t_letter_outline();
    let mut sc = Target::Polygon {
        outline: t_letter,
        offset: [0.0; 2],
        depth_m: 0.7,
        albedo: 1.0,
        spacing_m: 1.0 / 64.0,
    }
    .scatterers()
    .unwrap();
    sc.extend(
        Target::Point {
            pos: DVec3::new(0.3, -0.3, 0.6),
            albedo: 0.02,
        }
        .scatterers()
        .unwrap(),
    );
    add_first_bounce(
        &mut cap,
        &sc,
        &SynthOptions {
            cosines: true,
            ..SynthOptions::default()
        },
    )
    .unwrap();
    let dir = tmpdir("pf-fbp");
    let file = dir.join("t_single.h5");
    murk_io::write_capture(&file, &cap).unwrap();

    let (lambda, cycles) = (4.0 / 32.0, 4.0);
    let sigma = cycles * lambda / 6.0;
    let script = format!(
        r#"
import sys, numpy as np, tal
tal.set_log_level(tal.LogLevel.WARNING)
d = tal.io.read_capture(sys.argv[1])
vol = tal.reconstruct.get_volume_project_rw(d, depths=list(np.linspace(0.55, 0.85, 16)))
r = tal.reconstruct.fbp.solve(d, wl_mean={lambda}, wl_sigma={sigma}, volume_xyz=vol,
    camera_system=tal.enums.CameraSystem.DIRECT_LIGHT, progress=False)
print(' '.join(repr(float(v)) for v in (np.abs(r) ** 2).ravel()))
"#
    );
    let out = run_python(&py, &script, &[&file]);
    let tal_i: Vec<f64> = out.split_whitespace().map(|v| v.parse().unwrap()).collect();

    let c = 0.5 - 0.5 / 32.0;
    let vol = murk_core::Volume {
        x: murk_core::Axis::new(-c, c, 32),
        y: murk_core::Axis::new(-c, c, 32),
        z: murk_core::Axis::new(0.55, 0.85, 16),
    };
    let params = murk_recon::PfParams {
        wavelength: murk_recon::Wavelength::Metres(lambda),
        cycles,
        ..Default::default()
    };
    let rec = murk_recon::reconstruct(
        &murk_io::read_capture(&file).unwrap(),
        &vol,
        &params,
        murk_recon::PfForm::Fast,
        &murk_recon::NoProgress,
    )
    .unwrap();
    assert_eq!(tal_i.len(), rec.intensity.len());
    let murk_i: Vec<f64> = rec.intensity.iter().map(|&v| v as f64).collect();
    let corr = pearson(&murk_i, &tal_i);
    eprintln!("PF (murk) vs fbp (y-tal): Pearson correlation of |U|² = {corr:.5}");
    assert!(corr >= 0.99, "correlation {corr}");
    std::fs::remove_dir_all(&dir).ok();
}

fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    sab / (saa * sbb).sqrt()
}
