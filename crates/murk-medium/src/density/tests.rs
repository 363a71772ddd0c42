use super::*;
use murk_recon::Compensation;

/// A grid file of `shape` with `density` written to a fresh temporary folder.
fn grid_file(name: &str, shape: [usize; 3], density: &[f32]) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("murk-density-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("density.npy");
    murk_io::write_npy_f32(&path, &shape, density).unwrap();
    path
}

/// Voxels in front of a 1 m wall (z from 0.05 to 2.2 m, some beyond the box of the layered test),
/// with the wall points the compensation's legs start from.
fn voxels() -> Vec<DVec3> {
    let mut v = Vec::new();
    for i in 0..5 {
        for k in 0..12 {
            let x = -0.6 + 0.3 * i as f64;
            v.push(DVec3::new(x, 0.37 * x - 0.1, 0.05 + 0.19 * k as f64));
        }
    }
    v
}

const POINT: DVec3 = DVec3::new(0.1, -0.2, 0.0);
const APERTURE: DVec3 = DVec3::new(0.0, 0.05, 0.0);

/// A grid of density 1 over a box that holds every leg gives the homogeneous compensation (the cell
/// walk's sum of pieces against one product: within 1e-12), paper and ballistic, confocal or not.
#[test]
fn constant_density_is_the_homogeneous_compensation() {
    let region = Aabb {
        min: DVec3::new(-2.0, -2.0, -0.01),
        max: DVec3::new(2.0, 2.0, 3.0),
    };
    let file = grid_file("constant", [3, 4, 5], &[1.0; 60]);
    let grid = GridDensity::load(&file, region).unwrap();
    for comp in [
        Compensation::Ballistic { mu_t_per_m: 0.7 },
        Compensation::Paper {
            mu_t_per_m: 1.3,
            albedo: 0.6,
        },
    ] {
        for confocal in [false, true] {
            for v in voxels() {
                let plain = comp.gain(v, POINT, APERTURE, confocal);
                let along = comp.gain_along(v, POINT, APERTURE, confocal, Some(&grid));
                assert!(
                    (along - plain).abs() <= 1e-12 * plain,
                    "{comp:?} confocal {confocal} at {v}: {along} vs {plain}"
                );
            }
        }
    }
}

/// Two layers (density 2 up to z = 0.8 m, 0.25 from there to the box's top at 1.6 m, 0 beyond): the
/// ballistic gain at each voxel against e^{2μt(∫ρ + ∫ρ)} with each leg's ∫ρ a 100 000-step midpoint
/// sum of the layers as a formula. The sum misplaces the layer face and the box's top by under a step
/// each, so the exponents agree within 2 legs × 2 faces × step × 2 × 2μt.
#[test]
fn two_layers_match_a_line_integral() {
    let region = Aabb {
        min: DVec3::new(-1.5, -1.5, 0.0),
        max: DVec3::new(1.5, 1.5, 1.6),
    };
    let rho = |p: DVec3| {
        let inside = (0..3).all(|a| p[a] >= region.min[a] && p[a] <= region.max[a]);
        match (inside, p.z < 0.8) {
            (false, _) => 0.0,
            (true, true) => 2.0,
            (true, false) => 0.25,
        }
    };
    let line = |a: DVec3, b: DVec3| -> (f64, f64) {
        let n = 100_000;
        let dt = (b - a).length() / n as f64;
        let sum = (0..n)
            .map(|i| rho(a + (b - a) * ((i as f64 + 0.5) / n as f64)) * dt)
            .sum();
        (sum, dt)
    };
    let file = grid_file("layers", [1, 1, 2], &[2.0, 0.25]);
    let grid = GridDensity::load(&file, region).unwrap();
    let mu_t_per_m = 0.9;
    let comp = Compensation::Ballistic { mu_t_per_m };
    let mut beyond = 0;
    for v in voxels() {
        let (ill, dt_ill) = line(POINT, v);
        let (cam, dt_cam) = line(APERTURE, v);
        let want = 2.0 * mu_t_per_m * (ill + cam);
        let got = comp.gain_along(v, POINT, APERTURE, false, Some(&grid)).ln();
        let tol = 2.0 * mu_t_per_m * 2.0 * 2.0 * (dt_ill + dt_cam);
        assert!((got - want).abs() <= tol, "at {v}: {got} vs {want}");
        beyond += usize::from(v.z > 1.6);
    }
    // Some voxels lie past the box, where the legs' last stretch adds nothing.
    assert!(beyond > 0);
    // The layers are not the mean: a homogeneous medium of the box's mean density is off.
    let v = DVec3::new(0.3, 0.0, 1.5);
    let mean = Compensation::Ballistic {
        mu_t_per_m: mu_t_per_m * (2.0 + 0.25) / 2.0,
    };
    let ratio = comp.gain_along(v, POINT, APERTURE, false, Some(&grid))
        / mean.gain(v, POINT, APERTURE, false);
    assert!(!(0.9..1.1).contains(&ratio), "{ratio}");
}

