//! The study of Luesia et al. as a plan of independent render tasks, their reconstructions, metrics
//! against the renderer's ground truth, figures and an HTML report.
//!
//! Each of the paper's figures is a spec ([`spec`]): its cells and the findings the report states.
//!
//! ```
//! use murk_study::plan::Figure;
//!
//! // Fig. 3b sweeps three μt by five albedos of the Z letter in fog.
//! let cells = Figure::Fig3b.cells();
//! assert_eq!(cells.len(), 15);
//! assert_eq!((cells[0].row.as_str(), cells[0].col.as_str()), ("μt = 0.5", "α = 0.15"));
//! // Without results, no claim can be judged.
//! assert!(Figure::Fig3b.findings(&[]).is_empty());
//! ```
//!
//! The whole study, quick scale (renders for minutes):
//!
//! ```no_run
//! use murk_study::{plan::{Scale, StudyOptions}, run::Silent};
//! let opt = StudyOptions {
//!     scale: Scale::Quick,
//!     only: vec![],
//!     cells: vec![],
//!     seeds: 1,
//!     shards: 1,
//!     spp: None,
//!     scenes_dir: "scenes".into(),
//! };
//! let index = murk_study::run_study(std::path::Path::new("study"), &opt, &Silent).unwrap();
//! ```

pub mod demo;
mod figure_media;
mod figure_real;
mod figures;
mod format;
pub mod metrics;
pub mod plan;
pub mod render_error;
pub mod report;
pub mod run;
pub mod spec;

pub use demo::demo;
pub use figure_media::figure_media;
pub use figure_real::figure_real;

use murk_core::{Error, Result};
use plan::{StudyOptions, StudyPlan};
use run::{Event, Observer};
use std::path::{Path, PathBuf};

/// A study folder held by one `murk experiment` (or Python) run: two at once would render the same
/// tasks twice and count their CPU twice. The operating system lets it go when the process ends,
/// however it ends.
pub struct FolderLock {
    _file: std::fs::File,
    path: PathBuf,
}

/// A finished (or failed) study leaves no `.lock` behind; the lock itself went with the process's
/// handle, so a study started meanwhile holds its own file.
impl Drop for FolderLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

impl FolderLock {
    fn take(dir: &Path) -> Result<FolderLock> {
        let path = dir.join(".lock");
        let file = std::fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&path)
            .map_err(|e| Error::io(&path, e))?;
        match file.try_lock() {
            Err(std::fs::TryLockError::WouldBlock) => Err(Error::param(format!(
                "{}: another murk study is running in this folder; wait for it to end or choose another folder",
                dir.display()
            ))),
            // A file system without locks (some network and FUSE mounts) still holds a study: the
            // lock is a guard against a mistake, not a condition for running.
            Ok(()) | Err(std::fs::TryLockError::Error(_)) => Ok(FolderLock { _file: file, path }),
        }
    }
}

/// Plans the study, makes `DIR/renders/` for the tasks' outputs, takes the folder and writes
/// `DIR/plan.json`; the folder stays taken while the lock lives.
pub fn prepare(dir: &Path, opt: &StudyOptions) -> Result<(StudyPlan, FolderLock)> {
    let plan = plan_for(dir, opt)?;
    let renders = dir.join("renders");
    murk_io::create_output_dir(&renders)?;
    let lock = FolderLock::take(dir)?;
    // What killed runs left: temporaries of captures, of the report's files and of its plots.
    for sub in ["", "renders", "plots"] {
        let d = dir.join(sub);
        if d.is_dir() {
            murk_io::remove_stale_temporaries(&d)?;
        }
    }
    let path = dir.join("plan.json");
    let json = serde_json::to_string_pretty(&plan)
        .map_err(|e| Error::param(format!("cannot serialise the plan: {e}")))?;
    murk_io::write_atomic(&path, |w| {
        w.write_all(json.as_bytes())
            .map_err(|e| Error::io(&path, e))
    })?;
    Ok((plan, lock))
}

/// The study's plan for folder `dir`, which must be a folder or not exist yet.
fn plan_for(dir: &Path, opt: &StudyOptions) -> Result<StudyPlan> {
    let plan = StudyPlan::new(opt)?;
    if dir.exists() && !dir.is_dir() {
        return Err(Error::param(format!(
            "{}: is a file; the study needs a folder",
            dir.display()
        )));
    }
    Ok(plan)
}

/// The render commands still to run for a study in `dir` (`murk experiment --list-tasks`), each
/// running `program`; writes nothing (each command makes the renders' folder it writes into).
pub fn list_tasks(dir: &Path, opt: &StudyOptions, program: &Path) -> Result<Vec<String>> {
    let plan = plan_for(dir, opt)?;
    Ok(plan.task_commands(dir, program, |job, t| run::pending(dir, job, t)))
}

/// Plans, renders what is missing, reconstructs and scores every cell, and writes the report; returns
/// the path of `index.html`.
pub fn run_study(dir: &Path, opt: &StudyOptions, obs: &dyn Observer) -> Result<PathBuf> {
    let (plan, _lock) = prepare(dir, opt)?;
    run::render_missing(&plan, dir, obs)?;
    let results = run::evaluate(&plan, dir, obs)?;
    obs.event(Event::Step("writing the report"));
    report::write(&plan, &results, dir)
}
