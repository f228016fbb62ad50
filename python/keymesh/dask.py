"""keymesh.dask: contours of chunked Dask arrays (issue 36), equal to the
in-memory calls bit for bit.

    >>> import dask.array as da, keymesh.dask
    >>> volume = da.from_zarr("ct.zarr")            # or any dask array
    >>> mesh = keymesh.dask.contour(volume, 300.5)  # == keymesh.contour(volume.compute(), 300.5)

contour: one task per chunk contours the chunk's voxels (its samples and one
plane of its high neighbours', plus a ghost plane on every side for gradient
normals and curvature) with the whole grid's keys, a grid edge's key being
3 x its first point's id in the whole volume + its axis, the same in every
chunk; one merge task welds the pieces by one KEY-REDUCE and puts points and
triangles in the whole contour's order. The chunks' shared faces need no
coordinate comparison, and the mesh (points, triangles, their order and
every field) is the one ``keymesh.contour`` gives for the whole array, for
any chunking.

contour_labels: the label map is cut into slabs of its last axis, one task
per slab of chunks (the chunks along the last axis: ``array.chunks[2]``),
each slab spanning the whole first two axes. The slabs' passes are those of
``keymesh labels --memory-limit`` and ``mpirun ... keymesh labels``
(generate/labels_stream.hpp): distinct labels, voxel counts, then each
slab's pieces of the surfaces with global keys, merged, smoothed and
coarsened by one task: equal to ``keymesh.contour_labels`` on the whole
array, bit for bit.

labels_precomputed: Neuroglancer's multi-resolution meshes, one task per
Neuroglancer lod-0 chunk (the grid ``chunk_shape`` sets, whatever the Dask
chunks): each task reads its chunk's box plus the halo the meshing needs
(``array[box]``: only the Dask chunks that overlap it) and keeps its pieces
under ``path/chunks/`` as ``keymesh labels --chunk I J K`` does; one final
task writes the output from them as ``--assemble`` does. The directory is
byte-identical to the one-call run's.

The merge task holds the whole output mesh (the result comes back to the
caller anyway). Runs on any Dask scheduler: the threaded default, processes
or a ``dask.distributed`` cluster (the client in force).
"""
from __future__ import annotations

from typing import Any, Optional, Sequence

import numpy as np

from . import _keymesh as _ext
from . import Error, Mesh, _isovalues, _mesh, _threads

__all__ = ["contour", "contour_labels", "labels_precomputed"]


def _dask_array(array):
    import dask.array as da
    if not isinstance(array, da.Array):
        array = da.from_array(array, chunks=getattr(array, "chunks", "auto") or "auto")
    if array.ndim != 3:
        raise ValueError(f"keymesh.dask: the array must be 3-D, got {array.ndim}-D")
    return array


def _chunk_bounds(chunks):
    """Each chunk's first index along one axis, and the axis's length."""
    starts = np.concatenate([[0], np.cumsum(chunks)]).astype(int)
    return [(int(a), int(b)) for a, b in zip(starts[:-1], starts[1:])]


def _boxes(array, ghost: int):
    """Per chunk: the box of samples its task reads (slices) and the voxels
    it owns ([lo, hi) per axis). A chunk owns the voxels whose first corner
    is one of its samples; the box adds one plane above (their far corners)
    and, with ghosts, one more plane on every side the array has."""
    shape = array.shape
    per_axis = [_chunk_bounds(c) for c in array.chunks]
    for b0 in per_axis[0]:
        for b1 in per_axis[1]:
            for b2 in per_axis[2]:
                bounds = (b0, b1, b2)
                own_lo = [b[0] for b in bounds]
                own_hi = [min(b[1], n - 1) for b, n in zip(bounds, shape)]
                if any(lo >= hi for lo, hi in zip(own_lo, own_hi)):
                    continue  # a last chunk of one plane: its voxels are its neighbour's
                first = [max(lo - ghost, 0) for lo in own_lo]
                end = [min(hi + 1 + ghost, n) for hi, n in zip(own_hi, shape)]
                yield tuple(slice(a, b) for a, b in zip(first, end)), first, own_lo, own_hi


