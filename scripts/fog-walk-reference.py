#!/usr/bin/env python3
"""murk and mitransient against an independent analog random walk, in absolute units, on the smallest fog
scene: one laser point and one SPAD point on a black wall (z = 0), homogeneous isotropic fog from z = 0.001
to 3 m, at most 8 hidden vertices. docs/media-heterogeneous.md has the recipe and the results.

Four subcommands, each writing or reading a pixel's time profile (1 cm bins from path 0, 3 m):

  walk OUT.npy     the reference: from the laser spot in a cosine direction, exponential flights, weight α
                   per scattering, isotropic turns, every vertex connected to the SPAD point (p = 1/4π,
                   the leg's transmittance, cos_s/(π r²)); stores orders 1 and 1-8 per batch of 10⁶
                   paths, whose spread gives its standard error.
  murk OUT.npy     renders the scene with the murk binary (--murk).
  mit OUT.npy      renders it with mitransient's transient_prbvolpath: a unit-power 2 mm area light for the
                   laser spot (--opaque-laser gives it the opaque surface that blocks shadow rays), a 2 mm
                   sensor patch at the SPAD point, max_depth 10 (= 8 hidden vertices), no Russian roulette.
  compare          prints each render / the walk per window.

The normalisation is murk's: a unit-power laser spot of intensity cos/π, SPAD importance cos/π, and a bin
holds the integral of H over its path lengths; mitransient's sensor reads the radiance the patch reflects,
E/π, so it needs no constant. Needs numpy; `mit` needs the mitransient venv, `murk` h5py.
"""

import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np

Z0, TOP, HALF = 0.001, 3.0, 3.0
BIN_M, BINS = 0.01, 300
MAX_VERTICES = 8


def cmd_walk(a):
    rng = np.random.default_rng(a.seed)
    xs = np.array([a.spad[0], a.spad[1], 0.0])
    # per batch of 1e6 paths, the mean profile of order 1 and of orders 1-8; the batches' spread gives
    # the standard errors
    batches = []
    for _ in range(a.batches):
        k = 1_000_000
        u1, phi = rng.random(k), 2 * np.pi * rng.random(k)
        d = np.stack([np.sqrt(u1) * np.cos(phi), np.sqrt(u1) * np.sin(phi), np.sqrt(1 - u1)], 1)
        t_in = Z0 / d[:, 2]
        p = np.array([a.laser[0], a.laser[1], 0.0]) + d * t_in[:, None]
        path, w, alive = t_in, np.ones(k), np.ones(k, bool)
        h = np.zeros((2, BINS))
        for order in range(MAX_VERTICES):
            flight = rng.exponential(1 / a.mu_t, k)
            with np.errstate(divide="ignore"):
                # leaving through the floor ends on the black wall; through the top or sides, in the void
                exit_m = np.where(d[:, 2] < 0, (Z0 - p[:, 2]) / d[:, 2], (TOP - p[:, 2]) / d[:, 2])
            p, path = p + d * flight[:, None], path + flight
            alive &= (flight < exit_m) & (np.abs(p[:, :2]) < HALF).all(1) & (path < BIN_M * BINS)
            w = w * a.albedo
            rs = np.linalg.norm(xs - p, axis=1)
            z = np.where(alive, p[:, 2], 1.0)
            c = w / (4 * np.pi) * np.exp(-a.mu_t * rs * (1 - Z0 / z)) * (z / rs) / (np.pi * rs ** 2)
            b = ((path + rs) / BIN_M).astype(np.int64)
            ok = alive & (b < BINS)
            step = np.bincount(b[ok], weights=c[ok], minlength=BINS)[:BINS] / k
            h[1] += step
            if order == 0:
                h[0] += step
            cz, phi = 2 * rng.random(k) - 1, 2 * np.pi * rng.random(k)
            sz = np.sqrt(1 - cz ** 2)
            d = np.stack([sz * np.cos(phi), sz * np.sin(phi), cz], 1)
        batches.append(h)
    np.save(a.out, np.asarray(batches))


def cmd_murk(a):
    toml = f"""
[relay]
kind = "wall"
size = [{2 * HALF}, {2 * HALF}]
albedo = 0.0
[capture]
kind = "laser-grid"
grid = [1, 1]
center = [{a.laser[0]}, {a.laser[1]}]
extent = [0.001, 0.001]
spad_point = [{a.spad[0]}, {a.spad[1]}]
bins = {BINS}
bin_width = {BIN_M}
start = 0.0
[render]
max_depth = {MAX_VERTICES}
[medium]
mu_t = {a.mu_t}
albedo = {a.albedo}
g = 0.0
min = [-{HALF}, -{HALF}, {Z0}]
max = [{HALF}, {HALF}, {TOP}]
"""
    import h5py

    with tempfile.TemporaryDirectory() as tmp:
        scene, out = os.path.join(tmp, "fog.toml"), os.path.join(tmp, "fog.h5")
        with open(scene, "w") as f:
            f.write(toml)
        subprocess.run([a.murk, "render", scene, "--out", out, "--spp", str(a.spp), "--seed", str(a.seed),
                        "--checkpoint-every", "0", "-q"], check=True)
        with h5py.File(out, "r") as f:
            np.save(a.out, np.asarray(f["H"], dtype=np.float64).reshape(BINS))


