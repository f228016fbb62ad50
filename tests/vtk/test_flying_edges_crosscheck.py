"""Cross-check of `keymesh contour` against VTK's vtkFlyingEdges3D and
vtkMarchingCubes on real volumes from Debian packages, with non-integer
isovalues: the point and triangle counts must equal vtkFlyingEdges3D's, every
keymesh point must lie within 1e-4 voxels of a VTK point (and vice versa), and
vtkMarchingCubes (which merges coincident points spatially) must give the same
triangles and as many points as keymesh has distinct positions.

VTK reads the volumes through numpy here (not through keymesh), so the check
covers keymesh's readers too."""
import gzip
import os
import struct
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import (check, finish, nearest_distances, points_of, read_polydata, require_vtk, run,  # noqa
                    tempdir, triangles_of, vtk_contour)

require_vtk()
import numpy as np  # noqa: E402
import vtk  # noqa: E402
from vtk.util import numpy_support as ns  # noqa: E402

D = tempdir()
DEN = "/usr/share/doc/libvolpack1-dev/examples/brainsmall.den"
MRICRON = "/usr/share/mricron/templates"


def load_den(path):
    """VolPack .den (see denfile.c in libvolpack1-dev): a 62-byte header of shorts in the writer's byte
    order (version 1 tells which), map_len (x, y, z) at shorts 25..27; uint8 data, x fastest."""
    raw = open(path, "rb").read()
    endian = "<" if struct.unpack("<h", raw[:2])[0] == 1 else ">"
    h = struct.unpack(endian + "28h", raw[:56])
    nx, ny, nz = h[25], h[26], h[27]
    data = np.frombuffer(raw, dtype=np.uint8, count=nx * ny * nz, offset=62)
    return data, (nx, ny, nz), (1.0, 1.0, 1.0)


def load_nifti(path):
    raw = gzip.open(path, "rb").read() if path.endswith(".gz") else open(path, "rb").read()
    endian = "<" if struct.unpack("<i", raw[:4])[0] == 348 else ">"
    dim = struct.unpack(endian + "8h", raw[40:56])
    datatype = struct.unpack(endian + "h", raw[70:72])[0]
    pixdim = struct.unpack(endian + "8f", raw[76:108])
    vox_offset = int(struct.unpack(endian + "f", raw[108:112])[0])
    slope, inter = struct.unpack(endian + "2f", raw[112:120])
    dtype = {2: "u1", 4: "i2", 8: "i4", 16: "f4", 64: "f8", 256: "i1", 512: "u2"}[datatype]
    nx, ny, nz = dim[1], dim[2], dim[3]
    data = np.frombuffer(raw, dtype=np.dtype(endian + dtype), count=nx * ny * nz, offset=vox_offset)
    if slope not in (0.0, 1.0) or inter != 0.0:
        data = data.astype(np.float32) * np.float32(slope) + np.float32(inter)
    return data, (nx, ny, nz), tuple(abs(p) for p in pixdim[1:4])


def contour_image(data, dims, spacing, iso, cls):
    img = vtk.vtkImageData()
    img.SetDimensions(*dims)
    img.SetSpacing(*spacing)
    arr = ns.numpy_to_vtk(np.ascontiguousarray(data), deep=True)
    arr.SetName("s")
    img.GetPointData().SetScalars(arr)
    return vtk_contour(cls, img, iso, ComputeScalars=False, ComputeGradients=False)


def compare(path, loader, iso):
    def t():
        data, dims, spacing = loader(path)
        out = os.path.join(D, os.path.basename(path) + f".{iso}.vtp")
        run("contour", path, "-o", out, "--iso", iso, "--quiet")
        km = read_polydata(out)
        fe = contour_image(data, dims, spacing, iso, vtk.vtkFlyingEdges3D)
        assert (km.GetNumberOfPoints(), km.GetNumberOfCells()) == (fe.GetNumberOfPoints(), fe.GetNumberOfCells()), \
            ("vtkFlyingEdges3D", km.GetNumberOfPoints(), fe.GetNumberOfPoints(), km.GetNumberOfCells(), fe.GetNumberOfCells())
        # vtkMarchingCubes merges points through a spatial locator, so two
        # crossings that round to the same float position (a sample within
        # float rounding of the isovalue) become one point, and a triangle
        # left with a repeated point is dropped; keys keep such points apart.
        # Its counts are therefore keymesh's after merging equal positions.
        mc = contour_image(data, dims, spacing, iso, vtk.vtkMarchingCubes)
        _, position_id = np.unique(points_of(km), axis=0, return_inverse=True)
        position_id = position_id.reshape(-1)
        t = position_id[triangles_of(km)]
        kept = int(np.count_nonzero((t[:, 0] != t[:, 1]) & (t[:, 1] != t[:, 2]) & (t[:, 0] != t[:, 2])))
        distinct = int(position_id.max()) + 1 if len(position_id) else 0
        assert (distinct, kept) == (mc.GetNumberOfPoints(), mc.GetNumberOfCells()), \
            ("vtkMarchingCubes", distinct, mc.GetNumberOfPoints(), kept, mc.GetNumberOfCells())
        assert km.GetNumberOfCells() > 1000, "isovalue picks too small a surface to be a test"
        a, b = points_of(km) / spacing, points_of(fe) / spacing  # in voxels
        sample = slice(None, None, max(1, len(a) // 40000))
        assert nearest_distances(a[sample], b).max() < 1e-4, "a keymesh point is off VTK's"
        assert nearest_distances(b[sample], a).max() < 1e-4, "a VTK point is off keymesh's"
    return t


if os.path.exists(DEN):
    for iso in (37.5, 90.25):
        check(f"brainsmall.den at iso {iso}: counts and points equal VTK's", compare(DEN, load_den, iso))
else:
    print(f"note: {DEN} missing (libvolpack1-dev); its cases skipped")
for name, iso in (("ch2.nii.gz", 70.5), ("ch2.nii.gz", 121.3), ("inia19-t1-brain.nii.gz", 60.37)):
    path = os.path.join(MRICRON, name)
    if os.path.exists(path):
        check(f"{name} at iso {iso}: counts and points equal VTK's", compare(path, load_nifti, iso))
    else:
        print(f"note: {path} missing (mricron-data); its case skipped")

finish()
