//! `murk.Capture`: a `murk_core::Capture` owned by Python, with numpy views of its arrays.

use crate::{compute, to_py};
use murk_core::{Pairing, PointLayout, PointSet};
use murk_io::import::{BinWidth, Dim, Flip, ImportOptions, Layout, Preset};
use numpy::ndarray::{ArrayView, IxDyn};
use numpy::{PyArray, PyArray1, PyArrayDyn, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyAny;
use std::path::PathBuf;

/// A transient NLOS capture (y-tal's fields, murk's layout). Read one with `murk.read_capture`,
/// make one with `murk.synth` or `murk.render`, or convert y-tal's with `Capture.from_tal`.
///
/// `H` is a read-only view of murk's histograms without a copy: time is the *last* axis
/// (y-tal puts it first), the others are the laser grid's then the sensor grid's (a paired or
/// confocal capture, or one with a single laser point, has only the sensor grid's).
///
/// >>> cap = murk.read_capture("z.h5")
/// >>> cap.H.shape, cap.kind, cap.bin_width_m
/// ((128, 128, 1, 1, 4096), 'laser grid + one SPAD point', 0.0009)
#[pyclass(frozen, name = "Capture", module = "murk")]
pub struct Capture {
    pub(crate) cap: murk_core::Capture,
}

fn dims(p: &PointSet) -> Vec<usize> {
    match p.layout {
        PointLayout::Grid { nx, ny } => vec![nx, ny],
        PointLayout::List => vec![p.len()],
    }
}

/// Points or normals as float64 (…, 3) in the set's grid shape.
fn xyz<'py>(
    py: Python<'py>,
    p: &PointSet,
    v: &[murk_core::DVec3],
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let flat: Vec<f64> = v.iter().flat_map(|q| q.to_array()).collect();
    let mut shape = dims(p);
    shape.push(3);
    PyArray1::from_vec(py, flat).reshape(shape)
}

