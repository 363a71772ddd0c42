//! `index.html`: the page that ties the outputs together, with the switch between methods and colour
//! scales, the parameters and the choices made.

use super::provenance::provenance;
use super::{
    default_method, fill, findings, method_label, methods, page, scored, Switched, COLOUR_SCALES,
    METRICS,
};
use crate::format::{esc, show, show_stat, stat};
use crate::metrics;
use crate::plan::{Figure, Format, SceneKind, StudyPlan};
use crate::run::CellResult;
use murk_core::Result;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The choices the study makes where the paper is silent or inconsistent.
const CHOICES: &[&str] = &[
    "Wall spacing: the paper gives Δc = 0.11 m with 128² points, which implies a 14 m diffuser; we keep the 2 m diffuser of its Fig. 2 (Δc = 2/128 m at paper scale, 2/64 m at quick scale) and λ0 = 4Δc.",
    "Time window: the paper's 4096 bins of 3 ps cover 3.69 m of path, less than the path to a target at 2 m and back in fog; at paper scale we keep 4096 bins but of 1.5 mm (5 ps) from 2.0 m (quick scale: 1200 bins of 5 mm from 2.0 m), so that the window starts 1 m of path before any voxel's shortest path and ends at least 1.4 m after its longest (a corner voxel's 6.6 m): 8σ and 11σ of the longest pulse (Fig. 4's 3λ0 = 0.1875 m, σ = 0.125 m) at quick scale, 8σ and 12σ at paper scale. The tail_share column says how much signal is still there when the window ends: the largest signal in the last 5 % of bins over the peak. In Fig. 5's closed room it stays near 6 % even without fog, from light passed around by the room's walls; the cut still lies at least 11σ of the longest pulse beyond every voxel's paths.",
    "Albedo sweeps: the five cells of a row of Fig. 3b or 3c are one render whose paths serve every albedo (the renderer's sampling does not depend on the albedo in fog); each capture equals, to float rounding, a render of that albedo alone with the same seed. The CPU column gives each cell a fifth of its row's render.",
    "Fig. 3b: the paper shows one cell twice; we render every μt × α cell.",
    "Fig. 4: the paper's file names suggest 4λ0 for its third column; its caption says 3λ0, which we use. Its λ0 is the paper scale's 4Δc = 0.0625 m at both scales, so that λ keeps the paper's ratio to the 0.8 m letter; at quick scale that is 2Δc, the 64² grid's Nyquist limit, so the λ0 picture is noisier than Fig. 3's (which keep 4Δc of their own grid).",
    "Compensation: every cell is scored without compensation, with the paper's K(xᵥ) as printed (α·d mixes units) and with the physical ballistic gain exp(2 μt (d_ill + d_cam)); the switch above the figures chooses which the figures, plots and tables show (the Findings use the paper's K).",
    "Medium-aware: every cell is also scored as murk reconstructs without being told the medium: the medium estimated from the cell's own capture (murk medium, all of μt, α and g free), its response removed, the gate and window end of murk reconstruct, and the paper's K with the estimate; metrics.csv gives the estimate beside the truth (est_mu_t, est_albedo, est_g).",
    "Metrics: IoU of the front maximum projection thresholded at the best and at Otsu's threshold against the renderer's ground-truth mask (the Z; in the room, everything but the room's walls); depth error = median over that mask of the brightest voxel's depth minus the true depth; PSNR and SSIM of the normalised front projection against the same scene without medium at the same λ; CNR of the mask against the rest; high-frequency share = spectral energy above half Nyquist.",
    "Shelf objects: a pixel's surface is its column's nearest local maximum that reaches half of the column's brightest voxel, where that brightest voxel is at least twice the column's mean (a flat column has none); an object is detected when more than half of its pixels have their surface within two voxels of the object's true depth, and its depth error is the median over its pixels. Not the brightest voxel: the virtual aperture sees around a small object, so the shelf's back panel can be brighter in the object's own column.",
];

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

