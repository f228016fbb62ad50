"""Hardening of the readers and writers, round three (issue 34), end to end
through the `keymesh` command:

- DICOM: a slice whose PixelData holds fewer bytes than rows x columns x
  bits/8 is refused by name on every read path (GDCM zero-filled it: a slice
  of 2 of its 60 bytes was read as [100, 0, 0, ...]); a slice at z = 1e300 is
  refused for its position, not reported as two slices "at the same position";
- Zarr: chunk existence from one directory listing (an array of 8.4 million
  absent chunks made as many stat() calls); a chunk that is a link loop or a
  dangling link is an error naming the chunk, only an absent chunk is fill_value;
- glTF: a point field holding NaN or inf is refused by name (glTF accessors
  must be finite); fields whose attribute names collide are all written,
  renamed with a warning, every accessor used (checked by the Khronos
  validator when `make gltf-validator` installed it);
- paths: a valid long output name is written (its temporary name fits the
  file system's name limit); `-o file/x.ply` says "not a directory"; a
  missing input of an unknown extension says "no such file"; a newline in a
  file name does not split the error line; `-o` a FIFO with no reader is
  refused at once instead of blocking.
"""
import json
import os
import shutil
import subprocess
import sys
import threading
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import KEYMESH, SOURCE_DIR, check, finish, mpirun, parse_glb, run, tempdir  # noqa: E402
from dicom_series import write_dicom_series  # noqa: E402

import numpy as np  # noqa: E402

D = tempdir()


def km(*args, timeout=60, env=None):
    """(returncode, stdout, stderr) of keymesh; never a signal."""
    p = subprocess.run([KEYMESH, *map(str, args)], capture_output=True, text=True, stdin=subprocess.DEVNULL,
                       timeout=timeout, env=env)
    assert p.returncode >= 0, f"keymesh {args}: killed by signal {-p.returncode}\n{p.stderr}"
    return p.returncode, p.stdout, p.stderr


def refused(args, *fragments, timeout=60):
    """Exit 1 and one line on stderr holding every fragment; returns the line."""
    rc, _, err = km(*args, timeout=timeout)
    lines = [line for line in err.splitlines() if line.strip()]
    assert rc == 1, f"keymesh {args}: exit {rc}, expected 1\n{err}"
    assert len(lines) == 1, f"keymesh {args}: expected one line on stderr, got:\n{err}"
    for fragment in fragments:
        assert fragment in lines[0], f"keymesh {args}: '{lines[0]}' lacks '{fragment}'"
    return lines[0]


def path(name):
    return os.path.join(D, name)


# ---- DICOM ---------------------------------------------------------------------------

def series(name, change=None, slices=3):
    """A 3-slice series of 6 x 5 int16 pixels (60 bytes a slice) under the
    file names s0, s1, s2 (in position order); `change(k, dataset)` edits slice k."""
    import pydicom
    volume = np.zeros((slices, 5, 6))
    volume[1, 2, 3] = 100
    folder = path(name)
    write_dicom_series(folder, volume, shuffle=False, names=[f"s{k}" for k in range(slices)])
    if change:
        for k in range(slices):
            f = os.path.join(folder, f"s{k}")
            ds = pydicom.dcmread(f)
            if change(k, ds) is not False:
                ds.save_as(f)
    return folder


def every_read_path(folder, *fragments):
    """info (whole read), contour in memory and streamed plane by plane, and
    the MPI slab reads where mpirun runs: each refuses with the fragments."""
    refused(["info", folder], folder, *fragments)
    out = path("dicom_out.ply")
    refused(["contour", folder, "--iso", "50", "-o", out, "-q"], folder, *fragments)
    refused(["contour", folder, "--iso", "50", "-o", out, "-q", "--memory-limit", "1K"], folder, *fragments)
    assert not os.path.exists(out)
    if shutil.which("mpirun") and mpirun(2, expect=None, program=shutil.which("true")).returncode == 0:
        p = mpirun(2, "contour", folder, "--iso", "50", "-o", out, "-q", expect=None)
        if "built without MPI" not in p.stderr:
            assert p.returncode != 0 and all(f in p.stderr for f in fragments), (p.returncode, p.stderr)
            assert not os.path.exists(out)


