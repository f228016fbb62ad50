"""Hardening rules of issue 34 for the commands that run under mpirun, and
the option checks every command shares.

- One way out for errors under mpirun: an error any rank meets (a DICOM
  slice or a Zarr chunk only the last rank reads) reaches every rank; the
  run ends with exit 1 and one `keymesh:` line, no hang (a time limit turns
  one into a failure) and no output. Also refusals made before the work
  (an unwritable -o) and usage errors: said once, not once per rank.
- --max-memory is applied by every command that accepts it: a tiny budget is
  refused by name, a generous one changes nothing.
- Messages: sizes printed with a unit that tells them apart (no "0 MiB");
  an integer option past 64 bits (or negative where it cannot be) is a usage
  error naming the value as typed, never clamped.

Without mpirun or an MPI build the one-process checks run and the test
exits 77 (skipped) when they pass.
"""
import os
import shutil
import signal
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import check, finish, mpirun_command, report, require_numpy, run, tempdir  # noqa: E402

np = require_numpy()

D = tempdir()
MPIRUN = shutil.which("mpirun")
HANG_LIMIT = 90  # seconds: each run below takes about one


def mpi(P, *args, timeout=HANG_LIMIT):
    """`mpirun -np P keymesh args` in a session of its own: (exit, stderr).
    Past `timeout` the whole session is killed and the check fails (a hang)."""
    cmd, env = mpirun_command(P, *args)
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True,
                         env=env, start_new_session=True)
    try:
        _, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        p.terminate()  # mpirun passes it on to the ranks
        try:
            p.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            p.communicate()
        raise AssertionError(f"mpirun -np {P} keymesh {' '.join(map(str, args))}: still running after {timeout} s")
    return p.returncode, err


def keymesh_lines(stderr):
    """keymesh's own lines (mpirun adds its banner about the exit code)."""
    return [line for line in stderr.splitlines() if line.startswith("keymesh")]


def said_once(stderr, *words):
    lines = keymesh_lines(stderr)
    assert len(lines) == 1, f"expected one keymesh line, got {len(lines)}:\n{stderr}"
    for w in words:
        assert w in lines[0], f"{w!r} not in {lines[0]!r}"
    assert "MPI_ABORT" not in stderr, stderr
    return lines[0]


def mpi_usable():
    if not MPIRUN:
        return "no mpirun (install openmpi-bin and libopenmpi-dev)"
    rc, err = mpi(2, "--version")
    if rc != 0:
        return f"mpirun -np 2 keymesh --version fails here (exit {rc}): {err.strip()[:300]}"
    rc, err = mpi(2, "info", os.path.join(D, "none.raw"), "--dims", 2, 2, 2)
    if "built without MPI" in err:
        return "keymesh was built without MPI"
    return None


# A label volume (x, y, z) = (10, 9, 8): two boxes.
LABELS = np.zeros((8, 9, 10), np.int16)  # z, y, x
LABELS[1:6, 2:7, 2:8] = 3
LABELS[3:8, 1:5, 4:9] = 7


def zarr_with_corrupt_top_chunk():
    """A Zarr v2 label volume in one-plane chunks whose top plane's chunk is
    not zlib data: only the rank holding the top rows meets it."""
    import json
    import zlib
    folder = os.path.join(D, "labels.zarr")
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, ".zarray"), "w") as f:
        json.dump({"zarr_format": 2, "shape": list(LABELS.shape), "chunks": [1, *LABELS.shape[1:]], "dtype": "<i2",
                   "compressor": {"id": "zlib", "level": 1}, "fill_value": 0, "order": "C", "filters": None}, f)
    for z in range(LABELS.shape[0]):
        data = zlib.compress(LABELS[z].astype("<i2").tobytes())
        if z == LABELS.shape[0] - 1:
            data = b"\x78\x9c" + b"\xff" * 40  # a zlib header, then garbage
        with open(os.path.join(folder, f"{z}.0.0"), "wb") as f:
            f.write(data)
    return folder


def dicom_with_truncated_last_slice():
    """A DICOM series whose top slice (by position) is cut short in its pixel data."""
    from dicom_series import write_dicom_series
    folder = os.path.join(D, "series")
    names = [f"s{k:02d}.dcm" for k in range(LABELS.shape[0])]
    write_dicom_series(folder, LABELS, shuffle=False, names=names, slope=1.0, intercept=0.0)
    top = os.path.join(folder, names[-1])
    size = os.path.getsize(top)
    os.truncate(top, size - LABELS.shape[1] * LABELS.shape[2])  # half its pixel data
    return folder


