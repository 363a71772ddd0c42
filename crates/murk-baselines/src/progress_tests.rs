//! The confocal methods' progress, of their plans and of their runs: each bar ends exactly at the
//! total it announced, and a caller that asks to stop part-way gets an error, not a plan or a
//! partial volume.

use crate::testutil::{add_point, axis, confocal, Recorder};
use crate::{
    CdtParams, CdtPlan, DlctParams, DlctPlan, FkParams, FkPlan, LctParams, LctPlan, Reconstruction,
};
use murk_core::{Capture, DVec3, NoProgress, Progress, Result};
use std::sync::atomic::Ordering::Relaxed;

type Run = Box<dyn Fn(&Capture, &dyn Progress) -> Result<Reconstruction>>;

/// Each method planned for `c`, with the word its stop error starts with.
fn methods(c: &Capture) -> Vec<(&'static str, Run)> {
    let lct = LctPlan::new(c, LctParams::default(), &NoProgress).unwrap();
    let fk = FkPlan::new(c, FkParams::default()).unwrap();
    let cdt = CdtPlan::new(c, CdtParams::default(), &NoProgress).unwrap();
    let dlct = DlctPlan::new(c, DlctParams::default(), &NoProgress).unwrap();
    vec![
        ("light-cone", Box::new(move |c, p| lct.run(c, p))),
        (
            "directional light-cone",
            Box::new(move |c, p| dlct.run(c, p)),
        ),
        ("f-k", Box::new(move |c, p| fk.run(c, p))),
        ("confocal diffuse", Box::new(move |c, p| cdt.run(c, p))),
    ]
}

fn capture() -> Capture {
    let mut c = confocal(16, 0.64, axis(0.0, 0.01, 128));
    add_point(&mut c, DVec3::new(0.02, -0.02, 0.4));
    c
}

#[test]
fn each_bar_ends_at_its_total() {
    let c = capture();
    for (name, run) in methods(&c) {
        let p = Recorder::new(u64::MAX);
        let full = run(&c, &p).unwrap();
        let (total, done) = (p.total.load(Relaxed), p.done.load(Relaxed));
        assert!(total > 0 && done == total, "{name}: {done} of {total}");
        // Reporting progress changes nothing in the result.
        let quiet = run(&c, &NoProgress).unwrap();
        assert_eq!(full.intensity, quiet.intensity, "{name}");
    }
}

#[test]
fn a_stop_part_way_is_an_error() {
    let c = capture();
    for (name, run) in methods(&c) {
        // The first pass is a thousand units: stop a third of the way through it.
        let p = Recorder::new(333);
        let e = run(&c, &p).unwrap_err().to_string();
        assert!(e.starts_with(name) && e.ends_with("stopped"), "{name}: {e}");
        assert!(p.done.load(Relaxed) < p.total.load(Relaxed), "{name}");
    }
}

type MakePlan = Box<dyn Fn(&Capture, &dyn Progress) -> Result<()>>;

/// The methods whose plans report progress (f-k's plans only its FFTs), with the word their stop
/// error starts with.
fn plans() -> Vec<(&'static str, MakePlan)> {
    vec![
        (
            "light-cone",
            Box::new(|c, p| LctPlan::new(c, LctParams::default(), p).map(drop)),
        ),
        (
            "confocal diffuse",
            Box::new(|c, p| CdtPlan::new(c, CdtParams::default(), p).map(drop)),
        ),
        (
            "directional light-cone",
            Box::new(|c, p| DlctPlan::new(c, DlctParams::default(), p).map(drop)),
        ),
    ]
}

#[test]
fn plans_report_their_bar_and_stop_part_way() {
    let c = capture();
    for (name, plan) in plans() {
        let p = Recorder::new(u64::MAX);
        plan(&c, &p).unwrap();
        let (total, done) = (p.total.load(Relaxed), p.done.load(Relaxed));
        assert!(total > 0 && done == total, "{name}: {done} of {total}");
        let p = Recorder::new(333);
        let e = plan(&c, &p).unwrap_err().to_string();
        assert!(e.starts_with(name) && e.ends_with("stopped"), "{name}: {e}");
        assert!(p.done.load(Relaxed) < p.total.load(Relaxed), "{name}");
    }
}
