"""Renders spread over a Dask cluster: one task per shard, assembled into the bytes an unsharded render
gives. Each task renders its shard into a checkpoint file that holds only that shard's histograms, so
a task retried after its worker died resumes where the checkpoint left it, and a finished one is
reused.

>>> import murk.dask
>>> cap = murk.dask.render("scenes/z-letter.toml", shards=8, grid=64)          # a LocalCluster
>>> from dask.distributed import Client
>>> cap = murk.dask.render("scenes/z-letter.toml", client=Client("tcp://head:8786"),
...                        shards=64, workdir="/shared/scratch/z")              # a real cluster
>>> clear, thick = murk.dask.render_albedos("scenes/z-letter.toml", [0.15, 0.83], shards=8)

On a cluster the workers must see ``workdir`` (a shared file system) and the scene file.
"""

import os
import shutil
import tempfile
import time
import uuid
from typing import Any, Dict, List, Optional, Sequence, Union

import murk


# Dask's monitors (stack profiler every 10 ms, event-loop ticks every 20 ms, memory and system
# sampling) take CPU from the renders on small machines (docs/python.md gives the measurement). The
# profiler and system samples feed the dashboard, which murk's LocalCluster does not start; the ticks
# only warn of a blocked event loop; the memory monitor's spill, pause and terminate checks run every
# second instead of ten times a second.
QUIET_MONITORS = {
    "distributed.worker.profile.enabled": False,
    "distributed.admin.tick.interval": "1s",
    "distributed.admin.system-monitor.interval": "2s",
    "distributed.worker.memory.monitor-interval": "1s",
}


def local_cluster(monitors=QUIET_MONITORS, **kwargs):
    """A LocalCluster of single-threaded worker processes for murk's tasks, with Dask's monitors
    set by ``monitors`` (slowed down by default; ``{}`` keeps Dask's own settings). Its workers
    ignore Ctrl-C, which the client handles (:func:`render`).

    Dask's nannies set ``MALLOC_TRIM_THRESHOLD_`` in their workers to hand freed Python memory back
    to the system; any fixed threshold also turns off glibc's adaptive mmap threshold, so the
    renderer's large buffers would be mapped and unmapped on every use. Its workers run without
    it.

    Its processes print only critical log records: a task's error reaches the client, which raises
    it, while the workers' own records at a shutdown (a heartbeat that met the closing scheduler,
    after Ctrl-C) were tracebacks about nothing a user did. ``silence_logs`` sets another level."""
    import logging

    import dask
    from dask.distributed import LocalCluster

    config = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None, **monitors}
    kwargs.setdefault("silence_logs", logging.CRITICAL)
    with dask.config.set(config):
        return LocalCluster(threads_per_worker=1, processes=True, dashboard_address=None,
                            preload=["murk._worker"], **kwargs)


def render_shard(
    scene: str,
    shard,
    part: str,
    *,
    spp=None,
    seed=0,
    set=None,
    grid=None,
    bins=None,
    threads=None,
    checkpoint_every=60.0,
    progress=None,
    albedos=None,
    stop=None,
) -> str:
    """One Dask task: renders shard ``(i, n)`` of ``scene`` (of the sweep over ``albedos`` when
    given) into the checkpoint ``part``, which holds every unit of the shard when this returns (at
    once if it already did; an interrupted task's part resumes); returns ``part``. ``progress`` as
    for ``murk.render``. ``stop``: a file whose appearance ends the render after its unit in flight;
    ``part`` then holds the units done so far and is returned incomplete (``assemble`` says so), not
    raised as an error that Dask would log and retry. ``render`` creates one on Ctrl-C, so that its
    tasks end by themselves instead of being killed with their unsaved units."""
    part = murk._path(part, "part")
    path, args = murk._render_args(scene, spp=spp, seed=seed, shard=shard, set=set, grid=grid,
                                   bins=bins, checkpoint=part, checkpoint_every=checkpoint_every,
                                   albedos=albedos)
    try:
        murk._murk.render_part(path, args, threads,
                               _stoppable(murk._progress(progress, "shard"), stop))
    except _Stopped:
        pass
    return part