/// A capture whose stored scene's `[medium]` has the lines `medium` over the box
/// (−1.5, −0.5, 0)..(1.5, 1.0, 1.6).
fn stored(medium: &str) -> murk_core::Capture {
    let info = format!(
        "generator: murk render\nscene: |\n  [medium]\n{}  mu_t = 1.0\n  min = [-1.5, -0.5, 0]\n  max = [1.5, 1.0, 1.6]\n",
        medium.lines().map(|l| format!("  {l}\n")).collect::<String>()
    );
    crate::scene::capture_with_info(&info)
}

const CLI: Spelling = Spelling::Cli;

/// The box comes from the scene `murk render` stored; a capture without one is refused, naming why.
#[test]
fn the_box_is_the_stored_scenes() {
    let file = grid_file("stored", [1, 1, 2], &[2.0, 0.25]);
    let given = DensityGiven {
        file: Some(file),
        height_scale_m: None,
    };
    let cap = stored("kind = \"grid\"\ndensity = \"plume.npy\"");
    let along = given.along(&cap, true, true, CLI).unwrap();
    let g = along.density.unwrap();
    // Straight up through both layers and out of the box's top.
    let up = g.density_length_m(DVec3::ZERO, DVec3::new(0.0, 0.0, 2.0));
    assert!((up - (2.0 * 0.8 + 0.25 * 0.8)).abs() < 1e-12, "{up}");
    assert!(along.row.unwrap().contains("density.npy"));
    let no_box = murk_core::Capture {
        scene_info: cap.scene_info.replace("  max = [1.5, 1.0, 1.6]\n", ""),
        ..cap.clone()
    };
    let e = given.along(&no_box, true, true, CLI).err().unwrap();
    assert!(e.to_string().contains("no max = [x, y, z]"), "{e}");
    let none = murk_core::Capture {
        scene_info: "generator: murk synth\n".into(),
        ..cap
    };
    let e = given.along(&none, true, true, CLI).err().unwrap();
    assert!(e.to_string().contains("no scene description"), "{e}");
}

/// The box of the height-fog tests (as `stored`'s), and the fog's scale.
const FOG_BOX: Aabb = Aabb {
    min: DVec3::new(-1.5, -0.5, 0.0),
    max: DVec3::new(1.5, 1.0, 1.6),
};
const FOG_SCALE_M: f64 = 0.4;

/// The height fog's density length against a 200 000-step midpoint sum of exp(−(y − floor)/H)
/// inside the box, on legs that rise, fall, run level (y = 0.3 at both ends) and leave the box. The
/// sum errs by under (len·h²/24)·max|ρ''| ≤ len·h²/(24 H²) in the fog (ρ ≤ 1), and misplaces each of
/// the box's two faces a leg crosses by under a step: tolerance len·h²/(24 H²) + 2h + 1e-12.
#[test]
fn height_fog_matches_a_line_integral() {
    let (region, scale_m) = (FOG_BOX, FOG_SCALE_M);
    let fog = HeightDensity::new(region, scale_m);
    let rho = |p: DVec3| {
        let inside = (0..3).all(|a| p[a] >= region.min[a] && p[a] <= region.max[a]);
        if inside {
            (-(p.y - region.min.y) / scale_m).exp()
        } else {
            0.0
        }
    };
    let mut legs: Vec<(DVec3, DVec3)> = voxels()
        .into_iter()
        .flat_map(|v| [(POINT, v), (APERTURE, v)])
        .collect();
    legs.push((DVec3::new(-1.0, 0.3, 0.2), DVec3::new(1.2, 0.3, 1.3)));
    legs.push((DVec3::new(0.0, 0.3, 0.2), DVec3::new(0.0, 0.3 + 1e-10, 1.0)));
    legs.push((DVec3::new(0.0, 1.4, 0.5), DVec3::new(0.1, -0.7, 0.9)));
    for (a, b) in legs {
        let n = 200_000;
        let len = (b - a).length();
        let h = len / n as f64;
        let sum: f64 = (0..n)
            .map(|i| rho(a + (b - a) * ((i as f64 + 0.5) / n as f64)) * h)
            .sum();
        let got = fog.density_length_m(a, b);
        let tol = len * h * h / (24.0 * scale_m * scale_m) + 2.0 * h + 1e-12;
        assert!((got - sum).abs() <= tol, "{a} → {b}: {got} vs {sum}");
    }
}

