"""`keymesh labels --memory-limit` (issue 18): the input volume streamed in
slabs of z-planes, the slabs' pieces merged by key, then smoothed and written
whole. The reference is the in-memory run of the same keymesh (whose
surfaces tests/cli/test_labels_cli.py checks against numpy and skimage): the
files must be byte-identical at every slab size, for both methods, one
network and --per-label, with and without smoothing, label selection and
another background, so no point is doubled and no face lost at a slab border.
The report must show that the run really used several slabs of the expected
size; gzip-compressed input too. Refusals: a limit below three planes and a
float volume, each by name with no output written."""
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import check, finish, report, require_numpy, run, tempdir  # noqa: E402

np = require_numpy()

D = tempdir()


def write_nrrd(path, volume, encoding="raw"):
    """volume[x, y, z] as NRRD (x fastest)."""
    kind = {np.uint8: "uint8", np.int16: "int16", np.int32: "int32", np.float32: "float"}[volume.dtype.type]
    data = volume.astype(volume.dtype.newbyteorder("<")).tobytes(order="F")
    if encoding == "gzip":
        import gzip
        data = gzip.compress(data)
    header = (f"NRRD0004\ntype: {kind}\ndimension: 3\nsizes: {' '.join(map(str, volume.shape))}\n"
              f"spacings: 0.5 1 2\nencoding: {encoding}\nendian: little\n\n")
    with open(path, "wb") as f:
        f.write(header.encode())
        f.write(data)
    return path


rng = np.random.default_rng(18)
SHAPE = (10, 11, 13)  # x, y, z
# White noise of four labels (-1 .. 2) mixed with two boxes (5 and 9): triple
# lines, diagonal contacts and regions touching every border and slab cut.
noise = rng.integers(-1, 3, size=SHAPE)
boxes = np.zeros(SHAPE, np.int16)
boxes[1:7, 3:8, 2:9] = 5
boxes[4:9, 1:6, 6:12] = 9
MIX = write_nrrd(os.path.join(D, "mix.nrrd"), np.where(rng.random(SHAPE) < 0.5, noise, boxes).astype(np.int16))
ROWS = SHAPE[2] + 2  # padded planes: one of background either side
# A padded plane of samples (int16) and one of 16-bit label indices.
PLANE = SHAPE[0] * SHAPE[1] * 2 + (SHAPE[0] + 2) * (SHAPE[1] + 2) * 2


def streamed_equals_in_memory(args, rows_per_slab_list=(1, 2, 5, ROWS)):
    def fn():
        ref = os.path.join(D, "ref.vtp")
        run("labels", MIX, "-o", ref, *args, "-q")
        with open(ref, "rb") as f:
            expected = f.read()
        assert len(expected) > 1000
        for rows in rows_per_slab_list:
            out, rep = os.path.join(D, f"s{rows}.vtp"), os.path.join(D, f"s{rows}.json")
            run("labels", MIX, "-o", out, *args, "-q", "--memory-limit", (rows + 2) * PLANE, "--report", rep)
            s = report(rep)["stream"]
            assert s["rows_per_slab"] == rows, s
            assert s["slabs"] == math.ceil(ROWS / rows), s
            with open(out, "rb") as f:
                assert f.read() == expected, f"{args} with {rows} rows per slab: not byte-identical"
    return fn


for method in ("surfacenets", "discrete-mc"):
    for per_label in ([], ["--per-label"]):
        for smooth in ("0", "4"):
            args = ["--method", method, *per_label, "--smooth", smooth]
            check(f"{' '.join(args)}: byte-identical at 1, 2, 5 and all rows per slab",
                  streamed_equals_in_memory(args))
    check(f"{method} --labels 5,9,-1 --background 2: byte-identical",
          streamed_equals_in_memory(["--method", method, "--labels", "5,9,-1", "--background", "2"], (1, 3)))
    check(f"{method} --per-label --labels 9: byte-identical (slabs without the label)",
          streamed_equals_in_memory(["--method", method, "--per-label", "--labels", "9"], (1, 4)))


def refused(path, args, words):
    def fn():
        out = os.path.join(D, os.path.basename(path) + ".refused.vtp")
        p = run("labels", path, "-o", out, *args, expect=None)
        assert p.returncode != 0, p
        msg = p.stderr.strip()
        assert len(msg.splitlines()) == 1, msg
        for w in words:
            assert w in msg, (w, msg)
        assert not os.path.exists(out), "half-written output"
    return fn


check("a limit below three planes is refused by name",
      refused(MIX, ["--memory-limit", 3 * PLANE - 1], ["mix.nrrd", "--memory-limit", str(3 * PLANE)]))


def gzip_streams():
    gz = write_nrrd(os.path.join(D, "gz.nrrd"), (boxes + (noise > 1)).astype(np.int16), "gzip")
    run("labels", gz, "-o", os.path.join(D, "gz_ref.vtp"), "-q")
    run("labels", gz, "-o", os.path.join(D, "gz_s.vtp"), "-q", "--memory-limit", 3 * PLANE)
    with open(os.path.join(D, "gz_ref.vtp"), "rb") as a, open(os.path.join(D, "gz_s.vtp"), "rb") as b:
        assert a.read() == b.read()


check("gzip-compressed samples (read forward, windows overlapping): byte-identical", gzip_streams)
FLOAT = write_nrrd(os.path.join(D, "float.nrrd"), np.zeros(SHAPE, np.float32))
check("a float volume is refused by name", refused(FLOAT, ["--memory-limit", "1M"], ["float.nrrd", "float32"]))

finish()
