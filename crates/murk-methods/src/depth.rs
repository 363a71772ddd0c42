//! The default volume, and the depth search of the medium-aware path: with the default volume and a
//! capture whose early bins are a medium's response, the whole reach is first reconstructed coarsely
//! and the depths where the signal focuses best are kept.
//!
//! The search runs on a wall grid of at most [`SEARCH_GRID`] points a side: a finer capture is
//! binned (the mean histogram of each block of points) and searched at its own default volume, whose
//! planes the binned spacing sets. Which plane focuses best needs the focus, not the full lateral
//! resolution; the reconstruction kept is the capture's own.

use crate::plan::{edge_m, MediumGiven, ReconPlan, GATE_MARGIN_EDGES};
use crate::{Gate, Request, VolumeSpec};
use murk_core::window::shortest_path_m;
use murk_core::{
    Axis, Capture, DVec3, Error, Pairing, PointLayout, PointSet, Progress, Result, Volume,
};
use murk_recon::medium::{self, detect::Signature, DepthSearch, MediumRemoval};

/// What a depth search found: the plane, and its line for the summary.
pub type DepthFound = (medium::search::Found, String);

/// `req` with the volume the depth search chose, and what it found; `req` unchanged where no search
/// applies. A search that `given` holds for the request is taken instead of searching again.
pub fn search_depth(
    cap: &Capture,
    req: &Request,
    given: &MediumGiven,
    progress: &dyn Progress,
) -> Result<(Request, Option<DepthFound>)> {
    let found = match given.searched.as_ref().filter(|s| s.serves(req, given)) {
        Some(s) => s.found.clone(),
        None => find(cap, req, given, progress)?,
    };
    let mut chosen = *req;
    if let Some(v) = found.as_ref().and_then(|(f, _)| f.volume) {
        chosen.volume = VolumeSpec::Given(v);
    }
    Ok((chosen, found))
}

/// A depth search run before the reconstruction, kept so that the reconstruction takes its answer
/// instead of searching again: the medium's estimate searches to find where the scene's signal
/// begins, and `--medium-removal model` then reconstructs the same capture. It serves the request it
/// was run for with any removal: the plane where the signal focuses is the capture's.
#[derive(Clone, Debug, PartialEq)]
pub struct Searched {
    request: Request,
    found: Option<DepthFound>,
}

impl Searched {
    /// Searches `cap` as [`search_depth`] does for `req`, with nothing else known of its medium.
    pub fn new(cap: &Capture, req: &Request, progress: &dyn Progress) -> Result<Searched> {
        Ok(Searched {
            request: *req,
            found: find(cap, req, &MediumGiven::default(), progress)?,
        })
    }

    /// What the search found: `None` where no search applies.
    pub fn found(&self) -> Option<&DepthFound> {
        self.found.as_ref()
    }

    /// Whether the answer is `req`'s: the same request but for the removal (not off), and no density
    /// for the reconstruction to integrate, which would change what the search reconstructs.
    fn serves(&self, req: &Request, given: &MediumGiven) -> bool {
        let mut same = *req;
        same.medium.removal = self.request.medium.removal;
        same == self.request && req.medium.removal != MediumRemoval::Off && given.density.is_none()
    }
}

/// The depth search of [`search_depth`]: what it found, `None` where no search applies.
fn find(
    cap: &Capture,
    req: &Request,
    given: &MediumGiven,
    progress: &dyn Progress,
) -> Result<Option<DepthFound>> {
    let applies = req.volume == VolumeSpec::Default
        && req.medium.depth_search == DepthSearch::Auto
        && req.medium.removal != MediumRemoval::Off
        && !req.method.own_grid()
        && Signature::measure(cap).is_medium();
    if !applies {
        return Ok(None);
    }
    // The whole reach at no more than the search's planes, on the binned grid where the capture's is
    // finer; the depth range kept gets the capture's own lateral axes and the default volume's spacing.
    let full = default_volume(cap)?;
    let step_m = (full.z.end - full.z.start) / (full.z.n - 1) as f64;
    let binned = binned_for_search(cap);
    let searched = binned.as_ref().unwrap_or(cap);
    let reach = default_volume(searched)?;
    let coarse = Volume {
        z: Axis::new(
            reach.z.start,
            reach.z.end,
            reach.z.n.min(medium::search::SEARCH_PLANES),
        ),
        ..reach
    };
    let whole_req = Request {
        volume: VolumeSpec::Given(coarse),
        ..*req
    };
    let plan = ReconPlan::given(searched, &whole_req, given, progress)?;
    // The binned capture serves only this run: moved into it, not copied.
    let whole = plan.run(binned.unwrap_or_else(|| cap.clone()), progress)?;
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
    let Some(mut found) = medium::search::choose(&whole, &usable, step_m) else {
        return Ok(None);
    };
    found.volume = found.volume.map(|v| Volume {
        x: full.x,
        y: full.y,
        ..v
    });
    let line = found.describe(&whole.volume);
    Ok(Some((found, line)))
}

