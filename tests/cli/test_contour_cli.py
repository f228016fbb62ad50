"""End-to-end tests of `keymesh generate`, `contour`, `check` and `info`."""
import filecmp
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import (canonical_mesh, check, finish, points_of, read_polydata, report, require_vtk, run,  # noqa: E402
                    tempdir, triangles_of)

require_vtk()
import numpy as np  # noqa: E402

D = tempdir()


def sphere(n, ext="vti"):
    path = os.path.join(D, f"sphere{n}.{ext}")
    if not os.path.exists(path):
        run("generate", "sphere", "--size", n, "-o", path, "--quiet")
    return path


def contour_report(src, out, *extra):
    rep = out + ".json"
    run("contour", src, "-o", out, "--report", rep, "--quiet", *extra)
    return report(rep)


# The paper's Table 1: an edge-based marching cubes on the Spherical Distance
# field at iso N/2 - 1 + 0.001 (see shared DESIGN.md, Datasets).
def table1(n, points, cells):
    def t():
        r = contour_report(sphere(n), os.path.join(D, f"t1_{n}.vtp"), "--iso", n / 2 - 1 + 0.001)
        assert (r["points"], r["cells"]) == (points, cells), (r["points"], r["cells"])
    return t


check("table 1 at 128^3: 74,715 points, 149,420 triangles", table1(128, 74715, 149420))
check("table 1 at 256^3: 303,699 points, 607,388 triangles", table1(256, 303699, 607388))


def closed_sphere():
    n = 96
    out = os.path.join(D, "closed.vtp")
    contour_report(sphere(n), out, "--iso", n / 2 - 1.5, "--normals", "average")
    rep = os.path.join(D, "closed_check.json")
    run("check", out, "--expect-closed", "--report", rep)
    r = report(rep)
    assert r["closed_manifold"] is True
    assert r["euler_characteristic"] == 2
    assert r["boundary_edges"] == 0 and r["nonmanifold_edges"] == 0 and r["nonmanifold_vertices"] == 0
    assert r["duplicate_points"] == 0 and r["components"] == 1
    for key in ("points", "cells", "boundary_edges", "nonmanifold_edges", "nonmanifold_vertices",
                "duplicate_points", "components", "euler_characteristic", "closed_manifold"):
        assert key in r, key


check("sphere at iso N/2 - 1.5 is a closed 2-manifold with Euler characteristic 2", closed_sphere)


def open_surface_fails_expect_closed():
    out = os.path.join(D, "t1_128.vtp")
    if not os.path.exists(out):
        contour_report(sphere(128), out, "--iso", 63.001)
    p = run("check", out, "--expect-closed", expect=1)
    assert "not a closed 2-manifold" in p.stderr
    rep = os.path.join(D, "open_check.json")
    run("check", out, "--report", rep)
    assert report(rep)["boundary_edges"] == 12  # the three tiny holes at the box faces


check("table-1 surface has 12 boundary edges and fails --expect-closed", open_surface_fails_expect_closed)


def report_keys():
    r = contour_report(sphere(64), os.path.join(D, "keys.ply"), "--iso", 20.5)
    for key in ("points", "cells", "threads", "seconds"):
        assert key in r, key
    for key in ("total", "read", "contour", "write"):
        assert key in r["seconds"], key
    assert r["seconds"]["total"] >= r["seconds"]["contour"]


check("--report has points, cells, threads and seconds.{total,read,contour,write}", report_keys)


def same_mesh(a, b):
    pa, pb = read_polydata(a), read_polydata(b)
    ca = canonical_mesh(points_of(pa), triangles_of(pa))
    cb = canonical_mesh(points_of(pb), triangles_of(pb))
    assert ca[0].shape == cb[0].shape and ca[1].shape == cb[1].shape, (ca[0].shape, cb[0].shape)
    assert np.array_equal(ca[0], cb[0]), "points differ"
    assert np.array_equal(ca[1], cb[1]), "triangles differ"


def keyreduce_equals_vertexweld():
    src = sphere(80)
    a, b = os.path.join(D, "kr.vtp"), os.path.join(D, "vw.vtp")
    contour_report(src, a, "--iso", 30.3, "--iso", 12.7, "--weld", "keyreduce")
    contour_report(src, b, "--iso", 30.3, "--iso", 12.7, "--weld", "vertexweld")
    same_mesh(a, b)


check("--weld keyreduce and --weld vertexweld give the same mesh up to renumbering", keyreduce_equals_vertexweld)


