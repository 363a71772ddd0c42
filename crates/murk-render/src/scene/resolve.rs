//! From a parsed scene file to what the renderer uses: each part checks its own fields (the errors
//! name them) and settles its defaults here, once.

use super::file::{
    CaptureDef, CaptureKindDef, MediumDef, MediumKindDef, ObjectDef, RelayDef, RelayKind, RenderDef,
};
use super::{check_albedo, v3, Bad, CaptureSpec, Relay};
use crate::geometry::{triangulate, Aabb, Object, Shape};
use crate::medium::{
    Grid, Height, Homogeneous, Kind, Medium, Phase, MAX_HEIGHT_SCALE_M, MIN_HEIGHT_SCALE_M,
};
use murk_core::{short, DVec3, DensityCells, Error, Pairing, PointSet, Result, TimeAxis};
use std::path::Path;

impl RelayDef {
    pub(super) fn resolve(&self, bad: Bad) -> Result<Relay> {
        let r = self;
        let limits = murk_core::Limits::get();
        if !r.size_m.iter().all(|s| s.is_finite() && *s > 0.0) {
            return Err(bad(
                "relay.size",
                format!("must be two positive lengths in metres, got {:?}", r.size_m),
            ));
        }
        for s in r.size_m {
            limits
                .length("a side", s)
                .map_err(|e| bad("relay.size", e.to_string()))?;
        }
        let relay_albedo = r.albedo.unwrap_or(match r.kind {
            RelayKind::Wall => 1.0,
            RelayKind::Diffuser => 0.0,
        });
        check_albedo(relay_albedo, "relay.albedo", bad)?;
        let relay = Relay {
            kind: r.kind,
            half: [r.size_m[0] / 2.0, r.size_m[1] / 2.0],
            albedo: relay_albedo,
        };
        Ok(relay)
    }
}

