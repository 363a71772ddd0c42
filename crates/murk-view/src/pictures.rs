//! Pictures of a reconstructed volume: maximum-intensity projections along each axis and a depth map,
//! false-coloured, written as PNG with their extents in tEXt chunks, plus a one-page index.html.

use murk_core::{Result, Volume};
use std::path::{Path, PathBuf};

/// Key colours of a perceptual dark-to-bright map (close to matplotlib's "inferno").
const INFERNO: [[f32; 3]; 6] = [
    [0.0, 0.0, 4.0],
    [66.0, 10.0, 104.0],
    [147.0, 38.0, 103.0],
    [221.0, 81.0, 58.0],
    [252.0, 165.0, 10.0],
    [252.0, 255.0, 164.0],
];

/// Colour of `v` ∈ [0, 1].
pub(crate) fn colour(v: f32) -> [u8; 3] {
    let x = v.clamp(0.0, 1.0) * (INFERNO.len() - 1) as f32;
    let i = (x.floor() as usize).min(INFERNO.len() - 2);
    let f = x - i as f32;
    let (a, b) = (INFERNO[i], INFERNO[i + 1]);
    [0, 1, 2].map(|k| (a[k] + (b[k] - a[k]) * f).round() as u8)
}

/// A 2-D float image, row-major, with what its axes mean.
pub struct Plane {
    pub width: usize,
    pub height: usize,
    pub values: Vec<f32>,
    /// e.g. "columns: x from +0.98 m (left) to −0.98 m (right); rows: y from +0.98 m (top) to −0.98 m (bottom)".
    pub extents: String,
    /// The columns' axis and the rows' (names and end coordinates); `None` for a plane without one
    /// physical scale (a montage), drawn one square per value.
    pub axes: Option<[MetreAxis; 2]>,
}

/// A plane's axis in metres: its name (`x`, `y`, `z`) and the coordinates of its first and last
/// samples, in the order drawn (the front view's columns run from +x on the left to −x).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MetreAxis {
    pub name: &'static str,
    pub first_m: f64,
    pub last_m: f64,
}

impl MetreAxis {
    /// `axis` drawn from its end to its start when `reversed`.
    pub fn of(name: &'static str, axis: &murk_core::Axis, reversed: bool) -> MetreAxis {
        let (first_m, last_m) = if reversed {
            (axis.end, axis.start)
        } else {
            (axis.start, axis.end)
        };
        MetreAxis {
            name,
            first_m,
            last_m,
        }
    }
}

impl Plane {
    /// Physical width over height: each sample covers its axis's spacing, so a 73 × 59 plane over
    /// equal extents is square. Without axes (or with a degenerate one), one square per value.
    pub fn aspect(&self) -> f64 {
        let by_count = self.width as f64 / self.height as f64;
        let Some([c, r]) = self.axes else {
            return by_count;
        };
        let pitch =
            |a: MetreAxis, n: usize| (n > 1).then(|| (a.last_m - a.first_m).abs() / (n - 1) as f64);
        match (pitch(c, self.width), pitch(r, self.height)) {
            (Some(dx), Some(dy)) if dx > 0.0 && dy > 0.0 => {
                (dx * self.width as f64) / (dy * self.height as f64)
            }
            _ => by_count,
        }
    }

    /// Pixel size (width, height) of this plane drawn with `long_px` pixels on its longer physical side.
    pub fn fitted(&self, long_px: u32) -> (u32, u32) {
        let a = self.aspect();
        let l = f64::from(long_px);
        let (w, h) = if a >= 1.0 { (l, l / a) } else { (l * a, l) };
        ((w.round() as u32).max(1), (h.round() as u32).max(1))
    }
}

/// The projections murk draws, in the order they appear on the page.
pub struct Views {
    pub front: Plane,
    pub top: Plane,
    pub side: Plane,
    /// Depth (m) of the brightest voxel per (x, y), NaN where the front MIP is below 20 % of its maximum.
    pub depth: Plane,
    /// The volume's index of the brightest voxel behind each front pixel (row-major as `front`).
    pub front_voxels: Vec<usize>,
}

/// Below this share of the front view's maximum a pixel has no depth (nor normal): dim columns hold
/// no surface to speak of.
pub(crate) const SURFACE_LEVEL: f32 = 0.2;

fn axis_text(name: &str, a: &murk_core::Axis, reversed: bool, from: &str, to: &str) -> String {
    let (s, e) = if reversed {
        (a.end, a.start)
    } else {
        (a.start, a.end)
    };
    format!("{name} from {s:+.3} m ({from}) to {e:+.3} m ({to})")
}

