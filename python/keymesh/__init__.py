"""keymesh: history-based topology over numpy.

Marching cubes whose points are welded by the grid edge they were made on
(KEY-REDUCE: no coordinate comparison, no spatial search), the generic
KEY-REDUCE primitive for your own generators, a topology check and the
library's volume and mesh files.

    >>> import numpy as np, keymesh
    >>> i, j, k = np.indices((64, 64, 64))
    >>> field = np.sqrt((i - 32.0) ** 2 + (j - 32.0) ** 2 + (k - 32.0) ** 2)
    >>> mesh = keymesh.contour(field, 20.5)
    >>> keymesh.check(mesh)["closed_manifold"]
    True

Axis convention: axis 0 of a volume array is x, the first coordinate of the
output points (scikit-image's marching_cubes convention): the sample
``volume[i, j, k]`` sits at ``origin + (i, j, k) * spacing``.

The compute runs in C++ with the GIL released, on ``threads`` worker threads
(0: all cores); results do not depend on the thread count.
"""
from __future__ import annotations

import numbers
from typing import Any, Dict, Optional, Sequence, Tuple, Union

import numpy as np

from ._keymesh import DeviceArray, Error, LimitError, Volume
from ._arguments import INT32, int_arg as _int_arg
from . import _keymesh as _ext
from . import _foreign
from ._grid import CellCounts, Grid, grid_from_parts as _grid
from ._operations import coarsen, dual, incidence, quality, subdivide, tetrahedralize
from ._skimage_compat import marching_cubes

__all__ = [
    "Mesh", "Volume", "Error", "LimitError", "Grid", "contour", "key_reduce", "check", "read", "write", "marching_cubes",
    "tetrahedralize", "subdivide", "dual", "quality", "coarsen", "incidence", "from_vtk", "from_meshio",
    "release_memory", "retained_memory", "cuda_available", "DeviceArray",
]

__version__ = "0.1.0"

# Timings of the last contour() call in this process (seconds: copy, contour,
# mirror, and the library's stages); for benchmarks.
last_contour_info: Dict[str, Any] = {}


class Mesh(CellCounts):
    """A surface mesh: points, cells, point and cell fields, as numpy arrays.

    Attributes:
        points: (n, 3) float32 positions.
        cells: (m, 3) uint32 point indices of the triangles (any integer
            dtype is accepted on input). For polygon meshes (read from a
            file) ``cells`` is the flat connectivity and ``offsets`` says
            where each cell starts.
        offsets: None for triangle meshes; else (m + 1) cell bounds:
            cell c is ``cells[offsets[c]:offsets[c + 1]]``.
        point_data: dict of per-point arrays, (n,) or (n, k); contour()
            gives the interpolated ``"scalars"`` and, with normals,
            ``"Normals"`` (unit vectors pointing to lower values).
        cell_data: dict of per-cell arrays, (m,) or (m, k), e.g. a label
            surface's ``"boundary_labels"``. Carried by write and read
            (.vtp CellData, .ply face properties; the other formats have no
            place for them), to/from VTK and meshio, subdivide (each child
            cell its parent's) and coarsen (kept cells keep theirs).

    Arrays returned by keymesh own their memory (they outlive the Mesh).
    """

    __slots__ = ("points", "cells", "offsets", "point_data", "cell_data")

    def __init__(self, points: Any, cells: Any, point_data: Optional[Dict[str, Any]] = None,
                 offsets: Any = None, cell_data: Optional[Dict[str, Any]] = None) -> None:
        self.points = points
        self.cells = cells
        self.offsets = offsets
        self.point_data = {} if point_data is None else dict(point_data)
        self.cell_data = {} if cell_data is None else dict(cell_data)

    def __repr__(self) -> str:
        def shapes(data):
            return ", ".join(f"{k}{tuple(np.shape(v))}" for k, v in data.items())
        cells = f", cell_data: [{shapes(self.cell_data)}]" if self.cell_data else ""
        return (f"keymesh.{type(self).__name__}({self.n_points} points, {self.n_cells} cells, "
                f"point_data: [{shapes(self.point_data)}]{cells})")

    def polygons(self):
        """The cells as a list of index arrays (for polygon meshes)."""
        if self.offsets is None:
            return list(np.asarray(self.cells))
        o = np.asarray(self.offsets)
        c = np.asarray(self.cells)
        return [c[o[i]:o[i + 1]] for i in range(len(o) - 1)]

    # -- VTK and meshio (keymesh._interop says which arrays are shared) --
    def to_meshio(self):
        """A meshio.Mesh over the same arrays (needs python3-meshio):
        triangles as "triangle" cells, other polygons grouped by size (the
        cell data gathered with them)."""
        from . import _interop
        return _interop.mesh_to_meshio(self)

    @classmethod
    def from_meshio(cls, mesh) -> "Mesh":
        """A Mesh over a meshio.Mesh's triangle, quad and polygon cells
        (other cell types are refused: use keymesh.from_meshio for grids)."""
        from . import _interop
        return _interop.mesh_from_meshio(cls, mesh)

    def to_vtk(self):
        """A vtkPolyData (needs python3-vtk9) sharing the points, ids,
        point fields ("Normals" set as the normals) and cell fields; only
        the offsets of a triangle mesh are new."""
        from . import _interop
        return _interop.mesh_to_vtk(self)

    @classmethod
    def from_vtk(cls, poly) -> "Mesh":
        """A Mesh viewing a vtkPolyData's points, polygons, point and cell
        arrays (no copy; strips, lines and vertices are refused)."""
        from . import _interop
        return _interop.mesh_from_vtk(cls, poly)


