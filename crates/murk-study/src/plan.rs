//! The study as data: figure cells (what to reconstruct and compare) over render tasks (what to
//! simulate), each task keyed by the fingerprint of its resolved scene so finished work is found again.

use crate::spec::{CellSpec, NO_MEDIUM};
use murk_core::{Error, Result};
use murk_render::{fingerprint, render_outputs, Overrides, Scene};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// How big the study is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Scale {
    /// 64² laser points, 1 200 bins: the whole study in minutes on a laptop.
    Quick,
    /// The paper's 128² laser points × 4096 bins.
    Paper,
}

impl Scale {
    /// `quick` or `paper`.
    pub fn parse(s: &str) -> Result<Scale> {
        match s.trim() {
            "quick" => Ok(Scale::Quick),
            "paper" => Ok(Scale::Paper),
            _ => Err(Error::param(format!(
                "scale '{s}': expected quick or paper"
            ))),
        }
    }

    /// The name `parse` reads: `quick` or `paper`.
    pub fn name(self) -> &'static str {
        match self {
            Scale::Quick => "quick",
            Scale::Paper => "paper",
        }
    }
}

/// The paper's figures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Figure {
    /// Z letter, no medium.
    Fig3a,
    /// Z letter, μt × α, g = 0.
    Fig3b,
    /// Z letter, μt = 1, g × α.
    Fig3c,
    /// Z letter, μt = 1, α = 0.83, λ ∈ {λ0, 2λ0, 3λ0}.
    Fig4,
    /// Shelf in a room, μt ∈ {0, 1, 1.5}, α = 0.5.
    Fig5,
}

impl Figure {
    pub const ALL: [Figure; 5] = [
        Figure::Fig3a,
        Figure::Fig3b,
        Figure::Fig3c,
        Figure::Fig4,
        Figure::Fig5,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Figure::Fig3a => "fig3a",
            Figure::Fig3b => "fig3b",
            Figure::Fig3c => "fig3c",
            Figure::Fig4 => "fig4",
            Figure::Fig5 => "fig5",
        }
    }

    pub fn parse(s: &str) -> Result<Figure> {
        Figure::ALL
            .into_iter()
            .find(|f| f.name() == s.trim())
            .ok_or_else(|| {
                Error::param(format!(
                    "unknown figure '{s}' (use fig3a, fig3b, fig3c, fig4, fig5)"
                ))
            })
    }

    pub fn caption(self) -> &'static str {
        match self {
            Figure::Fig3a => "Fig. 3a: the Z letter without a medium",
            Figure::Fig3b => "Fig. 3b: the Z letter in fog of increasing density μt (rows) and albedo α (columns), g = 0",
            Figure::Fig3c => "Fig. 3c: the Z letter in fog of anisotropy g (rows) and albedo α (columns), μt = 1 /m",
            Figure::Fig4 => "Fig. 4: the Z letter in fog (μt = 1 /m, α = 0.83) for a longer virtual wavelength λ",
            Figure::Fig5 => "Fig. 5: the shelf in a room filled with fog of increasing density, α = 0.5",
        }
    }
}

/// The hidden scenes of the study.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SceneKind {
    ZLetter,
    Shelf,
}

impl SceneKind {
    pub fn file(self) -> &'static str {
        match self {
            SceneKind::ZLetter => "z-letter.toml",
            SceneKind::Shelf => "shelf.toml",
        }
    }
}

/// A homogeneous medium; μt = 0 is none.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MediumParams {
    /// Extinction coefficient μt (1/m); `mu_t` in plan.json.
    #[serde(rename = "mu_t")]
    pub mu_t_per_m: f64,
    pub albedo: f64,
    pub g: f64,
}

/// The capture format and reconstruction volume of one scene at one scale.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Format {
    pub grid: usize,
    pub bins: usize,
    pub bin_width_m: f64,
    pub start_m: f64,
    pub spp: u64,
    /// Reconstruction volume `x0:x1:nx,y0:y1:ny,z0:z1:nz`.
    pub volume: String,
    /// The paths (m) of the hidden objects' direct returns, where a render's error is measured.
    pub object_window_m: (f64, f64),
}

/// The Z's direct returns: 2 m + 2 m at the centre to 2.81 m + 2.08 m from a grid corner.
const Z_WINDOW: (f64, f64) = (4.0, 4.9);
/// The shelf's and its objects' direct returns: 1.8 m + 1.8 m to a far corner of the back panel and back.
const SHELF_WINDOW: (f64, f64) = (3.6, 5.4);

