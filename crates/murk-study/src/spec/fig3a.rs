//! Fig. 3a: the Z letter without a medium.

use super::{iou, paper, verdict, Cell, CellSpec, NO_MEDIUM};
use crate::metrics;
use crate::plan::SceneKind;
use crate::run::CellResult;

/// The Z letter without a medium.
pub(super) fn cells(cell: &Cell) -> Vec<CellSpec> {
    vec![cell(
        "no medium".into(),
        String::new(),
        SceneKind::ZLetter,
        NO_MEDIUM,
        1.0,
    )]
}

/// The claims the cells test, in the report's words.
pub(super) fn findings(cells: &[&CellResult]) -> Vec<String> {
    let mut out = Vec::new();
    if let Some(r) = cells.first() {
        let (i, d) = (iou(r), paper(r, |s| s.depth_err_m));
        out.push(format!(
            "Fig. 3a, no medium: the paper reconstructs the Z; it is found at its depth (IoU ≥ 0.7, depth within a voxel): {}. IoU {i:.3}, depth error {d:+.3} m against a voxel of {:.3} m.",
            verdict(i >= 0.7 && metrics::within_a_voxel(d, r.voxel_dz_m)),
            r.voxel_dz_m
        ));
    }
    out
}