impl CaptureDef {
    pub(super) fn resolve(&self, relay: &Relay, bad: Bad) -> Result<CaptureSpec> {
        let c = self;
        let limits = murk_core::Limits::get();
        let size = [2.0 * relay.half[0], 2.0 * relay.half[1]];
        let on_relay = |p: [f64; 2], field: &str| -> Result<()> {
            let tol = 1e-9;
            if !(p[0].abs() <= relay.half[0] + tol && p[1].abs() <= relay.half[1] + tol) {
                return Err(bad(
                    field,
                    format!(
                        "({}, {}) lies outside the {} m × {} m relay surface",
                        p[0], p[1], size[0], size[1]
                    ),
                ));
            }
            Ok(())
        };
        if c.grid[0] == 0 || c.grid[1] == 0 {
            return Err(bad(
                "capture.grid",
                format!("needs at least one point per axis, got {:?}", c.grid),
            ));
        }
        // The replay of shared tails converts bin indices to u32 (integrator/share.rs).
        if c.bins > u32::MAX as usize {
            return Err(bad(
                "capture.bins",
                format!("must be at most {}, got {}", u32::MAX, c.bins),
            ));
        }
        // H (f32 per bin) is the largest buffer a render allocates, and writing it makes a transposed
        // copy; checked before the grid's points.
        let points = c.grid[0].saturating_mul(c.grid[1]);
        let hists = match c.kind {
            CaptureKindDef::Exhaustive => points.saturating_mul(points),
            _ => points,
        };
        limits
            .capture_h(hists, c.bins)
            .map_err(|e| bad("capture.grid/capture.bins", e.to_string()))?;
        let extent = c.extent_m.unwrap_or(size);
        if !extent.iter().all(|e| e.is_finite() && *e > 0.0) {
            return Err(bad(
                "capture.extent",
                format!("must be two positive lengths, got {extent:?}"),
            ));
        }
        for (sx, sy) in [(-1.0, -1.0), (1.0, 1.0)] {
            on_relay(
                [
                    c.center_m[0] + sx * extent[0] / 2.0,
                    c.center_m[1] + sy * extent[1] / 2.0,
                ],
                "capture.grid (center ± extent/2)",
            )?;
        }
        let grid = PointSet::wall_grid(
            DVec3::new(c.center_m[0], c.center_m[1], 0.0),
            extent[0],
            extent[1],
            c.grid[0],
            c.grid[1],
        );
        let point = |p: Option<[f64; 2]>, field: &str| -> Result<PointSet> {
            let p = p.unwrap_or([0.0, 0.0]);
            on_relay(p, field)?;
            Ok(PointSet::single(DVec3::new(p[0], p[1], 0.0)))
        };
        let (illum, sensor, pairing) = match c.kind {
            CaptureKindDef::Confocal => (grid.clone(), grid, Pairing::Paired),
            CaptureKindDef::LaserGrid => (
                grid,
                point(c.spad_point_m, "capture.spad_point")?,
                Pairing::Product,
            ),
            CaptureKindDef::Single => (
                point(c.laser_point_m, "capture.laser_point")?,
                grid,
                Pairing::Product,
            ),
            CaptureKindDef::Exhaustive => (grid.clone(), grid, Pairing::Product),
        };
        if c.bins == 0 {
            return Err(bad("capture.bins", "must be at least 1".into()));
        }
        if !(c.bin_width_m.is_finite() && c.bin_width_m > 0.0) {
            return Err(bad(
                "capture.bin_width",
                format!(
                    "must be a positive path length in metres, got {}",
                    short(c.bin_width_m)
                ),
            ));
        }
        if !c.start_m.is_finite() {
            return Err(bad(
                "capture.start",
                format!("must be finite, got {}", c.start_m),
            ));
        }
        let time = TimeAxis {
            start_m: c.start_m,
            bin_width_m: c.bin_width_m,
            bins: c.bins,
        };
        limits
            .length("the start", time.start_m)
            .and_then(|_| limits.length("the window's end", time.end_m()))
            .map_err(|e| bad("capture.start/bins/bin_width", e.to_string()))?;
        if time.bin_width_m < limits.min_bin_width_m {
            return Err(bad(
                "capture.bin_width",
                format!(
                    "{} m is below the {} m murk accepts",
                    murk_core::short(time.bin_width_m),
                    murk_core::short(limits.min_bin_width_m)
                ),
            ));
        }
        let device = |p: Option<[f64; 3]>, field: &str| -> Result<Option<DVec3>> {
            match p {
                None if c.account_first_and_last_bounces => Err(bad(
                    field,
                    "is required when account_first_and_last_bounces = true".into(),
                )),
                Some(p) if !p.iter().all(|v| v.is_finite()) => {
                    Err(bad(field, format!("must be finite, got {p:?}")))
                }
                p => Ok(p.map(v3)),
            }
        };
        let capture = CaptureSpec {
            illum,
            sensor,
            pairing,
            time,
            account_first_and_last_bounces: c.account_first_and_last_bounces,
            laser_xyz: device(c.laser_position_m, "capture.laser_position")?,
            sensor_xyz: device(c.spad_position_m, "capture.spad_position")?,
            device_radiometry: c.device_radiometry,
        };
        if c.device_radiometry && (c.laser_position_m.is_none() || c.spad_position_m.is_none()) {
            return Err(bad(
                "capture.device_radiometry",
                "needs capture.laser_position and capture.spad_position".into(),
            ));
        }
        Ok(capture)
    }
}

