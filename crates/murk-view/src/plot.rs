//! Line plots of metrics (one line per series, points marked, vertical error bars where a point has a
//! spread), written as SVG (text stays text) or PNG.

use crate::{draw_error, ensure_font, name_target, FAMILY};
use murk_core::{Error, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// One line: points (x, y, spread); spread > 0 draws an error bar from y − spread to y + spread.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64, f64)>,
}

/// A plot of one or more series against a shared pair of axes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LinePlot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
}

/// Size (pixels, or SVG user units) of the plots written here.
pub const PLOT_SIZE: (u32, u32) = (800, 500);

/// Tableau's ten categorical colours (matplotlib's default cycle); series beyond ten reuse them.
const COLOURS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// The series' points with non-finite x or y dropped and a non-finite or negative spread read as none.
fn finite_points(s: &Series) -> Vec<(f64, f64, f64)> {
    s.points
        .iter()
        .filter(|(x, y, _)| x.is_finite() && y.is_finite())
        .map(|&(x, y, e)| (x, y, if e.is_finite() && e > 0.0 { e } else { 0.0 }))
        .collect()
}

/// [lo, hi] widened by 5 % each side; a single value gets ±10 % of itself (±1 around zero).
fn padded(lo: f64, hi: f64) -> (f64, f64) {
    let d = if hi > lo {
        (hi - lo) * 0.05
    } else if lo == 0.0 {
        1.0
    } else {
        lo.abs() * 0.1
    };
    let (a, b) = (lo - d, hi + d);
    if a.is_finite() && b.is_finite() && b > a {
        (a, b)
    } else {
        (lo, if hi > lo { hi } else { lo + 1.0 })
    }
}

/// Axis ranges covering every finite point (and its error bar); None when there is nothing to plot.
fn ranges(series: &[Vec<(f64, f64, f64)>]) -> Option<((f64, f64), (f64, f64))> {
    let pts = || series.iter().flatten();
    pts().next()?;
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y, e) in pts() {
        x0 = x0.min(x);
        x1 = x1.max(x);
        // An error bar too wide to represent is left out of the range rather than breaking it.
        let (lo, hi) = if (y - e).is_finite() && (y + e).is_finite() {
            (y - e, y + e)
        } else {
            (y, y)
        };
        y0 = y0.min(lo);
        y1 = y1.max(hi);
    }
    Some((padded(x0, x1), padded(y0, y1)))
}

/// Draws `plot` onto `root`; errors as text.
fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    plot: &LinePlot,
) -> std::result::Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(err)?;
    let series: Vec<_> = plot.series.iter().map(finite_points).collect();
    let range = ranges(&series);
    let ((x0, x1), (y0, y1)) = range.unwrap_or(((0.0, 1.0), (0.0, 1.0)));
    // Headroom above the data for the legend (upper right), so it never hides a point: about 21 px a
    // label plus its frame, out of the plotting area's height (the page less margins, title, x axis).
    let labels = plot.series.iter().filter(|s| !s.label.is_empty()).count();
    let plot_h = f64::from(root.dim_in_pixel().1.saturating_sub(32 + 40 + 52).max(1));
    let room = if labels > 0 && range.is_some() {
        ((21 * labels + 18) as f64 / plot_h).min(0.6)
    } else {
        0.0
    };
    let y1 = y0 + (y1 - y0) / (1.0 - room);

    let mut chart = ChartBuilder::on(root)
        .caption(&plot.title, (FAMILY, 24))
        .margin(16)
        .x_label_area_size(52)
        .y_label_area_size(76)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(plot.x_label.as_str())
        .y_desc(plot.y_label.as_str())
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 17))
        .light_line_style(TRANSPARENT)
        .bold_line_style(RGBColor(225, 225, 225))
        .draw()
        .map_err(err)?;

    if range.is_none() {
        let style = TextStyle::from((FAMILY, 22).into_font())
            .color(&RGBColor(110, 110, 110))
            .pos(Pos::new(HPos::Center, VPos::Center));
        chart
            .plotting_area()
            .draw(&Text::new(
                "no data",
                ((x0 + x1) / 2.0, (y0 + y1) / 2.0),
                style,
            ))
            .map_err(err)?;
    }

    for (i, (s, pts)) in plot.series.iter().zip(&series).enumerate() {
        let c = COLOURS[i % COLOURS.len()];
        let bars = pts
            .iter()
            .filter(|p| p.2 > 0.0)
            .map(|&(x, y, e)| ErrorBar::new_vertical(x, y - e, y, y + e, c.stroke_width(1), 8));
        chart.draw_series(bars).map_err(err)?;
        let line = chart
            .draw_series(LineSeries::new(
                pts.iter().map(|&(x, y, _)| (x, y)),
                c.stroke_width(2),
            ))
            .map_err(err)?;
        if !s.label.is_empty() {
            line.label(s.label.as_str()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 22, y)], c.stroke_width(2))
            });
        }
        chart
            .draw_series(
                pts.iter()
                    .map(|&(x, y, _)| Circle::new((x, y), 3, c.filled())),
            )
            .map_err(err)?;
    }
    if labels > 0 {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(160, 160, 160))
            .label_font((FAMILY, 15))
            .draw()
            .map_err(err)?;
    }
    root.present().map_err(err)
}

