"""keymesh reads what VTK's vtkXMLImageDataWriter writes, in every mode.

For every scalar type keymesh supports, every data mode (ascii, inline
binary, appended raw, appended base64), with and without zlib compression,
both header types and both byte orders, VTK writes a .vti of values the test
chose; `keymesh convert` turns it into .raw (the samples, native order) and
`keymesh info --report` gives dims, type, range, spacing and origin. The
samples must be bit-identical to the numpy array VTK was given, and the
geometry that of the vtkImageData (its extent does not start at 0, so the
origin must move). Compressors keymesh does not implement (LZ4, LZMA) and
multi-component arrays are refused by name with exit 1. And keymesh's own
.vti is read back by VTK with the same samples.
"""
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import KEYMESH, check, finish, require_vtk, run, tempdir  # noqa: E402

require_vtk()
import numpy as np  # noqa: E402
import vtk  # noqa: E402
from vtk.util import numpy_support as ns  # noqa: E402

D = tempdir()
EXTENT = (2, 6, -1, 2, 3, 5)  # 5 x 4 x 3 points, lower corner not at 0
DIMS = (EXTENT[1] - EXTENT[0] + 1, EXTENT[3] - EXTENT[2] + 1, EXTENT[5] - EXTENT[4] + 1)
SPACING = (0.5, 1.25, 2.0)
ORIGIN = (-3.0, 4.5, 10.0)
TYPES = {  # keymesh's name: numpy dtype
    "int8": np.int8, "uint8": np.uint8, "int16": np.int16, "uint16": np.uint16, "int32": np.int32,
    "float32": np.float32, "float64": np.float64,
}


def values(dtype):
    """Distinct samples over the type's range, its extremes included, x fastest."""
    n = DIMS[0] * DIMS[1] * DIMS[2]
    if np.issubdtype(dtype, np.integer):
        info = np.iinfo(dtype)
        v = np.linspace(info.min, info.max, n).round().astype(dtype)
        v[0], v[-1] = info.min, info.max
    else:
        v = (np.arange(n, dtype=np.float64) * 1.37 - 20.0).astype(dtype)
        v[3] = np.finfo(dtype).max
        v[4] = np.finfo(dtype).tiny
    return v


def image(dtype):
    img = vtk.vtkImageData()
    img.SetExtent(*EXTENT)
    img.SetSpacing(*SPACING)
    img.SetOrigin(*ORIGIN)
    arr = ns.numpy_to_vtk(values(dtype), deep=True)
    if dtype == np.int8:  # numpy_to_vtk maps int8 to VTK_CHAR; keymesh reads both as Int8
        signed = vtk.vtkSignedCharArray()
        signed.DeepCopy(arr)
        arr = signed
    arr.SetName("field")
    img.GetPointData().SetScalars(arr)
    return img


def write_vti(img, path, mode, compressor, header64, big):
    w = vtk.vtkXMLImageDataWriter()
    w.SetInputData(img)
    w.SetFileName(path)
    {"ascii": w.SetDataModeToAscii, "binary": w.SetDataModeToBinary}.get(mode, w.SetDataModeToAppended)()
    if mode.startswith("appended"):
        w.SetEncodeAppendedData(mode == "appended_base64")
    {"none": w.SetCompressorTypeToNone, "zlib": w.SetCompressorTypeToZLib, "lz4": w.SetCompressorTypeToLZ4,
     "lzma": w.SetCompressorTypeToLZMA}[compressor]()
    w.SetHeaderTypeToUInt64() if header64 else w.SetHeaderTypeToUInt32()
    w.SetByteOrderToBigEndian() if big else w.SetByteOrderToLittleEndian()
    assert w.Write() == 1, path


def keymesh_facts(path):
    r = os.path.join(D, "info.json")
    run("info", path, "--report", r)
    with open(r) as f:
        return json.load(f)


