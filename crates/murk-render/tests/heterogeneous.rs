//! Heterogeneous media: a grid of one density renders what the homogeneous medium of the same σt
//! renders, in expectation (delta-tracked free flights against the closed-form ones); and the shipped
//! `scenes/fog-plume.toml` renders the same bytes on one and two threads and across shards.

use murk_render::{merge, Overrides, Plan, RenderOptions, Scene};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Four laser points in pairs sharing their tails, fog with g = 0.3 around a Z, every distance
/// technique on: `[medium]` lines follow.
const SCENE: &str = r#"
[relay]
kind = "wall"
size = [1.0, 1.0]
[capture]
kind = "laser-grid"
grid = [2, 2]
bins = 64
bin_width = 0.05
[render]
share_tile = 2
equiangular = true
time_samples = 2
[[object]]
shape = "z-letter"
center = [0.0, 0.0, 1.0]
[medium]
albedo = 0.5
g = 0.3
min = [-1.5, -1.5, 0.001]
max = [1.5, 1.5, 2.5]
"#;

fn opts(spp: u64, seed: u64, shard: Option<(usize, usize)>) -> RenderOptions {
    RenderOptions {
        spp,
        seed,
        shard,
        checkpoint: None,
        checkpoint_every: Duration::ZERO,
    }
}

/// Sums of 8-bin windows over every histogram, for `seeds` seeds of the scene with `medium` lines.
fn window_sums(dir: &Path, medium: &str, seeds: u64) -> Vec<Vec<f64>> {
    let s = Scene::from_str(
        &format!("{SCENE}{medium}"),
        &dir.join("test.toml"),
        &Overrides::default(),
    )
    .unwrap();
    let plan = Plan::new(&s);
    (0..seeds)
        .map(|seed| {
            let c = plan
                .render(&opts(2048, seed + 1, None), &|_, _| {})
                .unwrap();
            let mut w = vec![0.0; 8];
            for (i, v) in c.h.iter().enumerate() {
                w[i % 64 / 8] += *v as f64;
            }
            w
        })
        .collect()
}

/// Mean and standard error of the mean, per window, over seeds.
fn mean_se(runs: &[Vec<f64>]) -> Vec<(f64, f64)> {
    let n = runs.len() as f64;
    (0..runs[0].len())
        .map(|w| {
            let m = runs.iter().map(|r| r[w]).sum::<f64>() / n;
            let var = runs.iter().map(|r| (r[w] - m).powi(2)).sum::<f64>() / (n - 1.0);
            (m, (var / n).sqrt())
        })
        .collect()
}

/// A 3 × 3 × 3 grid of density 0.5 at μt 2/m against the homogeneous medium of μt 1/m: every window's
/// mean over 12 seeds (2 048 paths per laser point each) within 4 standard errors (combined, estimated from the seeds) of the other's. The
/// windows' standard errors stay below 3 % of their means, so the test sees a 10 % change of σt, which it
/// checks: a grid of density 0.55 is more than 4 standard errors off in some window.
#[test]
fn constant_density_grid_equals_homogeneous_medium() {
    const SEEDS: u64 = 12;
    let dir = std::env::temp_dir().join(format!("murk-constant-grid-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, d) in [("half.npy", 0.5f32), ("more.npy", 0.55)] {
        murk_io::write_npy_f32(&dir.join(name), &[3, 3, 3], &[d; 27]).unwrap();
    }
    let grid = |file: &str| format!("kind = \"grid\"\ndensity = \"{file}\"\nmu_t = 2.0\n");
    let homogeneous = mean_se(&window_sums(&dir, "mu_t = 1.0\n", SEEDS));
    let same = mean_se(&window_sums(&dir, &grid("half.npy"), SEEDS));
    let more = mean_se(&window_sums(&dir, &grid("more.npy"), SEEDS));
    let z = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).abs() / a.1.hypot(b.1);
    for (w, (h, g)) in homogeneous.iter().zip(&same).enumerate() {
        eprintln!(
            "window {w}: homogeneous {:.4e} ± {:.1e}, grid {:.4e} ± {:.1e}, {:.2} SE apart",
            h.0,
            h.1,
            g.0,
            g.1,
            z(*h, *g)
        );
        assert!(
            h.0 > 0.0 && h.1 < 0.03 * h.0 && g.1 < 0.03 * g.0,
            "window {w}"
        );
        assert!(z(*h, *g) < 4.0, "window {w}");
    }
    let seen = homogeneous
        .iter()
        .zip(&more)
        .map(|(h, m)| z(*h, *m))
        .fold(0.0, f64::max);
    assert!(seen > 4.0, "density 0.55 is at most {seen:.2} SE off");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `scenes/fog-plume.toml` at 8² sensor points in tiles of 2 × 2: one thread, two threads and four
/// shards merged give the same bytes.
#[test]
fn fog_plume_is_bitwise_reproducible() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenes/fog-plume.toml");
    let ov = Overrides {
        grid: Some(8),
        set: vec!["render.share_tile=2".into()],
        ..Overrides::default()
    };
    let s = Scene::load(&path, &ov).unwrap();
    let plan = Plan::new(&s);
    let threads = |n: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap();
        pool.install(|| plan.render(&opts(8, 7, None), &|_, _| {}).unwrap())
    };
    let one = threads(1);
    assert!(one.h.iter().any(|v| *v > 0.0));
    assert_eq!(one.h, threads(2).h);
    let parts: Vec<_> = (0..4)
        .map(|i| {
            let c = plan.render(&opts(8, 7, Some((i, 4))), &|_, _| {}).unwrap();
            (PathBuf::from(format!("part{i}")), c)
        })
        .collect();
    let merged = merge(&parts).unwrap();
    assert_eq!(merged.h, one.h);
    // The capture carries the plume's cells as the scene's file holds them, through the merge too.
    let (shape, cells) = murk_io::read_npy_f32(&path.with_file_name("fog-plume.npy")).unwrap();
    for c in [&one, &merged] {
        let own = c.medium_density.as_deref().unwrap();
        assert_eq!((&own.dims()[..], own.values()), (&shape[..], &cells[..]));
    }
}
