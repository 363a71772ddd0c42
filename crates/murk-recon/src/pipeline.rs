//! One reconstruction contract over every method: what a user asks for ([`Request`]: the method with
//! its parameters, the volume, the time offset, the gate and the window's end) and what comes back
//! ([`Output`]: the volume, its intensity, the rows that say how it was made, warnings). `murk
//! reconstruct` is this call; a new method is one [`Method`] arm here and its own module.

use crate::{PfForm, PfParams, Progress};
use murk_baselines::{CdtParams, FbpOptions, FkParams, LctParams, Pulse, SlabParams};
use murk_core::window::{
    apply_gate, handle_end, shortest_path_m, EndReport, GateReport, WindowEnd,
};
use murk_core::{Axis, Capture, Error, Result, Volume};

/// Every reconstruction method, with its parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// Phasor Fields, fast planar form (the exact form where the wall is not a planar grid).
    Pf(PfParams),
    /// Phasor Fields, exact time-domain form for any geometry.
    PfExact(PfParams),
    /// Backprojection, on the requested volume.
    Bp,
    /// Filtered backprojection, on the requested volume.
    Fbp(FbpOptions),
    /// Light-cone transform (confocal grid; its own volume).
    Lct(LctParams),
    /// f-k migration (confocal grid; its own volume).
    Fk(FkParams),
    /// Confocal diffuse tomography (confocal grid behind a slab; its own volume).
    Cdt(CdtParams),
}

impl Method {
    /// Methods that reconstruct on the confocal scan grid and ignore the requested volume.
    pub fn own_grid(&self) -> bool {
        matches!(self, Method::Lct(_) | Method::Fk(_) | Method::Cdt(_))
    }

    fn pf(&self) -> Option<&PfParams> {
        match self {
            Method::Pf(p) | Method::PfExact(p) => Some(p),
            _ => None,
        }
    }

    /// PF's virtual pulse on this capture; `None` for the other methods.
    pub fn pulse(&self, cap: &Capture) -> Result<Option<Pulse>> {
        self.pf()
            .map(|p| {
                let wavelength_m = p.wavelength_m(cap)?;
                Ok(Pulse {
                    wavelength_m,
                    sigma_m: p.sigma_m(wavelength_m),
                })
            })
            .transpose()
    }
}

/// Ramp length (bins) at either end of the window for the methods without a pulse, chosen on a cut
/// real capture (docs/window-ends.md).
const BASELINE_EDGE_BINS: usize = 20;

/// How many edges before the volume's shortest path [`Gate::Auto`] opens.
const GATE_MARGIN_EDGES: f64 = 3.0;

/// Where the reconstruction's voxels are.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum VolumeSpec {
    /// The wall grid's extent and spacing; depth from 0.1 m to what the time window reaches.
    Default,
    Given(Volume),
}

/// Optical path removed from every time stamp before reconstructing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TOffset {
    None,
    Metres(f64),
    /// The slab's round-trip delay as the method sees it ([`SlabParams::round_trip_delay_m`]).
    Slab(SlabParams),
}

/// Where short paths are faded out (see `murk_core::window`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Gate {
    Off,
    /// Fully open from this path (m).
    At(f64),
    /// Three edges before the shortest path that reaches the volume.
    Auto,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Request {
    pub method: Method,
    pub volume: VolumeSpec,
    pub t_offset: TOffset,
    pub gate: Gate,
    pub window_end: WindowEnd,
}

impl Request {
    /// `method` on the default volume, with the defaults of `murk reconstruct`.
    pub fn new(method: Method) -> Request {
        Request {
            method,
            volume: VolumeSpec::Default,
            t_offset: TOffset::None,
            gate: Gate::Auto,
            window_end: WindowEnd::Auto,
        }
    }
}

/// A reconstruction by any method.
pub struct Output {
    pub volume: Volume,
    /// Float32 intensity in C order over (x, y, z).
    pub intensity: Vec<f32>,
    /// How it was made, as (key, value) rows: the method's parameters, the time offset, the gate and
    /// the window's end.
    pub rows: Vec<(String, String)>,
    pub warnings: Vec<String>,
}

