"""`keymesh pipeline ... --history` (issue 37): the contour stage's history.

pipeline runs the contour, then optional stages; its history is the
contour's (docs/HISTORY.md): with no later stage, the same history_key,
history_t and points as `keymesh contour --history` of the same volume
(which tests/cli/test_history.py reproduces from the samples), and every
point given back by the documented formula; a stage whose points are made
of several contour points (--coarsen, --subdivide, --dual), and a format
without UInt64 arrays, refused by name with nothing written.
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import box_filtered_noise, check, finish, require_vtk, run, tempdir  # noqa: E402

require_vtk()
import numpy as np  # noqa: E402
from vtk.util import numpy_support as ns  # noqa: E402

from kmtest import read_polydata  # noqa: E402

D = tempdir()
SAMPLES = box_filtered_noise((11, 13, 12), seed=3)  # (nz, ny, nx) float32
NZ, NY, NX = SAMPLES.shape
SPACING, ORIGIN = np.array([0.5, 0.25, 2.0]), np.array([1.0, 2.0, 3.0])


def write_vti():
    """The samples as a .vti written by VTK (pipeline reads volume files, not raw)."""
    import vtk
    image = vtk.vtkImageData()
    image.SetDimensions(NX, NY, NZ)
    image.SetSpacing(*SPACING)
    image.SetOrigin(*ORIGIN)
    array = ns.numpy_to_vtk(SAMPLES.reshape(-1), deep=1)
    array.SetName("f")
    image.GetPointData().SetScalars(array)
    writer = vtk.vtkXMLImageDataWriter()
    path = os.path.join(D, "noise.vti")
    writer.SetFileName(path)
    writer.SetInputData(image)
    writer.Write()
    return path


ARGS = [write_vti(), "--iso", 0.5, "--iso", 0.46]


def arrays(path):
    poly = read_polydata(path)
    pd = poly.GetPointData()
    keys = ns.vtk_to_numpy(pd.GetArray("history_key")).astype(np.uint64)
    return ns.vtk_to_numpy(poly.GetPoints().GetData()), keys, ns.vtk_to_numpy(pd.GetArray("history_t"))


def the_contours_history():
    out, ref = os.path.join(D, "pipeline.vtp"), os.path.join(D, "contour.vtp")
    run("pipeline", *ARGS, "--history", "-o", out, "-q")
    run("contour", *ARGS, "--history", "-o", ref, "-q")
    points, keys, t = arrays(out)
    p2, k2, t2 = arrays(ref)
    assert np.array_equal(keys, k2) and np.array_equal(t, t2) and np.array_equal(points, p2)
    # The documented formula, independently of keymesh.
    n = NX * NY * NZ
    edge = (keys % np.uint64(3 * n)).astype(np.int64)
    p, axis = edge // 3, edge % 3
    u = np.stack([p % NX, p // NX % NY, p // (NX * NY)], axis=1).astype(np.float64)
    u[np.arange(len(u)), axis] += t.astype(np.float64)
    assert np.array_equal((ORIGIN + SPACING * u).astype(np.float32), points)


def refusals():
    for extra, ext, needle in ((["--subdivide", "1"], "vtp", "--subdivide"), (["--dual"], "vtp", "--dual"),
                               (["--coarsen"], "vtp", "--coarsen"), ([], "ply", "only .vtp")):
        out = os.path.join(D, "refused." + ext)
        p = run("pipeline", *ARGS, "--history", "-o", out, *extra, expect=None)
        assert p.returncode == 2 and needle in p.stderr and p.stderr.count("\n") == 1, (extra, p.stderr)
        assert not os.path.exists(out)


check("pipeline --history: the contour's arrays, every point given back", the_contours_history)
check("--history with --subdivide, --dual, --coarsen, .ply: refused by name", refusals)
finish()
