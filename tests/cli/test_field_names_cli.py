"""One input, every path, the same bytes (issue 33, item 3): the same volume
written in every format keymesh reads (raw, .nrrd, .nii.gz, a .vti written
by VTK with a named array, a DICOM series, a Zarr array) is contoured in
memory, streamed (--memory-limit small enough for several slabs), under
`mpirun -np 3` and through Python (keymesh.read + keymesh.contour +
keymesh.write), for every normals mode, --curvature and --coarsen, into .vtp
and .ply: each path's file must be byte-identical to the in-memory one.

The scalar field keeps the name the file stores (the .vti's DataArray Name,
here "density"); formats that store none give "scalars" (docs/decisions/
scalar-field-name.md). Before that rule was shared, the streamed and
MPI paths called a .vti's field "scalars" while the in-memory one kept its
name, and no test saw it: the streamed .vti was compared with an in-memory
.nrrd, which is called "scalars" too.

Every normals mode is compared byte for byte, `--normals average` included
(its sums follow one process's order on every path since
generate/layer_blocks.hpp). `keymesh labels` of a named .vti label volume is
compared on its three CLI paths too.
Skipped (77) without numpy, VTK, pydicom or zarr; the MPI leg is skipped
when mpirun is missing or keymesh was built without MPI."""
import gzip
import importlib.util
import os
import shutil
import struct
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import KEYMESH, check, finish, mpirun, report, require_vtk, run, tempdir  # noqa: E402

require_vtk()
for module in ("numpy", "numcodecs", "pydicom", "zarr"):  # pydicom: tests/dicom_series.py writes with it
    if importlib.util.find_spec(module) is None:
        print(f"skipped: no {module} (install python3-numpy, python3-pydicom, python3-zarr)")
        sys.exit(77)
import numcodecs  # noqa: E402
import numpy as np  # noqa: E402
import zarr  # noqa: E402
from dicom_series import write_dicom_series  # noqa: E402

D = tempdir()
NX, NY, NZ = 36, 30, 34                    # uneven, so that a swapped axis shows
SPACING, ORIGIN = (0.5, 0.75, 1.25), (-3.0, 2.0, 7.5)
ISOS = ["--iso", 9.3, "--iso", 5.7]
NAME = "density"                           # the .vti's array name

# A distance field around an off-centre point, rippled so that the two
# isosurfaces have bumps (curvature, folds for --coarsen): float32, (z, y, x).
# Quantized to 1/16 so that the DICOM series (int16, slope 1/16) holds the
# very same values.
z, y, x = np.mgrid[0:NZ, 0:NY, 0:NX].astype(np.float64)
FIELD = np.sqrt((x - 17.3) ** 2 + (y - 14.1) ** 2 + (z - 16.4) ** 2) + 1.5 * np.sin(x / 3.0) * np.cos(y / 4.0)
FIELD = (np.round(FIELD * 16) / 16).astype(np.float32)
PLANE = NX * NY * 4
LIMIT = str(5 * PLANE)                     # 5 planes a slab: 7 or more slabs


def write_raw(path):
    FIELD.astype("<f4").tofile(path)
    return path


def write_nrrd(path):
    head = (f"NRRD0004\ntype: float\ndimension: 3\nsizes: {NX} {NY} {NZ}\nspace dimension: 3\n"
            f"space directions: ({SPACING[0]},0,0) (0,{SPACING[1]},0) (0,0,{SPACING[2]})\n"
            f"space origin: ({ORIGIN[0]},{ORIGIN[1]},{ORIGIN[2]})\nendian: little\nencoding: raw\n\n")
    with open(path, "wb") as f:
        f.write(head.encode() + FIELD.astype("<f4").tobytes())
    return path


def write_nifti_gz(path):
    """NIfTI-1 float32, pixdim = spacing, gzip-compressed (inflated in order
    when streamed)."""
    h = bytearray(348)
    struct.pack_into("<i", h, 0, 348)
    struct.pack_into("<8h", h, 40, 3, NX, NY, NZ, 1, 1, 1, 1)
    struct.pack_into("<hh", h, 70, 16, 32)                 # datatype float32, bitpix
    struct.pack_into("<8f", h, 76, 1, *SPACING, 0, 0, 0, 0)
    struct.pack_into("<fff", h, 108, 352.0, 0.0, 0.0)      # vox_offset; scl_slope 0: no scaling
    h[344:348] = b"n+1\0"
    with open(path, "wb") as f:
        f.write(gzip.compress(bytes(h) + b"\0" * 4 + FIELD.astype("<f4").tobytes()))
    return path