def _contour_chunk(block, order, kwargs):
    block = np.asfortranarray(block) if order == "F" else np.ascontiguousarray(block)
    return _ext.dask_contour_block(block, **kwargs)


def _merge_contour(pieces, kwargs):
    return _mesh(_ext.dask_contour_merge(list(pieces), **kwargs))


def _check_shape(array):
    for axis, n in enumerate(array.shape):
        if n < 2:
            raise Error(f"contour: grid has {n} point(s) along array axis {axis} (need at least 2)")


_SCALAR_DTYPES = tuple(np.dtype(t) for t in ("u1", "i1", "u2", "i2", "i4", "f4", "f8"))
# Label maps may also be the wide integers of connectomics segmentations.
_WIDE_LABEL_DTYPES = tuple(np.dtype(t) for t in ("u4", "i8", "u8"))


def _check_dtype(dtype, label_map: bool = False):
    dtype = np.dtype(dtype)
    native = dtype.newbyteorder("=")
    if native in _SCALAR_DTYPES or (label_map and native in _WIDE_LABEL_DTYPES):
        return
    hint = ("label maps of this type: contour_labels; convert with .astype(numpy.float64) for a contour"
            if native in _WIDE_LABEL_DTYPES else "convert with .astype(numpy.float32) for example")
    raise TypeError(f"volume has dtype {dtype}; keymesh supports uint8, int8, uint16, int16, int32, float32 "
                    f"and float64 ({hint})")


def _check_labels_dtype(dtype):
    _check_dtype(dtype, label_map=True)
    if np.dtype(dtype).kind == "f":
        raise Error(f"labels: a {np.dtype(dtype).name} volume is not a label map "
                    "(integer samples: uint8, int8, uint16, int16, int32, uint32, int64, uint64)")


def _order(order: str) -> str:
    if order not in ("C", "F"):
        raise ValueError(f"order must be 'C' or 'F', got {order!r}")
    return order


def _compute(result, compute: bool, scheduler):
    if not compute:
        return result
    return result.compute(scheduler=scheduler) if scheduler is not None else result.compute()


