//! `murk-bench --render --only 'paper cells'`: the CPU the paper-scale study needs for every cell's
//! capture at 6 % object-window error (docs/benchmarks.md, "The paper-scale study at 6 %").

use crate::say;
use murk_render::bench::timed_render;
use murk_render::{Plan, Scene};
use murk_study::plan::{load_scene, Format, Scale, StudyOptions, StudyPlan};
use murk_study::render_error::{split_rel_l2, window_mask};
use std::path::Path;

/// The error the study's captures should reach over their object window (the paper's figure).
const TARGET_ERROR: f64 = 0.06;
/// The central rows of the 128² laser grid that are rendered (rows 64–71 of 128, 1 024 points), as
/// in the paper format's own case.
const SHARD: (usize, usize) = (8, 16);
/// The measured spp is the study's spp divided by this.
const SPP_DIVISOR: u64 = 8;

/// Every capture job of the paper-scale study (one seed), rendered on [`SHARD`] at 1/[`SPP_DIVISOR`]
/// of the study's spp (more where that leaves an error above 1) in `runs` pairs of independent seeds. A job's error over its object window is
/// the root mean square of its pairs' errors (each pair's relL2 between the two renders over √2): the
/// mean of squares, not a median, because in forward fog a few pairs carry most of the variance. A
/// sweep's paths serve all its albedos, so its spp to 6 % is its noisiest albedo's. CPU to 6 %
/// extrapolates with error ∝ spp^−½ and CPU ∝ laser points × spp over the whole grid.
pub fn paper_cells(scenes_dir: &Path, runs: usize, quiet: bool) -> anyhow::Result<()> {
    let study = StudyPlan::new(&StudyOptions {
        scale: Scale::Paper,
        only: Vec::new(),
        cells: Vec::new(),
        seeds: 1,
        shards: 1,
        spp: None,
        scenes_dir: scenes_dir.to_path_buf(),
    })?;
    let (mut total_6, mut total_default) = (0.0, 0.0);
    for job in &study.captures {
        let scene = load_scene(scenes_dir, job.scene, &job.set)?;
        let plan = Plan::with_albedos(&scene, job.sweep())?;
        let window = Format::of(job.scene, Scale::Paper).object_window_m;
        let mut spp = (job.spp / SPP_DIVISOR).max(1);
        let (errors, cpu_per_path) = loop {
            let m = measure(&plan, &scene, spp, window, runs.max(1))?;
            // Above 1 the two renders barely share their signal and the pair's estimate of the
            // error breaks down: measure again with more paths, up to the study's own spp.
            if m.0.iter().all(|&e| e <= 1.0) || spp >= job.spp {
                break m;
            }
            spp = (2 * spp).min(job.spp);
        };
        // A NaN (no signal left over the noise) stays NaN.
        let worst = errors
            .iter()
            .fold(0.0, |w: f64, &e| if e > w || e.is_nan() { e } else { w });
        let spp_6 = spp as f64 * (worst / TARGET_ERROR).powi(2);
        let points = plan.n_points() as f64;
        let (cpu_6, cpu_default) = (
            cpu_per_path * points * spp_6,
            cpu_per_path * points * job.spp as f64,
        );
        total_6 += cpu_6;
        total_default += cpu_default;
        let medium = &job.medium;
        let what = match job.sweep() {
            _ if medium.mu_t_per_m == 0.0 => "no medium".to_string(),
            Some(albedos) => format!("μt {} g {} α {:?}", medium.mu_t_per_m, medium.g, albedos),
            None => format!(
                "μt {} g {} α {}",
                medium.mu_t_per_m, medium.g, medium.albedo
            ),
        };
        let shown: Vec<String> = errors.iter().map(|e| format!("{e:.3}")).collect();
        say(
            quiet,
            format!(
                "paper cells: {} {what}: {spp} spp gives object-window relL2 [{}] (rms of {} pairs); 6 % needs {spp_6:.0} spp = {:.2} CPU-hours (the study's {} spp: {:.2})",
                job.scene.file(),
                shown.join(", "),
                runs.max(1),
                cpu_6 / 3600.0,
                job.spp,
                cpu_default / 3600.0
            ),
        );
    }
    say(
        quiet,
        format!(
            "paper cells: the whole paper-scale study (one seed) at 6 % in every cell: {:.1} CPU-hours (at its default spp: {:.2})",
            total_6 / 3600.0,
            total_default / 3600.0
        ),
    );
    Ok(())
}

/// Each capture's object-window error (the rms over `runs` pairs of seeds) at `spp`, and the CPU
/// seconds per traced path.
fn measure(
    plan: &Plan,
    scene: &Scene,
    spp: u64,
    window: (f64, f64),
    runs: usize,
) -> anyhow::Result<(Vec<f64>, f64)> {
    let (mut sq, mut cpu_s, mut paths) = (Vec::new(), 0.0, 0.0);
    for p in 0..runs as u64 {
        let a = timed_render(plan, spp, 2 * p, Some(SHARD))?;
        let b = timed_render(plan, spp, 2 * p + 1, Some(SHARD))?;
        let mask = window_mask(&scene.capture.time, a.h.len(), window);
        let pairs = std::iter::once((&a.h, &b.h)).chain(a.rest.iter().zip(&b.rest));
        sq.resize(1 + a.rest.len(), 0.0);
        for (s, (x, y)) in sq.iter_mut().zip(pairs) {
            *s += split_rel_l2(x, y, &mask).powi(2) / runs as f64;
        }
        cpu_s += a.cpu_s + b.cpu_s;
        paths += a.paths + b.paths;
    }
    Ok((sq.iter().map(|s| s.sqrt()).collect(), cpu_s / paths))
}
