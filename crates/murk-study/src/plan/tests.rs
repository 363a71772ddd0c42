//! Tests of `plan`.

use super::*;

/// Every format's window keeps a pulse of σ = 8Δc (3λ0 at paper scale; twice Fig. 4's 3λ0 at quick
/// scale, where its λ0 is 2Δc) at least 4σ before the shortest path of any voxel and 5σ after the
/// longest (docs/study.md), with the paths measured from the wall grid's points to each voxel and
/// back to the SPAD at the wall's centre.
#[test]
fn windows_keep_the_longest_pulse_clear_of_every_voxel() {
    use murk_core::{DVec3, Volume};
    for scene in [SceneKind::ZLetter, SceneKind::Shelf] {
        for scale in [Scale::Quick, Scale::Paper] {
            let f = Format::of(scene, scale);
            let dc = 2.0 / f.grid as f64;
            let sigma = 8.0 * dc;
            let edge = 1.0 - dc / 2.0;
            let v = Volume::parse(&f.volume).unwrap();
            let (xs, ys, zs) = (v.x.values(), v.y.values(), v.z.values());
            // Shortest: the nearest plane, from the wall point nearest each voxel.
            let shortest = xs
                .iter()
                .flat_map(|&x| ys.iter().map(move |&y| (x, y)))
                .map(|(x, y)| {
                    let p = DVec3::new(x, y, zs[0]);
                    let near = DVec3::new(x.clamp(-edge, edge), y.clamp(-edge, edge), 0.0);
                    (p - near).length() + p.length()
                })
                .fold(f64::INFINITY, f64::min);
            // Longest: the far plane's corners, from the farthest wall corner.
            let corners = [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)];
            let longest = corners
                .iter()
                .map(|&(sx, sy)| {
                    let p = DVec3::new(
                        sx * xs[xs.len() - 1],
                        sy * ys[ys.len() - 1],
                        zs[zs.len() - 1],
                    );
                    let far = DVec3::new(-sx * edge, -sy * edge, 0.0);
                    (p - far).length() + p.length()
                })
                .fold(0.0, f64::max);
            let end = f.start_m + f.bins as f64 * f.bin_width_m;
            let (before, after) = ((shortest - f.start_m) / sigma, (end - longest) / sigma);
            assert!(
                before >= 4.0 && after >= 5.0,
                "{scene:?} {scale:?}: {before:.2}σ before, {after:.2}σ after"
            );
        }
    }
}

fn options(only: &[Figure], seeds: u64, shards: usize) -> StudyOptions {
    StudyOptions {
        scale: Scale::Quick,
        only: only.to_vec(),
        cells: Vec::new(),
        seeds,
        shards,
        spp: Some(8),
        scenes_dir: Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes"),
    }
}

/// Fig. 4's λ in metres is the same at both scales, so its ratio to the Z's size is the paper's
/// (3λ0 = 0.1875 m against the 0.8 m letter); the other figures keep λ0 = 4Δc of their own grid.
#[test]
fn fig4_keeps_the_papers_wavelength_in_metres() {
    let metres = |scale: Scale, figure: Figure| -> Vec<f64> {
        let mut opt = options(&[figure], 1, 1);
        opt.scale = scale;
        let plan = StudyPlan::new(&opt).unwrap();
        plan.cells
            .iter()
            .map(|c| c.wall_factor(scale) * 2.0 / Format::of(c.scene, scale).grid as f64)
            .collect()
    };
    for (q, p) in metres(Scale::Quick, Figure::Fig4)
        .into_iter()
        .zip(metres(Scale::Paper, Figure::Fig4))
    {
        assert!(
            (q - p).abs() < 1e-12,
            "{q} m at quick scale, {p} m at paper scale"
        );
    }
    assert_eq!(metres(Scale::Paper, Figure::Fig4), [0.0625, 0.125, 0.1875]);
    // The quick grid resolves λ0 = 2Δc (its Nyquist limit), no shorter.
    let quick_lambda0 = metres(Scale::Quick, Figure::Fig4)[0];
    assert!(quick_lambda0 >= 2.0 * 2.0 / 64.0 - 1e-12);
    assert_eq!(metres(Scale::Quick, Figure::Fig3a), [0.125]);
}

