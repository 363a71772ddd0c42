//! One reconstruction contract over every method, above Phasor Fields (`murk-recon`) and the
//! baselines (`murk-baselines`): what a user asks for ([`Request`]: the method with its options, the
//! volume, the time offset, the gate and the window's end), a [`ReconPlan`] made once per capture
//! geometry, and what comes back (a [`murk_core::Reconstruction`]: the volume, its intensity, the
//! rows that say how it was made, warnings). `murk reconstruct`, the Python module and the study are
//! this call.
//!
//! Each method's plan implements [`murk_core::Reconstructor`] in its own module; the one table
//! [`METHODS`] gives its name, help, the options it reads, whether it reconstructs on its own grid
//! and its constructor. Adding a method is its module plus one entry there.
//!
//! ```
//! use murk_core::{DVec3, NoProgress, TimeAxis};
//! use murk_methods::{Method, Options, ReconPlan, Request, METHODS};
//! use murk_synth::{add_first_bounce, CaptureLayout, LayoutKind, SynthOptions, Target};
//!
//! // A confocal scan of one point 0.5 m behind a 1 m wall.
//! let layout = CaptureLayout {
//!     kind: LayoutKind::Confocal,
//!     wall_size_m: 1.0,
//!     grid: 16,
//!     point: DVec3::ZERO,
//!     time: TimeAxis { start_m: 0.0, bin_width_m: 0.01, bins: 256 },
//!     laser_xyz: None,
//!     sensor_xyz: None,
//! };
//! let mut cap = layout.empty_capture()?;
//! let point = Target::Point { pos: DVec3::new(0.0, 0.0, 0.5), albedo: 1.0 };
//! add_first_bounce(&mut cap, &point.scatterers()?, &SynthOptions::default())?;
//!
//! assert!(METHODS.iter().any(|m| m.name == "fk"));
//! let method = Method::named("fk", &Options::default())?;
//! let plan = ReconPlan::new(&cap, &Request::new(method), &NoProgress)?; // once per geometry
//! let rec = plan.run(cap, &NoProgress)?; // per capture
//! let (peak, _) = rec.peak();
//! assert!((peak[2] - 0.5).abs() < 0.02, "{peak:?}");
//! # Ok::<(), murk_core::Error>(())
//! ```

mod args;
mod depth;
mod method;
mod plan;
mod request;
mod table;

pub use args::RequestArgs;
pub use depth::{default_volume, search_depth, DepthFound, Searched};
pub use method::{Method, Options};
pub use plan::{run, run_given, MediumGiven, ReconPlan};
pub use request::{Gate, Request, TOffset, VolumeSpec};
pub use table::{Knob, MethodSpec, Setup, METHODS};

#[cfg(test)]
mod tests;
