//! The capture's own scene with every object removed but the medium's room: what the renderer draws
//! as the medium's response alone.

use murk_core::{Capture, DVec3, DensityCells, Error, Result};
use murk_render::{density_fingerprint, Aabb, MAX_HEIGHT_SCALE_M, MIN_HEIGHT_SCALE_M};
use std::sync::Arc;

/// The resolved scene TOML that `murk render` stored in the capture's `scene_info`, without its
/// `[[object]]` tables but those that enclose the medium (`encloses`: a room's walls, which return
/// the medium's light as the medium itself does). The medium's values in it are replaced by the
/// table's; the geometry (relay, capture layout, time axis, the medium's extent and enclosure) and
/// the medium's shape where murk knows it ([`Modelled`]) are kept. A medium of unknown shape (a
/// grid without its cells) is dropped to a homogeneous one, fitted by one μt, α and g over its box.
pub fn medium_only(cap: &Capture) -> Result<String> {
    let mut table = stored_table(cap)?;
    // Without a box the medium has no walls to find (the fit then fails on the box, not here).
    let stored = medium_of(&table).ok();
    let region = stored.as_ref().map(|m| m.region);
    let enclosure: Vec<toml::Value> = match (table.remove("object"), region) {
        (Some(toml::Value::Array(objects)), Some(region)) => objects
            .into_iter()
            .filter(|o| encloses(o, &region))
            .collect(),
        _ => Vec::new(),
    };
    if !enclosure.is_empty() {
        table.insert("object".into(), toml::Value::Array(enclosure));
    }
    let medium = medium_table(&mut table)?;
    // The medium's own values are the table's to set; placeholders keep captures of one geometry
    // with different media on one table (and keep the truth out of the estimate).
    medium.insert("mu_t".into(), toml::Value::Float(1.0));
    medium.insert("albedo".into(), toml::Value::Float(0.5));
    medium.insert("g".into(), toml::Value::Float(0.0));
    match stored.and_then(|m| m.shape.modelled(cap)) {
        // The stored kind and height_scale stay as they are.
        Some(Modelled::Height { .. }) => {}
        // The table renders the capture's own cells ([`crate::table`]); the name carries their hash,
        // so that a table is kept for one grid only.
        Some(Modelled::Grid { cells }) => {
            let name = format!(
                "the capture's own cells, fnv1a {:016x}",
                density_fingerprint(&cells)
            );
            medium.insert("density".into(), toml::Value::String(name));
        }
        None => {
            for key in ["kind", "density", "height_scale"] {
                medium.remove(key);
            }
        }
    }
    toml::to_string(&table).map_err(|e| Error::param(format!("scene_info.scene: {e}")))
}

/// Whether a stored `[[object]]` is a box around the medium's whole box (to 1 cm): the room the medium
/// fills. Its walls light the medium and return its light from every histogram's first bins on, so a
/// model without them fits another medium. It is the medium's container, not the hidden scene the
/// reconstruction looks for.
fn encloses(object: &toml::Value, region: &Aabb) -> bool {
    const SLACK_M: f64 = 0.01;
    let corner = |key: &str| -> Option<DVec3> {
        let v: Vec<f64> = object
            .get(key)?
            .as_array()?
            .iter()
            .map(|v| v.as_float().or(v.as_integer().map(|i| i as f64)))
            .collect::<Option<_>>()?;
        (v.len() == 3).then(|| DVec3::new(v[0], v[1], v[2]))
    };
    let is_box = object.get("shape").and_then(|s| s.as_str()) == Some("box");
    match (is_box, corner("min"), corner("max")) {
        (true, Some(min), Some(max)) => {
            (0..3).all(|a| min[a] <= region.min[a] + SLACK_M && max[a] >= region.max[a] - SLACK_M)
        }
        _ => false,
    }
}

/// The scene TOML that `murk render` stored in the capture's `scene_info`, parsed.
pub(crate) fn stored_table(cap: &Capture) -> Result<toml::Table> {
    let text = stored_scene(&cap.scene_info).ok_or_else(|| {
        Error::param(
            "the capture carries no scene description (scene_info.scene, which murk render writes): the medium's forward model needs the relay, the capture layout and the medium's extent; captures from other sources are not supported yet",
        )
    })?;
    text.parse()
        .map_err(|e: toml::de::Error| Error::param(format!("scene_info.scene: {}", e.message())))
}

/// The medium of the scene that `murk render` stored in a capture: its box, and how its density
/// varies over it (the scene's `kind` with its own field).
#[derive(Clone, Debug, PartialEq)]
pub struct StoredMedium {
    pub region: Aabb,
    pub shape: StoredShape,
}

