//! A [`Request`] planned once per capture geometry ([`ReconPlan`]) and run per capture: the time
//! offset, the gate, the window's end and the medium's removal around the method's own plan.

use crate::depth::{deepest_reach_m, default_volume, search_depth, Searched};
use crate::{Gate, Request, TOffset, VolumeSpec};
use murk_baselines::Pulse;
use murk_core::window::{
    apply_gate, handle_end, shortest_path_m, EndReport, GateReport, WindowEnd,
};
use murk_core::{Capture, Error, Progress, Reconstruction, Reconstructor, Result};
use murk_recon::medium::{detect::Signature, removal, MediumRemoval};
use murk_recon::PathDensity;
use std::sync::Arc;

/// What the caller knows of the capture's medium besides the request: the response that
/// [`MediumRemoval::Model`] subtracts, the density that the compensation integrates along each leg,
/// and a depth search already run on the capture (murk-medium makes all three: the search is its
/// estimate's).
#[derive(Clone, Default)]
pub struct MediumGiven {
    pub predicted: Option<removal::Predicted>,
    pub density: Option<Arc<dyn PathDensity>>,
    pub searched: Option<Searched>,
}

/// Ramp length (bins) at either end of the window for the methods without a pulse, chosen on a cut
/// real capture (docs/window-ends.md).
const BASELINE_EDGE_BINS: usize = 20;

/// The ramp at either end of the window: PF's pulse σ, or a fixed number of bins.
pub(crate) fn edge_m(pulse: Option<Pulse>, cap: &Capture) -> f64 {
    pulse.map_or(BASELINE_EDGE_BINS as f64 * cap.time.bin_width_m, |p| {
        p.sigma_m
    })
}

/// How many edges before the volume's shortest path [`Gate::Auto`] opens.
pub(crate) const GATE_MARGIN_EDGES: f64 = 3.0;

/// A [`Request`] planned for captures of one geometry ([`Capture::same_geometry`]): the time offset,
/// the volume, the gate and the method's own plan are settled once; [`ReconPlan::run`] serves each capture.
pub struct ReconPlan {
    offset_m: f64,
    edge_m: f64,
    open_m: Option<f64>,
    /// Whether `open_m` was set by hand (`Gate::At`), which makes a gate that fades nothing worth saying.
    gate_given: bool,
    window_end: WindowEnd,
    /// Whether (and when) the medium's response is subtracted before the gate.
    removal: MediumRemoval,
    /// Whether the method reconstructs on a volume (auto removal serves only those).
    on_volume: bool,
    /// The geometry the plan was made for, with the time offset applied.
    geometry: Capture,
    /// The method's own plan.
    method: Box<dyn Reconstructor>,
    /// The warning for a volume that the method's own grid replaces.
    ignored_volume: Option<String>,
    /// The medium response that [`MediumRemoval::Model`] subtracts.
    predicted: Option<removal::Predicted>,
}

impl ReconPlan {
    /// Plans `req` for captures of `cap`'s geometry. The methods whose plan takes long (the LCT's and
    /// CDT's kernel spectra) report it to `progress` as a bar of its own and stop when it asks.
    pub fn new(cap: &Capture, req: &Request, progress: &dyn Progress) -> Result<ReconPlan> {
        ReconPlan::given(cap, req, &MediumGiven::default(), progress)
    }