#[pymethods]
impl Capture {
    /// Histograms, float32, read-only and shared with this capture (no copy).
    #[getter(H)]
    fn h<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyArrayDyn<f32>>> {
        let c = &slf.get().cap;
        // y-tal's dimensions in murk's order: a single laser point adds none (its T_Sx_Sy).
        let mut shape = match c.pairing {
            Pairing::Product if c.illum.len() > 1 => [dims(&c.illum), dims(&c.sensor)].concat(),
            _ => dims(&c.sensor),
        };
        shape.push(c.time.bins);
        let view = ArrayView::from_shape(IxDyn(&shape), &c.h)
            .map_err(|e| crate::error("Error", format!("H does not fit its shape: {e}")))?;
        // SAFETY: the array borrows `c.h`, which lives as long as `slf` (its base object) and never
        // changes: the class is frozen and the array is made read-only before it is returned.
        let arr = unsafe { PyArray::borrow_from_array(&view, slf.clone().into_any()) };
        let kw = pyo3::types::PyDict::new(slf.py());
        kw.set_item("write", false)?;
        arr.call_method("setflags", (), Some(&kw))?;
        Ok(arr)
    }
    /// Illuminated wall points, float64 (…, 3) in the laser grid's shape.
    #[getter]
    fn laser_points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        xyz(py, &self.cap.illum, &self.cap.illum.points)
    }
    #[getter]
    fn laser_normals<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        xyz(py, &self.cap.illum, &self.cap.illum.normals)
    }
    /// Sensed wall points, float64 (…, 3) in the sensor grid's shape.
    #[getter]
    fn sensor_points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        xyz(py, &self.cap.sensor, &self.cap.sensor.points)
    }
    #[getter]
    fn sensor_normals<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        xyz(py, &self.cap.sensor, &self.cap.sensor.normals)
    }
    /// The laser device's position (x, y, z) in metres, or None.
    #[getter]
    fn laser_xyz(&self) -> Option<(f64, f64, f64)> {
        self.cap.laser_xyz.map(|p| (p.x, p.y, p.z))
    }
    /// The SPAD device's position (x, y, z) in metres, or None.
    #[getter]
    fn sensor_xyz(&self) -> Option<(f64, f64, f64)> {
        self.cap.sensor_xyz.map(|p| (p.x, p.y, p.z))
    }
    /// Optical path (m) at the start of bin 0.
    #[getter]
    fn start_m(&self) -> f64 {
        self.cap.time.start_m
    }
    /// Bin width as optical path (m).
    #[getter]
    fn bin_width_m(&self) -> f64 {
        self.cap.time.bin_width_m
    }
    #[getter]
    fn bins(&self) -> usize {
        self.cap.time.bins
    }
    /// Optical path (m) at the start of each bin: bin i holds [t[i], t[i] + bin_width_m).
    #[getter]
    fn t<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let t = self.cap.time;
        let v = (0..t.bins)
            .map(|i| t.start_m + i as f64 * t.bin_width_m)
            .collect();
        PyArray1::from_vec(py, v)
    }
    /// What was measured, in words (e.g. "confocal", "laser grid + one SPAD point").
    #[getter]
    fn kind(&self) -> String {
        self.cap.kind().to_string()
    }
    /// "product" (every laser point × every sensor point) or "paired" (one laser point per sensor point).
    #[getter]
    fn pairing(&self) -> &'static str {
        match self.cap.pairing {
            Pairing::Product => "product",
            Pairing::Paired => "paired",
        }
    }
    /// Number of histograms.
    #[getter]
    fn n_hist(&self) -> usize {
        self.cap.n_hist()
    }
    #[getter]
    fn t_accounts_first_and_last_bounces(&self) -> bool {
        self.cap.t_accounts_first_and_last_bounces
    }
    /// y-tal's free-form metadata (YAML text).
    #[getter]
    fn scene_info(&self) -> &str {
        &self.cap.scene_info
    }
    /// This capture as a y-tal `NLOSCaptureData` (needs `pip install y-tal`).
    ///
    /// >>> tal_data = cap.to_tal()
    /// >>> tal_data.H.shape   # time first, as y-tal has it
    fn to_tal<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        slf.py()
            .import("murk._tal")?
            .call_method1("to_tal", (slf.clone(),))
    }
    /// A capture from a y-tal `NLOSCaptureData` (or any object `tal.io.write_capture` accepts).
    ///
    /// >>> cap = murk.Capture.from_tal(tal.io.read_capture("scene.hdf5"))
    #[staticmethod]
    fn from_tal<'py>(py: Python<'py>, data: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        py.import("murk._tal")?.call_method1("from_tal", (data,))
    }
    /// Pickling (multiprocessing, Dask, joblib) keeps every field exactly; a capture file keeps its
    /// coordinates and time axis as f32.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (State,))> {
        let c = &slf.get().cap;
        let set = |p: &PointSet| PointState {
            points: p.points.iter().flat_map(|q| q.to_array()).collect(),
            normals: p.normals.iter().flat_map(|q| q.to_array()).collect(),
            grid: match p.layout {
                PointLayout::Grid { nx, ny } => Some((nx, ny)),
                PointLayout::List => None,
            },
        };
        let state = State {
            illum: set(&c.illum),
            sensor: set(&c.sensor),
            laser_xyz: c.laser_xyz.map(|p| p.to_array()),
            sensor_xyz: c.sensor_xyz.map(|p| p.to_array()),
            time: (c.time.start_m, c.time.bin_width_m, c.time.bins),
            first_and_last: c.t_accounts_first_and_last_bounces,
            paired: c.pairing == Pairing::Paired,
            h: c.h.iter().flat_map(|v| v.to_le_bytes()).collect(),
            scene_info: c.scene_info.clone(),
            medium_density: c.medium_density.as_ref().map(|d| {
                let bytes = d.values().iter().flat_map(|v| v.to_le_bytes()).collect();
                (d.dims().to_vec(), bytes)
            }),
        };
        let rebuild = slf
            .py()
            .import("murk._murk")?
            .getattr("_capture_from_state")?;
        Ok((rebuild, (state,)))
    }
    fn __repr__(&self) -> String {
        let t = self.cap.time;
        format!(
            "<murk.Capture {}: {} histograms × {} bins, t from {} m by {} m>",
            self.cap.kind(),
            self.cap.n_hist(),
            t.bins,
            // Six significant digits: a bin width stored as f32 (0.0048) is not shown with its
            // float noise (0.004800000227987766).
            murk_core::short(t.start_m),
            murk_core::short(t.bin_width_m)
        )
    }
}

