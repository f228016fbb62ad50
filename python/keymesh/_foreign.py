"""Volumes of other array libraries, and meshes handed back in them.

keymesh.contour reads any object that exposes DLPack (``__dlpack__`` and
``__dlpack_device__``: PyTorch, CuPy, JAX, numpy >= 1.22) or
``__cuda_array_interface__`` (CuPy, Numba) without a host copy:

- a host tensor (DLPack device CPU or CUDA pinned host memory) becomes a
  numpy array over the same memory, so the call is the numpy call: the same
  mesh, bit for bit; non-contiguous strides are copied as numpy's are;
- a CUDA tensor is contoured on its device (backend "cuda"); the mesh comes
  back in device memory, as arrays of the input's library when it has
  ``from_dlpack`` (CuPy, PyTorch, JAX), else as keymesh.DeviceArray.

The mesh of a host tensor of a library other than numpy is converted with
that library's ``from_dlpack`` too (a PyTorch CPU tensor gives PyTorch
tensors); numpy arrays and objects of a library without ``from_dlpack``
give numpy arrays.
"""
from __future__ import annotations

import sys
from typing import Any, Optional

import numpy as np

from . import _keymesh as _ext

# DLPack's device types (dlpack.h's DLDeviceType).
CPU, CUDA, CUDA_HOST = 1, 2, 3
_DEVICE_NAMES = {1: "CPU", 2: "CUDA", 3: "CUDA host", 4: "OpenCL", 7: "Vulkan", 8: "Metal", 9: "VPI",
                 10: "ROCm", 11: "ROCm host", 13: "CUDA managed", 14: "oneAPI"}


class Source:
    """A volume as keymesh.contour reads it: a host array (numpy, or a
    numpy view of a host tensor), or a CUDA tensor (a consumed DLPack
    capsule or an object with __cuda_array_interface__)."""

    __slots__ = ("value", "on_cuda", "library")

    def __init__(self, value: Any, on_cuda: bool, library: Optional[str]) -> None:
        self.value = value
        self.on_cuda = on_cuda
        self.library = library


def _library_of(obj: Any) -> str:
    return type(obj).__module__.partition(".")[0]


def _dlpack_capsule(volume: Any, stream: Optional[int]) -> Any:
    """volume.__dlpack__(stream=...): producers that predate the stream
    argument are called without it."""
    try:
        return volume.__dlpack__() if stream is None else volume.__dlpack__(stream=stream)
    except TypeError:
        if stream is None:
            raise
        return volume.__dlpack__()


def volume_source(volume: Any) -> Source:
    """Where keymesh.contour finds the samples of ``volume``."""
    if isinstance(volume, (np.ndarray, _ext.Volume)):
        return Source(volume, False, None)
    if hasattr(volume, "__dlpack_device__") and hasattr(volume, "__dlpack__"):
        device_type, _ = volume.__dlpack_device__()
        if device_type in (CPU, CUDA_HOST):
            return Source(_ext.host_view(_dlpack_capsule(volume, None)), False, _library_of(volume))
        if device_type == CUDA:
            # stream=1: the producer orders its work before the legacy
            # default stream, which keymesh's stream waits for.
            return Source(_dlpack_capsule(volume, 1), True, _library_of(volume))
        name = _DEVICE_NAMES.get(device_type, "unknown")
        raise TypeError(f"volume is on DLPack device type {device_type} ({name}); keymesh reads host (CPU) "
                        "and CUDA memory")
    if hasattr(volume, "__cuda_array_interface__"):
        return Source(volume, True, _library_of(volume))
    return Source(volume, False, None)  # a list, an object numpy reads: numpy's conversion, as before


def check_backend(source: Source, backend: Optional[str]) -> str:
    """The backend a call runs on: backend=None is where the volume lies."""
    if backend is None:
        return "cuda" if source.on_cuda else "cpu"
    if not isinstance(backend, str):
        raise TypeError(f"backend must be 'cpu', 'cuda' or None, got {type(backend).__name__}")
    if backend not in ("cpu", "cuda"):
        raise ValueError(f"backend must be 'cpu', 'cuda' or None (where the volume lies), got {backend!r}")
    if backend == "cpu" and source.on_cuda:
        raise ValueError("volume is in CUDA device memory and backend='cpu' reads host memory: pass "
                         "backend='cuda' (or None), or copy it to the host yourself (cupy.asnumpy(v), v.cpu())")
    return backend


def _converter(library: Optional[str]):
    """The input library's from_dlpack, or None (numpy arrays stay)."""
    if library in (None, "numpy", "keymesh"):
        return None
    module = sys.modules.get(library)  # imported: the volume is one of its objects
    convert = getattr(module, "from_dlpack", None)
    if convert is None and library == "torch":  # PyTorch before 1.13: torch.utils.dlpack only
        convert = getattr(getattr(getattr(module, "utils", None), "dlpack", None), "from_dlpack", None)
    return convert


def _torch_ids(convert):
    """PyTorch imports no uint32 through DLPack before 2.3 (and has few
    uint32 operations after): point ids come as int64, its index type,
    widened by PyTorch on the array's device from an int32 view of the same
    bytes (ids past 2^31 - 1 kept by the mask)."""
    def convert_ids(array):
        if np.dtype(array.dtype) != np.uint32:
            return convert(array)
        as_int32 = convert(array.view(np.int32))
        return as_int32.to(dtype=sys.modules["torch"].int64) & 0xFFFFFFFF
    return convert_ids


def in_library(parts: tuple, library: Optional[str]) -> tuple:
    """contour's (points, cells, offsets, point_data, cell_data) as arrays of
    ``library`` where it has from_dlpack (no copy; PyTorch's point ids
    int64, _torch_ids), else as they are."""
    convert = _converter(library)
    if convert is None:
        return parts
    if library == "torch":
        convert = _torch_ids(convert)
    points, cells, offsets, point_data, cell_data = parts
    return (convert(points), convert(cells), offsets, {k: convert(v) for k, v in point_data.items()},
            {k: convert(v) for k, v in cell_data.items()})
