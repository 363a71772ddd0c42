//! Fig. 4: the Z letter at μt = 1, α = 0.83, reconstructed at three wavelengths.

use super::{fog, hf, iou, list, verdict, Cell, CellSpec, FOUND_IOU};
use crate::plan::SceneKind;
use crate::run::CellResult;

/// The wavelength at μt = 1, α = 0.83.
pub(super) fn cells(cell: &Cell) -> Vec<CellSpec> {
    [1.0, 2.0, 3.0]
        .into_iter()
        .map(|k| {
            let c = if k == 1.0 {
                "λ = λ0".to_string()
            } else {
                format!("λ = {k}λ0")
            };
            cell(String::new(), c, SceneKind::ZLetter, fog(1.0, 0.83, 0.0), k)
        })
        .collect()
}

/// The claims the cells test, in the report's words.
pub(super) fn findings(cells: &[&CellResult]) -> Vec<String> {
    let mut out = Vec::new();
    // Fig. 4: λ0, 2λ0, 3λ0.
    let mut fig4 = cells.to_vec();
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
    out
}
