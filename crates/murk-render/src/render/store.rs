//! The one render that stores its captures, as `murk render`, `murk.render` and the study run it:
//! outputs refused up front where one would replace an input or cannot be written, the checkpoint
//! kept and resumed, the captures written (each to a temporary file renamed into place) and the
//! checkpoint removed once they are.

use super::checkpoint::{checkpoint_interval, checkpoint_path};
use super::{Plan, RenderOptions};
use crate::scene::Scene;
use murk_core::{Capture, Error, Result};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Duration;

/// Where a render's captures and its checkpoint go.
#[derive(Clone, Copy, Debug)]
pub enum Outputs<'a> {
    /// `murk render`'s and the study's: the captures to `out` (one per albedo of a sweep,
    /// [`render_outputs`]) and the checkpoint beside it, `out.ckpt`, appended every `every_s`
    /// seconds. Without `resume` an old checkpoint is removed as the render starts, so it starts
    /// afresh; `every_s` = 0 keeps none, except that `resume` still reads an existing one (then
    /// appending to it only if the render is stopped or cannot store its captures).
    Beside {
        out: &'a Path,
        resume: bool,
        every_s: f64,
    },
    /// `murk.render`'s: the captures to `out` when given (else only returned), the checkpoint where
    /// the caller names it (none when `None`), resumed when it holds this render's units.
    Named {
        out: Option<&'a Path>,
        checkpoint: Option<&'a Path>,
        every_s: f64,
    },
}

impl Outputs<'_> {
    /// The capture files (none when only returned).
    fn captures(&self, albedos: Option<&[f64]>) -> Vec<PathBuf> {
        match self {
            Outputs::Beside { out, .. } | Outputs::Named { out: Some(out), .. } => {
                render_outputs(out, albedos)
            }
            Outputs::Named { out: None, .. } => Vec::new(),
        }
    }

    /// Refuses a checkpoint that would replace one of `inputs` (or for a named one, an output):
    /// it is replaced or removed as the render goes.
    fn check_checkpoint(&self, inputs: &[&Path], outs: &[PathBuf]) -> Result<()> {
        match *self {
            Outputs::Beside { out, .. } => {
                let ckpt = checkpoint_path(out);
                match inputs.iter().find(|i| murk_io::same_target(i, &ckpt)) {
                    Some(input) => Err(Error::param(format!(
                        "{}: is the render's checkpoint for {} {}; choose another output",
                        input.display(),
                        murk_core::Opt::Out,
                        out.display()
                    ))),
                    None => Ok(()),
                }
            }
            Outputs::Named {
                checkpoint: Some(c),
                ..
            } => {
                if let Some(input) = inputs.iter().find(|i| murk_io::same_target(i, c)) {
                    return Err(Error::param(format!(
                        "{}: the checkpoint would replace the input {}",
                        c.display(),
                        input.display()
                    )));
                }
                match outs.iter().any(|out| murk_io::same_target(c, out)) {
                    true => Err(Error::param(format!(
                        "{}: the checkpoint and the output are the same file",
                        c.display()
                    ))),
                    false => Ok(()),
                }
            }
            Outputs::Named {
                checkpoint: None, ..
            } => Ok(()),
        }
    }

    /// The checkpoint this render reads and appends to, with the interval between appends.
    fn checkpoint(&self) -> Result<Option<(PathBuf, Duration)>> {
        Ok(match *self {
            Outputs::Beside {
                out,
                resume,
                every_s,
            } => {
                let every = checkpoint_interval(every_s)?;
                let path = checkpoint_path(out);
                match (every_s > 0.0, resume && path.exists()) {
                    (true, _) => Some((path, every)),
                    (false, true) => Some((path, Duration::MAX)),
                    (false, false) => None,
                }
            }
            Outputs::Named {
                checkpoint,
                every_s,
                ..
            } => {
                let every = checkpoint_interval(every_s)?;
                checkpoint.map(|c| (c.to_path_buf(), every))
            }
        })
    }

    /// A stale checkpoint the render must not resume from: `out.ckpt` of a render without `resume`.
    fn stale_checkpoint(&self) -> Option<PathBuf> {
        match *self {
            Outputs::Beside {
                out, resume: false, ..
            } => Some(checkpoint_path(out)),
            _ => None,
        }
    }
}

/// A render that stores its captures, checked before any work: plan once, then [`StoredRender::run`].
pub struct StoredRender<'s> {
    plan: Plan<'s>,
    /// The scene file and the files it reads: inputs that no output may replace.
    inputs: Vec<PathBuf>,
    outs: Vec<PathBuf>,
    checkpoint: Option<(PathBuf, Duration)>,
    stale: Option<PathBuf>,
}