def error_said_once(command, path, *extra):
    """An error met reading `path` under mpirun: exit 1, one line naming the culprit (the file
    only the last rank reads), no output, for -np 2 and 3."""
    culprit = "s07.dcm" if path.endswith("series") else "7.0.0"
    if "1K" in extra:
        culprit = "fewer than three"

    def fn():
        out = os.path.join(D, "one_rank.vtp")
        args = ["--iso", 0.5] if command == "contour" else []
        for P in (2, 3):
            rc, err = mpi(P, command, path, *args, "-o", out, *extra)
            assert rc == 1, f"-np {P}: exit {rc}\n{err}"
            said_once(err, os.path.basename(path), culprit)
            assert not os.path.exists(out)
    return fn


def pieces_not_left():
    zarr = os.path.join(D, "labels.zarr")
    out = os.path.join(D, "pieces", "p.pvtp")
    os.makedirs(os.path.dirname(out), exist_ok=True)
    rc, err = mpi(3, "contour", zarr, "--iso", 0.5, "-o", out)
    assert rc == 1, err
    said_once(err, "labels.zarr")
    assert os.listdir(os.path.dirname(out)) == [], os.listdir(os.path.dirname(out))


def unwritable_output_said_once():
    raw = LABELRAW
    dims = ["--dims", 10, 9, 8, "--type", "int16"]
    for command, extra in (("labels", []), ("contour", ["--iso", 0.5])):
        for target in (os.path.join(D, "no_dir", "x.vtp"), os.path.join(D, "no_dir", "x.pvtp")):
            if command == "labels" and target.endswith(".pvtp"):
                continue
            rc, err = mpi(2, command, raw, *dims, *extra, "-o", target)
            assert rc == 1, f"{command} -> {target}: exit {rc}\n{err}"
            said_once(err, "cannot write", target)
        rc, err = mpi(2, command, raw, *dims, *extra, "-o", os.path.join(D, "r.vtp"), "--report",
                      os.path.join(D, "no_dir", "r.json"))
        assert rc == 1, err
        said_once(err, "cannot write", "r.json")


def usage_errors_said_once():
    raw = LABELRAW
    rc, err = mpi(2, "labels", raw, "--dims", 10, 9, 8, "--type", "int16", "-o", os.path.join(D, "u.vtp"),
                  "--background", "99999999999999999999")
    assert rc == 2, err
    lines = [line for line in err.splitlines() if "99999999999999999999" in line]
    assert len(lines) == 1, err
    rc, err = mpi(2, "labels", raw, "--dims", 10, 9, 8, "--type", "int16", "-o", os.path.join(D, "u.vtp"),
                  "--max-memory", 1)
    assert rc == 1, err
    said_once(err, "--max-memory")


def mpi_checks():
    why = mpi_usable()
    if why:
        return f"the mpirun checks: {why}"
    check("labels under mpirun: a corrupt top Zarr chunk (one rank's) ends every rank, said once",
          error_said_once("labels", zarr_with_corrupt_top_chunk()))
    # 1K holds fewer than three 10 x 9 planes (refused alike on every rank, said once): 2K streams.
    check("the same with --memory-limit 2K (labels streams its rows, a few at a time)",
          error_said_once("labels", os.path.join(D, "labels.zarr"), "--memory-limit", "2K"))
    check("--memory-limit 1K: too small for three planes on every rank, said once",
          error_said_once("labels", os.path.join(D, "labels.zarr"), "--memory-limit", "1K"))
    check("contour of the same Zarr under mpirun: said once, exit 1",
          error_said_once("contour", os.path.join(D, "labels.zarr")))
    check("contour --balance (the ranks read, then share their counts): said once, exit 1",
          error_said_once("contour", os.path.join(D, "labels.zarr"), "--balance"))
    check("contour into .pvtp pieces: said once, exit 1, no piece left", pieces_not_left)
    try:
        import pydicom  # noqa: F401
        series = dicom_with_truncated_last_slice()
        check("labels under mpirun: a DICOM series whose last slice is truncated ends every rank, said once",
              error_said_once("labels", series))
        check("contour of the same series: said once, exit 1", error_said_once("contour", series))
    except ImportError:
        print("skipped (DICOM part): no pydicom")
    check("an unwritable -o or --report under mpirun: one line, exit 1 (labels and contour)",
          unwritable_output_said_once)
    check("usage errors and --max-memory under mpirun: said once", usage_errors_said_once)
    return None


# ---------------------------------------------------------------- one process

def small_inputs():
    vol = os.path.join(D, "sphere.nrrd")
    run("generate", "sphere", "--size", 24, "-o", vol, "-q")
    mesh = os.path.join(D, "sphere.ply")
    run("contour", vol, "--iso", 8.5, "-o", mesh, "-q")
    labels = os.path.join(D, "one.raw")
    LABELS.tofile(labels)  # z, y, x in C order: x fastest
    return vol, mesh, labels