def contour(array: Any, iso: Any, spacing: Optional[Sequence[float]] = (1.0, 1.0, 1.0),
            origin: Optional[Sequence[float]] = (0.0, 0.0, 0.0), normals: Optional[str] = "average",
            weld: str = "keyreduce", coarsen: bool = False, curvature: bool = False, scalars: bool = True,
            order: str = "C", threads: int = 1, compute: bool = True, scheduler: Any = None,
            history: bool = False) -> Mesh:
    """Isosurface of a chunked 3-D Dask array: ``keymesh.contour`` of the
    whole array, bit for bit, made chunk by chunk.

    Args:
        array: a 3-D dask.array.Array (zarr-backed or any; other arrays,
            e.g. a zarr.Array, are wrapped with da.from_array and their own
            chunks) of uint8, int8, uint16, int16, int32, float32 or float64.
            Any chunking: chunks of one sample along an axis and uneven
            chunks included.
        iso, spacing, origin, normals, coarsen, curvature, scalars: as
            keymesh.contour (normals "average", "gradient" or "none";
            gradient normals and curvature read one ghost plane of samples on
            every side of a chunk, averaged normals and coarsening are
            computed by the merge task over the welded mesh).
        weld: "keyreduce" or "keyreduce-sort" (both give the same mesh);
            "vertexweld" compares coordinates and is refused (chunks weld by
            keys).
        order: the memory order whose in-memory contour to equal: "C"
            (default) gives ``keymesh.contour(np.ascontiguousarray(x))``,
            "F" gives ``keymesh.contour(np.asfortranarray(x))`` (the two
            triangulate some ambiguous cubes differently, see
            keymesh.contour). The chunks' own memory order does not matter.
        threads: worker threads of each chunk's task (default 1: the
            scheduler runs tasks side by side); the merge uses all cores.
        compute: False returns a dask Delayed whose result is the Mesh.
        history: point_data["history_key"] (uint64, the point's grid edge in
            the whole array) and point_data["history_t"] (float32), as
            keymesh.contour(..., history=True) gives them (docs/HISTORY.md):
            a chunk's keys are the whole grid's, so every chunking gives the
            same arrays. Not with coarsen (a coarse point has no one edge).
        scheduler: passed to dask's compute (default: dask's, or the
            dask.distributed client in force).

    Not supported: progress callbacks and VERTEX-WELD (ValueError).

    Returns:
        keymesh.Mesh, equal to ``keymesh.contour`` of the whole array:
        the same points, triangles, order and point_data.
    """
    import dask
    array = _dask_array(array)
    _check_shape(array)
    order = _order(order)
    if normals is None:
        normals = "none"
    if not isinstance(normals, str) or normals not in ("average", "gradient", "none"):
        raise ValueError(f"normals must be 'average', 'gradient' or 'none', got {normals!r}")
    if weld not in ("keyreduce", "keyreduce-sort"):
        raise ValueError(f"keymesh.dask.contour: weld {weld!r} is not supported: chunks are welded by keys "
                         "(use 'keyreduce' or 'keyreduce-sort')")
    _check_dtype(array.dtype)
    isovalues = _isovalues(iso)
    if not isovalues:
        raise ValueError("iso: give at least one isovalue")
    if not all(np.isfinite(isovalues)):
        raise ValueError(f"iso must be finite, got {iso!r}")
    threads = _threads(threads)
    if history and coarsen:
        raise ValueError("history with coarsen: a coarsened point merges crossings of several edges, so it has "
                         "no one edge and t (docs/HISTORY.md)")
    ghost = 1 if normals == "gradient" or curvature else 0
    chunk_kwargs = dict(isovalues=isovalues, spacing=spacing, origin=origin, whole=tuple(array.shape),
                        normals="gradient" if normals == "gradient" else "none", curvature=bool(curvature),
                        scalars=bool(scalars), coarse_keys=bool(coarsen), history=bool(history), threads=threads)
    task = dask.delayed(_contour_chunk, pure=True)
    pieces = []
    for box, first, own_lo, own_hi in _boxes(array, ghost):
        kwargs = dict(chunk_kwargs, first=tuple(first), own_lo=tuple(own_lo), own_hi=tuple(own_hi))
        pieces.append(task(array[box], order, kwargs))
    merge_kwargs = dict(whole=tuple(array.shape), isovalues=len(isovalues), average=normals == "average",
                        coarsen=bool(coarsen), history=bool(history), threads=0)
    return _compute(dask.delayed(_merge_contour, pure=True)(pieces, merge_kwargs), compute, scheduler)


def _label_slabs(array):
    """Per slab of chunks along axis 2: its padded rows [r0, r1) of the
    nz + 2 (the volume padded with a plane of background either side) and
    the planes [f0, f1) its passes read (labels_stream.cpp: a row's cells
    read the plane above, junction flags one plane further)."""
    nz = array.shape[2]
    bounds = _chunk_bounds(array.chunks[2])
    for q, (s, e) in enumerate(bounds):
        r0 = 0 if q == 0 else s + 1
        r1 = nz + 2 if q == len(bounds) - 1 else e + 1
        yield (r0, r1), max(r0 - 2, 0), min(r1 + 1, nz)


def _labels_distinct(slab, first_plane, whole, rows, options):
    return _ext.dask_labels_distinct(slab, first_plane, whole, rows, options)


def _labels_count(slab, first_plane, whole, rows, options, labels):
    return _ext.dask_labels_count(slab, first_plane, whole, rows, options, list(labels))


def _labels_pieces(slab, first_plane, whole, rows, options, labels, counts, spacing, origin, threads):
    return _ext.dask_labels_pieces(slab, first_plane, whole, rows, options, list(labels), list(counts), spacing,
                                   origin, threads)


