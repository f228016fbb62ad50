"""Hardening rules of issue 11, end to end through the `keymesh` command.

- hostile and malformed files of every format: exit 1, one line on stderr
  naming the file, no signal, no output file, within seconds and (outside
  sanitizer builds) within an address-space limit far below what the headers
  declare;
- sizes: zero, negative and overflowing dims refused by name;
- NaN/Inf samples never give a non-finite point, normal or field value;
  a non-finite isovalue is a usage error (2); one outside the data range
  gives an empty mesh, a warning and exit 0;
- meshes with out-of-range or negative indices refused; degenerate,
  repeated and non-manifold cells handled without a crash;
- outputs: a full device, an unwritable directory or a file-size limit
  leave no partial file and the old file intact, exit 1 with the reason.
"""
import base64
import gzip
import math
import json
import os
import resource
import signal
import struct
import subprocess
import sys
import zlib

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import KEYMESH, SOURCE_DIR, check, finish, report, run, tempdir  # noqa: E402

D = tempdir()
# Sanitizer builds reserve terabytes of shadow memory: no address-space limit there.
SANITIZED = any(k in os.environ for k in ("ASAN_OPTIONS", "TSAN_OPTIONS", "UBSAN_OPTIONS"))
AS_LIMIT = 1 << 30  # 1 GiB: every hostile file below declares far more


def limited(fsize=None, address_space=True):
    def setup():
        if address_space and not SANITIZED:
            resource.setrlimit(resource.RLIMIT_AS, (AS_LIMIT, AS_LIMIT))
        if fsize is not None:
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails with EFBIG instead
            resource.setrlimit(resource.RLIMIT_FSIZE, (fsize, fsize))
    return setup


def km(*args, preexec=None, timeout=60):
    """Runs keymesh; returns (returncode, stdout, stderr). Never a signal."""
    p = subprocess.run([KEYMESH, *map(str, args)], capture_output=True, text=True, stdin=subprocess.DEVNULL,
                       timeout=timeout, preexec_fn=preexec or limited())
    assert p.returncode >= 0, f"keymesh {args}: killed by signal {-p.returncode}\n{p.stderr}"
    return p.returncode, p.stdout, p.stderr


