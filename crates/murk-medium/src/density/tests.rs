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

/// The box comes from the scene `murk render` stored; a capture without one is refused, naming why.
#[test]
fn the_box_is_the_stored_scenes() {
    let file = grid_file("stored", [1, 1, 2], &[2.0, 0.25]);
    let info = "generator: murk render\nscene: |\n  [medium]\n  kind = \"grid\"\n  density = \"plume.npy\"\n  mu_t = 1.0\n  min = [-1.5, -1.5, 0]\n  max = [1.5, 1.5, 1.6]\n";
    let cap = crate::scene::capture_with_info(info);
    let g = GridDensity::for_capture(&cap, &file).unwrap();
    // Straight up through both layers and out of the box's top.
    let up = g.density_length_m(DVec3::ZERO, DVec3::new(0.0, 0.0, 2.0));
    assert!((up - (2.0 * 0.8 + 0.25 * 0.8)).abs() < 1e-12, "{up}");
    let no_box = murk_core::Capture {
        scene_info: info.replace("  max = [1.5, 1.5, 1.6]\n", ""),
        ..cap.clone()
    };
    let e = GridDensity::for_capture(&no_box, &file).err().unwrap();
    assert!(e.to_string().contains("no max = [x, y, z]"), "{e}");
    let none = murk_core::Capture {
        scene_info: "generator: murk synth\n".into(),
        ..cap
    };
    let e = GridDensity::for_capture(&none, &file).err().unwrap();
    assert!(e.to_string().contains("no scene description"), "{e}");
}
