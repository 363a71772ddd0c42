//! Determinism (threads, shards, resume) and one-line errors for bad scene files.

use murk_render::{
    checkpoint_path, merge, Outputs, Overrides, Plan, RenderOptions, Scene, StoredRender,
};
use std::path::{Path, PathBuf};
use std::time::Duration;

const SCENE: &str = r#"
[relay]
kind = "wall"
size = [1.0, 1.0]
[capture]
kind = "laser-grid"
grid = [4, 3]
bins = 64
bin_width = 0.05
[render]
share_tile = 2   # tiles of 2 × 1 laser points: six work units
[medium]
mu_t = 1.0
albedo = 0.5
min = [-1.5, -1.5, 0.001]
max = [1.5, 1.5, 2.5]
[[object]]
shape = "z-letter"
center = [0.0, 0.0, 1.0]
"#;

fn scene() -> Scene {
    Scene::from_str(SCENE, Path::new("det.toml"), &Overrides::default()).unwrap()
}

fn opts(shard: Option<(usize, usize)>, checkpoint: Option<PathBuf>) -> RenderOptions {
    RenderOptions {
        spp: 64,
        seed: 42,
        shard,
        checkpoint,
        checkpoint_every: Duration::ZERO,
    }
}

fn with_threads<T: Send>(n: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
        .install(f)
}

