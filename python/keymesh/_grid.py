"""keymesh.Grid: an unstructured grid (tetrahedra, hexahedra, ...) as numpy arrays."""
from __future__ import annotations

from typing import Any, Dict, Optional

import numpy as np

TETRA = 10
HEXAHEDRON = 12


class CellCounts:
    """n_points and n_cells of points + cells (+ offsets when cells are flat)."""

    __slots__ = ()

    @property
    def n_points(self) -> int:
        """Number of points."""
        return int(len(self.points))

    @property
    def n_cells(self) -> int:
        """Number of cells."""
        return int(len(self.offsets) - 1) if self.offsets is not None else int(len(self.cells))


class Grid(CellCounts):
    """An unstructured grid: points, cells of VTK cell types, point and cell fields.

    Attributes:
        points: (n, 3) positions (float32 from keymesh).
        cells: (m, k) point ids when every cell has type ``cell_type`` with
            k corners (tetrahedralize gives (m, 4), uint32 while ids fit);
            else the flat connectivity, with ``offsets`` (m + 1) and
            ``cell_types`` (m,) VTK type codes.
        cell_type: the VTK type of every cell of a uniform grid (10 = tetra,
            12 = hexahedron, 11 = voxel).
        point_data, cell_data: dicts of (n,) / (n, k) and (m,) / (m, k) arrays.
    """

    __slots__ = ("points", "cells", "offsets", "cell_types", "cell_type", "point_data", "cell_data")

    def __init__(self, points: Any, cells: Any, cell_type: int = TETRA, offsets: Any = None,
                 cell_types: Any = None, point_data: Optional[Dict[str, Any]] = None,
                 cell_data: Optional[Dict[str, Any]] = None) -> None:
        self.points = points
        self.cells = cells
        self.cell_type = int(cell_type)
        self.offsets = offsets
        self.cell_types = cell_types
        self.point_data = {} if point_data is None else dict(point_data)
        self.cell_data = {} if cell_data is None else dict(cell_data)

    def types(self) -> np.ndarray:
        """The VTK type of every cell, (m,) uint8."""
        if self.cell_types is not None:
            return np.asarray(self.cell_types, dtype=np.uint8)
        return np.full(self.n_cells, self.cell_type, dtype=np.uint8)

    def __repr__(self) -> str:
        return (f"keymesh.Grid({self.n_points} points, {self.n_cells} cells, point_data: "
                f"{sorted(self.point_data)}, cell_data: {sorted(self.cell_data)})")

    def to_vtk(self):
        """A vtkUnstructuredGrid sharing the point, connectivity and field
        arrays (see keymesh._interop for which arrays are copied)."""
        from . import _interop
        return _interop.grid_to_vtk(self)

    def to_meshio(self):
        """A meshio.Mesh over the same arrays (cells grouped in runs of one type)."""
        from . import _interop
        return _interop.grid_to_meshio(self)

    @classmethod
    def from_vtk(cls, ug) -> "Grid":
        """A Grid viewing a vtkUnstructuredGrid's arrays (no copy)."""
        from . import _interop
        return _interop.grid_from_vtk(cls, ug)

    @classmethod
    def from_meshio(cls, m) -> "Grid":
        """A Grid over a meshio.Mesh's arrays."""
        from . import _interop
        return _interop.grid_from_meshio(cls, m)


def grid_from_parts(parts) -> Grid:
    points, cells, offsets, cell_types, cell_type, point_data, cell_data = parts
    return Grid(points, cells, cell_type, offsets, cell_types, point_data, cell_data)
