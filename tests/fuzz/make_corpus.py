#!/usr/bin/python3
"""Writes the seed corpus of the fuzz targets: tests/fuzz/corpus/<target>/.

Small valid files of every variant each reader supports (hand-built here;
VTK's writers add theirs when python3-vtk9 is importable; DICOM series from
the tests' pydicom writer and python3-pydicom's own test files, Zarr arrays
from python3-zarr, each folder packed as tests/fuzz/folder_input.hpp reads). Re-run after
adding a variant: `/usr/bin/python3 tests/fuzz/make_corpus.py`.
"""
import base64
import gzip
import os
import struct
import sys
import tempfile
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
CORPUS = os.path.join(HERE, "corpus")


def put(target, name, data):
    d = os.path.join(CORPUS, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())


# A 3x2x2 volume: value = x + 3y + 6z (12 samples).
DIMS = (3, 2, 2)
VALUES = [x + 3 * y + 6 * z for z in range(2) for y in range(2) for x in range(3)]


def samples(fmt, big=False):
    return struct.pack(("<" if not big else ">") + fmt * len(VALUES), *VALUES)


# ---- volumes ------------------------------------------------------------------
def nrrd():
    head = "NRRD0004\ntype: {t}\ndimension: 3\nsizes: 3 2 2\nencoding: {e}\nendian: {n}\n{extra}\n"
    put("nrrd", "raw_float.nrrd", head.format(t="float", e="raw", n="little", extra="spacings: 1 2 3\n").encode()
        + samples("f"))
    put("nrrd", "gzip_short_big.nrrd",
        head.format(t="short", e="gzip", n="big", extra="space directions: (1,0,0) (0,2,0) (0,0,0.5)\n"
                    "space origin: (1,2,3)\n").encode() + gzip.compress(samples("h", big=True)))
    put("nrrd", "uchar_4d.nrrd", "NRRD0005\n# comment\ntype: uchar\ndimension: 4\nsizes: 1 3 2 2\n"
        "encoding: raw\nkey:=value\nbyte skip: 2\n\n".encode() + b"\0\0" + samples("B"))


def nifti(datatype=16, fmt="f", big=False, slope=0.0, inter=0.0):
    e = ">" if big else "<"
    h = bytearray(348)
    struct.pack_into(e + "i", h, 0, 348)
    struct.pack_into(e + "8h", h, 40, 3, *DIMS, 1, 1, 1, 1)
    bitpix = struct.calcsize(fmt) * 8
    struct.pack_into(e + "hh", h, 70, datatype, bitpix)
    struct.pack_into(e + "8f", h, 76, 1, 1.5, 2.0, 2.5, 1, 1, 1, 1)
    struct.pack_into(e + "f", h, 108, 352.0)
    struct.pack_into(e + "ff", h, 112, slope, inter)
    h[344:348] = b"n+1\0"
    return bytes(h) + b"\0" * 4 + samples(fmt, big)


def den():
    h = bytearray(62)
    struct.pack_into("<h", h, 0, 1)
    struct.pack_into("<3h", h, 50, *DIMS)
    struct.pack_into("<i", h, 58, len(VALUES))
    return bytes(h) + samples("B")


def vti(data_array, appended=b"", extra_root=""):
    head = ('<?xml version="1.0"?>\n<VTKFile type="ImageData" version="1.0" byte_order="LittleEndian"'
            ' header_type="UInt32"%s>\n<ImageData WholeExtent="0 2 0 1 0 1" Origin="0 0 0" Spacing="1 1 1">\n'
            '<Piece Extent="0 2 0 1 0 1"><PointData Scalars="v">%s</PointData></Piece>\n</ImageData>\n'
            % (extra_root, data_array))
    if appended:
        return head.encode() + b'<AppendedData encoding="raw">_' + appended + b"\n</AppendedData></VTKFile>\n"
    return (head + "</VTKFile>\n").encode()


def volumes():
    nrrd()
    put("nifti", "float.nii", nifti())
    put("nifti", "int16_big_scaled.nii", nifti(4, "h", big=True, slope=2.0, inter=-1.0))
    put("nifti", "uint8.nii.gz", gzip.compress(nifti(2, "B")))
    put("den", "small.den", den())
    ascii = " ".join(str(v) for v in VALUES)
    put("vti", "ascii.vti", vti('<DataArray type="Float32" Name="v" format="ascii">%s</DataArray>' % ascii))
    raw = samples("f")
    b64 = base64.b64encode(struct.pack("<I", len(raw)) + raw).decode()
    put("vti", "base64.vti", vti('<DataArray type="Float32" Name="v" format="binary">%s</DataArray>' % b64))
    put("vti", "appended.vti", vti('<DataArray type="Int16" Name="v" format="appended" offset="0"/>',
                                   struct.pack("<I", 24) + samples("h")))
    z = zlib.compress(raw)
    put("vti", "zlib.vti", vti('<DataArray type="Float32" Name="v" format="appended" offset="0"/>',
                               struct.pack("<4I", 1, len(raw), len(raw), len(z)) + z,
                               ' compressor="vtkZLibDataCompressor"'))
    # raw: 32 option bytes (int64 dims, int32 header bytes, type index, endian) then the file.
    opts = struct.pack("<3qiBB2x", *DIMS, 4, 5, 0)  # type 5 = float32
    put("raw", "float32.bin", opts + b"HEAD" + samples("f"))
    put("raw", "uint16_big.bin", struct.pack("<3qiBB2x", *DIMS, 0, 2, 1) + samples("H", big=True))


