//! The medium-aware defaults of `murk reconstruct` and `murk medium` on captures whose answer the code
//! was not told (docs/medium.md): the renderer's ground truth (`--truth`) scores them.

#[path = "common/cli.rs"]
mod cli;
use cli::{murk, ok, s, temp_dir};

fn row<'a>(summary: &'a str, key: &str) -> &'a str {
    summary
        .lines()
        .find_map(|l| l.trim().strip_prefix(&format!("{key}: ")))
        .unwrap_or_else(|| panic!("no {key} in {summary}"))
}

/// The depth of the summary's peak (m).
fn peak_z(summary: &str) -> f64 {
    row(summary, "peak")
        .rsplit("z ")
        .next()
        .unwrap()
        .trim_end_matches(" m")
        .parse()
        .unwrap()
}

/// The Z of the paper 2 m behind the diffuser in fog (μt = 1, α = 0.5; 64² laser points, 1 200 bins
/// of 5 mm from 1 m): with no flags the medium is detected, its response removed and the depth range
/// found, so the peak is on the Z (2.0 m ± 5 cm) and the front view's best-threshold IoU against the
/// renderer's ground truth is at least 0.5 (0.69 measured; 0.31 without the medium-aware path, its
/// peak on the fog at 0.44 m).
#[test]
fn the_z_in_fog_is_found_without_flags() {
    let d = temp_dir("medium-z");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/z-letter.toml");
    let (cap, truth, vol) = (d.join("z.h5"), d.join("truth.h5"), d.join("v.npy"));
    ok(&[
        "render",
        "-q",
        scene,
        "--out",
        s(&cap),
        "--grid",
        "64",
        "--bins",
        "1200",
        "--set",
        "capture.bin_width=0.005",
        "--truth",
        s(&truth),
    ]);
    let summary = ok(&["reconstruct", s(&cap), "--out", s(&vol)]);
    assert!(row(&summary, "medium").starts_with("detected"), "{summary}");
    let z = peak_z(&summary);
    assert!((z - 2.0).abs() <= 0.05, "{summary}");
    let (shape, _) = murk_io::read_npy_f32(&vol).unwrap();
    let t = murk_io::read_truth_h5(&truth).unwrap();
    assert_eq!(
        shape[..2],
        [t.x_m.len(), t.y_m.len()],
        "the default volume is the wall grid"
    );
    let mask: Vec<bool> = t.object.iter().map(|&o| o >= 0).collect();
    let front_iou = |vol: &std::path::Path| {
        let (shape, v) = murk_io::read_npy_f32(vol).unwrap();
        let front: Vec<f32> = v
            .chunks_exact(shape[2])
            .map(|col| col.iter().copied().fold(0.0, f32::max))
            .collect();
        murk_study::metrics::iou_scores(&front, &mask).best
    };
    let iou = front_iou(&vol);
    assert!(iou >= 0.5, "front-view IoU {iou}: {summary}");

    // The model removal (the medium's response rendered for the true μt and α) does as well (IoU
    // 0.69 measured).
    let model = ok(&[
        "reconstruct",
        s(&cap),
        "--out",
        s(&vol),
        "--medium-removal",
        "model",
        "--mu-t",
        "1",
        "--albedo",
        "0.5",
    ]);
    assert!(
        row(&model, "medium").contains("rendered for μt 1 /m, albedo 0.5, g 0"),
        "{model}"
    );
    assert!((peak_z(&model) - 2.0).abs() <= 0.05, "{model}");
    let iou = front_iou(&vol);
    assert!(
        iou >= 0.5,
        "front-view IoU with the model removal {iou}: {model}"
    );

    // Without the medium-aware path the fog near the wall wins, as before it.
    let plain = ok(&[
        "reconstruct",
        s(&cap),
        "--out",
        s(&vol),
        "--medium-removal",
        "off",
        "--depth-search",
        "off",
    ]);
    let plain_z = peak_z(&plain);
    assert!(plain_z < 1.0, "{plain}");
    std::fs::remove_dir_all(&d).ok();
}

