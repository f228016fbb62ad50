"""Helpers shared by the end-to-end tests (run with Debian's /usr/bin/python3).

Each test script is a plain program: it runs the `keymesh` binary given as
argv[1], asserts, prints one line per check and a closing
"N passed, N failed" line, and exits 0 only when everything passed
(77 = skipped, e.g. when VTK is not importable).
"""
import atexit
import json
import os
import shutil
import subprocess
import sys
import tempfile
import traceback

KEYMESH = sys.argv[1] if len(sys.argv) > 1 else os.environ.get("KEYMESH", "build/keymesh")
SOURCE_DIR = os.environ.get("KEYMESH_SOURCE_DIR", os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

_results = {"passed": 0, "failed": 0}


def run(*args, expect=0, env=None):
    """Runs keymesh with args; asserts the exit code; returns the CompletedProcess."""
    p = subprocess.run([KEYMESH, *map(str, args)], capture_output=True, text=True, stdin=subprocess.DEVNULL,
                       timeout=600, env=env)
    if expect is not None and p.returncode != expect:
        raise AssertionError(f"keymesh {' '.join(map(str, args))}: exit {p.returncode}, expected {expect}\n"
                             f"stdout: {p.stdout}\nstderr: {p.stderr}")
    return p


def report(path):
    with open(path) as f:
        return json.load(f)


def check(name, fn):
    try:
        fn()
        print(f"ok      {name}")
        _results["passed"] += 1
    except Exception:  # noqa: BLE001 - report every failure and go on
        print(f"FAILED  {name}")
        traceback.print_exc(file=sys.stdout)
        _results["failed"] += 1


def finish(skipped=None):
    """Exits 0 when every check passed, 1 otherwise; 77 (skipped) when all
    passed but `skipped` says why a part could not run here."""
    print(f"{_results['passed']} passed, {_results['failed']} failed")
    if _results["failed"] == 0 and skipped:
        print(f"skipped: {skipped}")
        sys.exit(77)
    sys.exit(0 if _results["failed"] == 0 else 1)


def precomputed_reader():
    """(numpy, tests/neuroglancer_precomputed) for the tests that read
    Neuroglancer precomputed output; exits 77 (skipped) without numpy or
    Debian's draco_decoder."""
    try:
        import numpy
    except ImportError as e:
        print(f"skipped: {e}")
        sys.exit(77)
    import neuroglancer_precomputed
    if not neuroglancer_precomputed.DRACO_DECODER:
        print("skipped: draco_decoder not found (Debian package draco)")
        sys.exit(77)
    return numpy, neuroglancer_precomputed


def write_label_nrrd(path, volume):
    """volume[x, y, z] (a numpy array, stored as uint8) as a raw NRRD, x fastest; returns path."""
    import numpy as np
    header = (f"NRRD0004\ntype: uint8\ndimension: 3\nsizes: {volume.shape[0]} {volume.shape[1]} {volume.shape[2]}\n"
              "spacings: 1 1 1\nencoding: raw\n\n")
    with open(path, "wb") as f:
        f.write(header.encode())
        f.write(volume.astype(np.uint8).tobytes(order="F"))
    return path


def box_filtered_noise(shape, seed):
    """Uniform noise in [0, 1) of `shape` (z, y, x), box-filtered along each
    axis (periodic): blobs a few voxels wide, which coarsening pinches."""
    import numpy as np
    v = np.random.default_rng(seed).random(shape, dtype=np.float32)
    for axis in range(3):
        v = (np.roll(v, 1, axis) + v + np.roll(v, -1, axis)) / 3
    return v.astype(np.float32)


def parse_glb(path):
    """The glTF 2.0 binary container by its specification: 12-byte header,
    a JSON chunk and a BIN chunk, each 4-byte aligned."""
    import struct
    data = open(path, "rb").read()
    magic, version, length = struct.unpack_from("<III", data, 0)
    assert magic == 0x46546C67 and version == 2 and length == len(data) and length % 4 == 0
    jlen, jtype = struct.unpack_from("<II", data, 12)
    assert jtype == 0x4E4F534A and jlen % 4 == 0
    doc = json.loads(data[20:20 + jlen])
    blen, btype = struct.unpack_from("<II", data, 20 + jlen)
    assert btype == 0x004E4942 and blen % 4 == 0 and 28 + jlen + blen == length
    assert doc["buffers"][0]["byteLength"] <= blen
    return doc, data[28 + jlen:28 + jlen + blen]


def accessor(doc, binary, index):
    """An accessor of a parsed .glb (SCALAR or VEC3 float32 / uint32): (accessor, values (count, width))."""
    import numpy as np
    a = doc["accessors"][index]
    v = doc["bufferViews"][a["bufferView"]]
    assert v["byteOffset"] % 4 == 0 and "byteStride" not in v
    dtype = {5126: "<f4", 5125: "<u4"}[a["componentType"]]
    width = {"SCALAR": 1, "VEC3": 3}[a["type"]]
    values = np.frombuffer(binary, dtype, a["count"] * width, v["byteOffset"]).reshape(-1, width)
    assert values.nbytes == v["byteLength"]
    return a, values


def tempdir():
    """A fresh directory, removed when the test program exits (a failing run
    included) unless KEYMESH_KEEP_TEST_DIRS is set: CLI tests write hundreds of
    MiB each, which filled a developer's disk when they were kept."""
    path = tempfile.mkdtemp(prefix="keymesh-test-")
    if not os.environ.get("KEYMESH_KEEP_TEST_DIRS"):
        atexit.register(shutil.rmtree, path, True)
    return path


def require_numpy():
    """numpy, or the test exits 77 (skipped) without it."""
    try:
        import numpy
    except ImportError as e:
        print(f"skipped: {e}")
        sys.exit(77)
    return numpy


def boxes_in_noise(shape, seed, boxes, noise_fraction, noise_labels=(0, 4)):
    """An int16 label volume [x, y, z] of `shape`: the boxes (label, slices;
    later ones on top, 0 around them), each voxel replaced with probability
    noise_fraction by uniform noise over the labels [lo, hi): triple lines,
    diagonal contacts and regions touching every border."""
    np = require_numpy()
    rng = np.random.default_rng(seed)
    noise = rng.integers(*noise_labels, size=shape)
    labels = np.zeros(shape, np.int16)
    for label, where in boxes:
        labels[where] = label
    return np.where(rng.random(shape) < noise_fraction, noise, labels).astype(np.int16)


def write_raw(path, volume):
    """volume[x, y, z] as raw samples, x fastest; returns path."""
    with open(path, "wb") as f:
        f.write(volume.tobytes(order="F"))
    return path


def require_vtk():
    try:
        import vtk  # noqa: F401
        from vtk.util import numpy_support  # noqa: F401
        import numpy  # noqa: F401
    except ImportError as e:
        print(f"skipped: {e} (install python3-vtk9 and python3-numpy)")
        sys.exit(77)


def read_polydata(path):
    """A mesh file read by VTK's own readers (not keymesh's)."""
    import vtk
    ext = os.path.splitext(path)[1].lower()
    reader = {".vtp": vtk.vtkXMLPolyDataReader, ".ply": vtk.vtkPLYReader, ".stl": vtk.vtkSTLReader,
              ".obj": vtk.vtkOBJReader}[ext]()
    reader.SetFileName(path)
    reader.Update()
    return reader.GetOutput()


def vtk_contour(filter_class, data, value, array=None, **switches):
    """VTK's contour filter_class run on data at one value, normals off as in
    keymesh's default output; switches set the filter's other flags
    (ComputeScalars=False calls SetComputeScalars(False)); array names the
    point array to contour when it is not the active scalars. The output."""
    import vtk
    f = filter_class()
    f.SetInputData(data)
    f.SetValue(0, value)
    f.ComputeNormalsOff()
    for name, on in switches.items():
        getattr(f, "Set" + name)(on)
    if array is not None:
        f.SetInputArrayToProcess(0, 0, 0, vtk.vtkDataObject.FIELD_ASSOCIATION_POINTS, array)
    f.Update()
    return f.GetOutput()


def points_of(poly):
    import numpy as np
    from vtk.util import numpy_support as ns
    if poly.GetNumberOfPoints() == 0:
        return np.zeros((0, 3))
    return ns.vtk_to_numpy(poly.GetPoints().GetData()).astype(np.float64)


def triangles_of(poly):
    import numpy as np
    from vtk.util import numpy_support as ns
    polys = poly.GetPolys()
    if polys.GetNumberOfCells() == 0:
        return np.zeros((0, 3), dtype=np.int64)
    conn = ns.vtk_to_numpy(polys.GetConnectivityArray()).astype(np.int64)
    offs = ns.vtk_to_numpy(polys.GetOffsetsArray()).astype(np.int64)
    assert (np.diff(offs) == 3).all(), "not all cells are triangles"
    return conn.reshape(-1, 3)


def welded_vtk_pieces(index, P, n_points, piece_rows, point_array=None):
    """A .pvtp's pieces read by VTK's parallel reader and welded by their
    GlobalPointIds: the points (float32, by global id), the named point
    array (float32 rows by id, or None), and piece_rows(piece, triangles in
    global ids, owned mask) of every non-empty piece. Every copy of a point
    (and of its array row) must agree bit for bit, and every id be held."""
    import numpy as np
    import vtk
    from vtk.util import numpy_support as ns
    reader = vtk.vtkXMLPPolyDataReader()
    reader.SetFileName(index)
    pts = np.full((n_points, 3), np.nan, np.float32)
    arr = None
    rows = []
    for q in range(P):
        reader.UpdatePiece(q, P, 0)
        piece = reader.GetOutput()
        if piece.GetNumberOfPoints() == 0:
            continue
        gid = ns.vtk_to_numpy(piece.GetPointData().GetGlobalIds()).astype(np.int64)
        p = ns.vtk_to_numpy(piece.GetPoints().GetData()).astype(np.float32)
        assert gid.min() >= 0 and gid.max() < n_points, (gid.min(), gid.max(), n_points)
        seen = ~np.isnan(pts[gid, 0])
        assert np.array_equal(pts[gid[seen]].view(np.uint32), p[seen].view(np.uint32)), "pieces disagree on a point"
        pts[gid] = p
        a = piece.GetPointData().GetArray(point_array) if point_array else None
        if a is not None:
            a = ns.vtk_to_numpy(a).astype(np.float32).reshape(len(gid), -1)
            if arr is None:
                arr = np.full((n_points, a.shape[1]), np.nan, np.float32)
            assert np.array_equal(arr[gid[seen]].view(np.uint32), a[seen].view(np.uint32)), \
                f"pieces disagree on a {point_array} row"
            arr[gid] = a
        ghost = ns.vtk_to_numpy(piece.GetCellData().GetArray("vtkGhostType")) & 1
        rows.append(piece_rows(piece, gid[triangles_of(piece)], ghost == 0))
    assert not np.isnan(pts).any(), "a global id no piece holds"
    return pts, arr, rows


def canonical_mesh(points, tris):
    """Points sorted lexicographically and triangles renumbered accordingly,
    each rotated to start at its smallest id and the list sorted: two meshes
    equal up to renumbering have equal canonical forms."""
    import numpy as np
    order = np.lexsort((points[:, 2], points[:, 1], points[:, 0]))
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    t = rank[tris]
    roll = np.argmin(t, axis=1)
    t = np.stack([t[np.arange(len(t)), (roll + k) % 3] for k in range(3)], axis=1)
    t = t[np.lexsort((t[:, 2], t[:, 1], t[:, 0]))]
    return points[order], t


def nearest_distances(a, b):
    """For every point of a, the distance to the nearest point of b (VTK locator)."""
    import numpy as np
    import vtk
    from vtk.util import numpy_support as ns
    pts = vtk.vtkPoints()
    pts.SetData(ns.numpy_to_vtk(np.ascontiguousarray(b, dtype=np.float64), deep=True))
    pd = vtk.vtkPolyData()
    pd.SetPoints(pts)
    loc = vtk.vtkStaticPointLocator()
    loc.SetDataSet(pd)
    loc.BuildLocator()
    d = np.empty(len(a))
    for i, p in enumerate(a):
        j = loc.FindClosestPoint(p)
        d[i] = np.linalg.norm(b[j] - p)
    return d


def mpirun_command(P, *args, program=None):
    """The command line and environment of `mpirun -np P keymesh args` (or `program`)."""
    cmd = [shutil.which("mpirun"), "--oversubscribe", "-np", str(P)]
    if os.geteuid() == 0:
        cmd.insert(1, "--allow-run-as-root")
    # One thread per rank: ranks are oversubscribed on small CI machines.
    # No CMA single-copy: containers without ptrace rights refuse it.
    # A session directory of its own per test process: two mpiruns at once
    # (ctest -j, or two test runs on one machine) raced to create the shared
    # /tmp/ompi.<host>.<uid> ("mkdir ... File exists", orte_init failed).
    env = dict(os.environ, OMP_NUM_THREADS="1", OMPI_MCA_rmaps_base_oversubscribe="1",
               OMPI_MCA_btl_vader_single_copy_mechanism="none", OMPI_MCA_orte_tmpdir_base=_mpi_session_base())
    if "ASAN_OPTIONS" in env:
        # make sanitize: OpenMPI's own allocations (MCA components, op tables)
        # are never freed; keymesh's leaks are checked by every other test.
        env["ASAN_OPTIONS"] += ":detect_leaks=0"
    return cmd + [program or KEYMESH, *map(str, args)], env


_MPI_SESSION_BASE = []


def _mpi_session_base():
    """A temporary folder for OpenMPI's session files, one per test process."""
    if not _MPI_SESSION_BASE:
        import atexit
        _MPI_SESSION_BASE.append(tempfile.mkdtemp(prefix="keymesh-ompi-"))
        atexit.register(shutil.rmtree, _MPI_SESSION_BASE[0], ignore_errors=True)
    return _MPI_SESSION_BASE[0]


def mpirun(P, *args, expect=0, program=None):
    """Runs `mpirun -np P keymesh args` (or `program`); asserts the exit code."""
    cmd, env = mpirun_command(P, *args, program=program)
    p = subprocess.run(cmd, capture_output=True, text=True, stdin=subprocess.DEVNULL, timeout=300, env=env)
    if expect is not None and p.returncode != expect:
        raise AssertionError(f"mpirun -np {P} keymesh {' '.join(map(str, args))}: exit {p.returncode}, "
                             f"expected {expect}\nstdout: {p.stdout}\nstderr: {p.stderr}")
    return p


def require_mpi(*probe):
    """Exits 77 (skipped) unless this machine runs MPI programs and keymesh
    was built with MPI: `mpirun -np 2 keymesh probe...` must start (exits 1
    when it fails for another reason)."""
    if not shutil.which("mpirun"):
        print("skipped: no mpirun (install openmpi-bin and libopenmpi-dev)")
        sys.exit(77)
    # Can this machine run MPI programs at all? (Not keymesh's fault if not.)
    launcher = mpirun(2, expect=None, program=shutil.which("true") or "/bin/true")
    if launcher.returncode != 0:
        print(f"skipped: mpirun -np 2 true fails here (exit {launcher.returncode}): {launcher.stderr.strip()[:400]}")
        sys.exit(77)
    p = mpirun(2, *probe, expect=None)
    if p.returncode != 0 and "built without MPI" in p.stderr:
        print("skipped: keymesh was built without MPI (install libopenmpi-dev and rebuild)")
        sys.exit(77)
    if p.returncode != 0:
        print(f"mpirun does not start keymesh here (exit {p.returncode}):\n{p.stderr}")
        sys.exit(1)


def write_triangles_ply(path, points, triangles):
    """points (n x 3) and triangles (m x 3 point ids) as a binary PLY; returns path."""
    import numpy as np
    with open(path, "wb") as f:
        f.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {len(points)}\nproperty float x\n"
                 f"property float y\nproperty float z\nelement face {len(triangles)}\n"
                 "property list uchar int vertex_indices\nend_header\n").encode())
        f.write(np.asarray(points, "<f4").tobytes())
        faces = np.zeros(len(triangles), dtype=[("n", "u1"), ("i", "<i4", 3)])
        faces["n"], faces["i"] = 3, triangles
        f.write(faces.tobytes())
    return path


