//! The study's outputs: `metrics.csv`, `objects.csv`, a figure grid per figure and compensation, metric
//! plots, and `index.html` tying them together with the parameters and the choices made.

use crate::metrics;
use crate::plan::{Figure, Format, Plan, SceneKind};
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

fn num(v: f64) -> String {
    if v.is_nan() {
        "nan".into()
    } else if v.is_infinite() {
        if v > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        format!("{v:.5}")
    }
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |e| Error::io(path, e)
}

/// Writes every output into `dir`; returns the path of `index.html`.
pub fn write(plan: &Plan, results: &[CellResult], dir: &Path) -> Result<PathBuf> {
    write_csv(results, &dir.join("metrics.csv"))?;
    write_objects_csv(results, &dir.join("objects.csv"))?;
    let figures = write_figures(results, dir)?;
    let plots = write_plots(results, dir)?;
    remove_earlier_outputs(dir, &figures, &plots)?;
    write_html(plan, results, &figures, &plots, dir)
}

/// Removes the figures and plots that an earlier run in `dir` wrote and this report does not show (a
/// run with other `--only` figures), so that the folder holds one study. Only the study's own names
/// (`fig*-<compensation>.png`, `plots/fig*.svg`) are touched.
fn remove_earlier_outputs(
    dir: &Path,
    figures: &[(String, PathBuf)],
    plots: &[(String, PathBuf)],
) -> Result<()> {
    let kept: Vec<&PathBuf> = figures.iter().chain(plots).map(|(_, p)| p).collect();
    let mut earlier: Vec<PathBuf> = Figure::ALL
        .iter()
        .flat_map(|f| {
            murk_recon::Compensation::NAMES
                .iter()
                .map(move |c| PathBuf::from(format!("{}-{c}.png", f.name())))
        })
        .collect();
    let plots_dir = dir.join("plots");
    for entry in std::fs::read_dir(&plots_dir).map_err(io(&plots_dir))? {
        let name = entry.map_err(io(&plots_dir))?.file_name();
        let name = name.to_string_lossy();
        if name.starts_with("fig") && name.ends_with(".svg") {
            earlier.push(Path::new("plots").join(&*name));
        }
    }
    for p in earlier.iter().filter(|p| !kept.contains(p)) {
        match std::fs::remove_file(dir.join(p)) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(Error::io(dir.join(p), e))
            }
            _ => {}
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
    s.push_str(",objects,objects_detected,objects_detected_sd,objects_worst_depth_err_m\n");
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
            let _ = writeln!(
                s,
                ",{},{},{},{}",
                scores.first().map_or(0, |x| x.objects.len()),
                num(found),
                num(found_sd),
                num(stat(scores, Scores::worst_object_depth_err_m).0)
            );
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

/// One grid per figure and compensation, laid out as the paper's (rows and columns from the cells).
fn write_figures(results: &[CellResult], dir: &Path) -> Result<Vec<(String, PathBuf)>> {
    let mut out = Vec::new();
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
        for (k, comp) in murk_recon::Compensation::NAMES.iter().enumerate() {
            let planes: Vec<Vec<Option<&Plane>>> = rows
                .iter()
                .map(|row| {
                    cols.iter()
                        .map(|col| {
                            cells
                                .iter()
                                .find(|r| r.cell.row == *row && r.cell.col == *col)
                                .map(|r| &r.by_compensation[k].2)
                        })
                        .collect()
                })
                .collect();
            let grid = FigureGrid {
                title: format!("{} — compensation: {comp}", fig.caption()),
                row_labels: rows.iter().map(|s| s.to_string()).collect(),
                col_labels: cols.iter().map(|s| s.to_string()).collect(),
                cells: planes,
            };
            let name = format!("{}-{comp}.png", fig.name());
            write_grid_png(&dir.join(&name), &grid, 160)?;
            out.push((
                format!("{} (compensation: {comp})", fig.caption()),
                PathBuf::from(name),
            ));
        }
    }
    Ok(out)
}

