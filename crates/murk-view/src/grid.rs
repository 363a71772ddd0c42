//! Labelled figure grids, laid out like a paper's figures: a title on top, a label above each column,
//! a label left of each row, and one false-coloured plane per cell, written as PNG.

use crate::pictures::{colour, MetreAxis, Plane};
use crate::{draw_error, ensure_font, name_target, FAMILY};
use murk_core::{Error, Result};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// A grid of planes with a title and row and column labels.
pub struct FigureGrid<'a> {
    pub title: String,
    /// One per row, drawn left of the row; empty for no label column.
    pub row_labels: Vec<String>,
    /// One per column, drawn above the column; empty for no label row.
    pub col_labels: Vec<String>,
    /// Rows × columns, every row as long as the first; `None` is an empty cell (drawn dark grey).
    pub cells: Vec<Vec<Option<&'a Plane>>>,
    /// One colour scale for every cell (0 .. the largest value of the grid), so that a cell fainter than
    /// another looks fainter; otherwise each cell is normalised to its own maximum.
    pub shared_scale: bool,
}

/// Where things go in the picture [`write_grid_png`] draws (pixels, origin top left).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GridLayout {
    pub width: u32,
    pub height: u32,
    pub rows: u32,
    pub cols: u32,
    /// Each cell is a `cell_px` × `cell_px` square; a plane fills it on its longer side, centred.
    pub cell_px: u32,
    /// Space between neighbouring cells.
    pub gap: u32,
    /// Left edge of the first column of cells (the row labels lie left of it).
    pub left: u32,
    /// Top edge of the first row of cells (the title and column labels lie above it).
    pub top: u32,
    /// Height of the title band at the top (0 without a title); the column labels lie between it and `top`.
    pub title_band: u32,
    /// Label text size (pixels); the title is drawn somewhat larger.
    pub font_px: u32,
    /// Width from `left` that the colour bar's end labels span: the bar's, or theirs where wider
    /// (a grid of one small cell), so that neither is clipped.
    pub bar_labels_span: u32,
    /// Top edge of the colour bar under the cells (from `left`, as wide as the cells, `font_px`
    /// high), with "0" and [`bar_top_label`] under its ends.
    pub bar_top: u32,
    /// Whether the cells' planes carry metre axes, drawn as named coordinates ("x (m)" between the
    /// end values) under the bottom row's cells and right of the last column's (the bands for them
    /// are reserved only then).
    pub axes: bool,
}

/// What the top of the colour bar stands for. A grid of one cell has one maximum, whichever scale
/// was asked for.
pub fn bar_top_label(grid: &FigureGrid) -> &'static str {
    if grid.cells.iter().flatten().count() == 1 {
        "max"
    } else if grid.shared_scale {
        "max of the whole grid"
    } else {
        "max of each cell"
    }
}

/// A coordinate in metres as the axes write it: two decimals and a real minus sign.
fn metres(v: f64) -> String {
    let t = format!("{v:.2}");
    match t.strip_prefix('-') {
        Some(rest) if rest.trim_matches(['0', '.']).is_empty() => rest.into(),
        Some(rest) => format!("−{rest}"),
        None => t,
    }
}

/// The planes of the grid, row by row.
fn planes<'a>(grid: &'a FigureGrid) -> impl Iterator<Item = &'a Plane> {
    grid.cells.iter().flatten().flatten().copied()
}

/// An axis's name as the grid writes it between the end values: "x (m)".
fn axis_name(a: &MetreAxis) -> String {
    format!("{} (m)", a.name)
}

/// The texts written right of the grid (the rows' axis: first, last, name), from its first plane
/// with axes.
fn row_axis_texts(grid: &FigureGrid) -> Option<[String; 3]> {
    let [_, rows] = planes(grid).find_map(|p| p.axes)?;
    Some([metres(rows.first_m), metres(rows.last_m), axis_name(&rows)])
}

impl GridLayout {
    /// Top-left corner of the cell at (`row`, `col`).
    pub fn cell_origin(&self, row: usize, col: usize) -> (u32, u32) {
        let step = self.cell_px + self.gap;
        (self.left + col as u32 * step, self.top + row as u32 * step)
    }
}

const BACKGROUND: [u8; 3] = [255, 255, 255];
const EMPTY_CELL: [u8; 3] = [64, 64, 64];
/// Larger than any figure murk draws; keeps a typo in `cell_px` from asking for gigabytes.
const MAX_SIDE: u32 = 16_384;

