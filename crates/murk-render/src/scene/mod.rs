//! Scene files (TOML). See `scenes/*.toml` for commented examples; every field is listed on
//! [`SceneFile`] and its parts. Errors name the file and the field and fit on one line.

use crate::geometry::Geometry;
use crate::medium::Medium;
use crate::overrides::{apply, canonical, Overrides, Spelling};
use murk_core::{short, DVec3, DensityCells, Error, Pairing, PointSet, Result, TimeAxis};
use std::path::{Path, PathBuf};

mod file;
mod resolve;

pub use file::{
    CaptureDef, CaptureKindDef, MediumDef, MediumKindDef, ObjectDef, RelayDef, RelayKind,
    RenderDef, SceneFile, TraceFrom,
};

/// The relay surface as the integrator sees it.
#[derive(Clone, Copy, Debug)]
pub struct Relay {
    pub kind: RelayKind,
    pub half: [f64; 2],
    pub albedo: f64,
}

/// What a render produces: the wall points, the pairing and the time axis.
#[derive(Clone, Debug)]
pub struct CaptureSpec {
    pub illum: PointSet,
    pub sensor: PointSet,
    pub pairing: Pairing,
    pub time: TimeAxis,
    pub account_first_and_last_bounces: bool,
    pub laser_xyz: Option<DVec3>,
    pub sensor_xyz: Option<DVec3>,
    pub device_radiometry: bool,
}

/// A validated scene, ready to render.
#[derive(Clone, Debug)]
pub struct Scene {
    pub relay: Relay,
    pub geometry: Geometry,
    pub medium: Option<Medium>,
    pub capture: CaptureSpec,
    pub settings: RenderDef,
    /// The scene file's text, or the resolved TOML where overrides apply; recorded in `scene_info`.
    pub source: String,
    /// The resolved scene as sorted `key = value` lines (this module's `canonical`), then a
    /// fingerprint of each mesh's triangles and of a density grid: what a checkpoint and a study's
    /// task key compare.
    pub resolved: String,
    /// The overrides as the user wrote them (`--set medium.g=0.7`, `--grid 32`).
    pub overrides: Vec<String>,
    /// One label per `[[object]]`, in order (ground truth's object ids index it).
    pub object_names: Vec<String>,
    /// The files the scene reads (meshes, a density grid): inputs that no output may replace.
    pub input_files: Vec<PathBuf>,
    pub file_name: String,
}

fn v3(a: [f64; 3]) -> DVec3 {
    DVec3::from_array(a)
}

impl Scene {
    /// Whether a medium scatters light in the scene (where tiles share tails and paths never roulette).
    pub fn scatters(&self) -> bool {
        self.medium.as_ref().is_some_and(Medium::scatters)
    }

    pub fn load(path: &Path, ov: &Overrides) -> Result<Scene> {
        let text = String::from_utf8(murk_core::read_input(path)?)
            .map_err(|_| Error::format(path, "the scene file is not UTF-8 text"))?;
        Scene::from_str(&text, path, ov)
    }

    /// Parses and validates `text`; `path` names the file in errors and anchors relative mesh paths.
    pub fn from_str(text: &str, path: &Path, ov: &Overrides) -> Result<Scene> {
        Scene::from_str_with_density(text, path, ov, None)
    }

    /// As [`Scene::from_str`], with a density grid's cells held in memory (`cells`, a capture's own)
    /// in place of the file that the scene's `density` names, which is then not read.
    pub fn from_str_with_density(
        text: &str,
        path: &Path,
        ov: &Overrides,
        cells: Option<&DensityCells>,
    ) -> Result<Scene> {
        // The file alone first, so that its own mistakes are reported with their line.
        let mut f: SceneFile = toml::from_str(text).map_err(|e| {
            let line = e
                .span()
                .map(|s| 1 + text[..s.start.min(text.len())].matches('\n').count());
            let msg = one_line(e.message());
            match line {
                Some(l) => Error::format(path, format!("line {l}: {msg}")),
                None => Error::format(path, msg),
            }
        })?;
        let mut table: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| Error::format(path, one_line(e.message())))?;
        // A bad override is the caller's argument, not the file's content: a parameter error (in
        // Python a ValueError naming it, not a FormatError about a good file).
        let bad_override = |m: String| Error::param(format!("{}: {m}", path.display()));
        let assignments = ov.assignments().map_err(bad_override)?;
        // One override at a time, so that a bad one is named.
        for (key, value, written) in &assignments {
            apply(&mut table, key, value.clone())
                .and_then(|()| {
                    table
                        .clone()
                        .try_into::<SceneFile>()
                        .map_err(|e| one_line(e.message()))
                })
                .map(|parsed| f = parsed)
                .map_err(|m| bad_override(format!("{written}: {m}")))?;
        }
        let source = if assignments.is_empty() {
            text.to_string()
        } else {
            toml::to_string(&table).map_err(|e| Error::format(path, e.to_string()))?
        };
        let bad = |field: &str, msg: String| match set_by(field, &assignments) {
            // A value an override set is named with how it was set, not only by the file it changed,
            // and, like any bad override, it is the caller's argument: a parameter error.
            Some(written) => bad_override(format!("{field} (from {written}): {msg}")),
            None => Error::format(path, format!("{field}: {msg}")),
        };
        let dir = path.parent().unwrap_or(Path::new("."));

