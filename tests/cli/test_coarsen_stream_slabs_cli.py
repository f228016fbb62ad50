"""`keymesh contour --coarsen --memory-limit` finishes coarse points slab by
slab (issue 36; docs/decisions/coarsen-slab-by-slab.md).

A coarse point is finished once the slab above it has been read, so the run
holds one slab's fine points and the crossings carried into the next, never
the whole fine mesh. Checked here: the file is byte-identical to the
in-memory --coarsen run for several limits (two planes a slab, the fewest,
up to the whole volume) and thread counts, on the ch2 MRI template (two
isovalues, gradient normals, curvature) and on a built-in sphere (three
isovalues, averaged normals); and the report's counters show that a small
limit held a small share of the fine points (the distinct fine points
counted equal the plain contour's points, so the counter counts the right
thing), where the former path held them all."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import check, finish, report, run, tempdir  # noqa: E402

D = tempdir()
HEAD = "/usr/share/mricron/templates/ch2.nii.gz"  # 181 x 217 x 181, uint8 (mricron-data)
HEAD_PLANE = 181 * 217
HEAD_ARGS = ["--iso", 90.5, "--iso", 40.5, "--normals", "gradient", "--curvature"]
SPHERE_N = 48
SPHERE_PLANE = SPHERE_N * SPHERE_N * 4
SPHERE_ARGS = ["--iso", 10.5, "--iso", 20.25, "--iso", 23.001, "--normals", "average"]


def coarsen(source, out, args, extra=()):
    run("contour", source, "-o", out, "--coarsen", "-q", *args, *extra)
    with open(out, "rb") as f:
        return f.read()


def streamed_equal(source, name, args, runs):
    ref = coarsen(source, os.path.join(D, f"{name}_mem.vtp"), args, ["--threads", 2])
    for limit, threads in runs:
        out = os.path.join(D, f"{name}_{limit}_{threads}.vtp")
        got = coarsen(source, out, args, ["--memory-limit", limit, "--threads", threads, "--report", out + ".json"])
        assert got == ref, f"{name} --memory-limit {limit} --threads {threads}: differs from in-memory"
        s = report(out + ".json")["stream"]
        assert s["slabs"] > 1 or limit == "1G", s


def head_equal():
    if not os.path.exists(HEAD):
        print(f"(no {HEAD}: install mricron-data)")
        return
    # Gradient normals read a ghost plane on either side: four planes at least.
    streamed_equal(HEAD, "head", HEAD_ARGS, [(4 * HEAD_PLANE, 1), (41 * HEAD_PLANE, 2)])


def sphere_equal():
    vol = os.path.join(D, "sphere.nrrd")
    run("generate", "sphere", "-n", SPHERE_N, "-o", vol, "-q")
    streamed_equal(vol, "sphere", SPHERE_ARGS,
                   [(2 * SPHERE_PLANE, 1), (2 * SPHERE_PLANE, 2), (7 * SPHERE_PLANE, 2), ("1G", 1)])


def few_fine_points_held():
    source = HEAD if os.path.exists(HEAD) else os.path.join(D, "sphere.nrrd")
    plane = HEAD_PLANE if source == HEAD else SPHERE_PLANE
    rep = os.path.join(D, "held.json")
    coarsen(source, os.path.join(D, "held.vtp"), ["--iso", 90.5 if source == HEAD else 20.25],
            ["--memory-limit", 8 * plane, "--report", rep])
    fine = os.path.join(D, "fine.json")
    run("contour", source, "-o", os.path.join(D, "fine.vtp"), "--iso", 90.5 if source == HEAD else 20.25, "-q",
        "--report", fine)
    s = report(rep)["stream"]
    assert s["fine_points"] == report(fine)["points"], (s, report(fine)["points"])
    # Eight planes a slab of 181 (of 48 for the sphere): a slab and its carried
    # crossings are a small share of the fine points; the whole mesh was held
    # before (most_fine_points_held == fine_points).
    assert 0 < s["most_fine_points_held"] * 4 < s["fine_points"], s


check("ch2 two isovalues, gradient normals, curvature: streamed --coarsen = in-memory (2 limits, 1 and 2 threads)",
      head_equal)
check("sphere three isovalues, averaged normals: streamed --coarsen = in-memory (2 to 48 planes, 1 and 2 threads)",
      sphere_equal)
check("--coarsen --memory-limit holds a slab's fine points, not the whole fine mesh (report counters)",
      few_fine_points_held)
finish()
