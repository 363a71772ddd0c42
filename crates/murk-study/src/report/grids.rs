//! The image grids: one PNG per figure, method and colour scale, laid out as the paper's.

use super::{fill, method_label, methods, scored, Switched, COLOUR_SCALES};
use crate::plan::Figure;
use crate::run::CellResult;
use murk_core::Result;
use murk_view::{write_grid_png, FigureGrid, Plane};
use std::path::{Path, PathBuf};

/// One grid per figure, method and colour scale, laid out as the paper's (rows and columns from the
/// cells), each image with its spatial axes in metres.
pub(super) fn write_figures(results: &[CellResult], dir: &Path) -> Result<Vec<Switched>> {
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
                    // The page's section heading names the figure; the picture says which method.
                    title: method_label(method),
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
