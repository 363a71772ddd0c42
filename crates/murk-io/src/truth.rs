//! Ground truth as HDF5: `depth` [nx, ny] f32 (m, NaN where nothing), `object` [nx, ny] i32 (−1 where
//! nothing), lattice axes `x`, `y` (m), and root attributes `bounds_min`, `bounds_max` ("x y z", m) and
//! `object_names` (one per line, indexed by `object`).

use crate::atomic::write_atomic;
use crate::h5;
use hdf5_pure::{AttrValue, FileBuilder};
use murk_core::{Error, GroundTruth, Result};
use std::path::Path;

/// Writes `truth` atomically.
pub fn write_truth_h5(path: &Path, truth: &GroundTruth) -> Result<()> {
    crate::check_h5_name(path)?;
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

/// Reads the depth map, object ids and axes of a file written by [`write_truth_h5`] (names and bounds are
/// left empty: they are for people).
pub fn read_truth_h5(path: &Path) -> Result<GroundTruth> {
    let file = h5::open(path)?;
    let limit = 1 << 30;
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
    Ok(GroundTruth {
        x_m,
        y_m,
        depth_m: dd.iter().map(|&v| v as f32).collect(),
        object: oo.iter().map(|&v| v as i32).collect(),
        object_names: Vec::new(),
        bounds_min_m: [f64::NAN; 3],
        bounds_max_m: [f64::NAN; 3],
    })
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
        let same = |a: f32, b: f32| a == b || (a.is_nan() && b.is_nan());
        assert!(r.depth_m.iter().zip(&t.depth_m).all(|(a, b)| same(*a, *b)));
    }
}
