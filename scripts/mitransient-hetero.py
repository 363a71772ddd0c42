#!/usr/bin/env python3
"""Checks murk's heterogeneous (grid) medium against mitransient's `transient_prbvolpath` on the T scene
(scenes/t-wall-medium.toml). docs/media-heterogeneous.md has the recipe and the results.

Three subcommands:

  density OUT.npy          writes the two-layer density: (nx, ny, nz) = (1, 1, 5) over the T scene's medium
                           box, density 2 in the cell next to the wall (z < 0.501 m) and 0.5 behind it
                           (--layers changes the layers).
  render --medium M ...    renders the same scene with mitransient (M = homogeneous or grid) and saves its
                           transient (rows = y, columns = x, time, channel) as .npy.
  compare ...              reads murk's HDF5 captures and mitransient's .npy files (one per seed) and prints
                           murk / mitransient per time window, in absolute units.

mitransient has no laser sampling in its volumetric integrator, so the laser spot is a 5 mm square area
light just off the wall centre and the sensor leg is dropped with camera_unwarp (as in
/work/shared/reference/mitransient_bench.py --mode vol --medium). The spot's surface is null (it emits but
blocks nothing): with an opaque spot 0.5 mm below the medium's boundary, Mitsuba's shadow rays that cross
that boundary near the spot end on the spot's own surface and are blocked, which takes about 60 % off the
signal near each point's onset and 3-11 % off the fog from 0.6 m on (docs/media-heterogeneous.md);
--opaque-laser renders that way. A unit-power spot in murk's units is radiance 1/(pi x area), so
murk / mitransient = 1 / (pi x RADIANCE x area) with nothing fitted. Its max_depth 10 counts the wall vertex
and the emitter, so it allows 8 hidden vertices, murk's max_depth 8. mitransient 1.3.1 drops the length of
null collisions from a path's time, so grid renders need the one-line patch given in the doc. Needs the
mitransient venv (mitransient 1.3.1, mitsuba 3.9.1) for `render`, numpy and h5py for `compare`.
"""

import argparse
import math
import sys

import numpy as np

BOX_MIN = (-1.5, -1.5, 0.001)
BOX_MAX = (1.5, 1.5, 2.5)
LAYERS = "2,0.5,0.5,0.5,0.5"  # default density of the layers along z, wall side first
LASER_HALF_M = 0.0025  # the laser spot is a 5 mm square
LASER_RADIANCE = 1000.0
# murk's laser spot has unit power; mitransient's emits pi x radiance x area
MURK_PER_MIT = 1.0 / (math.pi * LASER_RADIANCE * (2 * LASER_HALF_M) ** 2)


def density_grid(layers):
    """murk's layout: (nx, ny, nz), x slowest, cell [0, 0, 0] at the box's min corner."""
    values = [float(v) for v in layers.split(",")]
    return np.asarray(values, dtype=np.float32).reshape(1, 1, len(values))


def cmd_density(a):
    np.save(a.out, density_grid(a.layers))


def medium_dict(mi, kind, layers, mu_t, albedo, g):
    """The medium inside the box. Mitsuba's VolumeGrid is indexed (z, y, x, channel), and gridvolume's
    to_world maps the unit cube onto the box; 'nearest' keeps murk's constant-per-cell density."""
    phase = {"type": "hg", "g": g}
    if kind == "homogeneous":
        return {"type": "homogeneous", "sigma_t": mu_t, "albedo": albedo, "phase": phase}
    zyx = np.ascontiguousarray(density_grid(layers).transpose(2, 1, 0)[..., None])
    size = [hi - lo for lo, hi in zip(BOX_MIN, BOX_MAX)]
    T = mi.ScalarTransform4f
    return {
        "type": "heterogeneous",
        "sigma_t": {
            "type": "gridvolume",
            "grid": mi.VolumeGrid(zyx),
            "filter_type": "nearest",
            "to_world": T().translate(list(BOX_MIN)) @ T().scale(size),
        },
        "scale": mu_t,
        "albedo": albedo,
        "phase": phase,
    }