def dicom_short_pixel_data_refused():
    """PixelData of 2 bytes, and of 58, where 6 x 5 x 2 = 60 are due: GDCM
    copies what there is and zero-fills the rest without a word (exit 0,
    [100, 0, 0, ...] contoured); now refused naming the slice and both lengths."""
    def short(length):
        def change(k, ds):
            if k == 1:
                ds.PixelData = ds.PixelData[:length]
        return change
    for length in (2, 58):
        folder = series(f"short{length}", short(length))
        every_read_path(folder, "s1", f"PixelData holds {length} bytes", "need 60")
    # The same series whole is read, its one bright voxel where it was written.
    ok = series("whole")
    rc, out, err = km("info", ok)
    assert rc == 0 and "range -100 .. 100" in out, (rc, out, err)


def dicom_odd_8_bit_plane_read():
    """An 8-bit slice of 3 x 5 pixels: PixelData is padded to 16 bytes (DICOM
    values have even length), more than the 15 needed: still read, exactly."""
    def eight_bit(k, ds):
        ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 8, 8, 7, 0
        ds.Rows, ds.Columns = 3, 5
        ds.RescaleSlope, ds.RescaleIntercept = "1", "0"
        ds.PixelData = bytes(range(10 * k, 10 * k + 15)) + b"\0"
    folder = series("odd8", eight_bit)
    raw = path("odd8.raw")
    run("convert", folder, "-o", raw, "-q")
    assert open(raw, "rb").read() == b"".join(bytes(range(10 * k, 10 * k + 15)) for k in range(3))


def dicom_far_positions_named():
    """A slice at z = 1e300 was reported as two others "at the same position"
    (the mean step, 5e299, made their 2.5 mm gap look like nothing): now the
    slice and its position are named. A slice at 1e30 (within float32) leaves
    the others unevenly spaced, and that is what is said."""
    def far(z):
        def change(k, ds):
            if k == 2:
                ds.ImagePositionPatient = ["-20", "10", z]
        return change
    line = refused(["info", series("far1e300", far("1e300"))], "s2", "ImagePositionPatient", "float32")
    assert "same position" not in line, line
    line = refused(["info", series("far1e30", far("1e30"))], "uneven slice spacing")
    assert "same position" not in line, line
    # A repeated slice is still one.
    def repeat(k, ds):
        if k == 2:
            ds.ImagePositionPatient = ["-20", "10", "7.5"]
    refused(["info", series("repeat", repeat)], "s1 and s2 lie at the same position")


check("issue 34: DICOM PixelData shorter than rows x columns x bits refused on every read path",
      dicom_short_pixel_data_refused)
check("issue 34: DICOM 8-bit slices of an odd pixel count (padded PixelData) read exactly", dicom_odd_8_bit_plane_read)
check("issue 34: DICOM slice at z = 1e300 named for its position, not as a repeated slice", dicom_far_positions_named)


# ---- Zarr ----------------------------------------------------------------------------

def zarr_array(name, shape, chunks, separator=".", fill=7):
    folder = path(name)
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, ".zarray"), "w") as f:
        json.dump({"zarr_format": 2, "shape": shape, "chunks": chunks, "dtype": "|u1", "compressor": None,
                   "fill_value": fill, "order": "C", "filters": None, "dimension_separator": separator}, f)
    return folder


def stat_calls(*args):
    """The stat-family system calls `keymesh args` makes (strace -c)."""
    summary = path("strace.txt")
    # LeakSanitizer cannot run under ptrace (the sanitized run's keymesh
    # would exit 99): leaks are that run's other checks' business.
    env = dict(os.environ, ASAN_OPTIONS=(os.environ.get("ASAN_OPTIONS", "") + ":detect_leaks=0").lstrip(":"))
    subprocess.run(["strace", "-f", "-c", "-o", summary, "-e", "trace=stat,lstat,newfstatat,statx,access",
                    KEYMESH, *map(str, args)], capture_output=True, timeout=300, check=True, env=env)
    calls = 0
    for line in open(summary):
        fields = line.split()
        if len(fields) >= 5 and fields[-1] in ("stat", "lstat", "newfstatat", "statx", "access"):
            calls += int(fields[3])
    return calls


