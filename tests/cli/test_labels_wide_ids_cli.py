"""`keymesh labels` on the wide integer label maps of connectomics (uint32,
int64, uint64 segmentations: NRRD, NIfTI, raw, .vti, Zarr): the Neuroglancer
segment ids are exactly the volume's 64-bit values, and every segment's
manifest and fragments are byte for byte those of the same volume relabelled
to uint8 ids 1..8 (an increasing map, so the labels' order is the same).
Ids past 2^24 reach the float32 boundary_labels of the mesh formats only by a
refusal that names the label; uint64 ids past 2^63 - 1 are refused by name
(docs/decisions/wide-label-types.md)."""
import filecmp
import gzip
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import balls_atlas, check, finish, run, tempdir, precomputed_reader, write_label_nrrd  # noqa: E402

np, ngp = precomputed_reader()
D = tempdir()
SKIPPED = []

# Labels 1-8 of the uint8 volume become these ids (increasing, background 0 stays 0).
IDS = {
    "uint32": [5, 70000, 16777217, 3_000_000_000, 4_000_000_000, 4_000_000_001, 2**32 - 2, 2**32 - 1],
    "uint64": [7, 2**32, 2**40 + 3, 2**40 + 4, 2**53 + 1, 2**62, 2**63 - 2, 2**63 - 1],
    "int64": [9, 2**31, 2**33 + 5, 2**45, 2**52 + 7, 2**60, 2**62 + 1, 2**63 - 1],
}
NRRD_TYPE = {"uint8": "uint8", "uint32": "uint32", "uint64": "unsigned long long", "int64": "int64"}
GRID = ["--lods", "3", "--chunk-shape", "16", "16", "16", "--smooth", "4"]


SMALL = balls_atlas((40, 36, 30), 1)


def relabelled(dtype, ids, volume=SMALL):
    table = np.zeros(256, dtype=np.dtype(dtype))
    table[1:1 + len(ids)] = np.array(ids, dtype=np.dtype(dtype))
    return table[volume]


def write_nrrd(path, volume, type_name):
    """volume[x, y, z] as a raw little-endian NRRD of NRRD type `type_name`."""
    header = (f"NRRD0004\ntype: {type_name}\ndimension: 3\nsizes: {volume.shape[0]} {volume.shape[1]} "
              f"{volume.shape[2]}\nspacings: 1 1 1\nendian: little\nencoding: raw\n\n")
    with open(path, "wb") as f:
        f.write(header.encode())
        f.write(volume.astype(volume.dtype.newbyteorder("<")).tobytes(order="F"))
    return path


NIFTI_CODE = {np.dtype(np.uint32): 768, np.dtype(np.int64): 1024, np.dtype(np.uint64): 1280}


def write_nifti(path, volume):
    """A NIfTI-1 single file (.nii or .nii.gz) written with numpy: 348-byte
    header, 4 bytes of extension flag, samples x fastest."""
    h = np.zeros(348, np.uint8)
    h[0:4] = np.frombuffer(np.int32(348).tobytes(), np.uint8)
    dim = np.array([3, *volume.shape, 1, 1, 1, 1], "<i2")
    h[40:56] = np.frombuffer(dim.tobytes(), np.uint8)
    h[70:72] = np.frombuffer(np.int16(NIFTI_CODE[volume.dtype]).tobytes(), np.uint8)
    h[72:74] = np.frombuffer(np.int16(8 * volume.dtype.itemsize).tobytes(), np.uint8)
    h[76:108] = np.frombuffer(np.array([1, 1, 1, 1, 1, 1, 1, 1], "<f4").tobytes(), np.uint8)
    h[108:112] = np.frombuffer(np.float32(352).tobytes(), np.uint8)
    h[344:348] = np.frombuffer(b"n+1\0", np.uint8)
    data = h.tobytes() + bytes(4) + volume.astype(volume.dtype.newbyteorder("<")).tobytes(order="F")
    with (gzip.open if path.endswith(".gz") else open)(path, "wb") as f:
        f.write(data)
    return path


def write_zarr(folder, volume):
    """A Zarr v2 array, one uncompressed chunk; the last axis is x."""
    os.makedirs(folder, exist_ok=True)
    zyx = np.ascontiguousarray(volume.transpose(2, 1, 0)).astype(volume.dtype.newbyteorder("<"))
    meta = {"zarr_format": 2, "shape": list(zyx.shape), "chunks": list(zyx.shape), "dtype": zyx.dtype.str,
            "compressor": None, "fill_value": 0, "order": "C", "filters": None}
    with open(os.path.join(folder, ".zarray"), "w") as f:
        json.dump(meta, f)
    with open(os.path.join(folder, "0.0.0"), "wb") as f:
        f.write(zyx.tobytes())
    return folder