def self_intersections(points, triangles, path):
    """(crossing pairs, zero-area triangles) of a triangle mesh by `keymesh
    check --self-intersections` (exact predicates), written to `path` (PLY)."""
    import re
    write_triangles_ply(path, points, triangles)
    out = run("check", path, "--self-intersections", expect=None).stdout
    m = re.search(r"self-intersections (\d+) \(pairs of cells\), zero-area triangles (\d+)", out)
    assert m, out
    return int(m.group(1)), int(m.group(2))


def precomputed_level_crossings(ngp, out, segments, scratch):
    """{(segment, lod): (crossing pairs, zero-area triangles, triangles)} of a
    precomputed output: each segment's decoded fragments of one level (every
    chunk's) joined at their exact global quantized coordinates (node *
    (2^bits - 1) + value, integers exact in float32), one point per position,
    so crossings between triangles of neighbouring chunks count too."""
    import numpy as np
    info = ngp.read_info(out)
    top = 2 ** info["vertex_quantization_bits"] - 1
    found = {}
    for s in segments:
        mesh = ngp.read_segment(out, s, info)
        for lod in range(mesh.manifest.num_lods):
            frags = [f for f in mesh.fragments if f.lod == lod and f.size]
            if not frags:
                continue
            at = np.concatenate([np.array(f.position) * top + f.quantized for f in frags])
            first = np.cumsum([0] + [len(f.quantized) for f in frags])
            tris = np.concatenate([f.triangles + b for f, b in zip(frags, first)])
            points, index = np.unique(at, axis=0, return_inverse=True)
            path = os.path.join(scratch, f"segment_{s}_lod_{lod}.ply")
            pairs, zero = self_intersections(points.astype(np.float64), index.reshape(-1)[tris], path)
            found[(s, lod)] = (pairs, zero, len(tris))
    return found