class _Stopped(Exception):
    """Raised from a task's progress calls once its stop file exists."""


def _stoppable(progress, stop):
    """``progress`` (a callable or None) that raises :class:`_Stopped` once the file ``stop``
    exists; the renderer then ends through its stop flag, which keeps its finished units. ``stop``
    None: ``progress`` itself."""
    if stop is None:
        return progress
    stop = os.fspath(stop)

    def update(done, total):
        if os.path.exists(stop):
            raise _Stopped()
        if progress is not None:
            progress(done, total)

    return update


# How long a Ctrl-C'd run waits for its tasks to save their finished units and end.
STOP_GRACE_S = 30.0


def _stop_file(folder) -> str:
    """A fresh stop file's path in ``folder`` (not created)."""
    return os.path.abspath(os.path.join(os.fspath(folder), f"murk-stop-{uuid.uuid4().hex}"))


def _gather(client, futures, stop: str):
    """``client.gather(futures)`` for tasks that watch the file ``stop``. On Ctrl-C it creates the
    file, waits up to ``STOP_GRACE_S`` for the tasks to save their work and end (a second Ctrl-C
    stops waiting), cancels those still queued or running, and raises ``KeyboardInterrupt``; the
    file is removed only if every task ended (cancelling does not stop a running one, which must
    still see it). The waiting polls here rather than in ``client.gather``, so that a Ctrl-C lands
    in this thread and not in Dask's event loop, which would print the gather's abandoned tasks."""
    try:
        while not all(f.done() for f in futures) and not any(f.status == "error" for f in futures):
            time.sleep(0.1)
    except KeyboardInterrupt:
        open(stop, "w").close()
        deadline = time.monotonic() + STOP_GRACE_S
        while not all(f.done() for f in futures) and time.monotonic() < deadline:
            time.sleep(0.1)
        left = [f for f in futures if not f.done()]
        client.cancel(left)
        if not left:
            os.remove(stop)
        raise
    return client.gather(futures)


def assemble(scene, parts, *, spp=None, seed=0, set=None, grid=None, bins=None, albedos=None):
    """The capture an unsharded render gives, bit for bit, from the parts ``render_shard`` completed:
    ``parts[i]`` holds shard ``(i, len(parts))`` of ``scene`` with the same keywords; with
    ``albedos``, the list of the sweep's captures. A part of another render, or one with units
    missing, raises ``murk.FormatError`` naming its file."""
    caps = _assemble_all(scene, parts, spp=spp, seed=seed, set=set, grid=grid, bins=bins,
                         albedos=albedos)
    return caps if albedos is not None else caps[0]


def _assemble_all(scene, parts, *, spp, seed, set, grid, bins, albedos):
    """Every capture of the render (one, or one per albedo of a sweep)."""
    path, args = murk._render_args(scene, spp=spp, seed=seed, shard=None, set=set, grid=grid,
                                   bins=bins, albedos=albedos)
    return murk._murk.assemble(path, args, [murk._path(p, "parts") for p in murk._parts(parts)])


def render(
    scene: Union[str, os.PathLike],
    client=None,
    shards: int = 2,
    *,
    spp: Optional[int] = None,
    seed: int = 0,
    set: Union[None, Dict[str, Any], Sequence[str]] = None,
    grid: Optional[int] = None,
    bins: Optional[int] = None,
    workdir: Union[None, str, os.PathLike] = None,
    out: Union[None, str, os.PathLike] = None,
    threads: Optional[int] = None,
    checkpoint_every: float = 60.0,
    retries: int = 3,
) -> "murk.Capture":
    """Renders ``scene`` as ``shards`` Dask tasks on ``client`` and assembles them: the same bytes as
    ``murk.render(scene, ...)`` unsharded. Without a client a LocalCluster of one single-threaded
    worker per core runs it (at most ``shards`` workers). ``workdir`` keeps the parts, one
    checkpoint file per shard (default: a temporary folder, removed afterwards); a complete part
    already there is reused, an incomplete one resumed.
    ``threads``: renderer threads per task (default: all cores of the worker, or one per worker on
    the LocalCluster). ``out``: also write the assembled capture there.
    """
    return _render(scene, client, shards, None, spp=spp, seed=seed, set=set, grid=grid, bins=bins,
                   workdir=workdir, out=out, threads=threads, checkpoint_every=checkpoint_every,
                   retries=retries)