/// Runs `req` on `cap`.
pub fn run(mut cap: Capture, req: &Request, progress: &dyn Progress) -> Result<Output> {
    let m = &req.method;
    let pulse = m.pulse(&cap)?;
    let offset_m = match req.t_offset {
        TOffset::None => 0.0,
        TOffset::Metres(v) if v.is_finite() => v,
        TOffset::Metres(v) => {
            return Err(Error::param(format!("time offset must be finite, got {v}")))
        }
        TOffset::Slab(slab) => slab.round_trip_delay_m(pulse),
    };
    cap.time.start_m -= offset_m;
    // The ramp at either end of the window: PF's pulse σ, or a fixed number of bins.
    let edge_m = pulse.map_or(BASELINE_EDGE_BINS as f64 * cap.time.bin_width_m, |p| {
        p.sigma_m
    });
    let volume = match (req.volume, m.own_grid()) {
        (_, true) => None,
        (VolumeSpec::Given(v), false) => {
            v.validate()?;
            Some(v)
        }
        (VolumeSpec::Default, false) => Some(default_volume(&cap)?),
    };
    let open_m = match (req.gate, &volume) {
        (Gate::Auto, Some(v)) => Some(shortest_path_m(&cap, v) - GATE_MARGIN_EDGES * edge_m),
        // Own-grid methods have no volume to derive it from.
        (Gate::Auto, None) | (Gate::Off, _) => None,
        (Gate::At(p), _) => Some(p),
    };
    let gated = apply_gate(&mut cap, open_m, edge_m);
    let mut end = handle_end(&mut cap, req.window_end, edge_m);
    let mut out = dispatch(&cap, m, volume.as_ref(), progress)?;
    end.trim(&cap, &out.volume, &mut out.intensity);
    out.warnings.extend(end.warning());
    out.warnings
        .extend(near_face_warning(&out.volume, &out.intensity, &gated));
    out.rows.extend(closing_rows(offset_m, &gated, &end));
    Ok(out)
}

fn closing_rows(offset_m: f64, gated: &GateReport, end: &EndReport) -> Vec<(String, String)> {
    vec![
        ("t_offset_m".into(), format!("{offset_m:.6}")),
        ("gate".into(), gated.describe()),
        ("window_end".into(), end.describe()),
    ]
}

fn row(k: &str, v: String) -> (String, String) {
    (k.to_string(), v)
}

fn dispatch(
    cap: &Capture,
    method: &Method,
    volume: Option<&Volume>,
    progress: &dyn Progress,
) -> Result<Output> {
    let on_volume = || volume.ok_or_else(|| Error::param("this method needs a volume"));
    let baseline = |r: murk_baselines::Reconstruction, rows: Vec<(String, String)>| Output {
        volume: r.volume,
        intensity: r.data,
        rows,
        warnings: Vec::new(),
    };
    Ok(match *method {
        Method::Pf(p) | Method::PfExact(p) => {
            let form = if matches!(method, Method::PfExact(_)) {
                PfForm::Exact
            } else {
                PfForm::Fast
            };
            let rec = crate::reconstruct(cap, on_volume()?, &p, form, progress)?;
            let mut rows = rec.info.rows();
            if rec.info.evaluated_with == "fast" {
                rows.push(row("lateral", format!("{:?}", p.lateral).to_lowercase()));
            }
            Output {
                volume: rec.volume,
                intensity: rec.intensity,
                rows,
                warnings: rec.info.warnings,
            }
        }
        Method::Bp => baseline(
            murk_baselines::backproject(cap, on_volume()?, Default::default())?,
            vec![row(
                "method",
                "backprojection (linear reads at bin centres)".into(),
            )],
        ),
        Method::Fbp(o) => baseline(
            murk_baselines::fbp(cap, on_volume()?, o)?,
            vec![row(
                "method",
                "filtered backprojection (−∇²G, 5³ voxels, σ = 1 voxel)".into(),
            )],
        ),
        Method::Lct(p) => baseline(
            murk_baselines::lct(cap, p)?,
            vec![
                row("method", "light-cone transform (Wiener)".into()),
                row("snr", format!("{}", p.snr)),
                row("reflectance", format!("{:?}", p.reflectance)),
            ],
        ),
        Method::Fk(p) => baseline(
            murk_baselines::fk(cap, p)?,
            vec![row("method", "f-k migration".into())],
        ),
        Method::Cdt(p) => {
            let s = p.slab;
            baseline(
                murk_baselines::cdt(cap, p)?,
                vec![
                    row(
                        "method",
                        "confocal diffuse tomography (slab Wiener + f-k)".into(),
                    ),
                    row(
                        "slab",
                        format!(
                            "{} m, μa {} /m, μs′ {} /m, n {}, ze {} m",
                            s.thickness_m, s.mu_a, s.mu_s_prime, s.n, s.ze_m
                        ),
                    ),
                    row("snr", format!("{}", p.snr)),
                    row("time grid", format!("{:?}", p.grid)),
                ],
            )
        }
    })
}

