"""DICOM and Zarr folders through keymesh.read, .glb through keymesh.write
(the library's format table; the CLI side is tests/cli/test_formats_cli.py)."""
import json
import os
import struct
import sys

import numpy as np
import pytest

import keymesh
from conftest import sphere_field


def test_zarr_folder_reads_with_axis_0_as_x(tmp_path):
    zarr = pytest.importorskip("zarr")
    zyx = sphere_field((9, 8, 7)).astype(np.float32)  # a C-order (z, y, x) array
    z = zarr.open(str(tmp_path / "a.zarr"), mode="w", shape=zyx.shape, chunks=(4, 3, 5), dtype="<f4")
    z[:] = zyx
    vol = keymesh.read(tmp_path / "a.zarr")
    assert isinstance(vol, keymesh.Volume)
    assert np.array_equal(vol.array, zyx.transpose())  # keymesh's axis 0 is x: the Zarr's last axis
    assert vol.spacing == (1.0, 1.0, 1.0)


def test_dicom_folder_reads_with_spacing_and_rescale(tmp_path):
    pytest.importorskip("pydicom")
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    from dicom_series import write_dicom_series
    stored = (np.arange(4 * 5 * 6).reshape(4, 5, 6) * 3 - 20).astype(np.int16)  # (z, rows, columns)
    write_dicom_series(str(tmp_path / "series"), stored, pixel_spacing=(0.5, 0.25), step=3.0, origin=(1, 2, 3),
                       slope=0.5, intercept=7.0)
    vol = keymesh.read(tmp_path / "series")
    assert vol.spacing == (0.25, 0.5, 3.0) and vol.origin == (1.0, 2.0, 3.0)
    assert vol.array.dtype == np.float32
    assert np.array_equal(vol.array, (0.5 * stored.astype(np.float64) + 7).astype(np.float32).transpose())


def test_glb_written_from_python(tmp_path):
    mesh = keymesh.contour(sphere_field((20, 20, 20), (9.5, 9.5, 9.5)), 6.5)
    path = tmp_path / "m.glb"
    keymesh.write(mesh, path)
    data = path.read_bytes()
    magic, version, length, jlen, jtype = struct.unpack_from("<5I", data)
    assert (magic, version, length, jtype) == (0x46546C67, 2, len(data), 0x4E4F534A)
    doc = json.loads(data[20:20 + jlen])
    prim = doc["meshes"][0]["primitives"][0]
    pos = doc["accessors"][prim["attributes"]["POSITION"]]
    assert pos["count"] == len(mesh.points)
    view = doc["bufferViews"][pos["bufferView"]]
    binary = data[28 + jlen:]
    points = np.frombuffer(binary, "<f4", 3 * pos["count"], view["byteOffset"]).reshape(-1, 3)
    assert np.array_equal(points, mesh.points)
    assert pos["min"] == points.min(axis=0).tolist() and pos["max"] == points.max(axis=0).tolist()