/// A Capture argument or a path to a y-tal HDF5 capture.
pub(crate) enum Source<'a> {
    Object(&'a murk_core::Capture),
    File(PathBuf),
}

impl<'a> Source<'a> {
    pub(crate) fn of(obj: &'a Bound<'_, PyAny>) -> PyResult<Source<'a>> {
        match obj.cast::<Capture>() {
            Ok(c) => Ok(Source::Object(&c.get().cap)),
            Err(_) => Ok(Source::File(obj.extract().map_err(|_| {
                crate::error(
                    "InputError",
                    format!(
                        "expected a murk.Capture or a path to a capture, got {}",
                        obj.get_type().name().map_or("?".into(), |n| n.to_string())
                    ),
                )
            })?)),
        }
    }
    /// The capture, owned: a copy of a Capture's arrays (the library consumes it), or the file read.
    pub(crate) fn owned(&self) -> murk_core::Result<murk_core::Capture> {
        match self {
            Source::Object(c) => Ok((*c).clone()),
            Source::File(p) => murk_io::read_capture(p),
        }
    }
}

/// Reads a y-tal HDF5 capture (any H layout; pure-Rust HDF5, no libhdf5).
///
/// >>> cap = murk.read_capture("z.h5")
#[pyfunction]
pub fn read_capture(py: Python<'_>, path: PathBuf) -> PyResult<Capture> {
    let cap = py.detach(|| murk_io::read_capture(&path)).map_err(to_py)?;
    Ok(Capture { cap })
}

/// The keywords of `murk.import_capture` (its path aside), which are `murk import`'s flags.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct ImportArgs {
    format: Option<String>,
    var: Option<String>,
    axes: Option<String>,
    confocal: bool,
    wall_size: Option<f64>,
    bin_width_ps: Option<f64>,
    bin_width_m: Option<f64>,
    gate_bins: Option<usize>,
    flip: Option<String>,
    t0_bin: Option<usize>,
    tof: Option<PathBuf>,
}

impl ImportArgs {
    /// The library's options, as `murk import` builds them from its flags.
    fn options(&self) -> murk_core::Result<ImportOptions> {
        let bin_width = match (self.bin_width_ps, self.bin_width_m) {
            (Some(_), Some(_)) => {
                return Err(murk_core::Error::param(
                    "give bin_width_ps or bin_width_m, not both",
                ))
            }
            (ps, m) => ps.map(BinWidth::Ps).or(m.map(BinWidth::M)),
        };
        Ok(ImportOptions {
            layout: Layout::choose(
                self.format.as_deref().map(Preset::named).transpose()?,
                self.var.clone(),
                self.axes.as_deref().map(Dim::parse_axes).transpose()?,
                self.confocal,
            )?,
            wall_size_m: self.wall_size,
            bin_width,
            gate_bins: self.gate_bins,
            flip: self
                .flip
                .as_deref()
                .map(Flip::parse)
                .transpose()?
                .unwrap_or_default(),
            t0_bin: self.t0_bin,
            tof: self.tof.clone(),
        })
    }
}

/// Reads a public dataset's capture, or any 3-D array, as `murk import` does; see
/// `murk.import_capture`.
#[pyfunction]
pub fn import_capture(py: Python<'_>, path: PathBuf, args: ImportArgs) -> PyResult<Capture> {
    let cap = py
        .detach(|| murk_io::import::import(&path, &args.options()?))
        .map_err(to_py)?;
    Ok(Capture { cap })
}

