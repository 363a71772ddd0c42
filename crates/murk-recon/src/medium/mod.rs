//! Seeing through a medium without being told where to look: whether a capture's early bins are a
//! medium's response ([`detect`]), that response estimated from the capture itself and subtracted
//! ([`removal`]), and the depth range chosen from where the remaining signal focuses ([`search`]).
//!
//! What removal can and cannot do (measured in `docs/medium.md`): Phasor Fields' band-pass already
//! rejects the slowly varying mean of a medium's response, so subtracting it barely changes a PF image on
//! its own. It matters where the capture is cut: a gate or the window's start is a step in the strong
//! medium signal, which the band-pass turns into a false surface; with the mean removed first the step
//! is small. The medium's photon (or Monte Carlo) noise is not removed by any subtraction.

pub mod detect;
pub mod removal;
pub mod search;

use murk_core::Named;

/// Whether the medium's response is subtracted before reconstructing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum MediumRemoval {
    /// Subtract it when [`detect::Signature`] finds a medium, for the methods on a volume (pf,
    /// pf-exact, bp, fbp); captures without a medium are left as they are.
    #[default]
    Auto,
    /// Always subtract the model-free fit ([`removal::subtract`]), for any method.
    Fit,
    /// Subtract the response a forward model predicts for the medium ([`removal::Predicted`], which
    /// the caller supplies: murk-medium renders it for the estimated or given medium).
    Model,
    Off,
}

impl Named for MediumRemoval {
    const WHAT: &'static str = "medium removal";
    const CHOICES: &'static [(&'static str, Self)] = &[
        ("auto", Self::Auto),
        ("model", Self::Model),
        ("fit", Self::Fit),
        ("off", Self::Off),
    ];
}

/// Whether the default volume's depth range is chosen from the data when a medium is detected.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum DepthSearch {
    /// With the default volume and a detected medium: reconstruct the whole reach coarsely, then keep
    /// the depths around the plane where the signal focuses best ([`search`]).
    #[default]
    Auto,
    Off,
}

impl Named for DepthSearch {
    const WHAT: &'static str = "depth search";
    const CHOICES: &'static [(&'static str, Self)] = &[("auto", Self::Auto), ("off", Self::Off)];
}

/// What a request asks of the medium-aware path.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct MediumAware {
    pub removal: MediumRemoval,
    pub depth_search: DepthSearch,
}
