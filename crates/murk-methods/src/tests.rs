//! The contract's tests: one plan per geometry, the knobs each method refuses, the gate and volume
//! checks, and the table's invariants.

use crate::*;
use murk_baselines::Reflectance;
use murk_core::{Axis, DVec3, NoProgress, Volume};
use murk_recon::{Compensation, Lateral};
use murk_synth::testutil::{aligned_volume, point_capture, POINT};
use murk_synth::LayoutKind;

fn capture(kind: LayoutKind, start_m: f64, devices: bool) -> murk_core::Capture {
    point_capture(kind, start_m, devices, POINT)
}

/// One plan serves every capture of its geometry, byte for byte as planning for each; a capture of
/// another geometry is refused.
#[test]
fn a_plan_serves_every_capture_of_its_geometry() {
    let a = capture(LayoutKind::Confocal, 0.0, false);
    let b = point_capture(
        LayoutKind::Confocal,
        0.0,
        false,
        DVec3::new(-0.1, 0.15, 0.45),
    );
    for name in METHODS.iter().map(|m| m.name) {
        let method = Method::named(name, &Options::default()).unwrap();
        let volume = VolumeSpec::Given(Volume {
            z: Axis::new(0.3, 0.7, 9),
            ..aligned_volume()
        });
        let req = Request {
            volume,
            ..Request::new(method)
        };
        let plan = ReconPlan::new(&a, &req, &NoProgress).unwrap();
        for cap in [&a, &b] {
            let reused = plan.run(cap.clone(), &NoProgress).unwrap();
            let fresh = crate::run(cap.clone(), &req, &NoProgress).unwrap();
            assert_eq!(reused.intensity, fresh.intensity, "{name}");
            assert_eq!(reused.normals, fresh.normals, "{name}");
            assert_eq!(reused.rows, fresh.rows, "{name}");
            // Normals pass through the contract from the method that gives them, unit length where
            // there is intensity and zero where there is none.
            assert_eq!(reused.normals.is_some(), name == "dlct", "{name}");
            for (n, &v) in reused.normals.iter().flatten().zip(&reused.intensity) {
                let len = n.iter().map(|c| c * c).sum::<f32>().sqrt();
                assert!(
                    if v == 0.0 {
                        len == 0.0
                    } else {
                        (len - 1.0).abs() < 1e-4
                    },
                    "{name}: {n:?} at intensity {v}"
                );
            }
            // lct, fk and cdt reconstruct on the scan's own grid and say that the volume is ignored.
            assert_eq!(
                reused
                    .warnings
                    .iter()
                    .any(|w| w.contains("the given volume is ignored")),
                method.own_grid(),
                "{name}: {:?}",
                reused.warnings
            );
        }
        assert_eq!(method.name(), name);
        let mut later = a.clone();
        later.time.start_m += 0.01;
        let e = plan.run(later, &NoProgress).unwrap_err().to_string();
        assert!(
            e.contains("differ from the ones the plan was made for"),
            "{name}: {e}"
        );
    }
    let e = Method::named("lcd", &Options::default()).unwrap_err();
    assert!(e
        .to_string()
        .contains("unknown method 'lcd'; expected one of pf, pf-exact, bp"));
}

/// A knob that the named method would ignore is refused, naming the knob and the methods that read
/// it; the same knob for a method that reads it is accepted.
#[test]
fn methods_refuse_knobs_they_ignore() {
    let compensated = Options {
        compensation: Compensation::named("paper", 1.0, Some(0.5)).unwrap(),
        ..Options::default()
    };
    let snr = Options {
        snr: Some(3.0),
        ..Options::default()
    };
    let weighted = Options {
        reflectance: Reflectance::Retroreflective,
        ..Options::default()
    };
    let full = Options {
        lateral: Lateral::Full,
        ..Options::default()
    };
    // The readers come from the table, so that a new method reading a knob changes no test.
    let readers = |k: Knob| format!("(it applies to {})", k.readers());
    for (name, o, want) in [
        (
            "lct",
            &compensated,
            format!(
                "compensation does not apply to lct, which would ignore it {}",
                readers(Knob::Compensation)
            ),
        ),
        (
            "fk",
            &snr,
            format!(
                "a Wiener snr does not apply to fk, which would ignore it {}",
                readers(Knob::Snr)
            ),
        ),
        (
            "cdt",
            &weighted,
            "a reflectance weighting does not apply to cdt".into(),
        ),
        (
            "pf-exact",
            &full,
            "a lateral band does not apply to pf-exact".into(),
        ),
        (
            "dlct",
            &weighted,
            "a reflectance weighting does not apply to dlct".into(),
        ),
    ] {
        let e = Method::named(name, o).unwrap_err().to_string();
        assert!(e.starts_with(&want), "{name}: {e}");
    }
    assert_eq!(Knob::Compensation.readers(), "pf and pf-exact");
    for (name, o) in [
        ("pf", &compensated),
        ("pf-exact", &compensated),
        ("lct", &snr),
        ("cdt", &snr),
        ("dlct", &snr),
        ("lct", &weighted),
        ("pf", &full),
    ] {
        assert!(Method::named(name, o).is_ok(), "{name}");
    }
}

