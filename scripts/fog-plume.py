#!/usr/bin/env python3
"""Writes scenes/fog-plume.npy, the density grid of scenes/fog-plume.toml: a smoke plume rising from
the floor of the medium's box and drifting sideways in the wind, over a thin haze. Deterministic
(no random numbers), standard library only.

Shape (nx, ny, nz) = (32, 32, 24), x slowest, little-endian f32; cell (i, j, k) is centred at
min + (i + ½, j + ½, k + ½) × cell size over the box min = (−1.5, −1.5, 0.001), max = (1.5, 1.5, 2).

Usage: scripts/fog-plume.py [OUT]   (default: scenes/fog-plume.npy)
"""

import math
import struct
import sys
from pathlib import Path

DIMS = (32, 32, 24)
BOX_MIN = (-1.5, -1.5, 0.001)
BOX_MAX = (1.5, 1.5, 2.0)


def density(x, y, z):
    """The plume's centre leaves (−0.7, floor, 0.7) and drifts +0.35 m in x per metre it rises,
    widening (radius 0.12 m + 0.12 m per metre) and thinning as it goes, in puffs; haze 0.03."""
    h = y - BOX_MIN[1]
    xc, zc = -0.7 + 0.35 * h, 0.7 + 0.08 * math.sin(2.0 * h)
    r = 0.12 + 0.12 * h
    core = math.exp(-((x - xc) ** 2 + (z - zc) ** 2) / (2 * r * r)) * 0.3 / (r + 0.18)
    return 0.03 + 0.97 * core * (0.75 + 0.25 * math.sin(5.0 * h))


def main(argv):
    out = Path(argv[1]) if len(argv) > 1 else Path(__file__).resolve().parent.parent / "scenes" / "fog-plume.npy"
    cell = [(hi - lo) / n for lo, hi, n in zip(BOX_MIN, BOX_MAX, DIMS)]
    centre = [[lo + (i + 0.5) * c for i in range(n)] for lo, c, n in zip(BOX_MIN, cell, DIMS)]
    values = [density(x, y, z) for x in centre[0] for y in centre[1] for z in centre[2]]
    header = "{'descr': '<f4', 'fortran_order': False, 'shape': (%d, %d, %d), }" % DIMS
    header += " " * ((64 - (10 + len(header) + 1) % 64) % 64) + "\n"
    with open(out, "wb") as f:
        f.write(b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header.encode())
        f.write(struct.pack("<%df" % len(values), *values))
    print(f"{out}: shape {DIMS}, densities {min(values):.3f}..{max(values):.3f}")


if __name__ == "__main__":
    main(sys.argv)
