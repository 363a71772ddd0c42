//! Synthesis, rendering, merging and the study's plan: the library calls behind `murk synth`,
//! `murk render`, `murk merge` and `murk experiment`.

use crate::capture::{Capture, Source};
use crate::{compute, thread_count, to_py, Ticker};
use murk_core::{DVec3, TimeAxis};
use murk_render::{Outputs, Overrides, Scene, StoredRender};
use murk_study::plan::{Figure, Scale, StudyOptions};
use murk_study::run::{Event, Observer};
use murk_synth::{synthesize, CaptureLayout, SynthOptions, Synthesis};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

/// The keywords of `murk.synth`, which are `murk synth`'s flags.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct SynthArgs {
    targets: Vec<String>,
    kind: String,
    wall_size: f64,
    grid: usize,
    point: [f64; 2],
    bins: usize,
    bin_width: f64,
    start: f64,
    laser_xyz: Option<[f64; 3]>,
    sensor_xyz: Option<[f64; 3]>,
    mu_t: f64,
    jitter: f64,
    cosines: bool,
}

/// An analytic capture (first hidden bounce), as `murk synth` makes it; see `murk.synth`.
#[pyfunction]
#[pyo3(signature = (args))]
pub fn synth(py: Python<'_>, args: SynthArgs) -> PyResult<Capture> {
    let s = Synthesis {
        layout: CaptureLayout {
            kind: args.kind.parse().map_err(to_py)?,
            wall_size_m: args.wall_size,
            grid: args.grid,
            point: DVec3::new(args.point[0], args.point[1], 0.0),
            time: TimeAxis {
                start_m: args.start,
                bin_width_m: args.bin_width,
                bins: args.bins,
            },
            laser_xyz: args.laser_xyz.map(DVec3::from_array),
            sensor_xyz: args.sensor_xyz.map(DVec3::from_array),
        },
        targets: args.targets,
        options: SynthOptions {
            cosines: args.cosines,
            mu_t_per_m: args.mu_t,
            jitter_sigma_m: args.jitter,
        },
    };
    let cap = compute(py, None, None, |_| synthesize(&s))?;
    Ok(Capture { cap })
}

/// The keywords of `murk.render` (its scene, threads and progress aside), which are `murk render`'s
/// flags; `text` is the scene's TOML when it was given as text (read as if from `scene`).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct RenderArgs {
    text: Option<String>,
    spp: Option<u64>,
    seed: u64,
    shard: Option<(usize, usize)>,
    set: Vec<String>,
    grid: Option<usize>,
    bins: Option<usize>,
    checkpoint: Option<PathBuf>,
    checkpoint_every: f64,
    out: Option<PathBuf>,
    /// A sweep's albedos (`murk.render_albedos`), else None.
    albedos: Option<Vec<f64>>,
}

impl RenderArgs {
    /// The scene (from `text` when given, read as if from `path`) with these overrides applied.
    fn scene(&self, path: &Path) -> murk_core::Result<Scene> {
        let ov = Overrides {
            grid: self.grid,
            bins: self.bins,
            set: self.set.clone(),
            spelling: murk_core::Spelling::Python,
        };
        match &self.text {
            Some(text) => Scene::from_str(text, path, &ov),
            None => Scene::load(path, &ov),
        }
    }

    /// The render of `scene` (read from `path` unless given as `text`): plain, or a sweep over
    /// `albedos`, its outputs and checkpoint refused before any work where `murk render` would.
    fn stored<'s>(&self, path: &Path, scene: &'s Scene) -> murk_core::Result<StoredRender<'s>> {
        let outputs = Outputs::Named {
            out: self.out.as_deref(),
            checkpoint: self.checkpoint.as_deref(),
            every_s: self.checkpoint_every,
        };
        let file = self.text.is_none().then_some(path);
        StoredRender::new(scene, file, self.albedos.as_deref(), outputs)
    }

    /// The spp of a render of `scene`: the given one, else the scene's.
    fn spp(&self, scene: &Scene) -> u64 {
        self.spp.unwrap_or(scene.settings.spp)
    }
}

