"""The paper's study (``murk experiment paper``) from Python, its render tasks on Dask.

>>> tasks = murk.experiment.plan("study", only=["fig3a"])     # what --list-tasks prints
>>> tasks[0]["command"]
'murk render scenes/z-letter.toml --out study/renders/....h5 --spp 512 --seed 0 ... --resume --quiet'
>>> murk.experiment.run_dask("study", only=["fig3a"])            # renders on a LocalCluster, then
...                                                              # figures, metrics and report

From a shell, with a scheduler already running (e.g. dask_jobqueue, see docs/python.md)::

    python -m murk.experiment paper --out study --scheduler tcp://head:8786 --only fig3a
"""

import argparse
import contextlib
import os
import sys
from typing import List, Optional, Sequence

import murk
from . import _murk
from .errors import InputError


def _strings(value, what: str) -> List[str]:
    """A list of names (``only``, ``cells``): any iterable of str."""
    try:
        items = list(value)
    except TypeError:
        items = None
    if items is None or not all(isinstance(v, str) for v in items):
        raise InputError(f"{what}: expected a string or a list of strings, got {value!r}")
    return items


def _study(scale, only, cells, seeds, shards, spp, scenes) -> dict:
    """The study's options as the extension takes them. ``only`` may also be one comma-separated
    string, as the CLI's flag takes it, and ``cells`` one label (a string is not read letter by
    letter)."""
    if isinstance(only, str):
        only = [f for f in only.split(",") if f]
    if isinstance(cells, str):
        cells = [cells]
    return dict(scale=scale, only=_strings(only, "only"), cells=_strings(cells, "cells"),
                seeds=murk._count(seeds, "seeds"), shards=murk._count(shards, "shards"),
                spp=None if spp is None else murk._count(spp, "spp"),
                scenes=murk._path(scenes, "scenes"))


@contextlib.contextmanager
def _folder_held(out: str):
    """Holds the study folder as ``murk experiment`` does (the same lock file), for the renders a
    Dask cluster runs between planning and the report. A file system without locks is not held."""
    try:
        import fcntl
    except ImportError:  # not a POSIX system
        yield
        return
    with open(os.path.join(out, ".lock"), "a") as f:
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise InputError(f"{out}: another murk study is running in this folder; wait for it to "
                             "end or choose another folder") from None
        except OSError:
            pass
        yield


def plan(
    out,
    *,
    scale: str = "quick",
    only: Sequence[str] = (),
    cells: Sequence[str] = (),
    seeds: int = 1,
    shards: int = 1,
    spp: Optional[int] = None,
    scenes="scenes",
) -> List[dict]:
    """Plans the study in ``out`` (writes plan.json, makes renders/) and returns its render tasks, in
    the order and with the commands of ``murk experiment paper --list-tasks``: dicts with ``id``,
    ``scene``, ``out``, ``spp``, ``seed``, ``shard``, ``set``, ``albedos`` (a sweep's, else empty),
    ``outs`` (the files the task writes), ``captures``, ``capture_outs`` (its merged captures) and
    ``command``."""
    return _murk.study_plan(murk._path(out, "out"), _study(scale, only, cells, seeds, shards, spp, scenes))


def run(out, *, scale="quick", only=(), cells=(), seeds=1, shards=1, spp=None, scenes="scenes",
        threads=None, progress=None) -> str:
    """``murk experiment paper --out OUT``: renders what is missing (merging finished shards),
    reconstructs, scores and writes the report; returns the path of index.html."""
    return os.fspath(_murk.run_study(murk._path(out, "out"),
                                     _study(scale, only, cells, seeds, shards, spp, scenes),
                                     threads, murk._progress(progress, "study")))


def pending(tasks: Sequence[dict]) -> List[dict]:
    """The tasks whose outputs, and whose job's merged captures, are not all there."""
    def there(paths):
        return all(os.path.exists(p) for p in paths)
    return [t for t in tasks if not there(t["outs"]) and not there(t["capture_outs"])]