def zarr_absent_chunks_listed_once():
    """2 x 512 x 512 one-voxel chunks, none stored (the issue's case was
    2 x 2048 x 2048: 35 s of 8.4 M failed stat() calls): the array is
    fill_value, found from one listing, not 524,288 stat() calls; with '/'
    separators too."""
    for sep in (".", "/"):
        folder = zarr_array(f"absent{sep == '/'}.zarr", [2, 512, 512], [1, 1, 1], sep)
        rc, out, err = km("info", folder, timeout=120)
        assert rc == 0 and "range 7 .. 7" in out, (rc, out, err)
        if shutil.which("strace"):
            calls = stat_calls("info", folder)
            assert calls < 10000, f"{sep}: {calls} stat calls for 524,288 absent chunks"


def zarr_stored_chunks_found_by_listing():
    """Chunks stored among absent ones, '.' and nested '/' keys (a missing
    z directory, a y directory without the x file): each voxel is its chunk's
    value or fill_value."""
    for sep in (".", "/"):
        folder = zarr_array(f"some{sep == '/'}.zarr", [3, 2, 2], [1, 1, 2], sep, fill=9)
        for key, value in (((0, 0, 0), b"\1\2"), ((0, 1, 0), b"\3\4"), ((2, 1, 0), b"\5\6")):
            name = os.path.join(folder, *map(str, key)) if sep == "/" else os.path.join(folder, ".".join(map(str, key)))
            os.makedirs(os.path.dirname(name), exist_ok=True)
            open(name, "wb").write(value)
        raw = path(f"some{sep == '/'}.raw")
        run("convert", folder, "-o", raw, "-q")
        assert open(raw, "rb").read() == bytes([1, 2, 3, 4, 9, 9, 9, 9, 9, 9, 5, 6]), (sep, open(raw, "rb").read())


def zarr_unreadable_chunk_named():
    """A chunk that is a symbolic link to itself was read as fill_value
    (exit 0): only an absent chunk is; a link loop and a dangling link are
    refused naming the chunk."""
    for case, target in (("loop", "0.0.0"), ("dangling", "nowhere")):
        folder = zarr_array(f"{case}.zarr", [2, 2, 2], [1, 2, 2])
        open(os.path.join(folder, "1.0.0"), "wb").write(b"\1\2\3\4")
        os.symlink(target, os.path.join(folder, "0.0.0"))
        refused(["info", folder], folder, "chunk 0.0.0")


check("issue 34: Zarr absent chunks found from one listing, not one stat() each", zarr_absent_chunks_listed_once)
check("issue 34: Zarr chunks stored among absent ones read from the listing ('.' and '/')",
      zarr_stored_chunks_found_by_listing)
check("issue 34: a Zarr chunk that is a link loop or dangling link is refused by name", zarr_unreadable_chunk_named)


# ---- glTF ----------------------------------------------------------------------------

def vtp_with_fields(name, fields):
    """A one-triangle .vtp whose point fields are (name, components, values text)."""
    arrays = "".join(f'<DataArray type="Float32" Name="{n}" NumberOfComponents="{c}">{v}</DataArray>'
                     for n, c, v in fields)
    text = ('<VTKFile type="PolyData"><PolyData><Piece NumberOfPoints="3" NumberOfPolys="1">'
            f"<PointData>{arrays}</PointData>"
            '<Points><DataArray type="Float32" NumberOfComponents="3">0 0 0 1 0 0 0 1 0</DataArray></Points>'
            '<Polys><DataArray type="Int32" Name="connectivity">0 1 2</DataArray>'
            '<DataArray type="Int32" Name="offsets">3</DataArray></Polys></Piece></PolyData></VTKFile>')
    with open(path(name), "w") as f:
        f.write(text)
    return path(name)


