"""murk from Python: NLOS captures, reconstructions (Phasor Fields and baselines) and Monte Carlo
renders through scattering media. Every function calls murk's Rust library, the same code as the
``murk`` command line, with the GIL released; Ctrl-C interrupts long calls.

>>> import murk
>>> cap = murk.synth(["z:2.0"], kind="laser-grid", wall_size=2, grid=32, bins=1024,
...                  bin_width=0.004, start=3.5, cosines=True)
>>> rec = murk.reconstruct(cap, method="pf", volume="-0.99:0.99:33,-0.99:0.99:33,1.5:2.5:33")
>>> rec.intensity.shape
(33, 33, 33)

See docs/python.md for a worked example, Dask (``murk.dask``) and the study (``murk.experiment``).
"""

import functools
import operator
import os
import re
import types
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _murk as _raw
from .errors import (
    Error,
    FileError,
    FormatError,
    InputError,
    LimitError,
    UnsupportedError,
)



class _Native:
    """The extension module, with its argument conversion errors ("failed to extract field
    RenderArgs.spp") raised as InputError naming the keyword and what was wrong with it."""

    def __init__(self, module):
        self._module = module

    def __getattr__(self, name):
        f = getattr(self._module, name)
        if not isinstance(f, types.BuiltinFunctionType):
            return f

        @functools.wraps(f)
        def call(*args, **kwargs):
            try:
                return f(*args, **kwargs)
            except (TypeError, OverflowError) as e:
                m = re.fullmatch(r"failed to extract field \w+\.(\w+)", str(e))
                if m is not None:
                    why = e.__cause__ if e.__cause__ is not None else "wrong type"
                    raise InputError(f"{m.group(1)}: {why}") from e
                # An argument passed on its own (`threads`, a capture) is named in pyo3's note.
                notes = (re.fullmatch(r"while processing '(\w+)'", n)
                         for n in getattr(e, "__notes__", ()))
                arg = next((n for n in notes if n is not None), None)
                if arg is None:
                    raise
                raise InputError(f"{arg.group(1)}: {e}") from e

        return call


_murk = _Native(_raw)
Capture = _murk.Capture
__version__ = _murk.__version__

__all__ = [
    "Capture",
    "Reconstruction",
    "read_capture",
    "write_capture",
    "import_capture",
    "synth",
    "render",
    "render_albedos",
    "merge",
    "reconstruct",
    "methods",
    "estimate_medium",
    "Error",
    "InputError",
    "FileError",
    "FormatError",
    "LimitError",
    "UnsupportedError",
]

Progress = Union[None, bool, Callable[[int, int], Any]]


def _progress(progress: Progress, label: str):
    """``True``: a tqdm bar; a callable: called as ``progress(done, total)`` on every change and at
    least every half second (an exception it raises stops the call); None/False: nothing."""
    if progress is None or progress is False:
        return None
    if callable(progress):
        return progress
    if not isinstance(progress, (bool, np.bool_)):
        raise InputError(f"progress: expected True, False, None or a callable (done, total), got "
                         f"{progress!r}")
    from tqdm.auto import tqdm

    # One bar per stage: a method whose plan reports progress (e.g. lct, cdt) starts a second one,
    # with another total, for its run.
    bar = None

    def update(done, total):
        nonlocal bar
        if bar is None or bar.total != total or done < bar.n:
            if bar is not None:
                bar.close()
            bar = tqdm(desc=label, total=total)
        bar.n = done
        bar.refresh()
        if done >= total:
            bar.close()

    return update


def read_capture(path: Union[str, bytes, os.PathLike]) -> Capture:
    """Reads a y-tal HDF5 capture (any H layout; pure-Rust HDF5, no libhdf5).

    >>> cap = murk.read_capture("z.h5")
    """
    return _murk.read_capture(_path(path, "path"))


def write_capture(path: Union[str, bytes, os.PathLike], capture: Capture, compression: int = 0):
    """Writes ``capture`` as a y-tal HDF5 file, atomically; ``compression`` 1..9 gzips H as y-tal's
    ``compression_level`` does.

    >>> murk.write_capture("copy.h5", cap)
    """
    _murk.write_capture(_path(path, "path"), capture, compression)