/// The wall grid's extent and spacing in x and y; depth from 0.1 m to what the time window reaches.
pub fn default_volume(cap: &Capture) -> Result<Volume> {
    let side = if cap.sensor.len() > cap.illum.len() {
        &cap.sensor
    } else {
        &cap.illum
    };
    let spacing = crate::wall_spacing_m(cap)
        .ok_or_else(|| Error::param("the capture has a single wall point; give a volume"))?;
    let (lo, hi) = side
        .points
        .iter()
        .fold((side.points[0], side.points[0]), |(a, b), p| {
            (a.min(*p), b.max(*p))
        });
    let count = |a: f64, b: f64| ((b - a) / spacing).round() as usize + 1;
    let offsets = (0..cap.n_hist())
        .map(|i| {
            let (l, s) = cap.hist_pair(i);
            cap.first_bounce_m(l) + cap.last_bounce_m(s)
        })
        .fold(f64::MAX, f64::min);
    // The shortest round trip to depth z is 2z (a voxel straight in front of the wall points).
    let z_max = (cap.time.end_m() - offsets) / 2.0;
    let z_min = 0.1;
    if z_max <= z_min {
        return Err(Error::param(format!(
            "the capture's time window ends at {:.3} m of path, before any depth beyond {z_min} m; give a volume",
            cap.time.end_m()
        )));
    }
    let nz = (((z_max - z_min) / spacing).round() as usize + 1).clamp(2, 256);
    let v = Volume {
        x: Axis::new(lo.x, hi.x, count(lo.x, hi.x)),
        y: Axis::new(lo.y, hi.y, count(lo.y, hi.y)),
        z: Axis::new(z_min, z_max, nz),
    };
    v.validate()?;
    Ok(v)
}

/// Peak voxel position and value of an intensity volume.
pub fn peak(vol: &Volume, intensity: &[f32]) -> ([f64; 3], f32) {
    let (i, &v) = intensity
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .unwrap_or((0, &0.0));
    let (ix, iy, iz) = vol.unravel(i);
    (vol.centre(ix, iy, iz).to_array(), v)
}

/// In a medium the backscatter near the relay is the strongest early signal: a peak on the volume's
/// nearest plane, with no gate, usually images it rather than the scene.
fn near_face_warning(vol: &Volume, intensity: &[f32], gated: &GateReport) -> Option<String> {
    let (p, _) = peak(vol, intensity);
    let near = vol.z.start.min(vol.z.end);
    (gated.open_m.is_none() && vol.z.n > 2 && (p[2] - near).abs() < 1e-9).then(|| {
        format!(
            "the brightest voxel lies on the volume's nearest plane (z = {} m): if the capture is in a medium, that is its backscatter near the relay; start the volume further away or fade out the early paths with a gate (--gate PATH_M)",
            murk_core::short(near)
        )
    })
}
