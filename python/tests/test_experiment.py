import os
import signal
import subprocess
import sys
import time

import pytest

import murk
from conftest import MURK, ROOT, SCENES, cli, needs_cli

pytest.importorskip("distributed", reason="dask[distributed] is not installed")

ARGS = ["--only", "fig3a", "--spp", "4", "--shards", "2"]


@needs_cli
def test_plan_is_the_cli_task_list(tmp_path):
    lines = cli("experiment", "paper", "--out", tmp_path, *ARGS, "--scenes", SCENES,
                "--list-tasks").splitlines()
    tasks = murk.experiment.plan(tmp_path, only=["fig3a"], spp=4, shards=2, scenes=SCENES)
    # The CLI names itself by its absolute path; the package, which has no binary, names `murk`.
    lines = [line.replace(f" {MURK.resolve()} render ", " murk render ") for line in lines]
    assert [t["command"] for t in tasks] == lines and len(tasks) == 2
    assert [t["shard"] for t in tasks] == [(0, 2), (1, 2)]


@needs_cli
def test_study_on_dask_renders_the_cli_bytes_and_reuses_them(tmp_path):
    cli("experiment", "paper", "--out", tmp_path / "cli", *ARGS, "--quiet", cwd=ROOT)
    run = [sys.executable, "-m", "murk.experiment", "paper", "--out", str(tmp_path / "dask"),
           *ARGS]
    r = subprocess.run(run, cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "dask" / "index.html").exists()
    [cap] = (tmp_path / "cli" / "renders").glob("*.h5")
    assert (tmp_path / "dask" / "renders" / cap.name).read_bytes() == cap.read_bytes()
    tasks = murk.experiment.plan(tmp_path / "dask", only=["fig3a"], spp=4, shards=2,
                                 scenes=SCENES)
    assert murk.experiment.pending(tasks) == []


