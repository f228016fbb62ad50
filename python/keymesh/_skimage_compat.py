"""keymesh.marching_cubes: a drop-in for skimage.measure.marching_cubes.

The arguments are checked in scikit-image's order with its exception types
and messages; the work (classification, triangles, KEY-REDUCE weld, normals,
values, point numbering, winding) runs in C++ with the GIL released
(generate/classic_marching_cubes.hpp). Only the scaling by ``spacing`` is
numpy, done exactly as scikit-image does it so that the dtypes agree (float32
points at unit spacing, float64 otherwise).
"""
from __future__ import annotations

from typing import Any, Callable, Optional, Sequence, Tuple

import numpy as np

from . import _keymesh as _ext
from ._arguments import INT32, int_arg

_TABLE_CACHE: list = []


def _case_table() -> Optional[np.ndarray]:
    """scikit-image's classic case table when scikit-image is installed
    (its faces and normals are then reproduced exactly), else None: keymesh's
    own table (same points, values and polygons; some cubes split along the
    other diagonal, which moves the normals of their points)."""
    if not _TABLE_CACHE:
        table = None
        try:
            from skimage.measure import _marching_cubes_lewiner as mcl
            from skimage.measure import _marching_cubes_lewiner_luts as luts

            table = np.ascontiguousarray(mcl._to_array(luts.CASESCLASSIC), dtype=np.int8)
            if table.shape != (256, 16):
                table = None
        except Exception:  # not installed, or a layout this code does not know
            table = None
        _TABLE_CACHE.append(table)
    return _TABLE_CACHE[0]


_MC33_CACHE: list = []


def _mc33_tables() -> Optional[dict]:
    """Lewiner et al.'s Marching Cubes 33 tables as scikit-image ships them
    ({name: int8 array}: CASES, TILING*, TEST*, SUBCONFIG13), read from the
    installed scikit-image at the first call; None without it. keymesh
    carries no copy of them; the decisions that use them are keymesh's own
    (generate/classic_marching_cubes.cpp), checked against scikit-image."""
    if not _MC33_CACHE:
        tables = None
        try:
            from skimage.measure import _marching_cubes_lewiner as mcl
            from skimage.measure import _marching_cubes_lewiner_luts as luts

            names = [n for n in dir(luts) if n.isupper() and (n.startswith(('TILING', 'TEST'))
                                                               or n in ('CASES', 'SUBCONFIG13'))]
            tables = {n: np.ascontiguousarray(mcl._to_array(getattr(luts, n)), dtype=np.int8) for n in names}
        except Exception:  # not installed, or a layout this code does not know
            tables = None
        _MC33_CACHE.append(tables)
    return _MC33_CACHE[0]


def uses_skimage_table() -> bool:
    """Whether marching_cubes triangulates cubes with scikit-image's table."""
    return _case_table() is not None


def _remove_degenerate_faces(vertices, faces, *arrays):
    # scikit-image's rule: a face with two equal corners (positions compared
    # exactly) is dropped and those corners merge into the lower index;
    # merged points are removed and the faces renumbered (int64).
    return _ext.remove_degenerate_faces(vertices, faces, list(arrays))


def _mask_bytes(mask) -> np.ndarray:
    # scikit-image passes the mask to Cython as np.ndarray[npy_bool, cast=True]:
    # any ndarray of 1-byte items is taken byte for byte (nonzero = set);
    # wider items (float, int64, ...) raise ValueError, non-arrays TypeError.
    if not isinstance(mask, np.ndarray):
        raise TypeError("Argument 'mask' has incorrect type (expected numpy.ndarray, got %s)"
                        % type(mask).__name__)
    if mask.dtype.itemsize != 1:
        raise ValueError("Item size of buffer (%d bytes) does not match size of 'npy_bool' (1 byte)"
                         % mask.dtype.itemsize)
    return np.ascontiguousarray(mask).view(np.uint8)


def _level(volume, level, spacing):
    # scikit-image's level (None: the mid-range) and spacing checks
    if level is None:
        level = 0.5 * (volume.min() + volume.max())
    else:
        level = float(level)
        if level < volume.min() or level > volume.max():
            raise ValueError("Surface level must be within volume data range.")
    if len(spacing) != 3:
        raise ValueError("`spacing` must consist of three floats.")
    return level


