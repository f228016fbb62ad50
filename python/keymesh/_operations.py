"""The CLI's operations as functions: tetrahedralize, subdivide, dual,
quality, coarsen, incidence. Same option names and values as the commands
(``--scheme 5`` is ``scheme=5``); a bad value raises ValueError (the CLI's
exit 2), input the library refuses keymesh.Error (the CLI's exit 1).

Every call runs in C++ with the GIL released. ``progress=`` takes a callable
``progress(stage: str, fraction: float)`` called between stages; Ctrl-C
(KeyboardInterrupt) and an exception raised by the callback abandon the call
at the next stage boundary, leaving the inputs untouched.
"""
from __future__ import annotations

from typing import Any, Callable, Dict, Optional, Sequence, Tuple, Union

import numpy as np

from . import _keymesh as _ext
from ._arguments import INT32, int_arg
from ._grid import Grid, grid_from_parts

Progress = Optional[Callable[[str, float], Any]]


def _threads(threads: int) -> int:
    from . import _threads as check
    return check(threads)


def _mesh(parts):
    from . import _mesh as make
    return make(parts)


def _is_mesh(obj) -> bool:
    from . import Mesh
    return isinstance(obj, Mesh)


def tetrahedralize(volume: Any, scheme: int = 5, *, weld: str = "keyreduce",
                   spacing: Optional[Sequence[float]] = None, origin: Optional[Sequence[float]] = None,
                   threads: int = 0, progress: Progress = None) -> Grid:
    """Hexahedra into tetrahedra (``keymesh tetrahedralize``).

    Args:
        volume: a 3-D numpy array (axis 0 = x; point ids run x fastest, as in
            the grid), a keymesh.Volume, or a Grid of hexahedra/voxels.
        scheme: 5 (the minimal split, alternating so neighbouring faces
            match: 5 (N-1)^3 tets on N^3 points) or 24 (face-centred: a tet
            per face edge from the cell and face centres, the face centres
            welded by KEY-REDUCE on their face key).
        weld: scheme 24's face centres by "keyreduce" (face keys) or
            "vertexweld" (coordinates, the baseline).
        spacing, origin: of a numpy volume (a Volume carries its own).

    Returns:
        Grid of tetrahedra (cells (m, 4)), the volume's samples as the point
        field "scalars" (a Grid's fields are carried). Every tet is
        positively oriented.
    """
    if isinstance(scheme, bool) or not isinstance(scheme, (int, np.integer)):
        raise TypeError(f"scheme must be 5 or 24, got {scheme!r}")
    if isinstance(volume, Grid):
        spacing = origin = None
    return grid_from_parts(_ext.tetrahedralize(volume, int_arg(scheme, "scheme", INT32), weld, spacing, origin,
                                               _threads(threads), progress))


def subdivide(mesh: Any, levels: int = 1, *, scheme: str = "linear", weld: str = "keyreduce",
              threads: int = 0, progress: Progress = None):
    """Triangles 1 -> 4 or tetrahedra 1 -> 8 per level (``keymesh subdivide``).

    New points are keyed by their parent edge; old points keep their ids.
    scheme: "linear" (edge midpoints) or "bezier" (PN triangles from the
    "Normals" point field; surfaces only). weld: "keyreduce" or "vertexweld"
    (the coordinate-welding baseline; same mesh up to numbering).
    levels: 0..8. Returns the same kind as given (Mesh or Grid).
    """
    if isinstance(levels, bool) or not isinstance(levels, (int, np.integer)):
        raise TypeError(f"levels must be an int, got {type(levels).__name__}")
    levels = int_arg(levels, "levels", INT32)
    if isinstance(mesh, Grid):
        return grid_from_parts(_ext.subdivide_grid(mesh, levels, scheme, weld, _threads(threads), progress))
    return _mesh(_ext.subdivide_mesh(mesh, levels, scheme, weld, _threads(threads), progress))


def dual(mesh: Any, *, threads: int = 0, progress: Progress = None, return_stats: bool = False):
    """The dual of a polygon surface (``keymesh dual``): a polygon per point
    through the centroids of its cells, walked around the point's fan.

    With return_stats, also the dict of ``keymesh dual --report``'s counts:
    boundary_fans, nonmanifold_points, skipped_fans.
    """
    parts, stats = _ext.dual(mesh, _threads(threads), progress)
    return (_mesh(parts), stats) if return_stats else _mesh(parts)


def quality(mesh: Any, *, per_cell: bool = False, threads: int = 0) -> Dict[str, Any]:
    """Triangle quality Q = 4 sqrt(3) area / sum of squared edge lengths
    (``keymesh quality --report``): points, cells, min, median, mean,
    fraction_above_0_6, histogram (10 bins over [0, 1]); per_cell=True adds
    "per_cell", every triangle's Q (float64)."""
    return _ext.quality(mesh, bool(per_cell), _threads(threads))


def coarsen(mesh: Any, spacing: Sequence[float] = (1.0, 1.0, 1.0), origin: Sequence[float] = (0.0, 0.0, 0.0), *,
            normals: str = "average", threads: int = 0, progress: Progress = None, return_stats: bool = False):
    """Coarsens an existing welded surface by key (``contour --coarsen`` as a
    separate step): every point is keyed by the lattice point
    ``origin + i * spacing`` nearest to it, KEY-REDUCE merges the points that
    share a key (positions and fields averaged), triangles left with fewer
    than three points are dropped and folds cancel; a point left with more
    than one fan of triangles is split into one point per fan (copies at
    its position), and an edge with two triangles each way into two edges;
    points left without a triangle are removed.

    For a mesh contoured on that lattice this is the key ``contour
    --coarsen`` uses (the edge's end point nearest to the crossing).
    normals: "average" recomputes area-weighted normals after the merge when
    the mesh has "Normals" (what contour --coarsen does); "merge" keeps the
    averaged, renormalised input normals. With return_stats, also the counts
    (points_before/after, triangles_before/after, folded).
    """
    parts, stats = _ext.coarsen(mesh, spacing, origin, normals, _threads(threads), progress)
    return (_mesh(parts), stats) if return_stats else _mesh(parts)


def incidence(mesh: Any, *, threads: int = 0) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Incidence lists by KEY-REDUCE (the paper's Section 6.2).

    Returns (point_offsets, point_cells, cell_neighbours): the cells around
    point p are ``point_cells[point_offsets[p]:point_offsets[p + 1]]`` (a
    cell listed once per corner at p, in increasing cell order);
    ``cell_neighbours[c, k]`` is the cell across the edge from corner k to
    corner k + 1 of triangle c (-1 on the boundary, -2 when the edge has
    more than two cells); flat, one entry per corner, for polygon meshes.
    """
    return _ext.incidence(mesh, _threads(threads))
