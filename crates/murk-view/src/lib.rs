//! Pictures for murk: false-coloured projections of reconstructed volumes ([`pictures`]), labelled
//! figure grids laid out like a paper's figures ([`grid`], PNG) and line plots of metrics ([`plot`],
//! SVG or PNG). Text is drawn with DejaVu Sans, embedded in the crate (see `fonts/LICENSE`), so
//! nothing depends on the fonts installed on the machine. Every file is written atomically.
//!
//! ```
//! use murk_core::Volume;
//!
//! // One bright voxel at x = +1 m, y = 0, z = 1.5 m in a 3 × 3 × 5 volume.
//! let vol = Volume::parse("-1:1:3,-1:1:3,0.5:1.5:5")?;
//! let mut intensity = vec![0f32; vol.len()];
//! intensity[vol.index(2, 1, 4)] = 1.0;
//! let v = murk_view::views(&vol, &intensity);
//! // The front view looks from the wall into the scene with +y up, so +x is the left column.
//! assert_eq!((v.front.width, v.front.height), (3, 3));
//! assert_eq!(v.front.values[3], 1.0);
//! assert_eq!(v.depth.values[3], 1.5);
//! # Ok::<(), murk_core::Error>(())
//! ```

pub mod grid;
pub mod normal_map;
pub mod pictures;
pub mod plot;

pub use grid::{bar_top_label, grid_layout, write_grid_png, FigureGrid, GridLayout};
pub use pictures::{
    views, write_index, write_png, write_views, MetreAxis, Plane, Views, PAGE_STYLE,
};
pub use plot::{write_plot_png, write_plot_svg, LinePlot, Series, PLOT_SIZE};

use murk_core::{Error, Result};
use std::path::Path;

/// DejaVu Sans 2.37 (Bitstream Vera / Arev licence, in fonts/LICENSE).
static FONT: &[u8] = include_bytes!("../fonts/DejaVuSans.ttf");

/// The family name text is drawn with; plotters' default family, so every chart element finds it.
pub(crate) const FAMILY: &str = "sans-serif";

/// Registers the embedded font with plotters (once per process). plotters' ab_glyph text needs it for
/// drawing on bitmaps and for measuring labels when laying out charts, SVG included.
pub(crate) fn ensure_font() -> Result<()> {
    static REGISTERED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FAMILY, plotters::style::FontStyle::Normal, FONT).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(Error::Unsupported(
            "murk-view: the embedded font fonts/DejaVuSans.ttf does not parse".into(),
        ))
    }
}

/// An I/O error from a write under `path` reported against `path` itself (not the temporary sibling
/// that `murk_io::write_atomic` writes first), so the message names the file the caller asked for.
pub(crate) fn name_target(path: &Path, e: Error) -> Error {
    match e {
        Error::Io { source, .. } => Error::io(path, source),
        other => other,
    }
}

/// A drawing failure inside plotters, reported against the file being drawn.
pub(crate) fn draw_error(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::format(path, format!("drawing failed: {e}"))
}
