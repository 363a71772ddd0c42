//! Ground truth against the scene geometry, computed here independently of the renderer's ray casting:
//! the first surface along +z from a relay point is the nearest front face whose footprint contains it.

use murk_core::DVec3;
use murk_render::{Overrides, Scene};
use std::path::{Path, PathBuf};

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name)
}

/// Crossing-number point-in-polygon test.
fn inside(poly: &[[f64; 2]], x: f64, y: f64) -> bool {
    let mut c = false;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        if (a[1] > y) != (b[1] > y) && x < a[0] + (y - a[1]) * (b[0] - a[0]) / (b[1] - a[1]) {
            c = !c;
        }
    }
    c
}

#[test]
fn z_letter_truth_is_exact_at_pixel_centres() {
    let scene = Scene::load(&scene_path("z-letter.toml"), &Overrides::default()).unwrap();
    let t = scene.ground_truth();
    assert_eq!(t.shape(), [128, 128]);
    assert_eq!(t.object_names, ["object[0] (z-letter)"]);
    let z = murk_synth::z_letter_outline();
    let mut hits = 0;
    for (ix, &x) in t.x_m.iter().enumerate() {
        for (iy, &y) in t.y_m.iter().enumerate() {
            let k = ix * t.y_m.len() + iy;
            if inside(&z, x, y) {
                hits += 1;
                assert_eq!(t.depth_m[k], 2.0, "({x}, {y})");
                assert_eq!(t.object[k], 0);
            } else {
                assert!(t.depth_m[k].is_nan(), "({x}, {y}): {}", t.depth_m[k]);
                assert_eq!(t.object[k], -1);
            }
        }
    }
    // The pixels seen cover the letter's area (shoelace) to within its pixel fringe: the 0.103 m bars
    // span 7 rows of 0.0156 m, 6 % more than their height.
    let area: f64 = (0..z.len())
        .map(|i| {
            let (a, b) = (z[i], z[(i + 1) % z.len()]);
            0.5 * (a[0] * b[1] - b[0] * a[1])
        })
        .sum();
    let pixel = (2.0f64 / 128.0).powi(2);
    assert!(
        (hits as f64 * pixel / area.abs() - 1.0).abs() < 0.06,
        "{hits} vs {area}"
    );
    // The bounds are the outline's, in the plane z = 2 m (murk-io's test round-trips them).
    let lo = |k: usize| z.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
    let hi = |k: usize| z.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max);
    assert_eq!(t.bounds_min_m, [lo(0), lo(1), 2.0]);
    assert_eq!(t.bounds_max_m, [hi(0), hi(1), 2.0]);
    // Overrides move the truth with the scene.
    let moved = Scene::load(
        &scene_path("z-letter.toml"),
        &Overrides {
            grid: Some(16),
            set: vec!["object[0].center=[0.0, 0.0, 1.5]".into()],
            ..Overrides::default()
        },
    )
    .unwrap()
    .ground_truth();
    assert_eq!(moved.shape(), [16, 16]);
    assert!(moved.depth_m.contains(&1.5));
    assert!(moved.depth_m.iter().all(|d| d.is_nan() || *d == 1.5));
}

