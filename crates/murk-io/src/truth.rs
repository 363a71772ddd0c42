//! Ground truth as HDF5: `depth` [nx, ny] f32 (m, NaN where nothing), `object` [nx, ny] i32 (−1 where
//! nothing), lattice axes `x`, `y` (m), and root attributes `bounds_min`, `bounds_max` ("x y z", m),
//! `object_names` (one per line, indexed by `object`) and `murk_crc32` (of all of them, checked on read).

use crate::atomic::write_atomic;
use crate::h5;
use hdf5_pure::{AttrValue, FileBuilder};
use murk_core::{Error, GroundTruth, Result};
use std::path::Path;

/// Writes `truth` atomically.
pub fn write_truth_h5(path: &Path, truth: &GroundTruth) -> Result<()> {
    crate::check_h5_name(path)?;
    check_truth(truth).map_err(|m| Error::param(format!("ground truth: {m}")))?;
    let [nx, ny] = truth.shape();
    let mut fb = FileBuilder::new();
    fb.create_dataset("depth")
        .with_shape(&[nx as u64, ny as u64])
        .with_f32_data(&truth.depth_m);
    fb.create_dataset("object")
        .with_shape(&[nx as u64, ny as u64])
        .with_i32_data(&truth.object);
    fb.create_dataset("x").with_f64_data(&truth.x_m);
    fb.create_dataset("y").with_f64_data(&truth.y_m);
    let xyz = |v: [f64; 3]| AttrValue::String(format!("{} {} {}", v[0], v[1], v[2]));
    fb.set_attr("bounds_min", xyz(truth.bounds_min_m));
    fb.set_attr("bounds_max", xyz(truth.bounds_max_m));
    fb.set_attr(
        "object_names",
        AttrValue::String(truth.object_names.join("\n")),
    );
    fb.set_attr(h5::CRC32_ATTR, AttrValue::U32(truth_crc32(truth)));
    fb.set_attr(
        "convention",
        AttrValue::String(
            "first hidden surface along the relay normal (+z) from each lattice point (x-major)"
                .into(),
        ),
    );
    write_atomic(path, |w| {
        fb.finish_to(w)
            .map_err(|e| Error::format(path, h5::one_line(format!("HDF5 write failed: {e}"))))
    })
}

/// Reads a file written by [`write_truth_h5`]: depth map, object ids, axes, bounds and object names
/// (bounds NaN and names empty where a file has none).
pub fn read_truth_h5(path: &Path) -> Result<GroundTruth> {
    let file = h5::open(path)?;
    let attrs = file.root().attrs().unwrap_or_default();
    let xyz = |name: &str| -> Result<[f64; 3]> {
        let bad = || {
            Error::format(
                path,
                format!("attribute {name} is not three numbers \"x y z\""),
            )
        };
        match attrs.get(name) {
            None => Ok([f64::NAN; 3]),
            Some(AttrValue::String(s)) => {
                let v: Vec<f64> = s
                    .split_whitespace()
                    .map(str::parse)
                    .collect::<std::result::Result<_, _>>()
                    .map_err(|_| bad())?;
                <[f64; 3]>::try_from(v).map_err(|_| bad())
            }
            Some(_) => Err(bad()),
        }
    };
    let object_names = match attrs.get("object_names") {
        Some(AttrValue::String(s)) if !s.is_empty() => s.lines().map(String::from).collect(),
        _ => Vec::new(),
    };
    let limit = crate::tal::read_limit_bytes();
    let real = |name: &str| -> Result<(Vec<usize>, Vec<f64>)> {
        let ds = h5::dataset(path, &file, name)?;
        h5::read_real::<f64>(path, &ds, name, limit)
    };
    let (_, x_m) = real("x")?;
    let (_, y_m) = real("y")?;
    let (ds, dd) = real("depth")?;
    let (os, oo) = real("object")?;
    let want = vec![x_m.len(), y_m.len()];
    if ds != want || os != want {
        return Err(Error::format(
            path,
            format!("depth {ds:?} and object {os:?} must both have shape {want:?}"),
        ));
    }
    let truth = GroundTruth {
        x_m,
        y_m,
        depth_m: dd.iter().map(|&v| v as f32).collect(),
        object: oo.iter().map(|&v| v as i32).collect(),
        object_names,
        bounds_min_m: xyz("bounds_min")?,
        bounds_max_m: xyz("bounds_max")?,
    };
    check_truth(&truth).map_err(|m| Error::format(path, m))?;
    h5::check_crc32(path, attrs.get(h5::CRC32_ATTR), || truth_crc32(&truth))?;
    Ok(truth)
}

/// Whether `path` holds a ground truth's datasets (`depth` and `object`, and no `H`), so that a
/// reader can report what is wrong with it as a ground truth rather than as a capture.
pub fn looks_like_truth(path: &Path) -> bool {
    h5::open(path)
        .and_then(|f| h5::root_datasets(path, &f))
        .is_ok_and(|names| {
            let has = |k: &str| names.iter().any(|n| n == k);
            has("depth") && has("object") && !has("H")
        })
}

/// CRC-32 of what a ground truth file stores, little-endian: depths, object ids, axes, bounds and
/// names.
fn truth_crc32(t: &GroundTruth) -> u32 {
    let mut crc = crc32fast::Hasher::new();
    t.depth_m.iter().for_each(|v| crc.update(&v.to_le_bytes()));
    t.object.iter().for_each(|v| crc.update(&v.to_le_bytes()));
    let f64s = t
        .x_m
        .iter()
        .chain(&t.y_m)
        .chain(&t.bounds_min_m)
        .chain(&t.bounds_max_m);
    f64s.for_each(|v| crc.update(&v.to_le_bytes()));
    crc.update(t.object_names.join("\n").as_bytes());
    crc.finalize()
}