def import_capture(
    path: Union[str, bytes, os.PathLike],
    format: Optional[str] = None,
    *,
    wall_size: Optional[float] = None,
    bin_width_ps: Optional[float] = None,
    bin_width_m: Optional[float] = None,
    gate_bins: Optional[int] = None,
    flip: Optional[str] = None,
    t0_bin: Optional[int] = None,
    tof: Union[None, str, bytes, os.PathLike] = None,
    var: Optional[str] = None,
    axes: Optional[str] = None,
    confocal: bool = False,
) -> Capture:
    """Reads a public dataset's capture (``format``: cdt, lct, lct-transient, fk, ahn2019,
    xiao2024, wu2021, abp, znlos, bmm) or any 3-D array (``axes="t,x,y"`` in the array's order,
    ``var``, ``bin_width_*``, ``wall_size``, ``confocal=True``), as ``murk import``; the keywords
    are its flags. A ``bmm`` capture carries its medium's constants, which ``reconstruct(cap,
    "bmm")`` reads. docs/import.md has each dataset's details.

    >>> cap = murk.import_capture("4cmFoam_LambertianT_7cmFoam.mat", "bmm")
    >>> rec = murk.reconstruct(cap, "bmm")
    """
    return _murk.import_capture(_path(path, "path"), dict(
        format=format, var=var, axes=axes, confocal=confocal, wall_size=wall_size,
        bin_width_ps=bin_width_ps, bin_width_m=bin_width_m, gate_bins=gate_bins, flip=flip,
        t0_bin=t0_bin, tof=None if tof is None else _path(tof, "tof"),
    ))


def synth(
    targets: Union[str, Sequence[str]],
    *,
    kind: str = "laser-grid",
    wall_size: float = 1.0,
    grid: int = 32,
    point: Tuple[float, float] = (0.0, 0.0),
    bins: int = 2048,
    bin_width: float = 0.003,
    start: float = 0.0,
    laser_xyz: Optional[Tuple[float, float, float]] = None,
    sensor_xyz: Optional[Tuple[float, float, float]] = None,
    mu_t: float = 0.0,
    jitter: float = 0.0,
    cosines: bool = False,
) -> Capture:
    """An analytic capture (first hidden bounce), as ``murk synth``; the keywords are its flags.

    targets: ``point:X,Y,Z``, ``z:DEPTH`` (the paper's Z), ``t:DEPTH`` or ``polygon:DEPTH:x,y;x,y;...``.

    >>> cap = murk.synth("z:2.0", kind="laser-grid", wall_size=2, grid=128, bins=4096,
    ...                  bin_width=0.0009, start=3.5, cosines=True)   # the paper's Z
    """
    if isinstance(targets, str):
        targets = [targets]
    return _murk.synth(dict(
        targets=list(targets), kind=kind, wall_size=wall_size, grid=grid, point=tuple(point),
        bins=bins, bin_width=bin_width, start=start, laser_xyz=laser_xyz, sensor_xyz=sensor_xyz,
        mu_t=mu_t, jitter=jitter, cosines=cosines,
    ))


def _toml(v) -> str:
    """A Python value as the TOML value ``murk render --set key=VALUE`` takes (numpy arrays and
    scalars as the Python values they hold)."""
    if isinstance(v, (np.ndarray, np.generic)):
        v = v.tolist()
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml(x) for x in v) + "]"
    if isinstance(v, float):
        return repr(v)
    return str(v)


def _overrides(set) -> List[str]:
    if set is None:
        return []
    if isinstance(set, dict):
        return [f"{k}={_toml(v)}" for k, v in set.items()]
    return list(set)


