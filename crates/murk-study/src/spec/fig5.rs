//! Fig. 5: the shelf scene without a medium and at two μt.

use super::{verdict, Cell, CellSpec, NO_MEDIUM};
use crate::plan::{MediumParams, SceneKind};
use crate::run::{CellResult, Scores};

/// The shelf scene without a medium and at two μt.
pub(super) fn cells(cell: &Cell) -> Vec<CellSpec> {
    [0.0, 1.0, 1.5]
        .into_iter()
        .map(|mu_t| {
            let c = if mu_t == 0.0 {
                "no medium".to_string()
            } else {
                format!("μt = {mu_t}")
            };
            let m = MediumParams {
                mu_t_per_m: mu_t,
                ..NO_MEDIUM
            };
            cell(String::new(), c, SceneKind::Shelf, m, 1.0)
        })
        .collect()
}

/// The claims the cells test, in the report's words.
pub(super) fn findings(cells: &[&CellResult]) -> Vec<String> {
    let mut out = Vec::new();
    // Fig. 5: the shelf's objects, first seed.
    let fig5 = cells;
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
