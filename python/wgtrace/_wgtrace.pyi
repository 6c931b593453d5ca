"""Type stubs of the compiled module (python/src/lib.rs)."""

import os
from typing import Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

PathLike = Union[str, "os.PathLike[str]"]
Image = Dict[str, npt.NDArray[np.float32]]
Progress = Callable[[int, int], object]
Adapter = Union[int, str]

__version__: str

class WgtraceError(RuntimeError): ...
class SceneError(ValueError): ...
class DenoiseError(WgtraceError): ...

class Scene:
    width: int
    height: int
    spp: int
    path: str
    warnings: List[str]
    def render(
        self,
        *,
        spp: Optional[int] = None,
        seed: Optional[int] = None,
        aovs: Optional[Sequence[str]] = None,
        denoise: Optional[bool] = None,
        samples: Optional[Tuple[int, int]] = None,
        progress: Optional[Progress] = None,
        backend: Optional[str] = None,
        adapter: Optional[Adapter] = None,
    ) -> Image: ...
    def accumulate(
        self,
        *,
        samples: Optional[Tuple[int, int]] = None,
        spp: Optional[int] = None,
        seed: Optional[int] = None,
        aovs: Optional[bool] = None,
        progress: Optional[Progress] = None,
        backend: Optional[str] = None,
        adapter: Optional[Adapter] = None,
    ) -> "Sums": ...

class Sums:
    width: int
    height: int
    samples: List[Tuple[int, int]]
    aovs: bool
    def image(self, *, aovs: Optional[Sequence[str]] = None, denoise: Optional[bool] = None) -> Image: ...
    def write_image(
        self, path: PathLike, *, aovs: Optional[Sequence[str]] = None, denoise: Optional[bool] = None
    ) -> None: ...
    def save(self, path: PathLike) -> None: ...
    @staticmethod
    def load(path: PathLike) -> "Sums": ...
    def to_bytes(self) -> bytes: ...
    @staticmethod
    def from_bytes(data: bytes) -> "Sums": ...

def load(
    path: PathLike,
    *,
    width: Optional[int] = None,
    height: Optional[int] = None,
    spp: Optional[int] = None,
    max_depth: Optional[int] = None,
    seed: Optional[int] = None,
    sampler: Optional[str] = None,
    light_sampling: Optional[str] = None,
    filter: Optional[str] = None,
    background: Optional[Sequence[float]] = None,
    camera: Optional[str] = None,
) -> Scene: ...
def merge(parts: List[Union[Sums, PathLike]]) -> Sums: ...
def adapters() -> List[Dict[str, Optional[str]]]: ...
def read_exr(path: PathLike) -> Image: ...
