"""keymesh.contour: layouts, dtypes, options, and the closed sphere."""
import numpy as np
import pytest

import keymesh
from conftest import match_points, noise_field, oriented_faces, smooth_random_field, sphere_field

ISO = 12.37


def same_mesh(a, b):
    """Equal as meshes: same point set and the same oriented triangles."""
    p = match_points(a.points, b.points)
    assert oriented_faces(p[a.cells.astype(np.int64)]) == oriented_faces(b.cells)


def test_sphere_is_closed_manifold_with_expected_euler():
    mesh = keymesh.contour(sphere_field(), ISO)
    assert mesh.points.dtype == np.float32 and mesh.points.shape[1] == 3
    assert mesh.cells.shape[1] == 3 and mesh.cells.dtype.kind == "u"
    report = keymesh.check(mesh)
    assert report["closed_manifold"] and report["euler_characteristic"] == 2 and report["components"] == 1
    # Every point lies on the isosurface up to linear interpolation error.
    r = np.linalg.norm(mesh.points - np.array([20.3, 17.9, 22.6]), axis=1)
    assert np.abs(r - ISO).max() < 0.05
    assert np.abs(mesh.point_data["scalars"] - ISO).max() < 1e-4


def test_memory_layouts():
    """C order, Fortran order, strided views and other byte orders give the
    same mesh. A C-order array is contoured with its axes reversed (no copy)
    by the mirrored case table, so its cubes split their polygons as the
    Fortran-order walk does (before, about half split along the other
    diagonal); white noise has every case, averaged normals follow."""
    f = smooth_random_field()
    ref = keymesh.contour(f, 0.0123)
    same_mesh(keymesh.contour(np.asfortranarray(f), 0.0123), ref)
    noise = noise_field()
    for normals in ("none", "average", "gradient"):
        c = keymesh.contour(np.ascontiguousarray(noise), 0.1, normals=normals)
        fortran = keymesh.contour(np.asfortranarray(noise), 0.1, normals=normals)
        same_mesh(c, fortran)
        if normals != "none":  # the same vectors, summed (average) in another cube order
            p = match_points(c.points, fortran.points)
            assert np.abs(c.point_data["Normals"] - fortran.point_data["Normals"][p]).max() < 1e-5, normals
    # Non-contiguous views: a strided slice and a transposed copy's transpose.
    big = np.zeros((f.shape[0] * 2, f.shape[1], f.shape[2] + 3))
    big[::2, :, 1:-2] = f
    view = big[::2, :, 1:-2]
    assert not view.flags.c_contiguous and not view.flags.f_contiguous
    same_mesh(keymesh.contour(view, 0.0123), ref)
    # Big-endian samples.
    same_mesh(keymesh.contour(f.astype(">f8"), 0.0123), ref)


def test_smooth_field_has_no_nonmanifold_edges_in_either_order():
    """Both walking orders give manifold edges (a field where an older case table
    drew the same diagonal from two cubes: an edge with four triangles)."""
    f = smooth_random_field()
    for layout in (np.asfortranarray(f), np.ascontiguousarray(f)):
        assert keymesh.check(keymesh.contour(layout, 0.0123))["nonmanifold_edges"] == 0


@pytest.mark.parametrize("dtype", ["uint8", "int8", "uint16", "int16", "int32", "float32", "float64"])
def test_every_supported_dtype(dtype):
    """An integer volume contoured at a half-integer gives the mesh of the
    same samples as float64."""
    info = np.iinfo(dtype) if np.dtype(dtype).kind in "iu" else None
    f = sphere_field() * 4.0
    if info is not None:
        f = np.clip(np.round(f), info.min, info.max)
    iso = 40.5
    same_mesh(keymesh.contour(f.astype(dtype), iso), keymesh.contour(f.astype(np.float64), iso))


