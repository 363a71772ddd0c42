//! The default volume, and the depth search of the medium-aware path: with the default volume and a
//! capture whose early bins are a medium's response, the whole reach is first reconstructed coarsely
//! and the depths where the signal focuses best are kept.

use crate::plan::{edge_m, MediumGiven, ReconPlan, GATE_MARGIN_EDGES};
use crate::{Gate, Request, VolumeSpec};
use murk_core::window::shortest_path_m;
use murk_core::{Axis, Capture, Error, Progress, Result, Volume};
use murk_recon::medium::{self, detect::Signature, DepthSearch, MediumRemoval};

/// `req` with the volume the depth search chose, and what it found with its line for the summary;
/// `req` unchanged where no search applies.
pub fn search_depth(
    cap: &Capture,
    req: &Request,
    given: &MediumGiven,
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
    let whole = ReconPlan::given(cap, &whole_req, given, progress)?.run(cap.clone(), progress)?;
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

/// The deepest depth the time window reaches: the shortest round trip to depth z is 2z (a voxel
/// straight in front of the wall points) plus the devices' legs.
pub(crate) fn deepest_reach_m(cap: &Capture) -> f64 {
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
    let spacing = murk_recon::wall_spacing_m(cap).ok_or_else(|| {
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