def _isovalues(iso: Union[float, Sequence[float]]) -> list:
    try:
        if isinstance(iso, (numbers.Real, np.floating, np.integer)):
            return [float(iso)]
        values = [float(v) for v in np.asarray(iso, dtype=np.float64).reshape(-1)]
    except OverflowError:
        raise OverflowError("iso is past the range of a float64") from None
    except (TypeError, ValueError):
        raise TypeError(f"iso must be a number or a sequence of numbers, got {type(iso).__name__}") from None
    return values


def _threads(threads: int) -> int:
    if not isinstance(threads, (numbers.Integral, np.integer)) or isinstance(threads, bool):
        raise TypeError(f"threads must be an int, got {type(threads).__name__}")
    if threads < 0:
        raise ValueError(f"threads must be >= 0 (0 = all cores), got {threads}")
    return _int_arg(threads, "threads", INT32)


def _mesh(parts, cls=None) -> Mesh:
    points, cells, offsets, point_data, cell_data = parts
    return (cls or Mesh)(points, cells, point_data, offsets, cell_data)


def contour(volume: Union[np.ndarray, Volume], iso: Union[float, Sequence[float]],
            spacing: Optional[Sequence[float]] = (1.0, 1.0, 1.0),
            origin: Optional[Sequence[float]] = (0.0, 0.0, 0.0),
            normals: Optional[str] = "average", weld: str = "keyreduce",
            coarsen: bool = False, curvature: bool = False, threads: int = 0,
            progress: Optional[Any] = None, scalars: bool = True, backend: Optional[str] = None,
            history: bool = False) -> Mesh:
    """Isosurface of a 3-D volume: marching cubes, points welded by edge keys.

    Args:
        volume: a 3-D numpy array of uint8, int8, uint16, int16, int32,
            float32 or float64 (other dtypes: TypeError), or a keymesh.Volume.
            Axis 0 is x: ``volume[i, j, k]`` sits at
            ``origin + (i, j, k) * spacing``: the points and counts are those
            of ``skimage.measure.marching_cubes(volume, iso, spacing=spacing,
            method="lorensen")`` (plus origin; skimage winds triangles the
            other way and splits some cube polygons along the other
            diagonal). Any memory layout works: C- and Fortran-ordered
            arrays are read in place (no copy); other strides and
            non-native byte orders are made C-contiguous first;
            C and Fortran order give the same points, their triangulations
            may differ in such diagonals. A keymesh.Volume is read in place.
            A tensor of another library that exposes DLPack
            (``__dlpack__``, ``__dlpack_device__``) or
            ``__cuda_array_interface__`` is read without a host copy: a
            host tensor as the numpy array over its memory (the same mesh
            as that numpy call), a CUDA tensor (C- or Fortran-contiguous)
            on its GPU (see backend).
        iso: an isovalue or a sequence of them (finite). Inside means
            ``value >= iso``; NaN samples are outside. One point per grid
            edge whose samples straddle the isovalue.
        spacing, origin: voxel size and position of ``volume[0, 0, 0]``,
            per array axis. A Volume carries its own (pass None or the same).
        normals: "average" (area-weighted face normals merged per point,
            default), "gradient" (interpolated central differences) or
            "none"/None. Normals point to lower values, and so do the
            triangles' right-hand-rule normals.
        weld: "keyreduce" (structured plan, default), "keyreduce-sort" or
            "vertexweld" (the paper's coordinate-sort baseline); all give
            the same mesh.
        coarsen: merge the points nearest to one grid point (the key of a
            crossing becomes the input point nearest to it on its edge),
            averaging positions and fields; collapsed triangles are dropped,
            points where the collapse pinched sheets together are split
            into one point per fan (copies at the same position), and points
            left without a triangle are removed.
        curvature: add point_data["mean_curvature"] from the volume's
            gradient and Hessian: (|g|^2 tr H - g^T H g) / (2 |g|^3), 1/r on
            a sphere of a distance field (values growing outward).
        threads: worker threads, 0 = all cores. Output is identical for any count.
        progress: progress(stage, fraction), called at the start, between
            the contour's stages ("classify" per isovalue, "triangles",
            "points", then "normals" or "coarsen") and at the end; Ctrl-C
            during the call raises KeyboardInterrupt at the next stage
            boundary, and a callback that raises abandons the call.
        scalars: carry the interpolated input value as a point field
            (default): point_data["scalars"], or a Volume's name. On one
            isovalue it is that isovalue up to rounding; scalars=False
            leaves it out (one float less to write per point), as
            vtkFlyingEdges3D's ComputeScalarsOff() does (VTK computes it by
            default).
        backend: None (default: where the volume lies), "cpu" or "cuda"
            (an NVIDIA GPU; the same mesh, bit for bit; weld "vertexweld",
            coarsen and curvature are refused by name). A host volume on
            "cuda" is uploaded and its mesh comes back as numpy arrays; a
            CUDA tensor's mesh stays on its device, as tensors of its
            library (CuPy in, CuPy out; PyTorch in, PyTorch out; a library
            without ``from_dlpack``: keymesh.DeviceArray, which exports
            DLPack and ``__cuda_array_interface__``). A CUDA tensor with
            backend="cpu" is refused (ValueError): copy it to the host
            yourself. ``keymesh.cuda_available()`` says whether "cuda" runs.
        history: add point_data["history_key"] (uint64: the point's grid
            edge, ``3 * np.ravel_multi_index((i, j, k), volume.shape,
            order="F") + axis + isovalue_index * 3 * volume.size``, (i, j, k)
            the edge's lower end) and point_data["history_t"] (float32: t
            along the edge from that end, which gives the point back:
            ``np.float32(origin[axis] + spacing[axis] * (ijk[axis] +
            np.float64(t)))``), as ``keymesh contour --history`` writes them
            (docs/HISTORY.md). Not with coarsen, nor on the GPU (ValueError).

    Returns:
        Mesh with points (n, 3) float32, cells (m, 3) uint32 and point_data
        {"scalars": (n,) float32 unless scalars=False, "Normals": (n, 3)
        float32 unless normals="none"}. The arrays are the library's
        buffers (no copy).

    Raises:
        TypeError: unsupported dtype or argument type.
        ValueError: wrong ndim, fewer than 2 samples along an axis,
            non-finite iso, negative threads, unknown normals/weld
            (keymesh.Error, a ValueError, for input the library refuses,
            e.g. a spacing or origin that puts a point past float32 or at
            NaN; keymesh.LimitError past 2^32 - 1 points or corners).
        OverflowError: an integer argument past its C++ type.
        MemoryError: the copy a strided array needs does not fit (the
            message names the array and its size).
        keymesh.Error: backend="cuda" where no GPU is usable or keymesh was
            built without CUDA (the message says which); LimitError when
            the GPU runs out of memory.
    """
    if normals is None:
        normals = "none"
    if not isinstance(normals, str):
        raise TypeError(f"normals must be a string, got {type(normals).__name__}")
    if not isinstance(weld, str):
        raise TypeError(f"weld must be a string, got {type(weld).__name__}")
    if isinstance(volume, Volume):
        # A Volume's own spacing/origin apply; the defaults do not override them.
        if spacing is not None and tuple(map(float, spacing)) == (1.0, 1.0, 1.0):
            spacing = None
        if origin is not None and tuple(map(float, origin)) == (0.0, 0.0, 0.0):
            origin = None
    source = _foreign.volume_source(volume)
    backend = _foreign.check_backend(source, backend)
    if source.on_cuda:
        _threads(threads)
        if history:
            raise ValueError("history: per-point history is not available on the GPU yet (use backend=\"cpu\" "
                             "on a host copy)")
        parts, info = _ext.contour_device(source.value, _isovalues(iso), spacing, origin, normals, weld,
                                          bool(coarsen), bool(curvature), progress, bool(scalars))
    else:
        parts, info = _ext.contour(source.value, _isovalues(iso), spacing, origin, normals, weld, bool(coarsen),
                                   bool(curvature), _threads(threads), progress, bool(scalars), backend, bool(history))
    last_contour_info.clear()
    last_contour_info.update(info)
    return _mesh(_foreign.in_library(parts, source.library))


