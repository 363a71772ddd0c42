//! What the medium-aware path adds to a reconstruction on a given volume: the capture's detection
//! and the fitted removal, timed against the plain run, alternated (`-- CAPTURE VOLUME RUNS`).

use murk_recon::medium::{MediumAware, MediumRemoval};
use murk_recon::pipeline::{Method, Options, Plan, Request, VolumeSpec};

fn main() -> murk_core::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let cap = murk_io::read_capture(std::path::Path::new(&args[1]))?;
    let volume = murk_core::Volume::parse(&args[2])?;
    let runs: usize = args.get(3).and_then(|r| r.parse().ok()).unwrap_or(5);
    let method = Method::from_name("pf", cap.kind(), &Options::default())?;
    let plan_for = |removal| {
        let req = Request {
            volume: VolumeSpec::Given(volume),
            medium: MediumAware {
                removal,
                ..MediumAware::default()
            },
            ..Request::new(method)
        };
        Plan::new(&cap, &req, &murk_core::NoProgress)
    };
    let (plain, fit) = (plan_for(MediumRemoval::Off)?, plan_for(MediumRemoval::Fit)?);
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for _ in 0..runs {
        for (plan, times) in [(&plain, &mut a), (&fit, &mut b)] {
            let c = cap.clone();
            let t0 = std::time::Instant::now();
            plan.run(c, &murk_core::NoProgress)?;
            times.push(t0.elapsed().as_secs_f64());
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!(
        "plain {:.3} s, with removal {:.3} s (medians of {runs}, alternated)",
        median(&mut a),
        median(&mut b)
    );
    Ok(())
}