/// A volume out of the window's reach is refused when planning, naming the volume; a gate set by
/// hand after the window is refused naming the gate, and one before it is said to fade nothing.
#[test]
fn a_volume_or_gate_beyond_the_window_is_refused() {
    let cap = capture(LayoutKind::Confocal, 0.0, false);
    for name in ["pf", "bp"] {
        let method = Method::named(name, &Options::default()).unwrap();
        // The window ends at 5.6 m of path; a confocal voxel 4 m deep is 8 m away.
        let far = Request {
            volume: VolumeSpec::Given(Volume {
                z: Axis::new(4.0, 5.0, 5),
                ..aligned_volume()
            }),
            ..Request::new(method)
        };
        let e = ReconPlan::new(&cap, &far, &NoProgress)
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.contains("the volume lies beyond the capture's window")
                && e.contains("8.000 m")
                && e.contains("5.600 m"),
            "{name}: {e}"
        );
        let late_gate = Request {
            gate: Gate::At(6.0),
            ..Request::new(method)
        };
        let e = crate::run(cap.clone(), &late_gate, &NoProgress)
            .unwrap_err()
            .to_string();
        assert!(e.contains("the gate at 6.000 m opens after"), "{name}: {e}");
        // One before the window (it starts at 0) is no error, but is said: it fades nothing.
        let early_gate = Request {
            gate: Gate::At(0.0),
            ..Request::new(method)
        };
        let out = crate::run(cap.clone(), &early_gate, &NoProgress).unwrap();
        assert!(
            out.warnings.iter().any(|w| w
                .contains("the gate at 0.000 m opens before the capture's window starts (0.000 m")),
            "{name}: {:?}",
            out.warnings
        );
        let on_time = Request {
            gate: Gate::At(1.0),
            ..Request::new(method)
        };
        let out = crate::run(cap.clone(), &on_time, &NoProgress).unwrap();
        assert!(
            !out.warnings.iter().any(|w| w.contains("fades nothing")),
            "{name}"
        );
    }
}

/// Every knob is read by some method and every name is listed once, so that a refusal can always
/// name where a knob applies and `--method` offers each method once.
#[test]
fn the_table_names_each_method_once_and_every_knob_has_a_reader() {
    for (i, m) in METHODS.iter().enumerate() {
        assert!(!m.help.is_empty(), "{}", m.name);
        assert!(
            METHODS[..i].iter().all(|n| n.name != m.name),
            "{} twice",
            m.name
        );
    }
    for k in Knob::ALL {
        assert!(!k.readers().is_empty(), "{k:?}");
    }
    // `murk reconstruct --help` tells the methods on their own grid by this phrase.
    for m in METHODS {
        assert_eq!(m.help.contains("own volume"), m.own_grid, "{}", m.name);
    }
    let e = TOffset::parse(
        None,
        &Options {
            slab: murk_baselines::SlabParams {
                thickness_m: 0.05,
                ..Default::default()
            },
            ..Options::default()
        },
        &Method::named("fk", &Options::default()).unwrap(),
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "slab parameters are read only by cdt and by t-offset 'slab'; fk would ignore them"
    );
}

/// The front ends' arguments at `murk reconstruct`'s defaults.
fn default_args() -> RequestArgs {
    RequestArgs {
        method: "pf".into(),
        volume: None,
        wavelength_m: None,
        wavefactor: None,
        cycles: 4.0,
        compensate: None,
        mu_t_per_m: None,
        albedo: None,
        falloff: "none".into(),
        lateral: "propagating".into(),
        snr: None,
        weighting: "diffuse".into(),
        slab: murk_baselines::SlabParams::default(),
        medium: murk_baselines::BmmParams::default(),
        t_offset: None,
        gate: Gate::Auto,
        window_end: "auto".into(),
        medium_removal: "auto".into(),
        depth_search: "auto".into(),
    }
}