def write_vti(path, volume_zyx, name):
    """VTK's own writer: appended raw, uncompressed (streamable), the point
    array named `name`."""
    import vtk
    from vtk.util import numpy_support as ns
    image = vtk.vtkImageData()
    image.SetDimensions(volume_zyx.shape[2], volume_zyx.shape[1], volume_zyx.shape[0])
    image.SetSpacing(*SPACING)
    image.SetOrigin(*ORIGIN)
    array = ns.numpy_to_vtk(np.ascontiguousarray(volume_zyx).ravel(), deep=True)
    array.SetName(name)
    image.GetPointData().SetScalars(array)
    w = vtk.vtkXMLImageDataWriter()
    w.SetFileName(path)
    w.SetInputData(image)
    w.SetDataModeToAppended()
    w.EncodeAppendedDataOff()
    w.SetCompressorTypeToNone()
    assert w.Write() == 1
    return path


def write_dicom(path):
    write_dicom_series(path, np.round(FIELD * 16).astype(np.int16), pixel_spacing=(SPACING[1], SPACING[0]),
                       step=SPACING[2], origin=ORIGIN, slope=1 / 16, intercept=0)
    return path


def write_zarr(path):
    a = zarr.open(path, mode="w", shape=FIELD.shape, chunks=(5, 8, 9), dtype="<f4",
                  compressor=numcodecs.Zlib(level=1))
    a[:] = FIELD
    return path


RAW_ARGS = ["--dims", NX, NY, NZ, "--type", "float32", "--spacing", *SPACING, "--origin", *ORIGIN]
# (name, path, the CLI's extra arguments, keymesh.read's keyword arguments, the field's expected name)
INPUTS = [
    ("raw", write_raw(os.path.join(D, "f.raw")), RAW_ARGS,
     dict(dims=(NX, NY, NZ), dtype="float32", spacing=SPACING, origin=ORIGIN), "scalars"),
    ("nrrd", write_nrrd(os.path.join(D, "f.nrrd")), [], {}, "scalars"),
    ("nii.gz", write_nifti_gz(os.path.join(D, "f.nii.gz")), [], {}, "scalars"),
    ("vti", write_vti(os.path.join(D, "f.vti"), FIELD, NAME), [], {}, NAME),
    ("dicom", write_dicom(os.path.join(D, "series")), [], {}, "scalars"),
    ("zarr", write_zarr(os.path.join(D, "f.zarr")), [], {}, "scalars"),
]
# (name, CLI options, keymesh.contour's keyword arguments)
OPTIONS = [
    ("none", ["--normals", "none"], dict(normals="none")),
    ("average", ["--normals", "average"], dict(normals="average")),
    ("gradient-curvature", ["--normals", "gradient", "--curvature"], dict(normals="gradient", curvature=True)),
    ("coarsen", ["--normals", "average", "--coarsen"], dict(normals="average", coarsen=True)),
]
EXTS = (".vtp", ".ply")


def field_arrays(path):
    """The header bytes (field names, counts) and the arrays of a .vtp (VTK's
    reader: positions, triangles, every point field by name) or of a binary
    .ply as keymesh writes it (float vertex properties by name, faces of
    uchar count and uint ids), parsed here."""
    data = open(path, "rb").read()
    if path.endswith(".ply"):
        cut = data.index(b"end_header\n") + len(b"end_header\n")
        lines = data[:cut].decode().splitlines()
        props = [line.split()[-1] for line in lines if line.startswith("property float")]
        vertices = int(next(line.split()[-1] for line in lines if line.startswith("element vertex")))
        faces = int(next(line.split()[-1] for line in lines if line.startswith("element face")))
        v = np.frombuffer(data, "<f4", vertices * len(props), cut).reshape(vertices, len(props))
        f = np.frombuffer(data, [("n", "u1"), ("ids", "<u4", 3)], faces, cut + v.nbytes)
        assert cut + v.nbytes + f.nbytes == len(data) and (f["n"] == 3).all(), path
        return data[:cut], {"triangles": f["ids"], **{name: v[:, i] for i, name in enumerate(props)}}
    import vtk
    from vtk.util import numpy_support as ns
    reader = vtk.vtkXMLPolyDataReader()
    reader.SetFileName(path)
    reader.Update()
    poly = reader.GetOutput()
    arrays = {"points": ns.vtk_to_numpy(poly.GetPoints().GetData()),
              "triangles": ns.vtk_to_numpy(poly.GetPolys().GetConnectivityArray())}
    pd = poly.GetPointData()
    for i in range(pd.GetNumberOfArrays()):
        arrays[pd.GetArrayName(i)] = ns.vtk_to_numpy(pd.GetArray(i))
    return data[:data.index(b"<AppendedData")], arrays