impl RenderDef {
    pub(super) fn check(&self, bad: Bad) -> Result<()> {
        let s = self;
        // Checked here too (the render checks --spp) so that the file and key are named.
        if !(1..=murk_core::Limits::MAX_SPP).contains(&s.spp) {
            return Err(bad(
                "render.spp",
                format!(
                    "must be between 1 and {}, got {}",
                    murk_core::Limits::MAX_SPP,
                    s.spp
                ),
            ));
        }
        if s.max_depth == 0 {
            return Err(bad(
                "render.max_depth",
                "must be at least 1 (one hidden vertex)".into(),
            ));
        }
        if !(s.time_jitter_m.is_finite() && s.time_jitter_m >= 0.0) {
            return Err(bad(
                "render.time_jitter",
                format!("must be ≥ 0, got {}", short(s.time_jitter_m)),
            ));
        }
        if let Some(p) = s
            .hidden_geometry_sampling
            .filter(|p| !(0.0..=1.0).contains(p))
        {
            return Err(bad(
                "render.hidden_geometry_sampling",
                format!("must be in [0, 1], got {p}"),
            ));
        }
        // Per-segment draw counts: capped so a typo cannot stall a render.
        for (field, n) in [
            ("render.time_samples", s.time_samples),
            (
                "render.first_time_samples",
                s.first_time_samples.unwrap_or(0),
            ),
            ("render.target_split", s.target_split),
            ("render.object_draws", s.object_draws),
            ("render.phase_distances", s.phase_distances.unwrap_or(0)),
            ("render.spindle_draws", s.spindle_draws.unwrap_or(0)),
        ] {
            if n > 4096 {
                return Err(bad(field, format!("must be at most 4096, got {n}")));
            }
        }
        if s.share_tile > 16 {
            return Err(bad(
                "render.share_tile",
                format!("must be at most 16, got {}", s.share_tile),
            ));
        }
        if !(s.target_split_radius_m.is_finite() && s.target_split_radius_m >= 0.0) {
            return Err(bad(
                "render.target_split_radius",
                format!("must be ≥ 0 m, got {}", short(s.target_split_radius_m)),
            ));
        }
        if let Some(p) = s.target_lobe.filter(|p| !(0.0..1.0).contains(p)) {
            return Err(bad(
                "render.target_lobe",
                format!("must be in [0, 1), got {p}"),
            ));
        }
        if let Some(p) = s.surface_lobe.filter(|p| !(0.0..1.0).contains(p)) {
            return Err(bad(
                "render.surface_lobe",
                format!("must be in [0, 1), got {p}"),
            ));
        }
        if let Some(p) = s.medium_lobe.filter(|p| !(0.0..1.0).contains(p)) {
            return Err(bad(
                "render.medium_lobe",
                format!("must be in [0, 1), got {p}"),
            ));
        }
        if let Some(p) = s
            .target_phase_distances
            .filter(|p| !(0.0..=1.0).contains(p))
        {
            return Err(bad(
                "render.target_phase_distances",
                format!("must be in [0, 1], got {p}"),
            ));
        }
        if let Some(p) = s.first_vertex_survival.filter(|p| !(*p > 0.0 && *p <= 1.0)) {
            return Err(bad(
                "render.first_vertex_survival",
                format!("must be in (0, 1], got {p}"),
            ));
        }
        Ok(())
    }
}

/// The most anisotropic Henyey–Greenstein phase function a medium may have.
const MAX_ABS_G: f64 = 0.9999;

impl MediumDef {
    /// The medium, or `None` where it does not attenuate (μt = 0); a density grid is read from `dir`
    /// unless its `cells` are given.
    pub(super) fn resolve(
        &self,
        dir: &Path,
        cells: Option<&DensityCells>,
        bad: Bad,
    ) -> Result<Option<Medium>> {
        let m = self;
        murk_core::Limits::extinction(m.mu_t_per_m).map_err(|e| bad("medium.mu_t", e))?;
        check_albedo(m.albedo, "medium.albedo", bad)?;
        // Written so that NaN fails too. Real media stay below 0.99; nearer 1 the phase function's
        // denominator 1 + g² − 2g·cos cancels to zero or below (g = 0.99999999 rendered NaN).
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        let bad_g = !(m.g.abs() <= MAX_ABS_G);
        if bad_g {
            return Err(bad(
                "medium.g",
                format!("must satisfy |g| ≤ {MAX_ABS_G}, got {}", m.g),
            ));
        }
        // Past 4 (germanium's index; water's is 1.33) every path is stretched beyond any window
        // set for the geometry, and the capture would be all zeros.
        if !(m.ior.is_finite() && (1.0..=4.0).contains(&m.ior)) {
            return Err(bad(
                "medium.ior",
                format!("must be in [1, 4], got {}", short(m.ior)),
            ));
        }
        if !(0..3)
            .all(|i| m.min_m[i].is_finite() && m.max_m[i].is_finite() && m.min_m[i] < m.max_m[i])
        {
            return Err(bad(
                "medium.min/max",
                format!(
                    "must bound a non-empty box, got {:?}..{:?}",
                    m.min_m, m.max_m
                ),
            ));
        }
        if m.min_m[2] < 0.0 {
            return Err(bad(
                "medium.min",
                format!(
                    "z = {} reaches behind the relay surface (z = 0)",
                    m.min_m[2]
                ),
            ));
        }
        let region = Aabb {
            min: v3(m.min_m),
            max: v3(m.max_m),
        };
        let kind = self.kind(dir, cells, &region, bad)?;
        Ok(kind.map(|kind| Medium {
            kind,
            albedo: m.albedo,
            phase: Phase::new(m.g),
            ior: m.ior,
            region,
        }))
    }