/// What a ground truth must be: axes that increase, depths in front of the relay where an object is
/// seen and NaN where none is, and ids of the named objects.
fn check_truth(t: &GroundTruth) -> std::result::Result<(), String> {
    for (name, axis) in [("x", &t.x_m), ("y", &t.y_m)] {
        if axis.iter().any(|v| !v.is_finite()) || axis.windows(2).any(|w| w[1] <= w[0]) {
            return Err(format!("axis {name} must be finite and increasing"));
        }
    }
    let names = t.object_names.len() as i32;
    for (k, (&d, &o)) in t.depth_m.iter().zip(&t.object).enumerate() {
        let ok = match o {
            -1 => d.is_nan(),
            o => o >= 0 && (names == 0 || o < names) && d.is_finite() && d >= 0.0,
        };
        if !ok {
            return Err(format!(
                "point {k} holds object {o} at depth {d}: an object id of the {names} named, at a finite depth ≥ 0, or −1 with NaN"
            ));
        }
    }
    Ok(())
}

/// What a ground truth holds, as `murk info` prints it: the lattice, the points that see a surface
/// and their depths, each object's share, and the bounds.
pub fn describe_truth(t: &GroundTruth) -> Vec<String> {
    let [nx, ny] = t.shape();
    let span = |v: &[f64]| match (v.first(), v.last()) {
        (Some(a), Some(b)) => format!("{a:.4} to {b:.4} m"),
        _ => "empty".into(),
    };
    let seen: Vec<f32> = t.depth_m.iter().copied().filter(|d| !d.is_nan()).collect();
    let (near, far) = seen
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &d| {
            (a.min(d), b.max(d))
        });
    let mut lines = vec![
        format!(
            "ground truth: {nx} × {ny} lattice points, x {}, y {}",
            span(&t.x_m),
            span(&t.y_m)
        ),
        if seen.is_empty() {
            "hidden surface: seen from no lattice point".into()
        } else {
            format!(
                "hidden surface: seen from {} of {} points, depth {near:.4} to {far:.4} m",
                seen.len(),
                t.depth_m.len()
            )
        },
    ];
    for (id, name) in t.object_names.iter().enumerate() {
        let n = t.object.iter().filter(|&&o| o == id as i32).count();
        lines.push(format!("object {id} ({name}): first surface at {n} points"));
    }
    lines.push(format!(
        "bounds: {:?} to {:?} m",
        t.bounds_min_m, t.bounds_max_m
    ));
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips() {
        let t = GroundTruth {
            x_m: vec![-0.5, 0.5],
            y_m: vec![-1.0, 0.0, 1.0],
            depth_m: vec![1.0, f32::NAN, 2.5, 1.0, 1.5, f32::NAN],
            object: vec![0, -1, 1, 0, 2, -1],
            object_names: vec!["a".into(), "b".into(), "c".into()],
            bounds_min_m: [0.0; 3],
            bounds_max_m: [1.0; 3],
        };
        let p = std::env::temp_dir().join(format!("murk-truth-{}.h5", std::process::id()));
        write_truth_h5(&p, &t).unwrap();
        let r = read_truth_h5(&p).unwrap();
        std::fs::remove_file(&p).unwrap();
        assert_eq!((r.x_m, r.y_m, r.object), (t.x_m, t.y_m, t.object));
        assert_eq!(r.object_names, t.object_names);
        assert_eq!(
            (r.bounds_min_m, r.bounds_max_m),
            (t.bounds_min_m, t.bounds_max_m)
        );
        let same = |a: f32, b: f32| a == b || (a.is_nan() && b.is_nan());
        assert!(r.depth_m.iter().zip(&t.depth_m).all(|(a, b)| same(*a, *b)));
    }

    /// A ground truth that contradicts itself is not written; a written one whose depth is changed
    /// by one bit is refused naming the file and the checksum.
    #[test]
    fn a_bad_or_damaged_truth_is_refused() {
        let t = GroundTruth {
            x_m: vec![-0.5, 0.5],
            y_m: vec![0.0],
            depth_m: vec![2.5, f32::NAN],
            object: vec![0, -1],
            object_names: vec!["a".into()],
            bounds_min_m: [0.0; 3],
            bounds_max_m: [1.0; 3],
        };
        let dir = std::env::temp_dir().join(format!("murk-truth-bad-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("t.h5");
        for (what, bad) in [
            (
                "an unnamed id",
                GroundTruth {
                    object: vec![3, -1],
                    ..t.clone()
                },
            ),
            (
                "no object seen at a depth",
                GroundTruth {
                    object: vec![-1, -1],
                    ..t.clone()
                },
            ),
            (
                "a depth behind the relay",
                GroundTruth {
                    depth_m: vec![-1.0, f32::NAN],
                    ..t.clone()
                },
            ),
            (
                "a decreasing axis",
                GroundTruth {
                    x_m: vec![0.5, -0.5],
                    ..t.clone()
                },
            ),
        ] {
            let e = write_truth_h5(&p, &bad).unwrap_err().to_string();
            assert!(e.starts_with("ground truth: "), "{what}: {e}");
            assert!(!p.exists(), "{what}");
        }
        write_truth_h5(&p, &t).unwrap();
        let mut bytes = std::fs::read(&p).unwrap();
        let at = bytes
            .windows(4)
            .position(|w| w == 2.5f32.to_le_bytes())
            .unwrap();
        bytes[at] ^= 1;
        std::fs::write(&p, &bytes).unwrap();
        let e = read_truth_h5(&p).unwrap_err().to_string();
        assert!(
            e.contains("t.h5") && e.contains("do not match the checksum"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