/// A capture without a medium reconstructs byte for byte as with the medium-aware path off, with the
/// same summary: nothing is detected, so nothing is removed or searched. The shelf's closed room
/// without fog (16², 1 024 spp) is one: its walls meet the relay and answer every histogram from the
/// window's start, its histograms of equal separation agree about as well as fog's do, but its
/// response fades more slowly than 1/path², where fog's falls at least as fast (docs/medium.md).
#[test]
fn captures_without_a_medium_are_unchanged() {
    let d = temp_dir("medium-clear");
    let cap = d.join("z.h5");
    ok(&[
        "synth",
        "--out",
        s(&cap),
        "--kind",
        "laser-grid",
        "--wall-size",
        "2",
        "--grid",
        "32",
        "--bins",
        "1024",
        "--bin-width",
        "0.004",
        "--start",
        "3.0",
        "--target",
        "z:2.0",
    ]);
    let render = d.join("clear.h5");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/z-letter.toml");
    ok(&[
        "render",
        "-q",
        scene,
        "--out",
        s(&render),
        "--grid",
        "16",
        "--bins",
        "600",
        "--set",
        "capture.bin_width=0.01",
        "--set",
        "medium.mu_t=0",
        "--spp",
        "16",
    ]);
    let room = d.join("room.h5");
    let shelf = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/shelf.toml");
    ok(&[
        "render",
        "-q",
        shelf,
        "--out",
        s(&room),
        "--grid",
        "16",
        "--bins",
        "1200",
        "--set",
        "capture.bin_width=0.005",
        "--set",
        "medium.mu_t=0",
        "--spp",
        "1024",
    ]);
    for c in [&cap, &render, &room] {
        let (a, b) = (d.join("a.npy"), d.join("b.npy"));
        let with = ok(&["reconstruct", s(c), "--out", s(&a)]);
        let without = ok(&[
            "reconstruct",
            s(c),
            "--out",
            s(&b),
            "--medium-removal",
            "off",
            "--depth-search",
            "off",
        ]);
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
        let drop_time = |t: &str| -> Vec<String> {
            t.lines()
                .filter(|l| !l.contains("seconds:") && !l.starts_with("wrote"))
                .map(String::from)
                .collect()
        };
        assert_eq!(drop_time(&with), drop_time(&without));
        assert!(!with.contains("medium:") && !with.contains("depth search"));
    }
    // murk medium answers that it sees none, not a fit to noise; a compensation without μt cannot
    // be estimated then.
    for c in [&render, &room] {
        let out = ok(&["medium", s(c)]);
        assert!(out.starts_with("no medium detected"), "{out}");
    }
    let v = d.join("v.npy");
    let (code, _, err) = murk(&[
        "reconstruct",
        s(&render),
        "--out",
        s(&v),
        "--compensate",
        "ballistic",
    ]);
    assert_ne!(code, 0);
    assert!(
        err.contains("no medium detected") && err.contains("--mu-t") && err.contains("clear.h5"),
        "{err}"
    );
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    std::fs::remove_dir_all(&d).ok();
}