/// Checks the grid's shape and planes; returns (rows, cols).
fn check(grid: &FigureGrid, cell_px: u32) -> Result<(usize, usize)> {
    let rows = grid.cells.len();
    let cols = grid.cells.first().map_or(0, Vec::len);
    if rows == 0 || cols == 0 {
        return Err(Error::param("figure grid: no cells"));
    }
    if let Some(r) = grid.cells.iter().position(|r| r.len() != cols) {
        return Err(Error::param(format!(
            "figure grid: row {} has {} cells, row 1 has {cols}",
            r + 1,
            grid.cells[r].len()
        )));
    }
    if !grid.row_labels.is_empty() && grid.row_labels.len() != rows {
        return Err(Error::param(format!(
            "figure grid: {} row labels for {rows} rows",
            grid.row_labels.len()
        )));
    }
    if !grid.col_labels.is_empty() && grid.col_labels.len() != cols {
        return Err(Error::param(format!(
            "figure grid: {} column labels for {cols} columns",
            grid.col_labels.len()
        )));
    }
    if cell_px == 0 || cell_px > MAX_SIDE {
        return Err(Error::param(format!(
            "figure grid: cell size {cell_px} px is not in 1..={MAX_SIDE}"
        )));
    }
    for (r, row) in grid.cells.iter().enumerate() {
        for (c, plane) in row.iter().enumerate() {
            if let Some(p) = plane {
                if p.width == 0 || p.height == 0 || p.values.len() != p.width * p.height {
                    return Err(Error::param(format!(
                        "figure grid: cell ({}, {}) is {} × {} but holds {} values",
                        r + 1,
                        c + 1,
                        p.width,
                        p.height,
                        p.values.len()
                    )));
                }
            }
        }
    }
    Ok((rows, cols))
}

fn text_width(text: &str, px: u32) -> Result<u32> {
    if text.is_empty() {
        return Ok(0);
    }
    let font = FontDesc::new(FontFamily::Name(FAMILY), f64::from(px), FontStyle::Normal);
    font.box_size(text)
        .map(|(w, _)| w)
        .map_err(|e| Error::Unsupported(format!("measuring the label {text:?}: {e}")))
}

/// The layout [`write_grid_png`] uses for `grid` with cells of `cell_px` pixels.
pub fn grid_layout(grid: &FigureGrid, cell_px: u32) -> Result<GridLayout> {
    ensure_font()?;
    let (rows, cols) = check(grid, cell_px)?;
    let font_px = (f64::from(cell_px) * 0.09).clamp(13.0, 26.0).round() as u32;
    let title_px = font_px * 13 / 10;
    let gap = (cell_px / 32).max(4);
    let margin = font_px / 2 + 4;
    let title_band = if grid.title.is_empty() {
        0
    } else {
        title_px * 8 / 5
    };
    let col_band = if grid.col_labels.is_empty() {
        0
    } else {
        font_px * 9 / 5
    };
    let mut label_w = 0;
    for l in &grid.row_labels {
        label_w = label_w.max(text_width(l, font_px)?);
    }
    let row_band = if label_w == 0 { 0 } else { label_w + font_px };
    let (left, top) = (margin + row_band, margin + title_band + col_band);
    let cells_w = cols as u32 * (cell_px + gap) - gap;
    let cells_h = rows as u32 * (cell_px + gap) - gap;
    let axes = planes(grid).next().is_some() && planes(grid).all(|p| p.axes.is_some());
    let (x_band, y_band) = match row_axis_texts(grid).filter(|_| axes) {
        Some(texts) => {
            let mut w = 0;
            for t in &texts {
                w = w.max(text_width(t, font_px)?);
            }
            (font_px * 3 / 2, w + font_px / 2)
        }
        None => (0, 0),
    };
    let bar_labels_w =
        text_width(bar_top_label(grid), font_px)? + text_width("0", font_px)? + font_px;
    let width = (left + (cells_w + y_band).max(bar_labels_w) + margin)
        .max(text_width(&grid.title, title_px)? + 2 * margin);
    let bar_top = top + cells_h + x_band + font_px;
    let height = bar_top + font_px * 5 / 2 + margin;
    if width > MAX_SIDE || height > MAX_SIDE {
        return Err(Error::Limits(format!(
            "figure grid of {rows} × {cols} cells of {cell_px} px would be {width} × {height} px (limit {MAX_SIDE})"
        )));
    }
    Ok(GridLayout {
        width,
        height,
        rows: rows as u32,
        cols: cols as u32,
        cell_px,
        gap,
        left,
        top,
        title_band,
        font_px,
        bar_labels_span: cells_w.max(bar_labels_w),
        bar_top,
        axes,
    })
}