/// A scenes folder needs only the scenes of the chosen figures.
#[test]
fn scenes_folder_needs_the_chosen_figures_scenes() {
    let dir = std::env::temp_dir().join(format!("murk-scenes-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let here = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/z-letter.toml");
    std::fs::copy(here, dir.join("z-letter.toml")).unwrap();
    let mut opt = options(&[Figure::Fig3a, Figure::Fig4], 1, 1);
    opt.scenes_dir = dir.clone();
    assert!(StudyPlan::new(&opt).is_ok());
    opt.only = vec![Figure::Fig5];
    let e = StudyPlan::new(&opt).unwrap_err().to_string();
    assert!(e.contains("no shelf.toml in this scenes folder"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
    let e = StudyPlan::new(&opt).unwrap_err().to_string();
    assert!(
        e.contains(": no such scenes folder (the study reads z-letter.toml"),
        "{e}"
    );
}

/// Cells as the paper lays them out; a capture serves every cell that needs it (Fig. 4 and the
/// g = 0 row of Fig. 3c reuse Fig. 3b's μt = 1 renders, every cell's reference is Fig. 3a's), and
/// each row of albedos is one sweep.
#[test]
fn cells_share_captures() {
    let plan = StudyPlan::new(&options(&[], 1, 1)).unwrap();
    let count = |f: Figure| plan.cells.iter().filter(|c| c.figure == f).count();
    assert_eq!(
        Figure::ALL.map(count),
        [1, 15, 15, 3, 3],
        "cells per figure"
    );
    // Labels join the non-empty parts with single spaces (Fig. 3a has no column).
    let labels: Vec<String> = plan.cells.iter().map(Cell::label).collect();
    assert_eq!(labels[0], "fig3a no medium");
    assert!(
        labels.contains(&"fig3b μt = 1 α = 0.5".to_string()),
        "{labels:?}"
    );
    // Fig. 3a, Fig. 3b's three rows, Fig. 3c's g = ±0.7 rows, the shelf's three media.
    assert_eq!(plan.captures.len(), 1 + 3 + 2 + 3);
    let ids: std::collections::HashSet<String> =
        plan.captures.iter().flat_map(|j| j.capture_ids()).collect();
    assert_eq!(ids.len(), 1 + 15 + 10 + 3, "distinct captures");
    let sweeps: Vec<&CaptureJob> = plan
        .captures
        .iter()
        .filter(|j| !j.albedos.is_empty())
        .collect();
    assert_eq!(sweeps.len(), 5);
    assert!(sweeps.iter().all(|j| j.albedos == ALBEDOS
        && j.medium.albedo == 0.83
        && j.set.contains(&"medium.albedo=0.83".to_string())));
    let cell = |f: Figure, row: &str, col: &str| {
        plan.cells
            .iter()
            .find(|c| c.figure == f && c.row == row && c.col == col)
            .unwrap()
            .captures[0]
            .clone()
    };
    assert_eq!(
        cell(Figure::Fig4, "", "λ = 2λ0"),
        cell(Figure::Fig3b, "μt = 1", "α = 0.83")
    );
    assert_eq!(
        cell(Figure::Fig3c, "g = 0", "α = 0.5"),
        cell(Figure::Fig3b, "μt = 1", "α = 0.5")
    );
    assert_ne!(
        cell(Figure::Fig3c, "g = 0.7", "α = 0.5"),
        cell(Figure::Fig3b, "μt = 1", "α = 0.5")
    );
    let z_ref = cell(Figure::Fig3a, "no medium", "");
    assert!(plan
        .cells
        .iter()
        .filter(|c| c.scene == SceneKind::ZLetter)
        .all(|c| c.reference == [z_ref.clone()]));
}

/// Seeds and shards multiply the tasks; each task has its own key and output, and the listed commands
/// carry the overrides, seed and shard.
#[test]
fn tasks_and_commands() {
    let mut plan = StudyPlan::new(&options(&[Figure::Fig3a], 2, 3)).unwrap();
    assert_eq!(plan.captures.len(), 2);
    assert_eq!(plan.n_tasks(), 6);
    let mut ids: Vec<&String> = plan
        .captures
        .iter()
        .flat_map(|c| c.tasks.iter().map(|t| &t.id))
        .collect();
    ids.sort();
    ids.dedup();
    assert_eq!(ids.len(), 6);
    let cmds = plan.task_commands(Path::new("out"), Path::new("murk"), |_, _| true);
    assert_eq!(cmds.len(), 6);
    // Absolute paths: the commands run from any folder.
    let cwd = std::env::current_dir().unwrap();
    assert!(
        cmds[0].contains(&format!("--out {}/out/renders/", cwd.display()))
            && cmds[0].contains(&format!("murk render {}/", cwd.display())),
        "{}",
        cmds[0]
    );
    assert_eq!(
        plan.task_commands(Path::new("out"), Path::new("murk"), |_, t| t == 1)
            .len(),
        2
    );
    assert!(
        cmds[4].contains("--seed 1") && cmds[4].contains("--shard 1/3"),
        "{}",
        cmds[4]
    );
    assert!(
        cmds[0].contains("--set 'medium.mu_t=0.0'")
            && cmds[0].contains("--set 'capture.grid=[64, 64]'")
    );
    assert!(cmds[0].contains(&format!(
        "/out/renders/{}.part0of3.h5 ",
        plan.captures[0].id
    )));
    plan.retain_cells(|_| false);
    assert!(plan.captures.is_empty());
    // A row of Fig. 3b is one task that renders every albedo; one cell alone is a plain render.
    let row = StudyPlan::new(&StudyOptions {
        cells: vec!["μt = 2".into()],
        ..options(&[Figure::Fig3b], 1, 1)
    })
    .unwrap();
    // The sweep and the reference without a medium.
    assert_eq!(row.n_tasks(), 2);
    let cmd = &row.task_commands(Path::new("out"), Path::new("murk"), |_, _| true)[0];
    assert!(cmd.contains("--albedos 0.15,0.33,0.5,0.67,0.83"), "{cmd}");
    let id = &row.captures[0].id;
    assert_eq!(row.cells[2].captures, [format!("{id}-albedo0.5")]);
    assert!(cmd.contains(&format!("/out/renders/{id}.h5 ")), "{cmd}");
    let one = StudyPlan::new(&StudyOptions {
        cells: vec!["μt = 2 α = 0.5".into()],
        ..options(&[Figure::Fig3b], 1, 1)
    })
    .unwrap();
    assert!(one.captures.iter().all(|j| j.albedos.is_empty()));
    assert!(
        !one.task_commands(Path::new("out"), Path::new("murk"), |_, _| true)[0]
            .contains("--albedos")
    );
    assert_eq!(one.cells[0].captures, [one.captures[0].id.clone()]);
    // Every label that progress prints selects its cell, Fig. 4's and 5's (no row) too.
    let all = StudyPlan::new(&options(&Figure::ALL, 1, 1)).unwrap();
    for label in all.cells.iter().map(Cell::label) {
        let picked = StudyPlan::new(&StudyOptions {
            cells: vec![label.clone()],
            ..options(&Figure::ALL, 1, 1)
        })
        .unwrap();
        assert_eq!(picked.cells.len(), 1, "{label}");
        assert_eq!(picked.cells[0].label(), label);
    }
    assert!(StudyPlan::new(&options(&[], 0, 1)).is_err());
    assert!(Figure::parse("fig9")
        .unwrap_err()
        .to_string()
        .contains("fig9"));
}