def precomputed(volume, out, *extra, expect=0):
    return run("labels", volume, "-o", out, "--format", "precomputed", *GRID, *extra, expect=expect)


def same_tree(a, b):
    names = [sorted(os.path.relpath(os.path.join(r, f), t) for r, _, fs in os.walk(t) for f in fs) for t in (a, b)]
    assert names[0] == names[1], f"files differ: {sorted(set(names[0]) ^ set(names[1]))[:10]}"
    for name in names[0]:
        assert filecmp.cmp(os.path.join(a, name), os.path.join(b, name), shallow=False), f"{name} differs"


def assert_same_segments(small_out, wide_out, ids):
    """Segment ids exactly `ids`; segment k's manifest and fragments those of
    segment k + 1 of the uint8 output; every fragment decodes."""
    assert ngp.segment_ids(wide_out) == sorted(ids), (ngp.segment_ids(wide_out), ids)
    assert ngp.segment_ids(small_out) == list(range(1, len(ids) + 1))
    with open(os.path.join(small_out, "info"), "rb") as a, open(os.path.join(wide_out, "info"), "rb") as b:
        assert a.read() == b.read(), "info differs"
    for k, wide in enumerate(ids):
        assert ngp.read_segment_bytes(wide_out, wide) == ngp.read_segment_bytes(small_out, k + 1), \
            f"segment {wide} differs from segment {k + 1} of the uint8 volume"
    for wide in (ids[0], ids[-1]):
        mesh = ngp.read_segment(wide_out, wide)  # every fragment through draco_decoder
        assert sum(len(f.triangles) for f in mesh.fragments) > 0, f"segment {wide} decoded empty"


SMALL_IN = write_label_nrrd(os.path.join(D, "small.nrrd"), SMALL)
SMALL_OUT = os.path.join(D, "small_out")
precomputed(SMALL_IN, SMALL_OUT)


def wide_nrrd(dtype):
    return write_nrrd(os.path.join(D, f"{dtype}.nrrd"), relabelled(dtype, IDS[dtype]), NRRD_TYPE[dtype])


def test_nrrd_precomputed(dtype):
    out = os.path.join(D, f"{dtype}_out")
    precomputed(wide_nrrd(dtype), out)
    assert_same_segments(SMALL_OUT, out, IDS[dtype])


def test_wide_selection_and_background():
    """--labels and --background by 64-bit id: exactly those segments, each
    as the uint8 volume's run with the small ids."""
    ids = IDS["uint64"]
    picked, small = os.path.join(D, "u64_picked"), os.path.join(D, "u8_picked")
    precomputed(wide_nrrd("uint64"), picked, "--labels", f"{ids[2]},{ids[7]}")
    precomputed(SMALL_IN, small, "--labels", "3,8")
    assert ngp.segment_ids(picked) == [ids[2], ids[7]]
    for k in (2, 7):
        assert ngp.read_segment_bytes(picked, ids[k]) == ngp.read_segment_bytes(small, k + 1), ids[k]
    moved = os.path.join(D, "u64_background")
    precomputed(wide_nrrd("uint64"), moved, "--background", ids[4])
    assert ngp.segment_ids(moved) == sorted([0] + ids[:4] + ids[5:])


def test_nifti_uint32():
    for name in ("u32.nii", "u32.nii.gz"):
        nii = write_nifti(os.path.join(D, name), relabelled("uint32", IDS["uint32"]))
        out = os.path.join(D, name + "_out")
        precomputed(nii, out)
        assert_same_segments(SMALL_OUT, out, IDS["uint32"])


def test_raw_uint64():
    raw = os.path.join(D, "u64.raw")
    with open(raw, "wb") as f:  # x fastest
        f.write(relabelled("uint64", IDS["uint64"]).astype("<u8").tobytes(order="F"))
    out = os.path.join(D, "raw_out")
    dims = [str(n) for n in SMALL.shape]
    precomputed(raw, out, "--dims", *dims, "--type", "uint64")
    assert_same_segments(SMALL_OUT, out, IDS["uint64"])