def cuda_available() -> Optional[str]:
    """None when keymesh.contour(..., backend="cuda") can run here, else why
    not (no device, no driver, a build without CUDA, an earlier fault)."""
    return _ext.cuda_available()


def release_memory() -> int:
    """Unmap the memory kept from freed outputs; returns its bytes.

    When a mesh's large arrays (4 MiB or more) are freed, keymesh keeps their
    pages mapped, for 10 seconds (then a thread of its own unmaps them) and
    up to the smaller of 1 GiB and an eighth of RAM (environment variable KEYMESH_RETAINED_MEMORY_MB; 0 keeps
    nothing), and the next call's outputs reuse them instead of faulting in
    fresh pages (on a VM the first touch of a page can cost more than the
    contour's own work). Call this to give that memory back now.

        >>> m = keymesh.contour(volume, 90.5); del m
        >>> keymesh.release_memory()   # e.g. 69206016
    """
    return int(_ext.release_memory())


def retained_memory() -> Dict[str, int]:
    """What release_memory() would give back, and how often kept blocks served
    a call: {'kept_bytes', 'kept_blocks', 'reused', 'mapped', 'limit_bytes',
    'limit_seconds'}."""
    return dict(_ext.retained_memory())


def key_reduce(keys: Any, values: Any, op: str = "mean",
               threads: int = 0) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """KEY-REDUCE: group pairs (keys[i], values[i]) by key and reduce each group.

    The generic primitive behind contour's weld, for your own generators:
    key every generated element by its history (e.g. the id of the edge or
    face it came from) and KEY-REDUCE merges the duplicates.

    Args:
        keys: 1-D uint32, uint64 or int64 (other integer dtypes are widened;
            negative keys: ValueError).
        values: float32 or float64, shape (n,) or (n, k): one row per key;
            rows are reduced per column.
        op: "mean", "sum", "min" or "max". Sums and means accumulate in
            float64 over each group's pairs in increasing index order; min
            and max propagate NaN like numpy.minimum/maximum.
        threads: worker threads, 0 = all cores.

    Returns:
        (unique_keys, reduced, index_map, counts): the distinct keys in
        increasing order (the keys' dtype); the reduced values (one row per
        unique key, the values' dtype); index_map (n,) uint32, the group of
        every pair, so ``unique_keys[index_map] == keys``; counts (int64),
        the pairs per group. Deterministic, whatever the thread count.
    """
    k = np.asarray(keys)
    if k.dtype.kind in "iu" and k.dtype not in (np.dtype(np.uint32), np.dtype(np.uint64), np.dtype(np.int64)):
        k = k.astype(np.int64 if k.dtype.kind == "i" else np.uint32)
    elif k.dtype.kind not in "iu" and k.size == 0 and k.dtype == np.float64:
        k = k.astype(np.uint64)  # an empty list
    return _ext.key_reduce(k, np.asarray(values), op, _threads(threads))