def every_mode_every_type():
    cases = 0
    for name, dtype in TYPES.items():
        expected = values(dtype)
        img = image(dtype)
        for mode in ("ascii", "binary", "appended_raw", "appended_base64"):
            for compressor in ("none", "zlib"):
                for header64 in (False, True):
                    for big in (False, True):
                        tag = f"{name}-{mode}-{compressor}-{'64' if header64 else '32'}-{'big' if big else 'little'}"
                        path = os.path.join(D, tag + ".vti")
                        write_vti(img, path, mode, compressor, header64, big)
                        facts = keymesh_facts(path)
                        assert facts["dims"] == list(DIMS), (tag, facts)
                        assert facts["type"] == name, (tag, facts)
                        assert facts["spacing"] == list(SPACING), (tag, facts)
                        lower = [ORIGIN[a] + EXTENT[2 * a] * SPACING[a] for a in range(3)]
                        assert np.allclose(facts["origin"], lower, rtol=0, atol=1e-12), (tag, facts, lower)
                        raw = os.path.join(D, tag + ".raw")
                        run("convert", path, "-o", raw, "-q")
                        got = np.fromfile(raw, dtype=dtype)
                        assert got.tobytes() == expected.tobytes(), (tag, got[:8], expected[:8])
                        finite = expected[np.isfinite(expected.astype(np.float64))].astype(np.float64)
                        assert facts["range"] == [finite.min(), finite.max()], (tag, facts["range"])
                        os.remove(path)
                        os.remove(raw)
                        cases += 1
    print(f"        {cases} files written by VTK read back exactly")


def unsupported_refused_by_name():
    img = image(np.float32)
    for compressor, named in (("lz4", "vtkLZ4DataCompressor"), ("lzma", "vtkLZMADataCompressor")):
        path = os.path.join(D, compressor + ".vti")
        write_vti(img, path, "appended_raw", compressor, False, False)
        p = subprocess.run([KEYMESH, "info", path], capture_output=True, text=True)
        assert p.returncode == 1 and path in p.stderr and named in p.stderr, p.stderr
    vec = vtk.vtkImageData()
    vec.SetDimensions(3, 3, 3)
    arr = ns.numpy_to_vtk(np.zeros((27, 3), dtype=np.float32), deep=True)
    arr.SetName("v")
    vec.GetPointData().SetScalars(arr)
    path = os.path.join(D, "vector.vti")
    write_vti(vec, path, "binary", "none", False, False)
    p = subprocess.run([KEYMESH, "info", path], capture_output=True, text=True)
    assert p.returncode == 1 and path in p.stderr and "3 components" in p.stderr, p.stderr


def vtk_reads_keymesh_volumes():
    for name, dtype in TYPES.items():
        src = os.path.join(D, f"src-{name}.vti")
        write_vti(image(dtype), src, "appended_raw", "none", False, False)
        for ext in (".vti",):  # (VTK 9.1's vtkNrrdReader here is the MPI one, which needs a controller)
            out = os.path.join(D, f"km-{name}{ext}")
            run("convert", src, "-o", out, "-q")
            reader = vtk.vtkXMLImageDataReader()
            reader.SetFileName(out)
            reader.Update()
            got = reader.GetOutput()
            assert got.GetDimensions() == DIMS, (name, ext, got.GetDimensions())
            assert np.allclose(got.GetSpacing(), SPACING), (name, ext, got.GetSpacing())
            data = ns.vtk_to_numpy(got.GetPointData().GetScalars())
            assert data.astype(np.float64).tobytes() == values(dtype).astype(np.float64).tobytes(), (name, ext)


check("every scalar type x mode x compression x header x byte order of vtkXMLImageDataWriter", every_mode_every_type)
check("LZ4, LZMA and vector arrays: exit 1 naming the file and the reason", unsupported_refused_by_name)
check("VTK reads keymesh's .vti with the same samples", vtk_reads_keymesh_volumes)
finish()
