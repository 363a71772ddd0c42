//! A whole synthetic capture from one description: the layout, the targets as text specs
//! (`point:X,Y,Z`, `z:DEPTH`, `t:DEPTH`, `polygon:DEPTH:x,y;x,y;…`) and the options; what `murk synth`
//! and library users call.

use crate::{add_first_bounce, CaptureLayout, SynthOptions, Target};
use murk_core::{Capture, Error, Result};

/// Everything a synthetic capture needs.
#[derive(Clone, Debug)]
pub struct Synthesis {
    pub layout: CaptureLayout,
    /// Target specs (see [`Target::parse`]).
    pub targets: Vec<String>,
    pub options: SynthOptions,
}

impl Target {
    /// Parses a target spec; polygons are rasterised at `spacing_m`.
    pub fn parse(spec: &str, spacing_m: f64) -> Result<Target> {
        let bad = |msg: String| Error::param(format!("target '{spec}': {msg}"));
        let (kind, rest) = spec
            .split_once(':')
            .ok_or_else(|| bad("expected KIND:PARAMETERS".into()))?;
        let depth = |s: &str| -> Result<f64> {
            let d: f64 = s
                .trim()
                .parse()
                .map_err(|_| bad(format!("'{s}' is not a depth in metres")))?;
            if !(d > 0.0 && d.is_finite()) {
                return Err(bad("depth must be > 0 m".into()));
            }
            Ok(d)
        };
        let polygon = |outline, d| Target::Polygon {
            outline,
            offset: [0.0; 2],
            depth_m: d,
            albedo: 1.0,
            spacing_m,
        };
        Ok(match kind {
            "point" => {
                let [x, y, z] = floats::<3>(rest).map_err(bad)?;
                Target::Point {
                    pos: murk_core::DVec3::new(x, y, z),
                    albedo: 1.0,
                }
            }
            "z" => polygon(crate::z_letter_outline(), depth(rest)?),
            "t" => polygon(crate::t_letter_outline(), depth(rest)?),
            "polygon" => {
                let (d, pts) = rest
                    .split_once(':')
                    .ok_or_else(|| bad("expected polygon:DEPTH:x,y;x,y;...".into()))?;
                let outline = pts
                    .split(';')
                    .map(floats::<2>)
                    .collect::<std::result::Result<Vec<_>, _>>()
                    .map_err(bad)?;
                polygon(outline, depth(d)?)
            }
            _ => {
                return Err(bad(format!(
                    "unknown kind '{kind}' (point, z, t or polygon)"
                )))
            }
        })
    }
}

/// `N` comma-separated finite numbers.
pub fn floats<const N: usize>(s: &str) -> std::result::Result<[f64; N], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|e| format!("'{s}': {e}"))?;
    let arr: [f64; N] = v
        .try_into()
        .map_err(|_| format!("'{s}': expected {N} comma-separated numbers"))?;
    if arr.iter().any(|x| !x.is_finite()) {
        return Err(format!("'{s}': numbers must be finite"));
    }
    Ok(arr)
}

/// The capture `s` describes, with a `scene_info` that records it.
pub fn synthesize(s: &Synthesis) -> Result<Capture> {
    let l = &s.layout;
    let mut cap = l.empty_capture()?;
    // Half the wall spacing keeps the raster below the reconstruction's resolution.
    let spacing = l.wall_size_m / l.grid as f64 / 2.0;
    let mut scatterers = Vec::new();
    for t in &s.targets {
        scatterers.extend(Target::parse(t, spacing)?.scatterers()?);
    }
    add_first_bounce(&mut cap, &scatterers, &s.options)?;
    if cap.h.iter().all(|&v| v == 0.0) {
        // Without the medium's attenuation, is there signal? Then e^{−μt·path} underflowed.
        let mut clear = l.empty_capture()?;
        let no_medium = SynthOptions {
            mu_t_per_m: 0.0,
            ..s.options
        };
        add_first_bounce(&mut clear, &scatterers, &no_medium)?;
        if s.options.mu_t_per_m > 0.0 && clear.h.iter().any(|&v| v != 0.0) {
            return Err(Error::param(format!(
                "the medium's attenuation e^(−μt·path) with μt = {} /m leaves every return below what 32-bit floats hold; use a smaller μt",
                murk_core::short(s.options.mu_t_per_m)
            )));
        }
        return Err(Error::param(format!(
            "the time window ({:.3}..{:.3} m of path) contains none of the scene's paths; adjust its start, bins or bin width",
            cap.time.start_m,
            cap.time.end_m()
        )));
    }
    let o = &s.options;
    cap.scene_info = format!(
        "generator: murk synth\nmurk_version: {}\nkind: {}\ntargets: [{}]\nwall_size_m: {}\ngrid: {}\nmu_t_per_m: {}\njitter_sigma_m: {}\ncosines: {}\n",
        env!("CARGO_PKG_VERSION"),
        l.kind,
        s.targets.iter().map(|t| format!("'{t}'")).collect::<Vec<_>>().join(", "),
        l.wall_size_m,
        l.grid,
        o.mu_t_per_m,
        o.jitter_sigma_m,
        o.cosines
    );
    Ok(cap)
}