/// The largest finite value of `plane` (0 if none).
fn plane_max(plane: &Plane) -> f32 {
    plane
        .values
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0, f32::max)
}

/// Where `plane` lies in a `cell_px` square at `origin`: (left, top, width, height), centred, its
/// longer physical side filling the square.
fn plane_rect(origin: (u32, u32), cell_px: u32, plane: &Plane) -> (u32, u32, u32, u32) {
    let (sw, sh) = plane.fitted(cell_px);
    let (sw, sh) = (sw.min(cell_px), sh.min(cell_px));
    (
        origin.0 + (cell_px - sw) / 2,
        origin.1 + (cell_px - sh) / 2,
        sw,
        sh,
    )
}

/// Paints `plane` into the `cell_px` square at `origin`, values / `max` → colour map.
fn paint_plane(
    buf: &mut [u8],
    width: u32,
    origin: (u32, u32),
    cell_px: u32,
    plane: &Plane,
    max: f32,
) {
    // Same mapping as write_png with lo = 0, hi = max.
    let norm = max.max(f32::MIN_POSITIVE);
    let (ox, oy, sw, sh) = plane_rect(origin, cell_px, plane);
    for y in 0..sh {
        let py = (y as usize * plane.height / sh as usize).min(plane.height - 1);
        for x in 0..sw {
            let px = (x as usize * plane.width / sw as usize).min(plane.width - 1);
            let v = plane.values[py * plane.width + px];
            let c = if v.is_nan() {
                [0, 0, 0]
            } else {
                colour(v / norm)
            };
            let i = (((oy + y) * width + ox + x) * 3) as usize;
            buf[i..i + 3].copy_from_slice(&c);
        }
    }
}

/// The colour map from 0 (left) to 1 (right), as wide as the cells.
fn paint_bar(buf: &mut [u8], lay: &GridLayout) {
    let w = lay.cols * (lay.cell_px + lay.gap) - lay.gap;
    for x in 0..w {
        let c = colour(x as f32 / (w - 1).max(1) as f32);
        for y in lay.bar_top..lay.bar_top + lay.font_px {
            let i = ((y * lay.width + lay.left + x) * 3) as usize;
            buf[i..i + 3].copy_from_slice(&c);
        }
    }
}

fn fill_square(buf: &mut [u8], width: u32, origin: (u32, u32), side: u32, c: [u8; 3]) {
    for y in origin.1..origin.1 + side {
        for x in origin.0..origin.0 + side {
            let i = ((y * width + x) * 3) as usize;
            buf[i..i + 3].copy_from_slice(&c);
        }
    }
}

/// The text of the `murk:layout` iTXt chunk: "rows: a | b; columns: c | d | e".
fn layout_text(grid: &FigureGrid, rows: usize, cols: usize) -> String {
    let names = |labels: &[String], n: usize, what: &str| {
        if labels.is_empty() {
            (1..=n)
                .map(|i| format!("{what} {i}"))
                .collect::<Vec<_>>()
                .join(" | ")
        } else {
            labels.join(" | ")
        }
    };
    format!(
        "rows: {}; columns: {}",
        names(&grid.row_labels, rows, "row"),
        names(&grid.col_labels, cols, "column")
    )
}

