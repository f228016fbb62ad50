"""The CLI's operations as Python functions: tetrahedralize, subdivide, dual,
quality, coarsen, incidence; their progress hook and Ctrl-C.

Expected values come from the mathematics (tet counts and total volume of a
box, subdivision counts from an independent edge count, Q from numpy, the
dual's counts) or from an independent numpy construction (incidence lists);
the CLI's files are read back to check that Python and CLI agree."""
import os
import signal
import subprocess

import numpy as np
import pytest

import keymesh
from conftest import match_points, sphere_field

KEYMESH = os.environ.get("KEYMESH")


def tet_volumes(grid):
    p = np.asarray(grid.points, np.float64)
    c = np.asarray(grid.cells, np.int64)
    a, b, cc, d = p[c[:, 0]], p[c[:, 1]], p[c[:, 2]], p[c[:, 3]]
    return np.einsum("ij,ij->i", np.cross(b - a, cc - a), d - a) / 6.0


def edge_count(cells):
    c = np.asarray(cells, np.int64)
    e = np.concatenate([c[:, [0, 1]], c[:, [1, 2]], c[:, [2, 0]]])
    e.sort(axis=1)
    return len(np.unique(e, axis=0))


@pytest.fixture(scope="module")
def ball():
    # a closed sphere of a field new to these tests: an ellipsoid distance
    i, j, k = np.indices((26, 23, 29), dtype=np.float64)
    return np.sqrt(((i - 12.4) / 1.1) ** 2 + ((j - 11.3) / 0.9) ** 2 + (k - 14.2) ** 2).astype(np.float32)


@pytest.fixture(scope="module")
def surface(ball):
    return keymesh.contour(ball, 8.3, normals="average")


@pytest.mark.parametrize("scheme", [5, 24])
def test_tetrahedralize_counts_and_volume(scheme):
    v = np.random.default_rng(2).random((7, 5, 6)).astype(np.float32)
    spacing = (0.5, 2.0, 1.5)
    grid = keymesh.tetrahedralize(v, scheme, spacing=spacing)
    nx, ny, nz = v.shape
    cubes = (nx - 1) * (ny - 1) * (nz - 1)
    faces = (nx * (ny - 1) * (nz - 1) + (nx - 1) * ny * (nz - 1) + (nx - 1) * (ny - 1) * nz)
    assert grid.n_cells == scheme * cubes
    assert grid.n_points == (nx * ny * nz if scheme == 5 else nx * ny * nz + faces + cubes)
    vol = tet_volumes(grid)
    assert np.all(vol > 0)
    assert np.isclose(vol.sum(), cubes * np.prod(spacing), rtol=1e-5)
    # point ids run x fastest (axis 0), and the samples are carried
    assert np.allclose(grid.points[1], (0.5, 0, 0)) and np.allclose(grid.points[nx], (0, 2.0, 0))
    assert np.array_equal(grid.point_data["scalars"][: nx * ny * nz], v.reshape(-1, order="F"))


@pytest.mark.skipif(not KEYMESH, reason="KEYMESH (the CLI) is not set")
def test_tetrahedralize_same_as_cli(tmp_path):
    v = np.random.default_rng(3).random((6, 7, 5)).astype(np.float32)
    keymesh.write(v, tmp_path / "v.vti")
    subprocess.run([KEYMESH, "tetrahedralize", str(tmp_path / "v.vti"), "-o", str(tmp_path / "t.vtu"),
                    "--scheme", "24", "--quiet"], check=True)
    cli = keymesh.read(tmp_path / "t.vtu")
    py = keymesh.tetrahedralize(keymesh.read(tmp_path / "v.vti"), 24)
    assert np.array_equal(np.asarray(cli.points), np.asarray(py.points))
    assert np.array_equal(np.asarray(cli.cells, np.int64), np.asarray(py.cells, np.int64))


