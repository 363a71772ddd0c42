//! An albedo sweep renders, from one set of paths, the capture each albedo's own render gives: the
//! sampling does not depend on the albedo in a scattering medium, so the captures agree to float
//! rounding, not just within the Monte Carlo error.

use murk_render::{Overrides, Plan, RenderOptions, Scene};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Duration;

/// A wall relay (surface vertices on the relay and the Z), fog in front of it, tiles of 2 × 2 laser
/// points sharing their tails, and every medium technique on.
const SCENE: &str = r#"
[relay]
kind = "wall"
size = [1.0, 1.0]
[capture]
kind = "laser-grid"
grid = [4, 4]
bins = 96
bin_width = 0.05
start = 1.0
[render]
share_tile = 2
time_samples = 2
object_draws = 1
[medium]
mu_t = 1.0
albedo = 0.5
min = [-1.5, -1.5, 0.001]
max = [1.5, 1.5, 2.5]
[[object]]
shape = "z-letter"
center = [0.0, 0.0, 1.0]
"#;

fn scene(set: &[String]) -> Scene {
    let ov = Overrides {
        set: set.to_vec(),
        ..Overrides::default()
    };
    Scene::from_str(SCENE, Path::new("sweep.toml"), &ov).unwrap()
}

fn opts(checkpoint: Option<PathBuf>) -> RenderOptions {
    RenderOptions {
        spp: 16,
        seed: 9,
        shard: None,
        checkpoint,
        checkpoint_every: Duration::ZERO,
    }
}

/// Relative L2 difference of `a` from `b`.
fn rel(a: &[f32], b: &[f32]) -> f64 {
    let (mut d, mut n) = (0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        d += (*x as f64 - *y as f64).powi(2);
        n += (*y as f64).powi(2);
    }
    (d / n).sqrt()
}

/// Each albedo of the sweep against its own render with the same seed: isotropic and forward fog, and
/// an albedo above the scene's own (ratios above 1), and a sweep of one albedo. A contribution
/// credited with one scattering event too many or too few is off by a factor of 0.3–1.66 and fails by
/// orders of magnitude.
#[test]
fn sweep_matches_each_albedo_rendered_alone() {
    let three = [0.15, 0.5, 0.83];
    for (g, albedos) in [
        ("0.0", &three[..]),
        ("0.7", &three[..]),
        ("0.0", &[0.83][..]),
    ] {
        let base = [format!("medium.g={g}")];
        let s = scene(&base);
        let never = AtomicBool::new(false);
        let caps = Plan::sweep(&s, albedos)
            .unwrap()
            .render_all_until(&opts(None), &|_, _| {}, &never)
            .unwrap();
        assert_eq!(caps.len(), albedos.len());
        for (a, cap) in albedos.iter().zip(&caps) {
            let mut set = base.to_vec();
            set.push(format!("medium.albedo={a}"));
            let alone_scene = scene(&set);
            let alone = Plan::new(&alone_scene)
                .render(&opts(None), &|_, _| {})
                .unwrap();
            let e = rel(&cap.h, &alone.h);
            assert!(e < 1e-6, "g = {g}, α = {a}: relative difference {e}");
            assert!(cap.scene_info.contains(&format!("albedo: {a:?}")));
        }
        // The albedos really differ: the sweep is not one capture repeated.
        assert!(caps.len() == 1 || rel(&caps[0].h, &caps[2].h) > 0.1);
    }
}

/// A sweep's checkpoint resumes to the same captures, and refuses a plain render of the same scene.
#[test]
fn sweep_checkpoint_resumes_and_is_its_own() {
    let s = scene(&[]);
    let dir = std::env::temp_dir().join(format!("murk-sweep-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let ck = dir.join("sweep.ckpt");
    let plan = Plan::sweep(&s, &[0.33, 0.67]).unwrap();
    let never = AtomicBool::new(false);
    let first = plan
        .render_all_until(&opts(Some(ck.clone())), &|_, _| {}, &never)
        .unwrap();
    // The checkpoint now holds every unit: a resumed render starts with all of them done and gives
    // the same bytes.
    let start = std::sync::Mutex::new(None);
    let again = plan
        .render_all_until(
            &opts(Some(ck.clone())),
            &|done, total| {
                start.lock().unwrap().get_or_insert((done, total));
            },
            &never,
        )
        .unwrap();
    let (done, total) = start.into_inner().unwrap().unwrap();
    assert_eq!(done, total);
    for (a, b) in first.iter().zip(&again) {
        assert_eq!(a.h, b.h);
    }
    let e = Plan::new(&s)
        .render(&opts(Some(ck.clone())), &|_, _| {})
        .unwrap_err()
        .to_string();
    assert!(e.contains("render.albedo_sweep"), "{e}");
    // A plain call on a sweep is refused rather than dropping captures.
    assert!(plan.render(&opts(None), &|_, _| {}).is_err());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_sweeps_are_refused() {
    let s = scene(&[]);
    let msg = |albedos: &[f64]| Plan::sweep(&s, albedos).err().unwrap().to_string();
    assert!(msg(&[]).contains("1 to 16"));
    assert!(msg(&[0.5, 1.5]).contains("albedo 1.5"));
    assert!(msg(&[f64::NAN]).contains("NaN"));
    assert!(msg(&[0.5, 0.0]).contains("albedo 0 of the sweep"));
    assert!(msg(&[0.5; 17]).contains("got 17"));
    let roulette = scene(&["render.rr_depth=8".into()]);
    let e = Plan::sweep(&roulette, &[0.5]).err().unwrap().to_string();
    assert!(e.contains("render.rr_depth"), "{e}");
    assert!(msg(&[0.5, 0.2, 0.5]).contains("albedo 0.5 appears twice"));
    let clear = scene(&["medium.mu_t=0.0".into()]);
    let e = Plan::sweep(&clear, &[0.5]).err().unwrap().to_string();
    assert!(e.contains("scattering medium"), "{e}");
}

/// A sweep's file names: the albedo as written, or in exponent form when it is tiny (1e-300 as
/// written has 300 digits, more than a file name may hold).
#[test]
fn sweep_outputs_are_named_by_albedo() {
    let name = |a: f64| murk_render::sweep_output(Path::new("d/z.h5"), a);
    assert_eq!(name(0.83), Path::new("d/z-albedo0.83.h5"));
    assert_eq!(name(0.0), Path::new("d/z-albedo0.h5"));
    assert_eq!(name(1e-300), Path::new("d/z-albedo1e-300.h5"));
}