def threads_byte_identical():
    src = sphere(100)
    for ext in ("vtp", "ply", "obj", "stl"):
        for normals in ("none", "average", "gradient"):
            outs = []
            for t in (1, 2, 3):
                out = os.path.join(D, f"thr{t}_{normals}.{ext}")
                run("contour", src, "-o", out, "--iso", 40.2, "--normals", normals, "--threads", t, "--quiet")
                outs.append(out)
            assert filecmp.cmp(outs[0], outs[1], shallow=False), f"{ext} {normals}: 1 vs 2 threads"
            assert filecmp.cmp(outs[0], outs[2], shallow=False), f"{ext} {normals}: 1 vs 3 threads"


check("output files are byte-identical for --threads 1, 2 and 3", threads_byte_identical)


def formats_agree():
    n = 40
    vti = sphere(n, "vti")
    nrrd = sphere(n, "nrrd")
    raw = sphere(n, "raw")
    counts = []
    for src, extra in ((vti, ()), (nrrd, ()), (raw, ("--dims", n, n, n, "--type", "float32"))):
        r = contour_report(src, os.path.join(D, "fmt.vtp"), "--iso", 13.3, *extra)
        counts.append((r["points"], r["cells"]))
    assert counts[0] == counts[1] == counts[2], counts


check("the sphere written as .vti, .nrrd and .raw contours identically", formats_agree)


def info_volume_and_mesh():
    p = run("info", sphere(40))
    assert "40 x 40 x 40" in p.stdout and "float32" in p.stdout, p.stdout
    out = os.path.join(D, "info.vtp")
    r = contour_report(sphere(40), out, "--iso", 13.3)
    p = run("info", out)
    assert f"points {r['points']}" in p.stdout and f"cells {r['cells']}" in p.stdout, p.stdout


check("info describes volumes and meshes", info_volume_and_mesh)


def bad_inputs():
    src = sphere(32, "vti")
    data = open(src, "rb").read()
    cases = {
        "truncated.vti": data[: len(data) // 2],
        "garbage.nii": b"this is not a nifti file at all" * 20,
        "empty.nrrd": b"",
        "bad_header.nrrd": b"NRRD0004\ntype: float\ndimension: 3\nsizes: 100 100 100\nencoding: raw\n\n" + b"\0" * 64,
        "negative.nrrd": b"NRRD0004\ntype: float\ndimension: 3\nsizes: -4 4 4\nencoding: raw\n\n" + b"\0" * 256,
    }
    for name, content in cases.items():
        path = os.path.join(D, name)
        with open(path, "wb") as f:
            f.write(content)
        out = os.path.join(D, name + ".vtp")
        p = run("contour", path, "-o", out, "--iso", 1, expect=1)
        assert p.stderr.startswith("keymesh:") and len(p.stderr.strip().splitlines()) == 1, p.stderr
        assert name in p.stderr, p.stderr
        assert not os.path.exists(out), "output written for bad input"
    # Raw file smaller than its declared dims.
    out = os.path.join(D, "raw_short.vtp")
    run("contour", src, "--dims", 200, 200, 200, "--type", "float32", "-o", out, "--iso", 1, expect=1)
    assert not os.path.exists(out)
    # Unwritable output: no file, exit 1.
    p = run("contour", src, "-o", "/nonexistent-dir/out.vtp", "--iso", 5, expect=1)
    assert "/nonexistent-dir/out.vtp" in p.stderr
    # An existing output survives a failed run untouched.
    keep = os.path.join(D, "keep.vtp")
    with open(keep, "w") as f:
        f.write("old")
    run("contour", os.path.join(D, "truncated.vti"), "-o", keep, "--iso", 1, expect=1)
    assert open(keep).read() == "old"
    leftovers = [f for f in os.listdir(D) if ".tmp-" in f]
    assert not leftovers, leftovers


check("bad inputs exit 1 with one line naming the file and leave no output", bad_inputs)


def usage_errors():
    src = sphere(32)
    for args in (("contour", src), ("contour", src, "--iso", "abc", "-o", "x.vtp"),
                 ("contour", src, "-o", os.path.join(D, "u.vtp"), "--iso", "nan"),
                 ("contour", src, "-o", os.path.join(D, "u.vtp"), "--iso", 1, "--weld", "magic"),
                 ("frobnicate",), ()):
        run(*args, expect=2)
    assert not os.path.exists(os.path.join(D, "u.vtp"))


check("usage errors exit 2", usage_errors)


def out_of_range_iso_warns():
    out = os.path.join(D, "empty.vtp")
    p = run("contour", sphere(32), "-o", out, "--iso", 1e6)
    assert "outside the data range" in p.stderr
    assert read_polydata(out).GetNumberOfPoints() == 0


check("an isovalue outside the data range gives an empty mesh, a warning and exit 0", out_of_range_iso_warns)

finish()