    /// As [`ReconPlan::new`], with what the caller knows of the medium.
    pub fn given(
        cap: &Capture,
        req: &Request,
        given: &MediumGiven,
        progress: &dyn Progress,
    ) -> Result<ReconPlan> {
        let m = &req.method;
        let mut geometry = cap.geometry();
        geometry.validate_geometry()?;
        let pulse = m.pulse(&geometry)?;
        let offset_m = match req.t_offset {
            TOffset::None => 0.0,
            TOffset::Metres(v) => {
                murk_core::Limits::get().length("the time offset", v)?;
                v
            }
            TOffset::Slab(slab) => slab.round_trip_delay_m(pulse)?,
        };
        geometry.time.start_m -= offset_m;
        // The ramp at either end of the window: PF's pulse σ, or a fixed number of bins.
        let edge_m = edge_m(pulse, &geometry);
        let volume = match (req.volume, m.own_grid()) {
            // The methods on their own grid have no volume to check against the window.
            (_, true) if deepest_reach_m(&geometry) <= 0.0 => {
                return Err(Error::param(format!(
                    "the capture's time window ends at {:.3} m of path (after the time offset), before any depth behind the wall",
                    geometry.time.end_m()
                )))
            }
            (_, true) => None,
            (VolumeSpec::Given(v), false) => {
                v.validate()?;
                Some(v)
            }
            (VolumeSpec::Default, false) => Some(default_volume(&geometry)?),
        };
        let open_m = match (req.gate, &volume) {
            (Gate::Auto, Some(v)) => {
                let shortest_m = shortest_path_m(&geometry, v);
                let open_m = shortest_m - GATE_MARGIN_EDGES * edge_m;
                if open_m >= geometry.time.end_m() {
                    // Blaming the gate would send the user to the gate option; the volume is what is out of reach.
                    return Err(Error::param(format!(
                        "the volume lies beyond the capture's window: its nearest voxel is {shortest_m:.3} m of path away, the window ends at {:.3} m (after the time offset); choose a volume nearer the wall",
                        geometry.time.end_m()
                    )));
                }
                Some(open_m)
            }
            // Own-grid methods have no volume to derive it from.
            (Gate::Auto, None) | (Gate::Off, _) => None,
            (Gate::At(p), _) => Some(p),
        };
        let method = m.plan(&geometry, volume.as_ref(), given.density.as_ref(), progress)?;
        // Said with the result, so that the CLI and Python both report it.
        let ignored_volume =
            (matches!(req.volume, VolumeSpec::Given(_)) && m.own_grid()).then(|| {
                format!(
                    "the given volume is ignored by {}: it reconstructs on the capture's scan grid",
                    m.name()
                )
            });
        Ok(ReconPlan {
            ignored_volume,
            offset_m,
            edge_m,
            open_m,
            gate_given: matches!(req.gate, Gate::At(_)),
            window_end: req.window_end,
            removal: req.medium.removal,
            on_volume: !m.own_grid(),
            geometry,
            method,
            predicted: given.predicted.clone(),
        })
    }

