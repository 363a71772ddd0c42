//! Running the plan: the local executor renders the capture jobs whose files are missing (resuming any
//! checkpoint), then every cell is reconstructed and scored against the renderer's ground truth.

use crate::metrics::{self, IouScores};
use crate::plan::{CaptureJob, Cell, Format, SceneKind, StudyPlan};
use murk_core::{short, Capture, Error, GroundTruth, Result, Volume};
use murk_methods::{Method, Options, Request, VolumeSpec};
use murk_recon::{Compensation, NoProgress, PfForm, PfParams, Wavelength};
use murk_render::{merge, Outputs, StoredRender};
use murk_view::{views, Plane, Views};
use rustfft::num_complex::Complex32;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

/// What the executor reports as it goes.
pub enum Event<'a> {
    /// Task `index` of `total` (1-based) starts: the cell it serves and the estimated seconds left.
    Task {
        index: usize,
        total: usize,
        label: &'a str,
        eta_s: Option<f64>,
    },
    /// Work units of the running task.
    Units { done: usize, total: usize },
    /// A step after rendering (reconstructing a cell, writing the report).
    Step(&'a str),
    /// A line to say once, bar or not (which finished renders are reused).
    Note(&'a str),
}

/// Receives [`Event`]s (a progress bar, a log, nothing).
pub trait Observer: Sync {
    fn event(&self, e: Event);
    /// A flag that stops the running render once set: no unit starts after it, the checkpoint keeps
    /// every finished one for the next run, and the study returns an error.
    fn stop(&self) -> Option<&AtomicBool> {
        None
    }
}

pub struct Silent;
impl Observer for Silent {
    fn event(&self, _: Event) {}
}

/// The file of capture `id` (see [`CaptureJob::capture_ids`]), relative to the study folder.
pub fn capture_path(id: &str) -> PathBuf {
    PathBuf::from(format!("renders/{id}.h5"))
}

/// Whether every capture of `job` is in `dir`.
fn captured(dir: &Path, job: &CaptureJob) -> bool {
    job.capture_ids()
        .iter()
        .all(|id| dir.join(capture_path(id)).exists())
}

/// Whether task `t` of `job` has written its files into `dir`.
fn task_done(dir: &Path, job: &CaptureJob, t: usize) -> bool {
    job.outputs(&dir.join(&job.tasks[t].out))
        .iter()
        .all(|p| p.exists())
}

/// Whether task `t` of `job` still has to run: neither its capture nor its own output is in `dir`.
pub fn pending(dir: &Path, job: &CaptureJob, t: usize) -> bool {
    !captured(dir, job) && !task_done(dir, job, t)
}

/// The CPU seconds that task `t` of `job` has cost, over its interruptions.
fn cpu_path(dir: &Path, job: &CaptureJob, t: usize) -> PathBuf {
    dir.join(&job.tasks[t].out).with_extension("cpu_s")
}

/// A CPU tally's seconds, if the file is there and holds a number.
fn read_seconds(path: &Path) -> Option<f64> {
    std::fs::read_to_string(path).ok()?.trim().parse().ok()
}

/// A task's CPU tally, written as it renders (at most every 10 s) and when it ends, so that a run
/// that is stopped or killed still counts what it spent.
struct Tally {
    path: PathBuf,
    before_s: f64,
    cpu0_s: Option<f64>,
    written: std::sync::Mutex<Instant>,
}

impl Tally {
    /// A task resumed from its checkpoint adds to its tally; one that starts afresh (its capture
    /// rendered again) starts a new one.
    fn start(path: PathBuf, checkpoint: &Path) -> Tally {
        let before_s = if checkpoint.exists() {
            read_seconds(&path).unwrap_or(0.0)
        } else {
            0.0
        };
        Tally {
            path,
            before_s,
            cpu0_s: murk_core::process::cpu_seconds(),
            written: std::sync::Mutex::new(Instant::now()),
        }
    }

    fn write(&self) -> Result<()> {
        let (Some(a), Some(b)) = (self.cpu0_s, murk_core::process::cpu_seconds()) else {
            return Ok(());
        };
        murk_io::write_atomic(&self.path, |w| {
            writeln!(w, "{:.3}", self.before_s + b - a).map_err(|e| Error::io(&self.path, e))
        })
    }

    fn tick(&self) {
        let mut last = self.written.lock().unwrap_or_else(|e| e.into_inner());
        if last.elapsed() >= Duration::from_secs(10) {
            *last = Instant::now();
            // A failed write now is retried at the next tick and at the end, which reports it.
            let _ = self.write();
        }
    }
}

/// Renders every capture job whose file is missing, with all cores; returns how many tasks ran.
pub fn render_missing(plan: &StudyPlan, dir: &Path, obs: &dyn Observer) -> Result<usize> {
    let renders = dir.join("renders");
    murk_io::create_output_dir(&renders)?;
    let missing: Vec<&CaptureJob> = plan.captures.iter().filter(|j| !captured(dir, j)).collect();
    let all_parts =
        |j: &CaptureJob| j.tasks.len() > 1 && (0..j.tasks.len()).all(|t| task_done(dir, j, t));
    // Parts that another executor finished are merged before anything renders.
    for job in &missing {
        if all_parts(job) {
            merge_parts(dir, job)?;
        }
    }
    // Parts of a capture that is already merged (a listed command run again) are not needed.
    for job in plan
        .captures
        .iter()
        .filter(|j| j.tasks.len() > 1 && captured(dir, j))
    {
        for t in &job.tasks {
            for p in job.outputs(&dir.join(&t.out)) {
                let _ = std::fs::remove_file(p);
            }
        }
    }
    let reused = plan.captures.iter().filter(|j| captured(dir, j)).count();
    if reused > 0 {
        obs.event(Event::Note(&format!(
            "{reused} of the plan's {} renders are already in {}: reused",
            plan.captures.len(),
            renders.display()
        )));
    }
    let todo: Vec<(&CaptureJob, usize)> = missing
        .iter()
        .filter(|j| !captured(dir, j))
        .flat_map(|j| (0..j.tasks.len()).map(move |t| (*j, t)))
        .filter(|(j, t)| !task_done(dir, j, *t))
        .collect();
    let labels = job_labels(plan);
    let started = Instant::now();
    for (k, (job, t)) in todo.iter().enumerate() {
        // A stop that came as the last task was writing its captures starts no other.
        if obs
            .stop()
            .is_some_and(|s| s.load(std::sync::atomic::Ordering::Relaxed))
        {
            return Err(Error::param("render stopped"));
        }
        let eta_s =
            (k > 0).then(|| started.elapsed().as_secs_f64() / k as f64 * (todo.len() - k) as f64);
        let mut label = labels
            .get(job.id.as_str())
            .cloned()
            .unwrap_or_else(|| format!("the no-medium reference render of {}", job.scene.file()));
        if let Some((i, n)) = job.tasks[*t].shard {
            label.push_str(&format!(" (shard {i}/{n})"));
        }
        obs.event(Event::Task {
            index: k + 1,
            total: todo.len(),
            label: &label,
            eta_s,
        });
        let out = dir.join(&job.tasks[*t].out);
        let tally = Tally::start(cpu_path(dir, job, *t), &murk_render::checkpoint_path(&out));
        let rendered = run_task(plan, dir, job, *t, obs, &tally);
        // Counted whether the task ended or was stopped; a render's own failure is the one to report.
        let tallied = tally.write();
        rendered?;
        tallied?;
        if all_parts(job) {
            merge_parts(dir, job)?;
        }
    }
    Ok(todo.len())
}

fn run_task(
    plan: &StudyPlan,
    dir: &Path,
    job: &CaptureJob,
    t: usize,
    obs: &dyn Observer,
    tally: &Tally,
) -> Result<()> {
    let task = &job.tasks[t];
    let scene = crate::plan::load_scene(&plan.scenes_dir, job.scene, &job.set)?;
    let out = dir.join(&task.out);
    // Every task resumes its checkpoint, appended every 30 s.
    let outputs = Outputs::Beside {
        out: &out,
        resume: true,
        every_s: 30.0,
    };
    let file = plan.scenes_dir.join(job.scene.file());
    let stored = StoredRender::new(&scene, Some(&file), job.sweep(), outputs)?;
    let never = AtomicBool::new(false);
    stored.run(
        &stored.options(job.spp, job.seed, task.shard),
        &|done, total| {
            tally.tick();
            obs.event(Event::Units { done, total })
        },
        obs.stop().unwrap_or(&never),
    )?;
    Ok(())
}

/// Merges the shard parts of each of `job`'s captures, one capture at a time.
fn merge_parts(dir: &Path, job: &CaptureJob) -> Result<()> {
    for (k, id) in job.capture_ids().iter().enumerate() {
        let parts = job
            .tasks
            .iter()
            .map(|t| {
                let p = job.outputs(&dir.join(&t.out)).swap_remove(k);
                Ok((p.clone(), murk_io::read_capture(&p)?))
            })
            .collect::<Result<Vec<_>>>()?;
        murk_io::write_capture(&dir.join(capture_path(id)), &merge(&parts)?)?;
        for (p, _) in parts {
            let _ = std::fs::remove_file(p);
        }
    }
    Ok(())
}

/// A detected-or-not verdict and depth error for one named object of the scene.
#[derive(Clone, Debug)]
pub struct ObjectScore {
    pub name: String,
    /// More than half of its pixels hold their column's nearest surface within two voxels of their depth.
    pub detected: bool,
    /// The share of its pixels that do.
    pub hit_share: f64,
    /// Median over its pixels of (nearest surface − true) depth.
    pub depth_err_m: f64,
}

/// The numbers of one reconstruction (one seed, one compensation).
#[derive(Clone, Debug)]
pub struct Scores {
    pub iou: IouScores,
    /// Median over the object mask of (reconstructed − true) depth.
    pub depth_err_m: f64,
    pub psnr_db: f64,
    pub ssim: f64,
    pub cnr: f64,
    pub hf_share: f64,
    pub objects: Vec<ObjectScore>,
}

impl Scores {
    /// How many of the scene's objects are detected (NaN for a scene without named objects).
    pub fn objects_detected(&self) -> f64 {
        if self.objects.is_empty() {
            return f64::NAN;
        }
        self.objects.iter().filter(|o| o.detected).count() as f64
    }

    /// The largest |depth error| of the detected objects (NaN when none is detected).
    pub fn worst_object_depth_err_m(&self) -> f64 {
        self.objects
            .iter()
            .filter(|o| o.detected)
            .map(|o| o.depth_err_m.abs())
            .fold(f64::NAN, f64::max)
    }
}

/// A cell's result per compensation: scores per seed, and the first seed's front view for figures.
pub struct CellResult {
    pub cell: Cell,
    pub voxel_dz_m: f64,
    /// The summed histogram's largest value over its last 5 % of bins relative to its peak
    /// ([`Capture::end_level`]; 0 for an all-zero capture), per seed.
    pub tail_share: Vec<f64>,
    /// CPU seconds of the cell's renders (None where an external executor rendered them).
    pub cpu_s: Option<f64>,
    /// CPU seconds this process spent reconstructing and scoring the cell (every method, every seed,
    /// the medium estimate and the no-medium reference where this cell was the first to need them);
    /// None where the platform gives no process CPU time.
    pub scoring_cpu_s: Option<f64>,
    /// Relative L2 error of one seed's capture over the object window, estimated from pairs of seeds
    /// (median over pairs; None with one seed).
    pub render_rel_err: Option<f64>,
    pub by_compensation: Vec<(&'static str, Vec<Scores>, Plane)>,
    /// The medium estimated from each seed's capture for the medium-aware column ([`AWARE`]): μt,
    /// albedo, g; `None` where no medium was detected or the fit failed (the reason in `aware_notes`).
    pub estimated: Vec<Option<[f64; 3]>>,
    pub aware_notes: Vec<String>,
}

/// The medium-aware column's name: the capture's medium estimated from the capture itself
/// (`murk_medium`), its response removed, the gate and window end as `murk reconstruct` sets them,
/// and the paper's K with the *estimated* μt and α.
pub const AWARE: &str = "aware";

/// What progress calls each job: its first cell's label (later inserts win, hence the reversal); for
/// a sweep the row with every albedo it renders, not the first cell's one; for one capture that
/// several cells of a figure reconstruct (Fig. 4's three λ) the capture's medium and those cells.
pub fn job_labels(plan: &StudyPlan) -> HashMap<&str, String> {
    plan.cells
        .iter()
        .rev()
        .flat_map(|c| {
            c.captures.iter().map(move |id| {
                let job = plan.job(id);
                let label = match job.albedos.as_slice() {
                    [_, _, ..] => {
                        let all: Vec<String> = job.albedos.iter().map(|a| a.to_string()).collect();
                        crate::plan::cell_label(
                            c.figure,
                            &c.row,
                            &format!("α = {}", all.join(", ")),
                        )
                    }
                    _ => {
                        let serves: Vec<&str> = plan
                            .cells
                            .iter()
                            .filter(|o| o.figure == c.figure && o.captures.contains(id))
                            .map(|o| o.col.as_str())
                            .collect();
                        if serves.len() > 1 {
                            let m = &job.medium;
                            let mut what =
                                format!("μt = {} α = {}", short(m.mu_t_per_m), short(m.albedo));
                            if m.g != 0.0 {
                                what.push_str(&format!(" g = {}", short(m.g)));
                            }
                            let what = format!("{what}, one capture for {}", serves.join(", "));
                            crate::plan::cell_label(c.figure, &c.row, &what)
                        } else {
                            c.label()
                        }
                    }
                };
                (job.id.as_str(), label)
            })
        })
        .collect()
}

/// Reads capture `id`, refusing a file that holds another render than the plan's: one copied or
/// left there by hand would otherwise be scored as this cell's.
fn load_capture(plan: &StudyPlan, dir: &Path, id: &str) -> Result<Capture> {
    let path = dir.join(capture_path(id));
    // A damaged cache file is the study's own: rendering it again is the remedy.
    let cap = murk_io::read_capture(&path).map_err(|e| match e {
        Error::Format { path, msg } => Error::Format {
            path,
            msg: format!("{msg}; delete it to render it again"),
        },
        e => e,
    })?;
    let (job, k) = plan
        .captures
        .iter()
        .find_map(|j| {
            let k = j.capture_ids().iter().position(|c| c == id)?;
            Some((j, k))
        })
        .ok_or_else(|| Error::param(format!("capture {id} is not one of the plan's")))?;
    let scene = crate::plan::load_scene(&plan.scenes_dir, job.scene, &job.set)?;
    let want =
        murk_render::Plan::with_albedos(&scene, job.sweep())?.scene_infos(job.spp, job.seed, None);
    if cap.scene_info != want[k] {
        return Err(Error::format(
            &path,
            "holds another render than the plan's (its scene_info differs); delete it to render it again",
        ));
    }
    Ok(cap)
}

/// Reconstructs and scores every cell; the captures must exist.
pub fn evaluate(plan: &StudyPlan, dir: &Path, obs: &dyn Observer) -> Result<Vec<CellResult>> {
    // Captures are read when used, one at a time (a paper-scale capture is 268 MB).
    let load = |id: &str| load_capture(plan, dir, id);
    // Front views of the no-medium captures per (capture, λ): every cell of that scene compares with them.
    let mut references: HashMap<(String, u64), Plane> = HashMap::new();
    // Fields of captures that several cells reconstruct at the same λ (Fig. 3c's g = 0 row is Fig. 3b's
    // μt = 1 row), kept only for those.
    let mut uses: HashMap<(String, u64), usize> = HashMap::new();
    for c in &plan.cells {
        for id in &c.captures {
            *uses
                .entry((id.clone(), c.wall_factor(plan.scale).to_bits()))
                .or_default() += 1;
        }
    }
    let mut shared_fields: HashMap<(String, u64), Vec<Complex32>> = HashMap::new();
    // The medium estimate's renders, one table per capture geometry (a scene and scale).
    let tables = &mut Vec::new();
    let mut results = Vec::new();
    for (k, cell) in plan.cells.iter().enumerate() {
        let label = format!(
            "reconstructing {} ({}/{})",
            cell.label(),
            k + 1,
            plan.cells.len()
        );
        obs.event(Event::Step(&label));
        let cpu0_s = murk_core::process::cpu_seconds();
        let fmt = Format::of(cell.scene, plan.scale);
        let volume = Volume::parse(&fmt.volume)?;
        let scene = crate::plan::load_scene(
            &plan.scenes_dir,
            cell.scene,
            &plan.job(&cell.captures[0]).set,
        )?;
        let truth = scene.ground_truth_on(&volume.x.values(), &volume.y.values());
        let mut by_comp: Vec<(&'static str, Vec<Scores>, Option<Plane>)> = Compensation::NAMES
            .iter()
            .map(|c| (*c, Vec::new(), None))
            .collect();
        by_comp.push((AWARE, Vec::new(), None));
        let mut estimated = Vec::new();
        let mut aware_notes = Vec::new();
        let mut tails = Vec::new();
        let mut pair_errors = Vec::new();
        for pair in cell.captures.chunks_exact(2) {
            let (a, b) = (load(&pair[0])?, load(&pair[1])?);
            let mask = crate::render_error::window_mask(&a.time, a.h.len(), fmt.object_window_m);
            pair_errors.push(crate::render_error::split_rel_l2(&a.h, &b.h, &mask));
        }
        for (seed, (id, ref_id)) in cell.captures.iter().zip(&cell.reference).enumerate() {
            let cap = load(id)?;
            tails.push(cap.end_level());
            let wall_factor = cell.wall_factor(plan.scale);
            let field_key = (id.clone(), wall_factor.to_bits());
            let field = match shared_fields.get(&field_key) {
                Some(f) => f.clone(),
                None => {
                    let f = pf_field(&cap, &volume, wall_factor)?;
                    if uses[&field_key] > 1 {
                        shared_fields.insert(field_key, f.clone());
                    }
                    f
                }
            };
            let key = (ref_id.clone(), wall_factor.to_bits());
            if !references.contains_key(&key) {
                let rcap = load(ref_id)?;
                let r = pf_field(&rcap, &volume, wall_factor)?;
                let i = murk_recon::intensity(&rcap, &volume, &r, Compensation::None);
                references.insert(key.clone(), views(&volume, &i).front);
            }
            let reference = &references[&key];
            let a = aware_intensity(&cap, &volume, wall_factor, tables, &dir.join("renders"))?;
            estimated.push(a.estimate);
            aware_notes.extend(a.note);
            let mut aware = Some(a.intensity);
            for (name, scores, first) in by_comp.iter_mut() {
                let m = cell.medium;
                let i = if *name == AWARE {
                    aware.take().expect("one aware column")
                } else {
                    // Only the paper's K reads the albedo.
                    let albedo = (*name == "paper").then_some(m.albedo);
                    let comp = Compensation::named(name, m.mu_t_per_m, albedo)?;
                    murk_recon::intensity(&cap, &volume, &field, comp)
                };
                let v = views(&volume, &i);
                let surfaces =
                    (cell.scene == SceneKind::Shelf).then(|| nearest_surfaces(&volume, &i));
                scores.push(score(
                    &v,
                    surfaces.as_deref(),
                    reference,
                    &truth,
                    volume.z.step(),
                ));
                if seed == 0 {
                    *first = Some(v.front);
                }
            }
        }
        // A job's CPU is its tasks' (shards'); a sweep's is shared equally by the captures it writes.
        let cpu_s = cell
            .captures
            .iter()
            .map(|id| {
                let job = plan.job(id);
                (0..job.tasks.len())
                    .map(|t| read_seconds(&cpu_path(dir, job, t)))
                    .sum::<Option<f64>>()
                    .map(|s| s / job.capture_ids().len() as f64)
            })
            .sum::<Option<f64>>();
        let scoring_cpu_s = cpu0_s
            .zip(murk_core::process::cpu_seconds())
            .map(|(a, b)| b - a);
        results.push(CellResult {
            cell: cell.clone(),
            voxel_dz_m: volume.z.step(),
            tail_share: tails,
            cpu_s,
            scoring_cpu_s,
            render_rel_err: (!pair_errors.is_empty()).then(|| metrics::median(&pair_errors)),
            by_compensation: by_comp
                .into_iter()
                .map(|(n, s, p)| (n, s, p.expect("at least one seed")))
                .collect(),
            estimated,
            aware_notes,
        });
    }
    Ok(results)
}

/// The medium-aware reconstruction of `cap` on `volume`: the medium estimated from the capture (one
/// table of renders per geometry, kept in `tables` and as a file in `cache`, so that a study run
/// again reads it back), then `murk reconstruct`'s pipeline with the
/// medium's response removed, its gate and window end, and the paper's K with the estimate. A capture
/// without a detected medium, or whose fit fails, is reconstructed without K (the note says why).
fn aware_intensity(
    cap: &Capture,
    volume: &Volume,
    wall_factor: f64,
    tables: &mut Vec<murk_medium::ResponseTable>,
    cache: &Path,
) -> Result<Aware> {
    let opt = murk_medium::EstimateOptions {
        table_cache: Some(cache.to_path_buf()),
        ..murk_medium::EstimateOptions::default()
    };
    let scene_text = murk_medium::scene::medium_only(cap).ok();
    let known = scene_text.as_ref().and_then(|t| {
        tables
            .iter()
            .position(|tab| tab.serves(t, cap, &opt))
            .map(|k| tables.swap_remove(k))
    });
    let (estimate, note) = match murk_medium::estimate_with(cap, &opt, known, &|_, _| {}) {
        Ok((murk_medium::Outcome::Fitted(e), table)) => {
            tables.extend(table);
            (Some([e.mu_t_per_m.value, e.albedo.value, e.g.value]), None)
        }
        Ok((murk_medium::Outcome::NoMedium(_), table)) => {
            tables.extend(table);
            (None, None)
        }
        Err(e) => (None, Some(format!("medium estimate failed: {e}"))),
    };
    let compensation = match estimate {
        Some([mu_t_per_m, albedo, _]) => Compensation::Paper { mu_t_per_m, albedo },
        None => Compensation::None,
    };
    let params = PfParams {
        wavelength: Wavelength::WallFactor(wall_factor),
        compensation,
        ..PfParams::default()
    };
    let req = Request {
        volume: VolumeSpec::Given(*volume),
        ..Request::new(Method::named("pf", &Options::from_pf(&params))?)
    };
    let rec = murk_methods::run(cap.clone(), &req, &NoProgress)?;
    Ok(Aware {
        intensity: rec.intensity,
        estimate,
        note,
    })
}

/// One capture's medium-aware reconstruction and the estimate behind it.
struct Aware {
    intensity: Vec<f32>,
    /// μt, albedo, g; `None` where no medium was detected or the fit failed.
    estimate: Option<[f64; 3]>,
    /// Why the fit failed.
    note: Option<String>,
}

/// The PF field (λ = `wall_factor` × Δc, 4 cycles: the paper's synthetic settings).
fn pf_field(cap: &Capture, volume: &Volume, wall_factor: f64) -> Result<Vec<Complex32>> {
    let params = PfParams {
        wavelength: Wavelength::WallFactor(wall_factor),
        ..PfParams::default()
    };
    Ok(murk_recon::field(cap, volume, &params, PfForm::Fast, &NoProgress)?.values)
}

/// A truth lattice in the front view's layout (+x on the left, +y up).
fn front_layout<T: Copy>(truth: &GroundTruth, values: &[T]) -> Vec<T> {
    let [nx, ny] = truth.shape();
    (0..ny)
        .flat_map(|r| (0..nx).map(move |c| values[(nx - 1 - c) * ny + (ny - 1 - r)]))
        .collect()
}

/// Per pixel of the front view, the depth of its column's nearest surface (NaN for none;
/// [`metrics::nearest_surface`]).
fn nearest_surfaces(volume: &Volume, intensity: &[f32]) -> Vec<f64> {
    let (nx, ny, nz) = (volume.x.n, volume.y.n, volume.z.n);
    let mut column = vec![0f32; nz];
    (0..nx * ny)
        .map(|p| {
            // The front view's layout: +x on the left, +y up.
            let (ix, iy) = (nx - 1 - p % nx, ny - 1 - p / nx);
            for (iz, c) in column.iter_mut().enumerate() {
                *c = intensity[volume.index(ix, iy, iz)];
            }
            metrics::nearest_surface(&column).map_or(f64::NAN, |iz| volume.z.at(iz))
        })
        .collect()
}

/// An object is found within this many voxels of its true depth.
const OBJECT_DEPTH_VOXELS: f64 = 2.0;

/// Scores one reconstruction's views; `surfaces` (the shelf's) also scores every named object but
/// the room's walls.
fn score(
    v: &Views,
    surfaces: Option<&[f64]>,
    reference: &Plane,
    truth: &GroundTruth,
    dz_m: f64,
) -> Scores {
    let (front, depth) = (&v.front, &v.depth);
    let ids = front_layout(truth, &truth.object);
    let true_depth = front_layout(truth, &truth.depth_m);
    // The Z is object 0; in the room, everything but the room's walls.
    let room = truth.object_names.iter().position(|n| n == "room");
    let target = |id: i32| id >= 0 && Some(id as usize) != room;
    let mask: Vec<bool> = ids.iter().map(|&id| target(id)).collect();
    let depth_err = |m: &[bool]| {
        let d: Vec<f64> = (0..m.len())
            .filter(|&i| m[i] && depth.values[i].is_finite())
            .map(|i| (depth.values[i] - true_depth[i]) as f64)
            .collect();
        metrics::median(&d)
    };
    let (w, h) = (front.width, front.height);
    let objects = match surfaces {
        None => Vec::new(),
        Some(found) => {
            let true_m: Vec<f64> = true_depth.iter().map(|&d| d as f64).collect();
            let mut names: Vec<&String> = truth
                .object_names
                .iter()
                .filter(|n| n.as_str() != "room")
                .collect();
            names.dedup();
            names
                .into_iter()
                .map(|name| {
                    let m: Vec<bool> = ids
                        .iter()
                        .map(|&id| id >= 0 && truth.object_names[id as usize] == *name)
                        .collect();
                    let d = metrics::detect_object(found, &true_m, &m, OBJECT_DEPTH_VOXELS * dz_m);
                    ObjectScore {
                        name: name.clone(),
                        detected: d.detected,
                        hit_share: d.hit_share,
                        depth_err_m: d.depth_err_m,
                    }
                })
                .collect()
        }
    };
    Scores {
        iou: metrics::iou_scores(&front.values, &mask),
        depth_err_m: depth_err(&mask),
        psnr_db: metrics::psnr(&front.values, &reference.values),
        ssim: metrics::ssim(&front.values, &reference.values, w, h),
        cnr: metrics::cnr(&front.values, &mask),
        hf_share: metrics::high_frequency_share(&front.values, w, h),
        objects,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A task resumed from its checkpoint adds to its CPU tally; one rendered afresh starts anew.
    #[test]
    fn a_tally_adds_only_to_a_resumed_task() {
        let dir = std::env::temp_dir().join(format!("murk-tally-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (path, ckpt) = (dir.join("a.cpu_s"), dir.join("a.h5.ckpt"));
        std::fs::write(&path, "5.000\n").unwrap();
        assert_eq!(Tally::start(path.clone(), &ckpt).before_s, 0.0);
        std::fs::write(&ckpt, "").unwrap();
        let resumed = Tally::start(path.clone(), &ckpt);
        assert_eq!(resumed.before_s, 5.0);
        resumed.write().unwrap();
        let now: f64 = std::fs::read_to_string(&path)
            .unwrap()
            .trim()
            .parse()
            .unwrap();
        assert!((5.0..6.0).contains(&now), "{now}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A quick-scale plan of `figure`'s cells that match `cells` (all when empty), one seed.
    fn quick_plan(figure: crate::plan::Figure, cells: &[&str]) -> StudyPlan {
        StudyPlan::new(&crate::plan::StudyOptions {
            scale: crate::plan::Scale::Quick,
            only: vec![figure],
            cells: cells.iter().map(|c| c.to_string()).collect(),
            seeds: 1,
            shards: 1,
            spp: Some(8),
            scenes_dir: Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes"),
        })
        .unwrap()
    }

    /// A row of Fig. 3b renders five albedos at once: its progress names all five, not the first.
    #[test]
    fn a_sweeps_label_names_every_albedo() {
        let plan = quick_plan(crate::plan::Figure::Fig3b, &["μt = 2"]);
        let labels = job_labels(&plan);
        let sweep = plan.captures.iter().find(|j| j.albedos.len() == 5).unwrap();
        assert_eq!(
            labels[sweep.id.as_str()],
            "fig3b μt = 2 α = 0.15, 0.33, 0.5, 0.67, 0.83"
        );
    }

    /// Fig. 4's three λ reconstruct one capture: its progress says what that capture is (the fog it
    /// renders) and which cells it serves, not the first cell's λ.
    #[test]
    fn a_capture_shared_by_three_wavelengths_is_named_by_its_medium() {
        let plan = quick_plan(crate::plan::Figure::Fig4, &[]);
        let labels = job_labels(&plan);
        let fog = plan
            .captures
            .iter()
            .find(|j| j.medium.mu_t_per_m > 0.0)
            .unwrap();
        assert_eq!(
            labels[fog.id.as_str()],
            "fig4 μt = 1 α = 0.83, one capture for λ = λ0, λ = 2λ0, λ = 3λ0"
        );
    }
}
