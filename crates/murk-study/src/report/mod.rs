//! The study's outputs: `metrics.csv`, `objects.csv`, a figure grid per figure and compensation, metric
//! plots, and `index.html` tying them together with the parameters and the choices made. One module
//! per job: the CSV tables, the image grids, the plots, the findings (each figure's own in
//! [`crate::spec`]), the provenance and the page, whose pieces (`page`) `murk demo` shares.

mod csv;
mod findings;
mod grids;
mod html;
pub(crate) mod page;
mod plots;
mod provenance;

use crate::plan::{Figure, StudyPlan};
use crate::run::{CellResult, Scores};
use murk_core::{Error, Result};
use murk_view::Plane;
use std::path::{Path, PathBuf};

pub use crate::format::show;
pub use crate::spec::FOUND_IOU;
pub use findings::findings;
pub(crate) use provenance::run_provenance;

/// A metric of [`Scores`]: its column name, a readable label and how to read it.
pub(super) struct Metric {
    pub(super) column: &'static str,
    pub(super) label: &'static str,
    pub(super) get: fn(&Scores) -> f64,
}

pub(super) const METRICS: [Metric; 7] = [
    Metric {
        column: "iou_best",
        label: "IoU (best threshold)",
        get: |s| s.iou.best,
    },
    Metric {
        column: "iou_otsu",
        label: "IoU (Otsu threshold)",
        get: |s| s.iou.otsu,
    },
    Metric {
        column: "depth_err_m",
        label: "depth error (m, median over the object)",
        get: |s| s.depth_err_m,
    },
    Metric {
        column: "psnr_db",
        label: "PSNR vs no medium (dB)",
        get: |s| s.psnr_db,
    },
    Metric {
        column: "ssim",
        label: "SSIM vs no medium",
        get: |s| s.ssim,
    },
    Metric {
        column: "cnr",
        label: "contrast-to-noise ratio",
        get: |s| s.cnr,
    },
    Metric {
        column: "hf_share",
        label: "high-frequency energy share",
        get: |s| s.hf_share,
    },
];

pub(super) fn io(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |e| Error::io(path, e)
}

/// Writes every output into `dir`; returns the path of `index.html`.
pub fn write(plan: &StudyPlan, results: &[CellResult], dir: &Path) -> Result<PathBuf> {
    csv::write_csv(results, &dir.join("metrics.csv"))?;
    csv::write_objects_csv(results, &dir.join("objects.csv"))?;
    let figures = grids::write_figures(results, dir)?;
    let plots = plots::write_plots(results, dir)?;
    let kept: Vec<&PathBuf> = figures
        .iter()
        .flat_map(|f| &f.files)
        .chain(plots.iter().flat_map(|p| &p.files))
        .collect();
    remove_earlier_outputs(dir, &kept)?;
    html::write_html(plan, results, &figures, &plots, dir)
}

/// The methods (compensations, reconstructions) the cells were scored with, in their first cell's
/// order: the report's switch offers each, so a method added to the scores is one more entry.
pub fn methods(results: &[CellResult]) -> Vec<&'static str> {
    let mut out: Vec<&'static str> = Vec::new();
    for (name, ..) in results.iter().flat_map(|r| &r.by_compensation) {
        if !out.contains(name) {
            out.push(name);
        }
    }
    out
}

/// The method the report opens with: the paper's K where it was scored.
pub(super) fn default_method(methods: &[&'static str]) -> &'static str {
    methods
        .iter()
        .copied()
        .find(|m| *m == "paper")
        .or(methods.first().copied())
        .unwrap_or("paper")
}

/// How the switch names a method.
pub(super) fn method_label(name: &str) -> String {
    match name {
        "none" => "no compensation".into(),
        "paper" => "paper's K(xᵥ)".into(),
        "ballistic" => "ballistic gain exp(2 μt (d_ill + d_cam))".into(),
        crate::run::AWARE => "medium-aware (estimated medium removed, K with the estimate)".into(),
        other => other.into(),
    }
}

/// A cell's scores and front view under `method`, if it was scored so.
fn scored<'a>(r: &'a CellResult, method: &str) -> Option<&'a (&'static str, Vec<Scores>, Plane)> {
    r.by_compensation.iter().find(|(name, ..)| *name == method)
}

/// The two colour scales a figure is drawn with: (file tag, shared, what the switch says).
pub(super) const COLOUR_SCALES: [(&str, bool, &str); 2] = [
    ("shared", true, "one for the figure (shows fading)"),
    (
        "cell",
        false,
        "each cell to its own maximum (shows structure)",
    ),
];

/// A figure or plot drawn once per method (and colour scale): the page's `<img>` names its file
/// with `{method}` and `{scale}` left for the switch to fill.
pub(super) struct Switched {
    pub(super) figure: Figure,
    pub(super) title: String,
    /// The file name with `{method}` and `{scale}` placeholders.
    pub(super) pattern: String,
    pub(super) files: Vec<PathBuf>,
}

pub(super) fn fill(pattern: &str, method: &str, scale: &str) -> String {
    pattern
        .replace("{method}", method)
        .replace("{scale}", scale)
}

/// Removes the figures and plots that an earlier run in `dir` wrote and this report does not show (a
/// run with other `--only` figures or methods), so that the folder holds one study. Only the study's
/// own names (`fig*.png`, `plots/fig*.svg`) are touched.
fn remove_earlier_outputs(dir: &Path, kept: &[&PathBuf]) -> Result<()> {
    for (sub, ext) in [("", ".png"), ("plots", ".svg")] {
        let d = dir.join(sub);
        if !d.is_dir() {
            continue;
        }
        for entry in std::fs::read_dir(&d).map_err(io(&d))? {
            let name = entry.map_err(io(&d))?.file_name();
            let name = name.to_string_lossy();
            let rel = Path::new(sub).join(&*name);
            if name.starts_with("fig") && name.ends_with(ext) && !kept.contains(&&rel) {
                match std::fs::remove_file(dir.join(&rel)) {
                    Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                        return Err(Error::io(dir.join(&rel), e))
                    }
                    _ => {}
                }
            }
        }
    }
    Ok(())
}