    /// Reconstructs `cap`, which must have the geometry the plan was made for.
    pub fn run(&self, mut cap: Capture, progress: &dyn Progress) -> Result<Reconstruction> {
        // Measured on the time stamps as stored: the medium's earliest paths are physical ones.
        let removed = match (self.removal, self.on_volume) {
            (MediumRemoval::Off, _) | (MediumRemoval::Auto, false) => None,
            (MediumRemoval::Fit, _) => Some(removal::subtract(&mut cap, None)),
            (MediumRemoval::Model, _) => {
                let predicted = self.predicted.as_ref().ok_or_else(|| {
                    Error::param(
                        "model removal needs the medium's predicted response (murk_medium::model::predict makes it)",
                    )
                })?;
                let signature = Some(Signature::measure(&cap));
                Some(removal::subtract_predicted(&mut cap, predicted, signature)?)
            }
            (MediumRemoval::Auto, true) => {
                let signature = Signature::measure(&cap);
                signature
                    .is_medium()
                    .then(|| removal::subtract(&mut cap, Some(signature)))
            }
        };
        cap.time.start_m -= self.offset_m;
        if !self.geometry.same_geometry(&cap) {
            return Err(Error::param(
                "the capture's points or time axis differ from the ones the plan was made for",
            ));
        }
        if let Some(open_m) = self.open_m.filter(|&g| g >= cap.time.end_m()) {
            // Every bin would be gated away: a volume of zeros would look like a result.
            return Err(Error::param(format!(
                "the gate at {open_m:.3} m opens after the capture's window ends ({:.3} m): nothing would be left",
                cap.time.end_m()
            )));
        }
        let gated = apply_gate(&mut cap, self.open_m, self.edge_m);
        let mut end = handle_end(&mut cap, self.window_end, self.edge_m);
        let mut out = self.method.reconstruct(&cap, progress)?;
        let peak = || cap.h.iter().fold(0f32, |m, v| m.max(v.abs()));
        if out.intensity.iter().any(|v| !v.is_finite()) {
            // Finite data whose sums overflow f32: a volume of inf and NaN would look like a result.
            return Err(Error::Limits(format!(
                "the reconstruction overflows 32-bit floats (the capture's values reach {}); scale the capture down",
                murk_core::short(peak() as f64)
            )));
        }
        if out.intensity.iter().all(|&v| v == 0.0) {
            // A volume of zeros would look like a result (lct, fk and cdt gave one for windows that
            // cannot reach their volume, and for values that underflow).
            return Err(Error::param(match peak() {
                0.0 => "the reconstruction is all zeros because the capture's histograms are all zeros (after any gate)"
                    .to_string(),
                peak => format!(
                    "the reconstruction is all zeros: no signal of the capture's window ({:.3} to {:.3} m, values up to {}) reaches the volume",
                    cap.time.start_m,
                    cap.time.end_m(),
                    murk_core::short(peak as f64)
                ),
            }));
        }
        end.trim(&cap, &out.volume, &mut out.intensity);
        out.clear_dark_normals();
        // The volume is scanned only where the window end was trimmed, the cause explained here.
        let cleared = |_: &f64| out.intensity.iter().all(|&v| v == 0.0);
        if let Some(from_m) = end.trim_from_m.filter(cleared) {
            // The trim cleared what only the cut end of the window reaches: here, every voxel.
            let short = murk_core::short;
            let why = if from_m <= cap.time.start_m {
                format!(
                    "the window ({} to {} m) is shorter than its tapered end needs ({} m twice)",
                    short(cap.time.start_m),
                    short(cap.time.end_m()),
                    short(end.taper_m)
                )
            } else {
                format!(
                    "no voxel is reached by a path shorter than {} m, where its tapered end begins",
                    short(from_m)
                )
            };
            return Err(Error::param(format!(
                "the window-end handling cleared every voxel: the capture's window is cut while its signal is strong (the last 5 % of bins carry {:.0} % of the peak) and {why}; give a volume nearer the wall, a capture with a longer window, or window-end keep",
                100.0 * end.level
            )));
        }
        out.warnings.extend(self.ignored_volume.clone());
        if self.gate_given && gated.open_m.is_none() {
            out.warnings.push(format!(
                "the gate at {:.3} m opens before the capture's window starts ({:.3} m of path, after the time offset): it fades nothing",
                self.open_m.unwrap_or_default(),
                cap.time.start_m
            ));
        }
        out.warnings.extend(end.warning());
        out.warnings.extend(near_face_warning(&out, &gated));
        out.rows.extend(closing_rows(self.offset_m, &gated, &end));
        // Said only where a medium was met, so that captures without one keep their summaries.
        out.rows
            .extend(removed.map(|r| ("medium".to_string(), r.describe())));
        Ok(out)
    }
}

/// Runs `req` on `cap` (plans and runs). With the default volume, a method on a volume and a capture
/// whose early bins are a medium's response, the depth range is first searched ([`murk_recon::medium::search`]).
pub fn run(cap: Capture, req: &Request, progress: &dyn Progress) -> Result<Reconstruction> {
    run_given(cap, req, &MediumGiven::default(), progress)
}

/// As [`run`], with what the caller knows of the medium.
pub fn run_given(
    cap: Capture,
    req: &Request,
    given: &MediumGiven,
    progress: &dyn Progress,
) -> Result<Reconstruction> {
    let (req, searched) = search_depth(&cap, req, given, progress)?;
    let mut out = ReconPlan::given(&cap, &req, given, progress)?.run(cap, progress)?;
    out.rows
        .extend(searched.map(|(_, line)| ("depth search".to_string(), line)));
    Ok(out)
}

fn closing_rows(offset_m: f64, gated: &GateReport, end: &EndReport) -> Vec<(String, String)> {
    vec![
        ("t_offset_m".into(), format!("{offset_m:.6}")),
        ("gate".into(), gated.describe()),
        ("window_end".into(), end.describe()),
    ]
}

/// In a medium the backscatter near the relay is the strongest early signal: a peak on the volume's
/// nearest plane, with no gate, usually images it rather than the scene.
fn near_face_warning(rec: &Reconstruction, gated: &GateReport) -> Option<String> {
    let (p, _) = rec.peak();
    let vol = &rec.volume;
    let near = vol.z.start.min(vol.z.end);
    (gated.open_m.is_none() && vol.z.n > 2 && (p[2] - near).abs() < 1e-9).then(|| {
        format!(
            "the brightest voxel lies on the volume's nearest plane (z = {} m): if the capture is in a medium, that is its backscatter near the relay; start the volume further away or fade out the early paths with a gate ({})",
            murk_core::short(near),
            murk_core::Opt::Gate.set("PATH_M")
        )
    })
}
