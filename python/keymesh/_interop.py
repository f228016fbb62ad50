"""Mesh / Grid <-> VTK (vtkPolyData, vtkUnstructuredGrid) and meshio.Mesh.

What is shared and what is copied, and why:
- to_vtk: points, point and cell fields are handed to VTK as views when
  they are float32 and contiguous (numpy_support with deep=False; the VTK
  array keeps the numpy array alive). Connectivity: keymesh's uint32 ids
  are viewed as VTK's 32-bit storage (vtkCellArray holds 32- or 64-bit ids)
  while they are below 2^31, so no copy either; the offsets (keymesh stores
  none for all-triangle meshes and all-tet grids) and the cell types of a
  grid are new arrays, m + 1 ids and m bytes. Other dtypes are converted
  (a copy) because VTK needs them as such.
- from_vtk: every array is a numpy view of VTK's memory (vtk_to_numpy);
  the views keep the VTK arrays alive. A vtkImageData becomes a Volume,
  which owns its samples: one copy (Volume.to_vtk shares them the other way). Triangle and tet connectivity is
  reshaped (a view) to (m, 3) / (m, 4).
- meshio: meshio.Mesh and its CellBlocks keep the arrays given (no copy) both
  ways; polygon meshes of mixed sizes are regrouped by size (a gather, cell
  data too), and meshio's per-block cell data is concatenated on the way back.
"""
from __future__ import annotations

from typing import Any, Dict, Optional

import numpy as np

# VTK cell type ids (vtkCellType.h) and meshio's names for them.
_MESHIO_NAMES = {1: "vertex", 3: "line", 5: "triangle", 9: "quad", 10: "tetra", 11: "hexahedron",
                 12: "hexahedron", 13: "wedge", 14: "pyramid"}
_MESHIO_TYPES = {"vertex": 1, "line": 3, "triangle": 5, "quad": 9, "tetra": 10, "hexahedron": 12,
                 "wedge": 13, "pyramid": 14}
_CORNERS = {1: 1, 3: 2, 5: 3, 9: 4, 10: 4, 11: 8, 12: 8, 13: 6, 14: 5}


def _numpy_view(array, what: str) -> np.ndarray:
    """vtk_to_numpy(array), refusing by name (keymesh.Error) an array it
    cannot view: a vtkBitArray (8 values a byte) or a type numpy has no
    dtype for, where vtk_to_numpy only asserts (an AssertionError, or
    nothing at all under python -O)."""
    from vtkmodules.util import numpy_support as ns
    from vtkmodules.util.vtkConstants import VTK_BIT

    from ._keymesh import Error

    kind = array.GetDataType()
    if kind == VTK_BIT or kind not in ns.get_vtk_to_numpy_typemap():
        raise Error(f"from_vtk: {what} is a {array.GetClassName()} ({array.GetDataTypeAsString()} values), which "
                    "numpy cannot view; convert it to a numeric array (e.g. vtkUnsignedCharArray) first")
    return ns.vtk_to_numpy(array)


def _vtk_array(values: Any, name: Optional[str] = None):
    """A VTK data array over `values` (a view when it is contiguous)."""
    from vtkmodules.util import numpy_support as ns

    a = np.asarray(values)
    if a.dtype == np.float64 or a.dtype == np.float32:
        a = np.ascontiguousarray(a)
    else:
        a = np.ascontiguousarray(a, dtype=np.float32)
    arr = ns.numpy_to_vtk(a, deep=False)
    if name is not None:
        arr.SetName(name)
    return arr


def _vtk_ids(ids: Any):
    """A vtkTypeInt32Array / vtkTypeInt64Array over integer ids: the array
    types vtkCellArray stores as they are (any other type it wraps in a new
    array, which would drop the reference that keeps numpy's memory alive).
    A view when the ids are int32, int64 or uint32 below 2^31, else a copy."""
    from vtkmodules.vtkCommonCore import vtkTypeInt32Array, vtkTypeInt64Array

    a = np.ascontiguousarray(ids).reshape(-1)
    if a.dtype == np.uint32 and (a.size == 0 or int(a.max()) < 2 ** 31):
        a = a.view(np.int32)
    elif a.dtype not in (np.dtype(np.int32), np.dtype(np.int64)):
        a = a.astype(np.int64)
    arr = vtkTypeInt32Array() if a.dtype == np.int32 else vtkTypeInt64Array()
    if a.size:
        arr.SetVoidArray(a, a.size, 1)    # save=1: VTK never frees numpy's memory
    arr._numpy_reference = a              # kept by VTK's wrapper (a "ghost" while VTK holds it)
    return arr, a