def test_zarr_and_vti_uint64():
    volume = relabelled("uint64", IDS["uint64"])
    z = write_zarr(os.path.join(D, "u64.zarr"), volume)
    out = os.path.join(D, "zarr_out")
    precomputed(z, out)
    assert_same_segments(SMALL_OUT, out, IDS["uint64"])
    vti = os.path.join(D, "u64.vti")
    run("convert", wide_nrrd("uint64"), "-o", vti)
    out = os.path.join(D, "vti_out")
    precomputed(vti, out)
    assert_same_segments(SMALL_OUT, out, IDS["uint64"])


def test_chunk_tasks_and_update_uint64():
    """Chunk tasks (which read their box's planes) plus --assemble equal one
    call; --update after an edit equals a full run on the edited volume."""
    src = wide_nrrd("uint64")
    one, tasks = os.path.join(D, "u64_one"), os.path.join(D, "u64_tasks")
    precomputed(src, one)
    for i in range(3):
        for j in range(3):
            for k in range(2):
                precomputed(src, tasks, "--chunk", i, j, k)
    precomputed(src, tasks, "--assemble")
    same_tree(one, tasks)
    edited = relabelled("uint64", IDS["uint64"])
    edited[0:15, 0:15, 0:15] = IDS["uint64"][4]
    new = write_nrrd(os.path.join(D, "u64_edited.nrrd"), edited, "uint64")
    full = os.path.join(D, "u64_full")
    precomputed(new, full)
    precomputed(new, one, "--update", "0,0,0")
    for segment in ngp.segment_ids(full):
        assert ngp.read_segment_bytes(one, segment) == ngp.read_segment_bytes(full, segment), segment
    assert ngp.segment_ids(one) == ngp.segment_ids(full)


def test_uint64_past_int64_refused():
    ids = IDS["uint64"][:-1] + [2**63 + 11]
    src = write_nrrd(os.path.join(D, "u64_big.nrrd"), relabelled("uint64", ids), "uint64")
    out = os.path.join(D, "big_out")
    p = precomputed(src, out, expect=1)
    assert "label 9223372036854775819 is past 2^63 - 1" in p.stderr, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert not os.path.exists(os.path.join(out, "info")), "a refused run wrote output"


def test_mesh_formats_exact_ids():
    """.vtp of a uint32 volume with ids within 2^24: boundary_labels are the
    uint8 volume's mapped through the ids, the mesh the same, also streamed
    (--memory-limit); ids past 2^24 are refused by name."""
    ids = [3, 100, 1000, 65536, 70000, 1_000_000, 16_000_000, 2**24]
    src = write_nrrd(os.path.join(D, "u32_small.nrrd"), relabelled("uint32", ids), "uint32")
    small_vtp, wide_vtp, streamed = (os.path.join(D, n) for n in ("s.vtp", "w.vtp", "w_stream.vtp"))
    run("labels", SMALL_IN, "-o", small_vtp, "--per-label")
    run("labels", src, "-o", wide_vtp, "--per-label")
    run("labels", src, "-o", streamed, "--per-label", "--memory-limit", "64K")
    import kmtest
    kmtest.require_vtk()
    from vtk.util.numpy_support import vtk_to_numpy
    a, b, c = (kmtest.read_polydata(p) for p in (small_vtp, wide_vtp, streamed))
    table = np.array([0] + ids, np.float64)
    for name in ("boundary_labels", "label"):
        pa = vtk_to_numpy(a.GetCellData().GetArray(name)).astype(np.int64)
        pb = vtk_to_numpy(b.GetCellData().GetArray(name)).astype(np.float64)
        assert np.array_equal(table[pa], pb), name
        assert np.array_equal(pb, vtk_to_numpy(c.GetCellData().GetArray(name))), name
    assert np.array_equal(kmtest.points_of(a), kmtest.points_of(b))
    assert np.array_equal(kmtest.triangles_of(a), kmtest.triangles_of(b))
    p = run("labels", wide_nrrd("uint32"), "-o", os.path.join(D, "big.vtp"), expect=1)
    assert "label 4294967295 is past 2^24" in p.stderr and "precomputed" in p.stderr, p.stderr
    assert not os.path.exists(os.path.join(D, "big.vtp"))


