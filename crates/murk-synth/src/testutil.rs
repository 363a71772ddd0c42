//! Captures the reconstruction tests of several crates share: one point scatterer behind a 1 m wall
//! sampled on a 32² grid, and the volume on the wall's own lattice.

use crate::{add_first_bounce, CaptureLayout, LayoutKind, SynthOptions, Target};
use murk_core::{Axis, Capture, DVec3, TimeAxis, Volume};

/// Where [`point_capture`]'s point sits by default.
pub const POINT: DVec3 = DVec3::new(0.1, -0.2, 0.5);

/// A capture of one point scatterer at `pos` behind a 1 m wall of 32² points (4 mm bins, 1400 of
/// them from `start_m`), with the laser and the sensor off the wall when `devices`.
pub fn point_capture(kind: LayoutKind, start_m: f64, devices: bool, pos: DVec3) -> Capture {
    let layout = CaptureLayout {
        kind,
        wall_size_m: 1.0,
        grid: 32,
        point: DVec3::new(0.05, -0.03, 0.0),
        time: TimeAxis {
            start_m,
            bin_width_m: 0.004,
            bins: 1400,
        },
        laser_xyz: devices.then_some(DVec3::new(-0.8, 0.3, -1.2)),
        sensor_xyz: devices.then_some(DVec3::new(0.6, -0.4, -1.5)),
    };
    let mut cap = layout.empty_capture().expect("a valid layout");
    let sc = Target::Point { pos, albedo: 1.0 }
        .scatterers()
        .expect("a valid point");
    add_first_bounce(&mut cap, &sc, &SynthOptions::default()).expect("a valid capture");
    cap
}

/// The wall's own lattice in x, y (32 pixel centres of a 1 m wall) and 21 depths 0.3..0.7.
pub fn aligned_volume() -> Volume {
    let c = 0.5 - 0.5 / 32.0;
    Volume {
        x: Axis::new(-c, c, 32),
        y: Axis::new(-c, c, 32),
        z: Axis::new(0.3, 0.7, 21),
    }
}
