//! The study's outputs: `metrics.csv`, `objects.csv`, a figure grid per figure and compensation, metric
//! plots, and `index.html` tying them together with the parameters and the choices made.

use crate::metrics;
use crate::plan::{Figure, Format, SceneKind, StudyPlan};
use crate::run::{CellResult, Scores};
use murk_core::{Error, Result};
use murk_view::{write_grid_png, write_plot_svg, FigureGrid, LinePlot, Plane, Series};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A metric of [`Scores`]: its column name, a readable label and how to read it.
struct Metric {
    column: &'static str,
    label: &'static str,
    get: fn(&Scores) -> f64,
}

const METRICS: [Metric; 7] = [
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

/// Mean and spread over seeds.
fn stat(scores: &[Scores], get: fn(&Scores) -> f64) -> (f64, f64) {
    metrics::mean_std(&scores.iter().map(get).collect::<Vec<_>>())
}

/// A number as the CSV files hold it: every digit that round-trips (a share of 3.7e-5 kept whole,
/// where a fixed 5 decimals kept 0.00004), "nan" for none.
fn num(v: f64) -> String {
    if v.is_nan() {
        "nan".into()
    } else if v.is_infinite() {
        if v > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        format!("{v}")
    }
}

/// A number as the report shows it: three significant digits in plain decimals (0.0498 beside 0.999,
/// never 4.98e-2), integers from 1000 up, "—" where there is none (NaN), "∞" for an infinite value.
pub fn show(v: f64) -> String {
    if v.is_nan() {
        return "—".into();
    }
    if v.is_infinite() {
        return if v > 0.0 { "∞" } else { "−∞" }.into();
    }
    if v == 0.0 {
        return "0".into();
    }
    let digits = 2 - v.abs().log10().floor() as i32;
    let t = if digits <= 0 {
        format!("{v:.0}")
    } else {
        format!("{v:.*}", digits as usize)
    };
    // A real minus sign, and none on a value that rounds to zero.
    match t.strip_prefix('-') {
        Some(rest) if rest.trim_matches(['0', '.']).is_empty() => rest.into(),
        Some(rest) => format!("−{rest}"),
        None => t,
    }
}

/// Mean ± spread over seeds, as the report shows them (the spread only where there is one).
fn show_stat((mean, sd): (f64, f64)) -> String {
    if sd.is_finite() && !mean.is_nan() {
        format!("{} ± {}", show(mean), show(sd))
    } else {
        show(mean)
    }
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |e| Error::io(path, e)
}

/// Writes every output into `dir`; returns the path of `index.html`.
pub fn write(plan: &StudyPlan, results: &[CellResult], dir: &Path) -> Result<PathBuf> {
    write_csv(results, &dir.join("metrics.csv"))?;
    write_objects_csv(results, &dir.join("objects.csv"))?;
    let figures = write_figures(results, dir)?;
    let plots = write_plots(results, dir)?;
    let kept: Vec<&PathBuf> = figures
        .iter()
        .flat_map(|f| &f.files)
        .chain(plots.iter().flat_map(|p| &p.files))
        .collect();
    remove_earlier_outputs(dir, &kept)?;
    write_html(plan, results, &figures, &plots, dir)
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
fn default_method(methods: &[&'static str]) -> &'static str {
    methods
        .iter()
        .copied()
        .find(|m| *m == "paper")
        .or(methods.first().copied())
        .unwrap_or("paper")
}

/// How the switch names a method.
fn method_label(name: &str) -> String {
    match name {
        "none" => "no compensation".into(),
        "paper" => "paper's K(x_v)".into(),
        "ballistic" => "ballistic gain e^{2μt(d_ill + d_cam)}".into(),
        crate::run::AWARE => "medium-aware (estimated medium removed, K with the estimate)".into(),
        other => other.into(),
    }
}

/// A cell's scores and front view under `method`, if it was scored so.
fn scored<'a>(r: &'a CellResult, method: &str) -> Option<&'a (&'static str, Vec<Scores>, Plane)> {
    r.by_compensation.iter().find(|(name, ..)| *name == method)
}

/// The two colour scales a figure is drawn with: (file tag, shared, what the switch says).
const COLOUR_SCALES: [(&str, bool, &str); 2] = [
    ("shared", true, "one for the figure (shows fading)"),
    (
        "cell",
        false,
        "each cell to its own maximum (shows structure)",
    ),
];

/// A figure or plot drawn once per method (and colour scale): the page's `<img>` names its file
/// with `{method}` and `{scale}` left for the switch to fill.
struct Switched {
    figure: Figure,
    title: String,
    /// The file name with `{method}` and `{scale}` placeholders.
    pattern: String,
    files: Vec<PathBuf>,
}

fn fill(pattern: &str, method: &str, scale: &str) -> String {
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

fn write_csv(results: &[CellResult], path: &Path) -> Result<()> {
    let mut s = String::from(
        "figure,row,col,scene,mu_t,albedo,g,lambda_factor,compensation,seeds,tail_share,cpu_s,render_rel_err",
    );
    for m in &METRICS {
        let _ = write!(s, ",{0},{0}_sd", m.column);
    }
    // The thresholds behind the two IoUs (relative to each image's maximum; mean over seeds).
    s.push_str(",iou_best_threshold,iou_otsu_threshold");
    // The shelf's objects (empty for the Z): how many, how many detected (mean, sd over seeds), and
    // the detected ones' largest |depth error| (mean over seeds).
    s.push_str(",objects,objects_detected,objects_detected_sd,objects_worst_depth_err_m");
    // The medium the aware column estimated (mean over the seeds where one was detected).
    s.push_str(",est_mu_t,est_albedo,est_g\n");
    for r in results {
        let c = &r.cell;
        let tail = metrics::mean_std(&r.tail_share).0;
        // Without a medium, its albedo and g mean nothing: left empty.
        let (albedo, g) = if c.medium.mu_t_per_m > 0.0 {
            (c.medium.albedo.to_string(), c.medium.g.to_string())
        } else {
            (String::new(), String::new())
        };
        for (comp, scores, _) in &r.by_compensation {
            let _ = write!(
                s,
                "{},{},{},{},{},{albedo},{g},{},{comp},{},{},{},{}",
                c.figure.name(),
                c.row,
                c.col,
                c.scene.file().trim_end_matches(".toml"),
                c.medium.mu_t_per_m,
                c.lambda_factor,
                scores.len(),
                num(tail),
                r.cpu_s.map_or("".into(), num),
                r.render_rel_err.map_or("".into(), num)
            );
            for m in &METRICS {
                let (mean, sd) = stat(scores, m.get);
                let _ = write!(s, ",{},{}", num(mean), num(sd));
            }
            let _ = write!(
                s,
                ",{},{}",
                num(stat(scores, |x| x.iou.best_threshold as f64).0),
                num(stat(scores, |x| x.iou.otsu_threshold as f64).0)
            );
            let (found, found_sd) = stat(scores, Scores::objects_detected);
            let _ = write!(
                s,
                ",{},{},{},{}",
                scores.first().map_or(0, |x| x.objects.len()),
                num(found),
                num(found_sd),
                num(stat(scores, Scores::worst_object_depth_err_m).0)
            );
            let est: Vec<[f64; 3]> = r.estimated.iter().flatten().copied().collect();
            for k in 0..3 {
                let v: Vec<f64> = est.iter().map(|e| e[k]).collect();
                let cell = if v.is_empty() {
                    String::new()
                } else {
                    num(metrics::mean_std(&v).0)
                };
                let _ = write!(s, ",{cell}");
            }
            s.push('\n');
        }
    }
    murk_io::write_atomic(path, |w| w.write_all(s.as_bytes()).map_err(io(path)))
}

fn write_objects_csv(results: &[CellResult], path: &Path) -> Result<()> {
    let mut s =
        String::from("figure,col,compensation,seed,object,detected,hit_share,depth_err_m\n");
    for r in results {
        for (comp, scores, _) in &r.by_compensation {
            for (seed, sc) in scores.iter().enumerate() {
                for o in &sc.objects {
                    let _ = writeln!(
                        s,
                        "{},{},{comp},{seed},{},{},{},{}",
                        r.cell.figure.name(),
                        r.cell.col,
                        o.name,
                        o.detected,
                        num(o.hit_share),
                        num(o.depth_err_m)
                    );
                }
            }
        }
    }
    murk_io::write_atomic(path, |w| w.write_all(s.as_bytes()).map_err(io(path)))
}

/// One grid per figure, method and colour scale, laid out as the paper's (rows and columns from the
/// cells), each image with its spatial axes in metres.
fn write_figures(results: &[CellResult], dir: &Path) -> Result<Vec<Switched>> {
    let mut out = Vec::new();
    let methods = methods(results);
    for fig in Figure::ALL {
        let cells: Vec<&CellResult> = results.iter().filter(|r| r.cell.figure == fig).collect();
        if cells.is_empty() {
            continue;
        }
        let mut rows: Vec<&str> = Vec::new();
        let mut cols: Vec<&str> = Vec::new();
        for r in &cells {
            if !rows.contains(&r.cell.row.as_str()) {
                rows.push(&r.cell.row);
            }
            if !cols.contains(&r.cell.col.as_str()) {
                cols.push(&r.cell.col);
            }
        }
        let pattern = format!("{}-{{method}}-{{scale}}.png", fig.name());
        let mut files = Vec::new();
        for method in &methods {
            let planes: Vec<Vec<Option<&Plane>>> = rows
                .iter()
                .map(|row| {
                    cols.iter()
                        .map(|col| {
                            cells
                                .iter()
                                .find(|r| r.cell.row == *row && r.cell.col == *col)
                                .and_then(|r| scored(r, method))
                                .map(|s| &s.2)
                        })
                        .collect()
                })
                .collect();
            for (tag, shared, _) in COLOUR_SCALES {
                let grid = FigureGrid {
                    title: format!("{} — {}", fig.caption(), method_label(method)),
                    row_labels: rows.iter().map(|s| s.to_string()).collect(),
                    col_labels: cols.iter().map(|s| s.to_string()).collect(),
                    cells: planes.clone(),
                    shared_scale: shared,
                };
                let name = PathBuf::from(fill(&pattern, method, tag));
                write_grid_png(&dir.join(&name), &grid, 160)?;
                files.push(name);
            }
        }
        out.push(Switched {
            figure: fig,
            title: fig.caption().into(),
            pattern,
            files,
        });
    }
    Ok(out)
}

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
fn write_plots(results: &[CellResult], dir: &Path) -> Result<Vec<Switched>> {
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

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A best-threshold IoU from which the Z counts as found (the reduced study's test uses the same).
pub const FOUND_IOU: f64 = 0.2;

/// What this run shows against each claim of the paper it can test, one sentence each with its
/// numbers (the paper's K, mean over seeds) and a verdict computed from them: the report states a
/// claim that does not reproduce as plainly as one that does. Claims whose cells did not run are
/// left out.
pub fn findings(results: &[CellResult]) -> Vec<String> {
    let mean = |r: &CellResult, get: fn(&Scores) -> f64| {
        r.by_compensation
            .iter()
            .find(|(name, ..)| *name == "paper")
            .map_or(f64::NAN, |(_, scores, _)| stat(scores, get).0)
    };
    let iou = |r: &CellResult| mean(r, |s| s.iou.best);
    let hf = |r: &CellResult| mean(r, |s| s.hf_share);
    let cells =
        |f: Figure| -> Vec<&CellResult> { results.iter().filter(|r| r.cell.figure == f).collect() };
    let verdict = |holds: bool| if holds { "holds" } else { "does not hold" };
    let list = |rs: &[&CellResult],
                value: &dyn Fn(&CellResult) -> f64,
                key: &dyn Fn(&CellResult) -> String| {
        // Three significant digits, so that close values (high-frequency shares of 1e-5 to 0.1)
        // show which is larger.
        rs.iter()
            .map(|r| format!("{} ({})", show(value(r)), key(r)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let ssim = |r: &CellResult| mean(r, |s| s.ssim);
    let mut out = Vec::new();
    if let Some(r) = cells(Figure::Fig3a).first() {
        let (i, d) = (iou(r), mean(r, |s| s.depth_err_m));
        out.push(format!(
            "Fig. 3a, no medium: the paper reconstructs the Z; it is found at its depth (IoU ≥ 0.7, depth within a voxel): {}. IoU {i:.3}, depth error {d:+.3} m against a voxel of {:.3} m.",
            verdict(i >= 0.7 && metrics::within_a_voxel(d, r.voxel_dz_m)),
            r.voxel_dz_m
        ));
    }
    // Fig. 3b: rows are μt, columns α.
    let fig3b = cells(Figure::Fig3b);
    let column = |alpha: f64| -> Vec<&CellResult> {
        let mut c: Vec<&CellResult> = fig3b
            .iter()
            .copied()
            .filter(|r| r.cell.medium.albedo == alpha)
            .collect();
        c.sort_by(|a, b| {
            a.cell
                .medium
                .mu_t_per_m
                .total_cmp(&b.cell.medium.mu_t_per_m)
        });
        c
    };
    let mu_t = |r: &CellResult| format!("μt {}", r.cell.medium.mu_t_per_m);
    let low = column(0.15);
    if low.len() > 1 {
        out.push(format!(
            "Fig. 3b, α = 0.15: the paper says the image stays sharp as μt grows at low albedo; the Z is found (IoU ≥ {FOUND_IOU}) at every μt: {}. IoU {}.",
            verdict(low.iter().all(|r| iou(r) >= FOUND_IOU)),
            list(&low, &iou, &mu_t)
        ));
    }
    let mid = column(0.5);
    if mid.len() > 1 {
        out.push(format!(
            "Fig. 3b, α = 0.5: quality falls as μt grows (SSIM against the clear scene decreasing): {}. SSIM {}; IoU {}.",
            verdict(mid.windows(2).all(|w| ssim(w[1]) < ssim(w[0]))),
            list(&mid, &ssim, &mu_t),
            list(&mid, &iou, &mu_t)
        ));
    }
    let mut rows: Vec<f64> = fig3b.iter().map(|r| r.cell.medium.mu_t_per_m).collect();
    rows.sort_by(f64::total_cmp);
    rows.dedup();
    for m in rows {
        let at = |a: f64| {
            fig3b
                .iter()
                .find(|r| r.cell.medium.mu_t_per_m == m && r.cell.medium.albedo == a)
        };
        if let (Some(a), Some(b)) = (at(0.15), at(0.83)) {
            // The projection's high-frequency share also counts the fog's noise, so the loss of the
            // Z's detail is judged by its likeness to the clear scene; the share is given beside it.
            out.push(format!(
                "Fig. 3b, μt = {m}: the paper says a higher albedo costs coherence and high-frequency detail; SSIM against the clear scene falls from α = 0.15 to α = 0.83: {} ({:.3} → {:.3}; IoU {:.3} → {:.3}). The projection's high-frequency share goes {} → {}: {}.",
                verdict(ssim(b) < ssim(a)),
                ssim(a),
                ssim(b),
                iou(a),
                iou(b),
                show(hf(a)),
                show(hf(b)),
                if hf(b) > hf(a) {
                    "it rises, with the fog's noise rather than the Z's detail"
                } else {
                    "it falls"
                }
            ));
        }
    }
    // Fig. 3c: rows are g, columns α.
    let fig3c = cells(Figure::Fig3c);
    let at_g = |g: f64, a: f64| {
        fig3c
            .iter()
            .find(|r| r.cell.medium.g == g && r.cell.medium.albedo == a)
    };
    for (g, claim, better) in [
        (
            0.7,
            "forward scattering lets the phasor penetrate deeper",
            true,
        ),
        (-0.7, "backward scattering gives poorer visibility", false),
    ] {
        let pairs: Vec<(f64, f64, f64)> = crate::plan::ALBEDOS
            .iter()
            .filter_map(|&a| Some((a, iou(at_g(g, a)?), iou(at_g(0.0, a)?))))
            .collect();
        if pairs.is_empty() {
            continue;
        }
        let agree = pairs
            .iter()
            .filter(|(_, x, z)| if better { x >= z } else { x < z })
            .count();
        out.push(format!(
            "Fig. 3c, g = {g} against g = 0: the paper says {claim}; IoU is {} g = 0's at {agree} of {} albedos: {}. IoU {}.",
            if better { "at or above" } else { "below" },
            pairs.len(),
            verdict(agree == pairs.len()),
            pairs
                .iter()
                .map(|(a, x, z)| format!("α {a}: {x:.3} against {z:.3}"))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    // Fig. 4: λ0, 2λ0, 3λ0.
    let mut fig4 = cells(Figure::Fig4);
    fig4.sort_by(|a, b| a.cell.lambda_factor.total_cmp(&b.cell.lambda_factor));
    if fig4.len() > 1 {
        let lambda = |r: &CellResult| format!("{}λ0", r.cell.lambda_factor);
        out.push(format!(
            "Fig. 4: the paper says a longer λ gives smoother images that still recover the Z; the high-frequency share falls as λ grows and the Z is found (IoU ≥ {FOUND_IOU}) at every λ: {}. High-frequency share {}; IoU {}.",
            verdict(
                fig4.windows(2).all(|w| hf(w[1]) < hf(w[0]))
                    && fig4.iter().all(|r| iou(r) >= FOUND_IOU)
            ),
            list(&fig4, &hf, &lambda),
            list(&fig4, &iou, &lambda)
        ));
    }
    // Fig. 5: the shelf's objects, first seed.
    let fig5 = cells(Figure::Fig5);
    if !fig5.is_empty() {
        fn first_paper(r: &CellResult) -> Option<&Scores> {
            r.by_compensation
                .iter()
                .find(|(name, ..)| *name == "paper")
                .and_then(|(_, scores, _)| scores.first())
        }
        let detected = |r: &CellResult| {
            first_paper(r).map_or((0, 0), |s| {
                (
                    s.objects.iter().filter(|o| o.detected).count(),
                    s.objects.len(),
                )
            })
        };
        let counts: Vec<String> = fig5
            .iter()
            .map(|r| {
                let (d, n) = detected(r);
                let worst = first_paper(r).map_or(f64::NAN, Scores::worst_object_depth_err_m);
                let worst = if worst.is_nan() {
                    "none found".to_string()
                } else {
                    format!("largest depth error {:.1} voxels", worst / r.voxel_dz_m)
                };
                format!("{d} of {n} at μt {} ({worst})", r.cell.medium.mu_t_per_m)
            })
            .collect();
        out.push(format!(
            "Fig. 5: the paper says the shelf is reconstructed with good quality even in thick fog; all objects but at most one are found within two voxels of their depth at every μt: {}. Objects found (first seed): {}.",
            verdict(fig5.iter().all(|r| {
                let (d, n) = detected(r);
                n > 0 && d + 1 >= n
            })),
            counts.join(", ")
        ));
    }
    out.extend(aware_finding(results));
    out
}

/// How the medium-aware column compares with the paper's PF + K over the cells with a medium, and how
/// close its estimates came to the truth.
fn aware_finding(results: &[CellResult]) -> Option<String> {
    let score = |r: &CellResult, name: &str, get: fn(&Scores) -> f64| {
        scored(r, name).map_or(f64::NAN, |(_, s, _)| stat(s, get).0)
    };
    let fogged: Vec<&CellResult> = results
        .iter()
        .filter(|r| r.cell.medium.mu_t_per_m > 0.0 && scored(r, crate::run::AWARE).is_some())
        .collect();
    if fogged.is_empty() {
        return None;
    }
    let at_least = |get: fn(&Scores) -> f64| {
        fogged
            .iter()
            .filter(|r| score(r, crate::run::AWARE, get) >= score(r, "paper", get) - 1e-9)
            .count()
    };
    let close = fogged
        .iter()
        .filter(|r| {
            let m = r.cell.medium;
            let est: Vec<&[f64; 3]> = r.estimated.iter().flatten().collect();
            !est.is_empty()
                && est.iter().all(|e| {
                    (e[0] / m.mu_t_per_m - 1.0).abs() <= 0.1 && (e[1] / m.albedo - 1.0).abs() <= 0.1
                })
        })
        .count();
    let failed: usize = fogged.iter().map(|r| r.aware_notes.len()).sum();
    Some(format!(
        "Medium-aware (murk's own addition, not the paper's): reconstructed without being told the medium, it scores an IoU at least that of the paper's PF + K (which is told μt and α) in {} of {} cells with a medium, and an SSIM at least as high in {}; its estimate of μt and α (g free) is within 10 % of the truth in {} of them{}. Per cell: metrics.csv, rows `aware`, columns est_mu_t, est_albedo, est_g.",
        at_least(|s| s.iou.best),
        fogged.len(),
        at_least(|s| s.ssim),
        close,
        if failed > 0 {
            format!("; the estimate failed on {failed} captures, reconstructed without K")
        } else {
            String::new()
        }
    ))
}

/// The choices the study makes where the paper is silent or inconsistent.
const CHOICES: &[&str] = &[
    "Wall spacing: the paper gives Δc = 0.11 m with 128² points, which implies a 14 m diffuser; we keep the 2 m diffuser of its Fig. 2 (Δc = 2/128 m at paper scale, 2/64 m at quick scale) and λ0 = 4Δc.",
    "Time window: the paper's 4096 bins of 3 ps cover 3.69 m of path, less than the path to a target at 2 m and back in fog; at paper scale we keep 4096 bins but of 1.5 mm (5 ps) from 2.0 m (quick scale: 1200 bins of 5 mm from 2.0 m), so that the window starts 1 m of path before any voxel's shortest path and ends at least 1.4 m after its longest (a corner voxel's 6.6 m): 8σ and 11σ of the longest pulse (Fig. 4's 3λ0 = 0.1875 m, σ = 0.125 m) at quick scale, 8σ and 12σ at paper scale. The tail_share column says how much signal is still there when the window ends: the largest signal in the last 5 % of bins over the peak. In Fig. 5's closed room it stays near 6 % even without fog, from light passed around by the room's walls; the cut still lies at least 11σ of the longest pulse beyond every voxel's paths.",
    "Albedo sweeps: the five cells of a row of Fig. 3b or 3c are one render whose paths serve every albedo (the renderer's sampling does not depend on the albedo in fog); each capture equals, to float rounding, a render of that albedo alone with the same seed. The CPU column gives each cell a fifth of its row's render.",
    "Fig. 3b: the paper shows one cell twice; we render every μt × α cell.",
    "Fig. 4: the paper's file names suggest 4λ0 for its third column; its caption says 3λ0, which we use. Its λ0 is the paper scale's 4Δc = 0.0625 m at both scales, so that λ keeps the paper's ratio to the 0.8 m letter; at quick scale that is 2Δc, the 64² grid's Nyquist limit, so the λ0 picture is noisier than Fig. 3's (which keep 4Δc of their own grid).",
    "Compensation: every cell is scored without compensation, with the paper's K(x_v) as printed (α·d mixes units) and with the physical ballistic gain e^{2μt(d_ill + d_cam)}; the switch above the figures chooses which the figures, plots and tables show (the Findings use the paper's K).",
    "Medium-aware: every cell is also scored as murk reconstructs without being told the medium: the medium estimated from the cell's own capture (murk medium, all of μt, α and g free), its response removed, the gate and window end of murk reconstruct, and the paper's K with the estimate; metrics.csv gives the estimate beside the truth (est_mu_t, est_albedo, est_g).",
    "Metrics: IoU of the front maximum projection thresholded at the best and at Otsu's threshold against the renderer's ground-truth mask (the Z; in the room, everything but the room's walls); depth error = median over that mask of the brightest voxel's depth minus the true depth; PSNR and SSIM of the normalised front projection against the same scene without medium at the same λ; CNR of the mask against the rest; high-frequency share = spectral energy above half Nyquist.",
    "Shelf objects: a pixel's surface is its column's nearest local maximum that reaches half of the column's brightest voxel, where that brightest voxel is at least twice the column's mean (a flat column has none); an object is detected when more than half of its pixels have their surface within two voxels of the object's true depth, and its depth error is the median over its pixels. Not the brightest voxel: the virtual aperture sees around a small object, so the shelf's back panel can be brighter in the object's own column.",
];

/// What every murk page states first: murk's version, the command, when and on which machine.
pub(crate) fn run_provenance() -> Vec<(&'static str, String)> {
    let command = std::env::args()
        .map(|a| {
            if a.is_empty() || a.contains(|c: char| c.is_whitespace() || "'\"$\\".contains(c)) {
                format!("'{}'", a.replace('\'', "'\\''"))
            } else {
                a
            }
        })
        .collect::<Vec<_>>()
        .join(" ");
    vec![
        ("murk version", env!("CARGO_PKG_VERSION").to_string()),
        ("command", command),
        ("written", utc_now()),
        ("machine", machine()),
    ]
}

/// The run's provenance, for the top of the report: what ran, where, when and for how long.
fn provenance(plan: &StudyPlan, results: &[CellResult]) -> Vec<(&'static str, String)> {
    let cpu: Vec<f64> = results.iter().filter_map(|r| r.cpu_s).collect();
    let external = results.iter().filter(|r| r.cpu_s.is_none()).count();
    let mut cpu_text = format!(
        "{} CPU-hours of rendering ({} s) over {} cells",
        show(cpu.iter().sum::<f64>() / 3600.0),
        show(cpu.iter().sum::<f64>()),
        cpu.len()
    );
    if external > 0 {
        let _ = write!(
            cpu_text,
            "; {external} cells rendered by an external executor, not counted"
        );
    }
    let mut rows = run_provenance();
    rows.insert(
        2,
        (
            "scale",
            format!("{} ({} seeds)", plan.scale.name(), plan.seeds),
        ),
    );
    rows.insert(4, ("CPU time", cpu_text));
    rows
}

/// The current time as "YYYY-MM-DD HH:MM UTC" (days to civil date after Howard Hinnant's algorithm).
fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs()) as i64;
    let (days, rest) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02} UTC",
        rest / 3600,
        rest % 3600 / 60
    )
}

/// Host name, CPU model and the cores this process may use.
fn machine() -> String {
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|h| h.trim().to_string())
        .unwrap_or_else(|_| "unknown host".into());
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|c| {
            c.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.into());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!("{host}: {cpu}, {cores} cores available")
}

/// The page's switch: sets every image's file from its pattern and shows the table rows of the chosen
/// method. No network, no library.
const SWITCH_JS: &str = "<script>
function murkSwitch() {
  const m = document.getElementById('method').value;
  const s = document.querySelector('input[name=scale]:checked').value;
  document.querySelectorAll('img[data-pattern]').forEach(i => {
    i.src = i.dataset.pattern.replace('{method}', m).replace('{scale}', s);
  });
  document.querySelectorAll('[data-method]').forEach(e => { e.hidden = e.dataset.method !== m; });
}
document.querySelectorAll('#controls select, #controls input').forEach(e => e.addEventListener('change', murkSwitch));
murkSwitch();
</script>
";

const STYLE: &str = "<style>#controls{position:sticky;top:0;background:#f4f4f4;border-bottom:1px solid #bbb;padding:.4em .6em;z-index:1}\
figure{margin:.5em 0}.grid img{max-width:100%}\
.plots{display:grid;grid-template-columns:repeat(auto-fill,minmax(330px,1fr));gap:4px}.plots img{width:100%}\
li{margin:.3em 0}</style>";

fn write_html(
    plan: &StudyPlan,
    results: &[CellResult],
    figures: &[Switched],
    plots: &[Switched],
    dir: &Path,
) -> Result<PathBuf> {
    let methods = methods(results);
    let shown = default_method(&methods);
    let mut h = format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>murk: the paper's study</title>\n{}{STYLE}</head><body>\n\
         <h1>Phasor Fields in scattering media: the study of Luesia et al., rerun by murk</h1>\n<table id=\"provenance\">",
        murk_view::PAGE_STYLE
    );
    for (k, v) in provenance(plan, results) {
        let _ = write!(h, "<tr><th>{k}</th><td>{}</td></tr>", esc(&v));
    }
    h.push_str("</table>\n<h2>Findings</h2>\n<p>Each claim of the paper that this run's cells can test, with the numbers it rests on (paper's K, mean over this run's seeds at its spp) and the verdict they give. Few samples make verdicts noisy; docs/study.md in murk's repository says which hold at the scales it reports.</p>\n<ul id=\"findings\">\n");
    let found = findings(results);
    if found.is_empty() {
        h.push_str("<li>No claim of the paper can be tested with this run's cells alone: each needs a figure's no-medium cell, a row or column of cells, or a pair of them.</li>\n");
    }
    for f in found {
        let _ = writeln!(h, "<li>{}</li>", esc(&f));
    }
    h.push_str("</ul>\n");
    // The switch: every figure, plot and table below follows it.
    h.push_str("<div id=\"controls\"><label>Compensation: <select id=\"method\">");
    for m in &methods {
        let _ = write!(
            h,
            "<option value=\"{m}\"{}>{}</option>",
            if *m == shown { " selected" } else { "" },
            esc(&method_label(m))
        );
    }
    h.push_str("</select></label> &nbsp; Colour scale:");
    for (k, (tag, _, label)) in COLOUR_SCALES.iter().enumerate() {
        let _ = write!(
            h,
            " <label><input type=\"radio\" name=\"scale\" value=\"{tag}\"{}> {label}</label>",
            if k == 0 { " checked" } else { "" }
        );
    }
    h.push_str("</div>\n");
    let img = |pattern: &str, alt: &str| {
        format!(
            "<img data-pattern=\"{}\" src=\"{}\" alt=\"{}\">",
            esc(pattern),
            esc(&fill(pattern, shown, COLOUR_SCALES[0].0)),
            esc(alt)
        )
    };
    for fig in Figure::ALL {
        let grids: Vec<&Switched> = figures.iter().filter(|f| f.figure == fig).collect();
        let graphs: Vec<&Switched> = plots.iter().filter(|p| p.figure == fig).collect();
        if grids.is_empty() {
            continue;
        }
        let _ = writeln!(
            h,
            "<section id=\"{}\"><h2>{}</h2>",
            fig.name(),
            esc(fig.caption())
        );
        for g in grids {
            let _ = writeln!(
                h,
                "<figure class=\"grid\">{}</figure>",
                img(&g.pattern, &g.title)
            );
        }
        if !graphs.is_empty() {
            h.push_str("<div class=\"plots\">");
            for g in graphs {
                h.push_str(&img(&g.pattern, &g.title));
            }
            h.push_str("</div>\n");
        }
        h.push_str("</section>\n");
    }
    let _ = write!(
        h,
        "<h2>Parameters</h2>\n<table id=\"parameters\"><tr><th>scale</th><td>{}</td></tr><tr><th>seeds</th><td>{}</td></tr><tr><th>shards per capture</th><td>{}</td></tr><tr><th>captures</th><td>{}</td></tr><tr><th>renders (albedo sweeps count once)</th><td>{}</td></tr><tr><th>render tasks</th><td>{}</td></tr>",
        plan.scale.name(),
        plan.seeds,
        plan.shards,
        plan.captures.iter().map(|j| j.capture_ids().len()).sum::<usize>(),
        plan.captures.len(),
        plan.n_tasks()
    );
    // The scenes this study rendered.
    for scene in [SceneKind::ZLetter, SceneKind::Shelf]
        .into_iter()
        .filter(|s| plan.captures.iter().any(|c| c.scene == *s))
    {
        let f = Format::of(scene, plan.scale);
        let spp = plan
            .captures
            .iter()
            .find(|c| c.scene == scene)
            .map_or(f.spp, |c| c.spp);
        let _ = writeln!(
            h,
            "<tr><th>{}</th><td>{}² laser points, {} bins of {} m from {} m, {spp} samples per point, volume {}</td></tr>",
            scene.file().trim_end_matches(".toml"),
            f.grid,
            f.bins,
            show(f.bin_width_m),
            show(f.start_m),
            f.volume
        );
    }
    h.push_str("</table>\n<h2>Numbers per cell (mean ± spread over seeds)</h2>\n<table id=\"metrics\"><thead><tr><th>figure</th><th>row</th><th>column</th><th>tail share</th><th>CPU s</th><th>render error</th>");
    for m in &METRICS {
        let _ = write!(h, "<th>{}</th>", esc(m.label));
    }
    h.push_str("</tr></thead>\n");
    for method in &methods {
        let _ = writeln!(h, "<tbody data-method=\"{method}\">");
        for r in results {
            let Some((_, scores, _)) = scored(r, method) else {
                continue;
            };
            let _ = write!(
                h,
                "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>",
                r.cell.figure.name(),
                esc(&r.cell.row),
                esc(&r.cell.col),
                show(metrics::mean_std(&r.tail_share).0),
                r.cpu_s.map_or("external".into(), show),
                r.render_rel_err
                    .map_or("—".into(), |e| format!("{} %", show(100.0 * e)))
            );
            for m in &METRICS {
                let _ = write!(h, "<td>{}</td>", show_stat(stat(scores, m.get)));
            }
            h.push_str("</tr>\n");
        }
        h.push_str("</tbody>\n");
    }
    h.push_str("</table>\n");
    let shelf: Vec<&CellResult> = results
        .iter()
        .filter(|r| r.cell.scene == SceneKind::Shelf)
        .collect();
    if !shelf.is_empty() {
        h.push_str("<h2>Shelf objects (first seed)</h2>\n<table id=\"objects\"><thead><tr><th>cell</th><th>object</th><th>detected</th><th>depth error (m)</th></tr></thead>\n");
        for method in &methods {
            let _ = writeln!(h, "<tbody data-method=\"{method}\">");
            for r in &shelf {
                let Some((_, scores, _)) = scored(r, method) else {
                    continue;
                };
                for o in scores.first().map_or(&[][..], |s| &s.objects) {
                    let _ = writeln!(
                        h,
                        "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                        esc(&r.cell.col),
                        esc(&o.name),
                        if o.detected { "yes" } else { "no" },
                        show(o.depth_err_m)
                    );
                }
            }
            h.push_str("</tbody>\n");
        }
        h.push_str("</table>\n");
    }
    h.push_str("<h2>Choices</h2>\n<ul>\n");
    for c in CHOICES {
        let _ = writeln!(h, "<li>{}</li>", esc(c));
    }
    h.push_str("</ul>\n<p>Raw numbers: <a href=\"metrics.csv\">metrics.csv</a>, <a href=\"objects.csv\">objects.csv</a>; the task list: <a href=\"plan.json\">plan.json</a>.</p>\n");
    h.push_str(SWITCH_JS);
    h.push_str("</body></html>\n");
    let path = dir.join("index.html");
    murk_io::write_atomic(&path, |w| w.write_all(h.as_bytes()).map_err(io(&path)))?;
    Ok(path)
}
