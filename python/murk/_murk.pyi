"""Type stubs of the extension module; the documented API is the package `murk` (murk/__init__.py)."""

import os
from typing import Any, Callable, List, Optional, Sequence, Tuple, TypedDict, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, os.PathLike]
_Progress = Optional[Callable[[int, int], Any]]

__version__: str

class Capture:
    @property
    def H(self) -> npt.NDArray[np.float32]: ...
    @property
    def laser_points(self) -> npt.NDArray[np.float64]: ...
    @property
    def laser_normals(self) -> npt.NDArray[np.float64]: ...
    @property
    def sensor_points(self) -> npt.NDArray[np.float64]: ...
    @property
    def sensor_normals(self) -> npt.NDArray[np.float64]: ...
    @property
    def laser_xyz(self) -> Optional[Tuple[float, float, float]]: ...
    @property
    def sensor_xyz(self) -> Optional[Tuple[float, float, float]]: ...
    @property
    def start_m(self) -> float: ...
    @property
    def bin_width_m(self) -> float: ...
    @property
    def bins(self) -> int: ...
    @property
    def t(self) -> npt.NDArray[np.float64]: ...
    @property
    def kind(self) -> str: ...
    @property
    def pairing(self) -> str: ...
    @property
    def n_hist(self) -> int: ...
    @property
    def t_accounts_first_and_last_bounces(self) -> bool: ...
    @property
    def scene_info(self) -> str: ...
    def to_tal(self) -> Any: ...
    @staticmethod
    def from_tal(data: Any) -> "Capture": ...

def read_capture(path: _Path) -> Capture: ...
def write_capture(path: _Path, capture: Capture, compression: int = 0) -> None: ...
class _ImportArgs(TypedDict):
    format: Optional[str]
    var: Optional[str]
    axes: Optional[str]
    confocal: bool
    wall_size: Optional[float]
    bin_width_ps: Optional[float]
    bin_width_m: Optional[float]
    gate_bins: Optional[int]
    flip: Optional[str]
    t0_bin: Optional[int]
    tof: Optional[str]

def import_capture(path: _Path, args: _ImportArgs) -> Capture: ...
class _SynthArgs(TypedDict):
    targets: List[str]
    kind: str
    wall_size: float
    grid: int
    point: Tuple[float, float]
    bins: int
    bin_width: float
    start: float
    laser_xyz: Optional[Tuple[float, float, float]]
    sensor_xyz: Optional[Tuple[float, float, float]]
    mu_t: float
    jitter: float
    cosines: bool

class _RenderArgs(TypedDict):
    text: Optional[str]
    spp: Optional[int]
    seed: int
    shard: Optional[Tuple[int, int]]
    set: List[str]
    grid: Optional[int]
    bins: Optional[int]
    checkpoint: Optional[str]
    checkpoint_every: float
    out: Optional[str]
    albedos: List[float]

class _StudyArgs(TypedDict):
    scale: str
    only: List[str]
    cells: List[str]
    seeds: int
    shards: int
    spp: Optional[int]
    scenes: str

class _ReconstructArgs(TypedDict):
    method: str
    volume: Optional[str]
    wavelength: Optional[float]
    wavefactor: Optional[float]
    cycles: float
    compensate: Optional[str]
    mu_t: Optional[float]
    albedo: Optional[float]
    falloff: str
    lateral: str
    gate: str
    window_end: str
    t_offset: Optional[str]
    snr: Optional[float]
    weighting: str
    slab: Tuple[float, float, float, float]
    medium: Tuple[Optional[float], Optional[float], Optional[float]]
    medium_density: Optional[str]
    height_scale: Optional[float]

def synth(args: _SynthArgs) -> Capture: ...
def render(scene: str, args: _RenderArgs, threads: Optional[int], progress: _Progress) -> List[Capture]: ...
def merge(parts: Sequence[Union[Capture, str]]) -> Capture: ...
def render_part(scene: str, args: _RenderArgs, threads: Optional[int], progress: _Progress) -> None: ...
def check_render(scene: str, args: _RenderArgs, threads: Optional[int]) -> None: ...
def check_threads(threads: Optional[int]) -> None: ...
def assemble(scene: str, args: _RenderArgs, parts: Sequence[str]) -> Capture: ...
def study_plan(out: str, args: _StudyArgs) -> List[dict]: ...
def run_study(out: str, args: _StudyArgs, threads: Optional[int], progress: _Progress) -> str: ...
def methods() -> List[Tuple[str, str]]: ...
class _MediumArgs(TypedDict):
    fit: str
    mu_t: float
    albedo: float
    g: float
    until: Optional[float]

def estimate_medium(capture: Union[Capture, str], args: _MediumArgs, threads: Optional[int],
                    progress: _Progress) -> str: ...
def reconstruct(capture: Union[Capture, str], args: _ReconstructArgs, threads: Optional[int],
                progress: _Progress,
                ) -> Tuple[npt.NDArray[np.float32], List[npt.NDArray[np.float64]],
                           List[Tuple[str, str]], List[str],
                           Optional[npt.NDArray[np.float32]]]: ...