/// Projections of an intensity volume (C order [nx, ny, nz]). The front view is seen from the wall
/// looking into the hidden scene (+z), with +y up, so +x is on the left.
pub fn views(vol: &Volume, intensity: &[f32]) -> Views {
    let (nx, ny, nz) = (vol.x.n, vol.y.n, vol.z.n);
    let at = |ix: usize, iy: usize, iz: usize| intensity[vol.index(ix, iy, iz)];
    // Row r of an image with +y up is iy = ny − 1 − r; column c with +x on the left is ix = nx − 1 − c.
    let mut front = vec![0f32; nx * ny];
    let mut depth = vec![f32::NAN; nx * ny];
    let mut front_voxels = vec![0; nx * ny];
    for r in 0..ny {
        for c in 0..nx {
            let (ix, iy) = (nx - 1 - c, ny - 1 - r);
            let (iz, m) = (0..nz)
                .map(|iz| (iz, at(ix, iy, iz)))
                .fold((0, f32::MIN), |a, b| if b.1 > a.1 { b } else { a });
            front[r * nx + c] = m;
            depth[r * nx + c] = vol.z.at(iz) as f32;
            front_voxels[r * nx + c] = vol.index(ix, iy, iz);
        }
    }
    let fmax = front.iter().cloned().fold(0.0, f32::max);
    for (d, f) in depth.iter_mut().zip(&front) {
        if *f < SURFACE_LEVEL * fmax {
            *d = f32::NAN;
        }
    }
    let mut top = vec![0f32; nz * nx];
    for r in 0..nz {
        for c in 0..nx {
            top[r * nx + c] = (0..ny).map(|iy| at(nx - 1 - c, iy, r)).fold(0.0, f32::max);
        }
    }
    let mut side = vec![0f32; ny * nz];
    for r in 0..ny {
        for c in 0..nz {
            side[r * nz + c] = (0..nx).map(|ix| at(ix, ny - 1 - r, c)).fold(0.0, f32::max);
        }
    }
    // Columns run from +x (left) to −x, rows from +y (top) to −y, depth from near to far.
    let (xs, ys, zs) = (
        MetreAxis::of("x", &vol.x, true),
        MetreAxis::of("y", &vol.y, true),
        MetreAxis::of("z", &vol.z, false),
    );
    let cols_x = axis_text("columns: x", &vol.x, true, "left", "right");
    let rows_y = axis_text("rows: y", &vol.y, true, "top", "bottom");
    let rows_z = axis_text("rows: depth z", &vol.z, false, "top", "bottom");
    let cols_z = axis_text("columns: depth z", &vol.z, false, "left", "right");
    Views {
        front: Plane {
            width: nx,
            height: ny,
            values: front,
            extents: format!("{cols_x}; {rows_y}"),
            axes: Some([xs, ys]),
        },
        depth: Plane {
            width: nx,
            height: ny,
            values: depth,
            extents: format!(
                "{cols_x}; {rows_y}; colour: depth z from {:.3} m (dark) to {:.3} m (bright)",
                vol.z.start, vol.z.end
            ),
            axes: Some([xs, ys]),
        },
        top: Plane {
            width: nx,
            height: nz,
            values: top,
            extents: format!("{cols_x}; {rows_z}"),
            axes: Some([xs, zs]),
        },
        side: Plane {
            width: nz,
            height: ny,
            values: side,
            extents: format!("{cols_z}; {rows_y}"),
            axes: Some([zs, ys]),
        },
        front_voxels,
    }
}

/// Writes `plane` as an RGB PNG of roughly 384 px on its longer physical side (at least one pixel per
/// value; nearest neighbour, so voxels stay visible), its sides in the plane's physical aspect ratio.
/// Values map [lo, hi] → colour map; NaN is black.
pub fn write_png(path: &Path, plane: &Plane, lo: f32, hi: f32) -> Result<()> {
    write_pixels(path, plane, format!("{lo} .. {hi}"), |i| {
        let v = plane.values[i];
        if v.is_nan() {
            [0, 0, 0]
        } else {
            colour((v - lo) / (hi - lo).max(f32::MIN_POSITIVE))
        }
    })
}