        let relay = f.relay.resolve(&bad)?;
        let capture = f.capture.resolve(&relay, &bad)?;
        let s = &f.render;
        s.check(&bad)?;
        let medium = match &f.medium {
            None => None,
            Some(m) => m.resolve(dir, cells, &bad)?,
        };
        if let Some(p) = s
            .hidden_geometry_sampling
            .filter(|p| *p >= 1.0 && medium.as_ref().is_some_and(Medium::scatters))
        {
            return Err(bad(
                "render.hidden_geometry_sampling",
                format!(
                    "must be below 1 where the medium scatters (paths whose first vertex lies off the \
                     hidden geometry's directions would never be drawn), got {p}"
                ),
            ));
        }

        let objects = f
            .objects
            .iter()
            .enumerate()
            .map(|(i, o)| o.resolve(i, dir, path, &bad))
            .collect::<Result<Vec<_>>>()?;
        // A mesh's triangles come from a file the scene's text only names: its key carries them.
        let mut resolved = canonical(&table);
        for (i, (o, def)) in objects.iter().zip(&f.objects).enumerate() {
            if matches!(def, file::ObjectDef::Mesh { .. }) {
                resolved.push_str(&format!(
                    "\nobject[{i}].surfaces_fnv1a = {:016x}",
                    o.surface_fingerprint()
                ));
            }
        }
        // Likewise the densities of a grid.
        if let Some(crate::medium::Kind::Grid(g)) = medium.as_ref().map(|m| &m.kind) {
            resolved.push_str(&format!(
                "\nmedium.density_fnv1a = {:016x}",
                g.fingerprint()
            ));
        }
        // A forward medium's default lobe share is part of what its render computes: the key names
        // it, so that checkpoints made with another default are refused (scenes without one keep
        // their keys and bytes).
        let lobe = medium.as_ref().map_or(0.0, Medium::default_target_lobe);
        if f.render.target_lobe.is_none() && lobe > 0.0 {
            resolved.push_str(&format!("\nrender.target_lobe_default = {lobe}"));
        }
        // Likewise its default phase-angle distances.
        let (n, share) = medium
            .as_ref()
            .map_or((0, 0.0), Medium::default_phase_distances);
        if f.render.phase_distances.is_none() && n > 0 {
            resolved.push_str(&format!("\nrender.phase_distances_default = {n}"));
        }
        if f.render.target_phase_distances.is_none() && share > 0.0 {
            resolved.push_str(&format!(
                "\nrender.target_phase_distances_default = {share}"
            ));
        }
        let lobe = medium.as_ref().map_or(0.0, Medium::default_surface_lobe);
        if f.render.surface_lobe.is_none() && lobe > 0.0 {
            resolved.push_str(&format!("\nrender.surface_lobe_default = {lobe}"));
        }
        let spindle = medium.as_ref().map_or(0, Medium::default_spindle_draws);
        if f.render.spindle_draws.is_none() && spindle > 0 {
            resolved.push_str(&format!("\nrender.spindle_draws_default = {spindle}"));
        }
        let lobe = medium.as_ref().map_or(0.0, Medium::default_medium_lobe);
        if f.render.medium_lobe.is_none() && lobe > 0.0 {
            resolved.push_str(&format!("\nrender.medium_lobe_default = {lobe}"));
        }
        let geometry = Geometry::new(objects);
        if geometry.is_empty() && !medium.as_ref().is_some_and(Medium::scatters) {
            return Err(bad(
                "object",
                "the scene has no hidden object and no scattering medium, so every histogram would be zero"
                    .into(),
            ));
        }

