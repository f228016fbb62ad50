"""Issue 20's formats, end to end through the `keymesh` command, each against
an independent reference: a DICOM series written slice by slice with pydicom
from a known numpy volume, Zarr arrays written with the zarr package (and
chunk files written by hand with numpy + zlib), each compared with the same
array in an NRRD written here by hand (not by keymesh); streamed under
--memory-limit and not. The .glb output is parsed back by a small reader of
the glTF 2.0 container written here from the specification."""
import json
import os
import shutil
import struct
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import accessor, check, finish, parse_glb, report, run, tempdir  # noqa: E402
from dicom_series import write_dicom_series  # noqa: E402

import numpy as np  # noqa: E402

D = tempdir()


def write_nrrd(path, array_zyx, spacing=(1, 1, 1), origin=(0, 0, 0)):
    """The reference: a C-order (z, y, x) array as an attached raw NRRD whose
    x is the array's last axis (fastest in memory)."""
    a = np.ascontiguousarray(array_zyx)
    types = {"u1": "uint8", "i1": "int8", "u2": "uint16", "i2": "int16", "i4": "int32", "f4": "float", "f8": "double"}
    head = (f"NRRD0004\ntype: {types[a.dtype.str[1:]]}\ndimension: 3\nsizes: {a.shape[2]} {a.shape[1]} {a.shape[0]}\n"
            f"space dimension: 3\nspace directions: ({spacing[0]!r},0,0) (0,{spacing[1]!r},0) (0,0,{spacing[2]!r})\n"
            f"space origin: ({origin[0]!r},{origin[1]!r},{origin[2]!r})\n"
            f"endian: {'big' if a.dtype.byteorder == '>' else 'little'}\nencoding: raw\n\n")
    with open(path, "wb") as f:
        f.write(head.encode() + a.tobytes())


def read_nrrd(path):
    """An attached raw NRRD as keymesh writes it: (array (z, y, x), spacing, origin)."""
    data = open(path, "rb").read()
    head, body = data.split(b"\n\n", 1)
    fields = dict(line.split(": ", 1) for line in head.decode().splitlines()[1:] if ": " in line)
    sizes = [int(s) for s in fields["sizes"].split()]
    dtype = {"uint8": "u1", "int8": "i1", "uint16": "<u2", "int16": "<i2", "int32": "<i4", "float": "<f4",
             "double": "<f8"}[fields["type"]]
    dirs = [v.strip("()").split(",") for v in fields["space directions"].split()]
    spacing = tuple(float(dirs[a][a]) for a in range(3))
    origin = tuple(float(v) for v in fields["space origin"].strip("()").split(","))
    return np.frombuffer(body, dtype=dtype).reshape(sizes[::-1]), spacing, origin


def convert_refused(folder, out, words):
    """`keymesh convert folder out` fails with one line naming the folder and
    holding every word, and leaves no output."""
    p = run("convert", folder, "-o", out, expect=1)
    line = p.stderr.strip()
    assert "\n" not in line and line.startswith(f"keymesh: {folder}: "), p.stderr
    for w in words:
        assert w in line, (w, line)
    assert not os.path.exists(out)


def same_bytes(a, b):
    return open(a, "rb").read() == open(b, "rb").read()


def field(shape, center, scale=1.0):
    """A smooth analytic volume (z, y, x): scaled distance from a point."""
    z, y, x = np.meshgrid(*[np.arange(n, dtype=np.float64) for n in shape], indexing="ij")
    return scale * np.sqrt((x - center[2]) ** 2 + (y - center[1]) ** 2 + (z - center[0]) ** 2)


# ---------------------------------------------------------------- DICOM ----

STORED = np.round(field((9, 14, 11), (4.2, 6.1, 5.3), 40.0)).astype(np.int16) - 50  # (z, y, x)