impl Format {
    /// The study's choice per scene and scale (see `docs/study.md` for why each window is where it is).
    pub fn of(scene: SceneKind, scale: Scale) -> Format {
        // The window starts 1 m of path before the shortest path of any voxel and ends ≥ 1.4 m after the
        // longest, so the band-pass's ripple from either cut does not reach the volume: ≥ 8σ and ≥ 11σ
        // of the longest pulse (Fig. 4's 3λ0 = 0.1875 m; the test below holds twice that σ at quick scale). `tail_share` in the report measures what the fog
        // still carries there.
        match (scene, scale) {
            (SceneKind::ZLetter, Scale::Quick) => Format {
                grid: 64,
                bins: 1200,
                bin_width_m: 0.005,
                start_m: 2.0,
                spp: 256,
                volume: "-0.984375:0.984375:64,-0.984375:0.984375:64,1.5:2.5:41".into(),
                object_window_m: Z_WINDOW,
            },
            (SceneKind::ZLetter, Scale::Paper) => Format {
                grid: 128,
                bins: 4096,
                bin_width_m: 0.0015,
                start_m: 2.0,
                spp: 1024,
                volume: "-0.99:0.99:73,-0.99:0.99:59,1.5:2.5:73".into(),
                object_window_m: Z_WINDOW,
            },
            (SceneKind::Shelf, Scale::Quick) => Format {
                grid: 64,
                bins: 1200,
                bin_width_m: 0.005,
                start_m: 2.0,
                spp: 1024,
                volume: "-0.984375:0.984375:64,-0.984375:0.984375:64,1.5:2.5:41".into(),
                object_window_m: SHELF_WINDOW,
            },
            (SceneKind::Shelf, Scale::Paper) => Format {
                grid: 128,
                bins: 4096,
                bin_width_m: 0.0015,
                start_m: 2.0,
                spp: 256,
                volume: "-0.99:0.99:142,-0.99:0.99:142,1.5:2.5:142".into(),
                object_window_m: SHELF_WINDOW,
            },
        }
    }
}

/// One simulated render (a cell's medium at one seed), rendered as `shards` tasks. Cells whose media
/// differ only in albedo share one render, an albedo sweep, which writes one capture per albedo.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CaptureJob {
    /// Fingerprint of the unsharded render key: names the merged captures (`capture_ids`).
    pub id: String,
    pub scene: SceneKind,
    /// The medium; a sweep's paths are traced with the largest of its albedos.
    pub medium: MediumParams,
    pub seed: u64,
    /// Overrides of the scene file, as `murk render --set` takes them.
    pub set: Vec<String>,
    pub spp: u64,
    /// The albedos a sweep renders from the same paths, one capture each; empty: one capture.
    #[serde(default)]
    pub albedos: Vec<f64>,
    pub tasks: Vec<RenderTask>,
}

impl CaptureJob {
    /// The captures the job writes: its id, or `<id>-albedo<α>` per albedo of a sweep (each named
    /// `renders/<capture id>.h5`).
    pub fn capture_ids(&self) -> Vec<String> {
        let files = self.outputs(Path::new(&self.id));
        files.iter().map(|f| f.display().to_string()).collect()
    }

    /// The files a task whose output is `out` writes: `out`, or one per albedo of a sweep (as
    /// `murk render --albedos` names them).
    pub fn outputs(&self, out: &Path) -> Vec<PathBuf> {
        render_outputs(out, self.sweep())
    }

    /// The sweep's albedos, if the job is one.
    pub fn sweep(&self) -> Option<&[f64]> {
        sweep(&self.albedos)
    }
}

/// A job's albedo list as a sweep: none when empty (plan.json stores a plain job's as `[]`).
fn sweep(albedos: &[f64]) -> Option<&[f64]> {
    (!albedos.is_empty()).then_some(albedos)
}

/// One `murk render` run: a shard of a capture.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RenderTask {
    /// Fingerprint of the task's render key (resolved scene, spp, seed, shard, murk version).
    pub id: String,
    pub shard: Option<(usize, usize)>,
    /// Output path relative to the study folder.
    pub out: PathBuf,
}

/// One picture of a figure: a cell's spec with its capture jobs (its fields read through it, and
/// `plan.json` lists them inline).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Cell {
    #[serde(flatten)]
    pub spec: CellSpec,
    /// The capture job per seed.
    pub captures: Vec<String>,
    /// The same scene without a medium, per seed (PSNR and SSIM compare against it).
    pub reference: Vec<String>,
}