def render(
    scene: Union[str, os.PathLike],
    *,
    spp: Optional[int] = None,
    seed: int = 0,
    shard: Optional[Tuple[int, int]] = None,
    set: Union[None, Dict[str, Any], Sequence[str]] = None,
    grid: Optional[int] = None,
    bins: Optional[int] = None,
    checkpoint: Union[None, str, os.PathLike] = None,
    checkpoint_every: float = 60.0,
    out: Union[None, str, os.PathLike] = None,
    threads: Optional[int] = None,
    progress: Progress = None,
) -> Capture:
    """A Monte Carlo render of a scene, as ``murk render``: identical bytes for any thread count and
    any sharding.

    scene: a scene file (TOML, see scenes/) or TOML text (relative paths in it are taken from the
    current folder). set: overrides as ``murk render --set`` takes them, as a dict
    (``{"medium.albedo": 0.8}``) or ``["medium.albedo=0.8"]``. shard: ``(i, n)`` renders part i of n
    for ``murk.merge``. checkpoint: a file to append finished work to and to resume from (removed
    once the render completes); checkpoint_every: seconds between its appends (0: after every
    unit). out: also write the capture there (atomically). progress: True for
    a tqdm bar or a callable ``(done, total)``.

    >>> cap = murk.render("scenes/z-letter.toml", grid=32, spp=64, set={"medium.albedo": 0.83})
    >>> part = murk.render("scenes/z-letter.toml", grid=32, shard=(0, 4), checkpoint="p0.ckpt")
    """
    path, args = _render_args(scene, spp=spp, seed=seed, shard=shard, set=set, grid=grid, bins=bins,
                              checkpoint=checkpoint, checkpoint_every=checkpoint_every, out=out)
    return _murk.render(path, args, threads, _progress(progress, "render"))[0]


def render_albedos(
    scene: Union[str, os.PathLike],
    albedos: Sequence[float],
    *,
    spp: Optional[int] = None,
    seed: int = 0,
    shard: Optional[Tuple[int, int]] = None,
    set: Union[None, Dict[str, Any], Sequence[str]] = None,
    grid: Optional[int] = None,
    bins: Optional[int] = None,
    checkpoint: Union[None, str, os.PathLike] = None,
    checkpoint_every: float = 60.0,
    out: Union[None, str, os.PathLike] = None,
    threads: Optional[int] = None,
    progress: Progress = None,
) -> List[Capture]:
    """``murk render --albedos``: one capture per medium albedo, from the same paths. Each equals, to
    float rounding, ``render(scene, set={"medium.albedo": a}, ...)`` with the same seed, for the tracing
    cost of one render. out: also write capture a to ``out`` with ``-albedo<a>`` before its extension.
    Other keywords as :func:`render`.

    >>> clear, thick = murk.render_albedos("scenes/z-letter.toml", [0.15, 0.83], grid=32, spp=64)
    """
    path, args = _render_args(scene, spp=spp, seed=seed, shard=shard, set=set, grid=grid, bins=bins,
                              checkpoint=checkpoint, checkpoint_every=checkpoint_every, out=out,
                              albedos=_albedos(albedos))
    return _murk.render(path, args, threads, _progress(progress, "render"))


def _path(value, what: str) -> str:
    """A path keyword as text (bytes decoded as the OS does); an empty one, which would name the
    current folder, and values that are not paths are refused naming the keyword."""
    try:
        p = os.fsdecode(value)
    except TypeError:
        raise InputError(f"{what}: expected a path, got {type(value).__name__}") from None
    if not p:
        raise InputError(f"{what}: the path is empty")
    return p


def _scene_text(scene) -> Optional[str]:
    """The scene keyword when it is TOML text rather than a path: it holds a newline (a scene needs
    at least two tables)."""
    return scene if isinstance(scene, str) and "\n" in scene else None


def _count(value, what: str) -> int:
    """A whole-number keyword of at least 1 (``grid``, ``bins``, ``shards``)."""
    try:
        n = None if isinstance(value, bool) else operator.index(value)
    except TypeError:
        n = None
    if n is None or n < 1:
        raise InputError(f"{what} must be a whole number ≥ 1, got {value!r}")
    return n


def _albedos(albedos) -> List[float]:
    """A sweep's albedos: a sequence of numbers, or one comma-separated string as ``--albedos``
    takes it."""
    if albedos is None:
        raise InputError("albedos: expected a list of numbers, got None (murk.render renders one)")
    if isinstance(albedos, str):
        albedos = [a for a in albedos.split(",") if a.strip()]
    try:
        if not isinstance(albedos, bytes):
            return [float(a) for a in albedos]
    except (TypeError, ValueError):
        pass
    raise InputError(f"albedos: expected a list of numbers, got {albedos!r}")