def dicom_reads_back_equal():
    folder = os.path.join(D, "ct")
    write_dicom_series(folder, STORED)
    out = os.path.join(D, "ct.nrrd")
    run("convert", folder, "-o", out, "-q")
    array, spacing, origin = read_nrrd(out)
    expected = (2.0 * STORED.astype(np.float64) - 100.0).astype(np.float32)  # slope and intercept
    assert array.dtype == np.float32 and array.shape == STORED.shape, (array.dtype, array.shape)
    assert np.array_equal(array, expected)
    assert spacing == (0.9, 0.7, 2.5), spacing  # x = column spacing, y = row spacing, z = position step
    assert np.allclose(origin, (-20.0, 10.0, 5.0)), origin
    p = run("info", folder)
    assert "11" in p.stdout and "14" in p.stdout and "float32" in p.stdout, p.stdout


def dicom_contours_like_nrrd():
    folder = os.path.join(D, "ct")
    ref = os.path.join(D, "ct_ref.nrrd")
    write_nrrd(ref, (2.0 * STORED.astype(np.float64) - 100.0).astype(np.float32), (0.9, 0.7, 2.5), (-20.0, 10.0, 5.0))
    a, b, c = (os.path.join(D, n) for n in ("dcm.ply", "ref.ply", "dcm_stream.ply"))
    run("contour", folder, "-o", a, "--iso", 150.5, "--normals", "gradient", "-q", "--report", a + ".json")
    run("contour", ref, "-o", b, "--iso", 150.5, "--normals", "gradient", "-q")
    assert report(a + ".json")["cells"] > 100
    assert same_bytes(a, b), "DICOM contour differs from the same array in .nrrd"
    plane = 11 * 14 * 4
    run("contour", folder, "-o", c, "--iso", 150.5, "--normals", "gradient", "-q", "--memory-limit", str(5 * plane),
        "--report", c + ".json")
    assert report(c + ".json")["stream"]["slabs"] > 1
    assert same_bytes(a, c), "streamed DICOM contour differs"


def dicom_compressed_like_uncompressed():
    """The series re-encoded RLE Lossless by pydicom: GDCM decodes it to the
    same samples as the uncompressed files."""
    import pydicom
    from pydicom.uid import RLELossless
    folder = os.path.join(D, "ct_rle")
    shutil.copytree(os.path.join(D, "ct"), folder)
    for name in os.listdir(folder):
        ds = pydicom.dcmread(os.path.join(folder, name))
        ds.compress(RLELossless)
        ds.save_as(os.path.join(folder, name))
    a, b = os.path.join(D, "rle.nrrd"), os.path.join(D, "plain.nrrd")
    run("convert", folder, "-o", a, "-q")
    run("convert", os.path.join(D, "ct"), "-o", b, "-q")
    assert same_bytes(a, b), "RLE-compressed series reads differently"


def dicom_oblique_and_unscaled():
    """Slices along a tilted normal: the step is the distance along it; slope 1
    / intercept 0 keep the stored int16 samples."""
    folder = os.path.join(D, "oblique")
    s = np.sqrt(0.5)
    write_dicom_series(folder, STORED, orientation=(s, s, 0, 0, 0, -1), step=1.25, slope=1, intercept=0)
    out = os.path.join(D, "oblique.nrrd")
    run("convert", folder, "-o", out, "-q")
    array, spacing, _ = read_nrrd(out)
    assert array.dtype == np.int16 and np.array_equal(array, STORED)
    assert abs(spacing[2] - 1.25) < 1e-9, spacing