@needs_cli
def test_a_sweep_task_on_dask_writes_the_cli_captures(tmp_path):
    # One row of Fig. 3b is one task that renders every albedo of the row.
    args = dict(only=["fig3b"], cells=["μt = 2 α = 0.15", "μt = 2 α = 0.83"], spp=2,
                scenes=SCENES)
    flags = ["--only", "fig3b", "--cell", "μt = 2 α = 0.15", "--cell", "μt = 2 α = 0.83",
             "--spp", "2", "--scenes", SCENES]
    cli("experiment", "paper", "--out", tmp_path / "cli", *flags, "--quiet", cwd=ROOT)
    tasks = murk.experiment.plan(tmp_path / "dask", **args)
    [sweep] = [t for t in tasks if t["albedos"]]
    assert sweep["albedos"] == [0.15, 0.83] and "--albedos 0.15,0.83" in sweep["command"]
    assert len(sweep["outs"]) == 2 and len(sweep["capture_outs"]) == 2
    done = murk.experiment.run_dask(tmp_path / "dask", finish=False, **args)
    assert len(done) == 2
    for p in sweep["capture_outs"]:
        name = os.path.basename(p)
        assert open(p, "rb").read() == (tmp_path / "cli" / "renders" / name).read_bytes()
    assert murk.experiment.pending(murk.experiment.plan(tmp_path / "dask", **args)) == []


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="needs two cores for two render tasks at once")
def test_ctrl_c_keeps_the_studys_unfinished_renders_and_the_same_command_resumes(tmp_path):
    out = tmp_path / "study"
    # Fig. 3b at the quick scale: three rows of sweeps, several seconds each on one core.
    args = ["paper", "--out", str(out), "--only", "fig3b", "--scenes", str(SCENES), "--render-only"]
    script = tmp_path / "run.py"
    # A process started in the background inherits SIGINT ignored; a terminal's shell does not.
    script.write_text("""
import signal, sys, murk.experiment
if __name__ == "__main__":
    signal.signal(signal.SIGINT, signal.default_int_handler)
    sys.exit(murk.experiment.main(sys.argv[1:]))
""")
    p = subprocess.Popen([sys.executable, str(script), *args], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        renders = out / "renders"
        deadline = time.time() + 60
        while not (renders.exists() and any(f.suffix == ".ckpt" for f in renders.iterdir())):
            assert time.time() < deadline and p.poll() is None, "no render started"
            time.sleep(0.05)
        time.sleep(1.0)
        t0 = time.time()
        os.killpg(p.pid, signal.SIGINT)  # as a terminal does: the client and its workers
        _, err = p.communicate(timeout=60)
        stopped_s = time.time() - t0
    finally:
        try:
            os.killpg(p.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        p.wait()
    assert p.returncode == 130, err
    assert err.startswith("murk: interrupted;") and err.count("\n") == 1, err
    assert stopped_s < 10, stopped_s
    assert not [f for f in os.listdir(out) if f.startswith("murk-stop-")]
    assert [f for f in os.listdir(renders) if f.endswith(".ckpt")], "nothing unfinished was kept"
    r = subprocess.run([sys.executable, "-m", "murk.experiment", *args], capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stderr
    assert not [f for f in os.listdir(renders) if f.endswith(".ckpt")]
    tasks = murk.experiment.plan(out, only=["fig3b"], scenes=SCENES)
    assert murk.experiment.pending(tasks) == []


def test_bad_study_arguments(tmp_path):
    with pytest.raises(murk.InputError):
        murk.experiment.plan(tmp_path, only=["fig9"], scenes=SCENES)
    with pytest.raises(murk.InputError):
        murk.experiment.plan(tmp_path, scale="huge", scenes=SCENES)
    with pytest.raises(murk.InputError, match="spp must be a whole number ≥ 1, got 0"):
        murk.experiment.plan(tmp_path, spp=0, scenes=SCENES)
    with pytest.raises(murk.InputError, match="seeds must be in 1..=64, got 65"):
        murk.experiment.plan(tmp_path, seeds=65, scenes=SCENES)
    # Each keyword is named, not a bare TypeError; True is no count.
    for kw, name in [(dict(only=None), "only"), (dict(only=5), "only"), (dict(cells=None), "cells"),
                     (dict(cells=[1]), "cells"), (dict(spp=True), "spp"),
                     (dict(shards="2"), "shards")]:
        with pytest.raises(murk.InputError, match=f"^{name}"):
            murk.experiment.plan(tmp_path, scenes=SCENES, **kw)
    # One comma-separated string, as the CLI's --only takes it; one cell label, not its letters.
    tasks = murk.experiment.plan(tmp_path, only="fig3a", cells="fig3a", spp=4, scenes=SCENES)
    assert tasks == murk.experiment.plan(tmp_path, only=["fig3a"], spp=4, scenes=SCENES)
    # Absolute paths, as in the commands: a task runs from any folder.
    assert all(os.path.isabs(p) for t in tasks for p in [t["scene"], t["out"], *t["outs"]])


def test_run_dask_checks_its_arguments_before_a_cluster_starts(tmp_path, monkeypatch):
    def no_cluster(*a, **k):
        raise AssertionError("a cluster started")
    monkeypatch.setattr(murk.dask, "local_cluster", no_cluster)
    with pytest.raises(murk.InputError, match="^threads"):
        murk.experiment.run_dask(tmp_path, only=["fig3a"], spp=4, scenes=SCENES, threads="2")
    with pytest.raises(murk.InputError, match="^client: expected a dask.distributed.Client"):
        murk.experiment.run_dask(tmp_path, "x", only=["fig3a"], spp=4, scenes=SCENES)


def test_the_dask_phase_holds_the_folder_as_the_cli_does(tmp_path):
    # The lock run_dask holds while its cluster renders is the one murk experiment takes.
    murk.experiment.plan(tmp_path, only=["fig3a"], spp=4, scenes=SCENES)
    with murk.experiment._folder_held(os.fspath(tmp_path)):
        with pytest.raises(murk.InputError, match="another murk study is running in this folder"):
            murk.experiment.plan(tmp_path, only=["fig3a"], spp=4, scenes=SCENES)
    murk.experiment.plan(tmp_path, only=["fig3a"], spp=4, scenes=SCENES)


def test_an_interrupted_study_keeps_its_finished_units(tmp_path):
    # What Ctrl-C does: the progress poll raises, the render stops at its next unit and appends what
    # it finished to its checkpoint (whatever its 30 s interval), and the next run resumes from it.
    class Stop(Exception):
        pass

    def stop_early(done, total):
        if done >= 5:
            raise Stop()

    kw = dict(only=["fig3a"], spp=4096, scenes=SCENES, threads=1)
    with pytest.raises(Stop):
        murk.experiment.run(tmp_path, progress=stop_early, **kw)
    [ckpt] = (tmp_path / "renders").glob("*.h5.ckpt")
    assert ckpt.stat().st_size > 4096
    resumed = []
    murk.experiment.run(tmp_path, progress=lambda d, t: resumed.append(d), **kw)
    assert resumed[0] >= 5, resumed[:3]
    assert not list((tmp_path / "renders").glob("*.ckpt"))