    /// How σt varies over `region`, each kind with its own fields and no other's; `None` where μt = 0.
    fn kind(
        &self,
        dir: &Path,
        cells: Option<&DensityCells>,
        region: &Aabb,
        bad: Bad,
    ) -> Result<Option<Kind>> {
        let only = |field: &str, kind: &str| {
            bad(
                &format!("medium.{field}"),
                format!(
                    "is read only with medium.kind = \"{kind}\", here it is \"{}\"",
                    format!("{:?}", self.kind).to_lowercase()
                ),
            )
        };
        if self.kind != MediumKindDef::Grid && self.density.is_some() {
            return Err(only("density", "grid"));
        }
        if self.kind != MediumKindDef::Height && self.height_scale_m.is_some() {
            return Err(only("height_scale", "height"));
        }
        let mu_t = self.mu_t_per_m;
        if mu_t <= 0.0 {
            return Ok(None);
        }
        Ok(Some(match self.kind {
            MediumKindDef::Homogeneous => Kind::Homogeneous(Homogeneous {
                sigma_t_per_m: mu_t,
            }),
            MediumKindDef::Grid => {
                let Some(file) = &self.density else {
                    return Err(bad(
                        "medium.density",
                        "kind = \"grid\" needs a density grid (.npy, shape (nx, ny, nz))".into(),
                    ));
                };
                let grid = match cells {
                    Some(cells) => Grid::from_cells(cells.clone(), mu_t, region),
                    None => Grid::load(&dir.join(file), mu_t, region)?,
                };
                murk_core::Limits::extinction(grid.majorant_per_m)
                    .map_err(|e| bad("medium.mu_t × the largest density", e))?;
                Kind::Grid(grid)
            }
            MediumKindDef::Height => {
                let h = self.height_scale_m.unwrap_or(f64::NAN);
                if !(MIN_HEIGHT_SCALE_M..=MAX_HEIGHT_SCALE_M).contains(&h) {
                    return Err(bad(
                        "medium.height_scale",
                        format!(
                            "kind = \"height\" needs a height_scale in [{MIN_HEIGHT_SCALE_M}, {MAX_HEIGHT_SCALE_M:e}] m, got {}",
                            self.height_scale_m.map_or("none".into(), short)
                        ),
                    ));
                }
                Kind::Height(Height {
                    sigma_t_floor_per_m: mu_t,
                    floor_y_m: region.min.y,
                    scale_m: h,
                })
            }
        }))
    }
}