#[derive(Clone, Debug, PartialEq)]
pub enum StoredShape {
    Homogeneous,
    /// `kind = "grid"`: the file as the scene names it (relative to the scene file, which the capture
    /// does not hold, nor the cells).
    Grid {
        file: String,
    },
    /// `kind = "height"`: density exp(−(y − min.y)/`scale_m`).
    Height {
        scale_m: f64,
    },
}

impl StoredShape {
    /// The shape the forward model keeps: a height fog, or a grid whose cells `cap` holds; `None`
    /// for a homogeneous medium or a grid without its cells.
    pub fn modelled(&self, cap: &Capture) -> Option<Modelled> {
        match self {
            StoredShape::Homogeneous => None,
            StoredShape::Height { scale_m } => Some(Modelled::Height { scale_m: *scale_m }),
            StoredShape::Grid { .. } => cap
                .medium_density
                .clone()
                .map(|cells| Modelled::Grid { cells }),
        }
    }

    /// What it is, for a warning that a step assumes a homogeneous medium instead.
    pub fn describe(&self) -> Option<String> {
        match self {
            StoredShape::Homogeneous => None,
            StoredShape::Grid { file } => Some(format!("a density grid (density = {file:?})")),
            StoredShape::Height { scale_m } => Some(format!(
                "an exponential height fog (height_scale = {} m)",
                murk_core::short(*scale_m)
            )),
        }
    }
}

/// The stored scene's medium; errors name what it lacks (no scene, no `[medium]`, no box).
pub fn stored_medium(cap: &Capture) -> Result<StoredMedium> {
    medium_of(&stored_table(cap)?)
}

/// The medium of a parsed stored scene (see [`stored_medium`]).
fn medium_of(table: &toml::Table) -> Result<StoredMedium> {
    let Some(toml::Value::Table(medium)) = table.get("medium") else {
        return Err(no_medium_table());
    };
    let number = |v: &toml::Value| v.as_float().or(v.as_integer().map(|i| i as f64));
    let corner = |key: &str| -> Result<DVec3> {
        let v: Option<Vec<f64>> = medium
            .get(key)
            .and_then(|v| v.as_array()?.iter().map(number).collect());
        match v.as_deref() {
            Some(&[x, y, z]) => Ok(DVec3::new(x, y, z)),
            _ => Err(Error::param(format!(
                "scene_info.scene's [medium] has no {key} = [x, y, z]: the medium's box is unknown"
            ))),
        }
    };
    let region = Aabb {
        min: corner("min")?,
        max: corner("max")?,
    };
    if !(0..3).all(|a| region.min[a] < region.max[a]) {
        return Err(Error::param(format!(
            "scene_info.scene's [medium] box {}..{} is empty",
            region.min, region.max
        )));
    }
    let field = |key: &str| medium.get(key);
    let shape = match field("kind").map(|k| k.as_str()) {
        None | Some(Some("homogeneous")) => StoredShape::Homogeneous,
        Some(Some("grid")) => StoredShape::Grid {
            file: field("density")
                .and_then(|f| f.as_str())
                .unwrap_or_default()
                .to_string(),
        },
        Some(Some("height")) => {
            let scale_m = field("height_scale").and_then(number);
            StoredShape::Height {
                scale_m: check_height_scale(scale_m, "scene_info.scene's [medium] height_scale")?,
            }
        }
        Some(k) => {
            return Err(Error::param(format!(
                "scene_info.scene's [medium] kind {k:?} is not homogeneous, grid or height"
            )))
        }
    };
    Ok(StoredMedium { region, shape })
}

/// A heterogeneous medium whose shape the forward model keeps: the fitted μt is then σt where the
/// density is 1, the scene file's own `mu_t`.
#[derive(Clone, Debug, PartialEq)]
pub enum Modelled {
    /// The stored scene's exponential height fog: μt is σt on the box's floor.
    Height { scale_m: f64 },
    /// The stored scene's density grid, with the cells that the capture holds.
    Grid { cells: Arc<DensityCells> },
}

impl Modelled {
    /// What the estimate and the model removal say of it.
    pub fn describe(&self) -> String {
        let shape = match self {
            Modelled::Height { scale_m } => format!(
                "the capture's height fog, height_scale {} m",
                murk_core::short(*scale_m)
            ),
            Modelled::Grid { cells } => {
                let [nx, ny, nz] = cells.dims();
                format!("the capture's density grid, {nx} × {ny} × {nz} cells")
            }
        };
        format!("μt is σt where the density is 1 ({shape})")
    }
}