def write(name, data):
    path = os.path.join(D, name)
    with open(path, "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())
    return path


def expect_refused(args, named, fragment=""):
    """Exit 1, one line on stderr that names `named` (and holds fragment)."""
    rc, _, err = km(*args)
    lines = [line for line in err.splitlines() if line.strip()]
    assert rc == 1, f"keymesh {args}: exit {rc}, expected 1\n{err}"
    assert len(lines) == 1, f"keymesh {args}: expected one line on stderr, got:\n{err}"
    assert named in lines[0] and fragment in lines[0], f"keymesh {args}: '{lines[0]}' lacks '{named}' / '{fragment}'"
    return lines[0]


def outputs_left(out):
    """Files next to `out` that a failed run may have left (the output or a temporary)."""
    base = os.path.basename(out)
    return [f for f in os.listdir(os.path.dirname(out)) if f == base or f.startswith(base + ".tmp")]


# ---- hostile files of every format ------------------------------------------------

def nifti_header(dims, datatype=16, vox_offset=352.0, sizeof_hdr=348, magic=b"n+1\0"):
    h = bytearray(348)
    struct.pack_into("<i", h, 0, sizeof_hdr)
    struct.pack_into("<8h", h, 40, 3, *dims, 1, 1, 1, 1)
    struct.pack_into("<h", h, 70, datatype)
    struct.pack_into("<f", h, 108, vox_offset)
    h[344:348] = magic
    return bytes(h) + b"\0" * 4


def vti(extent, array, appended=b"", root=""):
    head = ('<?xml version="1.0"?>\n<VTKFile type="ImageData" version="1.0"%s>\n<ImageData WholeExtent="%s">\n'
            '<Piece Extent="%s"><PointData>%s</PointData></Piece></ImageData>\n' % (root, extent, extent, array))
    if appended:
        return head.encode() + b'<AppendedData encoding="raw">_' + appended + b"</AppendedData></VTKFile>"
    return (head + "</VTKFile>").encode()


def den(dims, length, body):
    h = bytearray(62)
    struct.pack_into("<h", h, 0, 1)
    struct.pack_into("<3h", h, 50, *dims)
    struct.pack_into("<i", h, 58, length)
    return bytes(h) + body


BIG = 2 ** 21  # three of these overflow 64 bits; two of them want 2^42 samples
VOLUMES = {
    "magic.nrrd": b"NRRX0004\ntype: float\n\n",
    "huge.nrrd": b"NRRD0004\ntype: float\ndimension: 3\nsizes: %d %d %d\nencoding: raw\n\n\0\0\0\0" % (BIG, BIG, BIG),
    "big.nrrd": b"NRRD0004\ntype: double\ndimension: 3\nsizes: %d %d 1\nencoding: raw\n\n" % (BIG, BIG) + bytes(64),
    "zero.nrrd": b"NRRD0004\ntype: float\ndimension: 3\nsizes: 4 0 2\nencoding: raw\n\n",
    "negative.nrrd": b"NRRD0004\ntype: float\ndimension: 3\nsizes: 4 -3 2\nencoding: raw\n\n",
    "short.nrrd": b"NRRD0004\ntype: float\ndimension: 3\nsizes: 4 3 2\nencoding: raw\n\n" + bytes(95),
    "gzlie.nrrd": b"NRRD0004\ntype: float\ndimension: 3\nsizes: 1024 1024 64\nencoding: gzip\n\n"
                  + gzip.compress(os.urandom(300000)),
    "gzjunk.nrrd": b"NRRD0004\ntype: float\ndimension: 3\nsizes: 4 3 2\nencoding: gzip\n\n" + b"\x1f\x8b" + bytes(200),
    "huge.nii": nifti_header((32767, 32767, 32767), 64) + bytes(64),
    "zero.nii": nifti_header((4, 0, 2)) + bytes(96),
    "negative.nii": nifti_header((4, -3, 2)) + bytes(96),
    "short.nii": nifti_header((4, 3, 2)) + bytes(95),
    "magic.nii": nifti_header((4, 3, 2), magic=b"xyz\0") + bytes(96),
    "huge.nii.gz": gzip.compress(nifti_header((32767, 32767, 32767), 64) + bytes(64)),
    "lie.nii.gz": gzip.compress(nifti_header((1024, 1024, 64)) + os.urandom(300000)),
    "junk.nii.gz": b"\x1f\x8b\x08\x00" + os.urandom(500),
    "short.den": den((4, 3, 2), 24, bytes(23)),
    "huge.den": den((32767, 32767, 2), 32767 * 32767 * 2, bytes(24)),
    "version.den": b"\x07" + bytes(61 + 24),
    "huge.vti": vti("0 %d 0 %d 0 %d" % (BIG - 1, BIG - 1, BIG - 1),
                    '<DataArray type="Float32" Name="f" format="appended" offset="0"/>', struct.pack("<I", 4) + bytes(4)),
    "big.vti": vti("0 %d 0 %d 0 0" % (BIG - 1, BIG - 1),
                   '<DataArray type="Float32" Name="f" format="appended" offset="0"/>', struct.pack("<I", 4) + bytes(4)),
    "bigascii.vti": vti("0 %d 0 %d 0 0" % (BIG - 1, BIG - 1), '<DataArray type="Float32" Name="f">1 2 3</DataArray>'),
    "negative.vti": vti("0 3 0 -2 0 1", '<DataArray type="Float32" Name="f">1 2 3</DataArray>'),
    "short.vti": vti("0 3 0 2 0 1", '<DataArray type="Float32" Name="f" format="appended" offset="0"/>',
                     struct.pack("<I", 96) + bytes(10)),
    "zliblie.vti": vti("0 1023 0 1023 0 255", '<DataArray type="Float32" Name="f" format="appended" offset="0"/>',
                       struct.pack("<4I", 1, 1 << 30, 0, 16) + bytes(16), ' compressor="vtkZLibDataCompressor"'),
    "zlibpast.vti": vti("0 3 0 2 0 1", '<DataArray type="Float32" Name="f" format="appended" offset="0"/>',
                        struct.pack("<4I", 1, 96, 96, len(zlib.compress(bytes(960)))) + zlib.compress(bytes(960)),
                        ' compressor="vtkZLibDataCompressor"'),
    "base64.vti": vti("0 3 0 2 0 1", '<DataArray type="Float32" Name="f" format="binary">@@@@</DataArray>'),
    "notxml.vti": b"\0\1\2 this is not XML",
}

TET = "0 0 0 1 0 0 0 1 0 0 0 1"
MESHES = {
    "count.ply": b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
                 b"property float y\nproperty float z\nend_header\n" + bytes(12),
    "index.ply": "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                 "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 99\n",
    "negindex.ply": "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                    "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n",
    "listlie.ply": b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                   b"property float z\nelement face 1\nproperty list uint uint vertex_indices\nend_header\n"
                   + bytes(36) + struct.pack("<I", 4000000000) + bytes(12),
    "truncated.ply": b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
                     b"property double z\nend_header\n" + bytes(50),
    "nomagic.ply": b"plx\n",
    "index.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99\n",
    "zero.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
    "negindex.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n",
    "hugeindex.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999999\n",
    "count.stl": b"\0" * 80 + struct.pack("<I", 4000000000) + bytes(50),
    "truncated.stl": "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0\n",
    "count.vtp": '<VTKFile type="PolyData"><PolyData><Piece NumberOfPoints="281474976710656" NumberOfPolys="1">'
                 '<Points><DataArray type="Float32" NumberOfComponents="3">0 0 0</DataArray></Points>'
                 '</Piece></PolyData></VTKFile>',
    "index.vtp": '<VTKFile type="PolyData"><PolyData><Piece NumberOfPoints="4" NumberOfPolys="1"><Points>'
                 '<DataArray type="Float32" NumberOfComponents="3">%s</DataArray></Points><Polys>'
                 '<DataArray type="Int32" Name="connectivity">0 1 7</DataArray>'
                 '<DataArray type="Int32" Name="offsets">3</DataArray></Polys></Piece></PolyData></VTKFile>' % TET,
    "negindex.vtp": '<VTKFile type="PolyData"><PolyData><Piece NumberOfPoints="4" NumberOfPolys="1"><Points>'
                    '<DataArray type="Float32" NumberOfComponents="3">%s</DataArray></Points><Polys>'
                    '<DataArray type="Int32" Name="connectivity">0 -1 2</DataArray>'
                    '<DataArray type="Int32" Name="offsets">3</DataArray></Polys></Piece></PolyData></VTKFile>' % TET,
    "offsets.vtp": '<VTKFile type="PolyData"><PolyData><Piece NumberOfPoints="4" NumberOfPolys="2"><Points>'
                   '<DataArray type="Float32" NumberOfComponents="3">%s</DataArray></Points><Polys>'
                   '<DataArray type="Int32" Name="connectivity">0 1 2</DataArray>'
                   '<DataArray type="Int32" Name="offsets">3 1</DataArray></Polys></Piece></PolyData></VTKFile>' % TET,
    "appended.vtp": b'<VTKFile type="PolyData" header_type="UInt64"><PolyData><Piece NumberOfPoints="4">'
                    b'<Points><DataArray type="Float32" NumberOfComponents="3" format="appended" offset="0"/></Points>'
                    b'</Piece></PolyData><AppendedData encoding="raw">_' + struct.pack("<Q", 1 << 62) + bytes(8),
}

GRIDS = {
    "count.vtu": '<VTKFile type="UnstructuredGrid"><UnstructuredGrid><Piece NumberOfPoints="4" '
                 'NumberOfCells="281474976710656"><Points><DataArray type="Float32" NumberOfComponents="3">%s'
                 '</DataArray></Points></Piece></UnstructuredGrid></VTKFile>' % TET,
    "index.vtu": '<VTKFile type="UnstructuredGrid"><UnstructuredGrid><Piece NumberOfPoints="4" NumberOfCells="1">'
                 '<PointData><DataArray type="Float32" Name="s">0 1 2 3</DataArray></PointData>'
                 '<Points><DataArray type="Float32" NumberOfComponents="3">%s</DataArray></Points><Cells>'
                 '<DataArray type="Int64" Name="connectivity">0 1 2 9</DataArray>'
                 '<DataArray type="Int64" Name="offsets">4</DataArray>'
                 '<DataArray type="UInt8" Name="types">10</DataArray></Cells></Piece></UnstructuredGrid></VTKFile>' % TET,
    "count.vtk": "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 1000000000000 float\n0 0 0\n",
    "negative.vtk": "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS -4 float\n0 0 0\n",
    "index.vtk": "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n%s\n"
                 "CELLS 1 5\n4 0 1 2 -7\nCELL_TYPES 1\n10\nPOINT_DATA 4\nSCALARS s float\nLOOKUP_TABLE default\n"
                 "0 1 2 3\n" % TET,
    "binary.vtk": b"# vtk DataFile Version 4.2\nx\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n" + bytes(20),
}


def hostile_volumes():
    for name, data in VOLUMES.items():
        path = write(name, data)
        out = os.path.join(D, "out_" + name + ".vtp")
        expect_refused(["contour", path, "-o", out, "--iso", "0.5", "-q"], path)
        expect_refused(["info", path], path)
        assert outputs_left(out) == [], outputs_left(out)


def hostile_meshes():
    for name, data in MESHES.items():
        path = write(name, data)
        expect_refused(["check", path], path)
        expect_refused(["info", path], path)
        for cmd in ("dual", "subdivide"):
            out = os.path.join(D, f"out_{cmd}_{name}.vtp")
            expect_refused([cmd, path, "-o", out, "-q"], path)
            assert outputs_left(out) == [], outputs_left(out)
        expect_refused(["quality", path], path)


def hostile_grids():
    for name, data in GRIDS.items():
        path = write(name, data)
        expect_refused(["info", path], path)
        out = os.path.join(D, "out_" + name + ".vtp")
        expect_refused(["contour", path, "-o", out, "--iso", "0.5", "-q"], path)
        assert outputs_left(out) == [], outputs_left(out)


def raw_dims_refused_by_name():
    path = write("v.raw", bytes(96))
    for dims, fragment in (((4, 0, 2), "--dims y"), ((-4, 3, 2), "--dims x"), ((BIG, BIG, BIG), "overflow"),
                           ((BIG, BIG, 2), "file holds")):
        expect_refused(["contour", path, "--dims", *dims, "--type", "float32", "-o", os.path.join(D, "r.vtp"),
                        "--iso", 1], path, fragment)
    expect_refused(["contour", path, "--dims", 4, 3, 2, "--type", "float64", "-o", os.path.join(D, "r.vtp"),
                    "--iso", 1], path, "expected 192")
    rc, _, _ = km("contour", path, "--dims", 4, 3, 2, "--type", "float32", "--header-bytes", -1,
                  "-o", os.path.join(D, "r.vtp"), "--iso", 1)
    assert rc == 2, rc


# ---- NaN, Inf and isovalues ----------------------------------------------------------

def ply_vertices(path):
    """The vertex table of a binary little-endian PLY keymesh wrote, as rows of floats."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    head = data[:end].decode().splitlines()
    n = int(next(line.split()[2] for line in head if line.startswith("element vertex")))
    props = sum(1 for line in head if line.startswith("property float"))
    values = struct.unpack_from("<%df" % (n * props), data, end)
    return [values[i * props:(i + 1) * props] for i in range(n)], head


def nonfinite_samples_give_finite_meshes():
    # A ball of distance values with NaN, +Inf and -Inf samples sprinkled in.
    n = 12
    values = []
    for z in range(n):
        for y in range(n):
            for x in range(n):
                d = math.sqrt((x - 5.5) ** 2 + (y - 5.5) ** 2 + (z - 5.5) ** 2)
                k = (x * 7 + y * 3 + z) % 11
                values.append(math.nan if k == 0 else math.inf if k == 1 else -math.inf if k == 2 else d)
    path = write("nonfinite.raw", struct.pack("<%df" % len(values), *values))
    for extra in ([], ["--normals", "gradient"], ["--normals", "average"], ["--curvature"], ["--coarsen"],
                  ["--weld", "vertexweld"], ["--iso", 2.25]):
        out = os.path.join(D, "nf.ply")
        rc, _, err = km("contour", path, "--dims", n, n, n, "--type", "float32", "-o", out, "--iso", 3.5, *extra,
                        "-q", "--report", out + ".json")
        assert rc == 0, err
        rows, head = ply_vertices(out)
        assert len(rows) > 0 and report(out + ".json")["points"] == len(rows)
        bad = [r for r in rows if not all(math.isfinite(v) for v in r)]
        assert not bad, f"{extra}: {len(bad)} of {len(rows)} points with a non-finite value, e.g. {bad[0]} ({head})"


def isovalues():
    vti_path = os.path.join(D, "s16.vti")
    run("generate", "sphere", "--size", 16, "-o", vti_path, "-q")
    out = os.path.join(D, "iso.vtp")
    for bad in ("nan", "inf", "-inf", "1e999"):
        rc, _, err = km("contour", vti_path, "-o", out, "--iso", bad, "-q")
        assert rc == 2 and "finite" in err, (bad, rc, err)
        assert outputs_left(out) == []
    # The sphere's samples run from 0 to 8 * sqrt(3): 100 and -5 lie outside.
    for outside in (100, -5):
        rc, _, err = km("contour", vti_path, "-o", out, "--iso", outside, "--report", out + ".json")
        assert rc == 0, err
        assert "warning" in err and "outside the data range" in err, err
        r = report(out + ".json")
        assert r["points"] == 0 and r["cells"] == 0, r
        run("check", out)  # the empty mesh is a valid file
    # The same on tetrahedra (marching tetrahedra).
    tets = os.path.join(D, "t16.vtu")
    run("tetrahedralize", vti_path, "-o", tets, "--scheme", 5, "-q")
    for bad in ("nan", "-inf"):
        rc, _, err = km("contour", tets, "-o", out, "--iso", bad, "-q")
        assert rc == 2 and "finite" in err, (bad, rc, err)
    rc, _, err = km("contour", tets, "-o", out, "--iso", 100, "--report", out + ".json")
    assert rc == 0 and "outside the data range" in err, err
    assert report(out + ".json")["points"] == 0


# ---- degenerate meshes ---------------------------------------------------------------

def degenerate_meshes_never_crash():
    # Repeated points in a cell, a cell listed twice, three triangles on one
    # edge, an unused point, a zero-area cell.
    obj = ("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 0 -1 0\nv 5 5 5\nv 2 0 0\n"
           "f 1 2 3\nf 1 2 3\nf 1 2 4\nf 1 2 5\nf 1 1 2\nf 1 2 7\n")
    path = write("degenerate.obj", obj)
    rc, out, err = km("check", path, "--report", path + ".json")
    assert rc == 0, err
    r = report(path + ".json")
    assert r["nonmanifold_edges"] >= 1 and not r["closed_manifold"], r
    for cmd in (["quality", path], ["dual", path, "-o", os.path.join(D, "dd.vtp")],
                ["subdivide", path, "-o", os.path.join(D, "ds.vtp")],
                ["subdivide", path, "-o", os.path.join(D, "db.vtp"), "--scheme", "bezier"]):
        rc, _, err = km(*cmd)
        assert rc in (0, 1), (cmd, rc, err)
        if rc == 1:  # a refusal is one line (e.g. bezier without normals)
            assert len(err.strip().splitlines()) == 1 and err.startswith("keymesh"), err


# ---- outputs -------------------------------------------------------------------------

def outputs_fail_cleanly():
    vti_path = os.path.join(D, "s24.vti")
    run("generate", "sphere", "--size", 24, "-o", vti_path, "-q")
    # A full device through a symlink: written in place, fails with the reason,
    # the device stays a device.
    if os.path.exists("/dev/full"):
        for ext in (".vtp", ".ply", ".obj", ".stl"):
            link = os.path.join(D, "full" + ext)
            if not os.path.islink(link):
                os.symlink("/dev/full", link)
            line = expect_refused(["contour", vti_path, "-o", link, "--iso", 10.5, "-q"], link)
            assert "No space left on device" in line, line
            assert os.path.islink(link) and os.path.realpath(link) == "/dev/full"
        link = os.path.join(D, "full.json")
        if not os.path.islink(link):
            os.symlink("/dev/full", link)
        expect_refused(["contour", vti_path, "-o", os.path.join(D, "ok.vtp"), "--iso", 10.5, "-q", "--report", link],
                       link, "No space left")
        for ext in (".vti", ".nrrd", ".raw"):
            link = os.path.join(D, "fullvol" + ext)
            os.symlink("/dev/full", link)
            expect_refused(["generate", "sphere", "--size", 16, "-o", link, "-q"], link, "No space left")
        import stat
        assert stat.S_ISCHR(os.stat("/dev/full").st_mode)
    # An unwritable place: a directory that does not exist, a path under a file.
    for bad in (os.path.join(D, "no", "such", "dir", "o.vtp"), os.path.join(vti_path, "o.vtp")):
        expect_refused(["contour", vti_path, "-o", bad, "--iso", 10.5, "-q"], bad, "cannot write")
    # A disk that fills part-way (a file-size limit): exit 1 with the reason,
    # the old file untouched, no temporary left behind.
    for ext in (".vtp", ".ply", ".obj", ".stl"):
        out = write("old" + ext, "the old contents")
        rc, _, err = km("contour", vti_path, "-o", out, "--iso", 10.5, "-q", preexec=limited(fsize=4096))
        assert rc == 1 and out in err and "File too large" in err, (rc, err)
        with open(out) as f:
            assert f.read() == "the old contents"
        assert outputs_left(out) == [os.path.basename(out)], outputs_left(out)
    out = write("old.vti", "the old contents")
    rc, _, err = km("generate", "sphere", "--size", 32, "-o", out, "-q", preexec=limited(fsize=4096))
    assert rc == 1 and "File too large" in err, (rc, err)
    with open(out) as f:
        assert f.read() == "the old contents"
    assert outputs_left(out) == ["old.vti"], outputs_left(out)


check("hostile volumes: exit 1, one line naming the file, no output", hostile_volumes)
check("hostile surface meshes: exit 1 from check, info, dual, subdivide, quality", hostile_meshes)
check("hostile unstructured grids: exit 1 from info and contour", hostile_grids)
check("raw --dims zero, negative, overflowing, past the file: refused by name", raw_dims_refused_by_name)
check("NaN and Inf samples never give a non-finite point, normal or field", nonfinite_samples_give_finite_meshes)
check("non-finite isovalue: exit 2; outside the range: empty mesh, warning, exit 0", isovalues)
check("degenerate, repeated and non-manifold cells: handled, never a crash", degenerate_meshes_never_crash)
check("full device, unwritable directory, file-size limit: exit 1, old file intact", outputs_fail_cleanly)

# ---- issue 19: the classes of round two ------------------------------------------------

def km2(*args, timeout=20):
    """The issue's checker: 2 GiB of address space, 20 s; (rc, stderr lines). Never a signal."""
    def setup():
        if not SANITIZED:
            resource.setrlimit(resource.RLIMIT_AS, (2 << 30, 2 << 30))
    p = subprocess.run([KEYMESH, *map(str, args)], capture_output=True, text=True, stdin=subprocess.DEVNULL,
                       timeout=timeout, preexec_fn=setup)
    assert p.returncode >= 0, f"keymesh {args}: killed by signal {-p.returncode}\n{p.stderr}"
    return p.returncode, [line for line in p.stderr.splitlines() if line.strip()]


def refused(args, named, code=1, fragment=""):
    rc, lines = km2(*args)
    assert rc == code, f"keymesh {args}: exit {rc}, expected {code}\n{lines}"
    assert len(lines) == 1, f"keymesh {args}: expected one line on stderr, got {lines}"
    assert named in lines[0] and fragment in lines[0], f"keymesh {args}: '{lines[0]}' lacks '{named}' / '{fragment}'"
    return lines[0]


def small_volume():
    path = os.path.join(D, "s12.vti")
    if not os.path.exists(path):
        run("generate", "sphere", "--size", 12, "-o", path, "-q")
    return path


def small_tets():
    path = os.path.join(D, "t12.vtu")
    if not os.path.exists(path):
        run("tetrahedralize", small_volume(), "-o", path, "-q")
    return path


def deep_xml_and_thread_counts():
    # Nesting deeper than any stack: refused by name for every XML format.
    for ext, kind in ((".vtp", "PolyData"), (".vti", "ImageData"), (".vtu", "UnstructuredGrid"),
                      (".pvtp", "PPolyData")):
        path = write("deep" + ext, '<VTKFile type="%s">' % kind + "<a>" * 300000)
        refused(["info", path], path, fragment="nested")
    wide = write("wide.vtp", '<VTKFile type="PolyData">' + "<a/>" * 200000 + "</VTKFile>")
    refused(["info", wide], wide)
    # --threads past the stated maximum (1024) or negative: usage error.
    vol = small_volume()
    for n in (100000, 1025, -1):
        rc, lines = km2("contour", vol, "-o", os.path.join(D, "t.ply"), "--iso", 2.5, "--threads", n, "-q")
        assert rc == 2 and lines, (n, rc, lines)
    assert not os.path.exists(os.path.join(D, "t.ply"))
    # The stated maximum is at least 64, and 64 threads start within 2 GiB of address space.
    rc, lines = km2("contour", vol, "-o", os.path.join(D, "t.ply"), "--iso", 2.5, "--threads", 64, "-q")
    assert rc == 0, (rc, lines)
    # A dataset that cannot fit is refused by size, naming the output, before allocation.
    big = os.path.join(D, "generated_big.nrrd")
    refused(["generate", "sphere", "--size", 4000, "-o", big, "-q"], big, fragment="--max-memory")
    assert not os.path.exists(big)


def non_regular_inputs_refused():
    fifo = os.path.join(D, "f.ply")
    if not os.path.exists(fifo):
        os.mkfifo(fifo)
    os.makedirs(os.path.join(D, "d.ply"), exist_ok=True)
    # A FIFO hangs a reader that opens it blocking; a directory or /dev/zero has
    # no size. Each must be refused by name, fast, for every kind of reader.
    for cmd in (["check"], ["info"], ["quality"]):
        refused(cmd + [fifo], fifo, fragment="not a regular file")
        refused(cmd + [os.path.join(D, "d.ply")], os.path.join(D, "d.ply"), fragment="not a regular file")
    for ext in (".ply", ".obj", ".stl", ".vtp", ".vtu", ".vtk", ".vti", ".nrrd", ".nii", ".pvtp"):
        link = os.path.join(D, "devzero" + ext)
        if not os.path.islink(link):
            os.symlink("/dev/zero", link)
        refused(["info", link], link, fragment="not a regular file")
        out = os.path.join(D, "zero_out" + (".vtu" if ext in (".vtu", ".vtk") else ".vtp"))
        cmd = "convert" if ext not in (".vti", ".nrrd", ".nii") else "contour"
        extra = ["--iso", 1] if cmd == "contour" else []
        refused([cmd, link, "-o", out, "-q", *extra], link)
        assert not os.path.exists(out)
    # A .pvtp whose piece is /dev/zero, or a FIFO, or a directory.
    for target in ("/dev/zero", fifo, os.path.join(D, "d.ply")):
        piece = os.path.join(D, "piece_%d.vtp" % abs(hash(target)))
        if not os.path.islink(piece):
            os.symlink(target, piece)
        index = write("idx.pvtp", '<VTKFile type="PPolyData"><PPolyData><PPoints><PDataArray type="Float32" '
                                  'NumberOfComponents="3"/></PPoints><Piece Source="%s"/></PPolyData></VTKFile>'
                      % os.path.basename(piece))
        refused(["check", index], piece, fragment="not a regular file")


def failed_runs_leave_every_file_untouched():
    vol = small_volume()
    tets = small_tets()
    surface = os.path.join(D, "surf.ply")
    run("contour", vol, "-o", surface, "--iso", 2.5, "-q")
    bad_report = "/nonexistent/dir/r.json"
    cases = [
        (["contour", vol, "--iso", 2.5], ".ply"),
        (["contour", tets, "--iso", 2.5], ".ply"),
        (["dual", surface], ".vtp"),
        (["subdivide", surface], ".obj"),
        (["convert", surface], ".stl"),
        (["tetrahedralize", vol], ".vtu"),
        (["pipeline", vol, "--iso", 2.5], ".vtp"),
    ]
    for args, ext in cases:
        keep = write("keep" + ext, "OLD")
        # Without -q too: one line, refused before any work (no "N points -> keep" first).
        rc, lines = km2(*args, "-o", keep, "--report", bad_report)
        assert rc == 1 and len(lines) == 1 and bad_report in lines[0], (args, rc, lines)
        with open(keep) as f:
            assert f.read() == "OLD", f"{args}: the old {keep} was replaced"
        assert outputs_left(keep) == [os.path.basename(keep)], outputs_left(keep)
        # A new output is not left behind either.
        fresh = os.path.join(D, "fresh" + ext)
        rc, _ = km2(*args, "-o", fresh, "--report", bad_report, "-q")
        assert rc == 1 and outputs_left(fresh) == [], (args, outputs_left(fresh))
    # The success path still writes both.
    out, rep = os.path.join(D, "both.ply"), os.path.join(D, "both.json")
    run("contour", vol, "-o", out, "--iso", 2.5, "--report", rep, "-q")
    assert report(rep)["points"] > 0 and os.path.getsize(out) > 0


def shared_paths_refused():
    vol = small_volume()
    with open(vol, "rb") as f:
        original = f.read()
    out = write("same.ply", "OLD")
    # --report equal to -o, spelled differently, or through a link: exit 2, nothing written.
    alias = os.path.join(D, ".", "same.ply")
    hard = os.path.join(D, "hard.ply")
    if not os.path.exists(hard):
        os.link(out, hard)
    for report_path in (out, alias, hard):
        line = refused(["contour", vol, "-o", out, "--iso", 2.5, "--report", report_path, "-q"], "same file", code=2)
        with open(out) as f:
            assert f.read() == "OLD"
    # A not-yet-existing output named twice through a different spelling.
    new = os.path.join(D, "new.ply")
    refused(["contour", vol, "-o", new, "--iso", 2.5, "--report", os.path.join(D, "..", os.path.basename(D), "new.ply"),
             "-q"], "same file", code=2)
    assert not os.path.exists(new)
    # --report or -o equal to the input: the input is never overwritten.
    link = os.path.join(D, "vol_link.vti")
    if not os.path.islink(link):
        os.symlink(vol, link)
    for args in (["contour", vol, "-o", os.path.join(D, "o.ply"), "--iso", 2.5, "--report", vol],
                 ["contour", vol, "-o", os.path.join(D, "o.ply"), "--iso", 2.5, "--report", link],
                 ["convert", vol, "-o", link], ["info", vol, "--report", vol]):
        refused(args + ["-q"] if args[0] != "info" else args, "same file", code=2)
        with open(vol, "rb") as f:
            assert f.read() == original, args
    # /dev/null twice is fine (a device is written in place).
    null = os.path.join(D, "null.ply")
    if not os.path.islink(null):
        os.symlink("/dev/null", null)
    rc, _ = km2("contour", vol, "-o", null, "--iso", 2.5, "--report", "/dev/null", "-q")
    assert rc == 0, rc


def nonfinite_geometry_refused():
    raw = write("g.raw", struct.pack("<512f", *[float(i % 7) for i in range(512)]))
    base = ["contour", raw, "--dims", 8, 8, 8, "--type", "float32", "--iso", 2.5, "-q"]
    for opt in (["--origin", "1e39", 0, 0], ["--spacing", "1e38", 1, 1], ["--origin", "3e38", 0, 0, "--spacing", "1e38", 1, 1]):
        out = os.path.join(D, "inf.ply")
        refused(base + opt + ["-o", out], raw, fragment="float32")
        assert not os.path.exists(out)
    # The same through every header that carries geometry.
    samples = struct.pack("<64f", *[float(i % 5) for i in range(64)])
    nrrd_o = write("o.nrrd", b"NRRD0004\ntype: float\ndimension: 3\nsizes: 4 4 4\nencoding: raw\nendian: little\n"
                              b"space dimension: 3\nspace origin: (1e39,0,0)\n\n" + samples)
    nrrd_s = write("s.nrrd", b"NRRD0004\ntype: float\ndimension: 3\nsizes: 4 4 4\nencoding: raw\nendian: little\n"
                              b"spacings: 2e38 1 1\n\n" + samples)
    vti_o = write("o.vti", vti("0 3 0 3 0 3", '<DataArray type="Float32" Name="f" format="appended" offset="0"/>',
                               struct.pack("<I", 256) + samples).replace(b'WholeExtent="0 3 0 3 0 3"',
                                                                          b'WholeExtent="0 3 0 3 0 3" Origin="1e39 0 0"'))
    vti_s = write("s.vti", vti("0 3 0 3 0 3", '<DataArray type="Float32" Name="f" format="appended" offset="0"/>',
                               struct.pack("<I", 256) + samples).replace(b'WholeExtent="0 3 0 3 0 3"',
                                                                          b'WholeExtent="0 3 0 3 0 3" Spacing="2e38 1 1"'))
    for path in (nrrd_o, nrrd_s, vti_o, vti_s):
        for cmd, out, extra in (("contour", "c.ply", ["--iso", 2.5]), ("tetrahedralize", "t.vtu", []),
                                ("convert", "v.nrrd", [])):
            out = os.path.join(D, out)
            refused([cmd, path, "-o", out, "-q", *extra], path)
            assert not os.path.exists(out), (cmd, path)
    # Meshes and grids with nan, inf, 1e400 or 1e39 coordinates: refused by
    # name by every command, so nothing non-finite is written and check never
    # calls such a mesh a manifold.
    for bad in ("nan", "inf", "-inf", "1e400", "1e39"):
        tet = "%s 0 0 1 0 0 0 1 0 0 0 1" % bad
        files = {
            "bad.ply": "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                       "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
                       + "\n".join(" ".join(tet.split()[3 * i:3 * i + 3]) for i in range(4))
                       + "\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
            "bad.obj": "".join("v %s\n" % " ".join(tet.split()[3 * i:3 * i + 3]) for i in range(4))
                       + "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
            "bad.vtp": '<VTKFile type="PolyData"><PolyData><Piece NumberOfPoints="4" NumberOfPolys="4"><Points>'
                       '<DataArray type="Float32" NumberOfComponents="3">%s</DataArray></Points><Polys>'
                       '<DataArray type="Int32" Name="connectivity">0 2 1 0 1 3 0 3 2 1 2 3</DataArray>'
                       '<DataArray type="Int32" Name="offsets">3 6 9 12</DataArray></Polys></Piece></PolyData>'
                       '</VTKFile>' % tet,
            "bad.stl": "solid s\n" + "".join("facet normal 0 0 0\nouter loop\n" + "".join(
                "vertex %s\n" % " ".join(tet.split()[3 * v:3 * v + 3]) for v in f) + "endloop\nendfacet\n"
                for f in ((0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3))) + "endsolid s\n",
            "bad.vtu": '<VTKFile type="UnstructuredGrid"><UnstructuredGrid><Piece NumberOfPoints="4" NumberOfCells="1">'
                       '<PointData><DataArray type="Float32" Name="s">0 1 2 3</DataArray></PointData>'
                       '<Points><DataArray type="Float32" NumberOfComponents="3">%s</DataArray></Points><Cells>'
                       '<DataArray type="Int64" Name="connectivity">0 1 2 3</DataArray>'
                       '<DataArray type="Int64" Name="offsets">4</DataArray>'
                       '<DataArray type="UInt8" Name="types">10</DataArray></Cells></Piece></UnstructuredGrid>'
                       '</VTKFile>' % tet,
            "bad.vtk": "# vtk DataFile Version 3.0\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 float\n%s\n"
                       "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\nPOINT_DATA 4\nSCALARS s float\nLOOKUP_TABLE default\n"
                       "0 1 2 3\n" % tet,
        }
        for name, data in files.items():
            path = write(bad.replace("-", "m") + "_" + name, data)
            grid = name.endswith((".vtu", ".vtk"))
            commands = [["info", path]]
            out_ext = ".vtu" if grid else ".ply"
            commands += [["convert", path, "-o", os.path.join(D, "nonfin" + out_ext)],
                         ["subdivide", path, "-o", os.path.join(D, "nonfin" + out_ext)]]
            if grid:
                commands += [["contour", path, "-o", os.path.join(D, "nonfin.ply"), "--iso", 1.5],
                             ["tetrahedralize", path, "-o", os.path.join(D, "nonfin.vtu")]]
            else:
                commands += [["check", path], ["quality", path], ["dual", path, "-o", os.path.join(D, "nonfin.vtp")]]
            for args in commands:
                refused(args, path, fragment="non-finite")
                for ext in (".ply", ".vtu", ".vtp"):
                    assert not os.path.exists(os.path.join(D, "nonfin" + ext)), (bad, name, args)


def work_estimated_before_allocation():
    tets = small_tets()  # 11^3 voxels x 5 = 6655 tets
    # 6655 * 8^8 tets: refused up front by name, with the sizes, not by the OOM killer.
    line = refused(["subdivide", tets, "-o", os.path.join(D, "huge.vtu"), "--levels", 8, "-q"], tets,
                   fragment="points")
    assert str(6655 * 8 ** 8) in line, line
    surface = os.path.join(D, "surf8.ply")
    run("contour", small_volume(), "-o", surface, "--iso", 4.5, "-q")
    # ~20 M triangles: within the index type, so the budget decides (stated, so that
    # the run is the same with or without an address-space limit).
    refused(["subdivide", surface, "-o", os.path.join(D, "huge.ply"), "--levels", 8, "--max-memory", "256M", "-q"],
            surface, fragment="--max-memory")
    # --max-memory: a small budget refuses what the default allows.
    rc, _ = km2("tetrahedralize", small_volume(), "-o", os.path.join(D, "ok.vtu"), "-q")
    assert rc == 0
    refused(["tetrahedralize", small_volume(), "-o", os.path.join(D, "no.vtu"), "--max-memory", "4K", "-q"],
            small_volume(), fragment="--max-memory")
    assert not os.path.exists(os.path.join(D, "no.vtu"))
    for bad in ("-5", "0", "1X", "99999999999999999999G"):
        rc, lines = km2("tetrahedralize", small_volume(), "-o", os.path.join(D, "no.vtu"), "--max-memory", bad)
        assert rc == 2 and lines, (bad, rc, lines)


def options_validated_with_exit_2():
    raw = write("v8.raw", bytes(4 * 512))
    base = ["contour", raw, "--dims", 8, 8, 8, "-o", os.path.join(D, "m.ply"), "--iso", 0.5]
    for bad in (["--memory-limit", "-5"], ["--memory-limit", "0"], ["--memory-limit", "5Q"],
                ["--memory-limit", "18446744073709551616"], ["--type", "float16"], ["--type", "complex"]):
        rc, lines = km2(*base, *bad)
        assert rc == 2 and lines, (bad, rc, lines)
    rc, _ = km2(*base, "--type", "float", "--memory-limit", "64K", "-q")  # aliases and units still accepted
    assert rc == 0, rc


def every_error_names_the_input():
    vol = small_volume()
    tets = small_tets()
    quads = write("quads.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    flat = write("flat.raw", bytes(4 * 8))
    surface = os.path.join(D, "surf.ply")
    run("contour", vol, "-o", surface, "--iso", 2.5, "-q")
    for args, named in (
            (["quality", quads], quads),
            (["contour", flat, "--dims", 8, 1, 1, "--type", "float32", "-o", os.path.join(D, "x.ply"), "--iso", 1],
             flat),
            (["contour", tets, "-o", os.path.join(D, "x.ply"), "--iso", 1, "--array", "nosuch"], tets),
            (["subdivide", quads, "-o", os.path.join(D, "x.ply")], quads),
            (["subdivide", surface, "-o", os.path.join(D, "x.ply"), "--scheme", "bezier"], surface)):
        refused(args + ["-q"], named)


def ply_properties_never_repeat():
    # A point field named x (and one named like the normals) written to PLY:
    # each property once, the field renamed field_x, as VTK's reader reads it.
    vtp = write("named.vtp", '<VTKFile type="PolyData"><PolyData><Piece NumberOfPoints="3" NumberOfPolys="1">'
                             '<PointData><DataArray type="Float32" Name="x">7 8 9</DataArray>'
                             '<DataArray type="Float32" Name="nx">4 5 6</DataArray></PointData>'
                             '<Points><DataArray type="Float32" NumberOfComponents="3">0 0 0 1 0 0 0 1 0</DataArray>'
                             '</Points><Polys><DataArray type="Int32" Name="connectivity">0 1 2</DataArray>'
                             '<DataArray type="Int32" Name="offsets">3</DataArray></Polys></Piece></PolyData>'
                             '</VTKFile>')
    out = os.path.join(D, "named.ply")
    run("convert", vtp, "-o", out, "-q")
    with open(out, "rb") as f:
        head = f.read().split(b"end_header")[0].decode()
    props = [line.split()[-1] for line in head.splitlines() if line.startswith("property float")]
    assert len(props) == len(set(props)), props
    assert props[:3] == ["x", "y", "z"] and "field_x" in props, props
    # Coordinates read back are the points, not the field (an independent parse of the body).
    n = len(props)
    with open(out, "rb") as f:
        body = f.read().split(b"end_header\n", 1)[1]
    rows = [struct.unpack_from("<%df" % n, body, 4 * n * i) for i in range(3)]
    assert [r[0] for r in rows] == [0.0, 1.0, 0.0], rows
    assert [r[props.index("field_x")] for r in rows] == [7.0, 8.0, 9.0], rows


def contour_output_estimated():
    """contour counts its rows first and refuses, by name and before allocating
    any output, a mesh larger than --max-memory; the estimate is the output's
    bytes (3 floats + 1 scalar per point, 3 ids per triangle)."""
    vol = os.path.join(D, "s40.vti")
    run("generate", "sphere", "--size", 40, "-o", vol, "-q")
    out = os.path.join(D, "est.ply")
    report = os.path.join(D, "est.json")
    run("contour", vol, "-o", out, "--iso", 17.5, "-q", "--report", report)
    with open(report) as f:
        r = json.load(f)
    need = 16 * r["points"] + 12 * r["cells"]
    os.remove(out)
    line = refused(["contour", vol, "-o", out, "--iso", 17.5, "-q", "--max-memory", need - 1], vol, 1, "contour:")
    assert str(r["points"]) in line and str(r["cells"]) in line, line
    assert not os.path.exists(out)
    run("contour", vol, "-o", out, "--iso", 17.5, "-q", "--max-memory", need + 1)
    assert os.path.exists(out)


check("issue 19: XML nested 300,000 deep refused; --threads past the maximum: exit 2; generate too big: refused", deep_xml_and_thread_counts)
check("issue 19: FIFO, directory, /dev/zero as any input or .pvtp piece: refused by name", non_regular_inputs_refused)
check("issue 19: a failed run (bad --report) leaves every old file untouched, no new file", failed_runs_leave_every_file_untouched)
check("issue 19: input, output, report naming one file: exit 2, nothing overwritten", shared_paths_refused)
check("issue 19: origin/spacing past float32, nan/inf/1e39 coordinates: refused by name", nonfinite_geometry_refused)
check("issue 19: subdivide --levels 8, --max-memory: work refused before allocation", work_estimated_before_allocation)
check("issue 19: --memory-limit -5, --type float16: exit 2 from the validators", options_validated_with_exit_2)
check("issue 19: operation errors name the input file", every_error_names_the_input)
check("issue 19: the PLY writer never repeats a property", ply_properties_never_repeat)
check("issue 19: contour's output estimated from its row counts, refused past --max-memory", contour_output_estimated)


# ---- what the DICOM and Zarr fuzz targets found (tests/fuzz/regressions) -------------------

def zarray(folder, **change):
    meta = {"zarr_format": 2, "shape": [2, 2, 2], "chunks": [2, 2, 2], "dtype": "|u1", "compressor": None,
            "fill_value": 7, "order": "C", "filters": None}
    meta.update(change)
    os.makedirs(os.path.join(D, folder), exist_ok=True)
    write(os.path.join(folder, ".zarray"), json.dumps(meta))
    return os.path.join(D, folder)


def zarr_chunks_sized_by_their_bytes():
    """A chunk shape of 1 GiB over a 2 x 2 x 2 array: absent chunks are
    fill_value without a chunk allocated (it took 1 GiB: out of memory under
    the 1 GiB address-space limit); a chunk file of a few bytes is refused
    before its decoded size is allocated."""
    big = [1024, 1024, 1024]
    rc, out, err = km("info", zarray("fill.zarr", chunks=big))
    assert rc == 0 and "range 7 .. 7" in out, (rc, out, err)
    for codec, data in ((None, b"\0" * 8), ({"id": "zlib", "level": 1}, zlib.compress(b"\0" * 4096))):
        folder = zarray(f"tiny_{codec is None}.zarr", chunks=big, compressor=codec)
        write(os.path.join(os.path.basename(folder), "0.0.0"), data)
        expect_refused(["info", folder], folder, "chunk 0.0.0")


def zarr_metadata_depth_bounded():
    """.zarray "filters" nested 100,000 deep: quoting it in the refusal
    (nlohmann's recursive dump) overflowed the stack, exit 139; .zattrs too."""
    deep = "[" * 100000 + "]" * 100000
    folder = zarray("deep.zarr")
    with open(os.path.join(folder, ".zarray")) as f:
        text = f.read().replace('"filters": null', '"filters": ' + deep)
    write(os.path.join("deep.zarr", ".zarray"), text)
    expect_refused(["info", folder], folder, ".zarray nests deeper than 64 levels")
    image = os.path.join(D, "deep_ome")
    os.makedirs(image, exist_ok=True)
    write(os.path.join("deep_ome", ".zattrs"), '{"multiscales": ' + deep + "}")
    expect_refused(["info", image], image, ".zattrs nests deeper than 64 levels")


def unpacked(regression, leaf):
    """A folder input of tests/fuzz/regressions (packed as folder_input.hpp
    reads it: "KMFILE:<name>\\n<bytes>" records joined by newlines)."""
    with open(os.path.join(SOURCE_DIR, "tests", "fuzz", "regressions", regression), "rb") as f:
        records = f.read().split(b"\nKMFILE:")
    folder = os.path.join(D, leaf)
    os.makedirs(folder, exist_ok=True)
    for record in records:
        name, _, body = record.removeprefix(b"KMFILE:").partition(b"\n")
        write(os.path.join(leaf, name.decode()), body)
    return folder


def dicom_library_aborts_reported():
    """A series whose second slice has a damaged meta header: Debian's GDCM
    fails an assert() on it (abort, exit 134, before the reader ran GDCM in a
    child process); now exit 1 and one line naming the folder and the slice."""
    folder = unpacked("dicom/gdcm_assert_in_meta_header", "gdcm_assert")
    for args in (["info", folder], ["contour", folder, "--iso", "1", "-o", os.path.join(D, "ga.vtp")]):
        expect_refused(args, folder, "s1: GDCM failed")


def dicom_library_memory_bounded():
    """A 6 KB JPEG-LS slice whose damaged length field GDCM allocates: its
    child process peaked at 1.1 GB; now it has a budget (256 MiB + 4 x the
    file and the plane) and the file is refused by name."""
    folder = unpacked("dicom/gdcm_allocates_a_length_field", "gdcm_memory")
    expect_refused(["info", folder], folder)
    if SANITIZED:  # no RLIMIT_AS under a sanitizer: the budget is off there
        return
    probe = ("import resource, subprocess, sys; subprocess.run(sys.argv[1:], capture_output=True); "
             "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)")
    p = subprocess.run([sys.executable, "-c", probe, KEYMESH, "info", folder], capture_output=True, text=True)
    assert int(p.stdout) < 400 << 10, f"keymesh info {folder}: a process peaked at {int(p.stdout) >> 10} MiB"


def dicom_integers_within_32_bits():
    """NumberOfFrames '1e300' (an IS value strtod reads): its cast to long
    was undefined behaviour (UBSan in sanitize-quick); refused by name."""
    folder = unpacked("dicom/number_of_frames_1e300", "frames_1e300")
    expect_refused(["info", folder], folder, "bad NumberOfFrames '1e300")


check("fuzzed Zarr: chunks far larger than the array cost no memory until bytes on disk hold them",
      zarr_chunks_sized_by_their_bytes)
check("Zarr metadata nested 100,000 deep refused by name, no stack overflow", zarr_metadata_depth_bounded)
check("fuzzed DICOM: a file GDCM aborts on is refused by name, no crash", dicom_library_aborts_reported)
check("fuzzed DICOM: GDCM's allocations bounded in its child process", dicom_library_memory_bounded)
check("DICOM integer tags past 32 bits refused by name, no undefined cast", dicom_integers_within_32_bits)
finish()
