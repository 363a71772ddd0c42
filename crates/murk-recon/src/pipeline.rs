//! One reconstruction contract over every method: what a user asks for ([`Request`]: the method with
//! its parameters, the volume, the time offset, the gate and the window's end), a [`Plan`] made once
//! per capture geometry, and what comes back (a [`Reconstruction`]: the volume, its intensity, the
//! rows that say how it was made, warnings). `murk reconstruct` and the Python module are this call;
//! a new method is its own module plus one arm in [`Method`], [`Method::NAMES`] and [`Engine`].

use crate::medium::{self, detect::Signature, removal, DepthSearch, MediumAware, MediumRemoval};
use crate::{Compensation, Falloff, Lateral, PfForm, PfParams, PfPlan, Progress, Wavelength};
use murk_baselines::{
    BmmParams, BpOptions, CdtParams, CdtPlan, FbpOptions, FkParams, FkPlan, LctParams, LctPlan,
    Pulse, Reflectance, SlabParams,
};
use murk_core::window::{
    apply_gate, handle_end, shortest_path_m, EndReport, GateReport, WindowEnd,
};
use murk_core::{Axis, Capture, CaptureKind, Error, Reconstruction, Result, Volume};

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
    /// The boundary migration model (confocal scan of a diffusive medium's surface; its own volume).
    Bmm(BmmParams),
}

/// The knobs the methods read, by name: what `murk reconstruct`'s flags and Python's keywords fill.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// `None`: [`Wavelength::default_for`] the capture's kind.
    pub wavelength: Option<Wavelength>,
    /// Pulse length in wavelengths (PF).
    pub cycles: f64,
    pub falloff: Falloff,
    pub compensation: Compensation,
    pub lateral: Lateral,
    /// Wiener signal-to-noise ratio (lct, cdt); `None`: each method's default.
    pub snr: Option<f64>,
    pub reflectance: Reflectance,
    /// The scattering slab in front of the scene (cdt; [`TOffset::Slab`]).
    pub slab: SlabParams,
    /// The medium the scene is inside (bmm); unset constants come from the capture.
    pub medium: BmmParams,
}

impl Default for Options {
    fn default() -> Options {
        let pf = PfParams::default();
        Options {
            wavelength: None,
            cycles: pf.cycles,
            falloff: pf.falloff,
            compensation: pf.compensation,
            lateral: pf.lateral,
            snr: None,
            reflectance: Reflectance::Diffuse,
            slab: SlabParams::default(),
            medium: BmmParams::default(),
        }
    }
}

impl Options {
    fn pf(&self, kind: CaptureKind) -> PfParams {
        PfParams {
            wavelength: self
                .wavelength
                .unwrap_or_else(|| Wavelength::default_for(kind)),
            cycles: self.cycles,
            falloff: self.falloff,
            compensation: self.compensation,
            lateral: self.lateral,
        }
    }
}

impl Method {
    /// Every method's name and a line about it, in the order `--help` lists them.
    pub const NAMES: [(&'static str, &'static str); 8] = [
        ("pf", "Phasor Fields, fast planar form (falls back to the exact form when the wall is not a planar grid)"),
        ("pf-exact", "Phasor Fields, exact time-domain form for any geometry (slow on big captures)"),
        ("bp", "Backprojection (any capture kind, on the volume)"),
        ("fbp", "Filtered backprojection: BP then a −∇²G filter (any capture kind, on the volume)"),
        ("lct", "Light-cone transform with Wiener deconvolution (confocal grid; own volume)"),
        ("fk", "f-k (Stolt) migration (confocal grid; own volume)"),
        ("cdt", "Confocal diffuse tomography: slab deconvolution, then f-k (confocal grid behind a slab; own volume)"),
        ("bmm", "Boundary migration model: diffusion inverted to a virtual wave, then f-k (confocal scan of a medium the scene is inside; own volume)"),
    ];

