//! The study as data: figure cells (what to reconstruct and compare) over render tasks (what to
//! simulate), each task keyed by the fingerprint of its resolved scene so finished work is found again.

use crate::cells::{CellSpec, NO_MEDIUM};
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

/// One picture of a figure: a capture (per seed) reconstructed with one wavelength.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Cell {
    pub figure: Figure,
    pub row: String,
    pub col: String,
    pub scene: SceneKind,
    pub medium: MediumParams,
    /// λ as a multiple of the paper's λ0 = 4Δc ([`Cell::wall_factor`] gives it in Δc).
    pub lambda_factor: f64,
    /// The capture job per seed.
    pub captures: Vec<String>,
    /// The same scene without a medium, per seed (PSNR and SSIM compare against it).
    pub reference: Vec<String>,
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
        for CellSpec {
            figure,
            row,
            col,
            scene,
            medium,
            lambda_factor,
        } in cells
        {
            let albedos = sweep_of(scene, medium);
            let captures = (0..opt.seeds)
                .map(|s| plan.capture(opt, scene, medium, &albedos, s))
                .collect::<Result<_>>()?;
            let reference = (0..opt.seeds)
                .map(|s| plan.capture(opt, scene, none, &[], s))
                .collect::<Result<_>>()?;
            plan.cells.push(Cell {
                figure,
                row,
                col,
                scene,
                medium,
                lambda_factor,
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
mod tests {
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
}