def dicom_mixed_series_refused():
    def refused(folder, words):
        convert_refused(folder, os.path.join(D, "mixed.nrrd"), words)

    base = os.path.join(D, "ct")
    two = os.path.join(D, "two_series")
    shutil.copytree(base, two)
    write_dicom_series(os.path.join(D, "other"), STORED[:2], series="1.2.3.4.5", names=["zz1", "zz2"])
    shutil.copy(os.path.join(D, "other", "zz1"), two)
    refused(two, ["SeriesInstanceUID", "1.2.3.4.5", "zz1"])

    sizes = os.path.join(D, "sizes")
    shutil.copytree(base, sizes)
    write_dicom_series(os.path.join(D, "small"), STORED[:1, :5, :5], names=["small1"])
    shutil.copy(os.path.join(D, "small", "small1"), sizes)
    refused(sizes, ["5 x 5", "mixed series"])

    gap = os.path.join(D, "gap")
    write_dicom_series(gap, STORED, names=[f"s{k}" for k in range(STORED.shape[0])], shuffle=False)
    os.remove(os.path.join(gap, "s4"))
    refused(gap, ["uneven slice spacing", "s3", "s5"])

    tilted = os.path.join(D, "tilted")
    shutil.copytree(gap, tilted)
    write_dicom_series(os.path.join(D, "t1"), STORED[:1], orientation=(1, 0, 0, 0, 0.8, 0.6), names=["tilt"])
    shutil.copy(os.path.join(D, "t1", "tilt"), tilted)
    refused(tilted, ["ImageOrientationPatient", "tilt"])

    junk = os.path.join(D, "junk")
    shutil.copytree(base, junk)
    with open(os.path.join(junk, "notes.txt"), "w") as f:
        f.write("not a slice\n")
    refused(junk, ["notes.txt", "not a DICOM file"])

    cut = os.path.join(D, "cut")  # a slice whose pixel data ends early
    write_dicom_series(cut, STORED, names=[f"s{k}" for k in range(STORED.shape[0])], shuffle=False)
    with open(os.path.join(cut, "s6"), "r+b") as f:
        f.truncate(os.path.getsize(os.path.join(cut, "s6")) - 100)
    refused(cut, ["s6"])

    fifo = os.path.join(D, "fifo")  # a FIFO among the slices would block a reader: refused as every input
    shutil.copytree(base, fifo)
    os.mkfifo(os.path.join(fifo, "pipe"))
    p = run("convert", fifo, "-o", os.path.join(D, "fifo.nrrd"), expect=1)
    assert p.stderr.strip() == f"keymesh: {os.path.join(fifo, 'pipe')}: not a regular file (a FIFO)", p.stderr

    empty = os.path.join(D, "empty")
    os.makedirs(empty)
    refused(empty, ["no file"])


def have(module):
    try:
        __import__(module)
        return True
    except ImportError:
        print(f"        ({module} not installed: its checks are skipped)")
        return False


# ----------------------------------------------------------------- Zarr ----

VOLUME = field((23, 19, 17), (11.3, 8.6, 7.9)).astype(np.float32)  # (z, y, x)


def contour_pair(src, ref, name, *extra, iso=6.5):
    a, b = os.path.join(D, name + ".ply"), os.path.join(D, name + "_ref.ply")
    run("contour", src, "-o", a, "--iso", iso, "--normals", "gradient", "-q", *extra, "--report", a + ".json")
    run("contour", ref, "-o", b, "--iso", iso, "--normals", "gradient", "-q")
    assert report(a + ".json")["cells"] > 100
    assert same_bytes(a, b), f"{src} {extra}: contour differs from the in-memory contour of {ref}"
    return report(a + ".json")


def zarr_like_nrrd():
    import numcodecs
    import zarr
    ref = os.path.join(D, "vol.nrrd")
    write_nrrd(ref, VOLUME)
    codecs = {"none": None, "zlib": numcodecs.Zlib(level=5), "gzip": numcodecs.GZip(level=5),
              "blosc-lz4": numcodecs.Blosc(cname="lz4", clevel=5, shuffle=numcodecs.Blosc.SHUFFLE),
              "blosc-zstd": numcodecs.Blosc(cname="zstd", clevel=3, shuffle=numcodecs.Blosc.BITSHUFFLE)}
    plane = 17 * 19 * 4
    for name, codec in codecs.items():
        path = os.path.join(D, f"vol_{name}.zarr")
        z = zarr.open(path, mode="w", shape=VOLUME.shape, chunks=(5, 8, 6), dtype="<f4", compressor=codec)
        z[:] = VOLUME  # chunks that do not divide the shape: edge chunks are partly outside
        contour_pair(path, ref, "zarr_" + name)
        r = contour_pair(path, ref, "zarr_stream_" + name, "--memory-limit", str(6 * plane))
        assert r["stream"]["slabs"] > 3, r["stream"]


