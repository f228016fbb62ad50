"""`keymesh contour --history` (issue 37): per-point history_key and history_t.

A float32 volume (smoothed noise with many samples set exactly to an
isovalue) and a uint16 one, on grids with spacing and origin of their own
(one where a coordinate crosses zero), contoured at several isovalues into
.vtp. Read back with VTK's own reader (not keymesh's), independently of
keymesh:
  - history_key is UInt64 and names exactly the grid edges numpy finds cut
    by an isovalue (one point per cut edge, no two points share a key);
  - history_t lies in [0, 1], within a few float steps of the crossing's t
    recomputed from the samples, and gives the written position back:
    float32(origin + spacing * (ijk + t)) along the edge's axis, the grid
    line's coordinate on the other two, bit for bit where a float t can
    (docs/HISTORY.md), within the documented bound elsewhere;
  - the arrays are the same at 1 and 2 threads, with every weld, in slabs
    (--memory-limit), gathered under mpirun -np 2 and 3, and in .pvtp
    pieces (ghost points included);
  - combinations that cannot hold a history are refused by name.
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import (assert_pieces_carry_history, box_filtered_noise, check, finish, history_arrays,  # noqa: E402
                    mpirun, mpirun_runs, require_vtk, run, tempdir)

require_vtk()
import numpy as np  # noqa: E402
from vtk.util import numpy_support as ns  # noqa: E402

from kmtest import read_polydata  # noqa: E402

D = tempdir()


class Volume:
    """A raw volume (x fastest) with its geometry and the contour's arguments."""

    def __init__(self, name, samples, spacing, origin, isos):
        self.samples = samples  # numpy shape (nz, ny, nx)
        self.nz, self.ny, self.nx = samples.shape
        self.spacing = np.array(spacing, np.float64)
        self.origin = np.array(origin, np.float64)
        self.isos = isos
        self.path = os.path.join(D, name + ".raw")
        samples.tofile(self.path)
        self.type = {np.dtype(np.float32): "float32", np.dtype(np.uint16): "uint16"}[samples.dtype]

    def args(self):
        a = [self.path, "--dims", self.nx, self.ny, self.nz, "--type", self.type,
             "--spacing", *self.spacing, "--origin", *self.origin]
        for v in self.isos:
            a += ["--iso", v]
        return a

    def cut_edges(self):
        """Every cut edge's key (3 * point id + axis + iso index * 3N), from the samples."""
        v = self.samples.astype(np.float64)
        n = v.size
        ids = np.arange(n).reshape(v.shape)
        keys = []
        for index, iso in enumerate(self.isos):
            inside = v >= iso  # NaN-free volumes here
            for axis, np_axis in ((0, 2), (1, 1), (2, 0)):
                lo = [slice(None)] * 3
                hi = [slice(None)] * 3
                lo[np_axis] = slice(0, -1)
                hi[np_axis] = slice(1, None)
                cut = inside[tuple(lo)] != inside[tuple(hi)]
                keys.append(index * 3 * n + 3 * ids[tuple(lo)][cut] + axis)
        return np.sort(np.concatenate(keys)).astype(np.uint64)


def noise_volume():
    v = box_filtered_noise((17, 19, 23), seed=11)
    rng = np.random.default_rng(5)
    isos = [0.47, 0.5, 0.53]
    # Samples on an isovalue: crossings at t = 0 or 1 (inside means >= iso).
    on = rng.random(v.shape) < 0.05
    v[on] = np.float32(0.5)
    return Volume("noise", v, (0.3, 0.7, 1.1), (1.5, 2.25, 40.0), isos)


def centred_volume():
    """Origin at minus half the extent: the coordinates cross zero."""
    v = box_filtered_noise((21, 16, 18), seed=4)
    return Volume("centred", v, (0.25, 0.5, 1.0 / 3.0), (-2.125, -3.75, -3.3), [0.5, 0.46])


def integer_volume():
    rng = np.random.default_rng(9)
    v = (box_filtered_noise((13, 15, 11), seed=2) * 1000).astype(np.uint16)
    v[rng.random(v.shape) < 0.05] = 500
    return Volume("integers", v, (1.0, 2.0, 0.5), (-7.0, 0.0, 3.0), [500, 480.5])


