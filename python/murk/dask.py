"""Renders spread over a Dask cluster: one task per shard, merged into the bytes an unsharded render
gives. Each task writes its shard with a checkpoint next to it, so a task retried after its worker
died resumes where the checkpoint left it.

>>> import murk.dask
>>> cap = murk.dask.render("scenes/z-letter.toml", shards=8, grid=64)          # a LocalCluster
>>> from dask.distributed import Client
>>> cap = murk.dask.render("scenes/z-letter.toml", client=Client("tcp://head:8786"),
...                        shards=64, workdir="/shared/scratch/z")              # a real cluster

On a cluster the workers must see ``workdir`` (a shared file system) and the scene file.
"""

import os
import shutil
import tempfile
from typing import Any, Dict, Optional, Sequence, Union

import murk


def local_cluster(**kwargs):
    """A LocalCluster of single-threaded worker processes for murk's tasks. Dask's nannies set
    ``MALLOC_TRIM_THRESHOLD_`` in their workers to hand freed Python memory back to the system; any
    fixed threshold also turns off glibc's adaptive mmap threshold, so the renderer's large buffers
    are mapped and unmapped on every use, which cost it 4-8 % here. Its workers run without it."""
    import dask
    from dask.distributed import LocalCluster

    with dask.config.set({"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}):
        return LocalCluster(threads_per_worker=1, processes=True, dashboard_address=None, **kwargs)


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
) -> str:
    """One Dask task: renders shard ``(i, n)`` of ``scene`` into ``part`` (kept if already there),
    resuming from ``part + ".ckpt"``; returns ``part``."""
    part = os.fspath(part)
    if not os.path.exists(part):
        murk.render(scene, spp=spp, seed=seed, shard=shard, set=set, grid=grid, bins=bins,
                    checkpoint=part + ".ckpt", checkpoint_every=checkpoint_every, out=part,
                    threads=threads)
    return part


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
    """Renders ``scene`` as ``shards`` Dask tasks on ``client`` and merges them: the same bytes as
    ``murk.render(scene, ...)`` unsharded. Without a client a LocalCluster of one single-threaded
    worker per core runs it (at most ``shards`` workers). ``workdir`` keeps the parts and their
    checkpoints (default: a temporary folder, removed afterwards); a part already there is reused.
    ``threads``: renderer threads per task (default: all cores of the worker, or one per worker on
    the LocalCluster). ``out``: also write the merged capture there.
    """
    from dask.distributed import Client

    scene = os.fspath(scene)
    if "\n" not in scene:
        scene = os.path.abspath(scene)
    own = client is None
    if own:
        cores = os.cpu_count() or 1
        workers = max(1, min(shards, cores))
        cluster = local_cluster(n_workers=workers)
        client = Client(cluster)
        if threads is None:
            threads = max(1, cores // workers)
    tmp = workdir is None
    workdir = tempfile.mkdtemp(prefix="murk-dask-") if tmp else os.fspath(workdir)
    os.makedirs(workdir, exist_ok=True)
    try:
        futures = [
            client.submit(render_shard, scene, (i, shards),
                          os.path.abspath(os.path.join(workdir, f"part{i}.h5")), spp=spp,
                          seed=seed, set=set, grid=grid, bins=bins, threads=threads,
                          checkpoint_every=checkpoint_every, retries=retries, pure=False)
            for i in range(shards)
        ]
        parts = client.gather(futures)
        cap = murk.merge(parts)
        if out is not None:
            murk.write_capture(out, cap)
        return cap
    finally:
        if own:
            client.close()
            cluster.close()
        if tmp:
            shutil.rmtree(workdir, ignore_errors=True)
