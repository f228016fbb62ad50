"""Type stubs of keymesh's compiled core (use the `keymesh` package)."""
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

class Error(ValueError):
    """Bad input for keymesh (a file, an array, an argument)."""

class LimitError(Error):
    """A request past a keymesh limit (e.g. more than 2^32 - 1 output points)."""

class Volume:
    """A voxel volume owned by keymesh; ``array`` is a writable (nx, ny, nz)
    view, axis 0 = x, Fortran order."""
    def __init__(self, array: npt.ArrayLike, spacing: Sequence[float] = ..., origin: Sequence[float] = ...,
                 name: str = ...) -> None: ...
    @staticmethod
    def zeros(shape: Sequence[int], dtype: Any = ..., spacing: Sequence[float] = ...,
              origin: Sequence[float] = ..., name: str = ...) -> "Volume": ...
    @property
    def array(self) -> np.ndarray: ...
    @property
    def shape(self) -> Tuple[int, int, int]: ...
    @property
    def dtype(self) -> np.dtype: ...
    spacing: Tuple[float, float, float]
    origin: Tuple[float, float, float]
    name: str

_MeshParts = Tuple[np.ndarray, np.ndarray, Optional[np.ndarray], Dict[str, np.ndarray]]

def contour(volume: Union[npt.ArrayLike, Volume], isovalues: List[float], spacing: Optional[Sequence[float]] = ...,
            origin: Optional[Sequence[float]] = ..., normals: str = ..., weld: str = ..., coarsen: bool = ..., curvature: bool = ...,
            threads: int = ...) -> Tuple[_MeshParts, Dict[str, Any]]: ...
def key_reduce(keys: np.ndarray, values: np.ndarray, op: str = ...,
               threads: int = ...) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]: ...
def check(mesh: Any, threads: int = ...) -> Dict[str, Any]: ...
def read(path: str, dims: Optional[Sequence[int]] = ..., dtype: Any = ..., spacing: Optional[Sequence[float]] = ...,
         origin: Optional[Sequence[float]] = ..., endian: str = ...,
         header_bytes: int = ...) -> Tuple[str, Union[Volume, _MeshParts]]: ...
def write_mesh(mesh: Any, path: str) -> None: ...
def write_volume(volume: Volume, path: str) -> None: ...
def thread_count() -> int: ...