# ---- surface meshes --------------------------------------------------------
TET_PTS = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
TET_TRI = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]


def meshes():
    lines = ["ply", "format ascii 1.0", "comment tet", "element vertex 4", "property float x", "property float y",
             "property float z", "property float t_0", "property float t_1", "element face 4",
             "property list uchar int vertex_indices", "end_header"]
    lines += ["%g %g %g %d %d" % (*p, i, -i) for i, p in enumerate(TET_PTS)] + ["3 %d %d %d" % t for t in TET_TRI]
    put("ply", "ascii.ply", "\n".join(lines) + "\n")
    for fmt, e in (("binary_little_endian", "<"), ("binary_big_endian", ">")):
        head = ("ply\nformat %s 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\n"
                "property float nx\nproperty float ny\nproperty float nz\nelement face 4\n"
                "property list ushort uint vertex_indices\nelement edge 1\nproperty int a\nend_header\n" % fmt)
        body = b"".join(struct.pack(e + "3d3f", *p, 0, 0, 1) for p in TET_PTS)
        body += b"".join(struct.pack(e + "H3I", 3, *t) for t in TET_TRI) + struct.pack(e + "i", 7)
        put("ply", fmt + ".ply", head.encode() + body)
    obj = "# tet\n" + "".join("v %g %g %g\n" % p for p in TET_PTS) + "vn 0 0 1\nvt 0 0\n"
    obj += "".join("f %d//1 %d//1 %d//1\n" % tuple(i + 1 for i in t) for t in TET_TRI)
    put("obj", "tet.obj", obj)
    put("obj", "quad_negative.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\ng quad\nf -4 -3/1 -2 -1\n")
    stl = "solid tet\n"
    for t in TET_TRI:
        stl += " facet normal 0 0 0\n  outer loop\n" + "".join("   vertex %g %g %g\n" % TET_PTS[i] for i in t)
        stl += "  endloop\n endfacet\n"
    put("stl", "ascii.stl", stl + "endsolid tet\n")
    put("stl", "binary.stl", b"solid but binary".ljust(80, b" ") + struct.pack("<I", 4) + b"".join(
        struct.pack("<12fH", 0, 0, 0, *TET_PTS[t[0]], *TET_PTS[t[1]], *TET_PTS[t[2]], 0) for t in TET_TRI))
    pts = " ".join("%g %g %g" % p for p in TET_PTS)
    conn = " ".join("%d %d %d" % t for t in TET_TRI)
    put("vtp", "ascii.vtp", '<?xml version="1.0"?>\n<VTKFile type="PolyData" version="0.1">\n<PolyData>\n'
        '<Piece NumberOfPoints="4" NumberOfPolys="4"><PointData Scalars="s"><DataArray type="Float32" Name="s" '
        'format="ascii">0 1 2 3</DataArray></PointData><Points><DataArray type="Float32" NumberOfComponents="3" '
        'format="ascii">%s</DataArray></Points><Polys><DataArray type="Int32" Name="connectivity" format="ascii">'
        '%s</DataArray><DataArray type="Int32" Name="offsets" format="ascii">3 6 9 12</DataArray></Polys>'
        '</Piece>\n</PolyData>\n</VTKFile>\n' % (pts, conn))
    put("vtu", "ascii.vtu", '<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="0.1">\n'
        '<UnstructuredGrid><Piece NumberOfPoints="4" NumberOfCells="1"><PointData Scalars="s"><DataArray '
        'type="Float64" Name="s" format="ascii">0 1 2 3</DataArray></PointData><Points><DataArray type="Float32" '
        'NumberOfComponents="3" format="ascii">%s</DataArray></Points><Cells><DataArray type="Int64" '
        'Name="connectivity" format="ascii">0 1 2 3</DataArray><DataArray type="Int64" Name="offsets" '
        'format="ascii">4</DataArray><DataArray type="UInt8" Name="types" format="ascii">10</DataArray></Cells>'
        '</Piece></UnstructuredGrid>\n</VTKFile>\n' % pts)
    put("legacy_vtk", "ascii.vtk", "# vtk DataFile Version 3.0\ntet\nASCII\nDATASET UNSTRUCTURED_GRID\n"
        "POINTS 4 float\n%s\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\nPOINT_DATA 4\nSCALARS s float 1\n"
        "LOOKUP_TABLE default\n0 1 2 3\nCELL_DATA 1\nVECTORS v double\n1 2 3\n" % pts)
    put("legacy_vtk", "binary.vtk", b"# vtk DataFile Version 4.2\ntet\nBINARY\nDATASET UNSTRUCTURED_GRID\n"
        b"POINTS 4 float\n" + b"".join(struct.pack(">3f", *p) for p in TET_PTS) + b"\nCELLS 1 5\n"
        + struct.pack(">5i", 4, 0, 1, 2, 3) + b"\nCELL_TYPES 1\n" + struct.pack(">i", 10) + b"\n")
    put("legacy_vtk", "v51.vtk", "# vtk DataFile Version 5.1\ntet\nASCII\nDATASET UNSTRUCTURED_GRID\n"
        "POINTS 4 float\n%s\nCELLS 2 4\nOFFSETS vtktypeint64\n0 4\nCONNECTIVITY vtktypeint64\n0 1 2 3\n"
        "CELL_TYPES 1\n10\n" % pts)