def cmd_render(a):
    import mitransient_scene as ms

    mi = ms.mitsuba()
    T = mi.ScalarTransform4f
    white = {"type": "diffuse", "reflectance": 1.0}

    def facing_wall(cx, cy, hx, hy):
        # a rectangle is [-1, 1]² at z = 0 facing +z; turned to face the wall at z = 1 m
        to_world = T().translate([cx, cy, 1.0]) @ T().rotate([0, 1, 0], 180) @ T().scale([hx, hy, 1.0])
        return {"type": "rectangle", "to_world": to_world, "bsdf": white}

    centre = [(lo + hi) / 2 for lo, hi in zip(BOX_MIN, BOX_MAX)]
    half = [(hi - lo) / 2 for lo, hi in zip(BOX_MIN, BOX_MAX)]
    shapes = {
        "wall": {"type": "rectangle", "to_world": T().scale([0.5, 0.5, 1.0]), "bsdf": white,
                 "nlos_sensor": ms.sensor([0.0, 0.0, 0.5], a.res, a.bins, 0.003, a.spp)},
        "bar": facing_wall(0.0, 0.20, 0.25, 0.05),
        "stem": facing_wall(0.0, -0.05, 0.05, 0.20),
        # null unless --opaque-laser: the spot must not block the shadow rays that reach it (module docstring)
        "laser": ms.laser_spot(mi, 0.0, 0.0, LASER_HALF_M, LASER_RADIANCE, a.opaque_laser),
        "medium": ms.medium_box(mi, centre, half, medium_dict(mi, a.medium, a.layers, a.mu_t, a.albedo, 0.0)),
    }
    transient = ms.render(mi, shapes, 10, 5, a.seed, a.spp)
    np.save(a.out, transient.astype(np.float32))


def murk_profile(path):
    """Pixel-summed time profile of a murk capture (H is time × x × y)."""
    import h5py

    with h5py.File(path, "r") as f:
        return np.asarray(f["H"], dtype=np.float64).sum(axis=(1, 2))


def mit_profile(path):
    """Pixel-summed time profile of a mitransient transient (y × x × time × channel)."""
    return np.load(path).astype(np.float64)[..., 0].sum(axis=(0, 1))


def windows_of(profiles, windows, bin_m):
    """Per seed, the sum over each window [lo, hi) m."""
    out = []
    for p in profiles:
        out.append([p[int(round(lo / bin_m)):int(round(hi / bin_m))].sum() for lo, hi in windows])
    return np.asarray(out)


def mean_se(x):
    return x.mean(axis=0), x.std(axis=0, ddof=1) / np.sqrt(len(x))


def cmd_compare(a):
    windows = [tuple(float(v) for v in w.split("-")) for w in a.windows]
    murk = mean_se(windows_of([murk_profile(f) for f in a.murk], windows, a.bin_m))
    mit = mean_se(windows_of([mit_profile(f) for f in a.mit], windows, a.bin_m))
    print(f"murk / mitransient, absolute (mitransient x {MURK_PER_MIT:.4f}), ± from the seeds' spread:")
    print("| window (m) | murk rel. SE | mitransient rel. SE | murk / mitransient |")
    print("|---|---|---|---|")
    for i, (lo, hi) in enumerate(windows):
        rel_murk, rel_mit = murk[1][i] / murk[0][i], mit[1][i] / mit[0][i]
        r = murk[0][i] / (mit[0][i] * MURK_PER_MIT)
        print(f"| {lo:g}–{hi:g} | {rel_murk:.2%} | {rel_mit:.2%} | {r:.4f} ± {r * math.hypot(rel_murk, rel_mit):.4f} |")


def main(argv):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    d = sub.add_parser("density", help="write the two-layer density grid for murk")
    d.add_argument("out")
    layers_help = "comma-separated densities of equal layers along z, wall side first"
    d.add_argument("--layers", default=LAYERS, help=layers_help)
    r = sub.add_parser("render", help="render the T scene with mitransient")
    r.add_argument("--medium", choices=["homogeneous", "grid"], required=True)
    r.add_argument("--layers", default=LAYERS, help=layers_help + " (with --medium grid)")
    r.add_argument("--mu-t", dest="mu_t", type=float, default=1.0, help="μt (1/m) where the density is 1")
    r.add_argument("--albedo", type=float, default=0.5, help="single-scattering albedo (g is 0)")
    r.add_argument("--res", type=int, default=16, help="sensor grid res × res")
    r.add_argument("--bins", type=int, default=1024, help="3 mm bins from path 0")
    r.add_argument("--spp", type=int, required=True)
    r.add_argument("--seed", type=int, required=True)
    r.add_argument("--out", required=True)
    r.add_argument("--opaque-laser", dest="opaque_laser", action="store_true",
                   help="give the laser spot an opaque black surface, which blocks shadow rays (biased)")
    c = sub.add_parser("compare", help="print murk / mitransient per window")
    c.add_argument("--murk", nargs="+", required=True, help="murk's captures (.h5), one per seed")
    c.add_argument("--mit", nargs="+", required=True, help="mitransient's transients (.npy), one per seed")
    c.add_argument("--windows", nargs="+", default=["0.3-0.6", "0.6-0.9", "0.9-1.2", "1.2-1.9", "1.98-2.7", "2.7-3.07"])
    c.add_argument("--bin-m", dest="bin_m", type=float, default=0.003)
    a = p.parse_args(argv[1:])
    {"density": cmd_density, "render": cmd_render, "compare": cmd_compare}[a.cmd](a)


if __name__ == "__main__":
    main(sys.argv)