def render_albedos(
    scene: Union[str, os.PathLike],
    albedos: Sequence[float],
    client=None,
    shards: int = 2,
    *,
    spp: Optional[int] = None,
    seed: int = 0,
    set: Union[None, Dict[str, Any], Sequence[str]] = None,
    grid: Optional[int] = None,
    bins: Optional[int] = None,
    workdir: Union[None, str, os.PathLike] = None,
    out: Union[None, str, os.PathLike] = None,
    threads: Optional[int] = None,
    checkpoint_every: float = 60.0,
    retries: int = 3,
) -> List["murk.Capture"]:
    """:func:`render` for an albedo sweep: the captures ``murk.render_albedos(scene, albedos, ...)``
    gives unsharded, byte for byte, one per albedo; ``out`` names them as it does."""
    return _render(scene, client, shards, murk._albedos(albedos), spp=spp, seed=seed, set=set, grid=grid,
                   bins=bins, workdir=workdir, out=out, threads=threads,
                   checkpoint_every=checkpoint_every, retries=retries)


def _render(scene, client, shards, albedos, *, spp, seed, set, grid, bins, workdir, out, threads,
            checkpoint_every, retries):
    from dask.distributed import Client

    if murk._scene_text(scene) is None:
        scene = os.path.abspath(murk._path(scene, "scene"))
    # Here once, before a cluster starts: in the tasks each refusal would be logged and retried,
    # and an output that cannot be written would be found only after every shard had rendered.
    murk._count(shards, "shards")
    path, args = murk._render_args(scene, spp=spp, seed=seed, shard=(0, shards), set=set,
                                   grid=grid, bins=bins, albedos=albedos, out=out)
    murk._murk.check_render(path, args, threads)
    if workdir is not None:
        workdir = murk._path(workdir, "workdir")
        if os.path.exists(workdir) and not os.path.isdir(workdir):
            raise murk.InputError(f"{workdir}: the workdir is a file, not a folder")
    own = client is None
    if own:
        cores = os.cpu_count() or 1
        workers = max(1, min(shards, cores))
        cluster = local_cluster(n_workers=workers)
        client = Client(cluster)
        if threads is None:
            threads = max(1, cores // workers)
    tmp = workdir is None
    workdir = tempfile.mkdtemp(prefix="murk-dask-") if tmp else workdir
    os.makedirs(workdir, exist_ok=True)
    stop = _stop_file(workdir)
    try:
        futures = [
            client.submit(render_shard, scene, (i, shards),
                          os.path.abspath(os.path.join(workdir, f"part{i}.ckpt")), spp=spp,
                          seed=seed, set=set, grid=grid, bins=bins, threads=threads,
                          checkpoint_every=checkpoint_every, albedos=albedos, stop=stop,
                          retries=retries, pure=False)
            for i in range(shards)
        ]
        parts = _gather(client, futures, stop)
        caps = _assemble_all(scene, parts, spp=spp, seed=seed, set=set, grid=grid, bins=bins,
                             albedos=albedos)
        if out is not None:
            for path, cap in zip(murk._murk.render_outputs(murk._path(out, "out"), albedos), caps):
                murk.write_capture(path, cap)
        return caps if albedos is not None else caps[0]
    finally:
        if own:
            client.close()
            cluster.close()
        if tmp:
            shutil.rmtree(workdir, ignore_errors=True)