/// Writes `plot` as an SVG of [`PLOT_SIZE`]: axis ranges from the finite data (padded; NaN and infinite
/// values are skipped), a legend of the series labels, error bars where the spread is > 0, and "no data"
/// in an empty frame when nothing is finite. Text is SVG text in the "sans-serif" family. The file is
/// replaced atomically.
pub fn write_plot_svg(path: &Path, plot: &LinePlot) -> Result<()> {
    ensure_font()?; // plotters measures labels with it while laying out the chart
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, PLOT_SIZE).into_drawing_area();
        draw(&root, plot).map_err(|e| draw_error(path, e))?;
    }
    murk_io::write_atomic(path, |w| {
        w.write_all(svg.as_bytes()).map_err(|e| Error::io(path, e))
    })
    .map_err(|e| name_target(path, e))
}

/// Writes `plot` as an RGB PNG of [`PLOT_SIZE`] pixels, drawn as [`write_plot_svg`] draws it, with the
/// text rendered in the embedded DejaVu Sans. The file is replaced atomically.
pub fn write_plot_png(path: &Path, plot: &LinePlot) -> Result<()> {
    ensure_font()?;
    let (w, h) = PLOT_SIZE;
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        draw(&root, plot).map_err(|e| draw_error(path, e))?;
    }
    murk_io::write_atomic(path, |out| {
        let mut enc = png::Encoder::new(out, w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let fail = |e: png::EncodingError| Error::format(path, e.to_string());
        let mut wr = enc.write_header().map_err(fail)?;
        wr.write_image_data(&rgb).map_err(fail)?;
        wr.finish().map_err(fail)
    })
    .map_err(|e| name_target(path, e))
}

