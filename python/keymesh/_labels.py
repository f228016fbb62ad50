"""keymesh.contour_labels: welded surfaces of a label map (issue 18).

Named after PyVista's ``contour_labels``: the ``boundary_labels`` cell array
(two labels per face, smaller first), background 0, smoothing on by default.
"""
from __future__ import annotations

from typing import Any, Dict, Optional, Sequence

import numpy as np

from . import _keymesh as _ext
from . import Mesh, _mesh, _threads
from ._arguments import INT32, int_arg

# Timings and counts of the last contour_labels() call (seconds: scan,
# generate, weld, smooth; distinct_labels, surfaces, and guard_shortened: the
# smoothing moves the fold guard shortened or refused); for benchmarks.
last_labels_info: Dict[str, Any] = {}


class LabelMesh(Mesh):
    """A Mesh made by contour_labels: ``cell_data["boundary_labels"]`` (m, 2)
    and, for per-label surfaces and discrete marching cubes,
    ``cell_data["label"]`` (m,), the region whose surface the face is.
    (Every Mesh has cell_data and carries it; this class names the origin.)"""

    __slots__ = ()


def contour_labels(volume, spacing: Optional[Sequence[float]] = (1.0, 1.0, 1.0),
                   origin: Optional[Sequence[float]] = (0.0, 0.0, 0.0), method: str = "surface_nets",
                   labels: Optional[Sequence[int]] = None, background: int = 0, per_label: bool = False,
                   smoothing: bool = True, smoothing_iterations: int = 16, relaxation: float = 0.5,
                   coarsen: bool = False, threads: int = 0, history: bool = False) -> LabelMesh:
    """Surfaces between the regions of a label map, welded by history keys.

    Args:
        volume: a 3-D integer numpy array (uint8, int8, uint16, int16,
            int32, and the uint32, int64, uint64 of connectomics
            segmentations) or a keymesh.Volume; axis 0 is x
            (``volume[i, j, k]`` sits at ``origin + (i, j, k) * spacing``).
            Float arrays are refused (keymesh.Error); so are more than 65536
            distinct values and labels beyond +-2^24, which the float32
            boundary_labels cannot hold exactly (``keymesh labels --format
            precomputed`` keeps 64-bit segment ids exact).
        method: "surface_nets" (default: a point per cell of mixed labels,
            a quad per grid edge between two labels, every interface once,
            points shared by all labels meeting there) or
            "discrete_marching_cubes" (each label's marching cubes, points at
            edge midpoints shared by the two labels of the edge; one label
            gives vtkDiscreteFlyingEdges3D's points and triangles).
        labels: the labels to extract (default: all but the background);
            the others count as background.
        background: the background label (default 0). The volume is padded
            with it, so every region's surface is closed.
        per_label: each label's closed 2-manifold surface with its own
            points (cell_data["label"]) instead of one network.
        smoothing, smoothing_iterations, relaxation: Jacobi smoothing on
            the welded mesh: constrained to each point's cell for surface
            nets, Taubin for discrete marching cubes; triple lines smoothed
            along themselves. Output is identical at any thread count.
        coarsen: after smoothing, merge points by a coarser key (surface
            nets: a 2x2x2 block of cells; discrete marching cubes: the
            nearest grid point), as ``keymesh labels --coarsen``: faces that
            collapse are dropped, label pairs kept; each label's surface
            stays closed (not necessarily 2-manifold).
        threads: worker threads, 0 = all cores.
        history: add point_data["history_key"] (uint64) and
            point_data["history_t"] (float32), as ``keymesh labels
            --history`` writes them (docs/HISTORY.md): each point's element
            of the volume padded with one sample of background all round
            (array index (i, j, k) is padded point
            ``p = np.ravel_multi_index((i + 1, j + 1, k + 1), shape + 2, order="F")``):
            discrete marching cubes its edge ``3 * p + axis`` (t = 0.5, the
            midpoint), surface nets its cell ``16 * p + slot`` (p the
            cell's lowest corner; slot 0-3 the cell's loop, 4 + 2 * axis +
            arc a per-label face point; t = 0.5, the cell's centre). The
            unsmoothed point's, whatever the smoothing. Not with coarsen
            (keymesh.Error).

    Returns:
        LabelMesh: points (n, 3) float32, cells (m, 3) uint32,
        cell_data["boundary_labels"] (m, 2) float32, smaller label first.
        Surface nets networks: each face's normal points from
        boundary_labels[:, 0] to boundary_labels[:, 1]; per-label surfaces
        and discrete marching cubes: out of cell_data["label"].
    """
    if isinstance(volume, _ext.Volume):
        spacing = origin = None
    iterations = int_arg(smoothing_iterations, "smoothing_iterations", INT32) if smoothing else 0
    # an object array keeps ints past 64 bits as they are, for int_arg to name
    wanted = [] if labels is None else [int_arg(v, f"labels[{i}]")
                                        for i, v in enumerate(np.asarray(labels, dtype=object).reshape(-1))]
    parts, info = _ext.contour_labels(
        volume, spacing, origin, method, wanted, int_arg(background, "background"), bool(per_label), iterations,
        float(relaxation), bool(coarsen), _threads(threads), bool(history))
    last_labels_info.clear()
    last_labels_info.update(info)
    return _mesh(parts, LabelMesh)