def _render_args(scene, *, spp, seed, shard, set, grid, bins, checkpoint=None, checkpoint_every=60.0,
                 out=None, albedos=None) -> Tuple[str, dict]:
    """The scene's path and the keywords ``_murk``'s render calls take; a scene given as TOML text
    is read as if from ``./scene.toml``."""
    text = _scene_text(scene)
    path = _path(scene, "scene") if text is None else os.path.join(os.getcwd(), "scene.toml")
    return path, dict(text=text, spp=spp, seed=seed, shard=None if shard is None else tuple(shard),
                      set=_overrides(set), grid=None if grid is None else _count(grid, "grid"),
                      bins=None if bins is None else _count(bins, "bins"),
                      checkpoint=None if checkpoint is None else _path(checkpoint, "checkpoint"),
                      checkpoint_every=checkpoint_every,
                      out=None if out is None else _path(out, "out"),
                      albedos=None if albedos is None else _albedos(albedos))


def merge(parts: Sequence[Union[Capture, str, os.PathLike]]) -> Capture:
    """The capture an unsharded render gives, bit for bit, from all its shards (Captures or files).

    >>> cap = murk.merge([murk.render(scene, shard=(i, 4)) for i in range(4)])
    """
    return _murk.merge([p if isinstance(p, Capture) else _path(p, "parts") for p in _parts(parts)])


def _parts(parts) -> list:
    """``parts`` as a list; one path alone (which would be read as its characters) is refused."""
    if isinstance(parts, (str, bytes, os.PathLike)):
        raise InputError(f"parts must be a list of captures or files, got the one path {parts!r}")
    return list(parts)


@dataclass(repr=False)
class Reconstruction:
    """A reconstructed volume: ``intensity[ix, iy, iz]`` (float32, C order) at voxel centres
    ``x[ix], y[iy], z[iz]`` (metres; z is the depth in front of the wall), the parameters used
    (``params``: the rows ``murk reconstruct`` prints), the library's warnings and, from the
    methods that recover surface orientation (dlct), ``normals[ix, iy, iz]``: the unit normal
    (float32, n_z < 0 facing the wall; zero where the intensity is), else ``None``."""

    intensity: np.ndarray
    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    params: Dict[str, str] = field(default_factory=dict)
    warnings: List[str] = field(default_factory=list)
    normals: Optional[np.ndarray] = None

    def __repr__(self) -> str:
        # The dataclass's own repr printed the whole intensity array and the axes' float noise.
        def axis(name, a):
            return f"{name} {a[0]:.6g}..{a[-1]:.6g} m" if len(a) else f"{name} empty"

        shape = " × ".join(str(n) for n in self.intensity.shape)
        method = self.params.get("method", "?")
        return (f"<murk.Reconstruction {method}: {shape} voxels, {axis('x', self.x)}, "
                f"{axis('y', self.y)}, {axis('z', self.z)}>")

    @property
    def dims(self) -> Tuple[str, str, str]:
        return ("x", "y", "z")

    @property
    def coords(self) -> Dict[str, np.ndarray]:
        return {"x": self.x, "y": self.y, "z": self.z}

    def to_xarray(self):
        """The volume as an ``xarray.DataArray`` (needs xarray)."""
        import xarray

        return xarray.DataArray(self.intensity, coords=self.coords, dims=self.dims,
                                attrs=dict(self.params))


def _text(v) -> Optional[str]:
    return None if v is None else str(v)