    /// The method called `name`, with its parameters from `o`, for a capture of `kind`. A knob of
    /// `o` set away from its default that this method does not read is refused, naming it: a
    /// compensation that lct silently dropped looked applied.
    pub fn from_name(name: &str, kind: CaptureKind, o: &Options) -> Result<Method> {
        let d = Options::default();
        // (what, set, the methods that read it)
        let knobs: [(&str, bool, &[&str]); 8] = [
            ("a wavelength", o.wavelength.is_some(), &["pf", "pf-exact"]),
            ("cycles", o.cycles != d.cycles, &["pf", "pf-exact"]),
            ("a falloff", o.falloff != d.falloff, &["pf", "pf-exact"]),
            (
                "compensation",
                o.compensation != d.compensation,
                &["pf", "pf-exact"],
            ),
            ("a lateral band", o.lateral != d.lateral, &["pf"]),
            ("a Wiener snr", o.snr.is_some(), &["lct", "cdt"]),
            (
                "a reflectance weighting",
                o.reflectance != d.reflectance,
                &["lct"],
            ),
            ("medium constants", o.medium != d.medium, &["bmm"]),
        ];
        let known = Method::NAMES.iter().any(|(n, _)| *n == name);
        if let Some((what, _, users)) = knobs
            .iter()
            .find(|(_, set, users)| known && *set && !users.contains(&name))
        {
            return Err(Error::param(format!(
                "{what} does not apply to {name}, which would ignore it (it applies to {})",
                users.join(" and ")
            )));
        }
        Ok(match name {
            "pf" => Method::Pf(o.pf(kind)),
            "pf-exact" => Method::PfExact(o.pf(kind)),
            "bp" => Method::Bp,
            "fbp" => Method::Fbp(FbpOptions::default()),
            "lct" => Method::Lct(LctParams {
                snr: o.snr.unwrap_or(LctParams::default().snr),
                reflectance: o.reflectance,
                ..Default::default()
            }),
            "fk" => Method::Fk(FkParams::default()),
            "cdt" => Method::Cdt(CdtParams {
                slab: o.slab,
                snr: o.snr.unwrap_or(CdtParams::default().snr),
                ..Default::default()
            }),
            "bmm" => Method::Bmm(o.medium),
            other => {
                let names: Vec<&str> = Method::NAMES.iter().map(|(n, _)| *n).collect();
                return Err(Error::param(format!(
                    "unknown method '{other}'; expected one of {}",
                    names.join(", ")
                )));
            }
        })
    }