def _cell_array(connectivity: Any, offsets: Any):
    from vtkmodules.vtkCommonDataModel import vtkCellArray

    connectivity = np.asarray(connectivity)
    if connectivity.size >= 2 ** 31:  # offsets past int32: both arrays 64-bit
        connectivity = connectivity.astype(np.int64)
    conn, conn_np = _vtk_ids(connectivity)
    offs, offs_np = _vtk_ids(np.ascontiguousarray(offsets, dtype=conn_np.dtype))
    cells = vtkCellArray()
    cells.SetData(offs, conn)
    cells._numpy_references = (offs_np, conn_np)
    return cells


def _points(points: Any):
    from vtkmodules.vtkCommonCore import vtkPoints

    pts = vtkPoints()
    a = np.asarray(points)
    pts.SetData(_vtk_array(a.reshape(-1, 3) if a.size else np.zeros((0, 3), np.float32)))
    return pts


def _add_fields(target, fields: Dict[str, Any]) -> None:
    for name, values in fields.items():
        arr = _vtk_array(values, name)
        if name == "Normals" and np.ndim(values) == 2 and np.shape(values)[1] == 3:
            target.SetNormals(arr)
        else:
            target.AddArray(arr)


def _meshio_fields(data) -> Dict[str, np.ndarray]:
    # meshio reads one-component fields as (n, 1); keymesh's are (n,) (a view)
    out = {}
    for k, v in data.items():
        a = np.asarray(v)
        out[k] = a.reshape(-1) if a.ndim == 2 and a.shape[1] == 1 else a
    return out


def _fields_from_vtk(data, what: str) -> Dict[str, np.ndarray]:
    out = {}
    for i in range(data.GetNumberOfArrays()):
        a = data.GetArray(i)
        if a is not None and a.GetName():
            out[a.GetName()] = _numpy_view(a, f"{what} array {a.GetName()!r}")
    return out


def _offsets(mesh_or_grid, corners_per_cell: int) -> np.ndarray:
    if mesh_or_grid.offsets is not None:
        return np.asarray(mesh_or_grid.offsets)
    return np.arange(0, corners_per_cell * mesh_or_grid.n_cells + 1, corners_per_cell, dtype=np.int64)


# -- surfaces -------------------------------------------------------------

def mesh_to_vtk(mesh):
    from vtkmodules.vtkCommonDataModel import vtkPolyData

    poly = vtkPolyData()
    poly.SetPoints(_points(mesh.points))
    poly.SetPolys(_cell_array(mesh.cells, _offsets(mesh, 3)))
    _add_fields(poly.GetPointData(), mesh.point_data)
    _add_fields(poly.GetCellData(), getattr(mesh, "cell_data", {}))
    return poly


def mesh_from_vtk(cls, poly):
    if poly.GetNumberOfStrips() or poly.GetNumberOfLines() or poly.GetNumberOfVerts():
        raise ValueError("from_vtk: only polygons are supported (triangulate strips first)")
    points = (_numpy_view(poly.GetPoints().GetData(), "the points") if poly.GetNumberOfPoints()
              else np.zeros((0, 3), np.float32))
    polys = poly.GetPolys()
    offs = _numpy_view(polys.GetOffsetsArray(), "the polygon offsets")
    conn = _numpy_view(polys.GetConnectivityArray(), "the polygon connectivity")
    data = _fields_from_vtk(poly.GetPointData(), "point data")
    cell_data = _fields_from_vtk(poly.GetCellData(), "cell data")  # polygons only: one tuple per polygon
    if len(offs) <= 1 or np.all(np.diff(offs) == 3):
        return cls(points, conn.reshape(-1, 3), data, cell_data=cell_data)
    return cls(points, conn, data, offs, cell_data)