def _old_lorensen(volume, level, spacing, gradient_direction, threads, progress):
    # scikit-image 0.19's method='_lorensen' (its old classic code): checks in
    # its order, float64 data, no step_size or allow_degenerate, and two
    # arrays: float64 points (always times spacing) and int64 faces with no
    # degenerate triangle. keymesh gives its 'lorensen' surface with
    # degenerate triangles removed: the same points (to float32 rounding),
    # some cubes split along the other diagonal.
    if volume.ndim != 3:
        raise ValueError("Input volume must have 3 dimensions.")
    level = _level(volume, level, spacing)
    if volume.shape[0] < 2 or volume.shape[1] < 2 or volume.shape[2] < 2:
        raise ValueError("Input array must be at least 2x2x2.")
    # scikit-image compares float64 samples with the level, keymesh float32
    # ones: the same unless a float64 sample rounds across the level.
    none_above = not np.any(np.asarray(volume, np.float64) > level)
    volume = np.ascontiguousarray(volume, np.float32)
    vertices, faces, _, _ = _ext.marching_cubes(volume, float(level), _case_table(), 1, None, True,
                                                int_arg(threads, "threads", INT32), progress)
    if none_above or not len(vertices):
        # scikit-image indexes its points with an empty float array here
        raise IndexError("arrays used as indices must be of integer (or boolean) type")
    if 'descent' in gradient_direction:
        pass
    elif 'ascent' in gradient_direction:
        faces = np.ascontiguousarray(faces[:, ::-1])
    else:
        raise ValueError("Incorrect input %s in `gradient_direction`, see docstring." % (gradient_direction))
    vertices, faces = _remove_degenerate_faces(vertices, faces)
    return vertices.astype(np.float64) * np.r_[spacing], faces.astype(np.int64)