/// The stored scene's heterogeneous medium where the forward model keeps its shape: a height fog,
/// or a density grid whose cells the capture holds; `None` for a homogeneous medium, none stored,
/// or a grid without its cells.
pub fn modelled(cap: &Capture) -> Option<Modelled> {
    stored_medium(cap).ok()?.shape.modelled(cap)
}

/// The warning that `step` fits one homogeneous medium where the capture's stored scene has a
/// heterogeneous one whose shape is unknown (a grid without its cells); `None` otherwise.
pub fn homogeneous_assumed(cap: &Capture, step: &str) -> Option<String> {
    let shape = stored_medium(cap).ok()?.shape;
    if shape.modelled(cap).is_some() {
        return None;
    }
    let what = shape.describe()?;
    Some(format!(
        "the capture's medium is {what} whose cells the capture does not hold (rendered before murk stored them): {step} assumes one homogeneous medium (one μt, albedo and g) over its box"
    ))
}

/// A height fog's scale (m) within the renderer's range (`what` names where it came from).
pub(crate) fn check_height_scale(scale_m: Option<f64>, what: &str) -> Result<f64> {
    match scale_m {
        Some(h) if (MIN_HEIGHT_SCALE_M..=MAX_HEIGHT_SCALE_M).contains(&h) => Ok(h),
        h => Err(Error::param(format!(
            "{what} must be in [{MIN_HEIGHT_SCALE_M}, {MAX_HEIGHT_SCALE_M:e}] m, got {}",
            h.map_or("none".into(), murk_core::short)
        ))),
    }
}

/// The `[medium]` table of a stored scene.
pub(crate) fn medium_table(table: &mut toml::Table) -> Result<&mut toml::Table> {
    match table.get_mut("medium") {
        Some(toml::Value::Table(medium)) => Ok(medium),
        _ => Err(no_medium_table()),
    }
}

fn no_medium_table() -> Error {
    Error::param("scene_info.scene has no [medium] table: the extent of the medium is unknown")
}

/// The block under `scene: |` in `scene_info` (YAML literal block, indented by two spaces).
fn stored_scene(scene_info: &str) -> Option<String> {
    let mut lines = scene_info
        .lines()
        .skip_while(|l| l.trim_end() != "scene: |");
    lines.next()?;
    let body: Vec<&str> = lines
        .take_while(|l| l.is_empty() || l.starts_with("  "))
        .map(|l| l.strip_prefix("  ").unwrap_or(""))
        .collect();
    (!body.is_empty()).then(|| body.join("\n"))
}

