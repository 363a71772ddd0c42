"""The medium-aware path from Python: the estimate, and the model removal against the CLI."""
import numpy as np
import pytest

import murk
from conftest import cli, render_z_in_fog

FOG = dict(spp=64, seed=3)


@pytest.fixture(scope="module")
def fog(tmp_path_factory):
    path = tmp_path_factory.mktemp("fog") / "fog.h5"
    render_z_in_fog(**FOG, out=path)
    return path


def test_the_model_removal_gives_the_clis_bytes(fog, tmp_path):
    cli("reconstruct", fog, "--out", tmp_path / "v.npy", "--medium-removal", "model",
        "--mu-t", "1", "--albedo", "0.5", "--quiet")
    rec = murk.reconstruct(fog, medium_removal="model", mu_t=1.0, albedo=0.5)
    assert np.array_equal(rec.intensity, np.load(tmp_path / "v.npy"))
    row = rec.params["medium"]
    assert "rendered for μt 1 /m, albedo 0.5, g 0" in row, row


def test_the_estimate_finds_the_fog_and_the_model_removal_uses_it(fog):
    m = murk.estimate_medium(fog)
    assert m["medium"] is True
    assert abs(m["mu_t_per_m"] - 1.0) < 0.15 and abs(m["albedo"] - 0.5) < 0.1, m
    rec = murk.reconstruct(fog, medium_removal="model")
    assert f"rendered for μt {m['mu_t_per_m']:.6g} /m" in rec.params["medium"]


def test_model_removal_without_a_medium_or_a_scene_is_refused(tmp_path):
    clear = tmp_path / "clear.h5"
    render_z_in_fog(**FOG, out=clear, settings={"medium.mu_t": 0.0})
    with pytest.raises(murk.InputError, match="no medium detected.*give mu_t and albedo"):
        murk.reconstruct(clear, medium_removal="model")
    with pytest.raises(murk.InputError, match="mu_t and albedo are read by a compensation"):
        murk.reconstruct(clear, mu_t=1.0)