/// A Monte Carlo render of a scene, as `murk render` does it: one capture, or one per albedo of
/// `args.albedos` (written to `out` as `murk render --albedos` names them); see `murk.render` and
/// `murk.render_albedos`.
#[pyfunction]
#[pyo3(signature = (scene, args, threads, progress))]
pub fn render(
    py: Python<'_>,
    scene: PathBuf,
    args: RenderArgs,
    threads: Option<i64>,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<Vec<Capture>> {
    let caps = compute(py, progress, threads, |t: &Ticker| {
        let loaded = args.scene(&scene)?;
        let stored = args.stored(&scene, &loaded)?;
        stored.run(
            &stored.options(args.spp(&loaded), args.seed, args.shard),
            &|done, total| t.count(done as u64, total as u64),
            t.stop(),
        )
    })?;
    Ok(caps.into_iter().map(|cap| Capture { cap }).collect())
}

/// Shard `args.shard` of a scene rendered into its checkpoint `args.checkpoint` alone, which then
/// holds every unit of the shard (returns at once when it already does): a part for `assemble`.
#[pyfunction]
#[pyo3(signature = (scene, args, threads, progress))]
pub fn render_part(
    py: Python<'_>,
    scene: PathBuf,
    args: RenderArgs,
    threads: Option<i64>,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<()> {
    compute(py, progress, threads, |t: &Ticker| {
        let loaded = args.scene(&scene)?;
        let stored = args.stored(&scene, &loaded)?;
        stored.plan().render_part(
            &stored.options(args.spp(&loaded), args.seed, args.shard),
            &|done, total| t.count(done as u64, total as u64),
            t.stop(),
        )
    })
}

/// Refuses, without rendering, what a sharded render would refuse only after its tasks: a bad
/// scene or override, spp out of range, more shards than work units, an output `args.out` that
/// cannot be written, a thread count the tasks could not start.
#[pyfunction]
#[pyo3(signature = (scene, args, threads))]
pub fn check_render(
    py: Python<'_>,
    scene: PathBuf,
    args: RenderArgs,
    threads: Option<i64>,
) -> PyResult<()> {
    threads.map(thread_count).transpose()?;
    compute(py, None, None, |_| {
        let loaded = args.scene(&scene)?;
        let stored = args.stored(&scene, &loaded)?;
        stored
            .plan()
            .check(&stored.options(args.spp(&loaded), args.seed, args.shard))
    })
}

/// Refuses a `threads` value before any work: a Dask executor checks it before its cluster starts.
#[pyfunction]
#[pyo3(signature = (threads))]
pub fn check_threads(threads: Option<i64>) -> PyResult<()> {
    threads.map(thread_count).transpose().map(|_| ())
}

/// The captures an unsharded render gives (one, or one per albedo of a sweep), bit for bit, from
/// the parts `render_part` completed (`parts[i]` holds shard i of `len(parts)`), for the same scene,
/// overrides, spp, seed and albedos.
#[pyfunction]
#[pyo3(signature = (scene, args, parts))]
pub fn assemble(
    py: Python<'_>,
    scene: PathBuf,
    args: RenderArgs,
    parts: Vec<PathBuf>,
) -> PyResult<Vec<Capture>> {
    let caps = compute(py, None, None, |_| {
        let loaded = args.scene(&scene)?;
        let stored = args.stored(&scene, &loaded)?;
        stored
            .plan()
            .assemble_all(args.spp(&loaded), args.seed, &parts)
    })?;
    Ok(caps.into_iter().map(|cap| Capture { cap }).collect())
}

/// The files a render to `out` writes: `out`, or one per albedo of a sweep, named as `murk render
/// --albedos` names them.
#[pyfunction]
#[pyo3(signature = (out, albedos))]
pub fn render_outputs(out: PathBuf, albedos: Option<Vec<f64>>) -> Vec<PathBuf> {
    murk_render::render_outputs(&out, albedos.as_deref())
}

/// The capture an unsharded render gives, from all parts of `murk render --shard i/N` (Capture
/// objects or paths, any order); see `murk.merge`.
#[pyfunction]
pub fn merge(py: Python<'_>, parts: Vec<Bound<'_, PyAny>>) -> PyResult<Capture> {
    let sources = parts.iter().map(Source::of).collect::<PyResult<Vec<_>>>()?;
    let cap = compute(py, None, None, |_| {
        let owned = sources
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let name = match s {
                    Source::File(p) => p.clone(),
                    Source::Object(_) => PathBuf::from(format!("<part {i}>")),
                };
                Ok((name, s.owned()?))
            })
            .collect::<murk_core::Result<Vec<_>>>()?;
        murk_render::merge(&owned)
    })?;
    Ok(Capture { cap })
}