def zarr_dtypes_fill_and_separator():
    import zarr
    for dtype in ("|u1", ">i2", "<u2", "<i4", ">f8"):
        path = os.path.join(D, f"dt{dtype[1:]}.zarr")
        data = (VOLUME * 9).astype(dtype)
        z = zarr.open(path, mode="w", shape=data.shape, chunks=(4, 7, 9), dtype=dtype, fill_value=3,
                      dimension_separator="/")
        z[:] = data
        shutil.rmtree(os.path.join(path, "1", "1"))  # chunks (1, 1, *) absent: fill_value
        if dtype == "<i4":  # an older nested array: no dimension_separator key, chunks in folders
            with open(os.path.join(path, ".zarray")) as f:
                meta = json.load(f)
            del meta["dimension_separator"]
            with open(os.path.join(path, ".zarray"), "w") as f:
                json.dump(meta, f)
        expected = data.astype(data.dtype.newbyteorder("="))
        expected[4:8, 7:14, :] = 3
        out = os.path.join(D, f"dt{dtype[1:]}.nrrd")
        run("convert", path, "-o", out, "-q")
        array, spacing, origin = read_nrrd(out)
        assert array.dtype == expected.dtype and np.array_equal(array, expected), dtype
        assert spacing == (1.0, 1.0, 1.0) and origin == (0.0, 0.0, 0.0)


def zarr_written_by_hand():
    """Chunks written here with numpy and zlib (no zarr package): 2 x 2 x 2
    chunks of a 4 x 3 x 5 (z, y, x) int16 array, C order."""
    import zlib
    path = os.path.join(D, "hand.zarr")
    os.makedirs(path)
    data = np.arange(60, dtype="<i2").reshape(4, 3, 5) * 7 - 100
    chunks = (2, 2, 3)
    with open(os.path.join(path, ".zarray"), "w") as f:
        json.dump({"zarr_format": 2, "shape": [4, 3, 5], "chunks": list(chunks), "dtype": "<i2",
                   "compressor": {"id": "zlib", "level": 1}, "fill_value": 0, "order": "C", "filters": None}, f)
    for i in range(2):
        for j in range(2):
            for k in range(2):
                block = np.zeros(chunks, "<i2")  # edge chunks are stored whole
                part = data[2 * i:2 * i + 2, 2 * j:2 * j + 2, 3 * k:3 * k + 3]
                block[:part.shape[0], :part.shape[1], :part.shape[2]] = part
                with open(os.path.join(path, f"{i}.{j}.{k}"), "wb") as f:
                    f.write(zlib.compress(block.tobytes()))
    out = os.path.join(D, "hand.nrrd")
    run("convert", path, "-o", out, "-q")
    array, _, _ = read_nrrd(out)
    assert np.array_equal(array, data)