# ---- folders: DICOM series, Zarr arrays (packed: tests/fuzz/folder_input.hpp) ----
def pack_folder(folder, open_sub=None):
    """The files of `folder` (relative names, sorted) as KMFILE records,
    joined by newlines (a file's bytes end where "\\nKMFILE:" starts)."""
    records = []
    for root, _, files in sorted(os.walk(folder)):
        for name in sorted(files):
            path = os.path.join(root, name)
            rel = os.path.relpath(path, folder).replace(os.sep, "/")
            with open(path, "rb") as f:
                records.append(b"KMFILE:" + rel.encode() + b"\n" + f.read())
    if open_sub:
        records.append(b"KMFILE:@open\n" + open_sub.encode())
    return b"\n".join(records)


def dicom():
    """A series written by the DICOM tests' own writer (tests/dicom_series.py,
    pydicom) and single slices from python3-pydicom's test files."""
    try:
        import numpy as np
        import pydicom
        from pydicom.uid import RLELossless
    except ImportError:
        return
    sys.path.insert(0, os.path.dirname(HERE))
    from dicom_series import write_dicom_series
    volume = (np.arange(3 * 4 * 5, dtype=np.int16).reshape(3, 4, 5) * 37 - 900)
    tmp = tempfile.mkdtemp(prefix="keymesh-corpus-")
    names = ["s0", "s1", "s2"]
    series = os.path.join(tmp, "ct")
    write_dicom_series(series, volume, names=names)
    put("dicom", "series_int16_scaled", pack_folder(series))
    oblique = os.path.join(tmp, "oblique")
    s = 0.5 ** 0.5
    write_dicom_series(oblique, volume[:2], orientation=(s, s, 0, 0, 0, -1), step=1.25, slope=1, intercept=0,
                       names=names[:2])
    put("dicom", "series_oblique_unscaled", pack_folder(oblique))
    rle = os.path.join(tmp, "rle")
    write_dicom_series(rle, volume[:2], names=names[:2])
    for name in names[:2]:
        ds = pydicom.dcmread(os.path.join(rle, name))
        ds.compress(RLELossless)
        ds.save_as(os.path.join(rle, name))
    put("dicom", "series_rle", pack_folder(rle))
    # One-slice series in other transfer syntaxes (explicit big endian, RLE,
    # JPEG-LS, JPEG 2000): python3-pydicom's test data, as Debian ships it.
    data = os.path.join(os.path.dirname(pydicom.__file__), "data", "test_files")
    for name in ("MR_small_bigendian.dcm", "MR_small_RLE.dcm", "MR_small_jpeg_ls_lossless.dcm",
                 "MR_small_jp2klossless.dcm"):
        path = os.path.join(data, name)
        if os.path.exists(path):
            with open(path, "rb") as f:
                put("dicom", "pydicom_" + name[:-4], b"KMFILE:" + name.encode() + b"\n" + f.read())


