"""Surface normals through the method contract: D-LCT's normals of an analytic tilted plane, from
`murk reconstruct` (the .h5's `normals`, the .npy's `-normals.npy`, normals.png) and from
`murk.reconstruct` alike; methods without normals give none."""

import numpy as np
import pytest

import murk
from conftest import cli, needs_cli

h5py = pytest.importorskip("h5py")

TILT_DEG = 25.0
CENTRE = np.array([0.0, 0.0, 0.5])


def tilted(towards):
    """The unit normal facing the wall (−z), tilted TILT_DEG towards `towards`."""
    t = np.radians(TILT_DEG)
    return np.array([0.0, 0.0, -np.cos(t)]) + np.sin(t) * np.asarray(towards, float)


def plane_capture(path, normal):
    """A 32 × 32 confocal scan of a 0.3 m square through CENTRE with unit normal `normal`, under
    D-LCT's own forward model and written independently of murk's synthesis: each 5 mm patch at p
    adds dA·⟨n, p′ − p⟩/r⁵ to the bin of round-trip path 2r of scan point p′."""
    cap = murk.synth("point:0,0,0.5", kind="confocal", wall_size=0.8, grid=32, bins=256,
                     bin_width=0.01)
    murk.write_capture(path, cap)
    u = np.cross(normal, [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    w = np.cross(normal, u)
    side, step = 0.3, 0.005
    at = -0.5 * side + (np.arange(int(side / step)) + 0.5) * step
    a, b = np.meshgrid(at, at, indexing="ij")
    patches = CENTRE + a.reshape(-1, 1) * u + b.reshape(-1, 1) * w
    wall = cap.laser_points.reshape(-1, 3)
    h = np.zeros((len(wall), cap.bins))
    for i, p in enumerate(wall):
        d = p - patches
        r = np.linalg.norm(d, axis=1)
        k = np.floor((2 * r - cap.start_m) / cap.bin_width_m).astype(int)
        np.add.at(h[i], k, step * step * (d @ normal) / r**5)
    with h5py.File(path, "r+") as f:
        # y-tal keeps time first; the checksum murk wrote is of the data replaced here.
        f["H"][...] = np.moveaxis(h.reshape(cap.H.shape), -1, 0).astype(np.float32)
        del f.attrs["murk_crc32"]


def mean_normal(intensity, normals, x, y, radius=0.1):
    """The intensity-weighted mean normal of each column's brightest voxel within `radius` m of the
    scan's axis."""
    k = intensity.argmax(axis=2)
    ix, iy = np.indices(k.shape)
    peak = intensity[ix, iy, k]
    n = normals[ix, iy, k]
    near = (np.hypot(x[ix], y[iy]) < radius) & (peak > 0)
    assert near.sum() >= 16, near.sum()
    m = (peak[near, None] * n[near]).sum(axis=0)
    return m / np.linalg.norm(m)


def degrees(a, b):
    return np.degrees(np.arccos(np.clip(np.dot(a, b), -1.0, 1.0)))


@needs_cli
@pytest.mark.parametrize("towards", [(1, 0, 0), (0, -1, 0)], ids=["x", "-y"])
def test_dlct_gives_a_tilted_planes_normal_to_the_cli_and_python(tmp_path, towards):
    n = tilted(towards)
    cap = tmp_path / "plane.h5"
    plane_capture(cap, n)
    pics = tmp_path / "pics"
    cli("reconstruct", cap, "--method", "dlct", "--out", tmp_path / "v.h5", "--png", pics,
        "--quiet")
    with h5py.File(tmp_path / "v.h5", "r") as f:
        intensity, normals = f["intensity"][...], f["normals"][...]
        x, y = f["x"][...], f["y"][...]
    assert normals.shape == intensity.shape + (3,) and normals.dtype == np.float32
    # 0.5° measured for either tilt.
    got = mean_normal(intensity, normals, x, y)
    assert degrees(got, n) < 2.0, (got, n)
    assert (pics / "normals.png").stat().st_size > 0

    rec = murk.reconstruct(cap, "dlct")
    assert np.array_equal(rec.intensity, intensity)
    assert np.array_equal(rec.normals, normals)

    cli("reconstruct", cap, "--method", "dlct", "--out", tmp_path / "v.npy", "--quiet")
    assert np.array_equal(np.load(tmp_path / "v-normals.npy"), normals)


@needs_cli
def test_a_method_without_normals_writes_none(tmp_path, captures):
    assert murk.reconstruct(captures["confocal"], "fk").normals is None
    cli("reconstruct", captures["confocal"], "--method", "fk", "--out", tmp_path / "v.npy",
        "--quiet")
    assert not (tmp_path / "v-normals.npy").exists()
    cli("reconstruct", captures["confocal"], "--method", "fk", "--out", tmp_path / "v.h5",
        "--quiet")
    with h5py.File(tmp_path / "v.h5", "r") as f:
        assert "normals" not in f