def test_subdivide_surface(surface):
    out = keymesh.subdivide(surface, 2)
    v, f, e = surface.n_points, surface.n_cells, edge_count(surface.cells)
    v1, f1, e1 = v + e, 4 * f, 2 * e + 3 * f
    assert out.n_cells == 16 * f
    assert out.n_points == v1 + e1
    assert keymesh.check(out)["closed_manifold"]
    # linear: each new point of one level is the midpoint of its parent edge
    one = keymesh.subdivide(surface, 1)
    c = np.asarray(surface.cells, np.int64)
    pairs = np.unique(np.sort(np.concatenate([c[:, [0, 1]], c[:, [1, 2]], c[:, [2, 0]]]), axis=1), axis=0)
    mids = (surface.points[pairs[:, 0]].astype(np.float64) + surface.points[pairs[:, 1]]) / 2
    match_points(one.points[v:], mids, tol=1e-5)
    assert np.array_equal(one.points[:v], surface.points)


def test_subdivide_bezier_stays_round():
    i, j, k = np.indices((30, 30, 30), dtype=np.float64)
    r = np.sqrt((i - 14.5) ** 2 + (j - 15.2) ** 2 + (k - 14.8) ** 2)
    mesh = keymesh.contour(r, 9.0, normals="gradient")
    lin = keymesh.subdivide(mesh, 1)
    bez = keymesh.subdivide(mesh, 1, scheme="bezier")
    c = np.array([14.5, 15.2, 14.8])
    err = lambda m: np.abs(np.linalg.norm(m.points - c, axis=1) - 9.0)[mesh.n_points:].mean()
    assert err(bez) < 0.5 * err(lin)


def test_subdivide_tets():
    grid = keymesh.tetrahedralize(np.zeros((4, 4, 4), np.float32), 5)
    fine = keymesh.subdivide(grid, 1)
    assert fine.n_cells == 8 * grid.n_cells
    vol = tet_volumes(fine)
    assert np.all(vol > 0) and np.isclose(vol.sum(), 27.0, rtol=1e-5)
    with pytest.raises(ValueError, match="bezier"):
        keymesh.subdivide(grid, 1, scheme="bezier")


def test_dual_counts(surface):
    d, stats = keymesh.dual(surface, return_stats=True)
    assert d.n_cells == surface.n_points       # a polygon per point of a closed surface
    assert d.n_points == surface.n_cells       # a centroid per triangle
    assert stats == {"boundary_fans": 0, "nonmanifold_points": 0, "skipped_fans": 0}
    sizes = np.diff(d.offsets)
    # every polygon has as many corners as its point has triangles
    counts = np.bincount(np.asarray(surface.cells, np.int64).reshape(-1), minlength=surface.n_points)
    assert np.array_equal(sizes, counts)


def test_quality_matches_numpy(surface):
    q = keymesh.quality(surface, per_cell=True)
    p = np.asarray(surface.points, np.float64)
    c = np.asarray(surface.cells, np.int64)
    a, b, cc = p[c[:, 0]], p[c[:, 1]], p[c[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, cc - a), axis=1)
    h2 = ((b - a) ** 2).sum(1) + ((cc - b) ** 2).sum(1) + ((a - cc) ** 2).sum(1)
    expect = 4 * np.sqrt(3) * area / h2
    assert np.allclose(q["per_cell"], expect, atol=1e-6)
    assert np.isclose(q["min"], expect.min(), atol=1e-6) and np.isclose(q["mean"], expect.mean(), atol=1e-6)
    assert q["cells"] == len(c) and sum(q["histogram"]) == len(c)
    assert np.isclose(q["fraction_above_0_6"], np.mean(expect > 0.6))


def test_coarsen_equals_contour_coarsen(ball):
    spacing = (0.7, 1.0, 1.3)
    fine = keymesh.contour(ball, 8.3, spacing=spacing, normals="average")
    coarse, stats = keymesh.coarsen(fine, spacing, return_stats=True)
    direct = keymesh.contour(ball, 8.3, spacing=spacing, normals="average", coarsen=True)
    assert coarse.n_points == direct.n_points and coarse.n_cells == direct.n_cells
    p = match_points(coarse.points, direct.points, tol=1e-5)
    assert stats["points_before"] == fine.n_points and stats["triangles_after"] == coarse.n_cells
    assert np.allclose(coarse.point_data["Normals"], direct.point_data["Normals"][p], atol=1e-5)


