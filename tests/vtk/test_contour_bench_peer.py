"""bench/contour_bench --peer fe3d: vtkFlyingEdges3D in the harness's own
process on keymesh's samples, the same-process ratio `make bench` quotes.

The peer is an independent contour of the same samples: its point and
triangle counts must equal keymesh's (both weld each cut edge's crossing to
one point, with the same cube cases), for one isovalue and for several in one
call, and its ratio must be its median over keymesh's. Options the peer
cannot serve are refused by name with exit status 2.

Skipped (77) where contour_bench was not built (KEYMESH_BUILD_BENCH=OFF) or
was built without VTK's C++ package (libvtk9-dev, a `make bench` package,
not a `make test` one)."""
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import KEYMESH, check, finish  # noqa: E402

BENCH = os.path.join(os.path.dirname(os.path.abspath(KEYMESH)), "contour_bench")


def bench(*args, expect=0, env=None):
    p = subprocess.run([BENCH, *map(str, args)], capture_output=True, text=True, stdin=subprocess.DEVNULL,
                       timeout=300, env=None if env is None else {**os.environ, **env})
    if p.returncode != expect:
        raise AssertionError(f"contour_bench {' '.join(map(str, args))}: exit {p.returncode}, expected {expect}\n"
                             f"stdout: {p.stdout}\nstderr: {p.stderr}")
    return p


if not os.path.exists(BENCH):
    print(f"skipped: no {BENCH} (bench programs not built)")
    sys.exit(77)
probe = subprocess.run([BENCH, "--peer", "fe3d", "--size", "8", "--reps", "1"], capture_output=True, text=True,
                       stdin=subprocess.DEVNULL, timeout=300)
if "built without VTK" in probe.stderr:
    print("skipped: contour_bench was built without VTK's C++ package (libvtk9-dev)")
    sys.exit(77)


def same_counts(*args, env=None):
    def test():
        line = json.loads(bench(*args, "--threads", "2", "--reps", "3", "--peer", "fe3d", env=env).stdout)
        assert line["peer"] == "vtkFlyingEdges3D", line
        assert line["cells"] > 0, line
        assert (line["peer_points"], line["peer_cells"]) == (line["points"], line["cells"]), line
        assert line["peer_min"] <= line["peer_median"] <= line["peer_max"], line
        # The medians are printed to the microsecond (+-0.5e-6 s), the ratio to 4 decimals.
        p, k, h = line["peer_median"], line["median"], 0.5e-6
        assert (p - h) / (k + h) - 1e-4 <= line["peer_ratio"] <= (p + h) / (k - h) + 1e-4, line
    return test


check("sphere 48: FE3D's counts are keymesh's", same_counts("--size", "48"))
check("sphere 48, three isovalues in one call: FE3D's counts are keymesh's",
      same_counts("--size", "48", "--iso", "8.5,15.25,21.75"))
check("sphere 40 with huge pages off: FE3D's counts are keymesh's",
      same_counts("--size", "40", env={"KEYMESH_HUGE_PAGES": "0"}))


def refused(args, needle):
    def test():
        p = bench(*args, expect=2)
        assert needle in p.stderr, p.stderr
        assert p.stdout == "", p.stdout
    return test


check("--peer other than fe3d is refused by name", refused(["--peer", "flyingedges", "--size", "8"], "--peer must be fe3d"))
check("--peer-order other than blocks or turns is refused by name",
      refused(["--peer", "fe3d", "--peer-order", "mixed", "--size", "8"], "--peer-order must be blocks or turns"))
check("sphere 40, a call of each in turn: FE3D's counts are keymesh's",
      same_counts("--size", "40", "--peer-order", "turns"))
check("--peer with --grid tet5 is refused by name",
      refused(["--peer", "fe3d", "--grid", "tet5", "--size", "8"], "voxel grid only"))
finish()