impl std::ops::Deref for Cell {
    type Target = CellSpec;
    fn deref(&self) -> &CellSpec {
        &self.spec
    }
}

impl Cell {
    /// The figure, row and column, e.g. `fig3b μt = 1 α = 0.5` (empty parts left out).
    pub fn label(&self) -> String {
        cell_label(self.figure, &self.row, &self.col)
    }

    /// λ in wall spacings Δc at `scale`: `lambda_factor` × 4. Fig. 4 studies λ against the Z's size, so
    /// there λ0 is the paper scale's 4Δc in metres at every scale (2Δc on the quick scale's 64² grid,
    /// at the grid's Nyquist limit): with the quick scale's own 4Δc, 3λ0 = 0.375 m is half the letter
    /// and images it as one round blob, where the paper's 3λ0 = 0.1875 m still draws the Z.
    pub fn wall_factor(&self, scale: Scale) -> f64 {
        let lambda0 = match self.figure {
            Figure::Fig4 => {
                let grid = |s: Scale| Format::of(self.scene, s).grid as f64;
                4.0 * grid(scale) / grid(Scale::Paper)
            }
            _ => 4.0,
        };
        lambda0 * self.lambda_factor
    }
}

/// Whether `words` occur in `label` as a run of whole words: `μt = 1` picks `fig5 μt = 1` but not
/// `fig5 μt = 1.5`, which a plain substring test would also pick.
fn holds_words(label: &str, words: &str) -> bool {
    let (label, words): (Vec<&str>, Vec<&str>) = (
        label.split_whitespace().collect(),
        words.split_whitespace().collect(),
    );
    !words.is_empty() && label.windows(words.len()).any(|w| w == words)
}

/// A cell's label as progress and `--cell` show it: the figure, its row and column, each once.
pub(crate) fn cell_label(figure: Figure, row: &str, col: &str) -> String {
    [figure.name(), row, col]
        .iter()
        .filter(|p| !p.is_empty())
        .copied()
        .collect::<Vec<_>>()
        .join(" ")
}

/// The whole study: cells over capture jobs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StudyPlan {
    pub scale: Scale,
    pub seeds: u64,
    pub shards: usize,
    pub scenes_dir: PathBuf,
    pub cells: Vec<Cell>,
    pub captures: Vec<CaptureJob>,
}

/// What the user asks for.
#[derive(Clone, Debug)]
pub struct StudyOptions {
    pub scale: Scale,
    pub only: Vec<Figure>,
    /// Only cells whose label (`fig3b μt = 1 α = 0.5`) holds one of these as whole words; empty: all.
    pub cells: Vec<String>,
    pub seeds: u64,
    pub shards: usize,
    /// Paths per laser point; default: the scale's.
    pub spp: Option<u64>,
    /// Where `z-letter.toml` and `shelf.toml` are.
    pub scenes_dir: PathBuf,
}

pub const ALBEDOS: [f64; 5] = [0.15, 0.33, 0.5, 0.67, 0.83];

fn fmt_num(v: f64) -> String {
    let s = format!("{v}");
    if s.contains('.') || s.contains('e') {
        s
    } else {
        format!("{s}.0")
    }
}