def test_incidence_matches_numpy(surface):
    offsets, cells, neighbours = keymesh.incidence(surface)
    c = np.asarray(surface.cells, np.int64)
    n = surface.n_points
    corner_cell = np.repeat(np.arange(len(c)), 3)
    order = np.argsort(c.reshape(-1), kind="stable")
    expect_offsets = np.concatenate([[0], np.cumsum(np.bincount(c.reshape(-1), minlength=n))])
    assert np.array_equal(offsets, expect_offsets)
    assert np.array_equal(cells, corner_cell[order])
    edges = {}
    for t, tri in enumerate(c.tolist()):
        for k in range(3):
            edges.setdefault(frozenset((tri[k], tri[(k + 1) % 3])), []).append(t)
    for t in range(0, len(c), max(1, len(c) // 300)):
        for k in range(3):
            others = [x for x in edges[frozenset((c[t, k], c[t, (k + 1) % 3]))] if x != t]
            assert neighbours[t, k] == others[0]


def test_bad_options_raise_like_the_cli(surface):
    v = np.zeros((3, 3, 3), np.float32)
    with pytest.raises(ValueError, match="scheme"):
        keymesh.tetrahedralize(v, 6)
    with pytest.raises(ValueError, match="weld"):
        keymesh.tetrahedralize(v, 24, weld="glue")
    with pytest.raises(ValueError, match="levels"):
        keymesh.subdivide(surface, 9)
    with pytest.raises(ValueError, match="scheme"):
        keymesh.subdivide(surface, 1, scheme="loop")
    with pytest.raises(TypeError, match="progress"):
        keymesh.subdivide(surface, 1, progress=3)
    with pytest.raises(keymesh.Error, match="Normals"):
        keymesh.subdivide(keymesh.Mesh(surface.points, surface.cells), 1, scheme="bezier")
    with pytest.raises(ValueError):
        keymesh.quality(keymesh.Mesh(surface.points, surface.cells + surface.n_points))


def test_progress_reports_stages(surface):
    seen = []
    keymesh.subdivide(surface, 3, progress=lambda stage, f: seen.append((stage, f)))
    fractions = [f for _, f in seen]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0
    assert [s for s, _ in seen][:3] == ["subdivide level 1/3", "subdivide level 2/3", "subdivide level 3/3"]
    seen.clear()
    keymesh.marching_cubes(sphere_field((64, 70, 66), (30.2, 33.1, 31.7)), 20.5,
                           progress=lambda s, f: seen.append((s, f)))
    stages = [s for s, _ in seen]
    assert stages[0].startswith("marching cubes") and stages[-1] == "marching cubes"
    assert stages.count("marching cubes: classify") == 8       # long stages report per block
    fractions = [f for _, f in seen]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0


def test_callback_exception_abandons_the_call(surface):
    def stop(stage, fraction):
        if fraction > 0.4:
            raise RuntimeError("stop here")

    before = surface.points.copy()
    with pytest.raises(RuntimeError, match="stop here"):
        keymesh.subdivide(surface, 3, progress=stop)
    assert np.array_equal(surface.points, before)


def test_ctrl_c_interrupts_cleanly(surface):
    """SIGINT during a call (raised here from inside the progress callback,
    as a key press would raise it) becomes KeyboardInterrupt at the next
    stage boundary; the interpreter and the inputs are intact after."""
    calls = []

    def press_ctrl_c(stage, fraction):
        calls.append(stage)
        if len(calls) == 1:
            signal.raise_signal(signal.SIGINT)

    with pytest.raises(KeyboardInterrupt):
        keymesh.subdivide(surface, 3, progress=press_ctrl_c)
    assert len(calls) == 1
    assert keymesh.subdivide(surface, 1).n_cells == 4 * surface.n_cells


def test_tetrahedralize_a_hexahedral_grid():
    """A Grid of VTK hexahedra (a 3 x 2 x 2 block of unit-ish cells built here
    by hand) goes through the same call: 5 or 24 tets per hexahedron, total
    volume that of the block, cell fields carried to the children."""
    nx, ny, nz = 4, 3, 3
    i, j, k = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    pts = np.stack([i * 1.5, j * 1.0, k * 0.5], axis=-1).reshape(-1, 3).astype(np.float32)
    # Each cell's 8 point ids in VTK's hexahedron order (bottom quad, then
    # top), cells in the points' order (the last index fastest).
    a, b, c = (x.ravel() for x in np.meshgrid(np.arange(nx - 1), np.arange(ny - 1), np.arange(nz - 1), indexing="ij"))
    corners = ((0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1))
    hexes = np.stack([((a + da) * ny + b + db) * nz + c + dc for da, db, dc in corners], axis=1).astype(np.int64)
    label = np.arange(len(hexes), dtype=np.float32)
    grid = keymesh.Grid(pts, hexes, cell_type=12, cell_data={"label": label})
    for scheme in (5, 24):
        tets = keymesh.tetrahedralize(grid, scheme)
        assert tets.n_cells == scheme * len(hexes)
        vol = tet_volumes(tets)
        assert np.all(vol > 0) and np.isclose(vol.sum(), 4.5 * 2.0 * 1.0, rtol=1e-5)
        assert np.array_equal(tets.cell_data["label"], np.repeat(label, scheme))


def test_contour_reports_start_and_end(ball):
    seen = []
    mesh = keymesh.contour(ball, 8.3, progress=lambda s, f: seen.append((s, f)))
    assert seen[0] == ("contour", 0.0) and seen[-1] == ("contour", 1.0) and mesh.n_cells > 0


def test_tetrahedralize_and_dual_report_stages(surface):
    seen = []
    keymesh.tetrahedralize(np.zeros((5, 4, 3), np.float32), 24, progress=lambda s, f: seen.append(s))
    assert "tetrahedralize 24: weld face centres" in seen and seen[-1] == "tetrahedralize"
    seen.clear()
    keymesh.dual(surface, progress=lambda s, f: seen.append(s))
    assert seen == ["dual", "dual: fans", "dual: polygons", "dual"]


def test_ctrl_c_stops_marching_cubes_between_blocks():
    calls = []

    def press_ctrl_c(stage, fraction):
        calls.append(stage)
        if stage == "marching cubes: classify" and calls.count(stage) == 2:
            signal.raise_signal(signal.SIGINT)

    with pytest.raises(KeyboardInterrupt):
        keymesh.marching_cubes(sphere_field((64, 70, 66), (30.2, 33.1, 31.7)), 20.5, progress=press_ctrl_c)
    assert calls.count("marching cubes: classify") == 2 and "marching cubes: generate" not in calls


def test_contour_reports_its_stages_and_can_be_abandoned():
    """keymesh.contour reports classify, triangles and points in order (the
    library's stage boundaries), and a callback that raises at the triangle
    stage abandons the call; the next call is unaffected."""
    field = sphere_field((48, 50, 52), (23.1, 24.2, 25.3))
    seen = []
    mesh = keymesh.contour(field, [10.5, 15.5], normals="average", progress=lambda s, f: seen.append((s, f)))
    stages = [s for s, _ in seen]
    for stage in ("classify", "triangles", "points", "normals"):
        assert stage in stages, stages
    assert stages.index("classify") < stages.index("triangles") < stages.index("points") < stages.index("normals")
    fractions = [f for _, f in seen]
    assert fractions == sorted(fractions)

    def stop(stage, fraction):
        if stage == "triangles":
            raise RuntimeError("abandoned at " + stage)

    with pytest.raises(RuntimeError, match="abandoned at triangles"):
        keymesh.contour(field, [10.5, 15.5], normals="average", progress=stop)
    again = keymesh.contour(field, [10.5, 15.5], normals="average")
    assert np.array_equal(again.points, mesh.points) and np.array_equal(again.cells, mesh.cells)
