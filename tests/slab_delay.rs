//! `--t-offset slab` for Phasor Fields: the slab's round trip delays a point behind it, and PF's
//! band-pass sees that delay earlier than the response's peak (the response rises sharply and decays
//! slowly). A square 0.5 m behind the CDT foam, rendered through it by CDT's own forward model,
//! must come back at 0.5 m with the pulse's delay, and 4 cm short with the peak's.

use murk_baselines::{through_slab, Pulse, SlabParams};
use murk_core::{Axis, DVec3, TimeAxis, Volume};
use murk_recon::{NoProgress, PfForm, PfParams};
use murk_synth::{add_first_bounce, CaptureLayout, LayoutKind, SynthOptions, Target};

/// Median depth of the brightest voxel per column over the columns whose front view reaches 30 %
/// of its maximum.
fn depth_m(vol: &Volume, intensity: &[f32]) -> f64 {
    let v = murk_view::pictures::views(vol, intensity);
    let top = v.front.values.iter().cloned().fold(f32::MIN, f32::max);
    let mut d: Vec<f64> = v
        .front
        .values
        .iter()
        .zip(&v.depth.values)
        .filter(|(f, _)| **f >= 0.3 * top)
        .map(|(_, d)| *d as f64)
        .collect();
    d.sort_by(f64::total_cmp);
    d[d.len() / 2]
}

#[test]
fn pf_finds_a_square_behind_the_foam_at_its_depth() {
    let layout = CaptureLayout {
        kind: LayoutKind::Confocal,
        wall_size_m: 0.7,
        grid: 32,
        point: DVec3::ZERO,
        time: TimeAxis {
            start_m: 0.0,
            bin_width_m: 0.0048, // 16 ps, as CDT's captures
            bins: 512,
        },
        laser_xyz: None,
        sensor_xyz: None,
    };
    let mut clear = layout.empty_capture().unwrap();
    let square = Target::Polygon {
        outline: vec![[-0.15, -0.15], [0.15, -0.15], [0.15, 0.15], [-0.15, 0.15]],
        offset: [0.0; 2],
        depth_m: 0.5,
        albedo: 1.0,
        spacing_m: 0.005,
    };
    add_first_bounce(
        &mut clear,
        &square.scatterers().unwrap(),
        &SynthOptions::default(),
    )
    .unwrap();
    let slab = SlabParams::default();
    let through = through_slab(&clear, &slab).unwrap();
    let params = PfParams::default();
    let wavelength_m = params.wavelength_m(&through).unwrap();
    let pulse = Pulse {
        wavelength_m,
        sigma_m: params.sigma_m(wavelength_m),
    };
    let vol = Volume {
        x: Axis::new(-0.35, 0.35, 32),
        y: Axis::new(-0.35, 0.35, 32),
        z: Axis::new(0.2, 0.8, 121),
    };
    let depth_with = |delay_m: f64| {
        let mut cap = through.clone();
        cap.time.start_m -= delay_m;
        let rec = murk_recon::reconstruct(&cap, &vol, &params, PfForm::Fast, &NoProgress).unwrap();
        depth_m(&vol, &rec.intensity)
    };
    let (seen, peak) = (
        slab.round_trip_delay_m(Some(pulse)).unwrap(),
        slab.round_trip_delay_m(None).unwrap(),
    );
    assert!(seen < peak, "pulse's delay {seen} m, peak {peak} m");
    let (with_seen, with_peak) = (depth_with(seen), depth_with(peak));
    // One voxel is 5 mm.
    assert!(
        (with_seen - 0.5).abs() <= 0.01,
        "pulse's delay: {with_seen} m"
    );
    assert!(with_peak < 0.47, "peak delay: {with_peak} m");
}
