"""keymesh.contour against scikit-image's marching_cubes on the same arrays:
the same point and triangle counts and the same points (within 1e-4).

The triangles themselves differ: the two case tables split some cube
polygons along different diagonals (about half of the triangles of a
sphere), and skimage winds its triangles the other way (its right-hand
normals point to higher values, ours to lower)."""
import numpy as np
import pytest

import keymesh
from conftest import match_points, noise_field, smooth_random_field, sphere_field

measure = pytest.importorskip("skimage.measure")

# Non-integer isovalues that no sample equals.
CASES = [
    ("sphere", sphere_field, 12.37),
    ("smooth", smooth_random_field, 0.0123),
    ("noise", noise_field, 0.0123),
]


def _skimage(field, iso, method, **kw):
    verts, faces, normals, values = measure.marching_cubes(field, iso, method=method, allow_degenerate=True, **kw)
    return verts, faces


@pytest.mark.parametrize("name,make,iso", CASES)
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_same_counts_and_points_as_lorensen(name, make, iso, dtype):
    """skimage's method='lorensen' (the classic case table) has our counts
    and points, ambiguous configurations included (white noise)."""
    field = make().astype(dtype)
    mesh = keymesh.contour(field, iso)
    verts, faces = _skimage(field, iso, "lorensen")
    assert mesh.points.shape == verts.shape and mesh.cells.shape == faces.shape
    match_points(verts, mesh.points)


@pytest.mark.parametrize("name,make,iso", CASES[:1])
def test_same_counts_and_points_as_lewiner_without_ambiguity(name, make, iso):
    """skimage's default method='lewiner' (Marching Cubes 33) agrees too
    where no cube is ambiguous enough for it to add an interior vertex."""
    field = make()
    mesh = keymesh.contour(field, iso)
    verts, faces = _skimage(field, iso, "lewiner")
    assert mesh.points.shape == verts.shape and mesh.cells.shape == faces.shape
    match_points(verts, mesh.points)


@pytest.mark.parametrize("make", [smooth_random_field, noise_field])
def test_lewiner_differs_only_by_extra_interior_points_when_ambiguous(make):
    """Where cubes are ambiguous MC33 adds interior vertices and more
    triangles; every one of our points is still one of its points."""
    field = make()
    iso = 0.0123
    mesh = keymesh.contour(field, iso)
    verts, faces = _skimage(field, iso, "lewiner")
    assert len(verts) > len(mesh.points) and len(faces) > len(mesh.cells)
    from scipy.spatial import cKDTree

    dist, _ = cKDTree(verts).query(mesh.points)
    assert dist.max() <= 1e-4


def test_allow_degenerate_false_drops_nothing_here():
    field = sphere_field()
    mesh = keymesh.contour(field, 12.37)
    verts, faces, _, _ = measure.marching_cubes(field, 12.37, method="lorensen", allow_degenerate=False)
    assert faces.shape == mesh.cells.shape


def test_spacing_matches_skimage():
    field = sphere_field()
    spacing = (0.5, 1.25, 2.0)
    origin = (3.0, -1.0, 0.5)
    mesh = keymesh.contour(field, 12.37, spacing=spacing, origin=origin)
    verts, faces = _skimage(field, 12.37, "lorensen", spacing=spacing)
    match_points(verts + np.array(origin), mesh.points)


def test_triangles_face_lower_values():
    """Right-hand-rule normals point to lower values: towards the centre of
    the distance field; and the averaged normals agree with the triangles."""
    center = np.array([20.3, 17.9, 22.6])
    mesh = keymesh.contour(sphere_field(center=tuple(center)), 12.37)
    tri = mesh.points[mesh.cells.astype(np.int64)]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    outward = tri.mean(axis=1) - center
    assert np.all(np.einsum("ij,ij->i", n, outward) < 0)
    normals = mesh.point_data["Normals"]
    radial = (mesh.points - center) / np.linalg.norm(mesh.points - center, axis=1)[:, None]
    assert np.all(np.einsum("ij,ij->i", normals, radial) < -0.9)
    # skimage winds the other way round.
    verts, faces = _skimage(sphere_field(center=tuple(center)), 12.37, "lorensen")
    tri = verts[faces]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert np.all(np.einsum("ij,ij->i", n, tri.mean(axis=1) - center) > 0)