/// The compensation through the closed-form height fog against the same fog as a fine grid
/// (1 × 3000 × 1 cells, each the fog's mean over its height, so a leg's full cells are exact). Only
/// the cells at a leg's two ends hold part of it; there the density differs from the fog's by under
/// e^{h/H} − 1 of it (h the cell height, ρ ≤ 1), over at most min(len, h/|d.y|) each: the exponent
/// 2μt·∑ legs agrees within 2μt × that, per leg.
#[test]
fn height_fog_compensation_matches_its_fine_grid() {
    let (region, scale_m) = (FOG_BOX, FOG_SCALE_M);
    let ny = 3000;
    let h = (region.max.y - region.min.y) / ny as f64;
    let cells: Vec<f32> = (0..ny)
        .map(|j| {
            let (lo, hi) = (j as f64 * h, (j + 1) as f64 * h);
            (scale_m / h * ((-lo / scale_m).exp() - (-hi / scale_m).exp())) as f32
        })
        .collect();
    let file = grid_file("height", [1, ny, 1], &cells);
    let grid = GridDensity::load(&file, region).unwrap();
    let fog = HeightDensity::new(region, scale_m);
    let mu_t_per_m = 1.1;
    let comp = Compensation::Ballistic { mu_t_per_m };
    let end_error = |a: DVec3, v: DVec3| {
        let len = (v - a).length();
        let dy = ((v.y - a.y) / len).abs();
        2.0 * (len.min(h / dy)) * ((h / scale_m).exp() - 1.0)
    };
    let mut worst = 0.0f64;
    for v in voxels() {
        let want = comp.gain_along(v, POINT, APERTURE, false, Some(&grid)).ln();
        let got = comp.gain_along(v, POINT, APERTURE, false, Some(&fog)).ln();
        // f32 cells add a relative 6e-8 of the exponent.
        let tol = 2.0 * mu_t_per_m * (end_error(POINT, v) + end_error(APERTURE, v)) + 1e-7 * want;
        assert!(
            (got - want).abs() <= tol,
            "at {v}: {got} vs {want} (tol {tol})"
        );
        worst = worst.max((got - want).abs());
        // The fog is not homogeneous: the same μt everywhere would compensate otherwise.
        let flat = comp.gain(v, POINT, APERTURE, false).ln();
        assert!((flat - got).abs() > 0.1, "at {v}: {flat} vs {got}");
    }
    assert!(worst > 0.0);
}

/// Which density the compensation reads, in order: the one given, the stored height fog (with μt
/// given or estimated), else homogeneous; a stored grid without its cells warns, naming what to give.
#[test]
fn the_density_given_comes_before_the_stored_one() {
    let height = stored("kind = \"height\"\nheight_scale = 0.4");
    let level = |a: &Along| {
        let d = a.density.as_ref().unwrap();
        d.density_length_m(DVec3::new(0.0, 0.3, 0.1), DVec3::new(0.0, 0.3, 1.1))
    };
    let none = DensityGiven::default();
    let auto = none.along(&height, true, true, CLI).unwrap();
    assert!((level(&auto) - (-0.8f64 / 0.4).exp()).abs() < 1e-12);
    assert!(auto.row.as_ref().unwrap().contains("the capture's scene"));
    assert!(auto.warnings.is_empty());
    let given = DensityGiven {
        file: None,
        height_scale_m: Some(0.8),
    };
    let explicit = given.along(&height, true, true, CLI).unwrap();
    assert!((level(&explicit) - (-0.8f64 / 0.8).exp()).abs() < 1e-12);
    // No compensation: nothing is read and nothing is said.
    let off = none.along(&height, false, false, CLI).unwrap();
    assert!(off.density.is_none() && off.row.is_none() && off.warnings.is_empty());
    // An estimated μt is σt on the fog's floor too (the estimate keeps the fog's shape).
    let estimated = none.along(&height, true, false, Spelling::Python).unwrap();
    assert!((level(&estimated) - (-0.8f64 / 0.4).exp()).abs() < 1e-12);
    assert!(estimated.warnings.is_empty());
    // A stored grid without its cells: homogeneous, naming what to give.
    let grid = stored("kind = \"grid\"\ndensity = \"plume.npy\"");
    for (mu_t_given, give) in [
        (true, "give --medium-density FILE.npy"),
        (false, "give --mu-t and --medium-density FILE.npy"),
    ] {
        let stored_grid = none.along(&grid, true, mu_t_given, CLI).unwrap();
        assert!(stored_grid.density.is_none());
        assert!(
            stored_grid.warnings[0].contains("density grid (density = \"plume.npy\")")
                && stored_grid.warnings[0].contains(give),
            "{:?}",
            stored_grid.warnings
        );
    }
    let homogeneous = none.along(&stored(""), true, true, CLI).unwrap();
    assert!(homogeneous.density.is_none() && homogeneous.warnings.is_empty());
    // Refused: both densities, one without μt, a scale out of range.
    let both = DensityGiven {
        file: Some("d.npy".into()),
        height_scale_m: Some(1.0),
    };
    let e = both
        .along(&height, true, true, Spelling::Python)
        .err()
        .unwrap();
    assert!(
        e.to_string().contains("medium_density and height_scale"),
        "{e}"
    );
    let e = given.along(&height, true, false, CLI).err().unwrap();
    assert!(
        e.to_string()
            .contains("--height-scale is read by --compensate with --mu-t"),
        "{e}"
    );
    for bad in [0.0, -1.0, f64::NAN, 1e-4] {
        let g = DensityGiven {
            file: None,
            height_scale_m: Some(bad),
        };
        let e = g.along(&height, true, true, CLI).err().unwrap();
        assert!(e.to_string().contains("--height-scale must be in"), "{e}");
    }
}
