//! `metrics.csv` (one row per cell and compensation) and `objects.csv` (one per shelf object).

use super::{io, METRICS};
use crate::format::{num, stat};
use crate::metrics;
use crate::run::{CellResult, Scores};
use murk_core::Result;
use std::fmt::Write as _;
use std::path::Path;

pub(super) fn write_csv(results: &[CellResult], path: &Path) -> Result<()> {
    let mut s = String::from(
        "figure,row,col,scene,mu_t,albedo,g,lambda_factor,compensation,seeds,tail_share,cpu_s,scoring_cpu_s,render_rel_err",
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
                "{},{},{},{},{},{albedo},{g},{},{comp},{},{},{},{},{}",
                c.figure.name(),
                c.row,
                c.col,
                c.scene.file().trim_end_matches(".toml"),
                c.medium.mu_t_per_m,
                c.lambda_factor,
                scores.len(),
                num(tail),
                r.cpu_s.map_or("".into(), num),
                r.scoring_cpu_s.map_or("".into(), num),
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

pub(super) fn write_objects_csv(results: &[CellResult], path: &Path) -> Result<()> {
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
