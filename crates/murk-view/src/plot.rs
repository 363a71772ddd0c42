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
    /// Ranges the axes span at least (data outside them widens them): a metric bounded to [0, 1]
    /// drawn over [0, 1] so that noise does not look like a trend, and x axes from a common origin.
    pub x_range: Option<(f64, f64)>,
    pub y_range: Option<(f64, f64)>,
}

/// Size (pixels, or SVG user units) of the plots written here.
pub const PLOT_SIZE: (u32, u32) = (480, 320);

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
    let widen = |(a, b): (f64, f64), fixed: Option<(f64, f64)>| match fixed {
        Some((lo, hi)) if range.is_some() => (lo.min(a), hi.max(b)),
        Some(r) => r,
        None => (a, b),
    };
    // A fixed range is kept exactly where the data lie inside it (no padding beyond [0, 1]).
    let inside = |(a, b): (f64, f64), fixed: Option<(f64, f64)>, data: Option<(f64, f64)>| match (
        fixed, data,
    ) {
        (Some((lo, hi)), Some((d0, d1))) if d0 >= lo && d1 <= hi => (lo, hi),
        _ => widen((a, b), fixed),
    };
    let data_x = data_span(&series, |p| (p.0, p.0));
    let data_y = data_span(&series, |p| (p.1 - p.2, p.1 + p.2));
    let (x0, x1) = inside((x0, x1), plot.x_range, data_x);
    let (y0, y1) = inside((y0, y1), plot.y_range, data_y);
    // The legend lies right of the chart, so it never hides a point nor stretches an axis.
    let mut labels: Vec<(usize, &str)> = plot
        .series
        .iter()
        .enumerate()
        .filter(|(_, s)| !s.label.is_empty())
        .map(|(i, s)| (i, s.label.as_str()))
        .collect();
    // A lone series is named in the title: a legend for one line would take a third of the width.
    let title = match labels.as_slice() {
        [(_, only)] if plot.series.len() == 1 => format!("{} ({only})", plot.title),
        _ => plot.title.clone(),
    };
    if plot.series.len() == 1 {
        labels.clear();
    }
    let legend_w = if labels.is_empty() {
        0
    } else {
        let font = FontDesc::new(FontFamily::Name(FAMILY), 13.0, FontStyle::Normal);
        let widest = labels
            .iter()
            .map(|(_, l)| font.box_size(l).map_or(8 * l.len() as u32, |b| b.0))
            .max()
            .unwrap_or(0);
        (widest + 36).min(root.dim_in_pixel().0 / 3)
    };
    let (root, legend) = root.split_horizontally(root.dim_in_pixel().0 - legend_w);

    let mut chart = ChartBuilder::on(&root)
        .caption(&title, (FAMILY, 17))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(plot.x_label.as_str())
        .y_desc(plot.y_label.as_str())
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .label_style((FAMILY, 13))
        .axis_desc_style((FAMILY, 14))
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

    for (i, pts) in series.iter().enumerate() {
        let c = COLOURS[i % COLOURS.len()];
        let bars = pts
            .iter()
            .filter(|p| p.2 > 0.0)
            .map(|&(x, y, e)| ErrorBar::new_vertical(x, y - e, y, y + e, c.stroke_width(1), 8));
        chart.draw_series(bars).map_err(err)?;
        chart
            .draw_series(LineSeries::new(
                pts.iter().map(|&(x, y, _)| (x, y)),
                c.stroke_width(2),
            ))
            .map_err(err)?;
        chart
            .draw_series(
                pts.iter()
                    .map(|&(x, y, _)| Circle::new((x, y), 3, c.filled())),
            )
            .map_err(err)?;
    }
    for (k, (i, label)) in labels.iter().enumerate() {
        let c = COLOURS[i % COLOURS.len()];
        let y = 40 + 18 * k as i32;
        legend
            .draw(&PathElement::new(vec![(4, y), (26, y)], c.stroke_width(2)))
            .map_err(err)?;
        let style = TextStyle::from((FAMILY, 13).into_font())
            .color(&BLACK)
            .pos(Pos::new(HPos::Left, VPos::Center));
        legend
            .draw(&Text::new(*label, (32, y), style))
            .map_err(err)?;
    }
    root.present().map_err(err)?;
    legend.present().map_err(err)
}

/// The smallest and largest of `f`'s bounds over every point; None without points.
fn data_span(
    series: &[Vec<(f64, f64, f64)>],
    f: impl Fn(&(f64, f64, f64)) -> (f64, f64),
) -> Option<(f64, f64)> {
    series.iter().flatten().map(f).fold(None, |acc, (a, b)| {
        let (a, b) = (a.min(b), a.max(b));
        Some(acc.map_or((a, b), |(lo, hi): (f64, f64)| (lo.min(a), hi.max(b))))
    })
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
            // Fixed, so that the plot with and without spreads has the same grid lines.
            x_range: Some((0.0, 2.0)),
            y_range: Some((0.0, 1.0)),
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

    /// An IoU of 0.68–0.71 over [0, 1] is drawn on [0, 1] (ticks 0.0 … 1.0), not zoomed so that noise
    /// looks like a trend; data beyond a fixed range widen it rather than leave the chart.
    #[test]
    fn fixed_ranges_hold_unless_the_data_leave_them() {
        let dir = std::env::temp_dir().join(format!("murk-view-fixed-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let svg = |ys: &[f64]| {
            let plot = LinePlot {
                title: "IoU".into(),
                x_label: "μt".into(),
                y_label: "IoU".into(),
                series: vec![Series {
                    label: "a long series label".into(),
                    points: ys
                        .iter()
                        .enumerate()
                        .map(|(i, &y)| (1.0 + i as f64, y, 0.01))
                        .collect(),
                }],
                x_range: Some((0.0, 1.0)),
                y_range: Some((0.0, 1.0)),
            };
            let p = dir.join("fixed.svg");
            write_plot_svg(&p, &plot).unwrap();
            std::fs::read_to_string(&p).unwrap()
        };
        let tick_texts = |svg: &str| -> Vec<String> {
            svg.split("<text")
                .skip(1)
                .filter_map(|t| {
                    Some(
                        t.split_once('>')?
                            .1
                            .split_once("</text>")?
                            .0
                            .trim()
                            .to_string(),
                    )
                })
                .collect()
        };
        let zoomed = tick_texts(&svg(&[0.68, 0.71, 0.69]));
        for t in ["0.0", "0.2", "1.0"] {
            assert!(zoomed.iter().any(|x| x == t), "no tick {t}: {zoomed:?}");
        }
        // x from the common origin 0 even though the data start at 1.
        assert!(
            zoomed.iter().filter(|x| *x == "0.0").count() >= 2,
            "{zoomed:?}"
        );
        let wide = tick_texts(&svg(&[0.5, 1.3]));
        assert!(wide.iter().any(|x| x == "1.3" || x == "1.4"), "{wide:?}");
        // A lone series is named in the title, not in a legend.
        assert!(
            wide.iter().any(|x| x == "IoU (a long series label)"),
            "{wide:?}"
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
                ..Default::default()
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