def cmd_mit(a):
    import mitransient_scene as ms

    mi = ms.mitsuba()
    T = mi.ScalarTransform4f
    half = 0.001
    fog = {"type": "homogeneous", "sigma_t": a.mu_t, "albedo": a.albedo, "phase": {"type": "isotropic"}}
    shapes = {
        "patch": {"type": "rectangle", "bsdf": {"type": "diffuse", "reflectance": 1.0},
                  "nlos_sensor": ms.sensor([a.spad[0], a.spad[1], 0.5], 1, BINS, BIN_M, a.spp),
                  "to_world": T().translate([a.spad[0], a.spad[1], 0.0]) @ T().scale([half, half, 1.0])},
        "laser": ms.laser_spot(mi, a.laser[0], a.laser[1], half, 1.0 / (np.pi * (2 * half) ** 2),
                               a.opaque_laser),
        "medium": ms.medium_box(mi, [0, 0, (Z0 + TOP) / 2], [HALF, HALF, (TOP - Z0) / 2], fog),
    }
    # max_depth counts the wall vertex and the emitter; no Russian roulette
    transient = ms.render(mi, shapes, MAX_VERTICES + 2, 100, a.seed, a.spp)
    np.save(a.out, transient.astype(np.float64).reshape(BINS))


def cmd_compare(a):
    windows = [tuple(float(v) for v in w.split("-")) for w in a.windows]
    cut = [(int(round(lo / BIN_M)), int(round(hi / BIN_M))) for lo, hi in windows]
    batches = np.load(a.walk)  # (batch, order 1 / orders 1-8, bin)
    print("| window (m) | walk, orders 1-8 | order 1's share | "
          + " | ".join(os.path.basename(f[0]) for f in a.render) + " |")
    print("|---" * (3 + len(a.render)) + "|")
    for (i, j), (lo, hi) in zip(cut, windows):
        per_batch = batches[:, :, i:j].sum(2)
        walk = per_batch[:, 1].mean()
        walk_rel_se = per_batch[:, 1].std(ddof=1) / np.sqrt(len(per_batch)) / walk
        cells = []
        for files in a.render:
            ratio = np.array([np.load(f)[i:j].sum() for f in files]) / walk
            spread = ratio.std(ddof=1) / np.sqrt(len(ratio)) if len(ratio) > 1 else float("nan")
            cells.append(f"{ratio.mean():.3f} ± {spread:.3f}")
        print(f"| {lo:g}–{hi:g} | {walk:.4e} (± {walk_rel_se:.1%}) | {per_batch[:, 0].mean() / walk:.2f} | "
              + " | ".join(cells) + " |")


def main(argv):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    for name in ("walk", "murk", "mit"):
        s = sub.add_parser(name)
        s.add_argument("out")
        s.add_argument("--laser", type=float, nargs=2, default=[0.0, 0.0], help="wall point (m)")
        s.add_argument("--spad", type=float, nargs=2, default=[0.3, 0.0], help="wall point (m)")
        s.add_argument("--mu-t", dest="mu_t", type=float, default=1.0, help="extinction (1/m)")
        s.add_argument("--albedo", type=float, default=0.5)
        s.add_argument("--seed", type=int, default=0)
    sub.choices["walk"].add_argument("--batches", type=int, default=20, help="batches of 10⁶ paths")
    for name in ("murk", "mit"):
        sub.choices[name].add_argument("--spp", type=int, default=1_000_000)
    sub.choices["murk"].add_argument("--murk", default="target/release/murk", help="the murk binary")
    sub.choices["mit"].add_argument("--opaque-laser", dest="opaque_laser", action="store_true",
                                    help="an opaque black laser spot, which blocks shadow rays (biased)")
    c = sub.add_parser("compare")
    c.add_argument("--walk", required=True, help="the walk's .npy")
    c.add_argument("--render", nargs="+", action="append", required=True,
                   help="one render's files (one per seed); repeat for each render")
    c.add_argument("--windows", nargs="+", default=["0.3-0.45", "0.45-0.6", "0.6-0.9", "0.9-1.2", "1.2-1.9",
                                                     "1.9-3"])
    a = p.parse_args(argv[1:])
    {"walk": cmd_walk, "murk": cmd_murk, "mit": cmd_mit, "compare": cmd_compare}[a.cmd](a)


if __name__ == "__main__":
    main(sys.argv)