/// The most wall points a side the depth search reconstructs: at 64 it costs an eighth of a 128²
/// capture's plain reconstruction (docs/benchmarks.md), and the quick format's grid is searched whole.
pub const SEARCH_GRID: usize = 64;

/// `cap` with its scanned wall grid binned k × k, k the smallest that divides both sides and brings
/// them to [`SEARCH_GRID`] or fewer: each block's mean histogram at its points' mean. `None` where the
/// grid is that small already, where no such k leaves half of [`SEARCH_GRID`] or more, or where
/// binning does not apply (every laser point with every sensor point, or a side that is not a
/// regular grid).
pub(crate) fn binned_for_search(cap: &Capture) -> Option<Capture> {
    // The grid the histograms follow: both sides of a paired scan, the many-point side of a product
    // with one point on the other.
    let (bin_illum, bin_sensor) = match cap.pairing {
        Pairing::Paired => (true, true),
        Pairing::Product if cap.sensor.len() == 1 => (true, false),
        Pairing::Product if cap.illum.len() == 1 => (false, true),
        Pairing::Product => return None,
    };
    let grid = if bin_illum { &cap.illum } else { &cap.sensor };
    let g = grid.regular_grid()?;
    let (nx, ny) = (g.nx, g.ny);
    if nx.max(ny) <= SEARCH_GRID || (bin_illum && bin_sensor && cap.sensor.shape() != (nx, ny)) {
        return None;
    }
    let k =
        (2..=nx.max(ny)).find(|&k| nx % k == 0 && ny % k == 0 && nx.max(ny) / k <= SEARCH_GRID)?;
    // No coarser than half the search's grid: a grid of a prime side is searched as it is.
    if nx.max(ny) / k < SEARCH_GRID / 2 || nx.min(ny) / k < 2 {
        return None;
    }
    let (bx, by) = (nx / k, ny / k);
    // Histogram i is point i of the binned side(s), points ordered ix·ny + iy.
    let block = |bx_i: usize, by_i: usize| {
        (0..k).flat_map(move |dx| (0..k).map(move |dy| (bx_i * k + dx) * ny + by_i * k + dy))
    };
    let bin_points = |set: &PointSet| -> PointSet {
        let mut points = Vec::with_capacity(bx * by);
        let mut normals = Vec::with_capacity(bx * by);
        for i in 0..bx {
            for j in 0..by {
                let n = (k * k) as f64;
                points.push(block(i, j).map(|p| set.points[p]).sum::<DVec3>() / n);
                normals.push(
                    block(i, j)
                        .map(|p| set.normals[p])
                        .sum::<DVec3>()
                        .normalize_or_zero(),
                );
            }
        }
        PointSet {
            points,
            normals,
            layout: PointLayout::Grid { nx: bx, ny: by },
        }
    };
    let nt = cap.time.bins;
    let mut h = vec![0f32; bx * by * nt];
    let scale = 1.0 / (k * k) as f32;
    for (b, out) in h.chunks_exact_mut(nt).enumerate() {
        for p in block(b / by, b % by) {
            for (o, &v) in out.iter_mut().zip(cap.histogram(p)) {
                *o += scale * v;
            }
        }
    }
    let side = |set: &PointSet, binned: bool| if binned { bin_points(set) } else { set.clone() };
    Some(Capture {
        illum: side(&cap.illum, bin_illum),
        sensor: side(&cap.sensor, bin_sensor),
        h,
        scene_info: cap.scene_info.clone(),
        medium_density: cap.medium_density.clone(),
        ..*cap
    })
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