def render_task(task: dict, threads=None, stop=None) -> str:
    """One Dask task: the study's render ``task`` as its ``murk render`` command runs it, into the
    files ``task["outs"]`` (kept if already there), resuming from ``out + ".ckpt"``; returns
    ``task["out"]``. ``stop``: as for ``murk.dask.render_shard``: once that file exists the render
    ends after its unit in flight, its finished units in the checkpoint and ``outs`` not written."""
    from .dask import _stoppable, _Stopped

    out = os.fspath(task["out"])
    if not all(os.path.exists(p) for p in task["outs"]):
        kw = dict(spp=task["spp"], seed=task["seed"], shard=task["shard"], set=task["set"],
                  checkpoint=out + ".ckpt", out=out, threads=threads,
                  progress=_stoppable(None, stop))
        try:
            if task["albedos"]:
                murk.render_albedos(task["scene"], task["albedos"], **kw)
            else:
                murk.render(task["scene"], **kw)
        except _Stopped:
            pass
    return out


def run_dask(out, client=None, *, scale="quick", only=(), cells=(), seeds=1, shards=1, spp=None,
             scenes="scenes", threads=None, finish=True):
    """Runs the study's pending render tasks on a Dask ``client`` (a LocalCluster when None), each
    resuming from its checkpoint, then (``finish``) the rest of the study here with :func:`run`.
    Returns index.html's path, or the list of rendered task outputs when ``finish`` is False."""
    from dask.distributed import Client

    from .dask import _gather, _stop_file, local_cluster

    opts = dict(scale=scale, only=only, cells=cells, seeds=seeds, shards=shards, spp=spp,
                scenes=os.path.abspath(murk._path(scenes, "scenes")))
    out = os.path.abspath(murk._path(out, "out"))
    # Checked before a cluster starts: every task would fail on them, three times each.
    _murk.check_threads(threads)
    if client is not None and not callable(getattr(client, "submit", None)):
        raise InputError(f"client: expected a dask.distributed.Client or None, got {client!r}")
    todo = pending(plan(out, **opts))
    with _folder_held(out):
        own = client is None
        if own:
            cluster = local_cluster()
            client = Client(cluster)
        stop = _stop_file(out)
        try:
            futures = [
                client.submit(render_task, t, threads=threads, stop=stop, retries=3, pure=False,
                              key=f"murk-render-{t['id']}")
                for t in todo
            ]
            done = _gather(client, futures, stop)
        finally:
            if own:
                client.close()
                cluster.close()
    if not finish:
        return done
    return run(out, threads=threads, **opts)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m murk.experiment",
        description="The paper's study with its render tasks on Dask; then figures, metrics and "
                    "the report as `murk experiment paper --out DIR` makes them.")
    p.add_argument("study", choices=["paper"])
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--scheduler", help="address of a running Dask scheduler (default: a LocalCluster)")
    p.add_argument("--scale", default="quick", choices=["quick", "paper"])
    p.add_argument("--only", default="", help="comma-separated figures: fig3a,fig3b,fig3c,fig4,fig5")
    p.add_argument("--cell", action="append", default=[], help="only cells whose label contains this")
    p.add_argument("--seeds", type=int, default=1)
    p.add_argument("--shards", type=int, default=1, help="render tasks per capture")
    p.add_argument("--spp", type=int)
    p.add_argument("--scenes", default="scenes", help="folder with z-letter.toml and shelf.toml")
    p.add_argument("--threads", type=int, help="renderer threads per task (default: all cores)")
    p.add_argument("--render-only", action="store_true",
                   help="only run the render tasks (finish later with `murk experiment paper`)")
    a = p.parse_args(argv)
    client = None
    if a.scheduler:
        from dask.distributed import Client

        client = Client(a.scheduler)
    try:
        r = run_dask(a.out, client, scale=a.scale, only=[s for s in a.only.split(",") if s],
                     cells=a.cell, seeds=a.seeds, shards=a.shards, spp=a.spp, scenes=a.scenes,
                     threads=a.threads, finish=not a.render_only)
    except murk.Error as e:
        print(f"murk: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"murk: interrupted; the finished renders and units are kept in {a.out}: the same "
              "command resumes them", file=sys.stderr)
        return 130
    print(r if isinstance(r, str) else f"rendered {len(r)} tasks into {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
