import os

import numpy as np
import pytest

import murk
from conftest import SCENES, cli, needs_cli

Z = SCENES / "z-letter.toml"


@needs_cli
def test_render_and_merged_shards_give_the_cli_bytes(tmp_path):
    # Tiles of 4 × 4 laser points: four work units, for three shards.
    cli("render", Z, "--out", tmp_path / "cli.h5", "--grid", "8", "--spp", "32", "--seed", "3",
        "--set", "medium.albedo=0.8", "--set", "render.share_tile=4", "--quiet")
    kw = dict(grid=8, spp=32, seed=3, set={"medium.albedo": 0.8, "render.share_tile": 4})
    whole = murk.render(Z, out=tmp_path / "py.h5", **kw)
    assert (tmp_path / "py.h5").read_bytes() == (tmp_path / "cli.h5").read_bytes()
    parts = [murk.render(Z, shard=(i, 3), **kw) for i in (2, 0, 1)]
    murk.write_capture(tmp_path / "merged.h5", murk.merge(parts))
    assert (tmp_path / "merged.h5").read_bytes() == (tmp_path / "cli.h5").read_bytes()
    # A part read back from its file has its time axis in f32 (as y-tal stores it); it still merges
    # with parts held in memory.
    murk.write_capture(tmp_path / "part2.h5", parts[0])
    assert murk.read_capture(tmp_path / "part2.h5").bin_width_m != parts[0].bin_width_m
    murk.write_capture(tmp_path / "mixed.h5", murk.merge([tmp_path / "part2.h5", *parts[1:]]))
    assert (tmp_path / "mixed.h5").read_bytes() == (tmp_path / "cli.h5").read_bytes()
    assert np.array_equal(whole.H, murk.read_capture(tmp_path / "cli.h5").H)


@needs_cli
def test_albedo_sweep_gives_the_cli_files_and_each_albedo_alone(tmp_path):
    cli("render", Z, "--out", tmp_path / "cli.h5", "--grid", "8", "--spp", "32", "--seed", "3",
        "--albedos", "0.2,0.8", "--quiet")
    caps = murk.render_albedos(Z, [0.2, 0.8], grid=8, spp=32, seed=3, out=tmp_path / "py.h5")
    assert len(caps) == 2
    for a, cap in zip(["0.2", "0.8"], caps):
        py, cl = tmp_path / f"py-albedo{a}.h5", tmp_path / f"cli-albedo{a}.h5"
        assert py.read_bytes() == cl.read_bytes()
        alone = murk.render(Z, grid=8, spp=32, seed=3, set={"medium.albedo": float(a)})
        assert np.allclose(cap.H, alone.H, rtol=1e-5, atol=1e-12 * alone.H.max())
    assert not np.allclose(caps[0].H, caps[1].H)


def test_scene_text_and_list_overrides():
    text = Z.read_text()
    a = murk.render(text, grid=4, spp=8, set=["medium.albedo=0.5"])
    b = murk.render(text, grid=4, spp=8, set={"medium.albedo": 0.5})
    assert np.array_equal(a.H, b.H) and a.H.any()


def test_interrupted_render_resumes_from_its_checkpoint(tmp_path):
    ckpt = tmp_path / "z.ckpt"
    kw = dict(grid=16, spp=64, checkpoint=ckpt, checkpoint_every=0.0, threads=1)

    class Stop(Exception):
        pass

    def stop_halfway(done, total):
        if done >= total // 2:
            raise Stop()

    # What Ctrl-C does: the progress poll raises, the render unwinds, its checkpoint stays.
    with pytest.raises(Stop):
        murk.render(Z, progress=stop_halfway, **kw)
    assert ckpt.exists() and ckpt.stat().st_size > 0
    first = []
    resumed = murk.render(Z, progress=lambda d, t: first.append(d), **kw)
    assert first[0] > 0, "the second run started from zero instead of the checkpoint"
    assert not ckpt.exists()
    fresh = murk.render(Z, grid=16, spp=64)
    assert np.array_equal(resumed.H, fresh.H)


def _kind_and_sum(cap):
    return cap.kind, float(cap.H.sum())


def test_capture_pickles_exactly_and_crosses_processes():
    import concurrent.futures
    import multiprocessing
    import pickle

    # Tiles of 2 × 2 laser points: four work units, for two shards.
    kw = dict(grid=4, spp=8, seed=2, set={"render.share_tile": 2})
    cap = murk.render(Z, shard=(1, 2), **kw)
    back = pickle.loads(pickle.dumps(cap))
    for name in ("H", "laser_points", "laser_normals", "sensor_points", "sensor_normals", "t"):
        assert np.array_equal(getattr(back, name), getattr(cap, name)), name
    for name in ("laser_xyz", "sensor_xyz", "start_m", "bin_width_m", "pairing", "scene_info",
                 "t_accounts_first_and_last_bounces"):
        assert getattr(back, name) == getattr(cap, name), name
    # A pickled shard is still a shard of the same render.
    other = murk.render(Z, shard=(0, 2), **kw)
    assert np.array_equal(murk.merge([back, other]).H, murk.merge([cap, other]).H)
    with concurrent.futures.ProcessPoolExecutor(
            1, mp_context=multiprocessing.get_context("spawn")) as pool:
        assert pool.submit(_kind_and_sum, cap).result() == _kind_and_sum(cap)
