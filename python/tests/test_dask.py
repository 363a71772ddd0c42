import os
import re
import signal
import subprocess
import sys
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


def test_local_workers_run_with_dasks_monitors_slowed(client):
    # At their defaults the monitors kept the idle cluster at 0.14 of the 2 cores (docs/python.md).
    def config():
        import dask

        return {k: dask.config.get(k) for k in murk.dask.QUIET_MONITORS}

    seen = client.run(config)
    assert len(seen) == 2 and all(c == murk.dask.QUIET_MONITORS for c in seen.values()), seen


def test_two_worker_render_equals_the_unsharded_cli_render(client, want, tmp_path):
    murk.dask.render(Z, client, shards=4, out=tmp_path / "z.h5", threads=1, **KW)
    assert (tmp_path / "z.h5").read_bytes() == want


@needs_cli
def test_a_sharded_sweep_equals_the_unsharded_cli_sweep(client, tmp_path):
    # A 16² grid is four units of 8 × 8 laser points: three shards of unequal size.
    cli("render", Z, "--out", tmp_path / "cli.h5", "--grid", "16", "--spp", "16", "--seed", "2",
        "--albedos", "0.3,0.7", "--quiet")
    caps = murk.dask.render_albedos(Z, [0.3, 0.7], client, shards=3, grid=16, spp=16, seed=2,
                                    threads=1, out=tmp_path / "dask.h5")
    assert len(caps) == 2
    for a in ["0.3", "0.7"]:
        got = (tmp_path / f"dask-albedo{a}.h5").read_bytes()
        assert got == (tmp_path / f"cli-albedo{a}.h5").read_bytes()
    assert (caps[0].H != caps[1].H).any()


def test_a_killed_worker_is_retried_with_the_same_bytes(client, want, tmp_path):
    work = tmp_path / "parts"
    os.makedirs(work, exist_ok=True)
    part0 = work / "part0.ckpt"
    futures = [client.submit(murk.dask.render_shard, str(Z), (i, 2), str(work / f"part{i}.ckpt"),
                             threads=1, checkpoint_every=0.0, retries=3, pure=False, **KW)
               for i in range(2)]
    deadline = time.time() + 60
    while not (part0.exists() and part0.stat().st_size > 4096):
        assert time.time() < deadline, "shard 0 never wrote a checkpoint"
        time.sleep(0.05)
    # The worker running shard 0 is the one whose task is processing it.
    processing = client.processing()
    addr = next(a for a, keys in processing.items() if futures[0].key in keys)
    pid = client.run(os.getpid, workers=[addr])[addr]
    at_kill = part0.read_bytes()
    os.kill(pid, signal.SIGKILL)

    parts = client.gather(futures)
    assert parts == [str(work / "part0.ckpt"), str(work / "part1.ckpt")]
    assert len(at_kill) < part0.stat().st_size, "shard 0 finished before the kill; the test proved nothing"
    cap = murk.dask.assemble(Z, parts, **KW)
    murk.write_capture(tmp_path / "z.h5", cap)
    assert (tmp_path / "z.h5").read_bytes() == want


def test_an_interrupted_shard_task_resumes_its_part(tmp_path):
    part = tmp_path / "p.ckpt"
    kw = dict(threads=1, checkpoint_every=3600.0, **KW)

    class Stop(Exception):
        pass

    def stop_after_one(done, total):
        if done >= 1:
            raise Stop()

    # What a Ctrl-C or a task cancelled mid-way leaves: the units it finished, whatever the interval.
    with pytest.raises(Stop):
        murk.dask.render_shard(str(Z), (0, 2), part, progress=stop_after_one, **kw)
    calls = []
    murk.dask.render_shard(str(Z), (0, 2), part, progress=lambda d, t: calls.append((d, t)), **kw)
    assert calls[0][0] >= 1 and calls[-1][0] == calls[-1][1], calls
    # A complete part is not rendered again.
    again = []
    murk.dask.render_shard(str(Z), (0, 2), part, progress=lambda d, t: again.append((d, t)), **kw)
    # Repeated while a complete part is read back (progress calls come at least every 0.5 s).
    assert set(again) == {calls[-1]}


def test_a_part_of_another_render_is_refused(client, tmp_path):
    part = murk.dask.render_shard(str(Z), (0, 1), tmp_path / "p.ckpt", threads=1, grid=4, spp=8)
    cap = murk.dask.assemble(Z, [part], grid=4, spp=8)
    one = murk.render(Z, grid=4, spp=8, threads=1)
    assert cap.H.any() and cap.H.tobytes() == one.H.tobytes()
    with pytest.raises(murk.FormatError, match=r"p\.ckpt.*render\.seed"):
        murk.dask.assemble(Z, [part], grid=4, spp=8, seed=3)


