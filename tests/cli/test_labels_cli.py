"""End-to-end tests of `keymesh labels` (issue 18) against independent
references: numpy counts of the label map's grid edges and cells,
skimage.measure.euler_number, the divergence theorem for enclosed volumes,
and VTK's reader for the files. Needs python3-vtk9, numpy and scikit-image."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import check, finish, report, require_vtk, run, tempdir  # noqa: E402

require_vtk()
try:
    import numpy as np
    from skimage.measure import euler_number
except ImportError as e:
    print(f"skipped: {e} (install python3-skimage)")
    sys.exit(77)
from vtk.util import numpy_support as ns  # noqa: E402

from kmtest import points_of, read_polydata, triangles_of  # noqa: E402
from mesh_checks import assert_closed_manifold  # noqa: E402

D = tempdir()
NRRD_TYPES = {np.uint8: "uint8", np.int8: "int8", np.uint16: "uint16", np.int16: "int16", np.int32: "int32",
              np.float32: "float"}


def write_nrrd(path, volume, spacing=(1, 1, 1)):
    """volume[x, y, z] as a raw NRRD (x fastest)."""
    header = (f"NRRD0004\ntype: {NRRD_TYPES[volume.dtype.type]}\ndimension: 3\n"
              f"sizes: {volume.shape[0]} {volume.shape[1]} {volume.shape[2]}\n"
              f"spacings: {spacing[0]} {spacing[1]} {spacing[2]}\nencoding: raw\nendian: little\n\n")
    with open(path, "wb") as f:
        f.write(header.encode())
        f.write(volume.astype(volume.dtype.newbyteorder("<")).tobytes(order="F"))
    return path


def blobs(shape, labels, seed):
    """A label map of random blobs: per label a smoothed random field, the
    label of the largest field where it is high enough, background elsewhere;
    regions touch each other and the grid border, with triple lines and
    diagonal contacts."""
    from scipy.ndimage import gaussian_filter
    rng = np.random.default_rng(seed)
    fields = np.stack([gaussian_filter(rng.standard_normal(shape), 1.5) for _ in range(labels)])
    v = np.argmax(fields, axis=0) + 1
    v[fields.max(axis=0) < 0.05] = 0
    return v.astype(np.int16)


def mesh_of(path):
    poly = read_polydata(path)
    cd = poly.GetCellData()
    fields = {cd.GetArrayName(i): ns.vtk_to_numpy(cd.GetArray(i)) for i in range(cd.GetNumberOfArrays())}
    return points_of(poly), triangles_of(poly), fields


def edges_of(tris):
    e = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    return np.sort(e, axis=1)


def euler_characteristic(tris):
    used = np.unique(tris)
    return len(used) - len(np.unique(edges_of(tris), axis=0)) + len(tris)


def enclosed_volume(points, tris):
    a, b, c = points[tris[:, 0]], points[tris[:, 1]], points[tris[:, 2]]
    return np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0


def surface_area(points, tris):
    a, b, c = points[tris[:, 0]], points[tris[:, 1]], points[tris[:, 2]]
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()


def boundary_faces(region):
    """Voxel faces between the region and the rest (6-neighbours), the region padded."""
    p = np.pad(region, 1)
    return sum(int((np.diff(p.astype(np.int8), axis=a) != 0).sum()) for a in range(3))


VOL = blobs((14, 13, 12), 4, seed=7)
SPACING = (1.0, 1.5, 0.75)
VOL_PATH = write_nrrd(os.path.join(D, "blobs.nrrd"), VOL, SPACING)
LABELS = [int(x) for x in np.unique(VOL) if x != 0]


def per_label_closed(method):
    def test():
        out = os.path.join(D, f"per-{method}.vtp")
        run("labels", VOL_PATH, "-o", out, "--method", method, "--per-label", "--smooth", 0, "-q")
        pts, tris, f = mesh_of(out)
        assert sorted(np.unique(f["label"]).astype(int)) == LABELS
        voxel = np.prod(SPACING)
        for lab in LABELS:
            t = tris[f["label"] == lab]
            assert_closed_manifold(t, f"{method} label {lab}")
            region = np.pad(VOL == lab, 1)
            # 6-connected label, 26-connected rest (skimage connectivity=1),
            # but for the rings the marching cubes table fills (labels.hpp).
            expected = 2 * (euler_number(region, connectivity=1) + filled_rings(region))
            assert euler_characteristic(t) == expected, (lab, euler_characteristic(t), expected)
            # Volume: within half a voxel of every boundary face of the voxels
            # (both surfaces lie in that shell around the voxel cubes' surface).
            n = int((VOL == lab).sum())
            vol = enclosed_volume(pts, t) / voxel
            bound = 0.5 * boundary_faces(VOL == lab)
            assert abs(vol - n) <= bound, (lab, vol, n, bound)
            if method == "discrete-mc":
                assert vol < n, (lab, vol, n)  # corners are cut, never added
    return test


def filled_rings(region):
    """Cubes (2x2x2 blocks) whose only outside corners are the two ends of a
    body diagonal: marching cubes (VTK's table too) joins the six inside
    corners around it, a ring that 6-connectivity leaves open."""
    c = np.stack([region[i:region.shape[0] - 1 + i, j:region.shape[1] - 1 + j, k:region.shape[2] - 1 + k]
                  for k in (0, 1) for j in (0, 1) for i in (0, 1)])
    out = ~c
    return int(sum(((out.sum(0) == 2) & out[a] & out[7 - a]).sum() for a in range(4)))


def surfacenets_exact_volume():
    # Boxes touching the border and each other: no diagonal contacts, so no
    # cell splits and the unsmoothed surface is the voxel cubes' boundary.
    v = np.zeros((9, 8, 7), dtype=np.uint8)
    v[:4, :, :3] = 1
    v[4:, 2:6, 1:5] = 2
    v[1:3, 1:7, 3:7] = 3
    path = write_nrrd(os.path.join(D, "boxes.nrrd"), v)
    out = os.path.join(D, "boxes.vtp")
    run("labels", path, "-o", out, "--per-label", "--smooth", 0, "-q")
    pts, tris, f = mesh_of(out)
    for lab in (1, 2, 3):
        t = tris[f["label"] == lab]
        assert_closed_manifold(t, f"box {lab}")
        assert abs(enclosed_volume(pts, t) - (v == lab).sum()) < 1e-4, lab
        assert euler_characteristic(t) == 2


def network_faces_match_voxels():
    out = os.path.join(D, "net.vtp")
    rep = out + ".json"
    run("labels", VOL_PATH, "-o", out, "--smooth", 0, "-q", "--report", rep)
    pts, tris, f = mesh_of(out)
    bl = f["boundary_labels"].astype(np.int64)
    assert (bl[:, 0] < bl[:, 1]).all()
    # Unsmoothed points are cell centres: voxel coordinates (i - 0.5, ...).
    sp = np.array(SPACING)
    g = pts / sp
    # Each triangle has one quad diagonal; its midpoint is the grid edge's midpoint.
    tri_pts = g[tris]
    found = []
    for k in range(3):
        a, b = tri_pts[:, k], tri_pts[:, (k + 1) % 3]
        diag = np.isclose(np.abs(a - b).sum(axis=1), 2.0)
        found.append(np.where(diag[:, None], (a + b) / 2, np.nan))
    mid = np.nanmax(np.stack(found), axis=0)
    assert not np.isnan(mid).any()
    normal = np.cross(tri_pts[:, 1] - tri_pts[:, 0], tri_pts[:, 2] - tri_pts[:, 0])
    axis = np.argmax(np.abs(normal), axis=1)
    step = np.eye(3)[axis] * 0.5 * np.sign(normal[np.arange(len(normal)), axis])[:, None]
    lo_end = np.rint(mid - step).astype(int) + 1  # padded index
    hi_end = np.rint(mid + step).astype(int) + 1
    p = np.pad(VOL, 1)
    la, lb = p[tuple(lo_end.T)], p[tuple(hi_end.T)]
    # The normal points from the smaller label to the larger one.
    assert (la == bl[:, 0]).all() and (lb == bl[:, 1]).all()
    # Every differing grid edge exactly once as a quad (two triangles), and no
    # other: counts per pair from numpy.
    pairs = {}
    for a in range(3):
        x = np.moveaxis(p, a, 0)
        u, w = x[:-1], x[1:]
        d = u != w
        lo, hi = np.minimum(u[d], w[d]), np.maximum(u[d], w[d])
        for pr, c in zip(*np.unique(np.stack([lo, hi], 1), axis=0, return_counts=True)):
            pairs[tuple(pr)] = pairs.get(tuple(pr), 0) + c
    r = report(rep)
    got = {tuple(x["labels"]): x["faces"] for x in r["pairs"]}
    assert got == {k: 2 * v for k, v in pairs.items()}, (got, pairs)
    assert len(np.unique(np.round(mid, 3), axis=0)) * 2 == len(tris)
    # One point per cell of the padded grid whose 8 corners hold two labels
    # or more (triple lines shared), none twice.
    c = np.stack([p[i:p.shape[0] - 1 + i, j:p.shape[1] - 1 + j, k:p.shape[2] - 1 + k]
                  for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    mixed = (c != c[0]).any(axis=0)
    assert len(pts) == mixed.sum() == r["points"], (len(pts), mixed.sum())
    assert len(np.unique(pts, axis=0)) == len(pts)
    assert sorted(np.unique(tris)) == list(range(len(pts)))


def smoothing_bounded_and_thread_independent():
    raw, sm1, sm2 = (os.path.join(D, n) for n in ("s0.vtp", "s1.vtp", "s2.vtp"))
    run("labels", VOL_PATH, "-o", raw, "--smooth", 0, "-q")
    run("labels", VOL_PATH, "-o", sm1, "--smooth", 20, "--threads", 1, "-q")
    run("labels", VOL_PATH, "-o", sm2, "--smooth", 20, "--threads", 2, "-q")
    assert open(sm1, "rb").read() == open(sm2, "rb").read()
    p0, t0, _ = mesh_of(raw)
    p1, t1, _ = mesh_of(sm1)
    assert (t0 == t1).all()
    # No point leaves its cell: within half a spacing of its cell centre.
    assert (np.abs(p1 - p0) <= 0.5 * np.array(SPACING) + 1e-5).all()
    assert np.abs(p1 - p0).max() > 0.05  # it did move
    # Closed per-label surfaces. Surface nets: every point stays in its cell,
    # so the surface stays in the half-voxel shell around the voxel cubes'
    # boundary: |V - voxels| <= half the boundary faces (voxel units).
    # Taubin (discrete MC): the volume changes by less than 10 %. Both: the
    # area drops (staircase smoothed away) but by less than 40 %.
    voxel = np.prod(SPACING)
    for method in ("surfacenets", "discrete-mc"):
        a, b = os.path.join(D, f"v0-{method}.vtp"), os.path.join(D, f"v1-{method}.vtp")
        run("labels", VOL_PATH, "-o", a, "--per-label", "--method", method, "--smooth", 0, "-q")
        run("labels", VOL_PATH, "-o", b, "--per-label", "--method", method, "--smooth", 10, "-q", "--threads", 2)
        c = os.path.join(D, f"v2-{method}.vtp")
        run("labels", VOL_PATH, "-o", c, "--per-label", "--method", method, "--smooth", 10, "-q", "--threads", 1)
        assert open(b, "rb").read() == open(c, "rb").read()
        pa, ta, fa = mesh_of(a)
        pb, tb, fb = mesh_of(b)
        for lab in LABELS:
            ka, kb = ta[fa["label"] == lab], tb[fb["label"] == lab]
            va, vb = enclosed_volume(pa, ka), enclosed_volume(pb, kb)
            aa, ab = surface_area(pa, ka), surface_area(pb, kb)
            if method == "surfacenets":
                n = (VOL == lab).sum()
                assert abs(vb / voxel - n) <= 0.5 * boundary_faces(VOL == lab), (lab, vb / voxel, n)
            else:
                assert abs(vb - va) <= 0.10 * va, (method, lab, va, vb)
            assert 0.6 * aa < ab < aa, (method, lab, aa, ab)


def selection_and_background():
    out = os.path.join(D, "sel.vtp")
    run("labels", VOL_PATH, "-o", out, "--labels", f"{LABELS[0]},{LABELS[2]}", "--smooth", 0, "-q")
    _, _, f = mesh_of(out)
    got = {tuple(x) for x in f["boundary_labels"].astype(int)}
    assert got <= {(0, LABELS[0]), (0, LABELS[2]), (LABELS[0], LABELS[2])}, got
    # Background 2: label 0 becomes a region like any other.
    run("labels", VOL_PATH, "-o", out, "--background", 2, "--smooth", 0, "-q", "--per-label")
    _, _, f = mesh_of(out)
    assert sorted(np.unique(f["label"]).astype(int)) == [x for x in [0] + LABELS if x != 2]


def every_integer_type():
    base = os.path.join(D, "t-int16.vtp")
    run("labels", VOL_PATH, "-o", base, "--smooth", 0, "-q")
    for dt in (np.uint8, np.int8, np.uint16, np.int32):
        path = write_nrrd(os.path.join(D, f"t.{dt.__name__}.nrrd"), VOL.astype(dt), SPACING)
        out = os.path.join(D, f"t-{dt.__name__}.vtp")
        run("labels", path, "-o", out, "--smooth", 0, "-q")
        assert open(out, "rb").read() == open(base, "rb").read(), dt
    # The same samples as headerless raw data (big-endian, after a 16-byte header).
    raw = os.path.join(D, "t.raw")
    with open(raw, "wb") as f:
        f.write(b"x" * 16 + VOL.astype(">i2").tobytes(order="F"))
    out = os.path.join(D, "t-raw.vtp")
    run("labels", raw, "-o", out, "--smooth", 0, "-q", "--dims", *VOL.shape, "--type", "int16", "--spacing", *SPACING,
        "--endian", "big", "--header-bytes", 16)
    assert open(out, "rb").read() == open(base, "rb").read()


def bad_input_refused():
    fl = write_nrrd(os.path.join(D, "float.nrrd"), VOL.astype(np.float32))
    out = os.path.join(D, "never.vtp")
    p = run("labels", fl, "-o", out, expect=1)
    assert fl in p.stderr and "float32" in p.stderr and "label map" in p.stderr, p.stderr
    many = write_nrrd(os.path.join(D, "many.nrrd"), np.arange(70000, dtype=np.int32).reshape(70, 100, 10))
    p = run("labels", many, "-o", out, expect=1)
    assert many in p.stderr and "65536" in p.stderr, p.stderr
    p = run("labels", VOL_PATH, "-o", out, "--labels", "99", expect=1)
    assert "99" in p.stderr and VOL_PATH in p.stderr, p.stderr
    run("labels", VOL_PATH, "-o", out, "--relaxation", 0, expect=2)
    run("labels", VOL_PATH, "-o", out, "--method", "flying", expect=2)
    assert not os.path.exists(out)


check("per-label surface nets: closed 2-manifolds, Euler = 2 x euler_number(conn. 1), volume", per_label_closed("surfacenets"))
check("per-label discrete MC: closed 2-manifolds, Euler = 2 x euler_number(conn. 1), volume", per_label_closed("discrete-mc"))
check("surface nets of boxes: volume = voxel count exactly", surfacenets_exact_volume)
check("surface nets network: face labels = voxels across the edge, counts per pair, one point per mixed cell",
      network_faces_match_voxels)
check("smoothing: stays in its cell, bounded area/volume change, 1 and 2 threads identical",
      smoothing_bounded_and_thread_independent)
check("--labels selects, --background", selection_and_background)
check("uint8/int8/uint16/int32 and big-endian raw give the int16 bytes", every_integer_type)
check("float volume, too many labels, missing label, bad options refused", bad_input_refused)
finish()
