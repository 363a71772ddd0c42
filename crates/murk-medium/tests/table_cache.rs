//! The table kept in a folder (`--table-cache`): read back, it equals the table built in memory, so
//! an estimate from it is the same; a file that does not read back whole is built again.

use murk_core::Capture;
use murk_medium::table::load_or_build;
use murk_medium::{EstimateOptions, ResponseTable, TableSpec};
use murk_render::{Overrides, Plan, RenderOptions, Scene};
use std::path::Path;

/// A small render of the paper's Z in fog: only its geometry and scene description matter here.
fn capture() -> Capture {
    let path = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenes/z-letter.toml"
    ));
    let ov = Overrides {
        grid: Some(4),
        bins: Some(300),
        set: vec!["capture.bin_width=0.0123".into()],
        ..Overrides::default()
    };
    let scene = Scene::load(path, &ov).unwrap();
    let opt = RenderOptions {
        spp: 4,
        seed: 1,
        shard: None,
        checkpoint: None,
        checkpoint_every: std::time::Duration::from_secs(3600),
    };
    Plan::new(&scene).render(&opt, &|_, _| {}).unwrap()
}

fn options(dir: &Path, spp: u64) -> EstimateOptions {
    EstimateOptions {
        table: TableSpec {
            grid: 2,
            spp,
            forward_spp: spp,
            seed: 0,
            mu_t_per_m: vec![0.5, 1.0],
            g: vec![-0.4, 0.4],
            albedos: vec![0.3, 0.6],
            rings: 2,
        },
        table_cache: Some(dir.to_path_buf()),
        ..EstimateOptions::default()
    }
}

#[test]
fn a_kept_table_reads_back_as_built() {
    let dir = std::env::temp_dir().join(format!("murk-table-cache-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    let cap = capture();
    let scene = murk_medium::scene::medium_only(&cap).unwrap();
    let opt = options(&dir, 8);
    let built = ResponseTable::build(&scene, &cap, &opt, &|_, _| {}).unwrap();
    let renders = std::sync::atomic::AtomicUsize::new(0);
    let count = |done: usize, _: usize| {
        if done > 0 {
            renders.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        }
    };
    // Written by the first call, read back (no render) by the second: both equal the built table.
    assert_eq!(
        load_or_build(&dir, &scene, &cap, &opt, &count).unwrap(),
        built
    );
    assert_eq!(renders.load(std::sync::atomic::Ordering::Relaxed), 4);
    let files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(files.len(), 1, "{files:?}");
    assert_eq!(
        load_or_build(&dir, &scene, &cap, &opt, &count).unwrap(),
        built
    );
    assert_eq!(renders.load(std::sync::atomic::Ordering::Relaxed), 4);
    // A truncated file is built again and replaced.
    let len = std::fs::metadata(&files[0]).unwrap().len();
    std::fs::OpenOptions::new()
        .write(true)
        .open(&files[0])
        .unwrap()
        .set_len(len - 3)
        .unwrap();
    assert_eq!(
        load_or_build(&dir, &scene, &cap, &opt, &count).unwrap(),
        built
    );
    assert_eq!(renders.load(std::sync::atomic::Ordering::Relaxed), 8);
    assert_eq!(std::fs::metadata(&files[0]).unwrap().len(), len);
    // Another spp renders other values: another file, not the first one's.
    let other = options(&dir, 4);
    let t = load_or_build(&dir, &scene, &cap, &other, &|_, _| {}).unwrap();
    assert_ne!(t, built);
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 2);
    std::fs::remove_dir_all(&dir).ok();
}