def test_mpirun_uint64():
    """Under mpirun the ranks read their slabs of a uint64 volume: the
    gathered .vtp is the one process's, byte for byte."""
    import shutil
    import kmtest
    if not shutil.which("mpirun"):
        SKIPPED.append("mpirun not found")
        return
    ids = [2, 30, 400, 5000, 60000, 700000, 8_000_000, 16_000_000]
    src = write_nrrd(os.path.join(D, "u64_mpi.nrrd"), relabelled("uint64", ids), "uint64")
    one, two = os.path.join(D, "mpi1.vtp"), os.path.join(D, "mpi2.vtp")
    run("labels", src, "-o", one, "--per-label", "-q")
    kmtest.mpirun(2, "labels", src, "-o", two, "--per-label", "-q")
    assert filecmp.cmp(one, two, shallow=False), "mpirun -np 2 differs from one process"


def test_distinct_label_limit_per_chunk_box():
    """67,032 distinct uint32 ids (every voxel its own segment): one call is
    refused by the 65,536-label limit, the message giving the true count
    (67,033 with the background) and the limit; streamed (--memory-limit),
    whose scan stops counting past the limit, it says "at least 65537"; a
    --chunk task scans only its box (chunk + halo, 13^3 here), so chunk
    tasks are the workaround."""
    shape = (42, 42, 38)
    index = np.arange(np.prod(shape), dtype=np.uint64).reshape(shape, order="F")
    ids = (index * 58_000 + 5).astype(np.uint32)
    assert len(np.unique(ids)) == ids.size
    src = write_nrrd(os.path.join(D, "many.nrrd"), ids, "uint32")
    grid = ["--format", "precomputed", "--lods", "2", "--chunk-shape", "8", "8", "8", "--smooth", "0"]
    p = run("labels", src, "-o", os.path.join(D, "many_one"), *grid, expect=1)
    said = [line for line in p.stderr.splitlines() if line.strip()]
    assert len(said) == 1 and said[0].endswith(
        ": labels: the volume holds 67033 distinct labels (background included), more than the supported 65536"), \
        p.stderr
    # A mesh file holds ids under 2^24 only (float32 boundary_labels): the same volume, ids 200 apart.
    small = write_nrrd(os.path.join(D, "many_small.nrrd"), (index * 200 + 5).astype(np.uint32), "uint32")
    p = run("labels", small, "-o", os.path.join(D, "many_streamed.vtp"), "--memory-limit", "64K", "-q", expect=1)
    said = [line for line in p.stderr.splitlines() if line.strip()]
    assert len(said) == 1 and said[0].endswith(
        ": labels: the volume holds at least 65537 distinct labels (background included), "
        "more than the supported 65536"), p.stderr
    assert not os.path.exists(os.path.join(D, "many_streamed.vtp"))
    tasks = os.path.join(D, "many_tasks")
    run("labels", src, "-o", tasks, *grid, "--chunk", 0, 0, 0)
    assert os.listdir(os.path.join(tasks, "chunks")), "the chunk task kept no pieces"


def test_contour_refuses_wide_samples():
    p = run("contour", wide_nrrd("uint64"), "-o", os.path.join(D, "c.vtp"), "--iso", "0.5", expect=1)
    assert "uint64 samples are label ids, which keymesh labels" in p.stderr, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1, p.stderr


for t in ("uint32", "uint64", "int64"):
    check(f"NRRD {t} to precomputed: exact ids, fragments as the uint8 volume's", lambda t=t: test_nrrd_precomputed(t))
check("--labels and --background by 64-bit id", test_wide_selection_and_background)
check("NIfTI uint32 (.nii, .nii.gz) to precomputed", test_nifti_uint32)
check("raw --type uint64 to precomputed", test_raw_uint64)
check("Zarr <u8 and .vti UInt64 to precomputed", test_zarr_and_vti_uint64)
check("uint64 chunk tasks + --assemble equal one call; --update equals a full run", test_chunk_tasks_and_update_uint64)
check("uint64 id past 2^63 - 1: one-line refusal naming it, no output", test_uint64_past_int64_refused)
check(".vtp of a uint32 volume: boundary_labels exact, streamed too; past 2^24 refused", test_mesh_formats_exact_ids)
check("mpirun -np 2 on a uint64 volume: byte-identical to one process", test_mpirun_uint64)
check("67,032 distinct uint32 ids: one call refused with the true count (streamed: at least 65537), a chunk task runs", test_distinct_label_limit_per_chunk_box)
check("contour of a uint64 volume: refused, naming labels", test_contour_refuses_wide_samples)
finish(skipped="; ".join(SKIPPED) or None)