def differs(ref, out):
    """Why `out` is not the in-memory file `ref` (None when it is): bytes
    compared; on a difference, the first array that differs is named."""
    a, b = open(ref, "rb").read(), open(out, "rb").read()
    if a == b:
        return None
    (ha, fa), (hb, fb) = field_arrays(ref), field_arrays(out)
    if ha != hb:
        at = next((i for i, (p, q) in enumerate(zip(ha, hb)) if p != q), min(len(ha), len(hb)))
        return f"headers differ at byte {at}: {ha[max(0, at - 40):at + 40]!r} vs {hb[max(0, at - 40):at + 40]!r}"
    if fa.keys() != fb.keys():
        return f"arrays {sorted(fa)} vs {sorted(fb)}"
    for key in fa:
        if not np.array_equal(fa[key], fb[key]):
            return f"{key} differs"
    return "bytes differ"


def compare_all(path_name, cases):
    """cases: (input, option, ext, file) made on one path. Asserts that each
    equals the in-memory file, listing every one that does not."""
    bad = []
    for name, opt, ext, out in cases:
        why = differs(REFS[name, opt, ext], out)
        if why:
            bad.append(f"{name} {opt} {ext}: {why}")
    print(f"        {path_name}: {len(cases) - len(bad)} of {len(cases)} files identical")
    assert not bad, f"{path_name}: {len(bad)} files differ from the in-memory ones:\n  " + "\n  ".join(bad)


def field_names(path):
    """The point fields of a .vtp (its <DataArray Name=...> under PointData)
    or the vertex properties of a .ply."""
    head = open(path, "rb").read(4096)
    if path.endswith(".ply"):
        head = head[:head.index(b"end_header")].decode()
        return [line.split()[-1] for line in head.splitlines() if line.startswith("property")]
    head = head.decode("latin-1")
    point_data = head[head.index("<PointData"):head.index("</PointData>")]
    return [part.split('"')[0] for part in point_data.split('Name="')[1:]]


def mpi_available():
    if not shutil.which("mpirun"):
        return "no mpirun (install openmpi-bin and libopenmpi-dev)"
    p = mpirun(3, "contour", INPUTS[0][1], *RAW_ARGS, "--iso", 9.3, "-o", os.path.join(D, "probe.ply"), "-q",
               expect=None)
    if p.returncode != 0 and "built without MPI" in p.stderr:
        return "keymesh was built without MPI"
    assert p.returncode == 0, f"mpirun -np 3 keymesh contour fails (exit {p.returncode}):\n{p.stderr}"
    return None


def python_module():
    """The module built next to the keymesh binary (<build>/python), or None
    when this build has none."""
    folder = os.path.join(os.path.dirname(os.path.abspath(KEYMESH)), "python")
    if not os.path.isdir(os.path.join(folder, "keymesh")):
        return None
    sys.path.insert(0, folder)
    import keymesh
    return keymesh


MPI_SKIP = mpi_available()
KM = python_module()
REFS = {}  # (input, option, ext) -> the in-memory file


def in_memory():
    """The reference files, and the rule they follow: the .vti's field keeps
    its array's name, every other format's is "scalars". raw, .nrrd, DICOM
    and .vti hold the same samples on the same geometry, so their files are
    the same but for that name (as long as "scalars": no offset moves)."""
    for name, path, extra, _, field in INPUTS:
        for opt, args, _ in OPTIONS:
            for ext in EXTS:
                out = os.path.join(D, f"{name}-{opt}-mem{ext}")
                run("contour", path, *extra, *ISOS, *args, "-o", out, "-q")
                REFS[name, opt, ext] = out
                names = field_names(out)
                assert field in names and not ({"scalars", NAME} - {field}) & set(names), (out, names)
    for opt, _, _ in OPTIONS:
        for ext in EXTS:
            raw = open(REFS["raw", opt, ext], "rb").read()
            for other in ("nrrd", "dicom", "vti"):
                data = open(REFS[other, opt, ext], "rb").read()
                assert data.replace(NAME.encode(), b"scalars") == raw, f"{other} {opt} {ext}: differs from raw"


