//! Fig. 3b: the Z letter in fog, μt (rows) by albedo (columns), isotropic.

use super::{fog, hf, iou, list, ssim, verdict, Cell, CellSpec, FOUND_IOU};
use crate::format::show;
use crate::plan::SceneKind;
use crate::plan::ALBEDOS;
use crate::run::CellResult;

/// μt by albedo, isotropic.
pub(super) fn cells(cell: &Cell) -> Vec<CellSpec> {
    [0.5, 1.0, 2.0]
        .into_iter()
        .flat_map(|mu_t| {
            ALBEDOS.map(|a| {
                let (r, c) = (format!("μt = {mu_t}"), format!("α = {a}"));
                cell(r, c, SceneKind::ZLetter, fog(mu_t, a, 0.0), 1.0)
            })
        })
        .collect()
}

/// The claims the cells test, in the report's words.
pub(super) fn findings(cells: &[&CellResult]) -> Vec<String> {
    let mut out = Vec::new();
    // Fig. 3b: rows are μt, columns α.
    let fig3b = cells;
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
    out
}