/// Writes `capture` as a y-tal HDF5 file, atomically; `compression` 1..9 gzips H as y-tal's
/// `compression_level` does.
///
/// >>> murk.write_capture("copy.h5", cap)
#[pyfunction]
#[pyo3(signature = (path, capture, compression = 0))]
pub fn write_capture(
    py: Python<'_>,
    path: PathBuf,
    capture: &Bound<'_, Capture>,
    compression: i64,
) -> PyResult<()> {
    let cap = &capture.get().cap;
    // Any integer is taken, so that a negative or huge one is named here rather than as an overflow.
    let level = u32::try_from(compression)
        .ok()
        .filter(|l| *l <= 9)
        .ok_or_else(|| {
            crate::error(
                "InputError",
                format!("compression must be 0 (none) to 9, got {compression}"),
            )
        })?;
    compute(py, None, None, |_| {
        murk_io::write_capture_compressed(&path, cap, level)
    })
}

/// One point set of a pickled [`Capture`]: flat xyz triples and the grid shape, if a grid.
#[derive(IntoPyObject, FromPyObject)]
#[pyo3(from_item_all)]
pub struct PointState {
    points: Vec<f64>,
    normals: Vec<f64>,
    grid: Option<(usize, usize)>,
}

/// A pickled [`Capture`]: its fields as a dict of plain Python values.
#[derive(IntoPyObject, FromPyObject)]
#[pyo3(from_item_all)]
pub struct State {
    illum: PointState,
    sensor: PointState,
    laser_xyz: Option<[f64; 3]>,
    sensor_xyz: Option<[f64; 3]>,
    time: (f64, f64, usize),
    first_and_last: bool,
    paired: bool,
    /// H as little-endian f32 bytes (a list of floats would take 30 bytes a sample).
    h: Vec<u8>,
    scene_info: String,
    /// The medium's density cells: shape and little-endian f32 bytes.
    medium_density: Option<(Vec<usize>, Vec<u8>)>,
}

/// Rebuilds a pickled capture, checking it as a file read is checked.
#[pyfunction]
pub fn _capture_from_state(state: State) -> PyResult<Capture> {
    let set = |p: PointState| {
        let xyz = |v: Vec<f64>| {
            v.chunks(3)
                .map(murk_core::DVec3::from_slice)
                .collect::<Vec<_>>()
        };
        let whole = p.points.len().is_multiple_of(3) && p.normals.len().is_multiple_of(3);
        whole.then(|| PointSet {
            points: xyz(p.points),
            normals: xyz(p.normals),
            layout: p
                .grid
                .map_or(PointLayout::List, |(nx, ny)| PointLayout::Grid { nx, ny }),
        })
    };
    let (Some(illum), Some(sensor)) = (set(state.illum), set(state.sensor)) else {
        return Err(crate::error(
            "InputError",
            "pickled capture: points are not xyz triples".into(),
        ));
    };
    let f32s = |b: &[u8]| -> Vec<f32> {
        b.chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect()
    };
    let medium_density = match state.medium_density {
        Some((shape, bytes)) if bytes.len().is_multiple_of(4) => Some(std::sync::Arc::new(
            murk_core::DensityCells::new(&shape, f32s(&bytes)).map_err(|e| {
                crate::error("InputError", format!("pickled capture: medium density: {e}"))
            })?,
        )),
        Some(_) => {
            return Err(crate::error(
                "InputError",
                "pickled capture: the medium density is not whole f32 values".into(),
            ))
        }
        None => None,
    };
    if !state.h.len().is_multiple_of(4) {
        return Err(crate::error(
            "InputError",
            "pickled capture: H is not whole f32 values".into(),
        ));
    }
    let h = f32s(&state.h);
    let (start_m, bin_width_m, bins) = state.time;
    let pairing = match state.paired {
        true => Pairing::Paired,
        false => Pairing::Product,
    };
    let time = murk_core::TimeAxis {
        start_m,
        bin_width_m,
        bins,
    };
    let cap = murk_core::Capture {
        laser_xyz: state.laser_xyz.map(murk_core::DVec3::from_array),
        sensor_xyz: state.sensor_xyz.map(murk_core::DVec3::from_array),
        t_accounts_first_and_last_bounces: state.first_and_last,
        scene_info: state.scene_info,
        medium_density,
        ..murk_core::Capture::new(illum, sensor, pairing, time, h)
    };
    cap.validate()
        .map_err(|e| crate::error("InputError", format!("pickled capture: {e}")))?;
    Ok(Capture { cap })
}