/// plotters' own tick text, without the sign of a key point that rounds to zero ("-0.0").
fn tick(v: &f64) -> String {
    let text = plotters::data::float::FloatPrettyPrinter {
        allow_scientific: false,
        min_decimal: 1,
        max_decimal: 5,
    }
    .print(*v);
    match text.strip_prefix('-') {
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_string(),
        _ => text,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_never_read_minus_zero() {
        assert_eq!(tick(&-0.0), "0.0");
        assert_eq!(tick(&-1e-17), "0.0");
        assert_eq!(tick(&-0.25), "-0.25");
        assert_eq!(tick(&1.5), "1.5");
    }
    use std::path::PathBuf;

    fn tmp_dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("murk-view-plot-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn sample() -> LinePlot {
        LinePlot {
            title: "Contrast against thickness".into(),
            x_label: "optical thickness μt".into(),
            y_label: "contrast".into(),
            series: vec![
                Series {
                    label: "Phasor Fields".into(),
                    points: vec![(0.5, 0.9, 0.05), (1.0, 0.7, 0.08), (2.0, 0.4, 0.1)],
                },
                Series {
                    label: "CDT".into(),
                    points: vec![
                        (0.5, 0.8, 0.0),
                        (1.0, f64::NAN, 0.0),
                        (2.0, 0.5, f64::INFINITY),
                    ],
                },
            ],
        }
    }

    /// Crude well-formedness: an <svg> root, and every element opened is closed in order.
    fn assert_xmlish(svg: &str) {
        assert!(
            svg.trim_start().starts_with("<svg"),
            "{}",
            &svg[..svg.len().min(200)]
        );
        assert!(svg.trim_end().ends_with("</svg>"));
        let mut stack = Vec::new();
        let mut rest = svg;
        while let Some(i) = rest.find('<') {
            let end = rest[i..].find('>').expect("unclosed tag") + i;
            let tag = &rest[i + 1..end];
            if let Some(name) = tag.strip_prefix('/') {
                assert_eq!(
                    stack.pop(),
                    Some(name.trim().to_string()),
                    "mismatched </{name}>"
                );
            } else if !tag.ends_with('/') && !tag.starts_with('?') && !tag.starts_with('!') {
                stack.push(tag.split_whitespace().next().unwrap().to_string());
            }
            rest = &rest[end + 1..];
        }
        assert!(stack.is_empty(), "unclosed elements {stack:?}");
    }

    #[test]
    fn svg_has_labels_lines_and_error_bars() {
        let dir = tmp_dir("svg");
        let path = dir.join("plot.svg");
        write_plot_svg(&path, &sample()).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert_xmlish(&svg);
        for text in [
            "Contrast against thickness",
            "optical thickness μt",
            "contrast",
            "Phasor Fields",
            "CDT",
        ] {
            assert!(svg.contains(text), "{text:?} missing from the SVG");
        }
        assert!(svg.contains("<polyline") || svg.contains("<path"));
        assert!(!svg.contains("no data"));
        assert!(
            !svg.contains("NaN") && !svg.contains("inf"),
            "non-finite coordinates"
        );
        // The same plot without spreads: one circle per finite point (3 + 2), fewer lines. With spreads,
        // each of the three error bars adds its lines (and plotters marks its centre with a circle).
        let (bare_lines, bare_circles) = {
            let mut p = sample();
            for s in &mut p.series {
                for pt in &mut s.points {
                    pt.2 = 0.0;
                }
            }
            let q = dir.join("bare.svg");
            write_plot_svg(&q, &p).unwrap();
            let t = std::fs::read_to_string(&q).unwrap();
            (t.matches("<line").count(), t.matches("<circle").count())
        };
        assert_eq!(bare_circles, 5);
        assert_eq!(svg.matches("<circle").count(), 5 + 3);
        let lines = svg.matches("<line").count();
        assert!(
            lines >= bare_lines + 3 * 3,
            "no error bars drawn ({lines} vs {bare_lines} lines)"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn ranges_cover_the_data_and_survive_degenerate_input() {
        let r = ranges(&[finite_points(&sample().series[0])]).unwrap();
        assert!(r.0 .0 < 0.5 && r.0 .1 > 2.0);
        assert!(r.1 .0 < 0.3 && r.1 .1 > 0.95);
        // One point: a non-empty range around it.
        let one = ranges(&[vec![(3.0, -2.0, 0.0)]]).unwrap();
        assert!(one.0 .0 < 3.0 && one.0 .1 > 3.0 && one.1 .0 < -2.0 && one.1 .1 > -2.0);
        let zero = ranges(&[vec![(0.0, 0.0, 0.0)]]).unwrap();
        assert_eq!(zero, ((-1.0, 1.0), (-1.0, 1.0)));
        assert!(ranges(&[vec![], vec![]]).is_none());
        let wide = ranges(&[vec![(-f64::MAX, f64::MAX, 0.0), (f64::MAX, -f64::MAX, 0.0)]]).unwrap();
        assert!(wide.0 .0.is_finite() && wide.0 .1.is_finite() && wide.0 .1 > wide.0 .0);
    }

    #[test]
    fn empty_or_non_finite_plots_say_no_data() {
        let dir = tmp_dir("empty");
        for (i, series) in [
            vec![],
            vec![Series {
                label: "nothing".into(),
                points: vec![],
            }],
            vec![Series {
                label: "all NaN".into(),
                points: vec![(f64::NAN, 1.0, 0.0), (1.0, f64::INFINITY, 0.0)],
            }],
        ]
        .into_iter()
        .enumerate()
        {
            let plot = LinePlot {
                title: "empty".into(),
                x_label: "x axis".into(),
                y_label: "y axis".into(),
                series,
            };
            let path = dir.join(format!("empty{i}.svg"));
            write_plot_svg(&path, &plot).unwrap();
            let svg = std::fs::read_to_string(&path).unwrap();
            assert_xmlish(&svg);
            assert!(svg.contains("no data") && svg.contains("x axis") && svg.contains("y axis"));
            for s in &plot.series {
                assert!(svg.contains(&s.label));
            }
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn png_plot_decodes_and_has_ink() {
        let dir = tmp_dir("png");
        let path = dir.join("plot.png");
        write_plot_png(&path, &sample()).unwrap();
        let mut reader = png::Decoder::new(std::fs::File::open(&path).unwrap())
            .read_info()
            .unwrap();
        let mut rgb = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut rgb).unwrap();
        assert_eq!((info.width, info.height), PLOT_SIZE);
        // The first series' colour appears (its line), and so does black-ish text.
        let px: Vec<&[u8]> = rgb[..info.buffer_size()].chunks(3).collect();
        assert!(px.iter().any(|p| *p == [31, 119, 180]));
        assert!(px.iter().filter(|p| p.iter().all(|&v| v < 60)).count() > 200);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn missing_directory_is_an_error_naming_the_path() {
        let missing = std::env::temp_dir()
            .join(format!("murk-view-no-such-dir-{}", std::process::id()))
            .join("plot.svg");
        for e in [
            write_plot_svg(&missing, &sample()).unwrap_err(),
            write_plot_png(&missing, &sample()).unwrap_err(),
            write_plot_svg(&missing, &LinePlot::default()).unwrap_err(),
        ] {
            assert!(
                e.to_string().contains(&missing.display().to_string()),
                "error does not name the path: {e}"
            );
        }
    }
}