/// `murk medium` on the T in fog (μt = 1, α = 0.5, g = 0; 32² sensor points), g given and g free: μt
/// and α within 10 %, g within 0.15 (docs/medium.md has the sweep); `--json` is one object with the
/// documented keys.
#[test]
fn the_medium_of_the_fog_is_estimated() {
    let d = temp_dir("medium-estimate");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/t-wall-medium.toml");
    let cap = d.join("fog.h5");
    ok(&["render", "-q", scene, "--out", s(&cap), "--spp", "64"]);
    let args = [
        "medium",
        s(&cap),
        "--json",
        "--fit",
        "mu_t,albedo",
        "--g",
        "0",
    ];
    let json = ok(&args);
    let value = |key: &str| json_number(&json, key);
    for key in [
        "mu_t_per_m_uncertainty",
        "albedo_uncertainty",
        "g_uncertainty",
        "residual_rms_ln",
    ] {
        assert!(value(key).is_finite(), "{key}: {json}");
    }
    assert!((value("mu_t_per_m") - 1.0).abs() <= 0.1, "{json}");
    assert!((value("albedo") - 0.5).abs() <= 0.05, "{json}");
    assert_eq!(value("g"), 0.0);
    // With --table-cache the table is rendered by the first call and read back by the second: both
    // answer exactly as the call without it.
    let tables = d.join("tables");
    for _ in 0..2 {
        let cached = ok(&[&args[..], &["--table-cache", s(&tables)]].concat());
        assert_eq!(cached, json);
        assert_eq!(std::fs::read_dir(&tables).unwrap().count(), 1);
    }
    // Every parameter free (the default; a given g is interpolated between the same g nodes, so the
    // table is the same, read back): μt and α within 10 %, g within 0.15.
    let free = ok(&["medium", s(&cap), "--json", "--table-cache", s(&tables)]);
    let free_value = |key: &str| json_number(&free, key);
    assert!((free_value("mu_t_per_m") - 1.0).abs() <= 0.1, "{free}");
    assert!((free_value("albedo") - 0.5).abs() <= 0.05, "{free}");
    assert!(free_value("g").abs() <= 0.15, "{free}");
    // --compensate without --mu-t takes the estimate (every parameter free; its table read back) and
    // says so.
    let v = d.join("v.npy");
    let summary = ok(&[
        "reconstruct",
        s(&cap),
        "--out",
        s(&v),
        "--compensate",
        "paper",
        "--table-cache",
        s(&tables),
    ]);
    let line = summary
        .lines()
        .find(|l| l.contains("compensated with: μt"))
        .unwrap_or_else(|| panic!("{summary}"));
    let mu: f64 = line
        .split("μt ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!((mu - 1.0).abs() <= 0.2, "{line}");
    std::fs::remove_dir_all(&d).ok();
}

/// `murk medium` on the T in an exponential height fog (σt = 2 /m × exp(−(y + 1.5 m)/2 m), 0.94 /m at
/// the wall's centre; α = 0.5, g = 0 given; 16² sensor points, 64 spp, seed 2) keeps the fog's shape
/// in its forward model: μt, σt where the density is 1, and α within 10 % (1.88 and 0.51 measured;
/// one homogeneous μt fitted 0.99, −51 %). `--compensate` and `--medium-removal model` then take the
/// estimate as the fog's scale, and nothing warns of a homogeneous medium.
#[test]
fn the_scale_of_a_height_fog_is_estimated() {
    let d = temp_dir("medium-height");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/t-wall-medium.toml");
    let cap = d.join("haze.h5");
    let set = [
        "--set",
        "medium.kind=height",
        "--set",
        "medium.height_scale=2.0",
        "--set",
        "medium.mu_t=2.0",
    ];
    let render = ["render", "-q", scene, "--out", s(&cap), "--grid", "16"];
    ok(&[&render[..], &["--spp", "64", "--seed", "2"], &set].concat());
    let tables = d.join("tables");
    let args = [
        "medium",
        s(&cap),
        "--fit",
        "mu_t,albedo",
        "--g",
        "0",
        "--table-cache",
        s(&tables),
    ];
    let json = ok(&[&args[..], &["--json"]].concat());
    let value = |key: &str| json_number(&json, key);
    assert!((value("mu_t_per_m") / 2.0 - 1.0).abs() <= 0.1, "{json}");
    assert!((value("albedo") / 0.5 - 1.0).abs() <= 0.1, "{json}");
    let said = "μt is σt where the density is 1 (the capture's height fog, height_scale 2 m)";
    assert!(json.contains(&format!("\"density\": \"{said}\"")), "{json}");
    let (code, summary, err) = murk(&args);
    assert_eq!(code, 0, "{err}");
    assert!(summary.contains(&format!("density: {said}")), "{summary}");
    assert!(!err.contains("homogeneous"), "{err}");
    let v = d.join("v.npy");
    let (code, summary, err) = murk(&[
        "reconstruct",
        s(&cap),
        "--out",
        s(&v),
        "--compensate",
        "ballistic",
        "--medium-removal",
        "model",
        "--table-cache",
        s(&tables),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        row(&summary, "compensated along").contains("the height fog of the capture's scene")
            && summary.contains(said),
        "{summary}"
    );
    assert!(!err.contains("homogeneous"), "{err}");
    std::fs::remove_dir_all(&d).ok();
}

/// The number after `"key": ` in `json`.
fn json_number(json: &str, key: &str) -> f64 {
    let at = json
        .find(&format!("\"{key}\": "))
        .unwrap_or_else(|| panic!("{key}: {json}"));
    json[at + key.len() + 4..]
        .split([',', '}'])
        .next()
        .unwrap()
        .trim()
        .parse()
        .unwrap()
}

/// Bad input: a file that is not a capture, a capture without a scene description, an impossible
/// span of medium-only bins: one line naming the file, exit ≠ 0.
#[test]
fn bad_input_is_one_line() {
    let d = temp_dir("medium-bad");
    let junk = d.join("junk.h5");
    std::fs::write(&junk, b"not hdf5").unwrap();
    let (code, _, err) = murk(&["medium", s(&junk)]);
    assert_ne!(code, 0);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("junk.h5"), "{err}");

    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/t-wall-medium.toml");
    let cap = d.join("fog.h5");
    ok(&[
        "render",
        "-q",
        scene,
        "--out",
        s(&cap),
        "--spp",
        "4",
        "--grid",
        "8",
    ]);
    let (code, _, err) = murk(&["medium", s(&cap), "--until", "-1"]);
    assert_ne!(code, 0);
    assert!(
        err.contains("fog.h5") && err.contains("before the capture's window starts"),
        "{err}"
    );
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    let (code, _, err) = murk(&["medium", s(&cap), "--fit", "mu_s"]);
    assert_ne!(code, 0);
    assert!(err.contains("mu_s"), "{err}");
    std::fs::remove_dir_all(&d).ok();
}