def test_volume_is_read_in_place_and_equals_the_array_path():
    f = sphere_field().astype(np.float32)
    vol = keymesh.Volume(f, spacing=(1, 2, 3), origin=(4, 5, 6))
    assert vol.shape == f.shape and np.array_equal(vol.array, f)
    a = keymesh.contour(vol, ISO)
    assert keymesh.last_contour_info["zero_copy"] is True
    # A Volume is in Fortran order (x fastest): the same mesh, array for array.
    b = keymesh.contour(np.asfortranarray(f), ISO, spacing=(1, 2, 3), origin=(4, 5, 6))
    assert keymesh.last_contour_info["zero_copy"] is True  # numpy arrays are read in place too
    assert np.array_equal(a.points, b.points) and np.array_equal(a.cells, b.cells)
    # Filling a zero Volume in place.
    z = keymesh.Volume.zeros(f.shape, "float32")
    z.array[...] = f
    c = keymesh.contour(z, ISO)
    assert np.array_equal(c.cells, keymesh.contour(np.asfortranarray(f), ISO).cells)
    with pytest.raises(ValueError, match="Volume carries its own spacing"):
        keymesh.contour(vol, ISO, spacing=(7, 7, 7))


def test_options_and_threads_do_not_change_the_mesh():
    f = smooth_random_field()
    ref = keymesh.contour(f, 0.0123, threads=1)
    for kw in ({"threads": 2}, {"weld": "keyreduce-sort"}, {"threads": 3, "weld": "keyreduce-sort"}):
        m = keymesh.contour(f, 0.0123, **kw)
        assert np.array_equal(m.points, ref.points) and np.array_equal(m.cells, ref.cells)
        assert np.array_equal(m.point_data["Normals"], ref.point_data["Normals"])
    same_mesh(keymesh.contour(f, 0.0123, weld="vertexweld"), ref)


def test_normals_options():
    f = sphere_field()
    assert set(keymesh.contour(f, ISO, normals="none").point_data) == {"scalars"}
    assert set(keymesh.contour(f, ISO, normals=None).point_data) == {"scalars"}
    g = keymesh.contour(f, ISO, normals="gradient").point_data["Normals"]
    a = keymesh.contour(f, ISO).point_data["Normals"]
    assert np.allclose(np.linalg.norm(g, axis=1), 1, atol=1e-5)
    assert np.einsum("ij,ij->i", g, a).min() > 0.9


def test_several_isovalues_are_the_union():
    f = sphere_field()
    both = keymesh.contour(f, [8.5, ISO])
    a = keymesh.contour(f, 8.5)
    b = keymesh.contour(f, ISO)
    assert both.n_points == a.n_points + b.n_points and both.n_cells == a.n_cells + b.n_cells
    assert keymesh.check(both)["components"] == 2
    assert keymesh.contour(f, np.array([ISO])).n_points == b.n_points


def test_no_surface_gives_empty_arrays():
    m = keymesh.contour(np.zeros((4, 5, 6), np.float32), 0.5)
    assert m.points.shape == (0, 3) and m.cells.shape == (0, 3)


def test_coarsen_and_curvature():
    f = sphere_field()
    fine = keymesh.contour(f, ISO)
    coarse = keymesh.contour(f, ISO, coarsen=True)
    assert 0 < len(coarse.cells) < len(fine.cells)
    assert keymesh.check(coarse)["duplicate_points"] == 0
    curved = keymesh.contour(f, ISO, curvature=True)
    assert curved.point_data["mean_curvature"].shape == (len(curved.points),)