def check(mesh: Mesh, threads: int = 0, self_intersections: bool = False) -> Dict[str, Any]:
    """Topology report of a surface mesh, the keys of ``keymesh check --report``:
    points, cells, edges, boundary_edges, nonmanifold_edges,
    nonmanifold_vertices, duplicate_points, unused_points, degenerate_cells,
    components, euler_characteristic, closed_manifold (a closed 2-manifold:
    no boundary, no non-manifold edge or vertex, no degenerate cell).

    With ``self_intersections=True`` (``keymesh check --self-intersections``)
    also: self_intersections (pairs of cells that cross, or touch where they
    share no corner, decided with exact predicates), self_intersecting_pairs
    (the first 16 such pairs of cell ids) and zero_area_triangles (left out
    of that test)."""
    return _ext.check(mesh, _threads(threads), bool(self_intersections))


def read(path: Any, dims: Optional[Sequence[int]] = None, dtype: Any = None,
         spacing: Optional[Sequence[float]] = None, origin: Optional[Sequence[float]] = None,
         endian: str = "little", header_bytes: int = 0) -> Union[Mesh, Grid, Volume]:
    """Reads a file, by extension.

    Volumes (.vti, .nrrd, .nhdr, .nii, .nii.gz, .den, a DICOM or Zarr folder; .raw with dims=(nx,
    ny, nz) and dtype, optionally spacing, origin, endian, header_bytes)
    give a keymesh.Volume: ``.array`` is a (nx, ny, nz) view of the samples
    (axis 0 = x, no copy), with ``.spacing``, ``.origin`` and ``.name``
    (the scalar field's name: a .vti's array name, else "scalars", as the
    keymesh command names it on every path).
    Surface meshes (.vtp, .ply, .obj, .stl) give a Mesh (with the cell fields
    of a .vtp or the face properties of a .ply as cell_data); unstructured
    grids (.vtu, legacy .vtk) a Grid. .glb is written, not read.
    Malformed files raise keymesh.Error (a ValueError) naming the file.
    """
    kind, obj = _ext.read(str(path), dims, dtype, spacing, origin, endian, _int_arg(header_bytes, "header_bytes"))
    if kind == "grid":
        return _grid(obj)
    return obj if kind == "volume" else _mesh(obj)