def streamed():
    cases = []
    for name, path, extra, _, _ in INPUTS:
        for opt, args, _ in OPTIONS:
            for ext in EXTS:
                out = os.path.join(D, f"{name}-{opt}-stream{ext}")
                run("contour", path, *extra, *ISOS, *args, "-o", out, "-q", "--memory-limit", LIMIT,
                    "--report", out + ".json")
                assert report(out + ".json")["stream"]["slabs"] >= 5, (out, report(out + ".json")["stream"])
                cases.append((name, opt, ext, out))
    compare_all(f"--memory-limit {LIMIT}", cases)


def distributed():
    """One mesh format per (input, option), alternating, so that every
    option is written as .vtp and .ply and every input as both (an mpirun
    costs most of a second here)."""
    if MPI_SKIP:
        print(f"        skipped: {MPI_SKIP}")
        return
    cases = []
    for i, (name, path, extra, _, _) in enumerate(INPUTS):
        for j, (opt, args, _) in enumerate(OPTIONS):
            ext = EXTS[(i + j) % 2]
            out = os.path.join(D, f"{name}-{opt}-mpi{ext}")
            mpirun(3, "contour", path, *extra, *ISOS, *args, "-o", out, "-q")
            cases.append((name, opt, ext, out))
    compare_all("mpirun -np 3", cases)


def python():
    if KM is None:
        print("        skipped: this build has no Python module")
        return
    cases = []
    for name, path, _, read_args, field in INPUTS:
        volume = KM.read(path, **read_args)
        assert volume.name == field, (name, volume.name)
        for opt, _, kwargs in OPTIONS:
            mesh = KM.contour(volume, [9.3, 5.7], **kwargs)
            for ext in EXTS:
                out = os.path.join(D, f"{name}-{opt}-py{ext}")
                KM.write(mesh, out)
                cases.append((name, opt, ext, out))
    compare_all("keymesh.read + contour + write", cases)


def labels():
    """`keymesh labels` of a .vti label volume whose array has a name: the
    streamed and MPI files are the in-memory one."""
    labels = np.zeros((NZ, NY, NX), np.uint8)
    labels[FIELD < 12] = 1
    labels[FIELD < 6] = 2
    labels[(FIELD < 9) & (x > 24)] = 3
    path = write_vti(os.path.join(D, "labels.vti"), labels, "tissue")
    for ext in EXTS:
        REFS["labels", "", ext] = os.path.join(D, f"labels-mem{ext}")
        run("labels", path, "-o", REFS["labels", "", ext], "-q")
    cases = []
    for ext in EXTS:
        out = os.path.join(D, f"labels-stream{ext}")
        # About 6 planes: labels holds 3.2 bytes a sample (the sample, its
        # label index) and refuses fewer than three planes.
        run("labels", path, "-o", out, "-q", "--memory-limit", str(6 * NX * NY * 16 // 5), "--report", out + ".json")
        assert report(out + ".json")["stream"]["slabs"] >= 5, report(out + ".json")["stream"]
        cases.append(("labels", "", ext, out))
        if not MPI_SKIP:
            out = os.path.join(D, f"labels-mpi{ext}")
            mpirun(3, "labels", path, "-o", out, "-q")
            cases.append(("labels", "", ext, out))
    compare_all("labels --memory-limit and mpirun -np 3", cases)


def timed(fn):
    def run_timed():
        t = time.monotonic()
        try:
            fn()
        finally:
            print(f"        ({time.monotonic() - t:.1f} s)")
    return run_timed


check("in memory: a .vti's field keeps its array name, other formats' is \"scalars\"", timed(in_memory))
check(f"--memory-limit {LIMIT} (several slabs): every format, option and mesh format byte-identical", timed(streamed))
check("mpirun -np 3: every format, option and mesh format byte-identical", timed(distributed))
check("Python keymesh.read + contour + write: byte-identical to the CLI", timed(python))
check("keymesh labels of a named .vti: in memory, streamed and MPI byte-identical", timed(labels))
finish()