def test_scalars_switch():
    """scalars=True (the default, as before the switch) carries the
    interpolated value, which on the surface is the isovalue of the point's
    own surface; scalars=False leaves only that field out: the same points,
    triangles and other fields, byte for byte, with every weld plan and with
    coarsening."""
    f = sphere_field().astype(np.float32)
    isos = [ISO, ISO + 3.25]
    default = keymesh.contour(f, isos, normals="gradient")
    assert set(default.point_data) == {"scalars", "Normals"}
    # Each point's scalar is one of the isovalues, and the point lies on it.
    s = default.point_data["scalars"].astype(np.float64)
    nearest = np.array(isos)[np.abs(s[:, None] - np.array(isos)[None, :]).argmin(axis=1)]
    assert np.abs(s - nearest).max() < 1e-4
    r = np.linalg.norm(default.points - np.array([20.3, 17.9, 22.6]), axis=1)
    assert np.abs(r - nearest).max() < 0.05
    assert np.array_equal(keymesh.contour(f, isos, normals="gradient", scalars=True).point_data["scalars"],
                          default.point_data["scalars"])
    for weld in ("keyreduce", "keyreduce-sort", "vertexweld"):
        for coarsen in (False, True):
            on = keymesh.contour(f, isos, normals="gradient", weld=weld, coarsen=coarsen)
            off = keymesh.contour(f, isos, normals="gradient", weld=weld, coarsen=coarsen, scalars=False)
            assert set(off.point_data) == {"Normals"}, (weld, coarsen)
            assert np.array_equal(off.points, on.points) and np.array_equal(off.cells, on.cells), (weld, coarsen)
            assert np.array_equal(off.point_data["Normals"], on.point_data["Normals"]), (weld, coarsen)
    # A Volume's field is named after it; scalars=False drops it too.
    vol = keymesh.Volume(f, name="distance")
    assert set(keymesh.contour(vol, ISO, normals="none").point_data) == {"distance"}
    assert keymesh.contour(vol, ISO, normals="none", scalars=False).point_data == {}


def test_positions_only_are_written_into_the_modules_own_arrays():
    """normals="none" without coarsening or curvature: the structured plan
    writes into arrays the module allocates (no zero-fill) and hands to
    numpy; the same bytes as the sort plan's mesh, in C order (mirrored
    back) and Fortran order, with and without scalars, and the arrays own
    their memory."""
    f = smooth_random_field().astype(np.float32)
    for layout in (np.ascontiguousarray(f), np.asfortranarray(f)):
        for scalars in (True, False):
            own = keymesh.contour(layout, [0.0123, 0.3], normals="none", scalars=scalars)
            ref = keymesh.contour(layout, [0.0123, 0.3], normals="none", scalars=scalars, weld="keyreduce-sort")
            assert own.points.dtype == np.float32 and own.cells.dtype == np.uint32
            assert own.points.shape == ref.points.shape and own.cells.shape == ref.cells.shape
            assert np.array_equal(own.points, ref.points) and np.array_equal(own.cells, ref.cells)
            assert own.points.flags.writeable and own.cells.flags.c_contiguous
            if scalars:
                assert np.array_equal(own.point_data["scalars"], ref.point_data["scalars"])
            else:
                assert own.point_data == {}
    cells = keymesh.contour(f, 0.0123, normals="none").cells
    import gc
    gc.collect()
    assert cells.max() > 0 and cells.base is not None
    empty = keymesh.contour(np.zeros((4, 5, 6), np.float32), 0.5, normals="none")
    assert empty.points.shape == (0, 3) and empty.cells.shape == (0, 3)


def test_check_self_intersections():
    """keymesh.check(..., self_intersections=True): none on a contour of white
    noise (the table's shortest splits), two on a tetrahedron with a planted spike."""
    from conftest import noise_field

    report = keymesh.check(keymesh.contour(noise_field(), 0.1), self_intersections=True)
    assert report["self_intersections"] == 0 and report["self_intersecting_pairs"] == []
    assert report["zero_area_triangles"] == 0 and report["cells"] > 1000
    assert "self_intersections" not in keymesh.check(keymesh.contour(noise_field(), 0.1))
    points = np.array([(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (0.2, 0.2, -1), (0.25, 0.2, 2), (0.2, 0.25, 2)],
                      np.float32)
    cells = np.array([(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3), (4, 5, 6)], np.uint32)
    report = keymesh.check(keymesh.Mesh(points, cells), self_intersections=True)
    assert report["self_intersections"] == 2 and report["self_intersecting_pairs"] == [[0, 4], [3, 4]]
