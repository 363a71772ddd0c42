use murk_core::{DVec3, Error, Result};

/// One point of the hidden scene with its total weight (albedo × area for surface samples).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scatterer {
    pub pos: DVec3,
    pub weight: f64,
    /// Surface normal for Lambertian samples; `None` for isotropic point scatterers.
    pub normal: Option<DVec3>,
}

/// Hidden geometry the analytic model understands.
#[derive(Clone, Debug, PartialEq)]
pub enum Target {
    /// An isotropic point scatterer.
    Point { pos: DVec3, albedo: f64 },
    /// A planar polygon parallel to the wall at `depth_m`, facing it, rasterised on a square lattice of
    /// `spacing_m` (keep it ≤ half the wall spacing so the lattice does not alias in reconstructions).
    Polygon {
        outline: Vec<[f64; 2]>,
        offset: [f64; 2],
        depth_m: f64,
        albedo: f64,
        spacing_m: f64,
    },
}

impl Target {
    pub fn scatterers(&self) -> Result<Vec<Scatterer>> {
        match self {
            Target::Point { pos, albedo } => {
                if pos.z <= 0.0 {
                    return Err(Error::param(format!(
                        "point target at z = {} is not behind the wall",
                        pos.z
                    )));
                }
                check_depth(pos.z)?;
                Ok(vec![Scatterer {
                    pos: *pos,
                    weight: *albedo,
                    normal: None,
                }])
            }
            Target::Polygon {
                outline,
                offset,
                depth_m,
                albedo,
                spacing_m,
            } => {
                if outline.len() < 3 {
                    return Err(Error::param("a polygon needs at least 3 vertices"));
                }
                if *depth_m <= 0.0 || spacing_m.is_nan() || *spacing_m <= 0.0 {
                    return Err(Error::param(format!(
                        "polygon depth ({depth_m} m) and spacing ({spacing_m} m) must be > 0"
                    )));
                }
                check_depth(*depth_m)?;
                let limits = murk_core::Limits::get();
                for v in outline {
                    for c in v.iter().chain(offset) {
                        limits.length("a polygon vertex's coordinate", *c)?;
                    }
                }
                let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
                for v in outline {
                    for k in 0..2 {
                        lo[k] = lo[k].min(v[k]);
                        hi[k] = hi[k].max(v[k]);
                    }
                }
                let n = [
                    ((hi[0] - lo[0]) / spacing_m).ceil() as usize,
                    ((hi[1] - lo[1]) / spacing_m).ceil() as usize,
                ];
                if n[0].saturating_mul(n[1]) > 50_000_000 {
                    return Err(Error::Limits(format!(
                        "polygon raster of {}×{} samples is too fine",
                        n[0], n[1]
                    )));
                }
                let area = spacing_m * spacing_m;
                let mut out = Vec::new();
                for i in 0..n[0] {
                    for j in 0..n[1] {
                        let p = [
                            lo[0] + (i as f64 + 0.5) * spacing_m,
                            lo[1] + (j as f64 + 0.5) * spacing_m,
                        ];
                        if inside(outline, p) {
                            out.push(Scatterer {
                                pos: DVec3::new(p[0] + offset[0], p[1] + offset[1], *depth_m),
                                weight: albedo * area,
                                normal: Some(-DVec3::Z),
                            });
                        }
                    }
                }
                if out.is_empty() {
                    return Err(Error::param(format!(
                        "the polygon covers no sample of its {} m raster: its area is zero or smaller than a sample's",
                        murk_core::short(*spacing_m)
                    )));
                }
                Ok(out)
            }
        }
    }
}

/// A target this close to the wall makes the 1/r² of its returns overflow 32-bit floats; nothing
/// is imaged that close anyway.
fn check_depth(z_m: f64) -> Result<()> {
    let least = murk_core::Limits::get().min_bin_width_m;
    if z_m < least {
        return Err(Error::param(format!(
            "a target at depth {} m is closer to the wall than the {} m murk accepts",
            murk_core::short(z_m),
            murk_core::short(least)
        )));
    }
    murk_core::Limits::get().length("a target's depth", z_m)
}

/// Even-odd point-in-polygon test.
fn inside(poly: &[[f64; 2]], p: [f64; 2]) -> bool {
    let mut c = false;
    let mut j = poly.len() - 1;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[j]);
        if (a[1] > p[1]) != (b[1] > p[1])
            && p[0] < (b[0] - a[0]) * (p[1] - a[1]) / (b[1] - a[1]) + a[0]
        {
            c = !c;
        }
        j = i;
    }
    c
}

/// y-tal's Z letter (0.8 m × 0.8 m, stroke ≈ 0.103 m) in world x–y. It is authored mirrored in world
/// coordinates, so it reads as a Z when seen from the wall looking into the hidden scene (+z).
pub fn z_letter_outline() -> Vec<[f64; 2]> {
    vec![
        [-0.4, 0.4],
        [0.3649, 0.4],
        [0.3649, 0.2968],
        [-0.1646, 0.2968],
        [0.4, -0.4],
        [-0.4, -0.4],
        [-0.4, -0.2968],
        [0.1646, -0.2968],
    ]
}

/// The letter T of the project's benchmark scene (docs/benchmarks.md, `scenes/t-wall-*.toml`): bar 0.5 × 0.1 m centred at
/// (0, 0.20), stem 0.1 × 0.4 m centred at (0, −0.05).
pub fn t_letter_outline() -> Vec<[f64; 2]> {
    vec![
        [-0.25, 0.25],
        [0.25, 0.25],
        [0.25, 0.15],
        [0.05, 0.15],
        [0.05, -0.25],
        [-0.05, -0.25],
        [-0.05, 0.15],
        [-0.25, 0.15],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_raster_area() {
        let t = Target::Polygon {
            outline: vec![[0.0, 0.0], [0.5, 0.0], [0.5, 0.2], [0.0, 0.2]],
            offset: [0.0, 0.0],
            depth_m: 1.0,
            albedo: 1.0,
            spacing_m: 0.01,
        };
        let s = t.scatterers().unwrap();
        let area: f64 = s.iter().map(|s| s.weight).sum();
        assert!((area - 0.1).abs() < 1e-9, "{area}");
        // Collinear vertices enclose nothing: refused as such, not as a time window without returns.
        let flat = Target::Polygon {
            outline: vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]],
            offset: [0.0, 0.0],
            depth_m: 1.0,
            albedo: 1.0,
            spacing_m: 0.01,
        };
        let e = flat.scatterers().unwrap_err().to_string();
        assert!(e.contains("covers no sample of its 0.01 m raster"), "{e}");
    }

    #[test]
    fn z_letter_area() {
        let t = Target::Polygon {
            outline: z_letter_outline(),
            offset: [0.0; 2],
            depth_m: 2.0,
            albedo: 1.0,
            spacing_m: 0.004,
        };
        let area: f64 = t.scatterers().unwrap().iter().map(|s| s.weight).sum();
        // Two bars of 0.8 × 0.1032 plus a diagonal band: about 0.26 m².
        assert!((0.22..0.30).contains(&area), "{area}");
    }
}