/// The defaults make `Request::new`'s request; each knob reaches the options under its name; both
/// wavelengths, or a compensation without μt, are refused (an unknown compensation named first).
#[test]
fn request_args_make_the_request() {
    let pf = Method::named("pf", &Options::default()).unwrap();
    assert_eq!(default_args().request().unwrap(), Request::new(pf));
    let given = RequestArgs {
        method: "pf-exact".into(),
        volume: Some("-0.5:0.5:3,-0.5:0.5:3,0.4:0.6:3".into()),
        wavefactor: Some(6.0),
        compensate: Some("paper".into()),
        mu_t_per_m: Some(1.0),
        albedo: Some(0.5),
        falloff: "inv-r".into(),
        t_offset: Some("0.25".into()),
        window_end: "keep".into(),
        ..default_args()
    };
    let req = given.request().unwrap();
    let o = req.method.options();
    assert_eq!(req.method.name(), "pf-exact");
    assert_eq!(o.wavelength, Some(murk_recon::Wavelength::WallFactor(6.0)));
    assert_eq!(
        o.compensation,
        Compensation::Paper {
            mu_t_per_m: 1.0,
            albedo: 0.5
        }
    );
    assert_eq!(o.falloff, murk_recon::Falloff::InvR);
    assert_eq!(req.t_offset, TOffset::Metres(0.25));
    assert_eq!(req.window_end, murk_core::window::WindowEnd::Keep);
    assert!(matches!(req.volume, VolumeSpec::Given(v) if v.z.n == 3));
    let none = RequestArgs {
        compensate: Some("none".into()),
        mu_t_per_m: Some(1.0),
        ..default_args()
    };
    assert_eq!(none.options().unwrap().compensation, Compensation::None);
    for (args, want) in [
        (
            RequestArgs {
                wavelength_m: Some(0.1),
                wavefactor: Some(4.0),
                ..default_args()
            },
            "give wavelength or wavefactor, not both",
        ),
        (
            RequestArgs {
                compensate: Some("paper".into()),
                ..default_args()
            },
            "compensate needs mu_t",
        ),
        (
            RequestArgs {
                compensate: Some("papr".into()),
                ..default_args()
            },
            "compensate 'papr': expected",
        ),
        (
            RequestArgs {
                lateral: "some".into(),
                ..default_args()
            },
            "lateral 'some': expected propagating, full",
        ),
    ] {
        let e = args.request().unwrap_err().to_string();
        assert!(e.starts_with(want), "{e}");
    }
}

/// The depth search bins a fine wall grid to at most 64 points a side: each block's mean histogram
/// at its points' mean; grids that small already, of a side no divisor brings near 64, or scanned
/// every laser point with every sensor point are searched as they are.
#[test]
fn a_fine_grid_is_searched_binned() {
    use murk_core::{Capture, Pairing, PointSet, TimeAxis};
    let laser_grid = |n: usize, sensors: usize| {
        let illum = PointSet::wall_grid(DVec3::ZERO, 2.0, 2.0, n, n);
        let sensor = PointSet::wall_grid(DVec3::ZERO, 0.1, 0.1, sensors, 1);
        let bins = 3;
        let h = (0..n * n * sensors * bins).map(|v| v as f32).collect();
        let time = TimeAxis {
            start_m: 0.0,
            bin_width_m: 0.01,
            bins,
        };
        Capture::new(illum, sensor, Pairing::Product, time, h)
    };
    let fine = laser_grid(128, 1);
    let b = crate::depth::binned_for_search(&fine).unwrap();
    assert_eq!(b.illum.shape(), (64, 64));
    assert_eq!(b.sensor, fine.sensor);
    assert_eq!(b.n_hist(), 64 * 64);
    // Binned point (1, 2) holds fine points (2..4) × (4..6).
    let block = [2 * 128 + 4, 2 * 128 + 5, 3 * 128 + 4, 3 * 128 + 5];
    let i = 64 + 2;
    let mean_point = block.iter().map(|&p| fine.illum.points[p]).sum::<DVec3>() / 4.0;
    assert!((b.illum.points[i] - mean_point).length() < 1e-12);
    for t in 0..3 {
        let mean = block.iter().map(|&p| fine.histogram(p)[t]).sum::<f32>() / 4.0;
        assert_eq!(b.histogram(i)[t], mean);
    }
    assert_eq!(b.illum.spacing_m(), Some(2.0 / 64.0));
    assert!(crate::depth::binned_for_search(&laser_grid(64, 1)).is_none());
    assert!(crate::depth::binned_for_search(&laser_grid(127, 1)).is_none());
    assert!(crate::depth::binned_for_search(&laser_grid(128, 2)).is_none());
    // A confocal scan bins both sides alike.
    let c = laser_grid(96, 1);
    let confocal = Capture::confocal(c.illum.clone(), c.time, c.h.clone(), String::new());
    let b = crate::depth::binned_for_search(&confocal).unwrap();
    assert_eq!(
        (b.illum.shape(), b.illum.clone()),
        (b.sensor.shape(), b.sensor.clone())
    );
    assert_eq!(b.illum.shape(), (48, 48));
}