def marching_cubes(volume: Any, level: Optional[float] = None, *, spacing: Sequence[float] = (1., 1., 1.),
                   gradient_direction: str = 'descent', step_size: int = 1, allow_degenerate: bool = True,
                   method: str = 'lewiner', mask: Any = None, threads: int = 0,
                   progress: Optional[Callable[[str, float], Any]] = None,
                   history: bool = False) -> Tuple[np.ndarray, ...]:
    """Marching cubes with scikit-image's arguments and results, welded by edge keys.

    ``verts, faces, normals, values = keymesh.marching_cubes(volume, level, spacing=s)``
    gives what ``skimage.measure.marching_cubes(volume, level, spacing=s)``
    gives (method='lewiner', Marching Cubes 33, the default of both): the
    same arrays, in the same order. It needs scikit-image installed, whose
    tables keymesh reads at the first call. method='lorensen' gives
    scikit-image's 'lorensen' arrays when it is installed (its classic case
    table); without it, the same points, values and polygons, some cubes
    split along the other diagonal (their points' normals then differ).

    Args:
        volume: (M, N, P) array, converted to float32 (as scikit-image does).
        level: the isovalue; None: the mid-range 0.5 * (min + max). Inside
            means value > level (a sample equal to it is outside).
        spacing: voxel size per array axis; points are array indices times it.
        gradient_direction: 'descent' (the object is greater than its
            exterior; a face's right-hand normal then points into the
            object, to higher values) or 'ascent' (the other winding). The
            returned normals point to lower values either way.
        step_size: cubes of step_size voxels along every axis.
        allow_degenerate: False removes zero-area triangles and merges
            their coincident points (faces are then int64, as in scikit-image).
        method: 'lewiner' (Lewiner et al.'s Marching Cubes 33: ambiguous
            faces and cube interiors tested, some cubes get a centre point;
            NotImplementedError without scikit-image's tables), 'lorensen'
            (the classic table), or '_lorensen' (scikit-image 0.19's old
            code): only (verts float64, faces int64), no degenerate
            triangles, no mask.
        mask: array of 1-byte items (bool, int8, uint8; nonzero = set) of
            the volume's shape; a cube is computed when the mask is set at
            its far corner (scikit-image's rule). Wider items: ValueError.
        threads: worker threads (keymesh only; 0 = all cores). The result
            does not depend on it.
        progress: keymesh only: progress(stage, fraction) between stages;
            Ctrl-C raises KeyboardInterrupt at the next stage.
        history: keymesh only: also return history_key (V,) uint64 and
            history_t (V,) float32 (docs/HISTORY.md), the key keymesh.contour
            gives the same edge of the same array: ``3 * np.ravel_multi_index(
            lo, volume.shape, order="F") + A``, ``lo`` the array index of the
            lower end of the point's edge along array axis ``A`` (with
            step_size, an edge of step_size samples from a multiple of it);
            ``verts[:, A] == np.float32(lo[A] + step_size * np.float64(t)) *
            spacing[A]`` (the cross axes: ``lo * spacing``). A cube centre
            point (method='lewiner') has key ``3 * N + ravel_multi_index(its
            lowest corner)``, N = volume.size, and t 0.5. Not with
            method='_lorensen' (ValueError).

    Returns:
        verts (V, 3) float32 (float64 when spacing is not all ones), faces
        (F, 3) int32, normals (V, 3) float32 (unit, pointing to lower
        values), values (V,) float32 (the largest value range of the cubes
        around each point). No two points share a grid edge (or a cube
        centre).

    Raises:
        ValueError, RuntimeError, TypeError as scikit-image does for the same
        arguments, in its order (RuntimeError when no surface is found, before
        a bad gradient_direction); NotImplementedError for method='lewiner'
        without scikit-image.

    A NaN sample is outside; a point on one of its edges is NaN on all three
    axes, and normals that took a NaN difference are NaN (as scikit-image).
    """
    if method == 'lewiner':
        mc33 = _mc33_tables()
        if mc33 is None:
            raise NotImplementedError(
                "keymesh.marching_cubes: method='lewiner' (scikit-image's default, Marching Cubes 33) "
                "reads its tables from scikit-image, which is not importable; method='lorensen' works "
                "without it")
    else:
        mc33 = None
    if method == '_lorensen':
        if history:
            raise ValueError("history: method='_lorensen' (scikit-image 0.19's old code) keeps no edge keys; "
                             "use method='lorensen' or 'lewiner'")
        if mask is not None:
            raise NotImplementedError(
                'Parameter `mask` is not implemented for method "_lorensen" and will be ignored.')
        return _old_lorensen(volume, level, spacing, gradient_direction, threads, progress)
    if method not in ('lewiner', 'lorensen'):
        raise ValueError("method should be one of 'lewiner', 'lorensen' or '_lorensen'.")
    if not isinstance(volume, np.ndarray) or (volume.ndim != 3):
        raise ValueError('Input volume should be a 3D numpy array.')
    if volume.shape[0] < 2 or volume.shape[1] < 2 or volume.shape[2] < 2:
        raise ValueError("Input array must be at least 2x2x2.")
    volume = np.ascontiguousarray(volume, np.float32)
    level = _level(volume, level, spacing)
    step_size = int_arg(step_size, "step_size", INT32)
    if step_size < 1:
        raise ValueError('step_size must be at least one.')
    if mask is not None:
        if not mask.shape == volume.shape:
            raise ValueError('volume and mask must have the same shape.')
        mask = _mask_bytes(mask)

    threads = int_arg(threads, "threads", INT32)
    arrays = _ext.marching_cubes(volume, float(level), _case_table(), step_size, mask, gradient_direction == 'descent',
                                 threads, progress, mc33, bool(history))
    vertices, faces, normals, values = arrays[:4]
    # scikit-image's order: "no surface" before a bad gradient_direction
    # (which it checks only once it has a surface to wind).
    if not len(vertices):
        raise RuntimeError('No surface found at the given iso value.')
    if gradient_direction not in ('descent', 'ascent'):
        raise ValueError("Incorrect input %s in `gradient_direction`, see docstring." % (gradient_direction))
    if not np.array_equal(spacing, (1, 1, 1)):
        vertices = vertices * np.r_[spacing]
    if allow_degenerate:
        return (vertices, faces, normals, values) + tuple(arrays[4:])
    return _remove_degenerate_faces(vertices.astype(np.float32), faces, normals, values, *arrays[4:])