def reconstruct(
    capture: Union[Capture, str, os.PathLike],
    method: str = "pf",
    *,
    volume: Optional[str] = None,
    wavelength: Optional[float] = None,
    wavefactor: Optional[float] = None,
    cycles: float = 4.0,
    compensate: Optional[str] = None,
    mu_t: Optional[float] = None,
    albedo: Optional[float] = None,
    falloff: str = "none",
    lateral: str = "propagating",
    gate: Union[str, float] = "auto",
    window_end: str = "auto",
    medium_removal: str = "auto",
    depth_search: str = "auto",
    t_offset: Union[None, str, float] = None,
    snr: Optional[float] = None,
    weighting: str = "diffuse",
    slab_thickness: float = 0.0254,
    slab_mua: float = 0.53,
    slab_musp: float = 262.0,
    slab_n: float = 1.12,
    medium_n: Optional[float] = None,
    medium_musp: Optional[float] = None,
    medium_mua: Optional[float] = None,
    medium_density: Union[None, str, os.PathLike] = None,
    height_scale: Optional[float] = None,
    threads: Optional[int] = None,
    progress: Progress = None,
) -> Reconstruction:
    """Reconstructs a capture with any method of ``murk reconstruct`` (those ``murk.methods()``
    lists); the keywords are its flags and take the same values, and the volume is the one
    its ``--out x.npy`` writes, byte for byte. bmm's medium: ``medium_n``, ``medium_musp`` (μs′,
    1/m), ``medium_mua`` (μa, 1/m); unset ones come from the capture, else the BMM foam's.
    A heterogeneous medium's compensation (with ``mu_t``, σt where the density is 1):
    ``medium_density`` a density grid (.npy) or ``height_scale`` (m) a height fog over the medium's
    box of the capture's stored scene; a capture rendered from a height fog uses its own fog
    (docs/media-heterogeneous.md).

    capture: a Capture (its H is copied once, since reconstruction gates and tapers its own copy)
    or a capture file (read straight into the reconstruction: no copy). volume:
    ``"x0:x1:nx,y0:y1:ny,z0:z1:nz"`` (metres, inclusive; default: the wall grid's extent).

    >>> rec = murk.reconstruct("z.h5", volume="-0.99:0.99:73,-0.99:0.99:59,1.5:2.5:73")
    >>> rec.params["wavelength_m"], rec.intensity.max()
    >>> fk = murk.reconstruct(cap, "fk")     # confocal methods ("own volume") on their own grid
    >>> d = murk.reconstruct(cap, "dlct")   # d.normals[ix, iy, iz]: unit surface normals
    """
    intensity, axes, rows, warnings, normals = _murk.reconstruct(
        capture if isinstance(capture, Capture) else _path(capture, "capture"),
        dict(method=method, volume=volume, wavelength=wavelength, wavefactor=wavefactor,
             cycles=cycles, compensate=compensate, mu_t=mu_t, albedo=albedo, falloff=falloff,
             lateral=lateral, gate=_text(gate), window_end=window_end,
             medium_removal=medium_removal, depth_search=depth_search, t_offset=_text(t_offset),
             snr=snr, weighting=weighting,
             slab=(slab_thickness, slab_mua, slab_musp, slab_n),
             medium=(medium_n, medium_musp, medium_mua),
             medium_density=None if medium_density is None else _path(medium_density, "medium_density"),
             height_scale=height_scale),
        threads, _progress(progress, "reconstruct"),
    )
    x, y, z = axes
    return Reconstruction(intensity, x, y, z, dict(rows), list(warnings), normals)


def methods() -> Dict[str, str]:
    """The methods ``reconstruct`` takes, each with a line about it: the library's table, as
    ``murk reconstruct --help`` lists it.

    >>> "cdt" in murk.methods()
    """
    return dict(_murk.methods())


def estimate_medium(
    capture: Union[Capture, str, os.PathLike],
    *,
    fit: Sequence[str] = ("mu_t", "albedo", "g"),
    mu_t: float = 1.0,
    albedo: float = 0.5,
    g: float = 0.0,
    until: Optional[float] = None,
    threads: Optional[int] = None,
    progress: Progress = None,
) -> Dict[str, Any]:
    """Estimates the medium of a capture rendered by murk, as ``murk medium --json`` does: a dict
    with ``medium`` (False when none is detected, with a ``reason``), and otherwise ``mu_t_per_m``,
    ``albedo``, ``g``, each with ``_uncertainty``, ``_fitted`` and ``_constrained``, the bins used
    and the fit's residual. ``fit`` names the parameters to fit; the others take ``mu_t``,
    ``albedo`` and ``g``. ``until``: the last path (m) of the medium-only bins (default: where the
    scene's own signal begins).

    >>> m = murk.estimate_medium("fog.h5")
    >>> m["mu_t_per_m"], m["albedo"], m["g_constrained"]
    """
    import json

    text = _murk.estimate_medium(
        capture if isinstance(capture, Capture) else _path(capture, "capture"),
        dict(fit=",".join(fit), mu_t=float(mu_t), albedo=float(albedo), g=float(g), until=until),
        threads, _progress(progress, "medium"),
    )
    return json.loads(text)

def __dir__():
    # What the package offers, not the names its own code imports (Any, np, os, re, ...).
    return sorted(__all__ + ["__version__", "dask", "experiment"])


def __getattr__(name):
    # murk.dask and murk.experiment load on first use: dask is optional, and `python -m
    # murk.experiment` must not find the module already imported by the package.
    if name in ("dask", "experiment"):
        import importlib

        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'murk' has no attribute '{name}'")
