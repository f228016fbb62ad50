"""keymesh.labels_precomputed: Neuroglancer's multi-resolution meshes of a
label volume (issue 37), the bytes ``keymesh labels IN -o DIR --format
precomputed`` writes. keymesh.dask.labels_precomputed makes the same
directory with one Dask task per chunk (python/keymesh/dask.py).
"""
from __future__ import annotations

import numbers
import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _keymesh as _ext
from . import _threads
from ._arguments import INT32, int_arg

# The CLI's ranges (keymesh labels --help): --lods 1-20, --chunk-shape 2-1048576,
# --relaxation (0, 1], --smooth >= 0.
_LODS = (1, 20)
_CHUNK_SHAPE = (2, 1048576)


def _int_in(value: Any, name: str, lo: int, hi: int) -> int:
    if not isinstance(value, (numbers.Integral, np.integer)) or isinstance(value, bool):
        raise TypeError(f"{name} must be an int, got {type(value).__name__}")
    v = int(value)
    if not lo <= v <= hi:
        raise ValueError(f"{name} must be in [{lo}, {hi}], got {v}")
    return v


def options(lods, chunk_shape, sharded, method, labels, background, smooth, relaxation) -> tuple:
    """The arguments both functions share, checked as the CLI checks its
    options, as the tuple the compiled module takes."""
    lods = _int_in(lods, "lods", *_LODS)
    shape = list(np.asarray(chunk_shape, dtype=object).reshape(-1))
    if len(shape) != 3:
        raise ValueError(f"chunk_shape must be 3 integers (x, y, z), got {chunk_shape!r}")
    shape = tuple(_int_in(v, f"chunk_shape[{a}]", *_CHUNK_SHAPE) for a, v in enumerate(shape))
    if method not in ("surfacenets", "discrete-mc", "surface_nets", "discrete_marching_cubes"):
        raise ValueError(f"method must be 'surfacenets' or 'discrete-mc', got {method!r}")
    smooth = _int_in(smooth, "smooth", 0, INT32[1])
    relaxation = float(relaxation)
    if not 1e-9 <= relaxation <= 1:
        raise ValueError(f"relaxation must be in (0, 1], got {relaxation!r}")
    wanted = [] if labels is None else [int_arg(v, f"labels[{i}]")
                                        for i, v in enumerate(np.asarray(labels, dtype=object).reshape(-1))]
    return (str(method), wanted, int_arg(background, "background"), smooth, relaxation, lods, shape, bool(sharded))


def output_path(path: Union[str, os.PathLike]) -> str:
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a str or os.PathLike (a directory), got {type(path).__name__}")
    return os.fspath(path)


def changed_chunks(update: Any) -> Optional[List[Tuple[int, int, int]]]:
    """update (None, or the chunks (i, j, k) an edit changed) as the list the
    compiled module takes; ValueError unless each is three integers."""
    if update is None:
        return None
    changed = [tuple(int_arg(v, "update") for v in np.asarray(c).reshape(-1)) for c in update]
    if any(len(c) != 3 for c in changed):
        raise ValueError(f"update must be chunks (i, j, k), got {update!r}")
    return changed


def segment_names(label_names: Any, background: int) -> Dict[int, str]:
    """label_names (None, a label table's path or a dict) as {id: name},
    read now (the Dask graph carries the names, not the file)."""
    return _ext.precomputed_segment_names(label_names, background)


def labels_precomputed(volume: Any, path: Union[str, os.PathLike], lods: int = 3,
                       chunk_shape: Sequence[int] = (32, 32, 32), sharded: bool = False, method: str = "surfacenets",
                       labels: Optional[Sequence[int]] = None, background: int = 0, smooth: int = 16,
                       relaxation: float = 0.5, spacing: Optional[Sequence[float]] = (1.0, 1.0, 1.0),
                       origin: Optional[Sequence[float]] = (0.0, 0.0, 0.0),
                       label_names: Union[None, str, os.PathLike, Mapping[int, str]] = None,
                       threads: int = 0, update: Optional[Sequence[Sequence[int]]] = None) -> Dict[str, Any]:
    """Neuroglancer multi-resolution meshes of a label volume: the directory
    ``keymesh labels IN -o path --format precomputed`` writes, byte for byte
    (one call; docs/cli/labels.md).

    Each label is a segment: its closed surface clipped at the lod-0 chunk
    planes (chunk (i, j, k) starts at sample ``-1 + (i, j, k) * chunk_shape``)
    and coarsened per chunk for each of ``lods`` levels, so that neighbouring
    chunks agree on their common face. Writes ``path/info``
    (``neuroglancer_multilod_draco``), a manifest and data file per segment
    (or the sharded layout), ``segment_properties/`` when names are given,
    and every chunk's pieces under ``path/chunks/`` (which ``keymesh labels
    --chunk``/``--assemble``/``--update`` read; delete it when no update will
    follow).

    Args:
        volume: a 3-D integer numpy array (axis 0 is x) or a keymesh.Volume.
        path: the output directory (created; a file, or a name like a mesh
            file's, is refused).
        lods: levels of detail, 1 to 20 (``--lods``, default 3).
        chunk_shape: samples per lod-0 chunk along x, y, z, each at least 2
            (``--chunk-shape``, default 32 32 32).
        sharded: the sharded layout (``--sharded``).
        method: "surfacenets" (default) or "discrete-mc" (``--method``;
            contour_labels' "surface_nets" and "discrete_marching_cubes" too).
        labels, background: the labels to mesh (default: all but the
            background) and the background label (``--labels``,
            ``--background``).
        smooth, relaxation: smoothing iterations (default 16, 0 = off) and
            relaxation factor in (0, 1] (default 0.5) (``--smooth``,
            ``--relaxation``).
        spacing, origin: the volume's geometry, written as the info's
            transform (ignored for a keymesh.Volume, which has its own).
        label_names: the segments' names (segment_properties): a label table
            file (``--label-names``: one "ID NAME" a line) or a dict
            {id: name}; None (default) writes none. The background's entry is
            left out.
        threads: worker threads, 0 = all cores; the bytes do not depend on it.
        update: re-mesh an edit (``keymesh labels --update CHUNKS``): the
            chunks (i, j, k) inside which ``volume`` differs from the volume
            of the run that wrote ``path`` (its ``path/chunks/`` is needed).
            Only the chunks within the halo's reach of them are re-meshed
            and only the segments they held or hold rewritten; the directory
            then equals a full run on ``volume``.

    Returns:
        dict: ``segments`` (the segment ids with a mesh; with ``update``,
        those rewritten), ``pieces``, ``chunks_written``,
        ``triangles_per_lod`` (as the CLI's report counts them).

    Raises:
        keymesh.Error (a ValueError) for what the CLI refuses (negative
        labels, a float volume), ValueError/TypeError for bad arguments.
    """
    if isinstance(volume, _ext.Volume):
        spacing = origin = None
    opts = options(lods, chunk_shape, sharded, method, labels, background, smooth, relaxation)
    return _ext.labels_precomputed(volume, spacing, origin, output_path(path), opts, label_names, _threads(threads),
                                   changed_chunks(update))