def write(obj: Union[Mesh, Grid, Volume, np.ndarray], path: Any,
          spacing: Sequence[float] = (1.0, 1.0, 1.0), origin: Sequence[float] = (0.0, 0.0, 0.0)) -> None:
    """Writes a Mesh (.vtp, .ply, .obj, .stl, .glb), a Grid (.vtu, .vtk) or a volume (.vti, .nrrd, .raw).

    A volume is a keymesh.Volume or a 3-D numpy array (axis 0 = x; spacing
    and origin per axis apply to arrays only). Files are written under a
    temporary name and renamed when complete. A Mesh's 1-D uint64 point
    arrays (contour's history_key) are written as UInt64 arrays of a .vtp;
    the other mesh formats would round them to float32 and raise ValueError.
    """
    if isinstance(obj, Volume):
        _ext.write_volume(obj, str(path))
    elif isinstance(obj, Grid):
        _ext.write_grid(obj, str(path))
    elif isinstance(obj, np.ndarray):
        _ext.write_volume(Volume(obj, spacing, origin), str(path))
    elif hasattr(obj, "points") and hasattr(obj, "cells"):
        _ext.write_mesh(obj, str(path))
    else:
        raise TypeError(f"write: expected a keymesh.Mesh, keymesh.Volume or numpy array, got {type(obj).__name__}")


def from_meshio(mesh) -> Union[Mesh, Grid]:
    """A Mesh when every cell block of the meshio.Mesh is a surface polygon,
    else a Grid; the arrays are shared, not copied."""
    from . import _interop
    return _interop.from_meshio(mesh, Mesh, Grid)


def from_vtk(obj) -> Union[Mesh, Grid, Volume]:
    """A Mesh from a vtkPolyData, a Grid from a vtkUnstructuredGrid, viewing
    VTK's arrays (no copy); a Volume from a vtkImageData (its point scalars
    copied once into the Volume)."""
    from . import _interop
    return _interop.from_vtk(obj, Mesh, Grid, Volume)


def _volume_to_vtk(self):
    """A vtkImageData whose point scalars view this Volume's samples (no copy)."""
    from . import _interop
    return _interop.volume_to_vtk(self)


Volume.to_vtk = _volume_to_vtk

from ._labels import LabelMesh, contour_labels  # noqa: E402  (label maps: python/keymesh/_labels.py)
__all__ += ["contour_labels", "LabelMesh"]
from ._precomputed import labels_precomputed  # noqa: E402  (Neuroglancer meshes: python/keymesh/_precomputed.py)
__all__ += ["labels_precomputed"]


def __getattr__(name: str):
    # keymesh.dask (contours of chunked Dask arrays) is imported on first use:
    # it needs dask, which plain keymesh does not.
    if name == "dask":
        import importlib
        return importlib.import_module(".dask", __name__)
    raise AttributeError(f"module 'keymesh' has no attribute {name!r}")
