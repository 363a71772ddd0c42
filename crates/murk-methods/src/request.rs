//! What a user asks for: the method with its options, the volume, the time offset, the gate, the
//! window's end and the medium-aware path ([`Request`]).

use crate::table::Knob;
use crate::{Method, Options};
use murk_baselines::SlabParams;
use murk_core::window::WindowEnd;
use murk_core::{Error, Result, Volume};
use murk_recon::medium::MediumAware;

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
        let slab_read = matches!(offset, TOffset::Slab(_)) || method.reads(Knob::Slab);
        if !slab_read && Knob::Slab.is_set(o) {
            return Err(Error::param(format!(
                "slab parameters are read only by {} and by t-offset 'slab'; {} would ignore them",
                Knob::Slab.readers(),
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