pub(super) fn write_html(
    plan: &StudyPlan,
    results: &[CellResult],
    figures: &[Switched],
    plots: &[Switched],
    dir: &Path,
) -> Result<PathBuf> {
    let methods = methods(results);
    let shown = default_method(&methods);
    let mut h = page::head(
        "murk: the paper's study",
        "Phasor Fields in scattering media: the study of Luesia et al., rerun by murk",
    );
    h.push_str(&page::key_values("provenance", &provenance(plan, results)));
    h.push_str("<h2>Findings</h2>\n<p>Each claim of the paper that this run's cells can test, with the numbers it rests on (paper's K, mean over this run's seeds at its spp) and the verdict they give. Few samples make verdicts noisy; docs/study.md in murk's repository says which hold at the scales it reports.</p>\n<ul id=\"findings\">\n");
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
            h.push_str(&page::figure("grid", &img(&g.pattern, &g.title), ""));
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
            volume_words(&f.volume)
        );
    }
    h.push_str("</table>\n<h2>Numbers per cell (mean ± spread over seeds)</h2>\n");
    for fig in Figure::ALL {
        let cells: Vec<&CellResult> = results.iter().filter(|r| r.cell.figure == fig).collect();
        if !cells.is_empty() {
            numbers_table(&mut h, fig, &cells, &methods);
        }
    }
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
    page::write(dir, h)
}

/// The columns of a figure's numbers table before the metrics: header and the cell's text (None:
/// nothing to say, "—" in a column that others fill).
type Column = (&'static str, fn(&CellResult) -> Option<String>);

const CELL_COLUMNS: [Column; 6] = [
    ("row", |r| {
        (!r.cell.row.is_empty()).then(|| r.cell.row.clone())
    }),
    ("column", |r| {
        (!r.cell.col.is_empty()).then(|| r.cell.col.clone())
    }),
    ("tail share", |r| {
        Some(show(metrics::mean_std(&r.tail_share).0))
    }),
    ("render CPU s", |r| {
        Some(r.cpu_s.map_or("external".into(), show))
    }),
    ("reconstruction and scoring CPU s", |r| {
        r.scoring_cpu_s.map(show)
    }),
    ("render error", |r| {
        r.render_rel_err.map(|e| format!("{} %", show(100.0 * e)))
    }),
];

/// `fig`'s numbers per cell, one table body per method; the columns that are empty for every cell
/// of the figure (Fig. 4's rows, a one-seed run's render error) are left out.
fn numbers_table(h: &mut String, fig: Figure, cells: &[&CellResult], methods: &[&'static str]) {
    let columns: Vec<&Column> = CELL_COLUMNS
        .iter()
        .filter(|(_, text)| cells.iter().any(|r| text(r).is_some()))
        .collect();
    let _ = write!(
        h,
        "<h3>{}</h3>\n<table class=\"metrics\" id=\"metrics-{}\"><thead><tr>",
        esc(fig.caption()),
        fig.name()
    );
    for (name, _) in &columns {
        let _ = write!(h, "<th>{name}</th>");
    }
    for m in &METRICS {
        let _ = write!(h, "<th>{}</th>", esc(m.label));
    }
    h.push_str("</tr></thead>\n");
    for method in methods {
        let _ = writeln!(h, "<tbody data-method=\"{method}\">");
        for r in cells {
            let Some((_, scores, _)) = scored(r, method) else {
                continue;
            };
            h.push_str("<tr>");
            for (_, text) in &columns {
                let _ = write!(h, "<td>{}</td>", esc(&text(r).unwrap_or("—".into())));
            }
            for m in &METRICS {
                let _ = write!(h, "<td>{}</td>", show_stat(stat(scores, m.get)));
            }
            h.push_str("</tr>\n");
        }
        h.push_str("</tbody>\n");
    }
    h.push_str("</table>\n");
}

/// A volume spec (`x0:x1:nx,…`) as the report writes numbers: voxels, then each axis's span in
/// metres; the spec itself where it does not parse.
fn volume_words(spec: &str) -> String {
    let Ok(v) = murk_core::Volume::parse(spec) else {
        return spec.to_string();
    };
    let span = |a: &murk_core::Axis| format!("{} to {} m", show(a.start), show(a.end));
    format!(
        "{} × {} × {} voxels (x {}, y {}, z {})",
        v.x.n,
        v.y.n,
        v.z.n,
        span(&v.x),
        span(&v.y),
        span(&v.z)
    )
}
