//! A capture described in words, for `murk info` and logs.

use murk_core::{Capture, Opt};

fn side(name: &str, p: &murk_core::PointSet) -> String {
    let (nx, ny) = p.shape();
    let layout = match p.layout {
        murk_core::PointLayout::Grid { .. } if p.len() == 1 => "one point".to_string(),
        murk_core::PointLayout::Grid { .. } => format!("{nx} × {ny} grid"),
        murk_core::PointLayout::List => format!("list of {}", p.len()),
    };
    let (lo, hi) = p
        .points
        .iter()
        .fold((p.points[0], p.points[0]), |(a, b), q| {
            (a.min(*q), b.max(*q))
        });
    // Both steps where they differ (a non-square scan over a square side), else the one.
    let spacing = p
        .regular_grid()
        .map(|g| (g.step_x.length(), g.step_y.length()))
        .map(|(step_x_m, step_y_m)| match (step_x_m - step_y_m).abs() <= 1e-9 * step_x_m.max(step_y_m) {
            true => format!(", spacing {step_x_m:.4} m"),
            false => format!(
                ", spacing {step_x_m:.4} m along the grid's first index, {step_y_m:.4} m along its second"
            ),
        })
        .unwrap_or_default();
    format!(
        "{name}: {layout}{spacing}, x {:+.3}..{:+.3}, y {:+.3}..{:+.3}, z {:+.3}..{:+.3} m",
        lo.x, hi.x, lo.y, hi.y, lo.z, hi.z
    )
}

/// How the time axis maps to depth: what a reconstruction's z means for this capture.
fn depth_axis(cap: &Capture) -> String {
    let t = cap.time;
    let wall_z = cap
        .sensor
        .points
        .iter()
        .map(|p| p.z)
        .fold(f64::MIN, f64::max);
    let legs = if cap.t_accounts_first_and_last_bounces {
        " after the laser→wall and wall→SPAD legs are removed"
    } else {
        ""
    };
    if cap.scene_info.contains(crate::import::TIME_ZERO_NOT_WALL) {
        format!(
            "depth axis: t = 0 is not the wall (an unrectified scan), so depth is not path/2 here; f-k files: import with their tof grid ({})",
            Opt::Tof
        )
    } else if cap.scene_info.contains("medium_n:") {
        format!(
            "depth axis: the scene lies inside a diffusive medium at z > {wall_z:+.3} m (its surface); light diffuses there, so depth is not path/2: reconstruct with {}",
            Opt::Method.set("bmm")
        )
    } else if cap.kind() == murk_core::CaptureKind::Confocal {
        format!(
            "depth axis: the scene lies at z > {wall_z:+.3} m (the wall); a return at path p{legs} comes from depth p/2, so this window reaches depths {:.3}..{:.3} m",
            t.start_m.max(0.0) / 2.0,
            t.end_m().max(0.0) / 2.0
        )
    } else {
        format!(
            "depth axis: the scene lies at z > {wall_z:+.3} m (the wall); a return at path p{legs} comes from points v with |l − v| + |v − s| = p"
        )
    }
}

/// What a capture holds, one line per fact: `murk info`'s report.
pub fn describe(cap: &Capture) -> Vec<String> {
    let t = cap.time;
    let mut out = vec![
        format!("kind: {}", cap.kind()),
        side("illumination", &cap.illum),
        side("sensor", &cap.sensor),
        format!(
            "time: {} bins of {:.6} m ({:.3} ps) from {:.6} m to {:.6} m of optical path",
            t.bins,
            t.bin_width_m,
            t.bin_width_m / murk_core::SPEED_OF_LIGHT_M_PER_S * 1e12,
            t.start_m,
            t.end_m()
        ),
        format!(
            "paths include laser→wall and wall→SPAD: {}{}",
            cap.t_accounts_first_and_last_bounces,
            match (cap.laser_xyz, cap.sensor_xyz) {
                (Some(l), Some(s)) => format!(
                    " (laser at {:.3?}, SPAD at {:.3?})",
                    l.to_array(),
                    s.to_array()
                ),
                _ => String::new(),
            }
        ),
    ];
    out.push(depth_axis(cap));
    let (mut sum, mut max, mut arg) = (0f64, f32::MIN, 0usize);
    for (i, &v) in cap.h.iter().enumerate() {
        sum += v as f64;
        if v > max {
            max = v;
            arg = i;
        }
    }
    let (hist, bin) = (arg / t.bins.max(1), arg % t.bins.max(1));
    let (l, s) = cap.hist_pair(hist);
    out.push(format!(
        "H: {} histograms, sum {sum:.6e}, max {max:.6e} at illumination {l}, sensor {s}, bin {bin} (path {:.4} m)",
        cap.n_hist(),
        t.start_m + (bin as f64 + 0.5) * t.bin_width_m
    ));
    let level = cap.end_level();
    out.push(format!(
        "window end: the last 5 % of bins carry {:.1} % of the summed histogram's peak{}",
        100.0 * level,
        if level >= murk_core::window::AUTO_LEVEL {
            format!(" (cut while strong: reconstructions taper it and clear the far voxels; see {} of reconstruct)", Opt::WindowEnd)
        } else {
            String::new()
        }
    ));
    for (k, v) in crate::scene_info_summary(&cap.scene_info) {
        out.push(format!("scene_info.{k}: {v}"));
    }
    out
}