/// Writes `grid` as an RGB PNG: a white page with the title, column labels above the columns, row
/// labels left of the rows, and each cell a `cell_px` square. Each plane is normalised to its own
/// maximum, or with `shared_scale` to the grid's (values / max → colour map, as [`crate::write_png`]
/// with lo 0, hi max; NaN is black) and scaled to `cell_px` on its longer physical side (nearest
/// neighbour), centred in its cell; empty cells are dark grey. Planes with metre axes get their
/// coordinates under the bottom row and right of the last column. The PNG carries iTXt chunks
/// `murk:layout` ("rows: …; columns: …", labels separated by " | ") and `murk:range`. The file is
/// replaced atomically.
pub fn write_grid_png(path: &Path, grid: &FigureGrid, cell_px: u32) -> Result<()> {
    let lay = grid_layout(grid, cell_px)?;
    let (w, h) = (lay.width, lay.height);
    let mut buf = BACKGROUND.repeat((w * h) as usize);
    let shared = planes(grid).map(plane_max).fold(0.0, f32::max);
    for (r, row) in grid.cells.iter().enumerate() {
        for (c, cell) in row.iter().enumerate() {
            let o = lay.cell_origin(r, c);
            match cell {
                Some(plane) => {
                    let max = if grid.shared_scale {
                        shared
                    } else {
                        plane_max(plane)
                    };
                    paint_plane(&mut buf, w, o, cell_px, plane, max)
                }
                None => fill_square(&mut buf, w, o, cell_px, EMPTY_CELL),
            }
        }
    }
    paint_bar(&mut buf, &lay);
    draw_labels(&mut buf, grid, &lay).map_err(|e| draw_error(path, e))?;

    let (rows, cols) = (lay.rows as usize, lay.cols as usize);
    murk_io::write_atomic(path, |out| {
        let mut enc = png::Encoder::new(out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let fail = |e: png::EncodingError| Error::format(path, e.to_string());
        enc.add_itxt_chunk("murk:layout".into(), layout_text(grid, rows, cols))
            .map_err(fail)?;
        let range = if grid.shared_scale {
            format!(
                "every cell: 0 .. {shared} (the grid's maximum); NaN black; empty cells dark grey"
            )
        } else {
            "each cell: 0 .. its own maximum; NaN black; empty cells dark grey".into()
        };
        enc.add_itxt_chunk("murk:range".into(), range)
            .map_err(fail)?;
        let mut wr = enc.write_header().map_err(fail)?;
        wr.write_image_data(&buf).map_err(fail)?;
        wr.finish().map_err(fail)
    })
    .map_err(|e| name_target(path, e))
}

/// Draws the title and labels over the painted cells (text only goes into the bands around them).
fn draw_labels(
    buf: &mut [u8],
    grid: &FigureGrid,
    lay: &GridLayout,
) -> std::result::Result<(), String> {
    let root = BitMapBackend::with_buffer(buf, (lay.width, lay.height)).into_drawing_area();
    let label = TextStyle::from((FAMILY, f64::from(lay.font_px)).into_font()).color(&BLACK);
    let title_px = f64::from(lay.font_px * 13 / 10);
    let err = |e: DrawingAreaErrorKind<_>| e.to_string();
    if !grid.title.is_empty() {
        let style = TextStyle::from((FAMILY, title_px).into_font())
            .color(&BLACK)
            .pos(Pos::new(HPos::Center, VPos::Center));
        let margin = lay.font_px / 2 + 4;
        let y = margin + lay.title_band / 2;
        root.draw(&Text::new(
            grid.title.as_str(),
            ((lay.width / 2) as i32, y as i32),
            style,
        ))
        .map_err(err)?;
    }
    let half = (lay.cell_px / 2) as i32;
    for (c, text) in grid.col_labels.iter().enumerate() {
        let (x, _) = lay.cell_origin(0, c);
        let y = lay.top as i32 - (lay.font_px as i32 * 9 / 10);
        let style = label.pos(Pos::new(HPos::Center, VPos::Center));
        root.draw(&Text::new(text.as_str(), (x as i32 + half, y), style))
            .map_err(err)?;
    }
    for (r, text) in grid.row_labels.iter().enumerate() {
        let (_, y) = lay.cell_origin(r, 0);
        let x = lay.left as i32 - (lay.font_px as i32 / 2);
        let style = label.pos(Pos::new(HPos::Right, VPos::Center));
        root.draw(&Text::new(text.as_str(), (x, y as i32 + half), style))
            .map_err(err)?;
    }
    if lay.axes {
        draw_axes(&root, grid, lay, &label).map_err(err)?;
    }
    let y = (lay.bar_top + lay.font_px * 2) as i32;
    for (text, x, h) in [
        ("0", lay.left, HPos::Left),
        (
            bar_top_label(grid),
            lay.left + lay.bar_labels_span,
            HPos::Right,
        ),
    ] {
        let style = label.pos(Pos::new(h, VPos::Center));
        root.draw(&Text::new(text, (x as i32, y), style))
            .map_err(err)?;
    }
    root.present().map_err(err)
}

/// The metre coordinates of the planes' edges with their axes' names: the columns' axis under each
/// bottom cell's plane (end values at its edges, "x (m)" between), the rows' right of the last
/// column's planes (end values at its top and bottom, "y (m)" between).
fn draw_axes<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    grid: &FigureGrid,
    lay: &GridLayout,
    label: &TextStyle,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let last_row = lay.rows as usize - 1;
    let last_col = lay.cols as usize - 1;
    for (c, plane) in grid.cells[last_row].iter().enumerate() {
        let Some(p) = plane else { continue };
        let Some([a, _]) = p.axes else {
            continue;
        };
        let (ox, oy, sw, sh) = plane_rect(lay.cell_origin(last_row, c), lay.cell_px, p);
        let y = (oy + sh + lay.font_px * 3 / 4) as i32;
        for (text, x, h) in [
            (metres(a.first_m), ox, HPos::Left),
            (axis_name(&a), ox + sw / 2, HPos::Center),
            (metres(a.last_m), ox + sw, HPos::Right),
        ] {
            let style = label.pos(Pos::new(h, VPos::Center));
            root.draw(&Text::new(text, (x as i32, y), style))?;
        }
    }
    for (r, row) in grid.cells.iter().enumerate() {
        let Some(p) = row[last_col] else { continue };
        let Some([_, a]) = p.axes else {
            continue;
        };
        let (ox, oy, sw, sh) = plane_rect(lay.cell_origin(r, last_col), lay.cell_px, p);
        let x = (ox + sw + lay.font_px / 3) as i32;
        for (text, y, vp) in [
            (metres(a.first_m), oy, VPos::Top),
            (axis_name(&a), oy + sh / 2, VPos::Center),
            (metres(a.last_m), oy + sh, VPos::Bottom),
        ] {
            let style = label.pos(Pos::new(HPos::Left, vp));
            root.draw(&Text::new(text, (x, y as i32), style))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn tmp_dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("murk-view-grid-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// A `w` × `h` plane whose value at (x, y) is `f(x, y)`.
    fn plane(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Plane {
        let mut values = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                values.push(f(x, y));
            }
        }
        Plane {
            width: w,
            height: h,
            values,
            extents: String::new(),
            axes: None,
        }
    }

    struct Decoded {
        width: u32,
        height: u32,
        rgb: Vec<u8>,
        texts: Vec<(String, String)>,
    }

    impl Decoded {
        fn at(&self, x: u32, y: u32) -> [u8; 3] {
            let i = ((y * self.width + x) * 3) as usize;
            [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
        }
        /// Pixels in [x0, x1) × [y0, y1) that are not the page background.
        fn ink(&self, x0: u32, x1: u32, y0: u32, y1: u32) -> usize {
            let mut n = 0;
            for y in y0..y1 {
                for x in x0..x1 {
                    n += usize::from(self.at(x, y) != BACKGROUND);
                }
            }
            n
        }
    }

    fn decode(path: &Path) -> Decoded {
        let dec = png::Decoder::new(std::fs::File::open(path).unwrap());
        let mut reader = dec.read_info().unwrap();
        let mut rgb = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut rgb).unwrap();
        assert_eq!(info.color_type, png::ColorType::Rgb);
        assert_eq!(info.bit_depth, png::BitDepth::Eight);
        rgb.truncate(info.buffer_size());
        let texts = reader
            .info()
            .utf8_text
            .iter()
            .map(|t| (t.keyword.clone(), t.get_text().unwrap()))
            .collect();
        Decoded {
            width: info.width,
            height: info.height,
            rgb,
            texts,
        }
    }

    #[test]
    fn grid_png_has_the_layout_labels_and_the_colour_mapped_cells() {
        let dir = tmp_dir("layout");
        // Brightest at the centre pixel (value 4 → 1 after normalisation), a gradient elsewhere.
        let a = plane(5, 5, |x, y| {
            if (x, y) == (2, 2) {
                4.0
            } else {
                (x + y) as f32 * 0.25
            }
        });
        // Not square: 8 wide, 4 high; values 0..=7 along x, scaled 10 ×.
        let b = plane(8, 4, |x, _| x as f32 * 10.0);
        let c = plane(3, 3, |_, _| f32::NAN);
        let grid = FigureGrid {
            title: "Test figure".into(),
            row_labels: vec!["μt = 0.5".into(), "μt = 2".into()],
            col_labels: vec!["α = 0.15".into(), "α = 0.3".into(), "α = 0.6".into()],
            cells: vec![
                vec![Some(&a), Some(&b), None],
                vec![None, Some(&c), Some(&a)],
            ],
            shared_scale: false,
        };
        let cell = 96;
        let path = dir.join("grid.png");
        write_grid_png(&path, &grid, cell).unwrap();
        let lay = grid_layout(&grid, cell).unwrap();
        let img = decode(&path);

        // Size: three columns and two rows of cells plus the gaps, the label bands and the margins.
        assert_eq!((img.width, img.height), (lay.width, lay.height));
        assert_eq!(
            lay.width,
            lay.left + 3 * cell + 2 * lay.gap + lay.font_px / 2 + 4
        );
        // Under the cells, the colour bar and its labels.
        assert_eq!(lay.bar_top, lay.top + 2 * cell + lay.gap + lay.font_px);
        assert_eq!(
            lay.height,
            lay.bar_top + lay.font_px * 5 / 2 + lay.font_px / 2 + 4
        );
        let bar_y = lay.bar_top + lay.font_px / 2;
        let bar_w = 3 * cell + 2 * lay.gap;
        assert_eq!(img.at(lay.left, bar_y), colour(0.0));
        assert_eq!(img.at(lay.left + bar_w - 1, bar_y), colour(1.0));
        let under = lay.bar_top + lay.font_px;
        let zero_ink = img.ink(lay.left, lay.left + lay.font_px, under, lay.height);
        let max_ink = img.ink(lay.left + bar_w / 2, lay.left + bar_w, under, lay.height);
        assert!(
            zero_ink > 5 && max_ink > 50,
            "bar labels: {zero_ink}, {max_ink}"
        );
        assert!(
            lay.left > 40,
            "no room for the row labels: left = {}",
            lay.left
        );
        assert!(
            lay.top > 2 * lay.font_px,
            "no room for title and column labels"
        );
        assert!(img.width < 3 * cell + 2 * lay.gap + 200 && img.height < 2 * cell + 200);

        // Text is drawn: dark pixels in the title band, above each column, left of each row.
        let title_ink = img.ink(0, img.width, 0, lay.title_band);
        assert!(title_ink > 50, "title band has {title_ink} ink pixels");
        for c in 0..3 {
            let (x0, _) = lay.cell_origin(0, c);
            let n = img.ink(x0, x0 + cell, lay.top - lay.font_px * 9 / 5, lay.top);
            assert!(n > 30, "column label {c} has {n} ink pixels");
        }
        for r in 0..2 {
            let (_, y0) = lay.cell_origin(r, 0);
            let n = img.ink(0, lay.left, y0, y0 + cell);
            assert!(n > 30, "row label {r} has {n} ink pixels");
        }
        // ...and nothing between the cells.
        let (x1, y1) = lay.cell_origin(0, 1);
        assert_eq!(img.ink(x1 - lay.gap, x1, y1, y1 + cell), 0);

        // Cell (0, 0): the centre pixel is the plane's maximum → the top of the colour map.
        let (x0, y0) = lay.cell_origin(0, 0);
        let centre = (x0 + cell / 2, y0 + cell / 2);
        assert_eq!(img.at(centre.0, centre.1), [252, 255, 164]);
        // Its top-left corner is value 0 → the bottom of the map; a pixel in source (4, 1) is 1.25 / 4.
        assert_eq!(img.at(x0, y0), [0, 0, 4]);
        let s = cell as f32 / 5.0;
        let p = ((4.5 * s) as u32, (1.5 * s) as u32);
        assert_eq!(img.at(x0 + p.0, y0 + p.1), colour(1.25 / 4.0));
        // Cell (0, 1): 8 × 4 scaled to 96 × 48, centred vertically; source column 5 holds 50 of max 70.
        let (x0, y0) = lay.cell_origin(0, 1);
        let top = y0 + (cell - cell / 2) / 2;
        assert_eq!(img.at(x0 + 5 * 12 + 6, top + 20), colour(50.0 / 70.0));
        assert_eq!(img.at(x0 + 7 * 12 + 6, top + 20), [252, 255, 164]);
        assert_eq!(
            img.at(x0 + cell / 2, y0 + 5),
            BACKGROUND,
            "above the short plane"
        );
        // Empty cells are dark grey, NaN cells black.
        let (x0, y0) = lay.cell_origin(0, 2);
        assert_eq!(img.at(x0 + cell / 2, y0 + cell / 2), EMPTY_CELL);
        let (x0, y0) = lay.cell_origin(1, 1);
        assert_eq!(img.at(x0 + cell / 2, y0 + cell / 2), [0, 0, 0]);

        let layout = img
            .texts
            .iter()
            .find(|(k, _)| k == "murk:layout")
            .map(|(_, v)| v.as_str());
        assert_eq!(
            layout,
            Some("rows: μt = 0.5 | μt = 2; columns: α = 0.15 | α = 0.3 | α = 0.6")
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A shared scale shows a cell of half the brightness as half as bright (the fading the study is
    /// about); per-cell scales draw both at full brightness. Planes with metre axes get coordinates
    /// under the bottom row and right of the last column, in the physical aspect ratio.
    #[test]
    fn shared_scale_shows_fading_and_axes_are_labelled_in_metres() {
        let dir = tmp_dir("shared");
        let mut bright = plane(4, 4, |_, _| 2.0);
        let mut faint = plane(4, 2, |_, _| 1.0);
        let axis = |name, first_m, last_m| MetreAxis {
            name,
            first_m,
            last_m,
        };
        bright.axes = Some([axis("x", 1.0, -1.0), axis("y", 1.0, -1.0)]);
        // 4 × 2 samples 1 m and 2 m apart: 4 m × 4 m, so drawn square despite the counts.
        faint.axes = Some([axis("x", 1.5, -1.5), axis("y", 1.0, -1.0)]);
        let cell = 64;
        for shared in [false, true] {
            let grid = FigureGrid {
                title: "t".into(),
                row_labels: vec!["r".into()],
                col_labels: vec!["a".into(), "b".into()],
                cells: vec![vec![Some(&bright), Some(&faint)]],
                shared_scale: shared,
            };
            let path = dir.join(format!("shared-{shared}.png"));
            write_grid_png(&path, &grid, cell).unwrap();
            let lay = grid_layout(&grid, cell).unwrap();
            let img = decode(&path);
            assert!(lay.axes);
            let (x1, y1) = lay.cell_origin(0, 1);
            let expect = if shared { colour(0.5) } else { colour(1.0) };
            assert_eq!(
                img.at(x1 + cell / 2, y1 + cell / 2),
                expect,
                "shared {shared}"
            );
            // Square, so the corners of the faint cell are painted too.
            assert_eq!(img.at(x1 + 1, y1 + 1), expect);
            let (x0, y0) = lay.cell_origin(0, 0);
            assert_eq!(img.at(x0 + 1, y0 + 1), colour(1.0));
            // Coordinates under the cells and right of the last one.
            let below = img.ink(x0, x1 + cell, y0 + cell + 1, lay.bar_top - 1);
            let right = img.ink(x1 + cell + 1, lay.width, y0, y0 + cell);
            assert!(below > 40 && right > 40, "axis labels: {below}, {right}");
            let range = &img.texts.iter().find(|(k, _)| k == "murk:range").unwrap().1;
            assert_eq!(range.contains("the grid's maximum"), shared, "{range}");
        }
        // The axes' names, between the end values: "x (m)" under the middle of the bottom cell's
        // plane, "y (m)" right of the last column at mid-height (cells large enough to part them).
        let cell = 200;
        let grid = FigureGrid {
            title: String::new(),
            row_labels: vec![],
            col_labels: vec![],
            cells: vec![vec![Some(&bright)]],
            shared_scale: true,
        };
        let path = dir.join("names.png");
        write_grid_png(&path, &grid, cell).unwrap();
        let lay = grid_layout(&grid, cell).unwrap();
        let img = decode(&path);
        let (x0, y0) = lay.cell_origin(0, 0);
        let (mid, f) = (cell / 2, lay.font_px);
        let name_below = img.ink(x0 + mid - f, x0 + mid + f, y0 + cell + 1, lay.bar_top - 1);
        let gap_below = img.ink(
            x0 + mid - 3 * f,
            x0 + mid - 2 * f,
            y0 + cell + 1,
            lay.bar_top - 1,
        );
        let name_right = img.ink(x0 + cell + 1, lay.width, y0 + mid - f / 2, y0 + mid + f / 2);
        let gap_right = img.ink(x0 + cell + 1, lay.width, y0 + 2 * f, y0 + 3 * f);
        assert!(
            name_below > 20 && gap_below == 0 && name_right > 20 && gap_right == 0,
            "axis names: {name_below} (gap {gap_below}), {name_right} (gap {gap_right})"
        );
        assert_eq!(axis_name(&bright.axes.unwrap()[0]), "x (m)");
        assert_eq!(metres(-0.004), "0.00");
        assert_eq!(metres(-0.98), "−0.98");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn grid_without_labels_has_no_label_bands() {
        let dir = tmp_dir("bare");
        let a = plane(4, 4, |x, _| x as f32);
        let grid = FigureGrid {
            title: String::new(),
            row_labels: vec![],
            col_labels: vec![],
            cells: vec![vec![Some(&a), Some(&a)]],
            shared_scale: false,
        };
        let path = dir.join("bare.png");
        write_grid_png(&path, &grid, 32).unwrap();
        let lay = grid_layout(&grid, 32).unwrap();
        let img = decode(&path);
        let margin = lay.font_px / 2 + 4;
        assert_eq!((lay.left, lay.top), (margin, margin));
        // The cells, then the colour bar; the bar's labels set the width of so small a grid.
        assert_eq!(lay.bar_top, margin + 32 + lay.font_px);
        assert_eq!(img.height, lay.bar_top + lay.font_px * 5 / 2 + margin);
        assert!(img.width > 2 * margin + 2 * 32 + lay.gap);
        // The right end label is anchored at the labels' span, not the narrower bar's end, so it
        // starts right of the left edge instead of being clipped.
        assert!(lay.bar_labels_span > 2 * 32 + lay.gap);
        assert_eq!(img.width, lay.left + lay.bar_labels_span + margin);
        let layout = &img
            .texts
            .iter()
            .find(|(k, _)| k == "murk:layout")
            .unwrap()
            .1;
        assert_eq!(layout, "rows: row 1; columns: column 1 | column 2");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bad_grids_and_paths_are_errors_not_panics() {
        let a = plane(2, 2, |_, _| 1.0);
        let good = || FigureGrid {
            title: "t".into(),
            row_labels: vec!["r".into()],
            col_labels: vec!["c".into()],
            cells: vec![vec![Some(&a)]],
            shared_scale: false,
        };
        let missing = std::env::temp_dir()
            .join(format!("murk-view-no-such-dir-{}", std::process::id()))
            .join("grid.png");
        let e = write_grid_png(&missing, &good(), 16).unwrap_err();
        assert!(
            e.to_string().contains(&missing.display().to_string()),
            "error does not name the path: {e}"
        );
        assert!(!missing.parent().unwrap().exists());

        let mut g = good();
        g.row_labels.push("extra".into());
        assert!(matches!(
            write_grid_png(&missing, &g, 16),
            Err(Error::Parameter(_))
        ));
        let mut g = good();
        g.cells.push(vec![]);
        assert!(matches!(
            write_grid_png(&missing, &g, 16),
            Err(Error::Parameter(_))
        ));
        let mut g = good();
        g.cells.clear();
        assert!(matches!(
            write_grid_png(&missing, &g, 16),
            Err(Error::Parameter(_))
        ));
        assert!(matches!(
            write_grid_png(&missing, &good(), 0),
            Err(Error::Parameter(_))
        ));
        let broken = Plane {
            width: 3,
            height: 3,
            values: vec![1.0; 4],
            extents: String::new(),
            axes: None,
        };
        let mut g = good();
        g.cells[0][0] = Some(&broken);
        assert!(matches!(
            write_grid_png(&missing, &g, 16),
            Err(Error::Parameter(_))
        ));
    }

    #[test]
    fn a_one_cell_grid_has_one_maximum() {
        fn grid(cells: Vec<Vec<Option<&Plane>>>, shared_scale: bool) -> FigureGrid<'_> {
            FigureGrid {
                title: String::new(),
                row_labels: Vec::new(),
                col_labels: Vec::new(),
                cells,
                shared_scale,
            }
        }
        let p = plane(4, 4, |x, y| (x + y) as f32);
        assert_eq!(bar_top_label(&grid(vec![vec![Some(&p)]], false)), "max");
        assert_eq!(bar_top_label(&grid(vec![vec![Some(&p)]], true)), "max");
        let two = vec![vec![Some(&p), Some(&p)]];
        assert_eq!(
            bar_top_label(&grid(two.clone(), true)),
            "max of the whole grid"
        );
        assert_eq!(bar_top_label(&grid(two, false)), "max of each cell");
    }
}