/// Bitwise equality (not a tolerance): one thread, two threads, four shards merged, and a resumed run.
#[test]
fn seeded_render_is_bitwise_reproducible() {
    let s = scene();
    let plan = Plan::new(&s);
    let one = with_threads(1, || plan.render(&opts(None, None), &|_, _| {}).unwrap());
    let two = with_threads(2, || plan.render(&opts(None, None), &|_, _| {}).unwrap());
    assert!(one.h.iter().any(|v| *v > 0.0));
    assert_eq!(one.h, two.h);

    let parts: Vec<_> = (0..4)
        .map(|i| {
            (
                PathBuf::from(format!("part{i}")),
                plan.render(&opts(Some((i, 4)), None), &|_, _| {}).unwrap(),
            )
        })
        .collect();
    let merged = merge(&parts).unwrap();
    assert_eq!(merged.h, one.h);
    assert_eq!(merged.scene_info, one.scene_info);
    // A part read back from its file has its time axis in f32 and still merges; another bin width
    // does not.
    let mut stored = parts.clone();
    let t = &mut stored[1].1.time;
    t.bin_width_m = t.bin_width_m as f32 as f64;
    t.start_m = t.start_m as f32 as f64;
    assert_ne!(stored[1].1.time, parts[1].1.time);
    assert_eq!(merge(&stored).unwrap().h, one.h);
    stored[1].1.time.bin_width_m *= 1.0 + 1e-6;
    assert!(merge(&stored).unwrap_err().to_string().contains("part1"));
    // A missing part is refused, naming the parts given.
    assert!(merge(&parts[..3])
        .unwrap_err()
        .to_string()
        .contains("shard 3/4 is missing: the parts given are part0, part1, part2"));
    // A part whose scene_info claims an impossible shard is refused, naming it (not an index panic).
    for bad in ["4/4", "5/4", "0/0", "0/99999999999999999999", "0/1000000"] {
        let mut forged = parts.clone();
        let info = &mut forged[3].1.scene_info;
        *info = info.replace("3/4", bad);
        let err = merge(&forged).unwrap_err().to_string();
        assert!(err.contains("part3") && err.contains(bad), "{bad}: {err}");
    }
    // More shards than work units (six here) would leave shards empty: refused before rendering.
    let e = plan
        .render(&opts(Some((0, 7)), None), &|_, _| {})
        .unwrap_err()
        .to_string();
    assert!(e.contains("shard 0/7: this render has 6 work units"), "{e}");
    // Shard 2's file relabelled as shard 3 (shard 3's own file dropped): its histograms overlap
    // shard 2's, so the merge would double them.
    let mut relabelled = parts.clone();
    relabelled[3].1 = parts[2].1.clone();
    relabelled[3].1.scene_info = parts[2].1.scene_info.replace("2/4", "3/4");
    let err = merge(&relabelled).unwrap_err().to_string();
    assert!(
        err.starts_with("part3: shard 3/4 has signal in histogram")
            && err.contains("shard 2/4 holds too"),
        "{err}"
    );
    // A part whose wall points were moved belongs to another render.
    let mut moved = parts.clone();
    moved[2].1.illum.points[0].x += 0.01;
    let err = merge(&moved).unwrap_err().to_string();
    assert!(
        err.contains("part2") && err.contains("different render"),
        "{err}"
    );

    // A checkpoint cut in the middle of a record (a kill) resumes to the same numbers.
    let dir = std::env::temp_dir().join(format!("murk-render-ckpt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let ck = dir.join("c.ckpt");
    let _ = std::fs::remove_file(&ck);
    with_threads(2, || {
        plan.render(&opts(None, Some(ck.clone())), &|_, _| {})
            .unwrap()
    });
    let len = std::fs::metadata(&ck).unwrap().len();
    let f = std::fs::OpenOptions::new().write(true).open(&ck).unwrap();
    f.set_len(len / 2).unwrap();
    drop(f);
    let resumed = with_threads(2, || {
        plan.render(&opts(None, Some(ck.clone())), &|_, _| {})
            .unwrap()
    });
    assert_eq!(resumed.h, one.h);
    // Every unit twice is more than any render of this plan records: refused before reading it all.
    let whole = std::fs::read(&ck).unwrap();
    let header_len = whole.len() - 6 * (8 + 4 * 2 * 64 + 8);
    let mut twice = whole.clone();
    twice.extend_from_slice(&whole[header_len..]);
    std::fs::write(&ck, &twice).unwrap();
    let e = plan
        .render(&opts(None, Some(ck.clone())), &|_, _| {})
        .unwrap_err()
        .to_string();
    assert!(e.contains("more bytes than a checkpoint"), "{e}");
    // A record with a flipped bit (or the zeros a crash leaves) ends the valid prefix: the units from
    // there on are rendered again, and the capture is the same.
    let rec = 8 + 4 * 2 * 64 + 8;
    for damage in [|b: &mut u8| *b ^= 0x10, |b: &mut u8| *b = 0] {
        let mut bad = whole.clone();
        bad[header_len + 2 * rec + 40..header_len + 4 * rec]
            .iter_mut()
            .for_each(damage);
        std::fs::write(&ck, &bad).unwrap();
        let resumed = plan.render(&opts(None, Some(ck.clone())), &|_, _| {});
        assert_eq!(resumed.unwrap().h, one.h);
    }
    std::fs::write(&ck, &whole).unwrap();
    // A checkpoint from another seed is refused rather than mixed in.
    let mut other = opts(None, Some(ck.clone()));
    other.seed = 1;
    assert!(plan
        .render(&other, &|_, _| {})
        .unwrap_err()
        .to_string()
        .contains("different render"));
    // Cut inside its header (a kill as the render started), it holds nothing and starts afresh;
    // a damaged header is refused as such, not as another murk version's.
    let header_len = std::fs::read(&ck).unwrap().len() as u64 - 6 * (8 + 4 * 2 * 64 + 8);
    let f = std::fs::OpenOptions::new().write(true).open(&ck).unwrap();
    f.set_len(20).unwrap();
    drop(f);
    let fresh = plan.render(&opts(None, Some(ck.clone())), &|_, _| {});
    assert_eq!(fresh.unwrap().h, one.h);
    let mut bytes = std::fs::read(&ck).unwrap();
    assert_eq!(bytes.len() as u64, header_len + 6 * (8 + 4 * 2 * 64 + 8));
    bytes[24..32].copy_from_slice(&u64::MAX.to_le_bytes());
    std::fs::write(&ck, &bytes).unwrap();
    let e = plan
        .render(&opts(None, Some(ck.clone())), &|_, _| {})
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("damaged checkpoint (its header is cut short)"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Parts that hold only their checkpoint assemble into the unsharded render's bytes; an incomplete
/// part, a part of another seed and a missing part are refused naming the file; a stopped render keeps
/// every unit it finished, whatever the interval.
#[test]
fn checkpoint_parts_assemble_bitwise() {
    use std::sync::atomic::{AtomicBool, Ordering};
    let s = scene();
    let plan = Plan::new(&s);
    let one = plan.render(&opts(None, None), &|_, _| {}).unwrap();
    let dir = std::env::temp_dir().join(format!("murk-render-parts-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let never = AtomicBool::new(false);
    let part = |i: usize, n: usize| {
        let mut o = opts(Some((i, n)), Some(dir.join(format!("p{i}of{n}.ckpt"))));
        // A long interval: the part must still hold every unit when it returns.
        o.checkpoint_every = Duration::from_secs(3600);
        o
    };
    let paths: Vec<PathBuf> = (0..3)
        .map(|i| {
            let o = part(i, 3);
            plan.render_part(&o, &|_, _| {}, &never).unwrap();
            o.checkpoint.unwrap()
        })
        .collect();
    let cap = plan.assemble(64, 42, &paths).unwrap();
    assert_eq!(cap.h, one.h);
    assert_eq!(cap.scene_info, one.scene_info);
    // A complete part renders nothing more: no progress beyond its total.
    let calls = std::sync::Mutex::new(Vec::new());
    plan.render_part(
        &part(0, 3),
        &|d, t| calls.lock().unwrap().push((d, t)),
        &never,
    )
    .unwrap();
    assert_eq!(*calls.lock().unwrap(), vec![(2, 2)]);

    // A part stopped after one unit resumes from it.
    let o = part(1, 2);
    let stop = AtomicBool::new(false);
    let r = with_threads(1, || {
        plan.render_part(&o, &|d, _| stop.store(d >= 1, Ordering::Relaxed), &stop)
    });
    assert!(r.is_err());
    let calls = std::sync::Mutex::new(Vec::new());
    plan.render_part(&o, &|d, t| calls.lock().unwrap().push((d, t)), &never)
        .unwrap();
    assert_eq!(calls.lock().unwrap()[0], (1, 3));

    // Another seed's parts are refused, naming the key.
    let e = plan.assemble(64, 7, &paths).unwrap_err().to_string();
    assert!(e.contains("p0of3.ckpt") && e.contains("render.seed"), "{e}");
    // A part with a damaged record is incomplete too.
    let mut bytes = std::fs::read(&paths[2]).unwrap();
    let n = bytes.len();
    bytes[n - 100] ^= 1;
    std::fs::write(&paths[2], &bytes).unwrap();
    let e = plan.assemble(64, 42, &paths).unwrap_err().to_string();
    assert!(
        e.contains("p2of3.ckpt") && e.contains("incomplete: 1 of its 2 units"),
        "{e}"
    );
    // A part cut short (a kill mid-record) is incomplete.
    let len = std::fs::metadata(&paths[1]).unwrap().len();
    let f = std::fs::OpenOptions::new()
        .write(true)
        .open(&paths[1])
        .unwrap();
    f.set_len(len - 3).unwrap();
    drop(f);
    let e = plan.assemble(64, 42, &paths).unwrap_err().to_string();
    assert!(
        e.contains("p1of3.ckpt") && e.contains("incomplete: 1 of its 2 units"),
        "{e}"
    );
    let e = plan
        .assemble(64, 42, &[dir.join("absent.ckpt")])
        .unwrap_err()
        .to_string();
    assert!(e.contains("absent.ckpt"), "{e}");
    // A part needs its checkpoint.
    assert!(plan
        .render_part(&opts(Some((0, 3)), None), &|_, _| {}, &never)
        .is_err());

    // A finished render leaves the interval's pending units unwritten (its caller deletes the file):
    // the checkpoint holds its header alone.
    let long = |ck: &Path| RenderOptions {
        checkpoint_every: Duration::from_secs(3600),
        ..opts(None, Some(ck.to_path_buf()))
    };
    let ck = dir.join("finished.ckpt");
    assert_eq!(plan.render(&long(&ck), &|_, _| {}).unwrap().h, one.h);
    let header = std::fs::metadata(&ck).unwrap().len();
    // Stopped after its second unit, a render with the same interval keeps both.
    let ck = dir.join("stopped.ckpt");
    let stop = AtomicBool::new(false);
    let r = with_threads(1, || {
        plan.render_all_until(
            &long(&ck),
            &|done, _| stop.store(done >= 2, Ordering::Relaxed),
            &stop,
        )
    });
    assert!(r.unwrap_err().to_string().contains("stopped"));
    let unit_bytes = 8 + 4 * 2 * 64 + 8; // index, 2 laser points × 1 sensor × 64 bins, checksum
    assert_eq!(
        std::fs::metadata(&ck).unwrap().len(),
        header + 2 * unit_bytes
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Each bad input gives one line that names the file and the field.
#[test]
fn bad_scenes_name_file_and_field() {
    let cases: &[(&str, &str, &str)] = &[
        ("mu_t = 1.0", "mu_t = -1.0", "medium.mu_t"),
        ("mu_t = 1.0", "mu_t = 2e6", "medium.mu_t: is 2e6 /m"),
        ("albedo = 0.5", "albedo = 1.5", "medium.albedo"),
        ("albedo = 0.5", "albedo = 0.5\ng = 1.0", "medium.g"),
        (
            "albedo = 0.5",
            "albedo = 0.5\ng = 0.99999999",
            "medium.g: must satisfy |g| ≤ 0.9999, got 0.99999999",
        ),
        (
            "grid = [4, 3]",
            "grid = [4, 3]\nextent = [2.0, 1.0]",
            "capture.grid",
        ),
        (
            "bin_width = 0.05",
            "bin_width = 0.001",
            "capture.bins/bin_width/start",
        ),
        // Past u32 (the tails' replay converts bin indices to it), before the memory budget.
        (
            "bins = 64",
            "bins = 5000000000",
            "capture.bins: must be at most 4294967295",
        ),
        (
            "bins = 64",
            "bins = 64\nstart = 50.0",
            "capture.bins/bin_width/start",
        ),
        (
            "[render]",
            "[render]\ntime_samples = 100000",
            "render.time_samples",
        ),
        (
            "[render]",
            "[render]\ntarget_split = 5000",
            "render.target_split",
        ),
        (
            "[render]",
            "[render]\ntarget_split_radius = -0.1",
            "render.target_split_radius",
        ),
        ("share_tile = 2", "share_tile = 17", "render.share_tile"),
        (
            "[render]",
            "[render]\nhidden_geometry_sampling = 1.0",
            "render.hidden_geometry_sampling",
        ),
        (
            "[render]",
            "[render]\nfirst_time_samples = 5000",
            "render.first_time_samples",
        ),
        (
            "[render]",
            "[render]\nobject_draws = 5000",
            "render.object_draws",
        ),
        ("kind = \"wall\"", "kind = \"wal\"", "line 3"),
        ("[capture]", "[capture\n", "line"),
        (
            "shape = \"z-letter\"",
            "shape = \"mesh\"\nfile = \"missing.obj\"",
            "object[0].file",
        ),
    ];
    for (from, to, field) in cases {
        assert!(SCENE.contains(from), "{from}");
        let text = SCENE.replacen(from, to, 1);
        let text = if field.starts_with("object") {
            text.replace("center = [0.0, 0.0, 1.0]\n", "")
        } else {
            text
        };
        let e = Scene::from_str(&text, Path::new("scenes/bad.toml"), &Overrides::default())
            .expect_err(to)
            .to_string();
        assert!(
            e.starts_with("scenes/bad.toml: ") && e.contains(field),
            "{to}: {e}"
        );
        assert!(!e.contains('\n'), "{to}: multi-line error {e:?}");
    }
    // An OBJ that does not parse.
    let dir = std::env::temp_dir().join(format!("murk-render-obj-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("bad.obj"), "v 0 0 1\nv 1 0 1\nf 1 2 9\n").unwrap();
    let text = SCENE.replace(
        "shape = \"z-letter\"\ncenter = [0.0, 0.0, 1.0]",
        "shape = \"mesh\"\nfile = \"bad.obj\"",
    );
    let e = Scene::from_str(&text, &dir.join("s.toml"), &Overrides::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("object[0].file") && e.contains("bad.obj"), "{e}");
    // A vertex at 1e300 (inf as the f32 OBJ reader holds it) is named, not dropped with its triangle.
    std::fs::write(
        dir.join("bad.obj"),
        "v 0 0 1\nv 1 0 1\nv 0 1e300 1\nf 1 2 3\n",
    )
    .unwrap();
    let e = Scene::from_str(&text, &dir.join("s.toml"), &Overrides::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("vertex 3 has the coordinate inf"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--set` overrides: a bad key or value is named on one line, every override and `--grid` land in
/// scene_info, and a checkpoint of other overrides is refused naming the key that differs.
#[test]
fn overrides_are_named_recorded_and_guard_resume() {
    let load = |ov: &Overrides| Scene::from_str(SCENE, Path::new("ov.toml"), ov);
    let set = |s: &[&str]| Overrides {
        set: s.iter().map(|s| s.to_string()).collect(),
        ..Overrides::default()
    };
    for (ov, want) in [
        (
            "medium.albedox=0.8",
            "--set medium.albedox=0.8: unknown field `albedox`",
        ),
        (
            "medium.albedo=abc",
            "--set medium.albedo=abc: invalid type: string \"abc\"",
        ),
        (
            "medium.albedo=1.5",
            "medium.albedo (from --set medium.albedo=1.5): must be in [0, 1], got 1.5",
        ),
        ("object[4].albedo=1", "object[4] does not exist"),
        ("medium.ior=1000", "medium.ior (from --set medium.ior=1000): must be in [1, 4], got 1000"),
        (
            "object[0].scale=0",
            "object[0].scale (from --set object[0].scale=0): must be a finite, non-zero factor, got 0",
        ),
        (
            "object[0].scale=1e300",
            "object[0].shape: a coordinate of its bounds is -4e299 m; murk accepts magnitudes up to",
        ),
        (
            "object[0].center=[0, 0, 0]",
            "object[0].shape: lies in the relay's plane z = 0",
        ),
        ("medium", "expected KEY=VALUE"),
        ("render.spp=0", "render.spp (from --set render.spp=0): must be between 1 and"),
        (
            "medium={mu_t=1e300, albedo=0.5, min=[-1, -1, 0.1], max=[1, 1, 2]}",
            "medium.mu_t (from --set medium={mu_t=1e300, albedo=0.5, min=[-1, -1, 0.1], max=[1, 1, 2]}): is 1e300 /m, a mean free path below",
        ),
        (
            "medium.albedo=0.1\nmedium.g=0.5",
            "the value spans lines; give one KEY=VALUE per --set",
        ),
    ] {
        let e = load(&set(&[ov])).unwrap_err().to_string();
        assert!(e.starts_with("ov.toml: ") && e.contains(want), "{ov}: {e}");
        assert!(!e.contains('\n'));
    }

    // One setting from two places: whichever came last would win unseen.
    let e = load(&Overrides {
        grid: Some(8),
        ..set(&["capture.grid=[4, 4]"])
    })
    .unwrap_err()
    .to_string();
    assert!(
        e.ends_with("--set capture.grid=[4, 4]: capture.grid is also set by --grid 8"),
        "{e}"
    );
    // The override named is the one that set the value validated (the last to set it), also where
    // it set a whole table or list, or one of several keys checked together.
    for (ov, want) in [
        (
            Overrides {
                grid: Some(8),
                ..set(&["capture={kind=\"confocal\", grid=[0, 0], extent=[1.0, 1.0], bins=64, bin_width=0.05}"])
            },
            "capture.grid (from --set capture={",
        ),
        (
            set(&["medium.albedo=0.5", "medium={mu_t=1.0, albedo=1.5, min=[-1, -1, 0.1], max=[1, 1, 2]}"]),
            "medium.albedo (from --set medium={mu_t=1.0, albedo=1.5",
        ),
        (
            set(&["object=[{shape=\"box\", min=[0, 0, 1], max=[0.1, 0.1, 1.1], albedo=1.5}]"]),
            "object[0].albedo (from --set object=[{",
        ),
        (
            Overrides {
                bins: Some(1 << 40),
                ..Overrides::default()
            },
            "(from --bins 1099511627776)",
        ),
    ] {
        let e = load(&ov).unwrap_err().to_string();
        assert!(e.contains(want), "{ov:?}: {e}");
    }
    // A bad --grid is named as the flag, not only as the file's key it replaced.
    let e = load(&Overrides {
        grid: Some(0),
        ..Overrides::default()
    })
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with("ov.toml: capture.grid (from --grid 0): needs at least one point"),
        "{e}"
    );

    // No object and a medium that does not scatter: every histogram would be zero.
    let empty = SCENE.split("[[object]]").next().unwrap();
    for medium in ["medium.mu_t=0", "medium.albedo=0"] {
        let e = Scene::from_str(empty, Path::new("ov.toml"), &set(&[medium]))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with(
                "ov.toml: object: the scene has no hidden object and no scattering medium"
            ),
            "{medium}: {e}"
        );
    }
    assert!(Scene::from_str(empty, Path::new("ov.toml"), &Overrides::default()).is_ok());

    let base = load(&Overrides::default()).unwrap();
    let fog = load(&Overrides {
        grid: Some(2),
        ..set(&["medium.g=0.7", "relay.kind=diffuser"])
    })
    .unwrap();
    assert_eq!(base.source, SCENE, "no overrides: the file's own text");
    assert!(
        matches!(fog.medium.as_ref().unwrap().phase, murk_render::Phase::HenyeyGreenstein { g } if g == 0.7)
    );
    assert_eq!(fog.capture.illum.len(), 4);
    let info = murk_render::scene_info(&fog, 8, 1, None);
    for want in [
        "- \"--grid 2\"",
        "- \"--set medium.g=0.7\"",
        "grid = [2, 2]",
        "g = 0.7",
        "kind = \"diffuser\"",
    ] {
        assert!(info.contains(want), "{want} not in {info}");
    }

    let dir = std::env::temp_dir().join(format!("murk-render-ov-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let ck = dir.join("c.ckpt");
    Plan::new(&base)
        .render(&opts(None, Some(ck.clone())), &|_, _| {})
        .unwrap();
    // A resume of another render is refused on one line, naming what differs.
    let refused = |scene: Scene, o: RenderOptions| {
        let e = Plan::new(&scene)
            .render(&o, &|_, _| {})
            .unwrap_err()
            .to_string();
        assert!(!e.contains('\n'), "{e}");
        e
    };
    let resume = || opts(None, Some(ck.clone()));
    let e = refused(load(&set(&["medium.g=0.7"])).unwrap(), resume());
    assert!(
        e.contains("different render (medium.g is unset there, 0.7 now; render.medium_lobe_default is unset there, 0.3 now; render.phase_distances_default is unset there, 2 now; render.spindle_draws_default is unset there, 1 now)"),
        "{e}"
    );
    let grid = Overrides {
        grid: Some(2),
        ..Overrides::default()
    };
    let e = refused(load(&grid).unwrap(), resume());
    assert!(
        e.contains("capture.grid is [4, 3] there, [2, 2] now"),
        "{e}"
    );
    let bins = Overrides {
        bins: Some(128),
        ..Overrides::default()
    };
    let e = refused(load(&bins).unwrap(), resume());
    assert!(e.contains("capture.bins is 64 there, 128 now"), "{e}");
    let fewer = RenderOptions {
        spp: 32,
        ..resume()
    };
    let e = refused(load(&Overrides::default()).unwrap(), fewer);
    assert!(e.contains("render.spp_used is 64 there, 32 now"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A mesh's triangles are part of the render's key: an edited OBJ is refused on resume, naming the
/// mesh, while an edit that changes no triangle (a comment) resumes.
#[test]
fn an_edited_mesh_changes_the_render_key() {
    let dir = std::env::temp_dir().join(format!("murk-render-mesh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let obj = dir.join("tri.obj");
    let text = SCENE.replace(
        "shape = \"z-letter\"\ncenter = [0.0, 0.0, 1.0]",
        "shape = \"mesh\"\nfile = \"tri.obj\"",
    );
    let load = || Scene::from_str(&text, &dir.join("s.toml"), &Overrides::default()).unwrap();
    std::fs::write(&obj, "v -0.3 -0.3 1\nv 0.3 -0.3 1\nv 0 0.3 1\nf 1 2 3\n").unwrap();
    let ck = dir.join("c.ckpt");
    let first = Plan::new(&load())
        .render(&opts(None, Some(ck.clone())), &|_, _| {})
        .unwrap();
    // A comment changes the file but not one triangle: the checkpoint is taken up again.
    std::fs::write(
        &obj,
        "# a comment\nv -0.3 -0.3 1\nv 0.3 -0.3 1\nv 0 0.3 1\nf 1 2 3\n",
    )
    .unwrap();
    let again = Plan::new(&load())
        .render(&opts(None, Some(ck.clone())), &|_, _| {})
        .unwrap();
    assert_eq!(again.h, first.h);
    // The triangle moved 1 cm: another render.
    std::fs::write(&obj, "v -0.3 -0.3 1.01\nv 0.3 -0.3 1\nv 0 0.3 1\nf 1 2 3\n").unwrap();
    let moved = load();
    let e = Plan::new(&moved)
        .render(&opts(None, Some(ck.clone())), &|_, _| {})
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("different render (object[0].surfaces_fnv1a is "),
        "{e}"
    );
    assert!(moved.resolved.contains("object[0].file = \"tri.obj\""));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `capture.device_radiometry`: the same paths (same seed), each histogram scaled by the laser's
/// cos/d² at its laser point times the SPAD's cos/d² at its sensor point; refused without devices.
#[test]
fn device_radiometry_scales_each_histogram_by_its_legs() {
    let with_devices = |on: bool| {
        let ov = Overrides {
            set: vec![
                "capture.laser_position=[0.3, 0.0, 0.5]".into(),
                "capture.spad_position=[-0.2, 0.1, 0.4]".into(),
                format!("capture.device_radiometry={on}"),
            ],
            ..Overrides::default()
        };
        Scene::from_str(SCENE, Path::new("dev.toml"), &ov).unwrap()
    };
    let (off, on) = (with_devices(false), with_devices(true));
    let render = |s: &Scene| Plan::new(s).render(&opts(None, None), &|_, _| {}).unwrap();
    let (a, b) = (render(&off), render(&on));
    let (laser, spad) = (
        murk_core::DVec3::new(0.3, 0.0, 0.5),
        murk_core::DVec3::new(-0.2, 0.1, 0.4),
    );
    let leg = |dev: murk_core::DVec3, p: murk_core::DVec3| {
        let v = dev - p;
        v.z.abs() / v.length().powi(3)
    };
    let mut compared = 0;
    for i in 0..a.n_hist() {
        let (l, s) = a.hist_pair(i);
        let f = leg(laser, a.illum.points[l]) * leg(spad, a.sensor.points[s]);
        for (x, y) in a.histogram(i).iter().zip(b.histogram(i)) {
            if *x != 0.0 {
                assert!(((*y as f64) / (*x as f64) / f - 1.0).abs() < 1e-5);
                compared += 1;
            }
        }
    }
    assert!(compared > 100, "only {compared} non-zero bins");
    let e = Scene::from_str(
        SCENE,
        Path::new("dev.toml"),
        &Overrides {
            set: vec!["capture.device_radiometry=true".into()],
            ..Overrides::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("capture.device_radiometry") && e.contains("laser_position"),
        "{e}"
    );
}

/// Shards deal out every unit exactly once, in shares that differ by at most one unit, and each
/// shard of two or more reaches both halves of the wall (a shard is not one stripe of it).
#[test]
fn shards_partition_the_units_evenly() {
    let text = SCENE
        .replace("grid = [4, 3]", "grid = [16, 12]")
        .replace("share_tile = 2", "share_tile = 1");
    let scene = Scene::from_str(&text, Path::new("det.toml"), &Overrides::default()).unwrap();
    let plan = Plan::new(&scene);
    let n = plan.n_units();
    assert_eq!(plan.shard_units(None), (0..n).collect::<Vec<_>>());
    for k in 1..=7 {
        let shards: Vec<Vec<usize>> = (0..k).map(|i| plan.shard_units(Some((i, k)))).collect();
        let mut all: Vec<usize> = shards.concat();
        all.sort();
        assert_eq!(all, (0..n).collect::<Vec<_>>(), "{k} shards");
        let sizes: Vec<usize> = shards.iter().map(Vec::len).collect();
        assert!(
            sizes.iter().max().unwrap() - sizes.iter().min().unwrap() <= 1,
            "{sizes:?}"
        );
        for s in shards.iter().filter(|_| k > 1) {
            let low = s.iter().filter(|&&u| u < n / 2).count();
            assert!(
                low > 0 && low < s.len(),
                "{k} shards: {s:?} lies in one half"
            );
        }
    }
}

/// `render_stored` hands each capture to the writer and then removes the checkpoint; a failed write
/// keeps it with every unit, so a resume renders nothing twice. Absurd spp and checkpoint intervals are refused in one line.
#[test]
fn stored_renders_drop_their_checkpoint_only_once_written() {
    use std::sync::atomic::AtomicBool;
    use std::sync::Mutex;
    let s = scene();
    let plan = Plan::new(&s);
    let never = AtomicBool::new(false);
    let dir = std::env::temp_dir().join(format!("murk-render-stored-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let ck = dir.join("s.ckpt");
    let out = dir.join("s.h5");
    let written = Mutex::new(Vec::new());
    let caps = plan
        .render_stored(
            &opts(None, Some(ck.clone())),
            std::slice::from_ref(&out),
            &|p, c| {
                written.lock().unwrap().push((p.to_path_buf(), c.h.clone()));
                Ok(())
            },
            &|_, _| {},
            &never,
        )
        .unwrap();
    let written = written.into_inner().unwrap();
    assert_eq!(written.len(), 1);
    assert_eq!((&written[0].0, &written[0].1), (&out, &caps[0].h));
    assert!(!ck.exists(), "the checkpoint outlived the stored capture");

    // Even with no append during the render (an interval longer than it), a failed write leaves
    // every unit in the checkpoint: the resume starts with all of them done.
    let mut rare = opts(None, Some(ck.clone()));
    rare.checkpoint_every = Duration::MAX;
    let failed = plan.render_stored(
        &rare,
        std::slice::from_ref(&out),
        &|p, _| Err(murk_core::Error::io(p, std::io::Error::other("disk full"))),
        &|_, _| {},
        &never,
    );
    assert!(failed.unwrap_err().to_string().contains("disk full"));
    assert!(ck.exists(), "a failed write removed the checkpoint");
    let first = Mutex::new(None);
    let resumed = plan
        .render(&rare, &|done, total| {
            first.lock().unwrap().get_or_insert((done, total));
        })
        .unwrap();
    assert_eq!(first.into_inner().unwrap(), Some((6, 6)));
    assert_eq!(resumed.h, caps[0].h);
    // Two outputs for one capture are refused before rendering.
    let two = [out.clone(), dir.join("t.h5")];
    let e = plan.render_stored(&rare, &two, &|_, _| Ok(()), &|_, _| {}, &never);
    assert!(e
        .unwrap_err()
        .to_string()
        .ends_with("2 outputs for a render of 1 capture"));
    std::fs::remove_dir_all(&dir).unwrap();

    let mut huge = opts(None, None);
    huge.spp = murk_core::Limits::MAX_SPP + 1;
    let e = plan.render(&huge, &|_, _| {}).unwrap_err().to_string();
    assert!(e.contains("spp must be between 1 and"), "{e}");
    assert_eq!(
        murk_render::checkpoint_interval(0.0).unwrap(),
        Duration::ZERO
    );
    assert_eq!(
        murk_render::checkpoint_interval(1.5).unwrap(),
        Duration::from_millis(1500)
    );
    for bad in [-1.0, f64::NAN, f64::INFINITY, 1e300] {
        assert!(murk_render::checkpoint_interval(bad).is_err(), "{bad}");
    }
    assert!(plan.spp_for_budget(f64::INFINITY, None).is_err());
    assert!(plan.spp_for_budget(0.0, None).is_err());
    // A thousand times the budget buys more paths (the pilot's timing noise is far below 1000×).
    let small = plan.spp_for_budget(0.01, None).unwrap();
    let large = plan.spp_for_budget(10.0, None).unwrap();
    assert!(large > 10 * small, "{small} vs {large}");
}

/// A fresh `StoredRender` removes a stale `out.ckpt` (one that would not even parse) and leaves only
/// its capture; a resume with no checkpoint and no interval keeps none; a named checkpoint over the
/// output is refused before any work.
#[test]
fn stored_renders_keep_and_drop_their_checkpoint() {
    use std::sync::atomic::AtomicBool;
    let s = scene();
    let dir = std::env::temp_dir().join(format!("murk-stored-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("s.h5");
    let ckpt = checkpoint_path(&out);
    std::fs::write(&ckpt, b"not a checkpoint").unwrap();
    let beside = |resume, every_s| Outputs::Beside {
        out: &out,
        resume,
        every_s,
    };
    let fresh = StoredRender::new(&s, None, None, beside(false, 60.0)).unwrap();
    assert_eq!(fresh.checkpoint(), Some(ckpt.as_path()));
    let never = AtomicBool::new(false);
    let caps = fresh
        .run(&fresh.options(2, 1, None), &|_, _| {}, &never)
        .unwrap();
    assert!(!ckpt.exists(), "a checkpoint outlived the stored capture");
    assert_eq!(murk_io::read_capture(&out).unwrap().h, caps[0].h);

    let resumed = StoredRender::new(&s, None, None, beside(true, 0.0)).unwrap();
    assert_eq!(resumed.checkpoint(), None);

    let over = Outputs::Named {
        out: Some(&out),
        checkpoint: Some(&out),
        every_s: 0.0,
    };
    let e = StoredRender::new(&s, None, None, over).err().unwrap();
    assert!(
        e.to_string()
            .ends_with("the checkpoint and the output are the same file"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
