//! Real captures in and behind scattering media side by side (`murk figure media`): every foam
//! capture of a folder (the boundary migration model's letter T inside foam, Du et al. 2022; the
//! CDT captures behind a foam slab, Lindell & Wetzstein 2020) reconstructed by BMM, CDT, Phasor
//! Fields without and with its medium-aware path, LCT and f-k, each with its defaults, as a PNG
//! grid (a row per capture, a column per method), an index.html and a depths.csv.

use crate::figures::{check_out, depths, grid_plane};
use murk_baselines::{BmmParams, SlabParams};
use murk_core::{Capture, Error, Reconstruction, Result};
use murk_io::import::{import, ImportOptions, Preset, BMM_SCENES, CDT_SCENES};
use murk_methods::{Method, Options, Request};
use murk_recon::medium::{DepthSearch, MediumAware, MediumRemoval};
use murk_recon::NoProgress;
use murk_view::pictures;
use std::path::{Path, PathBuf};

/// The grid's columns: a label, the method's name, and whether its medium-aware path is on (it
/// applies to PF only: the other methods reconstruct on their own grid).
const COLUMNS: [(&str, &str, bool); 6] = [
    ("BMM", "bmm", true),
    ("CDT", "cdt", true),
    ("PF", "pf", false),
    ("PF medium-aware", "pf", true),
    ("LCT", "lct", true),
    ("f-k", "fk", true),
];

/// One capture of the folder.
struct Foam {
    name: String,
    cap: Capture,
    /// How deep the object sits in the medium (m), where the file name says (`4cmFoam_…`).
    depth_m: Option<f64>,
    /// Transport mean free paths of foam the light crosses to reach the object: depth × μs′ inside
    /// the medium, the slab's thickness × μs′ behind it.
    mfp: Option<f64>,
    /// A CDT capture: the object stands in air behind a slab of foam.
    behind_slab: bool,
}

impl Foam {
    /// What the row says about the capture.
    fn describe(&self) -> String {
        let at = match (self.depth_m, self.behind_slab) {
            (Some(d), _) => format!("object {} cm deep in the foam", murk_core::short(d * 100.0)),
            (None, true) => format!(
                "object behind a {} cm foam slab",
                murk_core::short(SlabParams::default().thickness_m * 100.0)
            ),
            (None, false) => "object inside the medium".into(),
        };
        match self.mfp {
            Some(m) => format!("{at}, {m:.1} transport mean free paths"),
            None => at,
        }
    }
}

/// The foam captures in `data`: the BMM files, then the CDT ones, in their tables' order.
fn foams(data: &Path) -> Result<Vec<Foam>> {
    let mut out = Vec::new();
    for (name, _) in BMM_SCENES {
        let path = data.join(format!("{name}.mat"));
        if !path.exists() {
            continue;
        }
        let cap = import(&path, &ImportOptions::preset(Preset::Bmm))?;
        let depth_m = name
            .split_once("cmFoam")
            .and_then(|(cm, _)| cm.parse::<f64>().ok())
            .map(|cm| cm / 100.0);
        let musp = BmmParams::default().medium(&cap).mu_s_prime_per_m;
        out.push(Foam {
            name: name.into(),
            mfp: depth_m.map(|d| d * musp),
            depth_m,
            cap,
            behind_slab: false,
        });
    }
    let slab = SlabParams::default();
    for (name, _, _) in CDT_SCENES {
        let path = data.join(format!("{name}.mat"));
        if path.exists() {
            out.push(Foam {
                name: name.into(),
                cap: import(&path, &ImportOptions::preset(Preset::Cdt))?,
                depth_m: None,
                mfp: Some(slab.thickness_m * slab.mu_s_prime_per_m),
                behind_slab: true,
            });
        }
    }
    if out.is_empty() {
        let bmm: Vec<&str> = BMM_SCENES.iter().map(|s| s.0).collect();
        let cdt: Vec<&str> = CDT_SCENES.iter().map(|s| s.0).collect();
        return Err(Error::param(format!(
            "{}: no foam captures (expected .mat files named {} or {})",
            data.display(),
            bmm.join(", "),
            cdt.join(", ")
        )));
    }
    Ok(out)
}