def _labels_merge(dtype, whole, options, labels, counts, pieces, spacing, origin):
    from ._labels import LabelMesh
    return _mesh(_ext.dask_labels_merge(dtype, whole, options, list(labels), list(counts), list(pieces), spacing,
                                        origin, 0), LabelMesh)


def contour_labels(array: Any, spacing: Optional[Sequence[float]] = (1.0, 1.0, 1.0),
                   origin: Optional[Sequence[float]] = (0.0, 0.0, 0.0), method: str = "surface_nets",
                   labels: Optional[Sequence[int]] = None, background: int = 0, per_label: bool = False,
                   smoothing: bool = True, smoothing_iterations: int = 16, relaxation: float = 0.5,
                   coarsen: bool = False, threads: int = 1, compute: bool = True, scheduler: Any = None,
                   history: bool = False):
    """Surfaces of a chunked 3-D Dask label map: ``keymesh.contour_labels`` of
    the whole array, bit for bit.

    Tasks: the array is cut into slabs along axis 2 at its chunk bounds
    (``array.chunks[2]``), each slab spanning axes 0 and 1 whole (the chunks
    of a slab are joined by dask). Per slab, three tasks: its distinct
    labels, its voxel counts and label boxes (after every slab's labels are
    known), its pieces of the surfaces with global keys (after every slab's
    counts); then one task merges the pieces by key, smooths and coarsens
    the welded mesh. A slab's samples are read by each of its three tasks.

    Args:
        array: a 3-D integer dask.array.Array (uint8, int8, uint16, int16,
            int32, uint32, int64, uint64; labels past 2^24 are refused, see
            keymesh.contour_labels); other arrays are wrapped with
            da.from_array.
        spacing, origin, method, labels, background, per_label, smoothing,
        smoothing_iterations, relaxation, coarsen, history: as keymesh.contour_labels
            (smoothing and coarsening run in the merge task, on the welded
            mesh, as the in-memory call runs them).
        threads: worker threads of each slab's task (default 1); the merge
            uses all cores.
        compute, scheduler: as keymesh.dask.contour.

    Returns:
        keymesh.LabelMesh, equal to ``keymesh.contour_labels`` of the whole
        array: the same points, cells, order and cell_data.
    """
    import dask
    array = _dask_array(array)
    _check_labels_dtype(array.dtype)
    threads = _threads(threads)
    wanted = [] if labels is None else [int(v) for v in np.asarray(labels).reshape(-1)]
    options = (str(method), wanted, int(background), bool(per_label),
               int(smoothing_iterations) if smoothing else 0, float(relaxation), bool(coarsen), bool(history))
    whole = tuple(array.shape)
    slabs = [(array[:, :, f0:f1], f0, rows) for rows, f0, f1 in _label_slabs(array)]
    delayed = lambda f: dask.delayed(f, pure=True)  # noqa: E731
    distinct = [delayed(_labels_distinct)(s, f0, whole, rows, options) for s, f0, rows in slabs]
    counts = [delayed(_labels_count)(s, f0, whole, rows, options, distinct) for s, f0, rows in slabs]
    pieces = [delayed(_labels_pieces)(s, f0, whole, rows, options, distinct, counts, spacing, origin, threads)
              for s, f0, rows in slabs]
    result = delayed(_labels_merge)(np.dtype(array.dtype), whole, options, distinct, counts, pieces, spacing, origin)
    return _compute(result, compute, scheduler)


def _precomputed_chunk(box, whole, chunk, spacing, origin, path, options, threads, update):
    return _ext.precomputed_chunk(np.asarray(box), whole, chunk, spacing, origin, path, options, threads, update)


def _precomputed_assemble(whole, spacing, origin, path, options, names, update, counts):
    segments = set()
    for c in counts:  # --update: the segments the re-meshed chunks held before or hold now
        segments.update(c["segments"])
        segments.update(c.get("kept_segments", []))
    _ext.precomputed_assemble(whole, spacing, origin, path, options, names, sorted(segments) if update else None)
    report = {"segments": sorted(segments), "pieces": 0, "chunks_written": 0, "triangles_per_lod": []}
    for c in counts:
        report["pieces"] += c["pieces"]
        report["chunks_written"] += c["chunks_written"]
        per_lod = report["triangles_per_lod"]
        per_lod.extend([0] * (len(c["triangles_per_lod"]) - len(per_lod)))
        for lod, n in enumerate(c["triangles_per_lod"]):
            per_lod[lod] += n
    return report