def zarr_arrays():
    """Arrays written with python3-zarr as the Zarr tests write theirs
    (tests/cli/test_formats_cli.py): every codec, byte orders, absent chunks,
    '/' separators, an OME-Zarr image read whole and by level."""
    try:
        import json
        import numcodecs
        import numpy as np
        import zarr
    except ImportError:
        return
    tmp = tempfile.mkdtemp(prefix="keymesh-corpus-")
    volume = np.arange(3 * 4 * 5, dtype=np.float64).reshape(3, 4, 5)
    jobs = (("none_f4", "<f4", None, "."), ("zlib_i2_big", ">i2", numcodecs.Zlib(level=5), "."),
            ("gzip_u2_nested", "<u2", numcodecs.GZip(level=5), "/"),
            ("blosc_lz4_u1", "|u1", numcodecs.Blosc(cname="lz4", clevel=5, shuffle=numcodecs.Blosc.SHUFFLE), "."),
            ("blosc_zstd_f8", ">f8", numcodecs.Blosc(cname="zstd", clevel=3, shuffle=numcodecs.Blosc.BITSHUFFLE), "."))
    for name, dtype, codec, sep in jobs:
        path = os.path.join(tmp, name + ".zarr")
        z = zarr.open(path, mode="w", shape=volume.shape, chunks=(2, 3, 4), dtype=dtype, compressor=codec,
                      fill_value=7, dimension_separator=sep)
        z[:] = volume.astype(dtype)
        absent = os.path.join(path, "1/1/1" if sep == "/" else "1.1.1")
        if os.path.exists(absent):  # one chunk left to fill_value
            os.remove(absent)
        put("zarr", name, pack_folder(path))
    image = os.path.join(tmp, "image.ome.zarr")
    os.makedirs(image)
    with open(os.path.join(image, ".zgroup"), "w") as f:
        json.dump({"zarr_format": 2}, f)
    for level, data in (("0", volume[None]), ("1", volume[None, ::2, ::2, ::2])):
        z = zarr.open(os.path.join(image, level), mode="w", shape=data.shape, chunks=(1, 2, 3, 3), dtype="<f4")
        z[:] = data
    axes = [{"name": "c", "type": "channel"}] + [{"name": n, "type": "space"} for n in "zyx"]
    datasets = [{"path": "0", "coordinateTransformations": [{"type": "scale", "scale": [1, 2.0, 0.5, 0.25]},
                                                            {"type": "translation", "translation": [0, 3, 2, 1]}]},
                {"path": "1", "coordinateTransformations": [{"type": "scale", "scale": [1, 4.0, 1.0, 0.5]}]}]
    with open(os.path.join(image, ".zattrs"), "w") as f:
        json.dump({"multiscales": [{"version": "0.4", "axes": axes, "datasets": datasets}]}, f)
    put("zarr", "ome_image", pack_folder(image))
    put("zarr", "ome_level_1", pack_folder(image, open_sub="1"))


def vtk_written():
    """Files from VTK's own writers in every mode (when python3-vtk9 is importable)."""
    try:
        import vtk
    except ImportError:
        return
    tmp = tempfile.mkdtemp(prefix="keymesh-corpus-")
    img = vtk.vtkRTAnalyticSource()
    img.SetWholeExtent(0, 3, 0, 2, 0, 2)
    img.Update()
    sphere = vtk.vtkSphereSource()
    sphere.SetThetaResolution(4)
    sphere.SetPhiResolution(3)
    sphere.Update()
    tets = vtk.vtkUnstructuredGrid()
    p = vtk.vtkPoints()
    for q in TET_PTS:
        p.InsertNextPoint(*q)
    tets.SetPoints(p)
    tets.InsertNextCell(vtk.VTK_TETRA, 4, [0, 1, 2, 3])
    jobs = (("vti", vtk.vtkXMLImageDataWriter, img.GetOutput()), ("vtp", vtk.vtkXMLPolyDataWriter, sphere.GetOutput()),
            ("vtu", vtk.vtkXMLUnstructuredGridWriter, tets))
    for target, cls, data in jobs:
        for mode in ("ascii", "binary", "appended_raw", "appended_b64"):
            for compress in (False, True):
                if mode == "ascii" and compress:
                    continue
                w = cls()
                w.SetInputData(data)
                out = os.path.join(tmp, "x." + target)
                w.SetFileName(out)
                if mode == "ascii":
                    w.SetDataModeToAscii()
                elif mode == "binary":
                    w.SetDataModeToBinary()
                else:
                    w.SetDataModeToAppended()
                    w.SetEncodeAppendedData(mode == "appended_b64")
                if compress:
                    w.SetCompressorTypeToZLib()
                else:
                    w.SetCompressorTypeToNone()
                w.Write()
                with open(out, "rb") as f:
                    put(target, "vtk_%s%s.%s" % (mode, "_zlib" if compress else "", target), f.read())
    w = vtk.vtkUnstructuredGridWriter()
    w.SetInputData(tets)
    w.SetFileName(os.path.join(tmp, "x.vtk"))
    w.SetFileTypeToBinary()
    w.Write()
    with open(os.path.join(tmp, "x.vtk"), "rb") as f:
        put("legacy_vtk", "vtk_writer_binary.vtk", f.read())


if __name__ == "__main__":
    volumes()
    meshes()
    dicom()
    zarr_arrays()
    vtk_written()
    for t in sorted(os.listdir(CORPUS)):
        print(t, len(os.listdir(os.path.join(CORPUS, t))))
    sys.exit(0)
