//! The one table of reconstruction methods: each entry says what the method is called, what it
//! reads, where it reconstructs and how its plan is made. `murk reconstruct --method` (values and
//! help), Python's `murk.methods()` and the study's method columns all read [`METHODS`].

use crate::Options;
use murk_baselines::{
    BmmPlan, BpOptions, BpPlan, CdtParams, CdtPlan, DlctParams, DlctPlan, FbpOptions, FbpPlan,
    FkParams, FkPlan, LctParams, LctPlan,
};
use murk_core::{Capture, Error, Progress, Reconstructor, Result, Volume};
use murk_recon::{PathDensity, PfForm, PfPlan};
use std::sync::Arc;

/// A knob of [`Options`] that some methods read. A method given a knob it does not read refuses it,
/// naming the methods that do: a compensation that lct silently dropped looked applied.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Knob {
    Wavelength,
    Cycles,
    Falloff,
    Compensation,
    Lateral,
    Snr,
    Reflectance,
    /// The scattering slab: read by cdt and by `TOffset::Slab`, which refuses it instead.
    Slab,
    Medium,
}

impl Knob {
    /// Every knob, in the order a refusal names the first one set.
    pub const ALL: [Knob; 9] = [
        Knob::Wavelength,
        Knob::Cycles,
        Knob::Falloff,
        Knob::Compensation,
        Knob::Lateral,
        Knob::Snr,
        Knob::Reflectance,
        Knob::Slab,
        Knob::Medium,
    ];

    /// What the knob is, as a refusal names it.
    pub fn what(self) -> &'static str {
        match self {
            Knob::Wavelength => "a wavelength",
            Knob::Cycles => "cycles",
            Knob::Falloff => "a falloff",
            Knob::Compensation => "compensation",
            Knob::Lateral => "a lateral band",
            Knob::Snr => "a Wiener snr",
            Knob::Reflectance => "a reflectance weighting",
            Knob::Slab => "slab parameters",
            Knob::Medium => "medium constants",
        }
    }

    /// Whether `o` sets this knob away from its default.
    pub fn is_set(self, o: &Options) -> bool {
        let d = Options::default();
        match self {
            Knob::Wavelength => o.wavelength.is_some(),
            Knob::Cycles => o.cycles != d.cycles,
            Knob::Falloff => o.falloff != d.falloff,
            Knob::Compensation => o.compensation != d.compensation,
            Knob::Lateral => o.lateral != d.lateral,
            Knob::Snr => o.snr.is_some(),
            Knob::Reflectance => o.reflectance != d.reflectance,
            Knob::Slab => o.slab != d.slab,
            Knob::Medium => o.medium != d.medium,
        }
    }

    /// The methods that read this knob, in the table's order ("pf and pf-exact").
    pub fn readers(self) -> String {
        let names: Vec<&str> = METHODS
            .iter()
            .filter(|m| m.reads.contains(&self))
            .map(|m| m.name)
            .collect();
        names.join(" and ")
    }
}

/// What a method's constructor gets: the geometry with the time offset applied, the options, the
/// volume (for the methods that reconstruct on one) and where to report a long planning step.
pub struct Setup<'a> {
    pub geometry: &'a Capture,
    pub options: &'a Options,
    pub volume: Option<&'a Volume>,
    /// The medium's density along the compensation's legs (read with [`Knob::Compensation`]).
    pub density: Option<&'a Arc<dyn PathDensity>>,
    pub progress: &'a dyn Progress,
}

impl Setup<'_> {
    /// The volume, for the methods that reconstruct on one.
    pub fn volume(&self) -> Result<&Volume> {
        self.volume
            .ok_or_else(|| Error::param("this method needs a volume"))
    }
}

/// One reconstruction method: its entry in [`METHODS`].
pub struct MethodSpec {
    /// The name `--method` and Python's `method=` take.
    pub name: &'static str,
    /// A line about it, for `--help`.
    pub help: &'static str,
    /// The knobs of [`Options`] it reads; any other one set is refused.
    pub reads: &'static [Knob],
    /// Reconstructs on the confocal scan grid, ignoring the requested volume.
    pub own_grid: bool,
    /// Reconstructs with Phasor Fields' virtual pulse, whose σ sets the window's edges and the slab's
    /// delay as the method sees it.
    pub pulsed: bool,
    /// Plans the method for captures of one geometry.
    pub plan: fn(&Setup) -> Result<Box<dyn Reconstructor>>,
}