#[test]
fn shelf_truth_matches_its_boxes_letter_and_vase() {
    let path = scene_path("shelf.toml");
    let scene = Scene::load(&path, &Overrides::default()).unwrap();
    let t = scene.ground_truth();
    let file: toml::Table = std::fs::read_to_string(&path).unwrap().parse().unwrap();
    let objects = file["object"].as_array().unwrap();
    let v3 = |v: &toml::Value| -> [f64; 3] {
        let a = v.as_array().unwrap();
        [0, 1, 2].map(|i| a[i].as_float().unwrap())
    };
    // The vase's triangles as the renderer reads them (f32 vertices, then offset), and the nearest
    // one over (x, y): a ray along +z meets a triangle where (x, y) lies in its projection onto the
    // wall, at the depth its barycentric coordinates there interpolate.
    let vase = objects
        .iter()
        .find(|o| o["name"].as_str() == Some("vase"))
        .unwrap();
    let offset = DVec3::from_array(v3(&vase["translate"]));
    let text = std::fs::read_to_string(scene_path(vase["file"].as_str().unwrap())).unwrap();
    let mut verts: Vec<DVec3> = Vec::new();
    let mut tris: Vec<[usize; 3]> = Vec::new();
    for line in text.lines() {
        let mut w = line.split_whitespace();
        match w.next() {
            Some("v") => {
                let c: Vec<f64> = w.map(|s| s.parse::<f32>().unwrap() as f64).collect();
                verts.push(DVec3::new(c[0], c[1], c[2]) + offset);
            }
            Some("f") => {
                let f: Vec<usize> = w.map(|s| s.parse::<usize>().unwrap() - 1).collect();
                tris.extend((1..f.len() - 1).map(|i| [f[0], f[i], f[i + 1]]));
            }
            _ => {}
        }
    }
    let mesh_depth = |x: f64, y: f64| -> Option<f64> {
        tris.iter()
            .filter_map(|t| {
                let [a, b, c] = t.map(|i| verts[i]);
                let (e1, e2) = (b - a, c - a);
                let det = e1.x * e2.y - e2.x * e1.y;
                if det.abs() < 1e-15 {
                    return None;
                }
                let u = ((x - a.x) * e2.y - e2.x * (y - a.y)) / det;
                let v = (e1.x * (y - a.y) - (x - a.x) * e1.y) / det;
                (u >= 0.0 && v >= 0.0 && u + v <= 1.0).then_some(a.z + u * e1.z + v * e2.z)
            })
            .reduce(f64::min)
    };
    let mut seen = std::collections::BTreeSet::new();
    let mut vase_pixels = 0;
    for (ix, &x) in t.x_m.iter().enumerate() {
        for (iy, &y) in t.y_m.iter().enumerate() {
            // Nearest front face over the boxes (the room's back wall is its +z face) and the letter.
            let mut best = (f64::INFINITY, -1i32);
            for (i, o) in objects.iter().enumerate() {
                let z = match o["shape"].as_str().unwrap() {
                    "box" => {
                        let (a, b) = (v3(&o["min"]), v3(&o["max"]));
                        let over = a[0] < x && x < b[0] && a[1] < y && y < b[1];
                        let front = if o.get("omit").is_some() { b[2] } else { a[2] };
                        over.then_some(front)
                    }
                    "z-letter" => {
                        let (c, s) = (v3(&o["center"]), o["scale"].as_float().unwrap());
                        let poly: Vec<[f64; 2]> = murk_synth::z_letter_outline()
                            .iter()
                            .map(|p| [c[0] + s * p[0], c[1] + s * p[1]])
                            .collect();
                        inside(&poly, x, y).then_some(c[2])
                    }
                    "mesh" => mesh_depth(x, y),
                    _ => None,
                };
                if let Some(z) = z.filter(|z| *z < best.0) {
                    best = (z, i as i32);
                }
            }
            let k = ix * t.y_m.len() + iy;
            seen.insert(t.object[k]);
            if t.object[k] >= 0 && scene.object_names[t.object[k] as usize] == "vase" {
                // A triangle's depth to rounding (the renderer's own intersection arithmetic).
                vase_pixels += 1;
                assert_eq!(t.object[k], best.1, "({x}, {y})");
                assert!(
                    (t.depth_m[k] as f64 - best.0).abs() < 1e-6,
                    "({x}, {y}): {} against {}",
                    t.depth_m[k],
                    best.0
                );
                continue;
            }
            assert_eq!(
                (t.depth_m[k], t.object[k]),
                (best.0 as f32, best.1),
                "({x}, {y})"
            );
        }
    }
    // Every object is seen from the relay somewhere; the vase (0.24 m × 0.30 m) from many points.
    assert_eq!(seen.len(), objects.len(), "{seen:?}");
    assert!(vase_pixels > 100, "{vase_pixels}");
}