@pytest.mark.skipif((os.cpu_count() or 1) < 2,
                    reason="needs two cores: the LocalCluster runs both shards at once on two workers")
def test_ctrl_c_keeps_the_finished_units_quietly_and_a_rerun_completes_them(tmp_path):
    # About 7 s per shard on one core, in two units (8 × 8 laser points each) of about 3.5 s.
    kw = dict(grid=16, spp=4096, seed=2)
    work = tmp_path / "parts"
    script = tmp_path / "run.py"
    # A file, not `-c`: the LocalCluster's spawned workers import the main module. The handler is
    # set because a process started in the background inherits SIGINT ignored.
    script.write_text(f"""
import signal, sys, murk.dask
if __name__ == "__main__":
    signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        murk.dask.render({str(Z)!r}, shards=2, workdir={str(work)!r}, **{kw!r})
    except KeyboardInterrupt:
        sys.exit(3)
""")
    # Its own process group, which the Ctrl-C reaches as a terminal's would: the client and the
    # LocalCluster's workers alike.
    p = subprocess.Popen([sys.executable, str(script)], stderr=subprocess.PIPE, text=True,
                         start_new_session=True)
    try:
        parts = [work / "part0.ckpt", work / "part1.ckpt"]
        deadline = time.time() + 60
        while not all(f.exists() for f in parts):
            assert time.time() < deadline and p.poll() is None, "the shards never started"
            time.sleep(0.05)
        time.sleep(1.5)
        t0 = time.time()
        os.killpg(p.pid, signal.SIGINT)
        _, err = p.communicate(timeout=60)
        stopped_s = time.time() - t0
    finally:
        try:
            os.killpg(p.pid, signal.SIGKILL)  # what a failed test leaves must not outlive it
        except ProcessLookupError:
            pass
        p.wait()
    assert p.returncode == 3, err
    # Each task ends after its unit in flight; none is killed, and Dask prints nothing.
    assert stopped_s < 10, stopped_s
    assert err.strip() == "", err
    assert sorted(os.listdir(work)) == ["part0.ckpt", "part1.ckpt"], "the stop file was left behind"
    with pytest.raises(murk.FormatError, match=r"part 0/2 is incomplete: \d+ of") as e:
        murk.dask.assemble(Z, [str(f) for f in parts], **kw)
    saved = int(re.search(r"incomplete: (\d+) of", str(e.value)).group(1))
    assert saved >= 1, "no finished unit was saved"

    cap = murk.dask.render(Z, shards=2, workdir=work, **kw)
    assert cap.H.tobytes() == murk.render(Z, **kw).H.tobytes()


def test_a_render_the_tasks_would_refuse_is_refused_before_any_task():
    # In the tasks each refusal would be logged by Dask and retried; here it is one exception,
    # raised before a cluster starts.
    with pytest.raises(murk.InputError, match=r"1 work units .* so at most 1 shards"):
        murk.dask.render(Z, shards=4, grid=4, spp=8)
    with pytest.raises(murk.InputError, match=r"medium\.nope"):
        murk.dask.render(Z, shards=2, grid=16, spp=8, set={"medium.nope": 1})
    # An output that cannot be written: before, found only after every shard had rendered.
    with pytest.raises(murk.InputError, match="the folder /nonexistent does not exist"):
        murk.dask.render(Z, shards=2, grid=16, spp=8, out="/nonexistent/z.h5")
    for bad in (0, -1, 1.5):
        with pytest.raises(murk.InputError, match="shards must be a whole number"):
            murk.dask.render(Z, shards=bad, grid=16, spp=8)


def test_threads_and_albedos_are_checked_before_a_cluster_starts(monkeypatch):
    def no_cluster(**_):
        raise AssertionError("a cluster was started")

    monkeypatch.setattr(murk.dask, "local_cluster", no_cluster)
    # A thread count the tasks could not start failed inside each of them, retried.
    with pytest.raises(murk.InputError, match="threads must be ≥ 0, got -1"):
        murk.dask.render(Z, shards=2, grid=16, spp=8, threads=-1)
    with pytest.raises(murk.InputError, match="albedos: expected a list of numbers, got None"):
        murk.dask.render_albedos(Z, None, shards=2, grid=16, spp=8)


def test_parts_and_workdir_given_wrongly_are_named(tmp_path):
    # One path where a list belongs was read as its characters ("/: is a directory").
    with pytest.raises(murk.InputError, match="parts must be a list"):
        murk.dask.assemble(Z, str(tmp_path / "part0.ckpt"), grid=16, spp=8)
    with pytest.raises(murk.InputError, match="parts must be a list"):
        murk.merge(str(tmp_path / "part0.h5"))
    f = tmp_path / "file"
    f.write_text("")
    with pytest.raises(murk.InputError, match="the workdir is a file"):
        murk.dask.render(Z, shards=2, grid=16, spp=8, workdir=f)