        let scene = Scene {
            relay,
            geometry,
            medium,
            capture,
            settings: f.render.clone(),
            source,
            resolved,
            // Recorded in the command line's words whoever gave them, so that a render from Python and
            // the same render from the CLI write the same bytes; errors quote the user's own words.
            overrides: Overrides {
                spelling: Spelling::Cli,
                ..ov.clone()
            }
            .assignments()
            .map_err(bad_override)?
            .into_iter()
            .map(|(_, _, w)| w)
            .collect(),
            input_files: f
                .objects
                .iter()
                .filter_map(|o| match o {
                    file::ObjectDef::Mesh { file, .. } => Some(dir.join(file)),
                    _ => None,
                })
                .chain(
                    f.medium
                        .as_ref()
                        .and_then(|m| m.density.as_ref())
                        .filter(|_| cells.is_none())
                        .map(|d| dir.join(d)),
                )
                .collect(),
            object_names: f
                .objects
                .iter()
                .enumerate()
                .map(|(i, o)| o.label(i))
                .collect(),
            file_name: path
                .file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned()),
        };
        scene
            .check_time_window()
            .map_err(|m| bad("capture.bins/bin_width/start", m))?;
        Ok(scene)
    }

    /// Rejects a time window that cannot hold any return from the hidden geometry.
    fn check_time_window(&self) -> std::result::Result<(), String> {
        if self.geometry.is_empty() {
            return Ok(());
        }
        let b = self.geometry.bounds();
        let c = &self.capture;
        let range = |ps: &PointSet, dev: Option<DVec3>| {
            ps.points
                .iter()
                .fold((f64::INFINITY, 0.0f64), |(lo, hi), p| {
                    let (n, f) = b.distance_range(*p);
                    let leg = match (c.account_first_and_last_bounces, dev) {
                        (true, Some(d)) => (*p - d).length(),
                        _ => 0.0,
                    };
                    (lo.min(n + leg), hi.max(f + leg))
                })
        };
        let (il, ih) = range(&c.illum, c.laser_xyz);
        let (sl, sh) = range(&c.sensor, c.sensor_xyz);
        // Geometric bounds; a medium's index stretches paths, so scale the upper end by it.
        let ior = self.medium.as_ref().map_or(1.0, |m| m.ior);
        let (earliest, latest) = (il + sl, (ih + sh) * ior);
        let t = &c.time;
        if earliest >= t.end_m() {
            return Err(format!(
                "the window [{:.3}, {:.3}] m ends before the earliest return from the hidden geometry ({earliest:.3} m)",
                t.start_m,
                t.end_m()
            ));
        }
        if latest < t.start_m {
            return Err(format!(
                "the window [{:.3}, {:.3}] m starts after the latest direct return from the hidden geometry ({latest:.3} m)",
                t.start_m,
                t.end_m()
            ));
        }
        Ok(())
    }
}

/// Makes the one-line error that names a scene field.
type Bad<'a> = &'a dyn Fn(&str, String) -> Error;

/// The override that set `field` as validation names it (`capture.grid`, `object[0].albedo`, or
/// keys checked together: `capture.bins/bin_width/start`, `capture.grid (center ± extent/2)`), the
/// last one where several did, since the last one applied is the value validated.
fn set_by<'a>(field: &str, assignments: &'a [(String, toml::Value, String)]) -> Option<&'a str> {
    let field = field.split(" (").next().unwrap_or(field);
    let mut names = field.split('/');
    let first = names.next().unwrap_or(field);
    let table = first.rsplit_once('.').map_or("", |(t, _)| t);
    let keys: Vec<String> = std::iter::once(first.to_string())
        .chain(names.map(|n| match n.contains('.') || table.is_empty() {
            true => n.to_string(),
            false => format!("{table}.{n}"),
        }))
        .collect();
    let covers = |key: &str, k: &String| {
        k == key
            || k.strip_prefix(key)
                .is_some_and(|r| r.starts_with(['.', '[']))
    };
    assignments
        .iter()
        .rev()
        .find(|(key, ..)| keys.iter().any(|k| covers(key, k)))
        .map(|(_, _, written)| written.as_str())
}

fn one_line(msg: &str) -> String {
    msg.trim().replace('\n', " ")
}

fn check_albedo(a: f64, field: &str, bad: Bad) -> Result<()> {
    if (0.0..=1.0).contains(&a) {
        Ok(())
    } else {
        Err(bad(field, format!("must be in [0, 1], got {}", short(a))))
    }
}