/// `method` on `cap` with `murk reconstruct`'s defaults, the medium-aware path on or off.
fn reconstruct(cap: &Capture, method: &str, medium_aware: bool) -> Result<Reconstruction> {
    let mut req = Request::new(Method::named(method, &Options::default())?);
    if !medium_aware {
        req.medium = MediumAware {
            removal: MediumRemoval::Off,
            depth_search: DepthSearch::Off,
        };
    }
    murk_methods::run(cap.clone(), &req, &NoProgress)
}

/// Reconstructs every foam capture in `data` with every method, writes `out/grid.png`,
/// `out/depths.csv` and `out/index.html`, and returns the index's path; `say` receives one line
/// per reconstruction. A method that fails on a capture leaves its cell black and its reason in
/// the row.
pub fn figure_media(data: &Path, out: &Path, say: &dyn Fn(&str)) -> Result<PathBuf> {
    check_out(data, out)?;
    let foams = foams(data)?;
    let labels: Vec<&str> = COLUMNS.iter().map(|c| c.0).collect();
    let mut rows = vec![
        (
            "methods".to_string(),
            "each with the defaults of murk reconstruct --method NAME: BMM (the medium's constants from the capture), CDT (the 2.54 cm foam slab of Lindell & Wetzstein), PF with --medium-removal off --depth-search off, PF medium-aware (both auto: the medium's response subtracted and the depth range searched where a medium is detected), LCT, f-k".to_string(),
        ),
        (
            "depth".to_string(),
            "of each method's surface: the median, over the pixels whose front view exceeds half its maximum, of the brightest voxel's depth. BMM measures depth inside the medium with its speed of light c/n; the others assume free space (c), and CDT measures behind its slab".to_string(),
        ),
        (
            "grid.png".to_string(),
            format!(
                "a row per capture (in the order below), a column per method: {}; front views (from the wall, +y up, +x left), each normalised to its own range; black: the method failed",
                labels.join(", ")
            ),
        ),
    ];
    let mut csv = String::from(
        "capture,object_depth_m,transport_mfp,method,surface_depth_m,peak_depth_m,error\n",
    );
    let opt = |v: Option<f64>, digits: usize| v.map_or(String::new(), |v| format!("{v:.digits$}"));
    let mut recs: Vec<Vec<Option<Reconstruction>>> = COLUMNS.iter().map(|_| Vec::new()).collect();
    for foam in &foams {
        let mut cells = Vec::new();
        for (col, &(label, method, aware)) in COLUMNS.iter().enumerate() {
            let (cell, csv_cells) = match reconstruct(&foam.cap, method, aware) {
                Ok(rec) => {
                    let (peak, median) = depths(&rec);
                    recs[col].push(Some(rec));
                    (
                        format!("{label} {median:.3} m"),
                        format!("{median:.4},{peak:.4},"),
                    )
                }
                Err(e) => {
                    recs[col].push(None);
                    let why = e.to_string().replace(['\n', ','], " ");
                    (format!("{label} failed ({why})"), format!(",,{why}"))
                }
            };
            say(&format!("{} {cell}", foam.name));
            csv += &format!(
                "{},{},{},{label},{csv_cells}\n",
                foam.name,
                opt(foam.depth_m, 3),
                opt(foam.mfp, 2)
            );
            cells.push(cell);
        }
        rows.push((
            foam.name.clone(),
            format!("{}; surface depth: {}", foam.describe(), cells.join(", ")),
        ));
    }
    let columns: Vec<Vec<Option<&Reconstruction>>> = recs
        .iter()
        .map(|col| col.iter().map(Option::as_ref).collect())
        .collect();
    let names: Vec<&str> = foams.iter().map(|f| f.name.as_str()).collect();
    let grid = grid_plane(
        &columns,
        format!(
            "rows: {}; columns: {}; each a front view (from the wall, +y up, +x left), normalised to its own range",
            names.join(", "),
            labels.join(", ")
        ),
    );
    murk_io::create_output_dir(out)?;
    let png = out.join("grid.png");
    pictures::write_png(&png, &grid, 0.0, 1.0)?;
    let csv_path = out.join("depths.csv");
    murk_io::write_atomic(&csv_path, |w| {
        w.write_all(csv.as_bytes())
            .map_err(|e| Error::io(&csv_path, e))
    })?;
    pictures::write_index(
        out,
        "Real captures in and behind foam: BMM, CDT, Phasor Fields, LCT and f-k",
        &rows,
        &[(png, grid.extents.clone())],
    )
}