VALIDATOR = os.environ.get("KEYMESH_GLTF_VALIDATOR",
                           os.path.join(os.path.dirname(os.path.abspath(KEYMESH)), "node", "node_modules",
                                        "gltf-validator"))


def validator_errors(glb):
    """The Khronos validator's error count and codes, or None without it."""
    if not shutil.which("node") or not os.path.isfile(os.path.join(VALIDATOR, "package.json")):
        return None
    p = subprocess.run(["node", os.path.join(SOURCE_DIR, "tests", "gltf_validate.js"), VALIDATOR, glb],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    r = json.loads(p.stdout.splitlines()[0])
    return r["errors"], r["codes"]


def gltf_non_finite_fields_refused():
    """A point field holding NaN, inf or -inf wrote "min":[null] or NaN
    accessor data (invalid glTF): refused naming the field, no file written."""
    for value in ("nan", "inf", "-inf"):
        vtp = vtp_with_fields(f"nonfinite_{value}.vtp", [("ok", 1, "1 2 3"), ("temperature", 1, f"1 {value} 3")])
        out = path(f"nonfinite_{value}.glb")
        refused(["convert", vtp, "-o", out, "-q"], out, "'temperature'", "point 1", "finite")
        assert not os.path.exists(out)
    # Normals with NaN and inf: NORMAL is made unit (mesh/unit_normals.hpp), valid glTF.
    vtp = vtp_with_fields("nan_normals.vtp", [("Normals", 3, "nan nan nan inf 0 0 0 0 1")])
    out = path("nan_normals.glb")
    run("convert", vtp, "-o", out, "-q")
    doc, binary = parse_glb(out)
    normal = doc["accessors"][doc["meshes"][0]["primitives"][0]["attributes"]["NORMAL"]]
    assert None not in normal["min"] + normal["max"], normal
    errors = validator_errors(out)
    assert errors is None or errors[0] == 0, errors


def gltf_colliding_names_all_written():
    """Fields "a b" and "a-b" both became _A_B: one was dropped silently and
    its accessor left unused. Now the second is _A_B_2 (a warning says so),
    a second "Normals" is _NORMALS, and every accessor is used."""
    vtp = vtp_with_fields("names.vtp", [("a b", 1, "1 2 3"), ("a-b", 1, "4 5 6"), ("a.b", 1, "7 8 9"),
                                        ("Normals", 3, "0 0 1 0 0 1 0 0 1"), ("Normals", 3, "1 0 0 1 0 0 1 0 0")])
    out = path("names.glb")
    p = run("convert", vtp, "-o", out, "-q")
    assert "'a-b' written as glTF attribute _A_B_2" in p.stderr, p.stderr
    assert "'a.b' written as glTF attribute _A_B_3" in p.stderr, p.stderr
    doc, binary = parse_glb(out)
    attributes = doc["meshes"][0]["primitives"][0]["attributes"]
    assert set(attributes) == {"POSITION", "NORMAL", "_A_B", "_A_B_2", "_A_B_3", "_NORMALS"}, attributes
    used = set(attributes.values()) | {doc["meshes"][0]["primitives"][0]["indices"]}
    assert used == set(range(len(doc["accessors"]))), (used, len(doc["accessors"]))
    first = [doc["accessors"][attributes[a]]["min"][0] for a in ("_A_B", "_A_B_2", "_A_B_3")]
    assert first == [1.0, 4.0, 7.0], first
    errors = validator_errors(out)
    assert errors is None or errors[0] == 0, errors


check("issue 34: glTF point fields holding NaN/inf refused by name; NaN normals made unit",
      gltf_non_finite_fields_refused)
check("issue 34: glTF attribute names made unique with a warning, none dropped, every accessor used",
      gltf_colliding_names_all_written)


# ---- output and input paths ----------------------------------------------------------

MESH = vtp_with_fields("plain.vtp", [("f", 1, "1 2 3")])


def long_output_names_written():
    """A 249-byte file name (valid up to 255) was refused: its temporary name
    "<name>.tmp-<pid>-<n>" passed 255 bytes. 249 and 255 bytes are written,
    no temporary left; 256 bytes is refused before any work (not by the
    rename at the end), by name."""
    folder = path("long")
    os.makedirs(folder, exist_ok=True)
    for length in (249, 255):
        name = "n" * (length - 4) + ".ply"
        run("convert", MESH, "-o", os.path.join(folder, name), "-q")
        assert os.listdir(folder) == [name], os.listdir(folder)
        os.remove(os.path.join(folder, name))
    refused(["convert", MESH, "-o", os.path.join(folder, "n" * 252 + ".ply"), "-q"],
            "cannot write: File name too long (256 bytes")
    assert os.listdir(folder) == []


def output_under_a_file_named():
    """`-o not_a_dir.txt/x.ply` said "Permission denied"."""
    open(path("not_a_dir.txt"), "w").close()
    line = refused(["convert", MESH, "-o", path("not_a_dir.txt/x.ply"), "-q"], "not a directory")
    assert "Permission denied" not in line, line


def missing_input_named_missing():
    """A missing input of an unknown extension said "unknown volume format"
    (and a missing mesh "unknown mesh file extension"): the cause is that it
    is not there."""
    refused(["info", path("missing.xyz")], path("missing.xyz"), "no such file")
    refused(["convert", path("missing.xyz"), "-o", path("m.ply"), "-q"], path("missing.xyz"), "no such file")
    # An existing file of an unknown extension is still named for its format.
    open(path("present.xyz"), "w").close()
    refused(["info", path("present.xyz")], "unknown volume format")


def newline_in_file_names_escaped():
    """A newline in a file name split the error line in two: it is written
    as \\n, and the message stays one line."""
    bad = path("two\nlines.vti")
    line = refused(["info", bad], "two\\nlines.vti", "no such file")
    assert "\n" not in line
    refused(["convert", MESH, "-o", path("no\ndir/x.ply"), "-q"], "no\\ndir/x.ply")


def fifo_without_reader_refused():
    """`-o` a FIFO nobody reads blocked forever in open(); now refused at once.
    With a reader, the mesh goes through the FIFO as before."""
    fifo = path("out.ply")
    os.mkfifo(fifo)
    refused(["convert", MESH, "-o", fifo, "-q"], fifo, "FIFO with no reader", timeout=20)
    received = []
    reader = threading.Thread(target=lambda: received.append(open(fifo, "rb").read()), daemon=True)
    reader.start()
    run("convert", MESH, "-o", fifo, "-q")
    reader.join(20)
    assert received and received[0].startswith(b"ply\n"), received



def fifo_reader_gone_named():
    """A FIFO whose reader closes partway: keymesh died by SIGPIPE; now the
    write fails by name (Broken pipe) and exits 1."""
    big = path("big.ply")
    run("generate", "sphere", "--size", "96", "-o", path("s96.vti"), "-q")
    run("contour", path("s96.vti"), "-o", big, "--iso", "40.5", "-q")
    assert os.path.getsize(big) > 1 << 20  # well past a pipe's 64 KiB buffer
    fifo = path("partway.ply")
    os.mkfifo(fifo)

    def read_a_little():
        with open(fifo, "rb") as f:
            f.read(100)

    reader = threading.Thread(target=read_a_little, daemon=True)
    reader.start()
    time.sleep(0.2)  # the reader is waiting in open() before keymesh opens the FIFO
    refused(["convert", big, "-o", fifo, "-q"], fifo, "Broken pipe", timeout=60)
    reader.join(20)

check("issue 34: output names of 249 and 255 bytes written (the temporary name fits NAME_MAX)",
      long_output_names_written)
check("issue 34: -o under a regular file says 'not a directory'", output_under_a_file_named)
check("issue 34: a missing input of an unknown extension says 'no such file'", missing_input_named_missing)
check("issue 34: a newline in a file name is escaped: one error line", newline_in_file_names_escaped)
check("issue 34: -o a FIFO with no reader refused at once, not a hang", fifo_without_reader_refused)
check("issue 34: a FIFO whose reader leaves partway: the write fails by name, no SIGPIPE", fifo_reader_gone_named)
finish()
