//! The predicted medium response (`--medium-removal model`) against a render of the medium alone:
//! at the true parameters it removes the mean response, at wrong ones it leaves a clear residual.
//! And the depth search that the estimate ran, taken by the reconstruction only where it serves.

use murk_core::Capture;
use murk_medium::model::{predict, ModelSpec};
use murk_medium::Fixed;
use murk_recon::medium::removal::subtract_predicted;
use murk_render::{Overrides, Plan, RenderOptions, Scene};
use std::path::Path;
use std::sync::OnceLock;

/// The paper's Z scene in fog (μt = 1, α = 0.5, g = 0) with a black Z: only the medium returns light.
/// Rendered once for all the tests.
fn fog_only() -> Capture {
    static FOG: OnceLock<Capture> = OnceLock::new();
    FOG.get_or_init(render_fog_only).clone()
}

fn render_fog_only() -> Capture {
    let path = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenes/z-letter.toml"
    ));
    let ov = Overrides {
        grid: Some(16),
        bins: Some(1200),
        set: vec![
            "capture.bin_width=0.005".into(),
            "object[0].albedo=0.0".into(),
        ],
        ..Overrides::default()
    };
    let scene = Scene::load(path, &ov).unwrap();
    let opt = RenderOptions {
        spp: 256,
        seed: 7,
        shard: None,
        checkpoint: None,
        checkpoint_every: std::time::Duration::from_secs(3600),
    };
    Plan::new(&scene).render(&opt, &|_, _| {}).unwrap()
}

/// The mean histogram's residual after subtracting the model for `medium`, relative to the mean
/// histogram before (L2 over bins): averaging over histograms leaves the mean response, not noise.
fn mean_residual(cap: &Capture, medium: Fixed) -> f64 {
    let mean = |c: &Capture| -> Vec<f64> {
        let mut m = vec![0.0f64; c.time.bins];
        for i in 0..c.n_hist() {
            for (s, &v) in m.iter_mut().zip(c.histogram(i)) {
                *s += v as f64 / c.n_hist() as f64;
            }
        }
        m
    };
    let before = mean(cap);
    let mut left = cap.clone();
    let predicted = predict(cap, &medium, &ModelSpec::default()).unwrap();
    subtract_predicted(&mut left, &predicted, None).unwrap();
    let after = mean(&left);
    let l2 = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    l2(&after) / l2(&before)
}

#[test]
fn the_model_at_the_true_medium_removes_its_mean_response() {
    let cap = fog_only();
    let truth = Fixed {
        mu_t_per_m: 1.0,
        albedo: 0.5,
        g: 0.0,
    };
    let at_truth = mean_residual(&cap, truth);
    let denser = mean_residual(
        &cap,
        Fixed {
            mu_t_per_m: 1.3,
            ..truth
        },
    );
    let brighter = mean_residual(
        &cap,
        Fixed {
            albedo: 0.6,
            ..truth
        },
    );
    eprintln!("mean residual: truth {at_truth:.4}, μt 1.3 {denser:.4}, α 0.6 {brighter:.4}");
    assert!(at_truth < 0.05, "{at_truth}");
    assert!(denser > 1.8 * at_truth && brighter > 5.0 * at_truth);
}

#[test]
fn a_capture_without_a_scene_description_is_refused() {
    let mut cap = fog_only();
    cap.scene_info.clear();
    let e = predict(
        &cap,
        &Fixed {
            mu_t_per_m: 1.0,
            albedo: 0.5,
            g: 0.0,
        },
        &ModelSpec::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("no scene description"), "{e}");
}

/// A depth search run before (the estimate's, with the fitted removal) is taken by a reconstruction
/// with the model's removal and otherwise the same request; another request searches again. Here a
/// search that ran would fail (no predicted response is given for the model's removal), so success
/// says it was taken.
#[test]
fn the_estimates_depth_search_is_taken_only_where_it_serves() {
    use murk_core::NoProgress;
    use murk_methods::{search_depth, Gate, MediumGiven, Method, Options, Request, Searched};
    use murk_recon::medium::MediumRemoval;
    let cap = fog_only();
    let auto = Request::new(Method::named("pf", &Options::default()).unwrap());
    let searched = Searched::new(&cap, &auto, &NoProgress).unwrap();
    assert!(searched.found().is_some(), "a medium's capture is searched");
    let mut model = auto;
    model.medium.removal = MediumRemoval::Model;
    let given = MediumGiven {
        searched: Some(searched.clone()),
        ..MediumGiven::default()
    };
    let (chosen, found) = search_depth(&cap, &model, &given, &NoProgress).unwrap();
    assert_eq!(found.as_ref(), searched.found());
    let (again, _) = search_depth(&cap, &auto, &MediumGiven::default(), &NoProgress).unwrap();
    assert_eq!(chosen.volume, again.volume);
    // Another gate: not the request searched, so it searches, and the model's removal needs its
    // predicted response.
    let gated = Request {
        gate: Gate::At(1.0),
        ..model
    };
    let e = search_depth(&cap, &gated, &given, &NoProgress).unwrap_err();
    assert!(e.to_string().contains("predicted response"), "{e}");
    // No removal: no search applies, whatever is given.
    model.medium.removal = MediumRemoval::Off;
    assert!(search_depth(&cap, &model, &given, &NoProgress)
        .unwrap()
        .1
        .is_none());
}