impl StudyPlan {
    pub fn new(opt: &StudyOptions) -> Result<StudyPlan> {
        if opt.seeds == 0 || opt.seeds > 64 {
            return Err(Error::param(format!(
                "seeds must be in 1..=64, got {}",
                opt.seeds
            )));
        }
        if let Some(spp) = opt
            .spp
            .filter(|s| !(1..=murk_core::Limits::MAX_SPP).contains(s))
        {
            return Err(Error::param(format!(
                "spp must be in 1..={}, got {spp}",
                murk_core::Limits::MAX_SPP
            )));
        }
        if opt.shards == 0 || opt.shards > 1024 {
            return Err(Error::param(format!(
                "shards must be in 1..=1024, got {}",
                opt.shards
            )));
        }
        let mut plan = StudyPlan {
            scale: opt.scale,
            seeds: opt.seeds,
            shards: opt.shards,
            scenes_dir: opt.scenes_dir.clone(),
            cells: Vec::new(),
            captures: Vec::new(),
        };
        let none = NO_MEDIUM;
        let mut cells: Vec<CellSpec> = Figure::ALL
            .into_iter()
            .filter(|f| opt.only.is_empty() || opt.only.contains(f))
            .flat_map(Figure::cells)
            .collect();
        cells.retain(|c| {
            opt.cells.is_empty()
                || opt
                    .cells
                    .iter()
                    .any(|k| holds_words(&cell_label(c.figure, &c.row, &c.col), k))
        });
        if cells.is_empty() {
            return Err(Error::param(format!(
                "no cell of the study matches {:?} (labels look like 'fig3b μt = 1 α = 0.5')",
                opt.cells
            )));
        }
        // Before anything is written, so that a mistyped folder leaves no plan behind.
        if !opt.scenes_dir.is_dir() {
            return Err(Error::param(format!(
                "{}: no such scenes folder (the study reads z-letter.toml and shelf.toml from it; murk's own are in its repository's scenes/)",
                opt.scenes_dir.display()
            )));
        }
        // Only the scenes the chosen cells render.
        for scene in [SceneKind::ZLetter, SceneKind::Shelf] {
            let used = cells.iter().any(|c| c.scene == scene);
            if used && !opt.scenes_dir.join(scene.file()).is_file() {
                return Err(Error::param(format!(
                    "{}: no {} in this scenes folder",
                    opt.scenes_dir.display(),
                    scene.file()
                )));
            }
        }
        // Cells whose fog differs only in albedo share one render, an albedo sweep: its paths do not
        // depend on the albedo, so the tracing is paid once per row (docs/study.md).
        let mut sweeps: Vec<((SceneKind, u64, u64), Vec<f64>)> = Vec::new();
        for c in cells.iter().filter(|c| c.medium.mu_t_per_m > 0.0) {
            let (scene, m) = (c.scene, &c.medium);
            let key = (scene, m.mu_t_per_m.to_bits(), m.g.to_bits());
            match sweeps.iter_mut().find(|(k, _)| *k == key) {
                Some((_, a)) if !a.contains(&m.albedo) => a.push(m.albedo),
                Some(_) => {}
                None => sweeps.push((key, vec![m.albedo])),
            }
        }
        sweeps
            .iter_mut()
            .for_each(|(_, a)| a.sort_by(f64::total_cmp));
        let sweep_of = |scene: SceneKind, m: MediumParams| -> Vec<f64> {
            let key = (scene, m.mu_t_per_m.to_bits(), m.g.to_bits());
            sweeps
                .iter()
                .find(|(k, a)| *k == key && a.len() > 1)
                .map_or_else(Vec::new, |(_, a)| a.clone())
        };
        for spec in cells {
            let (scene, medium) = (spec.scene, spec.medium);
            let albedos = sweep_of(scene, medium);
            let captures = (0..opt.seeds)
                .map(|s| plan.capture(opt, scene, medium, &albedos, s))
                .collect::<Result<_>>()?;
            let reference = (0..opt.seeds)
                .map(|s| plan.capture(opt, scene, none, &[], s))
                .collect::<Result<_>>()?;
            plan.cells.push(Cell {
                spec,
                captures,
                reference,
            });
        }
        Ok(plan)
    }

    /// The overrides that make a scene file into one capture of the study.
    fn overrides(opt: &StudyOptions, scene: SceneKind, m: MediumParams) -> Vec<String> {
        let f = Format::of(scene, opt.scale);
        vec![
            format!("capture.grid=[{0}, {0}]", f.grid),
            format!("capture.bins={}", f.bins),
            format!("capture.bin_width={}", fmt_num(f.bin_width_m)),
            format!("capture.start={}", fmt_num(f.start_m)),
            format!("medium.mu_t={}", fmt_num(m.mu_t_per_m)),
            format!("medium.albedo={}", fmt_num(m.albedo)),
            format!("medium.g={}", fmt_num(m.g)),
        ]
    }