/// A small confocal capture whose `scene_info` is `info`, for the tests of the stored scene.
#[cfg(test)]
pub(crate) fn capture_with_info(info: &str) -> Capture {
    Capture {
        scene_info: info.to_string(),
        ..murk_core::Capture::confocal(
            murk_core::PointSet::wall_grid(murk_core::DVec3::ZERO, 1.0, 1.0, 2, 2),
            murk_core::TimeAxis {
                start_m: 0.0,
                bin_width_m: 0.01,
                bins: 4,
            },
            vec![0.0; 16],
            String::new(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stored_scene_is_read_and_its_objects_dropped() {
        let info = "generator: murk render\nscene: |\n  [medium]\n  mu_t = 1.0\n  kind = \"grid\"\n  density = \"plume.npy\"\n  \n  [[object]]\n  shape = \"quad\"\n  [relay]\n  kind = \"wall\"\nalbedo: 0.5\n";
        let text = stored_scene(info).unwrap();
        assert!(text.starts_with("[medium]\nmu_t = 1.0\nkind = \"grid\"\n"));
        assert!(!text.contains("albedo: 0.5"));
        let cap = capture_with_info(info);
        let only = medium_only(&cap).unwrap();
        assert!(only.contains("[medium]") && only.contains("[relay]") && !only.contains("object"));
        // A grid whose cells the capture does not hold is modelled homogeneous: the grid is gone.
        assert!(
            !only.contains("grid") && !only.contains("density"),
            "{only}"
        );
        let none = Capture {
            scene_info: "generator: murk synth\n".into(),
            ..cap
        };
        assert!(medium_only(&none)
            .unwrap_err()
            .to_string()
            .contains("no scene description"));
    }

    /// A box around the whole medium (a room, its front omitted) stays in the medium-only scene; a
    /// box inside it, a box that leaves out part of the medium by more than 1 cm and other shapes go.
    #[test]
    fn the_room_around_the_medium_stays() {
        let info = "generator: murk render\nscene: |\n  [medium]\n  mu_t = 1.5\n  min = [-1.0, -1.0, 0.001]\n  max = [1.0, 1.0, 2.6]\n  [[object]]\n  name = \"room\"\n  shape = \"box\"\n  min = [-1.0, -1.0, 0.0]\n  max = [1.0, 1.0, 2.6]\n  omit = [\"-z\"]\n  albedo = 0.4\n  [[object]]\n  name = \"shelf\"\n  shape = \"box\"\n  min = [-0.85, -0.9, 1.8]\n  max = [0.85, 0.7, 2.2]\n  [[object]]\n  name = \"short room\"\n  shape = \"box\"\n  min = [-1.0, -1.0, 0.0]\n  max = [1.0, 1.0, 2.58]\n  [[object]]\n  name = \"letter\"\n  shape = \"z-letter\"\n  center = [0.0, 0.0, 2.0]\n";
        let only = medium_only(&capture_with_info(info)).unwrap();
        let kept: toml::Table = only.parse().unwrap();
        let names: Vec<&str> = kept["object"]
            .as_array()
            .unwrap()
            .iter()
            .map(|o| o["name"].as_str().unwrap())
            .collect();
        assert_eq!(names, ["room"], "{only}");
        assert!(only.contains("mu_t = 1.0"), "{only}");
        // No room: no objects at all.
        let clear = info
            .split("  [[object]]\n  name = \"shelf\"")
            .next()
            .unwrap();
        let without = clear.replace(
            "name = \"room\"\n  shape = \"box\"",
            "name = \"room\"\n  shape = \"quad\"",
        );
        let only = medium_only(&capture_with_info(&without)).unwrap();
        assert!(!only.contains("object"), "{only}");
    }

    /// The medium-only scene keeps a height fog and a grid whose cells the capture holds, and says
    /// what μt then means; a step that fits one homogeneous medium says so only for a grid without
    /// its cells, naming it, and says nothing on a homogeneous capture or one without a stored scene.
    #[test]
    fn a_known_shape_is_kept_and_an_unknown_one_named() {
        let info = |medium: &str| {
            format!("generator: murk render\nscene: |\n  [medium]\n{medium}  mu_t = 1.0\n  min = [-1, -1, 0]\n  max = [1, 1, 2]\n")
        };
        let height = capture_with_info(&info("  kind = \"height\"\n  height_scale = 0.5\n"));
        assert_eq!(homogeneous_assumed(&height, "the estimate"), None);
        let only = medium_only(&height).unwrap();
        assert!(
            only.contains("kind = \"height\"") && only.contains("height_scale = 0.5"),
            "{only}"
        );
        assert_eq!(
            modelled(&height).unwrap().describe(),
            "μt is σt where the density is 1 (the capture's height fog, height_scale 0.5 m)"
        );
        let grid = capture_with_info(&info("  kind = \"grid\"\n  density = \"p.npy\"\n"));
        let w = homogeneous_assumed(&grid, "x").unwrap();
        assert!(
            w.contains(
                "a density grid (density = \"p.npy\") whose cells the capture does not hold"
            ),
            "{w}"
        );
        let cells = DensityCells::new(&[1, 2, 1], vec![0.5, 2.0]).unwrap();
        let own = Capture {
            medium_density: Some(Arc::new(cells.clone())),
            ..grid
        };
        assert_eq!(homogeneous_assumed(&own, "x"), None);
        let only = medium_only(&own).unwrap();
        let name = format!(
            "density = \"the capture's own cells, fnv1a {:016x}\"",
            density_fingerprint(&cells)
        );
        assert!(
            only.contains("kind = \"grid\"") && only.contains(&name),
            "{only}"
        );
        assert!(modelled(&own)
            .unwrap()
            .describe()
            .contains("density grid, 1 × 2 × 1 cells"));
        assert_eq!(
            homogeneous_assumed(&capture_with_info(&info("")), "x"),
            None
        );
        assert_eq!(
            homogeneous_assumed(&capture_with_info("generator: murk synth\n"), "x"),
            None
        );
        // A stored height fog's scale out of range is named, not used.
        let bad = capture_with_info(&info("  kind = \"height\"\n  height_scale = 0.0\n"));
        let e = stored_medium(&bad).unwrap_err().to_string();
        assert!(
            e.contains("height_scale must be in [0.001, 1e6] m, got 0"),
            "{e}"
        );
    }
}