def mesh_to_meshio(mesh):
    import meshio

    fields = {k: np.asarray(v) for k, v in getattr(mesh, "cell_data", {}).items()}
    if mesh.offsets is None:
        blocks = [("triangle", np.asarray(mesh.cells))]
        cell_data = {k: [v] for k, v in fields.items()}
    else:
        offsets = np.asarray(mesh.offsets)
        sizes = np.diff(offsets)
        flat = np.asarray(mesh.cells)
        blocks, cell_data = [], {k: [] for k in fields}
        for size in np.unique(sizes):
            rows = np.nonzero(sizes == size)[0]
            idx = offsets[rows][:, None] + np.arange(size)[None, :]
            kind = {3: "triangle", 4: "quad"}.get(int(size), "polygon")
            blocks.append((kind, flat[idx]))
            for k, v in fields.items():
                cell_data[k].append(v[rows])
    return meshio.Mesh(np.asarray(mesh.points), blocks,
                       point_data={k: np.asarray(v) for k, v in mesh.point_data.items()}, cell_data=cell_data)


def _is_surface_block(kind: str) -> bool:
    return kind in ("triangle", "quad") or kind.startswith("polygon")


def mesh_from_meshio(cls, m):
    polys = []
    for block in m.cells:
        if not _is_surface_block(block.type):
            raise ValueError(f"from_meshio: cell type {block.type!r} is not a surface polygon")
        polys.append(np.asarray(block.data))
    data = _meshio_fields(m.point_data)
    # one array per block, the blocks' cells in order: concatenated (a view for one block)
    cell_data = _meshio_fields({k: v[0] if len(v) == 1 else np.concatenate([np.asarray(x) for x in v])
                                for k, v in m.cell_data.items()})
    if len(polys) == 1 and polys[0].shape[1] == 3:
        return cls(np.asarray(m.points), polys[0], data, cell_data=cell_data)
    if all(p.shape[1] == 3 for p in polys):
        cells = np.concatenate(polys) if polys else np.zeros((0, 3), np.int64)
        return cls(np.asarray(m.points), cells, data, cell_data=cell_data)
    sizes = np.concatenate([np.full(len(p), p.shape[1]) for p in polys])
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    flat = np.concatenate([p.reshape(-1) for p in polys])
    return cls(np.asarray(m.points), flat, data, offsets, cell_data)


# -- unstructured grids ---------------------------------------------------

def grid_to_vtk(grid):
    from vtkmodules.util import numpy_support as ns
    from vtkmodules.vtkCommonCore import VTK_UNSIGNED_CHAR
    from vtkmodules.vtkCommonDataModel import vtkUnstructuredGrid

    ug = vtkUnstructuredGrid()
    ug.SetPoints(_points(grid.points))
    types = np.ascontiguousarray(grid.types(), dtype=np.uint8)
    vtk_types = ns.numpy_to_vtk(types, deep=False, array_type=VTK_UNSIGNED_CHAR)
    vtk_types._keymesh_keep = types
    corners = _CORNERS.get(int(grid.cell_type), 0)
    ug.SetCells(vtk_types, _cell_array(grid.cells, _offsets(grid, corners)))
    _add_fields(ug.GetPointData(), grid.point_data)
    _add_fields(ug.GetCellData(), grid.cell_data)
    return ug


def grid_from_vtk(cls, ug):
    points = (_numpy_view(ug.GetPoints().GetData(), "the points") if ug.GetNumberOfPoints()
              else np.zeros((0, 3), np.float32))
    cells = ug.GetCells()
    offs = _numpy_view(cells.GetOffsetsArray(), "the cell offsets")
    conn = _numpy_view(cells.GetConnectivityArray(), "the cell connectivity")
    types = (_numpy_view(ug.GetCellTypesArray(), "the cell types") if ug.GetNumberOfCells()
             else np.zeros(0, np.uint8))
    pd = _fields_from_vtk(ug.GetPointData(), "point data")
    cd = _fields_from_vtk(ug.GetCellData(), "cell data")
    if len(types) and np.all(types == types[0]) and int(types[0]) in _CORNERS:
        k = _CORNERS[int(types[0])]
        if len(conn) == k * len(types):
            return cls(points, conn.reshape(-1, k), cell_type=int(types[0]), point_data=pd, cell_data=cd)
    return cls(points, conn, offsets=offs, cell_types=types, point_data=pd, cell_data=cd)