VOLUMES = [noise_volume(), centred_volume(), integer_volume()]


def history(path):
    """points (float32), history_key (uint64), history_t (float32) as VTK reads them."""
    return history_arrays(read_polydata(path), path)


def contour(vol, name, *extra):
    out = os.path.join(D, name + ".vtp")
    run("contour", *vol.args(), "--history", "-o", out, "-q", *extra)
    return out


def decode(vol, keys):
    n = vol.nx * vol.ny * vol.nz
    iso_index = keys // np.uint64(3 * n)
    edge = (keys % np.uint64(3 * n)).astype(np.int64)
    p, axis = edge // 3, edge % 3
    ijk = np.stack([p % vol.nx, p // vol.nx % vol.ny, p // (vol.nx * vol.ny)], axis=1)
    return iso_index.astype(np.int64), p, axis, ijk


def reproduce(vol, keys, t):
    """The documented formula: every point's position from its key and t."""
    _, _, axis, ijk = decode(vol, keys)
    u = ijk.astype(np.float64)
    rows = np.arange(len(keys))
    u[rows, axis] += t.astype(np.float64)
    return (vol.origin + vol.spacing * u).astype(np.float32), axis


def keys_are_the_cut_edges():
    for vol in VOLUMES:
        _, keys, _ = history(contour(vol, vol.type + "_keys"))
        assert len(np.unique(keys)) == len(keys), "two points share a history_key"
        expected = vol.cut_edges()
        assert np.array_equal(np.sort(keys), expected), (len(keys), len(expected))


def positions_reproduced():
    for vol in VOLUMES:
        points, keys, t = history(contour(vol, vol.type + "_pos"))
        assert t.min() >= 0 and t.max() <= 1, (t.min(), t.max())
        again, axis = reproduce(vol, keys, t)
        rows = np.arange(len(keys))
        # Off the edge's axis: the grid line's coordinate, bit for bit.
        off = np.ones_like(again, bool)
        off[rows, axis] = False
        assert np.array_equal(again[off], points[off]), os.path.basename(vol.path)
        along_written = points[rows, axis].astype(np.float64)
        along_again = again[rows, axis].astype(np.float64)
        exact = along_again == along_written
        # The bound where no float t gives the coordinate back (docs/HISTORY.md):
        # |spacing| * 2^-25 plus one float step of the written coordinate.
        step = np.spacing(np.abs(points[rows, axis])).astype(np.float64)
        bound = vol.spacing[axis] * 2.0 ** -25 + step
        assert np.all(np.abs(along_again - along_written) <= bound)
        print(f"  {os.path.basename(vol.path)}: {exact.sum()} of {len(exact)} coordinates exact")
        # Bit for bit wherever the coordinate is a voxel or more from zero
        # (docs/HISTORY.md): there a float t giving it back exists.
        far = np.abs(along_written) >= vol.spacing[axis]
        assert exact[far].all(), np.flatnonzero(far & ~exact)[:10]
        if vol.origin.min() >= 0:
            assert exact.all()


def t_is_the_crossing():
    for vol in VOLUMES:
        _, keys, t = history(contour(vol, vol.type + "_t"))
        iso_index, p, axis, _ = decode(vol, keys)
        flat = vol.samples.reshape(-1).astype(np.float64)
        stride = np.array([1, vol.nx, vol.nx * vol.ny])[axis]
        v0, v1 = flat[p], flat[p + stride]
        iso = np.array(vol.isos)[iso_index]
        assert np.all((v0 >= iso) != (v1 >= iso)), "an edge its isovalue does not cut"
        exact_t = np.clip((iso - v0) / (v1 - v0), 0, 1)
        assert np.all(np.abs(t - exact_t) <= 2.0 ** -20), np.abs(t - exact_t).max()
        # Samples on the isovalue give t = 0 or 1 exactly.
        assert np.all(t[v0 == iso] == 0) and np.all(t[v1 == iso] == 1)


def same_history_any_way():
    for vol in VOLUMES:
        ref = contour(vol, vol.type + "_ref", "--threads", "2")
        ref_bytes = open(ref, "rb").read()
        assert open(contour(vol, vol.type + "_t1", "--threads", "1"), "rb").read() == ref_bytes
        assert open(contour(vol, vol.type + "_sort", "--weld", "keyreduce-sort"), "rb").read() == ref_bytes
        plane = vol.nx * vol.ny * vol.samples.itemsize
        for planes in (2, 3, 5):
            out = contour(vol, f"{vol.type}_slabs{planes}", "--memory-limit", str(planes * plane))
            assert open(out, "rb").read() == ref_bytes, f"--memory-limit of {planes} planes"
        if vol is not VOLUMES[1]:
            continue
        # VERTEX-WELD (on a volume with no sample on an isovalue, where it
        # merges the crossings at one grid point): the same points in
        # another order; the same key, t and position per point.
        points, keys, t = history(ref)
        p2, k2, t2 = history(contour(vol, vol.type + "_vw", "--weld", "vertexweld"))
        order = np.argsort(k2)
        assert np.array_equal(k2[order], keys) and np.array_equal(t2[order], t)
        assert np.array_equal(p2[order], points)


def normals_and_curvature_keep_the_history():
    vol = VOLUMES[0]
    points, keys, t = history(contour(vol, "plain"))
    for extra in (["--normals", "gradient", "--curvature"], ["--normals", "average"], ["--no-scalars"]):
        p2, k2, t2 = history(contour(vol, "with_" + extra[-1].strip("-"), *extra))
        assert np.array_equal(k2, keys) and np.array_equal(t2, t) and np.array_equal(p2, points), extra


def refusals():
    vol = VOLUMES[0]
    cases = [
        (["--coarsen"], "vtp", "--coarsen"),
        ([], "ply", "only .vtp"),
        ([], "obj", "only .vtp"),
        ([], "glb", "only .vtp"),
        (["--backend", "cuda"], "vtp", "per-point history (--history)"),
    ]
    for extra, ext, needle in cases:
        out = os.path.join(D, "refused." + ext)
        p = run("contour", *vol.args(), "--history", "-o", out, *extra, expect=None)
        assert p.returncode != 0 and needle in p.stderr, (extra, ext, p.returncode, p.stderr)
        assert p.stderr.count("\n") == 1, p.stderr
        assert not os.path.exists(out), out


def tet_grid():
    """A .vti (VTK's writer) of smoothed noise with its own spacing and
    origin, split into 5 tets per voxel by keymesh: edges along diagonals,
    so t moves all three coordinates."""
    import vtk
    v = box_filtered_noise((7, 8, 9), seed=21)
    image = vtk.vtkImageData()
    image.SetDimensions(9, 8, 7)
    image.SetSpacing(0.3, 0.45, 1.7)
    image.SetOrigin(0.6, -1.2, 2.5)
    array = ns.numpy_to_vtk(v.reshape(-1), deep=1)
    array.SetName("f")
    image.GetPointData().SetScalars(array)
    writer = vtk.vtkXMLImageDataWriter()
    vti, vtu = os.path.join(D, "tet_source.vti"), os.path.join(D, "tets.vtu")
    writer.SetFileName(vti)
    writer.SetInputData(image)
    writer.Write()
    run("tetrahedralize", vti, "-o", vtu, "-q")
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(vtu)
    reader.Update()
    grid = reader.GetOutput()
    points = ns.vtk_to_numpy(grid.GetPoints().GetData())
    samples = ns.vtk_to_numpy(grid.GetPointData().GetArray("f")).astype(np.float64)
    tets = ns.vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, 4)
    return vtu, points, samples, tets


def tet_history():
    vtu, P, S, tets = tet_grid()
    isos = [0.5, 0.47]
    iso_args = [a for v in isos for a in ("--iso", v)]
    out = os.path.join(D, "tets_history.vtp")
    run("contour", vtu, *iso_args, "--history", "-o", out, "-q")
    points, keys, t = history(out)
    assert len(np.unique(keys)) == len(keys) and t.min() >= 0 and t.max() <= 1
    b = max(1, (len(P) - 1).bit_length())
    mask = np.uint64((1 << b) - 1)
    level = (keys >> np.uint64(2 * b)).astype(np.int64)
    a = ((keys >> np.uint64(b)) & mask).astype(np.int64)
    c = (keys & mask).astype(np.int64)
    assert np.all(a < c)
    # Exactly the tet edges an isovalue cuts, one point each.
    pairs = np.concatenate([np.sort(tets[:, [x, y]], axis=1) for x in range(4) for y in range(x + 1, 4)])
    edges = np.unique(pairs, axis=0)
    cut = [(index, e0, e1) for index, iso in enumerate(isos) for e0, e1 in edges[(S[edges[:, 0]] >= iso) !=
                                                                                 (S[edges[:, 1]] >= iso)]]
    assert sorted(cut) == sorted(zip(level.tolist(), a.tolist(), c.tolist()))
    # The documented formula, per coordinate, from the smaller id a.
    pa, pc = P[a].astype(np.float64), P[c].astype(np.float64)
    again = (pa + t.astype(np.float64)[:, None] * (pc - pa)).astype(np.float32)
    exact = np.all(again == points, axis=1)
    bound = np.abs(pc - pa) * 2.0 ** -25 + np.spacing(np.abs(points)).astype(np.float64)
    assert np.all(np.abs(again.astype(np.float64) - points) <= bound)
    print(f"  tets: {exact.sum()} of {len(exact)} points exact")
    # Two or three coordinates must come back from one float t: not always
    # possible, but for nearly every point an edge or more from zero.
    step = np.abs(pc - pa)
    far = np.all((np.abs(points) >= step) | (step == 0), axis=1)
    assert exact[far].mean() > 0.99 and exact.mean() > 0.95, (exact[far].mean(), exact.mean())
    exact_t = np.clip((np.array(isos)[level] - S[a]) / (S[c] - S[a]), 0, 1)
    assert np.all(np.abs(t - exact_t) <= 2.0 ** -20)
    assert open(contour_file(vtu, iso_args, "tets_t1", "--threads", "1"), "rb").read() == open(out, "rb").read()


def contour_file(source, args, name, *extra):
    out = os.path.join(D, name + ".vtp")
    run("contour", source, *args, "--history", "-o", out, "-q", *extra)
    return out


def keymesh_reads_it_back():
    vol = VOLUMES[2]
    out = contour(vol, "readback")
    rep = out + ".json"
    run("check", out, "-q", "--report", rep)


def under_mpirun():
    if not mpirun_runs("contour", *VOLUMES[0].args(), "-o", os.path.join(D, "probe.vtp"), "-q"):
        return
    for vol in VOLUMES:
        ref = open(contour(vol, vol.type + "_mref"), "rb").read()
        for P in (2, 3):
            out = os.path.join(D, f"{vol.type}_np{P}.vtp")
            mpirun(P, "contour", *vol.args(), "--history", "-o", out, "-q")
            assert open(out, "rb").read() == ref, f"-np {P}: gathered .vtp differs"
    # Pieces (.pvtp, ghost cells included): every point, owned or ghost,
    # carries the key, t and position the single-process file gives it.
    vol = VOLUMES[0]
    ref = contour(vol, "pieces_ref")
    for P in (2, 3):
        index = os.path.join(D, f"pieces{P}.pvtp")
        mpirun(P, "contour", *vol.args(), "--history", "-o", index, "-q")
        assert_pieces_carry_history(ref, index, P)


check("history_key names exactly the cut grid edges, once each", keys_are_the_cut_edges)
check("history_key and history_t give every position back", positions_reproduced)
check("history_t is the crossing's t (0 and 1 on samples at the isovalue)", t_is_the_crossing)
check("the same history at 1 and 2 threads, any weld, in slabs", same_history_any_way)
check("normals, curvature and scalars leave the history unchanged", normals_and_curvature_keep_the_history)
check("--history with --coarsen, .ply/.obj/.glb, cuda: refused by name", refusals)
check("marching tetrahedra: history_key names the cut tet edge, history_t gives the point back", tet_history)
check("keymesh reads a history .vtp back", keymesh_reads_it_back)
check("mpirun -np 2 and 3: the single-process .vtp; .pvtp pieces carry every point's history", under_mpirun)
finish()