impl<'s> StoredRender<'s> {
    /// The render of `scene` (read from `scene_file`; `None` for a scene given as text), plain or a
    /// sweep over `albedos`, into `outputs`. Refuses, before any work, an output that cannot be
    /// written or would replace the scene file or a file the scene reads, a checkpoint that would
    /// replace one of them or an output, a bad sweep and a bad checkpoint interval.
    pub fn new(
        scene: &'s Scene,
        scene_file: Option<&Path>,
        albedos: Option<&[f64]>,
        outputs: Outputs,
    ) -> Result<Self> {
        let owned: Vec<PathBuf> = scene_file
            .map(Path::to_path_buf)
            .into_iter()
            .chain(scene.input_files.iter().cloned())
            .collect();
        let inputs: Vec<&Path> = owned.iter().map(PathBuf::as_path).collect();
        let outs = outputs.captures(albedos);
        for out in &outs {
            murk_io::check_h5_output(out, &inputs)?;
        }
        outputs.check_checkpoint(&inputs, &outs)?;
        // The plan checks a sweep's albedos before anything is written.
        let plan = Plan::with_albedos(scene, albedos)?;
        Ok(StoredRender {
            plan,
            inputs: owned,
            outs,
            checkpoint: outputs.checkpoint()?,
            stale: outputs.stale_checkpoint(),
        })
    }

    /// The plan: its work units and points, the spp that fits a time budget.
    pub fn plan(&self) -> &Plan<'s> {
        &self.plan
    }

    /// The capture files it writes, in the order of the captures.
    pub fn outputs(&self) -> &[PathBuf] {
        &self.outs
    }

    /// The files another output of the same command may not replace: the inputs and the captures.
    pub fn taken(&self) -> Vec<&Path> {
        self.inputs
            .iter()
            .chain(&self.outs)
            .map(PathBuf::as_path)
            .collect()
    }

    /// The checkpoint it keeps (`None`: none).
    pub fn checkpoint(&self) -> Option<&Path> {
        self.checkpoint.as_ref().map(|(p, _)| p.as_path())
    }

    /// The options of a render of `spp`, `seed` and `shard` with this checkpoint.
    pub fn options(&self, spp: u64, seed: u64, shard: Option<(usize, usize)>) -> RenderOptions {
        RenderOptions {
            spp,
            seed,
            shard,
            checkpoint: self.checkpoint.as_ref().map(|c| c.0.clone()),
            checkpoint_every: self.checkpoint.as_ref().map_or(Duration::MAX, |c| c.1),
        }
    }

    /// Renders and writes the captures of `opt` (from [`StoredRender::options`]), then removes the
    /// checkpoint, as [`Plan::render_stored`] does; returns the captures. A stale checkpoint is
    /// removed first.
    pub fn run(
        &self,
        opt: &RenderOptions,
        progress: &(dyn Fn(usize, usize) + Sync),
        stop: &AtomicBool,
    ) -> Result<Vec<Capture>> {
        if let Some(stale) = self.stale.as_deref().filter(|p| p.exists()) {
            std::fs::remove_file(stale).map_err(|e| Error::io(stale, e))?;
        }
        self.plan.render_stored(
            opt,
            &self.outs,
            &|out, cap| murk_io::write_capture(out, cap),
            progress,
            stop,
        )
    }
}

/// The capture files a render to `out` writes: `out`, or one per albedo of a sweep ([`sweep_output`]).
pub fn render_outputs(out: &Path, albedos: Option<&[f64]>) -> Vec<PathBuf> {
    match albedos {
        None => vec![out.to_path_buf()],
        Some(a) => a.iter().map(|&al| sweep_output(out, al)).collect(),
    }
}

/// Where a sweep's capture of `albedo` goes when the render's output is `out`: `-albedo<α>` before the
/// extension (`z.h5` → `z-albedo0.5.h5`; a shard part's `z.part0of4.h5` → `z.part0of4-albedo0.5.h5`).
pub fn sweep_output(out: &Path, albedo: f64) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy())
        .unwrap_or_default();
    // Below 1e-4 in exponent form: Display writes 1e-300 with 300 digits, too long for a file name.
    let albedo = match albedo {
        a if a == 0.0 || a.abs() >= 1e-4 => format!("{a}"),
        a => format!("{a:e}"),
    };
    let name = match out.extension() {
        Some(ext) => format!("{stem}-albedo{albedo}.{}", ext.to_string_lossy()),
        None => format!("{stem}-albedo{albedo}"),
    };
    out.with_file_name(name)
}