/// Plots of every metric against the study's axes (paper compensation, mean ± spread over seeds).
fn write_plots(results: &[CellResult], dir: &Path) -> Result<Vec<(String, PathBuf)>> {
    murk_io::create_output_dir(&dir.join("plots"))?;
    // (figure, file stem, x label, x value, series key)
    type Axis = (
        Figure,
        &'static str,
        &'static str,
        fn(&CellResult) -> f64,
        fn(&CellResult) -> String,
    );
    let axes: [Axis; 6] = [
        (
            Figure::Fig3b,
            "vs-albedo-by-mu_t",
            "albedo α",
            |r| r.cell.medium.albedo,
            |r| r.cell.row.clone(),
        ),
        (
            Figure::Fig3b,
            "vs-mu_t-by-albedo",
            "μt (1/m)",
            |r| r.cell.medium.mu_t_per_m,
            |r| r.cell.col.clone(),
        ),
        (
            Figure::Fig3c,
            "vs-albedo-by-g",
            "albedo α",
            |r| r.cell.medium.albedo,
            |r| r.cell.row.clone(),
        ),
        (
            Figure::Fig3c,
            "vs-g-by-albedo",
            "anisotropy g",
            |r| r.cell.medium.g,
            |r| r.cell.col.clone(),
        ),
        (
            Figure::Fig4,
            "vs-lambda",
            "λ / λ0",
            |r| r.cell.lambda_factor,
            |_| "μt = 1, α = 0.83".into(),
        ),
        (
            Figure::Fig5,
            "vs-mu_t",
            "μt (1/m)",
            |r| r.cell.medium.mu_t_per_m,
            |_| "shelf, α = 0.5".into(),
        ),
    ];
    let mut out = Vec::new();
    for (fig, stem, x_label, x, key) in axes {
        let cells: Vec<&CellResult> = results.iter().filter(|r| r.cell.figure == fig).collect();
        if cells.is_empty() {
            continue;
        }
        for m in &METRICS {
            let mut series: Vec<Series> = Vec::new();
            for r in &cells {
                let (mean, sd) = stat(&r.by_compensation[1].1, m.get);
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
                title: format!("{}: {} vs {x_label}", fig.name(), m.label),
                x_label: x_label.into(),
                y_label: m.label.into(),
                series,
            };
            let name = PathBuf::from(format!("plots/{}-{}-{stem}.svg", fig.name(), m.column));
            write_plot_svg(&dir.join(&name), &plot)?;
            out.push((plot.title, name));
        }
    }
    Ok(out)
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
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
            .map(|r| match value(r) {
                v if v.abs() < 0.1 => format!("{v:.2e} ({})", key(r)),
                v => format!("{v:.3} ({})", key(r)),
            })
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
                "Fig. 3b, μt = {m}: the paper says a higher albedo costs coherence and high-frequency detail; SSIM against the clear scene falls from α = 0.15 to α = 0.83: {} ({:.3} → {:.3}; IoU {:.3} → {:.3}). The projection's high-frequency share goes {:.2e} → {:.2e}: {}.",
                verdict(ssim(b) < ssim(a)),
                ssim(a),
                ssim(b),
                iou(a),
                iou(b),
                hf(a),
                hf(b),
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
    out
}

/// The choices the study makes where the paper is silent or inconsistent.
const CHOICES: &[&str] = &[
    "Wall spacing: the paper gives Δc = 0.11 m with 128² points, which implies a 14 m diffuser; we keep the 2 m diffuser of its Fig. 2 (Δc = 2/128 m at paper scale, 2/64 m at quick scale) and λ0 = 4Δc.",
    "Time window: the paper's 4096 bins of 3 ps cover 3.69 m of path, less than the path to a target at 2 m and back in fog; at paper scale we keep 4096 bins but of 1.5 mm (5 ps) from 2.0 m (quick scale: 1200 bins of 5 mm from 2.0 m), so that the window starts 1 m of path before any voxel's shortest path and ends at least 1.4 m after its longest (a corner voxel's 6.6 m): 8σ and 11σ of the longest pulse (Fig. 4's 3λ0 = 0.1875 m, σ = 0.125 m) at quick scale, 8σ and 12σ at paper scale. The tail_share column says how much signal is still there when the window ends: the largest signal in the last 5 % of bins over the peak. In Fig. 5's closed room it stays near 6 % even without fog, from light passed around by the room's walls; the cut still lies at least 11σ of the longest pulse beyond every voxel's paths.",
    "Albedo sweeps: the five cells of a row of Fig. 3b or 3c are one render whose paths serve every albedo (the renderer's sampling does not depend on the albedo in fog); each capture equals, to float rounding, a render of that albedo alone with the same seed. The CPU column gives each cell a fifth of its row's render.",
    "Fig. 3b: the paper shows one cell twice; we render every μt × α cell.",
    "Fig. 4: the paper's file names suggest 4λ0 for its third column; its caption says 3λ0, which we use. Its λ0 is the paper scale's 4Δc = 0.0625 m at both scales, so that λ keeps the paper's ratio to the 0.8 m letter; at quick scale that is 2Δc, the 64² grid's Nyquist limit, so the λ0 picture is noisier than Fig. 3's (which keep 4Δc of their own grid).",
    "Compensation: every cell is scored without compensation, with the paper's K(x_v) as printed (α·d mixes units) and with the physical ballistic gain e^{2μt(d_ill + d_cam)}; figures and plots use the paper's K unless the file name says otherwise.",
    "Metrics: IoU of the front maximum projection thresholded at the best and at Otsu's threshold against the renderer's ground-truth mask (the Z; in the room, everything but the room's walls); depth error = median over that mask of the brightest voxel's depth minus the true depth; PSNR and SSIM of the normalised front projection against the same scene without medium at the same λ; CNR of the mask against the rest; high-frequency share = spectral energy above half Nyquist.",
    "Shelf objects: a pixel's surface is its column's nearest local maximum that reaches half of the column's brightest voxel, where that brightest voxel is at least twice the column's mean (a flat column has none); an object is detected when more than half of its pixels have their surface within two voxels of the object's true depth, and its depth error is the median over its pixels. Not the brightest voxel: the virtual aperture sees around a small object, so the shelf's back panel can be brighter in the object's own column.",
];