def grid_to_meshio(grid):
    import meshio

    if grid.offsets is None:
        blocks = [(_MESHIO_NAMES[int(grid.cell_type)], np.asarray(grid.cells))]
        cell_data = {k: [np.asarray(v)] for k, v in grid.cell_data.items()}
    else:
        offsets = np.asarray(grid.offsets)
        types = np.asarray(grid.cell_types)
        flat = np.asarray(grid.cells)
        blocks, order = [], []
        # one block per run of equal types, so that cell order (and cell data) is kept
        starts = np.concatenate([[0], np.nonzero(np.diff(types))[0] + 1, [len(types)]])
        for b, e in zip(starts[:-1], starts[1:]):
            t = int(types[b])
            if t not in _MESHIO_NAMES:
                raise ValueError(f"to_meshio: VTK cell type {t} has no meshio name")
            k = _CORNERS[t]
            idx = offsets[b:e][:, None] + np.arange(k)[None, :]
            blocks.append((_MESHIO_NAMES[t], flat[idx]))
            order.append((b, e))
        cell_data = {k: [np.asarray(v)[b:e] for b, e in order] for k, v in grid.cell_data.items()}
    return meshio.Mesh(np.asarray(grid.points), blocks,
                       point_data={k: np.asarray(v) for k, v in grid.point_data.items()}, cell_data=cell_data)


def grid_from_meshio(cls, m):
    blocks = list(m.cells)
    data = _meshio_fields(m.point_data)
    for b in blocks:
        if b.type not in _MESHIO_TYPES:
            raise ValueError(f"from_meshio: cell type {b.type!r} is not supported")
    if len(blocks) == 1:
        t = _MESHIO_TYPES[blocks[0].type]
        cd = _meshio_fields({k: v[0] for k, v in m.cell_data.items()})
        return cls(np.asarray(m.points), np.asarray(blocks[0].data), cell_type=t, point_data=data, cell_data=cd)
    types = np.concatenate([np.full(len(b.data), _MESHIO_TYPES[b.type], np.uint8) for b in blocks])
    sizes = np.concatenate([np.full(len(b.data), np.asarray(b.data).shape[1]) for b in blocks])
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    flat = np.concatenate([np.asarray(b.data).reshape(-1) for b in blocks])
    cd = _meshio_fields({k: np.concatenate([np.asarray(x) for x in v]) for k, v in m.cell_data.items()})
    return cls(np.asarray(m.points), flat, offsets=offsets, cell_types=types, point_data=data, cell_data=cd)


# -- image data (volumes) --------------------------------------------------

def volume_to_vtk(volume):
    """A vtkImageData whose point scalars view the Volume's samples (x
    fastest in both, so no copy); the VTK array keeps the Volume alive."""
    from vtkmodules.util import numpy_support as ns
    from vtkmodules.vtkCommonDataModel import vtkImageData

    image = vtkImageData()
    image.SetDimensions(*volume.shape)
    image.SetSpacing(*volume.spacing)
    image.SetOrigin(*volume.origin)
    samples = volume.array.reshape(-1, order="F")   # a view: the array is Fortran-ordered
    scalars = ns.numpy_to_vtk(samples, deep=False)
    scalars.SetName(volume.name)
    image.GetPointData().SetScalars(scalars)
    return image


def volume_from_vtk(volume_cls, image):
    """A keymesh.Volume from a vtkImageData's point scalars (one copy: a
    Volume owns its samples), spacing and origin."""
    scalars = image.GetPointData().GetScalars()
    if scalars is None or scalars.GetNumberOfComponents() != 1:
        raise ValueError("from_vtk: the vtkImageData needs one-component point scalars")
    dims = image.GetDimensions()
    samples = _numpy_view(scalars, "the point scalars").reshape(dims, order="F")
    return volume_cls(samples, image.GetSpacing(), image.GetOrigin(), scalars.GetName() or "scalars")


def from_vtk(obj, mesh_cls, grid_cls, volume_cls):
    """A Mesh from a vtkPolyData, a Grid from a vtkUnstructuredGrid, a Volume from a vtkImageData."""
    name = obj.GetClassName() if hasattr(obj, "GetClassName") else type(obj).__name__
    if name == "vtkPolyData":
        return mesh_from_vtk(mesh_cls, obj)
    if name == "vtkUnstructuredGrid":
        return grid_from_vtk(grid_cls, obj)
    if name in ("vtkImageData", "vtkStructuredPoints"):
        return volume_from_vtk(volume_cls, obj)
    raise TypeError(f"from_vtk: expected a vtkPolyData, vtkUnstructuredGrid or vtkImageData, got {name}")


def from_meshio(m, mesh_cls, grid_cls):
    """A Mesh when every cell block is a surface polygon, else a Grid."""
    if all(_is_surface_block(b.type) for b in m.cells):
        return mesh_from_meshio(mesh_cls, m)
    return grid_from_meshio(grid_cls, m)