    /// The name [`Method::from_name`] reads.
    pub fn name(&self) -> &'static str {
        let i = match self {
            Method::Pf(_) => 0,
            Method::PfExact(_) => 1,
            Method::Bp => 2,
            Method::Fbp(_) => 3,
            Method::Lct(_) => 4,
            Method::Fk(_) => 5,
            Method::Cdt(_) => 6,
            Method::Bmm(_) => 7,
        };
        Method::NAMES[i].0
    }

    /// Methods that reconstruct on the confocal scan grid and ignore the requested volume.
    pub fn own_grid(&self) -> bool {
        matches!(
            self,
            Method::Lct(_) | Method::Fk(_) | Method::Cdt(_) | Method::Bmm(_)
        )
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

/// The ramp at either end of the window: PF's pulse σ, or a fixed number of bins.
fn edge_m(pulse: Option<Pulse>, cap: &Capture) -> f64 {
    pulse.map_or(BASELINE_EDGE_BINS as f64 * cap.time.bin_width_m, |p| {
        p.sigma_m
    })
}

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

impl TOffset {
    /// Reads `metres` or `slab` (the delay of `o.slab`'s round trip); `None` is no offset. A slab
    /// other than the default that neither `method` (cdt) nor the offset reads is refused, so that it
    /// cannot look applied.
    pub fn parse(text: Option<&str>, o: &Options, method: &Method) -> Result<TOffset> {
        let offset = match text {
            None => TOffset::None,
            Some("slab") => TOffset::Slab(o.slab),
            Some(s) => match s.parse::<f64>() {
                Ok(v) if v.is_finite() => TOffset::Metres(v),
                _ => {
                    return Err(Error::param(format!(
                        "t-offset '{s}': expected metres or 'slab'"
                    )))
                }
            },
        };
        let slab_read = matches!(offset, TOffset::Slab(_)) || matches!(method, Method::Cdt(_));
        if !slab_read && o.slab != SlabParams::default() {
            return Err(Error::param(format!(
                "slab parameters are read only by cdt and by t-offset 'slab'; {} would ignore them",
                method.name()
            )));
        }
        Ok(offset)
    }
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

impl std::str::FromStr for Gate {
    type Err = Error;

    /// Reads a path in metres, `auto` or `off`.
    fn from_str(text: &str) -> Result<Gate> {
        Ok(match text {
            "off" => Gate::Off,
            "auto" => Gate::Auto,
            t => match t.parse::<f64>() {
                Ok(p) if p.is_finite() => {
                    murk_core::Limits::get().length(&format!("gate '{t}'"), p)?;
                    Gate::At(p)
                }
                _ => {
                    return Err(Error::param(format!(
                        "gate '{t}': expected a path in metres, auto or off"
                    )))
                }
            },
        })
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Request {
    pub method: Method,
    pub volume: VolumeSpec,
    pub t_offset: TOffset,
    pub gate: Gate,
    pub window_end: WindowEnd,
    /// The medium's response removed, and the depth range searched, when a medium is detected.
    pub medium: MediumAware,
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
            medium: MediumAware::default(),
        }
    }
}

/// A method's own plan: what it builds once per geometry.
enum Engine {
    Pf(Box<PfPlan>),
    Bp(Volume, BpOptions),
    Fbp(Volume, FbpOptions),
    Lct(LctPlan),
    Fk(FkPlan),
    Cdt(CdtPlan),
    Bmm(BmmParams),
}

impl Engine {
    fn new(
        geometry: &Capture,
        method: &Method,
        volume: Option<&Volume>,
        progress: &dyn Progress,
    ) -> Result<Engine> {
        let on_volume = || volume.ok_or_else(|| Error::param("this method needs a volume"));
        Ok(match *method {
            Method::Pf(p) => Engine::Pf(Box::new(PfPlan::new(
                geometry,
                on_volume()?,
                &p,
                PfForm::Fast,
            )?)),
            Method::PfExact(p) => Engine::Pf(Box::new(PfPlan::new(
                geometry,
                on_volume()?,
                &p,
                PfForm::Exact,
            )?)),
            Method::Bp => Engine::Bp(*on_volume()?, BpOptions::default()),
            Method::Fbp(o) => Engine::Fbp(*on_volume()?, o),
            Method::Lct(p) => Engine::Lct(LctPlan::new(geometry, p, progress)?),
            Method::Fk(p) => Engine::Fk(FkPlan::new(geometry, p)?),
            Method::Cdt(p) => Engine::Cdt(CdtPlan::new(geometry, p, progress)?),
            // Its window and inversion are measured on each capture: nothing to plan.
            Method::Bmm(p) => Engine::Bmm(p),
        })
    }

    fn run(&self, cap: &Capture, progress: &dyn Progress) -> Result<Reconstruction> {
        match self {
            Engine::Pf(plan) => plan.run(cap, progress),
            Engine::Bp(v, o) => murk_baselines::backproject_with(cap, v, *o, progress),
            Engine::Fbp(v, o) => murk_baselines::fbp_with(cap, v, *o, progress),
            Engine::Lct(plan) => plan.run(cap, progress),
            Engine::Fk(plan) => plan.run(cap, progress),
            Engine::Cdt(plan) => plan.run(cap, progress),
            Engine::Bmm(p) => murk_baselines::bmm_with(cap, *p, progress),
        }
    }
}

/// A [`Request`] planned for captures of one geometry ([`Capture::same_geometry`]): the time offset,
/// the volume, the gate and the method's own plan are settled once; [`Plan::run`] serves each capture.
pub struct Plan {
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
    engine: Engine,
    /// The warning for a volume that the method's own grid replaces.
    ignored_volume: Option<String>,
    /// The medium response that [`MediumRemoval::Model`] subtracts.
    predicted: Option<removal::Predicted>,
}

impl Plan {
    /// Plans `req` for captures of `cap`'s geometry. The methods whose plan takes long (the LCT's and
    /// CDT's kernel spectra) report it to `progress` as a bar of its own and stop when it asks.
    pub fn new(cap: &Capture, req: &Request, progress: &dyn Progress) -> Result<Plan> {
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
                    // Blaming the gate would send the user to --gate; the volume is what is out of reach.
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
        let engine = Engine::new(&geometry, m, volume.as_ref(), progress)?;
        // Said with the result, so that the CLI and Python both report it.
        let ignored_volume =
            (matches!(req.volume, VolumeSpec::Given(_)) && m.own_grid()).then(|| {
                format!(
                    "the given volume is ignored by {}: it reconstructs on the capture's scan grid",
                    m.name()
                )
            });
        Ok(Plan {
            ignored_volume,
            offset_m,
            edge_m,
            open_m,
            gate_given: matches!(req.gate, Gate::At(_)),
            window_end: req.window_end,
            removal: req.medium.removal,
            on_volume: !m.own_grid(),
            geometry,
            engine,
            predicted: None,
        })
    }

    /// The plan with the medium response that [`MediumRemoval::Model`] subtracts.
    pub fn with_predicted(self, predicted: Option<removal::Predicted>) -> Plan {
        Plan { predicted, ..self }
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
        let mut out = self.engine.run(&cap, progress)?;
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
/// whose early bins are a medium's response, the depth range is first searched ([`medium::search`]).
pub fn run(cap: Capture, req: &Request, progress: &dyn Progress) -> Result<Reconstruction> {
    run_with(cap, req, None, progress)
}

/// As [`run`], with the medium response that [`MediumRemoval::Model`] subtracts.
pub fn run_with(
    cap: Capture,
    req: &Request,
    predicted: Option<removal::Predicted>,
    progress: &dyn Progress,
) -> Result<Reconstruction> {
    let (req, searched) = search_depth(&cap, req, predicted.as_ref(), progress)?;
    let mut out = Plan::new(&cap, &req, progress)?
        .with_predicted(predicted)
        .run(cap, progress)?;
    out.rows
        .extend(searched.map(|(_, line)| ("depth search".to_string(), line)));
    Ok(out)
}

/// `req` with the volume the depth search chose, and what it found with its line for the summary;
/// `req` unchanged where no search applies.
pub fn search_depth(
    cap: &Capture,
    req: &Request,
    predicted: Option<&removal::Predicted>,
    progress: &dyn Progress,
) -> Result<(Request, Option<(medium::search::Found, String)>)> {
    let applies = req.volume == VolumeSpec::Default
        && req.medium.depth_search == DepthSearch::Auto
        && req.medium.removal != MediumRemoval::Off
        && !req.method.own_grid()
        && Signature::measure(cap).is_medium();
    if !applies {
        return Ok((*req, None));
    }
    // The whole reach at no more than the search's planes; the depth range kept gets the default
    // volume's spacing.
    let full = default_volume(cap)?;
    let step_m = (full.z.end - full.z.start) / (full.z.n - 1) as f64;
    let coarse = Volume {
        z: Axis::new(
            full.z.start,
            full.z.end,
            full.z.n.min(medium::search::SEARCH_PLANES),
        ),
        ..full
    };
    let whole_req = Request {
        volume: VolumeSpec::Given(coarse),
        ..*req
    };
    let whole = Plan::new(cap, &whole_req, progress)?
        .with_predicted(predicted.cloned())
        .run(cap.clone(), progress)?;
    // A given gate's edge is a step in the signal that lights the planes its paths reach: only the
    // planes it leaves fully open are searched.
    let open_m = match req.gate {
        Gate::At(open_m) => Some(open_m + GATE_MARGIN_EDGES * edge_m(req.method.pulse(cap)?, cap)),
        _ => None,
    };
    let usable = |z_m: f64| -> bool {
        let plane = Volume {
            z: Axis::new(z_m, z_m, 1),
            ..whole.volume
        };
        open_m.is_none_or(|open_m| shortest_path_m(cap, &plane) >= open_m)
    };
    let Some(found) = medium::search::choose(&whole, &usable, step_m) else {
        return Ok((*req, None));
    };
    let line = found.describe(&whole.volume);
    let mut chosen = *req;
    if let Some(v) = found.volume {
        chosen.volume = VolumeSpec::Given(v);
    }
    Ok((chosen, Some((found, line))))
}

fn closing_rows(offset_m: f64, gated: &GateReport, end: &EndReport) -> Vec<(String, String)> {
    vec![
        ("t_offset_m".into(), format!("{offset_m:.6}")),
        ("gate".into(), gated.describe()),
        ("window_end".into(), end.describe()),
    ]
}

/// The deepest depth the time window reaches: the shortest round trip to depth z is 2z (a voxel
/// straight in front of the wall points) plus the devices' legs.
fn deepest_reach_m(cap: &Capture) -> f64 {
    let offsets = (0..cap.n_hist())
        .map(|i| {
            let (l, s) = cap.hist_pair(i);
            cap.first_bounce_m(l) + cap.last_bounce_m(s)
        })
        .fold(f64::MAX, f64::min);
    (cap.time.end_m() - offsets) / 2.0
}

/// The wall grid's extent and spacing in x and y; depth from 0.1 m to what the time window reaches.
pub fn default_volume(cap: &Capture) -> Result<Volume> {
    let side = if cap.sensor.len() > cap.illum.len() {
        &cap.sensor
    } else {
        &cap.illum
    };
    let spacing = crate::wall_spacing_m(cap).ok_or_else(|| {
        Error::param(match side.len() {
            1 => "the capture has a single wall point, so no spacing to derive a volume from; give a volume".to_string(),
            n => format!("the capture's {n} wall points all coincide, so no spacing to derive a volume from; give a volume"),
        })
    })?;
    let (lo, hi) = side
        .points
        .iter()
        .fold((side.points[0], side.points[0]), |(a, b), p| {
            (a.min(*p), b.max(*p))
        });
    let count = |a: f64, b: f64| ((b - a) / spacing).round() as usize + 1;
    let z_max = deepest_reach_m(cap);
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

/// In a medium the backscatter near the relay is the strongest early signal: a peak on the volume's
/// nearest plane, with no gate, usually images it rather than the scene.
fn near_face_warning(rec: &Reconstruction, gated: &GateReport) -> Option<String> {
    let (p, _) = rec.peak();
    let vol = &rec.volume;
    let near = vol.z.start.min(vol.z.end);
    (gated.open_m.is_none() && vol.z.n > 2 && (p[2] - near).abs() < 1e-9).then(|| {
        format!(
            "the brightest voxel lies on the volume's nearest plane (z = {} m): if the capture is in a medium, that is its backscatter near the relay; start the volume further away or fade out the early paths with a gate (--gate PATH_M)",
            murk_core::short(near)
        )
    })
}