/// Every method, in the order `--help` lists them. A new method is its own module (its parameters
/// and a plan implementing [`Reconstructor`]) plus one entry here.
pub const METHODS: &[MethodSpec] = &[
    MethodSpec {
        name: "pf",
        help: "Phasor Fields, fast planar form (falls back to the exact form when the wall is not a planar grid)",
        reads: &[Knob::Wavelength, Knob::Cycles, Knob::Falloff, Knob::Compensation, Knob::Lateral],
        own_grid: false,
        pulsed: true,
        plan: |s| pf(s, PfForm::Fast),
    },
    MethodSpec {
        name: "pf-exact",
        help: "Phasor Fields, exact time-domain form for any geometry (slow on big captures)",
        reads: &[Knob::Wavelength, Knob::Cycles, Knob::Falloff, Knob::Compensation],
        own_grid: false,
        pulsed: true,
        plan: |s| pf(s, PfForm::Exact),
    },
    MethodSpec {
        name: "bp",
        help: "Backprojection (any capture kind, on the volume)",
        reads: &[],
        own_grid: false,
        pulsed: false,
        plan: |s| {
            Ok(Box::new(BpPlan {
                volume: *s.volume()?,
                options: BpOptions::default(),
            }))
        },
    },
    MethodSpec {
        name: "fbp",
        help: "Filtered backprojection: BP then a −∇²G filter (any capture kind, on the volume)",
        reads: &[],
        own_grid: false,
        pulsed: false,
        plan: |s| {
            Ok(Box::new(FbpPlan {
                volume: *s.volume()?,
                options: FbpOptions::default(),
            }))
        },
    },
    MethodSpec {
        name: "lct",
        help: "Light-cone transform with Wiener deconvolution (confocal grid; own volume)",
        reads: &[Knob::Snr, Knob::Reflectance],
        own_grid: true,
        pulsed: false,
        plan: |s| {
            let params = LctParams {
                snr: s.options.snr.unwrap_or(LctParams::default().snr),
                reflectance: s.options.reflectance,
                ..Default::default()
            };
            Ok(Box::new(LctPlan::new(s.geometry, params, s.progress)?))
        },
    },
    MethodSpec {
        name: "dlct",
        help: "Directional light-cone transform: albedo and surface normals by a vector Wiener filter (confocal grid; own volume)",
        reads: &[Knob::Snr],
        own_grid: true,
        pulsed: false,
        plan: |s| {
            let params = DlctParams {
                snr: s.options.snr.unwrap_or(DlctParams::default().snr),
                ..Default::default()
            };
            Ok(Box::new(DlctPlan::new(s.geometry, params, s.progress)?))
        },
    },
    MethodSpec {
        name: "fk",
        help: "f-k (Stolt) migration (confocal grid; own volume)",
        reads: &[],
        own_grid: true,
        pulsed: false,
        plan: |s| Ok(Box::new(FkPlan::new(s.geometry, FkParams::default())?)),
    },
    MethodSpec {
        name: "cdt",
        help: "Confocal diffuse tomography: slab deconvolution, then f-k (confocal grid behind a slab; own volume)",
        reads: &[Knob::Snr, Knob::Slab],
        own_grid: true,
        pulsed: false,
        plan: |s| {
            let params = CdtParams {
                slab: s.options.slab,
                snr: s.options.snr.unwrap_or(CdtParams::default().snr),
                ..Default::default()
            };
            Ok(Box::new(CdtPlan::new(s.geometry, params, s.progress)?))
        },
    },
    MethodSpec {
        name: "bmm",
        help: "Boundary migration model: diffusion inverted to a virtual wave, then f-k (confocal scan of a medium the scene is inside; own volume)",
        reads: &[Knob::Medium],
        own_grid: true,
        pulsed: false,
        // Its window and inversion are measured on each capture: nothing to plan.
        plan: |s| Ok(Box::new(BmmPlan { params: s.options.medium })),
    },
];

/// Phasor Fields in `form`, with the options' wavelength (else the default for the capture's kind).
fn pf(s: &Setup, form: PfForm) -> Result<Box<dyn Reconstructor>> {
    let params = s.options.pf(s.geometry.kind());
    Ok(Box::new(PfPlan::new_along(
        s.geometry,
        s.volume()?,
        &params,
        form,
        s.density.cloned(),
    )?))
}
