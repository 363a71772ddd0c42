"""A heterogeneous medium's compensation from Python: a density grid (``medium_density``) and a
height fog (``height_scale``, or the capture's own), as ``murk reconstruct`` takes them."""
import numpy as np
import pytest

import murk
from conftest import cli, render_z_in_fog

# The Z in a height fog settling toward the medium's floor at y = −3 m (its box is y −3 … 3 m).
SCALE_M = 0.5
FLOOR_M, TOP_M = -3.0, 3.0
# Depth search off and a fixed volume: the volumes compared are the same voxels.
RECON = dict(compensate="ballistic", mu_t=1.0, depth_search="off",
             volume="-0.9:0.9:9,-0.9:0.9:9,1.2:2.8:17")


@pytest.fixture(scope="module")
def height(tmp_path_factory):
    path = tmp_path_factory.mktemp("height") / "height.h5"
    render_z_in_fog(spp=4, seed=5, out=path,
                    settings={"medium.kind": "height", "medium.height_scale": SCALE_M})
    return path


def fog_grid(path, cells):
    """The height fog as a (1, cells, 1) grid over the box, each cell the fog's mean over its height."""
    edges = np.linspace(0.0, TOP_M - FLOOR_M, cells + 1)
    h = edges[1] - edges[0]
    means = SCALE_M / h * (np.exp(-edges[:-1] / SCALE_M) - np.exp(-edges[1:] / SCALE_M))
    np.save(path, means.astype(np.float32).reshape(1, cells, 1))
    return path


def test_the_captures_height_fog_matches_its_fine_grid(height, tmp_path):
    # 60 000 cells of h = 0.1 mm: a leg's full cells are exact, and only its two end cells differ
    # from the fog, by under e^{h/H} − 1 = 2e-4 of the density over at most the leg's length (2.9 m
    # here), so each voxel's gain e^{2μt ∑ legs} agrees within e^{2 · 2 · 2 · 2.9 · 2e-4} − 1 = 0.5 %.
    auto = murk.reconstruct(height, **RECON)
    assert "the height fog of the capture's scene" in auto.params["compensated along"]
    assert not any("the capture's medium is" in w for w in auto.warnings), auto.warnings
    grid = murk.reconstruct(height, medium_density=fog_grid(tmp_path / "fog.npy", 60_000), **RECON)
    assert "fog.npy" in grid.params["compensated along"]
    np.testing.assert_allclose(auto.intensity, grid.intensity, rtol=5e-3, atol=0)
    # The same height fog named by height_scale, and the CLI's bytes for both keywords.
    named = murk.reconstruct(height, height_scale=SCALE_M, **RECON)
    assert np.array_equal(named.intensity, auto.intensity)
    flags = ["--compensate", "ballistic", "--mu-t", "1", "--depth-search", "off",
             "--volume", RECON["volume"], "--quiet"]
    cli("reconstruct", height, "--out", tmp_path / "g.npy", *flags,
        "--medium-density", tmp_path / "fog.npy")
    assert np.array_equal(np.load(tmp_path / "g.npy"), grid.intensity)
    cli("reconstruct", height, "--out", tmp_path / "a.npy", *flags)
    assert np.array_equal(np.load(tmp_path / "a.npy"), auto.intensity)
    # Not the homogeneous medium: density 1 everywhere gains far more.
    ones = tmp_path / "ones.npy"
    np.save(ones, np.ones((1, 1, 1), np.float32))
    flat = murk.reconstruct(height, medium_density=ones, **RECON)
    assert np.median(flat.intensity / np.maximum(auto.intensity, 1e-30)) > 2.0


def test_bad_densities_are_refused(height, tmp_path):
    bad = tmp_path / "nan.npy"
    np.save(bad, np.array([[[0.5, np.nan]]], np.float32))
    with pytest.raises(murk.FormatError, match=r"nan\.npy.*density\[0, 0, 1\] = NaN"):
        murk.reconstruct(height, medium_density=bad, **RECON)
    flat = tmp_path / "flat.npy"
    np.save(flat, np.ones((4, 2), np.float32))
    with pytest.raises(murk.FormatError, match="3 dimensions"):
        murk.reconstruct(height, medium_density=flat, **RECON)
    for scale in (0.0, -1.0, float("nan")):
        with pytest.raises(murk.InputError, match=r"height_scale must be in \[0.001, 1e6\] m"):
            murk.reconstruct(height, height_scale=scale, **RECON)
    with pytest.raises(murk.InputError, match="medium_density and height_scale each give"):
        murk.reconstruct(height, medium_density=flat, height_scale=0.5, **RECON)
    with pytest.raises(murk.InputError, match="medium_density is read by compensate with mu_t"):
        murk.reconstruct(height, medium_density=flat, depth_search="off")


def test_a_grid_capture_compensates_along_its_own_cells_in_memory_and_pickled(tmp_path):
    import pickle

    grid = fog_grid(tmp_path / "fog.npy", 12)
    cap = render_z_in_fog(spp=1, seed=5, grid=8,
                          settings={"medium.kind": "grid", "medium.density": str(grid)})
    by_hand = murk.reconstruct(cap, medium_density=grid, **RECON)
    for c in (cap, pickle.loads(pickle.dumps(cap))):
        own = murk.reconstruct(c, **RECON)
        assert "the capture's own grid (1 × 12 × 1 cells)" in own.params["compensated along"]
        assert np.array_equal(own.intensity, by_hand.intensity)