/// The keywords of `murk.experiment.plan` and `murk.experiment.run` (their `out`, threads and
/// progress aside), which are `murk experiment paper`'s flags.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct StudyArgs {
    scale: String,
    only: Vec<String>,
    cells: Vec<String>,
    seeds: u64,
    shards: usize,
    spp: Option<u64>,
    scenes: PathBuf,
}

fn study_options(args: StudyArgs) -> PyResult<StudyOptions> {
    let StudyArgs {
        scale,
        only,
        cells,
        seeds,
        shards,
        spp,
        scenes,
    } = args;
    Ok(StudyOptions {
        scale: Scale::parse(&scale).map_err(to_py)?,
        only: only
            .iter()
            .map(|s| Figure::parse(s))
            .collect::<murk_core::Result<_>>()
            .map_err(to_py)?,
        cells,
        seeds,
        shards,
        spp,
        scenes_dir: scenes,
    })
}

/// Plans the study in `out` (writes `plan.json`, makes `renders/`) and returns its render tasks, one
/// dict per `murk experiment paper --list-tasks` line; see `murk.experiment.plan`.
#[pyfunction]
#[pyo3(signature = (out, args))]
pub fn study_plan<'py>(
    py: Python<'py>,
    out: PathBuf,
    args: StudyArgs,
) -> PyResult<Bound<'py, PyList>> {
    let opt = study_options(args)?;
    // Absolute, as the commands are: a task runs from any folder.
    let out = murk_study::plan::absolute(&out);
    let (plan, _lock) = py
        .detach(|| murk_study::prepare(&out, &opt))
        .map_err(to_py)?;
    let scenes = murk_study::plan::absolute(&plan.scenes_dir);
    // The Python package has no murk binary of its own: its commands name the one on PATH.
    let commands = plan.task_commands(&out, std::path::Path::new("murk"), |_, _| true);
    let tasks = PyList::empty(py);
    let mut k = 0;
    for c in &plan.captures {
        for t in &c.tasks {
            let d = PyDict::new(py);
            d.set_item("id", &t.id)?;
            let captures = c.capture_ids();
            let capture_outs: Vec<PathBuf> = (captures.iter())
                .map(|id| out.join(murk_study::run::capture_path(id)))
                .collect();
            d.set_item("captures", captures)?;
            d.set_item("scene", scenes.join(c.scene.file()))?;
            d.set_item("out", out.join(&t.out))?;
            d.set_item("outs", c.outputs(&out.join(&t.out)))?;
            d.set_item("capture_outs", capture_outs)?;
            d.set_item("albedos", &c.albedos)?;
            d.set_item("spp", c.spp)?;
            d.set_item("seed", c.seed)?;
            d.set_item("shard", t.shard)?;
            d.set_item("set", &c.set)?;
            d.set_item("command", &commands[k])?;
            tasks.append(d)?;
            k += 1;
        }
    }
    Ok(tasks)
}

/// The study's progress as `(done, total)` render units; the task and step lines are the CLI's.
struct Units<'a>(&'a Ticker);

impl Observer for Units<'_> {
    fn event(&self, e: Event) {
        match e {
            // A render stops through its flag, which keeps its checkpoint whole; unwinding from
            // inside it would lose the units since the last append.
            Event::Units { done, total } => self.0.count(done as u64, total as u64),
            _ => self.0.check(),
        }
    }
    fn stop(&self) -> Option<&AtomicBool> {
        Some(self.0.stop())
    }
}

/// Runs the study in `out` (reusing finished renders and merging finished shards), writes the figures,
/// metrics and report, and returns the path of `index.html`; see `murk.experiment.run`.
#[pyfunction]
#[pyo3(signature = (out, args, threads, progress))]
pub fn run_study(
    py: Python<'_>,
    out: PathBuf,
    args: StudyArgs,
    threads: Option<i64>,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<PathBuf> {
    let opt = study_options(args)?;
    let dir: &Path = &out;
    compute(py, progress, threads, |t| {
        murk_study::run_study(dir, &opt, &Units(t))
    })
}
