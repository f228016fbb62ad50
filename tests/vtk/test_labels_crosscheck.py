"""`keymesh labels --method discrete-mc` of one label against VTK's
vtkDiscreteFlyingEdges3D (python3-vtk9) on the AAL atlas (Debian
mricron-data): the same points and triangles, counted and compared as
point sets. Skipped (77) without VTK or the atlas."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import (check, finish, points_of, read_polydata, require_vtk, run, tempdir, triangles_of,  # noqa: E402
                    vtk_contour)

require_vtk()
import numpy as np  # noqa: E402
import vtk  # noqa: E402
from vtk.util import numpy_support as ns  # noqa: E402

AAL = "/usr/share/mricron/templates/aal.nii.gz"
if not os.path.exists(AAL):
    print(f"skipped: {AAL} not found (apt-get install mricron-data)")
    sys.exit(77)

D = tempdir()
reader = vtk.vtkNIFTIImageReader()
reader.SetFileName(AAL)
reader.Update()
image = reader.GetOutput()
values = ns.vtk_to_numpy(image.GetPointData().GetScalars())
labels, counts = np.unique(values, return_counts=True)
labels, counts = labels[labels != 0], counts[labels != 0]
# The largest, the smallest and a few in between.
order = np.argsort(counts)
CHOSEN = sorted({int(labels[i]) for i in (order[0], order[len(order) // 3], order[len(order) // 2], order[-1])})


def same_as_vtk(label):
    def test():
        out = os.path.join(D, f"aal{label}.vtp")
        run("labels", AAL, "-o", out, "--method", "discrete-mc", "--labels", label, "--smooth", 0, "-q")
        ours = read_polydata(out)
        theirs = vtk_contour(vtk.vtkDiscreteFlyingEdges3D, image, label, ComputeGradients=False,
                             ComputeScalars=False)
        assert ours.GetNumberOfPoints() == theirs.GetNumberOfPoints(), (ours.GetNumberOfPoints(),
                                                                         theirs.GetNumberOfPoints())
        assert ours.GetNumberOfPolys() == theirs.GetNumberOfPolys(), (ours.GetNumberOfPolys(),
                                                                      theirs.GetNumberOfPolys())
        # Point sets equal in index space (VTK's reader and keymesh's may
        # place the grid differently in world space): both are edge midpoints.
        a = points_of(ours)
        b = points_of(theirs)
        sa = np.array(image.GetSpacing())
        oa = np.array(image.GetOrigin())
        ia = np.round((a - a.min(axis=0)) * 2).astype(np.int64)
        ib = np.round((b - oa) / sa * 2).astype(np.int64)
        ib -= ib.min(axis=0)
        ka = np.unique(ia, axis=0)
        kb = np.unique(ib, axis=0)
        assert len(ka) == len(a) and (ka == kb).all()
        assert len(triangles_of(ours)) == theirs.GetNumberOfPolys()
    return test


for lab in CHOSEN:
    check(f"AAL label {lab}: discrete-mc = vtkDiscreteFlyingEdges3D (points, triangles, point set)", same_as_vtk(lab))
finish()
