import os
import signal
import time

import pytest

import murk
from conftest import SCENES, cli, needs_cli

distributed = pytest.importorskip("distributed", reason="dask[distributed] is not installed")
import murk.dask  # noqa: E402

Z = SCENES / "z-letter.toml"
# About 2 s per shard on one core: long enough to kill a worker mid-task.
KW = dict(grid=16, spp=512, seed=1)


@pytest.fixture(scope="module")
def want(tmp_path_factory):
    if not (SCENES.parent / "target" / "release" / "murk").exists():
        pytest.skip("target/release/murk missing: run `cargo build --release` first")
    out = tmp_path_factory.mktemp("cli") / "z.h5"
    cli("render", Z, "--out", out, "--grid", "16", "--spp", "512", "--seed", "1", "--quiet")
    return out.read_bytes()


@pytest.fixture()
def client():
    cluster = murk.dask.local_cluster(n_workers=2)
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def test_local_workers_keep_glibcs_adaptive_malloc(client):
    # Dask's nanny default (MALLOC_TRIM_THRESHOLD_=65536) slows the renderer by 4-8 %.
    env = client.run(lambda: os.environ.get("MALLOC_TRIM_THRESHOLD_"))
    assert len(env) == 2 and set(env.values()) == {None}, env


def test_two_worker_render_equals_the_unsharded_cli_render(client, want, tmp_path):
    murk.dask.render(Z, client, shards=4, out=tmp_path / "z.h5", threads=1, **KW)
    assert (tmp_path / "z.h5").read_bytes() == want


def test_a_killed_worker_is_retried_and_resumes(client, want, tmp_path):
    work = tmp_path / "parts"
    futures = [client.submit(murk.dask.render_shard, str(Z), (i, 2), str(work / f"part{i}.h5"),
                             threads=1, checkpoint_every=0.0, retries=3, pure=False, **KW)
               for i in range(2)]
    os.makedirs(work, exist_ok=True)
    ckpt = work / "part0.h5.ckpt"
    deadline = time.time() + 60
    while not (ckpt.exists() and ckpt.stat().st_size > 4096):
        assert time.time() < deadline, "shard 0 never wrote a checkpoint"
        time.sleep(0.05)
    # The worker running shard 0 is the one whose task is processing it.
    processing = client.processing()
    addr = next(a for a, keys in processing.items() if futures[0].key in keys)
    pid = client.run(os.getpid, workers=[addr])[addr]
    units_at_kill = ckpt.stat().st_size
    unfinished = not (work / "part0.h5").exists()
    os.kill(pid, signal.SIGKILL)
    assert unfinished, "shard 0 finished before the kill; the test proved nothing"

    parts = client.gather(futures)
    merged = murk.merge(parts)
    murk.write_capture(tmp_path / "z.h5", merged)
    assert (tmp_path / "z.h5").read_bytes() == want
    assert units_at_kill > 0 and not ckpt.exists()
    assert (work / "part0.h5").exists()
