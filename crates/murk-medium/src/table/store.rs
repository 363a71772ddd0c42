//! A table kept in a folder: rendered once per geometry and read back by every later estimate of
//! a capture of that geometry, in this process or another (`murk medium --table-cache DIR`). Its
//! renders are most of an estimate's cost (docs/medium.md).

use super::{node_values, table_scene, Reduction, ResponseTable};
use crate::EstimateOptions;
use murk_core::{Capture, Error, Result};
use std::path::{Path, PathBuf};

/// The first line of a table file, before its key.
const MAGIC: &str = "murk medium table 1";

/// The table for `cap` from `dir` when a file there was built for the same medium-only scene,
/// renderer, nodes, rings and time axis; else built and written there. A file that does not read
/// back whole (an interrupted write, another version) is built again and replaced.
pub fn load_or_build(
    dir: &Path,
    scene_text: &str,
    cap: &Capture,
    opt: &EstimateOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<ResponseTable> {
    let (key, path) = file_for(dir, scene_text, cap, opt)?;
    if let Some(values) = read(&path, key) {
        let (mu_t_per_m, g, albedos) = node_values(opt);
        let table = ResponseTable {
            mu_t_per_m,
            g,
            albedos,
            reduction: Reduction::of(cap, opt.table.rings),
            spec: opt.table.clone(),
            built_for: (scene_text.to_string(), cap.time, opt.clone()),
            values,
        };
        if table.values.len() == table.expected_len() {
            return Ok(table);
        }
    }
    let table = ResponseTable::build(scene_text, cap, opt, progress)?;
    write(&path, key, &table.values)?;
    Ok(table)
}

/// The key of the table that serves `cap`, and its file in `dir`. The key holds what the renders
/// depend on (the renderer's key of the medium-only scene, spp, forward fog's spp and seed, with its estimator's
/// revision and murk's version; the scene's key names the medium's kind, a height fog's scale and a
/// grid's cells by their hash), the nodes, and what the reduction depends on (the capture's
/// separations and time axis).
fn file_for(
    dir: &Path,
    scene_text: &str,
    cap: &Capture,
    opt: &EstimateOptions,
) -> Result<(u64, PathBuf)> {
    let spec = &opt.table;
    let scene = table_scene(scene_text, cap, spec, Vec::new())?;
    let text = format!(
        "{}{}\nnodes = {:?}\nreduction = {:?}\ntime = {:?}",
        murk_render::render_key(&scene, spec.spp, spec.seed, None),
        // Named only where it differs: tables of one spp keep their files.
        if spec.forward_spp == spec.spp {
            String::new()
        } else {
            format!("\nforward_spp = {}", spec.forward_spp)
        },
        node_values(opt),
        Reduction::of(cap, opt.table.rings),
        (
            cap.time.start_m.to_bits(),
            cap.time.bin_width_m.to_bits(),
            cap.time.bins
        ),
    );
    let key = murk_render::fingerprint(&text);
    Ok((key, dir.join(format!("medium-table-{key:016x}.bin"))))
}

/// The values of the table file at `path` if it holds `key` and reads back whole.
fn read(path: &Path, key: u64) -> Option<Vec<f64>> {
    let bytes = std::fs::read(path).ok()?;
    let header = format!("{MAGIC} {key:016x}\n");
    let body = bytes.strip_prefix(header.as_bytes())?;
    if body.len() % 8 != 0 {
        return None;
    }
    Some(
        body.chunks_exact(8)
            .map(|b| f64::from_le_bytes(b.try_into().expect("chunks of 8")))
            .collect(),
    )
}

/// Writes `values` under `key` to `path` atomically (murk-io's temporary-and-rename), so that a
/// reader never sees half a table.
fn write(path: &Path, key: u64, values: &[f64]) -> Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    murk_io::write_atomic(path, |out| {
        let fail = |e: std::io::Error| Error::io(path, e);
        out.write_all(format!("{MAGIC} {key:016x}\n").as_bytes())
            .map_err(fail)?;
        for v in values {
            out.write_all(&v.to_le_bytes()).map_err(fail)?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{capture_with_info, medium_only};
    use murk_core::DensityCells;
    use std::sync::Arc;

    /// A table is kept for one medium shape: homogeneous, each height fog's scale and each grid's
    /// cells have their own key. A grid whose cells the capture does not hold is modelled, and
    /// keyed, as the homogeneous medium.
    #[test]
    fn the_key_names_the_medium_shape() {
        let info = |medium: &str| {
            format!("generator: murk render\nscene: |\n  [relay]\n  kind = \"wall\"\n  size = [1.0, 1.0]\n  [capture]\n  kind = \"confocal\"\n  grid = [2, 2]\n  bins = 4\n  bin_width = 0.01\n  [medium]\n{medium}  mu_t = 1.0\n  min = [-1.0, -1.0, 0.001]\n  max = [1.0, 1.0, 2.0]\n")
        };
        let stored_grid = info("  kind = \"grid\"\n  density = \"p.npy\"\n");
        let grid = |top: f32| Capture {
            medium_density: Some(Arc::new(
                DensityCells::new(&[1, 2, 1], vec![0.5, top]).unwrap(),
            )),
            ..capture_with_info(&stored_grid)
        };
        let key = |cap: &Capture| {
            let text = medium_only(cap).unwrap();
            file_for(Path::new("tables"), &text, cap, &EstimateOptions::default())
                .unwrap()
                .0
        };
        let keys: Vec<u64> = [
            capture_with_info(&info("")),
            capture_with_info(&info("  kind = \"height\"\n  height_scale = 0.5\n")),
            capture_with_info(&info("  kind = \"height\"\n  height_scale = 1.0\n")),
            grid(2.0),
            grid(3.0),
        ]
        .iter()
        .map(key)
        .collect();
        for (i, a) in keys.iter().enumerate() {
            assert!(!keys[i + 1..].contains(a), "{keys:x?}");
        }
        assert_eq!(key(&capture_with_info(&stored_grid)), keys[0]);
    }
}