def labels_precomputed(array: Any, path: Any, lods: int = 3, chunk_shape: Sequence[int] = (32, 32, 32),
                       sharded: bool = False, method: str = "surfacenets", labels: Optional[Sequence[int]] = None,
                       background: int = 0, smooth: int = 16, relaxation: float = 0.5,
                       spacing: Optional[Sequence[float]] = (1.0, 1.0, 1.0),
                       origin: Optional[Sequence[float]] = (0.0, 0.0, 0.0), label_names: Any = None,
                       threads: int = 1, compute: bool = True, scheduler: Any = None,
                       update: Optional[Sequence[Sequence[int]]] = None):
    """Neuroglancer multi-resolution meshes of a chunked 3-D Dask label map:
    the directory ``keymesh.labels_precomputed`` (and ``keymesh labels IN -o
    path --format precomputed``) writes, byte for byte, made chunk by chunk.

    Tasks: one per Neuroglancer lod-0 chunk (``chunk_shape``; the Dask
    chunking does not matter), each reading ``array[box]``, its chunk's box
    grown by the meshing's halo (``--smooth`` samples, twice that for
    discrete-mc, plus 4), meshing it and writing its pieces to
    ``path/chunks/`` (``keymesh labels --chunk I J K``; chunk tasks may run
    side by side, in threads or processes); then one task writes the output
    from every chunk's pieces (``keymesh labels --assemble``). On a
    dask.distributed cluster, ``path`` must be one directory for every
    worker (a shared file system).

    Args:
        array: a 3-D integer dask.array.Array (axis 0 is x; other arrays
            are wrapped with da.from_array).
        path, lods, chunk_shape, sharded, method, labels, background,
        smooth, relaxation, spacing, origin, label_names: as
            keymesh.labels_precomputed (a label table named by label_names
            is read when the graph is made).
        threads: worker threads of each chunk's task (default 1: the
            scheduler runs tasks side by side).
        compute, scheduler: as keymesh.dask.contour (compute=False returns
            a dask Delayed whose result is the report).
        update: re-mesh an edit (``keymesh labels --update CHUNKS``): the
            chunks (i, j, k) inside which ``array`` differs from the volume
            of the run that wrote ``path`` (its ``path/chunks/`` is needed).
            Only the chunks within the halo's reach of them are re-meshed (a
            task each) and only the segments they held or hold rewritten;
            the directory then equals a full run on ``array``.

    Returns:
        dict: ``segments``, ``pieces``, ``chunks_written``,
        ``triangles_per_lod``, equal to keymesh.labels_precomputed's.
    """
    import dask
    from . import _precomputed
    array = _dask_array(array)
    _check_labels_dtype(array.dtype)
    opts = _precomputed.options(lods, chunk_shape, sharded, method, labels, background, smooth, relaxation)
    path = _precomputed.output_path(path)
    threads = _threads(threads)
    whole = tuple(int(n) for n in array.shape)
    names = _precomputed.segment_names(label_names, opts[2])
    changed = _precomputed.changed_chunks(update)
    plan = _ext.precomputed_plan(whole, opts, path, changed)
    task = dask.delayed(_precomputed_chunk, pure=False)  # it writes a file: never merged with another graph's
    counts = [task(array[tuple(slice(a, a + n) for a, n in zip(lo, dims))], whole, tuple(chunk), spacing, origin,
                   path, opts, threads, changed is not None)
              for chunk, lo, dims in plan["boxes"]]
    result = dask.delayed(_precomputed_assemble, pure=False)(whole, spacing, origin, path, opts, names,
                                                             changed is not None, counts)
    return _compute(result, compute, scheduler)