def ome_zarr_levels():
    """An OME-Zarr image (c, z, y, x) with two levels: level 0 by default
    with its scale as spacing, level 1 when its folder is given."""
    import zarr
    image = os.path.join(D, "image.ome.zarr")
    os.makedirs(image)
    with open(os.path.join(image, ".zgroup"), "w") as f:
        json.dump({"zarr_format": 2}, f)
    full = VOLUME[None]
    half = np.ascontiguousarray(VOLUME[::2, ::2, ::2])[None]
    for level, data in (("0", full), ("1", half)):
        z = zarr.open(os.path.join(image, level), mode="w", shape=data.shape, chunks=(1, 6, 6, 6), dtype="<f4")
        z[:] = data
    axes = [{"name": "c", "type": "channel"}] + [{"name": n, "type": "space", "unit": "micrometer"} for n in "zyx"]
    datasets = [{"path": "0", "coordinateTransformations": [{"type": "scale", "scale": [1, 2.0, 0.5, 0.25]},
                                                            {"type": "translation", "translation": [0, 3, 2, 1]}]},
                {"path": "1", "coordinateTransformations": [{"type": "scale", "scale": [1, 4.0, 1.0, 0.5]}]}]
    with open(os.path.join(image, ".zattrs"), "w") as f:
        json.dump({"multiscales": [{"version": "0.4", "axes": axes, "datasets": datasets}]}, f)
    ref0, ref1 = os.path.join(D, "ome0.nrrd"), os.path.join(D, "ome1.nrrd")
    write_nrrd(ref0, VOLUME, (0.25, 0.5, 2.0), (1.0, 2.0, 3.0))
    write_nrrd(ref1, half[0], (0.5, 1.0, 4.0))
    contour_pair(image, ref0, "ome0")
    contour_pair(image, ref0, "ome0_stream", "--memory-limit", str(4 * 17 * 19 * 4))
    contour_pair(os.path.join(image, "1"), ref1, "ome1", iso=5.5)


def zarr_refused_by_name():
    import zlib
    base = {"zarr_format": 2, "shape": [2, 3, 4], "chunks": [2, 3, 4], "dtype": "<f4", "compressor": None,
            "fill_value": 0, "order": "C", "filters": None}

    def refused(name, change, words, chunk=None):
        path = os.path.join(D, name + ".zarr")
        os.makedirs(path)
        with open(os.path.join(path, ".zarray"), "w") as f:
            json.dump({**base, **change}, f)
        if chunk is not None:
            with open(os.path.join(path, "0.0.0"), "wb") as f:
                f.write(chunk)
        convert_refused(path, os.path.join(D, name + ".nrrd"), words)

    refused("fortran", {"order": "F"}, ["order is not C"])
    refused("filters", {"filters": [{"id": "delta", "dtype": "<f4"}]}, ["filters", "delta"])
    refused("lz4", {"compressor": {"id": "lz4", "acceleration": 1}}, ["compressor 'lz4'"])
    refused("float16", {"dtype": "<f2"}, ["dtype '<f2'"])  # (<i8 and <u8 are label maps: test_labels_wide_ids_cli)
    refused("twod", {"shape": [3, 4], "chunks": [3, 4]}, ["2 dimensions"])
    refused("time", {"shape": [5, 2, 3, 4], "chunks": [1, 2, 3, 4]}, ["axis 0 has size 5"])
    refused("short", {}, ["chunk 0.0.0", "holds 7 bytes"], chunk=bytes(7))
    refused("corrupt", {"compressor": {"id": "zlib", "level": 1}}, ["chunk 0.0.0", "corrupt"], chunk=b"\x78\x9c" + bytes(30))
    refused("toolong", {"compressor": {"id": "zlib", "level": 1}}, ["chunk 0.0.0", "more than"],
            chunk=zlib.compress(bytes(200)))
    refused("v3", {"zarr_format": 3}, ["zarr_format"])
    refused("wrongtype", {"order": 5}, ["unexpected type"])
    # Sizes no machine holds are refused before anything is allocated.
    refused("huge", {"shape": [2 ** 40, 2 ** 40, 2 ** 40], "chunks": [1, 1, 1]}, ["overflow"])
    refused("bigchunk", {"chunks": [2 ** 20, 2 ** 20, 2 ** 20]}, ["chunks past 1 GiB"])
    bad = os.path.join(D, "notjson.zarr")
    os.makedirs(bad)
    with open(os.path.join(bad, ".zarray"), "w") as f:
        f.write('{"zarr_format": 2, "shape": [2, 3')
    convert_refused(bad, os.path.join(D, "notjson.nrrd"), [".zarray is not valid JSON"])


