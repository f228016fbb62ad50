"""`keymesh contour --memory-limit`: the volume streamed in slabs gives the
byte-identical file of the in-memory run, and with the limit at a quarter of
the volume the process holds far less memory than reading it whole."""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import check, finish, report, run, tempdir  # noqa: E402

D = tempdir()
N = 256
RAW = os.path.join(D, f"s{N}.raw")
run("generate", "sphere", "--size", N, "-o", RAW, "-q")
DIMS = ["--dims", N, N, N, "--type", "float32"]
VOLUME = N ** 3 * 4


def identical_output():
    whole, part = os.path.join(D, "whole.ply"), os.path.join(D, "part.ply")
    for isos in (["--iso", 90.5], ["--iso", 40.25, "--iso", 93.0]):
        run("contour", RAW, *DIMS, "-o", whole, *isos, "-q", "--report", whole + ".json")
        run("contour", RAW, *DIMS, "-o", part, *isos, "-q", "--memory-limit", f"{VOLUME // 4 // 1024}K",
            "--report", part + ".json")
        assert open(whole, "rb").read() == open(part, "rb").read(), "streamed output differs"
        r = report(part + ".json")
        assert r["stream"]["slabs"] > 4 and r["stream"]["slab_bytes"] <= VOLUME // 4, r["stream"]


def bounded_memory():
    whole, part = os.path.join(D, "w.vtp"), os.path.join(D, "p.vtp")
    tiny = os.path.join(D, "tiny.raw")
    run("generate", "sphere", "--size", 4, "-o", tiny, "-q")
    run("contour", tiny, "--dims", 4, 4, 4, "-o", os.path.join(D, "t.vtp"), "--iso", 1.5, "-q",
        "--report", os.path.join(D, "t.json"))
    base = report(os.path.join(D, "t.json"))["peak_rss_mib"]  # the process itself
    run("contour", RAW, *DIMS, "-o", whole, "--iso", 60.5, "-q", "--report", whole + ".json")
    run("contour", RAW, *DIMS, "-o", part, "--iso", 60.5, "-q", "--memory-limit", f"{VOLUME // 4}",
        "--report", part + ".json")
    w, p = report(whole + ".json"), report(part + ".json")
    if "ASAN_OPTIONS" in os.environ or "TSAN_OPTIONS" in os.environ:
        # make sanitize: shadow memory and the allocator's quarantine make RSS
        # say nothing about keymesh's own arrays.
        print("        (peak RSS bound not asserted under sanitizers)")
        return
    # The output mesh as the in-memory run holds it: points, scalars, triangles.
    mesh_mib = (p["points"] * 16 + p["cells"] * 12) / 2 ** 20
    limit_mib = VOLUME / 4 / 2 ** 20
    print(f"        peak RSS: whole {w['peak_rss_mib']:.0f} MiB, streamed {p['peak_rss_mib']:.0f} MiB; "
          f"process {base:.0f}, limit {limit_mib:.0f}, mesh {mesh_mib:.1f} MiB")
    # The whole run holds the volume; the streamed one a quarter of it.
    assert p["peak_rss_mib"] < w["peak_rss_mib"] - 0.5 * VOLUME / 2 ** 20, (p["peak_rss_mib"], w["peak_rss_mib"])
    # Under the process, the limit and the output mesh, with the merge's
    # working arrays (keys, sort buffers: about twice the mesh) and 2 MiB
    # page rounding of each array (8 MiB).
    assert p["peak_rss_mib"] < base + limit_mib + 3 * mesh_mib + 8, (p["peak_rss_mib"], base, limit_mib, mesh_mib)


def nrrd_streamed():
    """An attached NRRD (keymesh's writer) streamed at a quarter of its size
    gives the in-memory file; so does a gzip NRRD (inflated once, in order)."""
    nrrd = os.path.join(D, "s.nrrd")
    run("generate", "sphere", "--size", 96, "-o", nrrd, "-q")
    whole, part = os.path.join(D, "nw.ply"), os.path.join(D, "np.ply")
    run("contour", nrrd, "-o", whole, "--iso", 30.5, "-q")
    run("contour", nrrd, "-o", part, "--iso", 30.5, "-q", "--memory-limit", f"{96 ** 3 * 4 // 4}")
    assert open(whole, "rb").read() == open(part, "rb").read(), "streamed NRRD differs"
    import gzip
    gz = os.path.join(D, "g.nrrd")
    with open(nrrd, "rb") as f:
        data = f.read()
    head, body = data.split(b"\n\n", 1)
    with open(gz, "wb") as f:
        f.write(head.replace(b"encoding: raw", b"encoding: gzip") + b"\n\n" + gzip.compress(body))
    run("contour", gz, "-o", part + "2.ply", "--iso", 30.5, "-q", "--memory-limit", f"{96 ** 3 * 4 // 4}",
        "--report", part + "2.json")
    assert report(part + "2.json")["stream"]["slabs"] > 3
    assert open(whole, "rb").read() == open(part + "2.ply", "rb").read(), "streamed gzip NRRD differs"


def derivatives_streamed():
    """--normals gradient and --curvature: central differences across slab
    borders read a ghost plane on either side, so the file is still
    byte-identical (without the ghosts the border points' normals differ)."""
    whole, part = os.path.join(D, "dw.vtp"), os.path.join(D, "dp.vtp")
    args = ["--iso", 90.5, "--iso", 40.25, "--normals", "gradient", "--curvature", "-q"]
    run("contour", RAW, *DIMS, "-o", whole, *args)
    for limit in (VOLUME // 4, 5 * N * N * 4):  # a quarter; then 3 planes and the two ghosts per slab
        run("contour", RAW, *DIMS, "-o", part, *args, "--memory-limit", limit, "--report", part + ".json")
        assert open(whole, "rb").read() == open(part, "rb").read(), f"limit {limit}: streamed derivatives differ"
    assert report(part + ".json")["stream"]["slabs"] > 100
    p = run("contour", RAW, *DIMS, "-o", part, *args, "--memory-limit", 3 * N * N * 4, expect=1)
    assert "fewer than four" in p.stderr and "ghost planes" in p.stderr, p.stderr


def refusals():
    p = run("contour", RAW, *DIMS, "-o", os.path.join(D, "x.ply"), "--iso", 9, "--memory-limit", "10", expect=1)
    assert "fewer than two" in p.stderr
    run("contour", RAW, *DIMS, "-o", os.path.join(D, "x.ply"), "--iso", 9, "--memory-limit", "lots", expect=2)
    run("contour", RAW, *DIMS, "-o", os.path.join(D, "x.ply"), "--iso", 9, "--memory-limit", "1M",
        "--weld", "vertexweld", expect=1)
    assert not os.path.exists(os.path.join(D, "x.ply"))


check("streamed contour equals the in-memory one byte for byte (one and two isovalues)", identical_output)
check("a quarter-volume limit keeps peak memory near the limit plus the mesh", bounded_memory)
check("--memory-limit streams an uncompressed NRRD; gzip refused by name", nrrd_streamed)
check("gradient normals and curvature streamed with ghost planes: byte-identical", derivatives_streamed)
check("limits too small, bad sizes and unsupported options are refused", refusals)
finish()
