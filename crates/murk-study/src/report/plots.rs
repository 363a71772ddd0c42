//! The metric plots: one SVG per figure axis, metric and method.

use super::{fill, methods, scored, Switched, METRICS};
use crate::format::stat;
use crate::plan::Figure;
use crate::run::CellResult;
use murk_core::Result;
use murk_view::{write_plot_svg, LinePlot, Series};
use std::path::{Path, PathBuf};

/// The axis a metric is drawn over: [0, 1] for a score bounded so, from 0 for a non-negative one.
fn metric_range(column: &str) -> Option<(f64, f64)> {
    match column {
        "iou_best" | "iou_otsu" | "ssim" | "hf_share" => Some((0.0, 1.0)),
        "cnr" | "psnr_db" => Some((0.0, 0.0)),
        _ => None,
    }
}

/// Plots of every metric against the study's axes, one per method (mean ± spread over seeds). The
/// x axes of a quantity that starts at zero (μt, α, λ) start there, so plots side by side compare.
pub(super) fn write_plots(results: &[CellResult], dir: &Path) -> Result<Vec<Switched>> {
    murk_io::create_output_dir(&dir.join("plots"))?;
    // (figure, file stem, x label, x from zero, x value, series key)
    type Axis = (
        Figure,
        &'static str,
        &'static str,
        bool,
        fn(&CellResult) -> f64,
        fn(&CellResult) -> String,
    );
    let axes: [Axis; 6] = [
        (
            Figure::Fig3b,
            "vs-albedo-by-mu_t",
            "albedo α",
            true,
            |r| r.cell.medium.albedo,
            |r| r.cell.row.clone(),
        ),
        (
            Figure::Fig3b,
            "vs-mu_t-by-albedo",
            "μt (1/m)",
            true,
            |r| r.cell.medium.mu_t_per_m,
            |r| r.cell.col.clone(),
        ),
        (
            Figure::Fig3c,
            "vs-albedo-by-g",
            "albedo α",
            true,
            |r| r.cell.medium.albedo,
            |r| r.cell.row.clone(),
        ),
        (
            Figure::Fig3c,
            "vs-g-by-albedo",
            "anisotropy g",
            false,
            |r| r.cell.medium.g,
            |r| r.cell.col.clone(),
        ),
        (
            Figure::Fig4,
            "vs-lambda",
            "λ / λ0",
            true,
            |r| r.cell.lambda_factor,
            |_| "μt = 1, α = 0.83".into(),
        ),
        (
            Figure::Fig5,
            "vs-mu_t",
            "μt (1/m)",
            true,
            |r| r.cell.medium.mu_t_per_m,
            |_| "shelf, α = 0.5".into(),
        ),
    ];
    let methods = methods(results);
    let mut out = Vec::new();
    for (fig, stem, x_label, from_zero, x, key) in axes {
        let cells: Vec<&CellResult> = results.iter().filter(|r| r.cell.figure == fig).collect();
        if cells.is_empty() {
            continue;
        }
        for m in &METRICS {
            let pattern = format!("plots/{}-{}-{stem}-{{method}}.svg", fig.name(), m.column);
            let mut files = Vec::new();
            for method in &methods {
                let mut series: Vec<Series> = Vec::new();
                for r in &cells {
                    let Some((_, scores, _)) = scored(r, method) else {
                        continue;
                    };
                    let (mean, sd) = stat(scores, m.get);
                    let k = key(r);
                    match series.iter_mut().find(|s| s.label == k) {
                        Some(s) => s.points.push((x(r), mean, sd)),
                        None => series.push(Series {
                            label: k,
                            points: vec![(x(r), mean, sd)],
                        }),
                    }
                }
                series
                    .iter_mut()
                    .for_each(|s| s.points.sort_by(|a, b| a.0.total_cmp(&b.0)));
                let plot = LinePlot {
                    title: m.label.into(),
                    x_label: x_label.into(),
                    y_label: m.label.into(),
                    series,
                    x_range: from_zero.then_some((0.0, 0.0)),
                    y_range: metric_range(m.column),
                };
                let name = PathBuf::from(fill(&pattern, method, ""));
                write_plot_svg(&dir.join(&name), &plot)?;
                files.push(name);
            }
            out.push(Switched {
                figure: fig,
                title: format!("{} vs {x_label}", m.label),
                pattern,
                files,
            });
        }
    }
    Ok(out)
}