# ------------------------------------------- .vti and gzip NIfTI streams ----

def write_nifti_gz(path, array_zyx, spacing, slope=1.0, inter=0.0):
    """A NIfTI-1 .nii.gz written here from the specification (348-byte
    header, vox_offset 352), int16 samples."""
    import gzip
    h = bytearray(348)
    struct.pack_into("<i", h, 0, 348)
    nz, ny, nx = array_zyx.shape
    struct.pack_into("<8h", h, 40, 3, nx, ny, nz, 1, 1, 1, 1)
    struct.pack_into("<hh", h, 70, 4, 16)  # datatype int16, bitpix
    struct.pack_into("<8f", h, 76, 1, *spacing, 1, 1, 1, 1)
    struct.pack_into("<f", h, 108, 352.0)
    struct.pack_into("<ff", h, 112, slope, inter)
    h[344:348] = b"n+1\0"
    with open(path, "wb") as f:
        f.write(gzip.compress(bytes(h) + bytes(4) + array_zyx.astype("<i2").tobytes()))


def vti_and_nii_gz_streamed():
    # keymesh's own .vti writer appends the samples raw and uncompressed.
    vti = os.path.join(D, "s.vti")
    run("generate", "sphere", "--size", 40, "-o", vti, "-q")
    # Against the in-memory contour of the same .vti: its field is named
    # "distance" on both paths (a .nrrd's would be "scalars").
    r = contour_pair(vti, vti, "vti_stream", "--memory-limit", str(5 * 40 * 40 * 4), iso=15.5)
    assert r["stream"]["slabs"] > 5, r["stream"]
    nii = os.path.join(D, "v.nii.gz")
    data = np.round(VOLUME * 13).astype(np.int16) - 40
    write_nifti_gz(nii, data, (0.5, 0.75, 1.5), slope=0.5, inter=2.0)
    ref = os.path.join(D, "v_ref.nrrd")
    write_nrrd(ref, (0.5 * data.astype(np.float64) + 2.0).astype(np.float32), (0.5, 0.75, 1.5))
    for extra in ([], ["--memory-limit", str(4 * 17 * 19 * 4)], ["--memory-limit", str(9 * 17 * 19 * 4)]):
        r = contour_pair(nii, ref, "niigz", *extra, iso=40.5)
        assert not extra or r["stream"]["slabs"] > 2, r
    # A truncated .nii.gz fails by name, streamed, and leaves no output.
    cut = os.path.join(D, "cut.nii.gz")
    with open(nii, "rb") as f:
        blob = f.read()
    with open(cut, "wb") as f:
        f.write(blob[:len(blob) * 2 // 3])
    out = os.path.join(D, "cut.ply")
    p = run("contour", cut, "-o", out, "--iso", 40.5, "--memory-limit", str(4 * 17 * 19 * 4), expect=1)
    assert p.stderr.startswith(f"keymesh: {cut}: ") and "gzip" in p.stderr and not os.path.exists(out), p.stderr


# ------------------------------------------------------------------ .glb ----

def glb_from_contour_and_convert():
    """The .glb of a contour holds the .ply's points, normals and triangles
    (the .ply read back by VTK when present, else by the PLY header here)."""
    vti = os.path.join(D, "g.vti")
    run("generate", "sphere", "--size", 24, "-o", vti, "-q")
    glb, ply = os.path.join(D, "g.glb"), os.path.join(D, "g.ply")
    run("contour", vti, "-o", glb, "--iso", 9.5, "--normals", "average", "-q")
    run("contour", vti, "-o", ply, "--iso", 9.5, "--normals", "average", "-q")
    doc, binary = parse_glb(glb)
    prim = doc["meshes"][0]["primitives"][0]
    assert prim["mode"] == 4
    pa, pos = accessor(doc, binary, prim["attributes"]["POSITION"])
    _, nrm = accessor(doc, binary, prim["attributes"]["NORMAL"])
    _, idx = accessor(doc, binary, prim["indices"])
    assert pa["min"] == pos.min(axis=0).astype(float).tolist() and pa["max"] == pos.max(axis=0).astype(float).tolist()
    head, body = open(ply, "rb").read().split(b"end_header\n", 1)
    nv = int(head.split(b"element vertex ")[1].split()[0])
    nf = int(head.split(b"element face ")[1].split()[0])
    props = [l.split()[-1] for l in head.split(b"\n") if l.startswith(b"property float")]
    verts = np.frombuffer(body, "<f4", nv * len(props)).reshape(nv, len(props))
    faces = np.frombuffer(body[verts.nbytes:], np.dtype([("n", "u1"), ("v", "<u4", 3)]), nf)
    assert np.array_equal(pos, verts[:, :3]) and np.array_equal(nrm, verts[:, [props.index(b"nx"), props.index(b"ny"),
                                                                             props.index(b"nz")]])
    assert np.array_equal(idx.reshape(-1, 3), faces["v"])
    again = os.path.join(D, "again.glb")
    run("convert", ply, "-o", again, "-q")
    doc2, binary2 = parse_glb(again)
    _, pos2 = accessor(doc2, binary2, doc2["meshes"][0]["primitives"][0]["attributes"]["POSITION"])
    assert np.array_equal(pos2, pos)


def info_says_what_a_file_holds():
    # A legacy .vtk holding a surface (POLYDATA), or no VTK header at all, is
    # refused by the grid reader, which says so; a command that reads only
    # volumes says the format's kind. Never "unknown volume format".
    poly = os.path.join(D, "poly.vtk")
    with open(poly, "w") as f:
        f.write("# vtk DataFile Version 3.0\nsurface\nASCII\nDATASET POLYDATA\nPOINTS 0 float\nPOLYGONS 0 0\n")
    empty = os.path.join(D, "zero.vtk")
    open(empty, "w").close()
    for path, words in ((poly, "POLYDATA"), (empty, "not a legacy VTK file")):
        p = run("info", path, expect=1)
        assert path in p.stderr and words in p.stderr and "unknown volume format" not in p.stderr, p.stderr
    p = run("labels", poly, "-o", os.path.join(D, "labels.vtp"), expect=1)
    assert "unstructured grid format, not a volume" in p.stderr, p.stderr


if have("pydicom"):
    check("DICOM series reads back equal: slope/intercept, spacing, origin", dicom_reads_back_equal)
    check("DICOM series contours byte-identical to the same array in .nrrd, streamed too", dicom_contours_like_nrrd)
    check("DICOM RLE Lossless series (decoded by GDCM) reads like the uncompressed one", dicom_compressed_like_uncompressed)
    check("DICOM oblique orientation, unscaled int16", dicom_oblique_and_unscaled)
    check("mixed series, sizes, orientations, uneven spacing, junk refused by name", dicom_mixed_series_refused)
if have("zarr") and have("numcodecs"):
    check("Zarr (none, zlib, gzip, blosc) contours byte-identical to .nrrd, streamed too", zarr_like_nrrd)
    check("Zarr dtypes, byte orders, fill_value for absent chunks, '/' separator", zarr_dtypes_fill_and_separator)
    check("OME-Zarr: level 0 with its scale and translation, level 1 by folder", ome_zarr_levels)
check("Zarr chunks written by hand with numpy + zlib read back equal", zarr_written_by_hand)
check("Zarr refusals name the problem", zarr_refused_by_name)
check(".vti (raw appended) and .nii.gz stream byte-identical; a cut .nii.gz fails by name", vti_and_nii_gz_streamed)
check("info on a POLYDATA or empty .vtk says what it holds; labels says it is not a volume", info_says_what_a_file_holds)
check(".glb from contour and convert: container, accessors, arrays equal to the .ply's", glb_from_contour_and_convert)
finish()