fn write_html(
    plan: &Plan,
    results: &[CellResult],
    figures: &[(String, PathBuf)],
    plots: &[(String, PathBuf)],
    dir: &Path,
) -> Result<PathBuf> {
    let mut h = String::from(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>murk: the paper's study</title>\n\
         <style>body{font-family:sans-serif;max-width:1200px;margin:auto}table{border-collapse:collapse;font-size:12px}\
         td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}img{max-width:100%}</style></head><body>\n\
         <h1>Phasor Fields in scattering media: the study of Luesia et al., rerun by murk</h1>\n",
    );
    let _ = writeln!(
        h,
        "<h2>Parameters</h2>\n<table id=\"parameters\"><tr><th>scale</th><td>{:?}</td></tr><tr><th>seeds</th><td>{}</td></tr><tr><th>shards per capture</th><td>{}</td></tr><tr><th>captures</th><td>{}</td></tr><tr><th>renders (albedo sweeps count once)</th><td>{}</td></tr><tr><th>render tasks</th><td>{}</td></tr>",
        plan.scale,
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
            "<tr><th>{}</th><td>{}² laser points, {} bins of {} m from {} m, {spp} spp, volume {}</td></tr>",
            scene.file(),
            f.grid,
            f.bins,
            f.bin_width_m,
            f.start_m,
            f.volume
        );
    }
    h.push_str("</table>\n<h2>Findings</h2>\n<p>Each claim of the paper that this run's cells can test, with the numbers it rests on (paper's K, mean over this run's seeds at its spp) and the verdict they give. Few samples make verdicts noisy; docs/study.md in murk's repository says which hold at converged settings.</p>\n<ul id=\"findings\">\n");
    let found = findings(results);
    if found.is_empty() {
        h.push_str("<li>No claim of the paper can be tested with this run's cells alone: each needs a figure's no-medium cell, a row or column of cells, or a pair of them.</li>\n");
    }
    for f in found {
        let _ = writeln!(h, "<li>{}</li>", esc(&f));
    }
    h.push_str("</ul>\n<h2>Choices</h2>\n<ul>\n");
    for c in CHOICES {
        let _ = writeln!(h, "<li>{}</li>", esc(c));
    }
    h.push_str("</ul>\n<h2>Figures</h2>\n");
    for (caption, path) in figures {
        let _ = writeln!(
            h,
            "<figure><img src=\"{}\" alt=\"{}\"><figcaption>{}</figcaption></figure>",
            path.display(),
            esc(caption),
            esc(caption)
        );
    }
    h.push_str("<h2>Numbers per cell (compensation: paper; mean ± spread over seeds)</h2>\n<table id=\"metrics\"><tr><th>figure</th><th>row</th><th>column</th><th>tail share</th><th>CPU s</th><th>render error</th>");
    for m in &METRICS {
        let _ = write!(h, "<th>{}</th>", esc(m.label));
    }
    h.push_str("</tr>\n");
    for r in results {
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>",
            r.cell.figure.name(),
            esc(&r.cell.row),
            esc(&r.cell.col),
            num(metrics::mean_std(&r.tail_share).0),
            r.cpu_s.map_or("external".into(), |c| format!("{c:.1}")),
            r.render_rel_err
                .map_or("—".into(), |e| format!("{:.1} %", 100.0 * e))
        );
        for m in &METRICS {
            let (mean, sd) = stat(&r.by_compensation[1].1, m.get);
            let _ = match sd.is_nan() {
                true => write!(h, "<td>{}</td>", num(mean)),
                false => write!(h, "<td>{} ± {}</td>", num(mean), num(sd)),
            };
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</table>\n");
    let shelf: Vec<&CellResult> = results
        .iter()
        .filter(|r| r.cell.scene == SceneKind::Shelf)
        .collect();
    if !shelf.is_empty() {
        h.push_str("<h2>Shelf objects (compensation: paper, first seed)</h2>\n<table id=\"objects\"><tr><th>cell</th><th>object</th><th>detected</th><th>depth error (m)</th></tr>\n");
        for r in shelf {
            for o in &r.by_compensation[1].1[0].objects {
                let _ = writeln!(
                    h,
                    "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
                    esc(&r.cell.col),
                    esc(&o.name),
                    if o.detected { "yes" } else { "no" },
                    num(o.depth_err_m)
                );
            }
        }
        h.push_str("</table>\n");
    }
    if !plots.is_empty() {
        h.push_str("<h2>Plots</h2>\n");
    }
    for (title, path) in plots {
        let _ = writeln!(
            h,
            "<figure><img src=\"{}\" alt=\"{}\"></figure>",
            path.display(),
            esc(title)
        );
    }
    h.push_str("<p>Raw numbers: <a href=\"metrics.csv\">metrics.csv</a>, <a href=\"objects.csv\">objects.csv</a>; the task list: <a href=\"plan.json\">plan.json</a>.</p>\n</body></html>\n");
    let path = dir.join("index.html");
    murk_io::write_atomic(&path, |w| w.write_all(h.as_bytes()).map_err(io(&path)))?;
    Ok(path)
}