VOL, MESH, LABELRAW = small_inputs()
LABELDIMS = ["--dims", 10, 9, 8, "--type", "int16"]


def max_memory_applied():
    out = os.path.join(D, "mm")
    cases = [
        ("labels", [LABELRAW, *LABELDIMS, "-o", out + ".vtp"]),
        ("labels", [LABELRAW, *LABELDIMS, "--memory-limit", "4K", "-o", out + ".vtp"]),
        ("pipeline", [VOL, "--iso", 8.5, "-o", out + ".ply"]),
        ("pipeline", [VOL, "--iso", 8.5, "--subdivide", 2, "--dual", "-o", out + ".vtp"]),
        ("dual", [MESH, "-o", out + ".vtp"]),
        ("convert", [MESH, "-o", out + ".vtp"]),
        ("convert", [VOL, "-o", out + ".vti"]),
        ("check", [MESH]),
        ("quality", [MESH]),
    ]
    for command, args in cases:
        p = run(command, *args, "--max-memory", 1, "-q", expect=1)
        assert "--max-memory" in p.stderr and "1 byte" in p.stderr, f"{command}: {p.stderr}"
        assert len(p.stderr.strip().splitlines()) == 1, p.stderr
        for path in (out + ".vtp", out + ".ply", out + ".vti"):
            assert not os.path.exists(path), f"{command} --max-memory 1 left {path}"
        run(command, *args, "--max-memory", "4G", "-q")
        for path in (out + ".vtp", out + ".ply", out + ".vti"):
            if os.path.exists(path):
                os.remove(path)


def pipeline_subdivision_checked():
    """pipeline --subdivide K refuses what subdivide K alone refuses."""
    contoured = os.path.join(D, "pc.ply")
    run("contour", VOL, "--iso", 8.5, "--normals", "average", "-o", contoured, "-q")
    p = run("subdivide", contoured, "--levels", 6, "--max-memory", "16M", "-o", os.path.join(D, "s6.ply"), expect=1)
    assert "--max-memory" in p.stderr, p.stderr
    p = run("pipeline", VOL, "--iso", 8.5, "--subdivide", 6, "--max-memory", "16M",
            "-o", os.path.join(D, "p6.ply"), expect=1)
    assert "--max-memory" in p.stderr and "--subdivide 6" in p.stderr, p.stderr
    assert not os.path.exists(os.path.join(D, "p6.ply"))


def sizes_tell_apart():
    for command, args in (("contour", [VOL, "--iso", 8.5]), ("tetrahedralize", [VOL])):
        for budget, shown in (("1", "1 byte"), ("1K", "1 KiB"), ("1000", "1000 bytes")):
            ext = ".vtu" if command == "tetrahedralize" else ".ply"
            p = run(command, *args, "--max-memory", budget, "-o", os.path.join(D, "m" + ext), expect=1)
            line = p.stderr.strip()
            assert "0 MiB" not in line and f"more than the {shown} of --max-memory" in line, line
            need = line.split("need about ")[1].split(",")[0]
            assert need != shown, line


def integers_not_clamped():
    out = os.path.join(D, "i.vtp")
    for option, value in (("--labels", "99999999999999999999"), ("--background", "99999999999999999999"),
                          ("--background", "-99999999999999999999"), ("--labels", "3,18446744073709551617")):
        p = run("labels", LABELRAW, *LABELDIMS, "-o", out, option, value, expect=2)
        typed = value.split(",")[-1]
        assert f"{option}: {typed} is out of range" in p.stderr, p.stderr
    p = run("generate", "sphere", "--size", "99999999999999999999", "-o", os.path.join(D, "g.raw"), expect=2)
    assert "99999999999999999999" in p.stderr, p.stderr
    p = run("contour", LABELRAW, "--dims", 10, 9, "99999999999999999999", "--iso", 1, "-o", out, expect=2)
    assert "99999999999999999999" in p.stderr, p.stderr
    assert not os.path.exists(out)
    # Leading zeros are decimal, not octal: --smooth 010 smooths 10 times.
    rep = os.path.join(D, "s.json")
    run("labels", LABELRAW, *LABELDIMS, "-o", out, "--smooth", "010", "--report", rep, "-q")
    assert report(rep)["smooth"] == 10, report(rep)["smooth"]


check("--max-memory applied by labels, pipeline, dual, convert, check and quality (1 byte refused, 4G runs)",
      max_memory_applied)
check("pipeline --subdivide 6 --max-memory 16M refused as subdivide --levels 6 is", pipeline_subdivision_checked)
check("--max-memory messages show both sizes in a unit that tells them apart", sizes_tell_apart)
check("integer options past 64 bits refused naming the value as typed; leading zeros read as decimal",
      integers_not_clamped)
finish(skipped=mpi_checks())  # 77 when mpirun or MPI is missing (the one-process checks still count)