impl ObjectDef {
    /// Object `i` of the file at `path` (relative mesh paths are read from `dir`).
    pub(super) fn resolve(&self, i: usize, dir: &Path, path: &Path, bad: Bad) -> Result<Object> {
        let o = self;
        let field = |name: &str| format!("object[{i}].{name}");
        let (albedo, prims) = match o {
            ObjectDef::Quad {
                center_m,
                size_m,
                normal,
                up,
                albedo,
                ..
            } => {
                let n = v3(*normal).normalize_or_zero();
                let u = v3(*up);
                let ex = u.cross(n).normalize_or_zero();
                if n == DVec3::ZERO || ex == DVec3::ZERO {
                    return Err(bad(
                        &field("normal"),
                        "normal and up must be non-zero and not parallel".into(),
                    ));
                }
                if !size_m.iter().all(|s| s.is_finite() && *s > 0.0) {
                    return Err(bad(
                        &field("size"),
                        format!("must be positive, got {size_m:?}"),
                    ));
                }
                let ey = n.cross(ex);
                let (e1, e2) = (ex * size_m[0], ey * size_m[1]);
                (
                    *albedo,
                    vec![Shape::rect(v3(*center_m) - 0.5 * (e1 + e2), e1, e2)],
                )
            }
            ObjectDef::Box {
                min_m,
                max_m,
                omit,
                albedo,
                ..
            } => {
                let (a, b) = (v3(*min_m), v3(*max_m));
                if !(a.cmplt(b).all()) {
                    return Err(bad(
                        &field("min"),
                        format!("must be below max in every axis, got {min_m:?}..{max_m:?}"),
                    ));
                }
                let d = b - a;
                let faces = [
                    ("-x", Shape::rect(a, DVec3::Y * d.y, DVec3::Z * d.z)),
                    (
                        "+x",
                        Shape::rect(DVec3::new(b.x, a.y, a.z), DVec3::Y * d.y, DVec3::Z * d.z),
                    ),
                    ("-y", Shape::rect(a, DVec3::X * d.x, DVec3::Z * d.z)),
                    (
                        "+y",
                        Shape::rect(DVec3::new(a.x, b.y, a.z), DVec3::X * d.x, DVec3::Z * d.z),
                    ),
                    ("-z", Shape::rect(a, DVec3::X * d.x, DVec3::Y * d.y)),
                    (
                        "+z",
                        Shape::rect(DVec3::new(a.x, a.y, b.z), DVec3::X * d.x, DVec3::Y * d.y),
                    ),
                ];
                if let Some(w) = omit.iter().find(|w| !faces.iter().any(|(n, _)| n == w)) {
                    return Err(bad(
                        &field("omit"),
                        format!("unknown face '{w}' (use -x, +x, -y, +y, -z, +z)"),
                    ));
                }
                let prims = faces
                    .into_iter()
                    .filter(|(n, _)| !omit.iter().any(|w| w == n))
                    .map(|(_, s)| s)
                    .collect();
                (*albedo, prims)
            }
            ObjectDef::ZLetter {
                center_m,
                scale,
                albedo,
                ..
            } => {
                check_scale(*scale, &field("scale"), bad)?;
                let outline = murk_synth::z_letter_outline();
                let c = v3(*center_m);
                let p = |k: usize| c + DVec3::new(outline[k][0], outline[k][1], 0.0) * *scale;
                let prims = triangulate(&outline)
                    .into_iter()
                    .map(|t| Shape::Triangle {
                        p0: p(t[0]),
                        e1: p(t[1]) - p(t[0]),
                        e2: p(t[2]) - p(t[0]),
                    })
                    .collect();
                (*albedo, prims)
            }
            ObjectDef::Mesh {
                file,
                scale,
                translate_m,
                albedo,
                ..
            } => {
                check_scale(*scale, &field("scale"), bad)?;
                // A NaN offset made every triangle degenerate, reported as an OBJ without any.
                for v in translate_m {
                    murk_core::Limits::get()
                        .length("its offset", *v)
                        .map_err(|e| bad(&field("translate"), e.to_string()))?;
                }
                let full = dir.join(file);
                let opts = tobj::LoadOptions {
                    triangulate: true,
                    single_index: true,
                    ..Default::default()
                };
                // A regular file only: a FIFO would block and a device never end.
                let text = murk_core::read_input(&full).map_err(|e| {
                    Error::format(path, format!("{}: cannot read OBJ: {e}", field("file")))
                })?;
                let no_materials = |_: &Path| Err(tobj::LoadError::OpenFileFailed);
                let (models, _) = tobj::load_obj_buf(&mut text.as_slice(), &opts, no_materials)
                    .map_err(|e| {
                        Error::format(
                            path,
                            format!("{}: cannot load OBJ {}: {e}", field("file"), full.display()),
                        )
                    })?;
                let mut prims = Vec::new();
                let mut faces = 0;
                let limits = murk_core::Limits::get();
                for m in &models {
                    let pos = &m.mesh.positions;
                    // A vertex beyond the length limit would make its triangles' areas inf or NaN.
                    if let Some(k) = pos.iter().position(|v| {
                        let v = *v as f64 * *scale;
                        !(v.is_finite() && v.abs() <= limits.max_length_m)
                    }) {
                        return Err(Error::format(
                            path,
                            format!(
                                "{}: OBJ {}: vertex {} has the coordinate {} (scaled by {}); murk accepts finite coordinates up to {} m",
                                field("file"),
                                full.display(),
                                k / 3 + 1,
                                short(pos[k] as f64),
                                short(*scale),
                                short(limits.max_length_m)
                            ),
                        ));
                    }
                    let p = |k: u32| {
                        let k = k as usize * 3;
                        DVec3::new(pos[k] as f64, pos[k + 1] as f64, pos[k + 2] as f64) * *scale
                            + v3(*translate_m)
                    };
                    faces += m.mesh.indices.len() / 3;
                    for t in m.mesh.indices.chunks_exact(3) {
                        let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
                        if (b - a).cross(c - a).length_squared() > 0.0 {
                            prims.push(Shape::Triangle {
                                p0: a,
                                e1: b - a,
                                e2: c - a,
                            });
                        }
                    }
                }
                if prims.is_empty() && faces > 0 {
                    // Faces that the scale shrank to nothing: the file is not at fault.
                    return Err(bad(
                        &field("scale"),
                        format!(
                            "{}: every one of the OBJ's {faces} triangles has zero area once scaled",
                            short(*scale)
                        ),
                    ));
                }
                if prims.is_empty() {
                    return Err(Error::format(
                        path,
                        format!("{}: OBJ {} has no triangles", field("file"), full.display()),
                    ));
                }
                (*albedo, prims)
            }
        };
        check_albedo(albedo, &field("albedo"), bad)?;
        if prims.is_empty() {
            // Only a box's `omit` can leave none (meshes without triangles are named above).
            return Err(bad(
                &field("omit"),
                "leaves no face to reflect light".into(),
            ));
        }
        let obj = Object::new(albedo, prims);
        if obj.bounds.min.z < 0.0 || !obj.bounds.min.is_finite() || !obj.bounds.max.is_finite() {
            return Err(bad(
                &field("shape"),
                format!(
                    "must lie in the hidden volume z ≥ 0 and be finite, its bounds are {:?}..{:?}",
                    obj.bounds.min.to_array(),
                    obj.bounds.max.to_array()
                ),
            ));
        }
        let limits = murk_core::Limits::get();
        for v in obj
            .bounds
            .min
            .to_array()
            .into_iter()
            .chain(obj.bounds.max.to_array())
        {
            limits
                .length("a coordinate of its bounds", v)
                .map_err(|e| bad(&field("shape"), e.to_string()))?;
        }
        // Light reaches the hidden side only through z > 0; a shape flat in the relay's plane is never hit.
        if obj.bounds.max.z <= 0.0 {
            return Err(bad(
                &field("shape"),
                "lies in the relay's plane z = 0, where no light from the hidden side reaches it"
                    .into(),
            ));
        }
        // Smaller than the finest bin murk accepts, it returns no measurable light (a scale of
        // 1e-320 rendered an all-zero capture).
        let across = (obj.bounds.max - obj.bounds.min).max_element();
        if across < limits.min_bin_width_m {
            return Err(bad(
                &field("shape"),
                format!(
                    "is {} m across; murk needs at least {} m",
                    short(across),
                    short(limits.min_bin_width_m)
                ),
            ));
        }
        Ok(obj)
    }
}

/// A shape's scale factor: finite and not zero (a negative one mirrors, which two-sided surfaces allow).
fn check_scale(scale: f64, field: &str, bad: Bad) -> Result<()> {
    if scale.is_finite() && scale != 0.0 {
        Ok(())
    } else {
        Err(bad(
            field,
            format!("must be a finite, non-zero factor, got {}", short(scale)),
        ))
    }
}
