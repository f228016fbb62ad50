"""read / write / check, against the CLI and meshio."""
import json
import os
import subprocess

import numpy as np
import pytest

import keymesh
from conftest import match_points, oriented_faces, sphere_field

CLI = os.environ.get("KEYMESH")


@pytest.fixture(scope="module")
def mesh():
    return keymesh.contour(sphere_field(), 12.37)


@pytest.mark.parametrize("ext", ["vtp", "ply", "obj", "stl"])
def test_mesh_round_trip(tmp_path, mesh, ext):
    path = tmp_path / f"m.{ext}"
    keymesh.write(mesh, path)
    back = keymesh.read(path)
    assert isinstance(back, keymesh.Mesh) and back.cells.shape == mesh.cells.shape
    p = match_points(mesh.points, back.points, tol=1e-6)
    assert oriented_faces(p[mesh.cells.astype(np.int64)]) == oriented_faces(back.cells)
    if ext in ("vtp", "ply"):
        np.testing.assert_array_equal(back.point_data["Normals"][p], mesh.point_data["Normals"])


@pytest.mark.parametrize("ext", ["vti", "nrrd"])
def test_volume_round_trip(tmp_path, ext):
    f = sphere_field().astype(np.float32)
    path = tmp_path / f"v.{ext}"
    keymesh.write(f, path, spacing=(0.5, 1, 2), origin=(1, 2, 3))
    vol = keymesh.read(path)
    assert isinstance(vol, keymesh.Volume)
    assert vol.shape == f.shape and np.array_equal(vol.array, f)
    assert vol.spacing == (0.5, 1.0, 2.0) and vol.origin == (1.0, 2.0, 3.0)
    keymesh.write(vol, tmp_path / f"again.{ext}")
    assert np.array_equal(keymesh.read(tmp_path / f"again.{ext}").array, f)


def test_raw_volume(tmp_path):
    f = sphere_field().astype(np.uint16)
    path = tmp_path / "v.raw"
    f.tofile(path)  # C order: axis 2 varies fastest, so the file's x is axis 2
    vol = keymesh.read(path, dims=f.shape[::-1], dtype="uint16", spacing=(1, 1, 2))
    assert np.array_equal(vol.array, f.transpose())


def test_check_has_the_cli_report_keys_and_values(tmp_path, mesh):
    report = keymesh.check(mesh)
    assert report["closed_manifold"] is True and report["boundary_edges"] == 0
    # Euler: V - E + F with E = 3F/2 on a closed triangle mesh.
    assert report["edges"] * 2 == 3 * report["cells"]
    assert report["points"] - report["edges"] + report["cells"] == report["euler_characteristic"]
    if not CLI or not os.path.exists(CLI):
        pytest.skip("KEYMESH (the CLI) not given")
    path = tmp_path / "m.vtp"
    keymesh.write(mesh, path)
    subprocess.run([CLI, "check", str(path), "--report", str(tmp_path / "r.json")], check=True,
                   capture_output=True)
    cli = json.loads((tmp_path / "r.json").read_text())
    for key, value in report.items():
        assert cli[key] == value, key


def test_check_open_and_polygon_meshes():
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0]], np.float32)
    quad_and_tri = keymesh.Mesh(pts, np.array([0, 1, 2, 3, 1, 4, 2]), offsets=np.array([0, 4, 7]))
    r = keymesh.check(quad_and_tri)
    assert r["cells"] == 2 and r["boundary_edges"] == 5 and not r["closed_manifold"]
    assert keymesh.check(keymesh.Mesh(pts, np.array([[0, 1, 2, 3]])))["cells"] == 1


def test_meshio_round_trip(tmp_path, mesh):
    meshio = pytest.importorskip("meshio")
    m = mesh.to_meshio()
    assert isinstance(m, meshio.Mesh) and m.cells[0].type == "triangle"
    back = keymesh.Mesh.from_meshio(m)
    assert np.array_equal(back.points, mesh.points) and np.array_equal(back.cells, mesh.cells)
    assert np.array_equal(back.point_data["Normals"], mesh.point_data["Normals"])
    # A file meshio writes is read by keymesh.
    meshio.write(tmp_path / "x.ply", m)
    assert keymesh.read(tmp_path / "x.ply").cells.shape == mesh.cells.shape
    pts = np.zeros((5, 3), np.float32)
    mixed = meshio.Mesh(pts, [("triangle", np.array([[0, 1, 2]])), ("quad", np.array([[0, 1, 3, 4]]))])
    km = keymesh.from_meshio(mixed)
    assert km.offsets.tolist() == [0, 3, 7] and km.n_cells == 2
    assert [c.type for c in km.to_meshio().cells] == ["triangle", "quad"]
