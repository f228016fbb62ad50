"""`mpirun -np P keymesh contour`: the distributed contour (issue 9).

Every rank reads its slab of the volume and the ranks weld the planes they
share by edge key. Checked against the single-process run of the same
keymesh: the gathered file is byte-identical for P = 1..4 (and 7 on an odd
grid), so points, triangles and their order agree bitwise; the .pvtp pieces (ghost cells dropped),
read by VTK's own reader and merged by their GlobalPointIds, give the same
points and triangles; the sphere stays a closed 2-manifold with no duplicate
point at slab borders. Skipped (77) when mpirun is missing or keymesh was
built without MPI."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import check, finish, mpirun, report, require_mpi, run, tempdir  # noqa: E402

D = tempdir()
N = 48
SPHERE = os.path.join(D, "sphere.raw")
run("generate", "sphere", "--size", N, "-o", SPHERE, "-q")
DIMS = ["--dims", N, N, N]
# Two nested spheres (the Spherical Distance field is centred in the grid).
ISOS = ["--iso", 20.5, "--iso", 11.25]
require_mpi("contour", SPHERE, *DIMS, "--iso", 20.5, "-o", os.path.join(D, "probe.ply"), "-q")

REF = os.path.join(D, "ref.ply")
run("contour", SPHERE, *DIMS, *ISOS, "-o", REF, "-q")


def gathered_equals_single_process():
    ref = open(REF, "rb").read()
    for P in (1, 2, 3, 4):
        out = os.path.join(D, f"g{P}.ply")
        rep = out + ".json"
        mpirun(P, "contour", SPHERE, *DIMS, *ISOS, "-o", out, "-q", "--report", rep)
        assert open(out, "rb").read() == ref, f"-np {P}: gathered file differs from the single-process one"
        r = report(rep)
        assert r["ranks"] == P and len(r["distributed"]["per_rank"]) == P, r["distributed"]
        owned = sum(s["points_owned"] for s in r["distributed"]["per_rank"])
        assert owned == r["points"], (owned, r["points"])
        # Slabs tile the voxel layers: each starts where the previous ends.
        slabs = r["distributed"]["per_rank"]
        assert slabs[0]["first_plane"] == 0 and slabs[-1]["first_plane"] + slabs[-1]["planes"] == N
        for a, b in zip(slabs, slabs[1:]):
            assert b["first_plane"] == a["first_plane"] + a["planes"] - 1, (a, b)
        if P > 1:
            assert r["distributed"]["bytes_exchanged"] > 0


def closed_manifold_across_borders():
    for P in (2, 4):
        out = os.path.join(D, f"g{P}.ply")
        rep = out + ".check.json"
        run("check", out, "--expect-closed", "-q", "--report", rep)
        c = report(rep)
        assert c["closed_manifold"] and c["duplicate_points"] == 0 and c["euler_characteristic"] == 4, c


def odd_grid_many_ranks():
    """uint16 big-endian noise on a 21x17x15 grid: every marching cubes case,
    borders at uneven planes, 7 ranks for 14 voxel layers."""
    import numpy as np
    rng = np.random.default_rng(7)
    vol = rng.integers(0, 1000, size=(15, 17, 21), dtype=np.uint16)
    path = os.path.join(D, "noise.raw")
    vol.astype(">u2").tofile(path)
    args = ["--dims", 21, 17, 15, "--type", "uint16", "--endian", "big", "--iso", 499.5, "--iso", 250.25]
    ref = os.path.join(D, "noise_ref.vtp")
    run("contour", path, *args, "-o", ref, "-q")
    for P in (3, 7):
        out = os.path.join(D, f"noise{P}.vtp")
        mpirun(P, "contour", path, *args, "-o", out, "-q")
        assert open(out, "rb").read() == open(ref, "rb").read(), f"-np {P}: noise volume differs"


def pieces_merge_to_the_same_mesh():
    import numpy as np
    import vtk
    from vtk.util import numpy_support as ns
    from kmtest import points_of, read_polydata, triangles_of
    ref = read_polydata(REF)
    ref_pts, ref_tris = points_of(ref).astype(np.float32), triangles_of(ref)
    for P in (2, 3):
        index = os.path.join(D, f"pieces{P}.pvtp")
        mpirun(P, "contour", SPHERE, *DIMS, *ISOS, "-o", index, "-q")
        assert sorted(f for f in os.listdir(D) if f.startswith(f"pieces{P}")) == \
            sorted([f"pieces{P}.pvtp"] + [f"pieces{P}_{q}.vtp" for q in range(P)])
        reader = vtk.vtkXMLPPolyDataReader()
        reader.SetFileName(index)
        pts = np.full((len(ref_pts), 3), np.nan, dtype=np.float32)
        tris, copies = [], 0
        for q in range(P):
            reader.UpdatePiece(q, P, 0)
            piece = reader.GetOutput()
            gid_array = piece.GetPointData().GetGlobalIds()
            assert gid_array is not None and gid_array.GetName() == "GlobalPointIds"
            gid = ns.vtk_to_numpy(gid_array).astype(np.int64)
            p = ns.vtk_to_numpy(piece.GetPoints().GetData()).astype(np.float32)
            assert gid.min() >= 0 and gid.max() < len(ref_pts)
            seen = ~np.isnan(pts[gid, 0])
            # A point two pieces hold has bitwise the same position in both.
            assert np.array_equal(pts[gid[seen]], p[seen]), "shared point differs between pieces"
            copies += int(seen.sum())
            pts[gid] = p
            # Ghost cells (vtkGhostType DUPLICATECELL) are a neighbour's, carried for filters.
            ghost = ns.vtk_to_numpy(piece.GetCellData().GetArray("vtkGhostType")) & 1
            tris.append(gid[triangles_of(piece)[ghost == 0]])
        assert not np.isnan(pts).any(), "a global id no piece holds"
        assert np.array_equal(pts, ref_pts), "merged points differ from the single-process run"
        merged = np.concatenate(tris)
        key = lambda t: t[np.lexsort((t[:, 2], t[:, 1], t[:, 0]))]  # noqa: E731
        assert np.array_equal(key(merged), key(ref_tris)), "merged triangles differ"
        assert copies > 0, "no point on a shared plane?"
        print(f"        -np {P}: {len(ref_pts)} points ({copies} copies in a second piece: shared planes, "
              f"ghost cells), {len(merged)} triangles")


def balanced_slabs():
    """--balance moves the slab boundaries by triangle counts: the file stays
    byte-identical, and the busiest rank holds fewer triangles than with
    equal layer counts (the sphere's top and bottom slabs are nearly empty)."""
    ref = open(REF, "rb").read()
    for P in (3, 4, 7):
        even, bal = os.path.join(D, f"even{P}.ply"), os.path.join(D, f"bal{P}.ply")
        mpirun(P, "contour", SPHERE, *DIMS, *ISOS, "-o", even, "-q", "--report", even + ".json")
        mpirun(P, "contour", SPHERE, *DIMS, *ISOS, "-o", bal, "-q", "--balance", "--report", bal + ".json")
        assert open(bal, "rb").read() == ref, f"-np {P} --balance: file differs"
        e, b = report(even + ".json")["distributed"], report(bal + ".json")["distributed"]
        assert b["triangle_imbalance"] < e["triangle_imbalance"], (P, b["triangle_imbalance"], e["triangle_imbalance"])
        slabs = b["per_rank"]
        assert slabs[0]["first_plane"] == 0 and slabs[-1]["first_plane"] + slabs[-1]["planes"] == N
        for a, c in zip(slabs, slabs[1:]):
            assert c["first_plane"] == a["first_plane"] + a["planes"] - 1 and a["planes"] >= 2, (a, c)


def keymesh_reads_its_pieces():
    """keymesh's own .pvtp reader welds the pieces by GlobalPointIds: `check`
    finds the closed sphere, and `convert` to .ply gives the gathered file
    byte for byte (one isovalue: the triangle order is the same) with
    gradient normals. With averaged normals a piece keeps its owners' merge
    of the ranks' partial sums (the gathered file sums in one process's
    order): the same points and triangles, unit normals within 1e-6."""
    import numpy as np
    import meshio

    index = os.path.join(D, "own.pvtp")
    gathered = os.path.join(D, "own_gathered.ply")
    converted = os.path.join(D, "own_converted.ply")
    for normals in ("gradient", "average"):
        args = [*DIMS, "--iso", 20.5, "--normals", normals, "-q"]
        mpirun(3, "contour", SPHERE, *args, "-o", index)
        mpirun(3, "contour", SPHERE, *args, "-o", gathered)
        run("check", index, "--expect-closed", "-q")
        run("convert", index, "-o", converted, "-q")
        if normals == "gradient":
            assert open(converted, "rb").read() == open(gathered, "rb").read(), "pieces read back differ"
            continue
        a, b = meshio.read(converted), meshio.read(gathered)
        assert np.array_equal(a.points, b.points) and np.array_equal(a.cells[0].data, b.cells[0].data)
        na = np.stack([a.point_data[k] for k in ("nx", "ny", "nz")], 1).astype(np.float64)
        nb = np.stack([b.point_data[k] for k in ("nx", "ny", "nz")], 1).astype(np.float64)
        assert np.abs(na - nb).max() < 1e-6 and np.abs(np.linalg.norm(na, axis=1) - 1).max() < 1e-6


def averaged_normals_merge_across_ranks():
    """--normals average: rank 0 sums the gathered mesh's face normals in one
    process's blocks of voxel layers (read from the points' edge keys), so the
    file is the single-process file byte for byte, with --balance too. (The
    owners' merge of partial sums, which pieces keep, differed in the last
    bits.)"""
    ref = os.path.join(D, "normals_ref.vtp")
    run("contour", SPHERE, *DIMS, *ISOS, "--normals", "average", "-o", ref, "-q")
    for P, extra in ((2, []), (3, []), (4, []), (3, ["--balance"])):
        out = os.path.join(D, f"normals{P}{''.join(extra)}.vtp")
        mpirun(P, "contour", SPHERE, *DIMS, *ISOS, "--normals", "average", "-o", out, "-q", *extra)
        assert open(out, "rb").read() == open(ref, "rb").read(), f"-np {P} {extra}: differs from one process"


def write_nifti(path, vol, slope, inter):
    """A NIfTI-1 .nii of int16 samples (x fastest), scl_slope/scl_inter set."""
    import struct
    h = bytearray(348)
    struct.pack_into("<i", h, 0, 348)
    nz, ny, nx = vol.shape
    struct.pack_into("<8h", h, 40, 3, nx, ny, nz, 1, 1, 1, 1)
    struct.pack_into("<hh", h, 70, 4, 16)                  # datatype int16, bitpix
    struct.pack_into("<8f", h, 76, 1, 0.5, 0.5, 0.5, 0, 0, 0, 0)
    struct.pack_into("<fff", h, 108, 352.0, slope, inter)  # vox_offset, scl_slope, scl_inter
    h[344:348] = b"n+1\0"
    with open(path, "wb") as f:
        f.write(bytes(h) + b"\0" * 4 + vol.astype("<i2").tobytes())


def derivatives_with_ghost_planes():
    """--normals gradient and --curvature: each rank reads a ghost plane on
    either side of its slab for the central differences; the gathered file is
    byte-identical to one process (normals and curvature included)."""
    args = [*DIMS, *ISOS, "--normals", "gradient", "--curvature", "-q"]
    ref = os.path.join(D, "deriv_ref.vtp")
    run("contour", SPHERE, *args, "-o", ref)
    for P in (2, 3, 5):
        for balance in ([], ["--balance"]):  # moved boundaries: held planes copied, the rest read
            out = os.path.join(D, f"deriv{P}.vtp")
            mpirun(P, "contour", SPHERE, *args, "-o", out, *balance)
            assert open(out, "rb").read() == open(ref, "rb").read(), f"-np {P} {balance}: derivatives differ"


def nrrd_and_nifti_read_by_slab():
    """Volumes in NRRD (uncompressed, big-endian) and scaled NIfTI: each
    rank reads its planes at their offset; the file equals the one process
    that reads the whole volume."""
    import numpy as np
    rng = np.random.default_rng(3)
    vol = rng.integers(-500, 500, size=(19, 16, 13)).astype(np.int16)
    nrrd = os.path.join(D, "v.nrrd")
    with open(nrrd, "wb") as f:
        f.write(b"NRRD0004\ntype: short\ndimension: 3\nsizes: 13 16 19\nencoding: raw\nendian: big\n"
                b"spacings: 1 2 0.5\n\n" + vol.astype(">i2").tobytes())
    nii = os.path.join(D, "v.nii")
    write_nifti(nii, vol, 0.25, 10.0)
    # gzip (each rank inflates up to its slab) and a Zarr folder (chunk rows).
    import gzip
    import zlib
    niigz = nii + ".gz"
    with open(nii, "rb") as f, open(niigz, "wb") as g:
        g.write(gzip.compress(f.read()))
    zarr = os.path.join(D, "v.zarr")
    os.makedirs(zarr, exist_ok=True)
    with open(os.path.join(zarr, ".zarray"), "w") as f:
        f.write('{"zarr_format": 2, "shape": [19, 16, 13], "chunks": [19, 16, 13], "dtype": "<i2", '
                '"compressor": {"id": "zlib", "level": 1}, "fill_value": 0, "order": "C", "filters": null}')
    with open(os.path.join(zarr, "0.0.0"), "wb") as f:
        f.write(zlib.compress(vol.astype("<i2").tobytes()))
    for path, iso in ((nrrd, 0.5), (nii, 10.125), (niigz, 10.125), (zarr, 0.5)):
        ref = os.path.join(D, "slab_ref.ply")
        run("contour", path, "--iso", iso, "-o", ref, "-q")
        for P in (2, 3):
            out = os.path.join(D, f"slab{P}.ply")
            mpirun(P, "contour", path, "--iso", iso, "-o", out, "-q")
            assert open(out, "rb").read() == open(ref, "rb").read(), f"{path} -np {P} differs"


def refusals():
    out = os.path.join(D, "refused.ply")
    vti = os.path.join(D, "s.vti")  # ascii samples: no offset to read a plane at
    with open(vti, "w") as f:
        f.write('<?xml version="1.0"?>\n<VTKFile type="ImageData" version="1.0" byte_order="LittleEndian">\n'
                '<ImageData WholeExtent="0 3 0 3 0 3" Origin="0 0 0" Spacing="1 1 1"><Piece Extent="0 3 0 3 0 3">'
                '<PointData Scalars="s"><DataArray type="Float32" Name="s" format="ascii">'
                + " ".join(str(i % 11) for i in range(64)) + '</DataArray></PointData></Piece></ImageData></VTKFile>\n')
    p = mpirun(2, "contour", vti, "--iso", 5.5, "-o", out, expect=1)
    assert "plane by plane" in p.stderr and p.stderr.count("plane by plane") == 1, p.stderr
    p = mpirun(2, "subdivide", REF, "-o", out, expect=2)
    assert "not distributed" in p.stderr and p.stderr.count("not distributed") == 1, p.stderr
    # Coarsening into pieces is no longer refused (test_coarsen_pieces_mpi_cli.py checks its pieces).
    mpirun(2, "contour", SPHERE, *DIMS, "--iso", 20.5, "--coarsen", "-o", os.path.join(D, "c.pvtp"), "-q")
    assert os.path.exists(os.path.join(D, "c.pvtp")) and os.path.exists(os.path.join(D, "c_1.vtp"))
    p = mpirun(2, "contour", SPHERE, *DIMS, "--iso", 20.5, "--gather", "-o", os.path.join(D, "x.pvtp"), expect=2)
    tiny = os.path.join(D, "tiny.raw")
    run("generate", "sphere", "--size", 4, "-o", tiny, "-q")
    p = mpirun(4, "contour", tiny, "--dims", 4, 4, 4, "--iso", 1.5, "-o", out, expect=1)
    assert "voxel layers" in p.stderr and "MPI_ABORT" not in p.stderr, p.stderr
    # Pieces into a directory that does not exist: nothing written, exit 1.
    p = mpirun(2, "contour", SPHERE, *DIMS, "--iso", 20.5, "-o", os.path.join(D, "nowhere", "x.pvtp"), expect=1)
    assert not os.path.exists(out) and not os.path.exists(os.path.join(D, "x.pvtp"))


check("mpirun -np 1..4: gathered file byte-identical to the single-process run; slabs tile the grid",
      gathered_equals_single_process)
check("distributed sphere is a closed 2-manifold, no duplicate point at slab borders", closed_manifold_across_borders)
check("uint16 big-endian noise on an odd grid, -np 3 and 7: byte-identical", odd_grid_many_ranks)
check(".pvtp pieces read by VTK and merged by GlobalPointIds equal the single-process mesh",
      pieces_merge_to_the_same_mesh)
check("--balance: slabs by triangle counts, byte-identical, busiest rank lighter (-np 3, 4, 7)", balanced_slabs)
check("keymesh reads its .pvtp: closed sphere, converts to the gathered file byte for byte", keymesh_reads_its_pieces)
check("--normals average: gathered output byte-identical to one process",
      averaged_normals_merge_across_ranks)
check("gradient normals and curvature with ghost planes: byte-identical at -np 2, 3, 5",
      derivatives_with_ghost_planes)
check(".nrrd (big-endian), scaled .nii and .nii.gz, a Zarr folder read by slab: byte-identical at -np 2 and 3",
      nrrd_and_nifti_read_by_slab)
check("refused by name: .vti input, other commands, --gather with .pvtp, too many ranks (coarsening into pieces "
      "runs), "
      "unwritable pieces", refusals)
finish()