    /// The capture of (scene, medium, seed), its job added once (a sweep over `albedos` where there
    /// are any); returns the capture's id.
    fn capture(
        &mut self,
        opt: &StudyOptions,
        scene: SceneKind,
        medium: MediumParams,
        albedos: &[f64],
        seed: u64,
    ) -> Result<String> {
        // A sweep traces with its largest albedo, so every other one scales contributions down.
        let traced = MediumParams {
            albedo: albedos.iter().copied().fold(medium.albedo, f64::max),
            ..medium
        };
        let set = StudyPlan::overrides(opt, scene, traced);
        let resolved = load_scene(&opt.scenes_dir, scene, &set)?;
        let render = murk_render::Plan::with_albedos(&resolved, sweep(albedos))?;
        let spp = opt.spp.unwrap_or(Format::of(scene, opt.scale).spp);
        let id = format!("{:016x}", fingerprint(&render.key(spp, seed, None)));
        // A plain job's one capture, or the sweep's capture of this medium's albedo.
        let capture_id = |job: &CaptureJob| {
            let k = match job.sweep() {
                None => 0,
                Some(a) => (a.iter().position(|a| *a == medium.albedo))
                    .expect("a sweep holds the albedo of every cell it serves"),
            };
            job.capture_ids()[k].clone()
        };
        if let Some(job) = self.captures.iter().find(|c| c.id == id) {
            return Ok(capture_id(job));
        }
        // No more shards than the render has work units: each shard must hold one.
        let n = opt.shards.min(render.n_units());
        let tasks = (0..n)
            .map(|i| {
                let shard = (n > 1).then_some((i, n));
                let tid = format!("{:016x}", fingerprint(&render.key(spp, seed, shard)));
                let out = match shard {
                    None => PathBuf::from(format!("renders/{id}.h5")),
                    Some(_) => PathBuf::from(format!("renders/{id}.part{i}of{n}.h5")),
                };
                RenderTask {
                    id: tid,
                    shard,
                    out,
                }
            })
            .collect();
        let job = CaptureJob {
            id,
            scene,
            medium: traced,
            seed,
            set,
            spp,
            albedos: albedos.to_vec(),
            tasks,
        };
        let capture = capture_id(&job);
        self.captures.push(job);
        Ok(capture)
    }

    /// Keeps the cells `keep` accepts and the jobs they use (a reduced study).
    pub fn retain_cells(&mut self, keep: impl Fn(&Cell) -> bool) {
        self.cells.retain(keep);
        let used: std::collections::HashSet<&String> = self
            .cells
            .iter()
            .flat_map(|c| c.captures.iter().chain(&c.reference))
            .collect();
        self.captures
            .retain(|j| j.capture_ids().iter().any(|id| used.contains(id)));
    }

    /// The job that writes capture `id`.
    pub fn job(&self, id: &str) -> &CaptureJob {
        self.captures
            .iter()
            .find(|c| c.capture_ids().iter().any(|k| k == id))
            .expect("cells name captures of the same plan")
    }

    pub fn n_tasks(&self) -> usize {
        self.captures.iter().map(|c| c.tasks.len()).sum()
    }

    /// One `murk render` command per task that `keep` (given the job and the task's index) keeps,
    /// for any executor, running `program` (the murk binary); a later `murk experiment` picks their
    /// outputs up. Paths are absolute, so the commands run from any folder.
    pub fn task_commands(
        &self,
        dir: &Path,
        program: &Path,
        keep: impl Fn(&CaptureJob, usize) -> bool,
    ) -> Vec<String> {
        let (scenes, dir) = (absolute(&self.scenes_dir), absolute(dir));
        // Each line makes the renders' folder itself: listing the tasks writes nothing.
        let mkdir = format!("mkdir -p {} && ", shell(&dir.join("renders")));
        let mut out = Vec::new();
        for c in &self.captures {
            for (k, t) in c.tasks.iter().enumerate() {
                if !keep(c, k) {
                    continue;
                }
                let mut cmd = format!(
                    "{mkdir}{} render {} --out {} --spp {} --seed {}",
                    shell(program),
                    shell(&scenes.join(c.scene.file())),
                    shell(&dir.join(&t.out)),
                    c.spp,
                    c.seed
                );
                if let Some((i, n)) = t.shard {
                    cmd.push_str(&format!(" --shard {i}/{n}"));
                }
                if !c.albedos.is_empty() {
                    let a: Vec<String> = c.albedos.iter().map(|a| a.to_string()).collect();
                    cmd.push_str(&format!(" --albedos {}", a.join(",")));
                }
                for s in &c.set {
                    cmd.push_str(&format!(" --set '{s}'"));
                }
                cmd.push_str(" --resume --quiet");
                out.push(cmd);
            }
        }
        out
    }
}

/// `p` from the root (as the working folder makes it), so that a task's paths hold wherever it runs.
pub fn absolute(p: &Path) -> PathBuf {
    std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf())
}

fn shell(p: &Path) -> String {
    let s = p.display().to_string();
    if s.chars()
        .all(|c| c.is_ascii_alphanumeric() || "/._-+".contains(c))
    {
        s
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

/// The scene file of `scene` with the study's overrides.
pub fn load_scene(dir: &Path, scene: SceneKind, set: &[String]) -> Result<Scene> {
    Scene::load(
        &dir.join(scene.file()),
        &Overrides {
            set: set.to_vec(),
            ..Overrides::default()
        },
    )
}

#[cfg(test)]
mod tests;