/// Writes an RGB PNG of `plane`'s size and aspect (as [`write_png`]), value `i` of the plane drawn
/// in `colour_of(i)`, with the extents and `range` in its text chunks.
pub(crate) fn write_pixels(
    path: &Path,
    plane: &Plane,
    range: String,
    colour_of: impl Fn(usize) -> [u8; 3],
) -> Result<()> {
    let long = (plane.width.max(plane.height) as u32).max(384);
    let (w, h) = plane.fitted(long);
    let (w, h) = (w as usize, h as usize);
    let mut rgb = Vec::with_capacity(w * h * 3);
    for y in 0..h {
        let py = (y * plane.height / h).min(plane.height - 1);
        for x in 0..w {
            let px = (x * plane.width / w).min(plane.width - 1);
            rgb.extend_from_slice(&colour_of(py * plane.width + px));
        }
    }
    murk_io::write_atomic(path, |out| {
        let mut enc = png::Encoder::new(out, w as u32, h as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let fail = |e: png::EncodingError| murk_core::Error::format(path, e.to_string());
        enc.add_itxt_chunk("murk:extents".into(), plane.extents.clone())
            .map_err(fail)?;
        enc.add_itxt_chunk("murk:range".into(), range)
            .map_err(fail)?;
        let mut wr = enc.write_header().map_err(fail)?;
        wr.write_image_data(&rgb).map_err(fail)?;
        wr.finish().map_err(fail)
    })
}

/// The files [`write_views`] and [`write_index`] write into their folder.
pub const PICTURE_FILES: [&str; 6] = [
    "front.png",
    "top.png",
    "side.png",
    "depth.png",
    crate::normal_map::FILE,
    "index.html",
];

/// Refuses, before anything is computed, a pictures folder `dir` that is a file or names the file
/// `out`, or whose pictures would replace one of `inputs` or land on `out`.
pub fn check_pictures_dir(dir: &Path, inputs: &[&Path], out: &Path) -> Result<()> {
    let refuse = |why: String| Err(murk_core::Error::param(format!("{}: {why}", dir.display())));
    if dir.exists() && !dir.is_dir() {
        return refuse("the pictures need a folder, and this is a file".into());
    }
    if !dir.exists() {
        // The folder is made only after the reconstruction: probe now that it can be, with one
        // made and removed at once in the nearest folder that exists.
        let base = dir
            .ancestors()
            .skip(1)
            .find(|a| a.as_os_str().is_empty() || a.exists())
            .filter(|a| !a.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        if !base.is_dir() {
            return refuse(format!(
                "cannot be made: {} is not a folder",
                base.display()
            ));
        }
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.subsec_nanos());
        let probe = base.join(format!(".murk-probe-{}-{nanos}", std::process::id()));
        if let Err(e) = std::fs::create_dir(&probe) {
            return refuse(format!("cannot be made in {}: {e}", base.display()));
        }
        let _ = std::fs::remove_dir(&probe);
    }
    if murk_io::same_target(dir, out) {
        return refuse(format!(
            "the pictures' folder is the output {}",
            out.display()
        ));
    }
    for name in PICTURE_FILES {
        let p = dir.join(name);
        if murk_io::same_target(&p, out) {
            return refuse(format!("its {name} would be the output {}", out.display()));
        }
        if dir.is_dir() {
            murk_io::check_output(&p, inputs)?;
        }
    }
    Ok(())
}

/// Writes front.png, top.png, side.png and depth.png into `dir`, and normals.png where the method gave
/// `normals`; returns their paths with captions.
pub fn write_views(
    dir: &Path,
    vol: &Volume,
    intensity: &[f32],
    normals: Option<&[[f32; 3]]>,
) -> Result<Vec<(PathBuf, String)>> {
    murk_io::create_output_dir(dir)?;
    let v = views(vol, intensity);
    let max = intensity.iter().cloned().fold(0.0, f32::max);
    let mut out = Vec::new();
    for (name, plane, caption) in [
        (
            "front.png",
            &v.front,
            "front: maximum along depth, seen from the wall",
        ),
        ("top.png", &v.top, "top: maximum along y"),
        ("side.png", &v.side, "side: maximum along x"),
    ] {
        let p = dir.join(name);
        write_png(&p, plane, 0.0, max)?;
        out.push((p, format!("{caption} ({})", plane.extents)));
    }
    let p = dir.join("depth.png");
    let (z0, z1) = (
        vol.z.start.min(vol.z.end) as f32,
        vol.z.start.max(vol.z.end) as f32,
    );
    write_png(&p, &v.depth, z0, z1)?;
    out.push((
        p,
        format!("depth of the brightest voxel ({})", v.depth.extents),
    ));
    if let Some(normals) = normals {
        out.push(crate::normal_map::write(dir, &v, normals)?);
    }
    Ok(out)
}

/// The look every murk page shares (the study's report, the demo, reconstruct's pictures): one font,
/// left-aligned key/value tables, numbers right-aligned.
pub const PAGE_STYLE: &str = "<style>body{font-family:sans-serif;max-width:1400px;margin:auto;padding:0 1em;color:#222}\
table{border-collapse:collapse;font-size:13px}td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}\
#provenance td,#provenance th,#parameters td,#parameters th{text-align:left}</style>";

/// A self-contained page: a parameter table and the pictures (relative links).
pub fn write_index(
    dir: &Path,
    title: &str,
    params: &[(String, String)],
    pictures: &[(PathBuf, String)],
) -> Result<PathBuf> {
    let esc = |s: &str| {
        s.replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
    };
    let mut html = format!(
        "<!doctype html><html><head><meta charset=\"utf-8\"><title>{t}</title>{PAGE_STYLE}<style>figure{{display:inline-block;margin:.5em;vertical-align:top;max-width:400px}}img{{image-rendering:pixelated;border:1px solid #888}}</style></head><body><h1>{t}</h1><table id=\"provenance\">",
        t = esc(title)
    );
    for (k, v) in params {
        html += &format!("<tr><td>{}</td><td>{}</td></tr>", esc(k), esc(v));
    }
    html += "</table>";
    for (p, caption) in pictures {
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        html += &format!(
            "<figure><img src=\"{n}\" alt=\"{n}\"><figcaption>{}</figcaption></figure>",
            esc(caption),
            n = esc(&name)
        );
    }
    html += "</body></html>\n";
    let path = dir.join("index.html");
    murk_io::write_atomic(&path, |w| {
        w.write_all(html.as_bytes())
            .map_err(|e| murk_core::Error::io(&path, e))
    })?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use murk_core::Axis;

    #[test]
    fn front_view_has_plus_x_on_the_left_and_plus_y_on_top() {
        let vol = Volume {
            x: Axis::new(-1.0, 1.0, 3),
            y: Axis::new(-1.0, 1.0, 2),
            z: Axis::new(1.0, 2.0, 2),
        };
        let mut v = vec![0f32; vol.len()];
        v[vol.index(2, 1, 1)] = 5.0; // x = +1, y = +1, z = 2
        let views = views(&vol, &v);
        assert_eq!(views.front.values[0], 5.0);
        assert_eq!(views.depth.values[0], 2.0);
        assert!(views.depth.values[1].is_nan());
        assert_eq!(views.top.values[3], 5.0); // row = depth index 1, column 0 = +x
        assert_eq!(views.side.values[1], 5.0); // row 0 = +y, column = depth index 1
                                               // The axes the grids write name the same orientation: the front view's first column is
                                               // x = +1 (left), its first row y = +1 (top); the side view's columns run in depth.
        let [cols, rows] = views.front.axes.unwrap();
        assert_eq!((cols.name, cols.first_m, cols.last_m), ("x", 1.0, -1.0));
        assert_eq!((rows.name, rows.first_m, rows.last_m), ("y", 1.0, -1.0));
        let [cols, rows] = views.side.axes.unwrap();
        assert_eq!((cols.name, cols.first_m, rows.name), ("z", 1.0, "y"));
        assert_eq!(views.top.axes.unwrap()[1].name, "z");
        assert_eq!(colour(0.0), [0, 0, 4]);
        assert_eq!(colour(1.0), [252, 255, 164]);
    }

    /// The case: 73 × 59 voxels over equal extents drew the Z 24 % too wide at one pixel a
    /// voxel; the PNG must be square, and a 2:1 box twice as wide as high whatever its voxel counts.
    #[test]
    fn pngs_keep_the_physical_aspect_ratio() {
        let dir = std::env::temp_dir().join(format!("murk-view-aspect-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let size = |vol: &Volume| {
            let v = views(vol, &vec![1f32; vol.len()]);
            let p = dir.join("front.png");
            write_png(&p, &v.front, 0.0, 1.0).unwrap();
            let info = png::Decoder::new(std::fs::File::open(&p).unwrap())
                .read_info()
                .unwrap()
                .info()
                .size();
            info
        };
        // Equal extents: 73 samples over 2 m and 59 over 2 m → pitches 2/72 and 2/58; physical sides
        // 73·2/72 and 59·2/58 m, equal to 1.2 %.
        let (w, h) = size(&Volume {
            x: Axis::new(-1.0, 1.0, 73),
            y: Axis::new(-1.0, 1.0, 59),
            z: Axis::new(1.0, 2.0, 4),
        });
        assert!((w as f64 / h as f64 - 1.0).abs() < 0.02, "{w} × {h}");
        assert!(w.max(h) >= 384);
        let (w, h) = size(&Volume {
            x: Axis::new(-2.0, 2.0, 17),
            y: Axis::new(-1.0, 1.0, 33),
            z: Axis::new(1.0, 2.0, 4),
        });
        // Sides 17·4/16 = 4.25 m and 33·2/32 = 2.06 m.
        assert!(
            (w as f64 / h as f64 - 4.25 / 2.0625).abs() < 0.02,
            "{w} × {h}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
