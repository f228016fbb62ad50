"""`keymesh labels --format precomputed` end to end (issue 37), read back by the
independent reader tests/neuroglancer_precomputed.py (its own murmurhash and
gzip, Debian's draco_decoder for every fragment): the info's type, every
fragment decoded, neighbouring nodes' decoded points equal on their common
face at every level, chunk tasks plus --assemble byte-identical to one call,
--update equal to a full run on the edited volume, and the refusals."""
import filecmp
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import (balls_atlas, check, finish, report, run, tempdir, precomputed_reader,  # noqa: E402
                    write_label_nrrd)

np, ngp = precomputed_reader()
D = tempdir()


atlas = balls_atlas
VOLUME = atlas((40, 36, 30), 1)
IN = write_label_nrrd(os.path.join(D, "atlas.nrrd"), VOLUME)
GRID = ["--lods", "3", "--chunk-shape", "16", "16", "16", "--smooth", "4"]


def precomputed(out, *extra, volume=IN):
    return run("labels", volume, "-o", out, "--format", "precomputed", *GRID, *extra)


def same_tree(a, b):
    """Every file of two directories byte for byte (names too)."""
    files = []
    for top in (a, b):
        names = set()
        for root, _, fs in os.walk(top):
            names |= {os.path.relpath(os.path.join(root, f), top) for f in fs}
        files.append(names)
    assert files[0] == files[1], f"files differ: {sorted(files[0] ^ files[1])[:10]}"
    for name in files[0]:
        assert filecmp.cmp(os.path.join(a, name), os.path.join(b, name), shallow=False), f"{name} differs"


ONE = os.path.join(D, "one")
precomputed(ONE, "--report", os.path.join(D, "one.json"))


def face_points(fragment, axis, plane):
    """Decoded points of a fragment on the plane `axis` = plane, those on the
    face's border lines (lod-0 chunk edge lines, shared by four chunks)
    included."""
    p = fragment.points
    return {tuple(x) for x in p[p[:, axis] == plane]}


def noise(shape, seed):
    """White noise of labels 1-4: thin, touching, self-touching regions that cross every chunk edge line."""
    return np.random.default_rng(seed).integers(1, 5, shape).astype(np.uint8)


def test_info_and_fragments():
    info = ngp.read_info(ONE)
    assert info["@type"] == "neuroglancer_multilod_draco", info
    assert info["lod_scale_multiplier"] == 1
    r = report(os.path.join(D, "one.json"))
    assert r["format"] == "precomputed" and r["lods"] == 3 and r["chunks"] == [3, 3, 2], r
    segments = sorted(ngp.segment_ids(ONE))
    assert segments == sorted(int(v) for v in np.unique(VOLUME) if v), segments
    decoded = 0
    for s in segments:
        mesh = ngp.read_segment(ONE, s, info)
        ngp.check_octree(mesh.manifest)
        assert mesh.manifest.num_lods == 3
        decoded += sum(1 for f in mesh.fragments if f.size)
    assert decoded > 3 * len(segments)


def faces_agree(out):
    """At every level, two neighbouring nodes' decoded points on their common
    face are the same, the face's edge lines included. Returns how many points
    were compared, and how many of them lie on a lod-0 chunk edge line."""
    info = ngp.read_info(out)
    compared = on_lines = 0
    for s in ngp.segment_ids(out):
        mesh = ngp.read_segment(out, s, info)
        nodes = {(f.lod, tuple(f.position)): f for f in mesh.fragments if f.size}
        for (lod, pos), f in nodes.items():
            origin, size = ngp.node_box(mesh.manifest, lod, pos)
            for axis in range(3):
                nxt = list(pos)
                nxt[axis] += 1
                g = nodes.get((lod, tuple(nxt)))
                plane = origin[axis] + size[axis]
                mine = face_points(f, axis, plane)
                theirs = face_points(g, axis, plane) if g else set()
                assert mine == theirs, (f"segment {s} lod {lod} node {pos} axis {axis}: "
                                        f"{len(mine ^ theirs)} of {len(mine | theirs)} points differ: "
                                        f"{sorted(mine - theirs)[:3]} / {sorted(theirs - mine)[:3]}")
                compared += len(mine)
                on_lines += sum(1 for x in mine if on_edge_line(x, axis, mesh.manifest.chunk_shape))
    return compared, on_lines


def on_edge_line(point, axis, chunk_shape):
    """Whether a decoded point of the plane normal to `axis` lies on a lod-0
    chunk plane along another axis too (planes at -1 + k * shape)."""
    return any(((point[a] + 1) / chunk_shape[a]).is_integer() for a in range(3) if a != axis)


def test_faces_agree_in_decoded_output():
    compared, on_lines = faces_agree(ONE)
    assert compared > 100 and on_lines > 10, (compared, on_lines)


def test_noise_faces_agree_on_edge_lines():
    """Noise volumes, both methods, 4 levels, 8^3 chunks: at every level the
    face point sets agree, the points on chunk edge lines included."""
    for seed, method in ((3, "surfacenets"), (4, "discrete-mc"), (5, "surfacenets")):
        vol = write_label_nrrd(os.path.join(D, f"noise{seed}.nrrd"), noise((20, 19, 21), seed))
        out = os.path.join(D, f"noise{seed}")
        run("labels", vol, "-o", out, "--format", "precomputed", "--lods", "4", "--chunk-shape", "8", "8", "8",
            "--method", method, "--smooth", str(seed))
        compared, on_lines = faces_agree(out)
        assert compared > 1000 and on_lines > 100, (seed, method, compared, on_lines)


def test_issue_settings_discrete_mc_sharded():
    """The issue's check: 3 levels of detail, 32^3 chunks; here with discrete-mc and --sharded."""
    big = write_label_nrrd(os.path.join(D, "big.nrrd"), atlas((70, 66, 60), 2))
    out = os.path.join(D, "big")
    run("labels", big, "-o", out, "--format", "precomputed", "--lods", "3", "--chunk-shape", "32", "32", "32",
        "--method", "discrete-mc", "--sharded")
    info = ngp.read_info(out)
    assert info["@type"] == "neuroglancer_multilod_draco" and "sharding" in info, info
    compared, on_lines = faces_agree(out)
    assert compared > 100 and on_lines > 10, (compared, on_lines)


def test_chunk_tasks_and_assembly_equal_one_call():
    tasks = os.path.join(D, "tasks")
    chunks = report(os.path.join(D, "one.json"))["chunks"]
    for k in range(chunks[2]):
        for j in range(chunks[1]):
            for i in range(chunks[0]):
                precomputed(tasks, "--chunk", i, j, k)
    precomputed(tasks, "--assemble")
    same_tree(ONE, tasks)


def test_chunk_task_reads_only_its_planes():
    """A chunk task of a raw NRRD reads the planes of its box (chunk + halo)
    only (report: samples_read); its pieces and the assembled output equal
    one call's, and a gzip NRRD (inflated in order, only the box's planes
    kept) gives the same bytes."""
    tall = atlas((20, 18, 80), 3)
    raw = write_label_nrrd(os.path.join(D, "tall.nrrd"), tall)
    gz = os.path.join(D, "tall_gz.nrrd")
    with open(raw, "rb") as f:
        header, samples = f.read().split(b"\n\n", 1)
    import gzip
    with open(gz, "wb") as f:
        f.write(header.replace(b"encoding: raw", b"encoding: gzip") + b"\n\n" + gzip.compress(samples))
    one, tasks = os.path.join(D, "tall_one"), os.path.join(D, "tall_tasks")
    precomputed(one, volume=raw)
    whole = tall.size
    halo = 2 * 4 + 4  # --smooth 4: surface nets reach 2 cells a step (the fold guard), + 4
    for k in range(6):  # (80 + 16) // 16 chunks along z
        for j in range(2):
            for i in range(2):
                r_path = os.path.join(D, "task.json")
                precomputed(tasks, "--chunk", i, j, k, "--report", r_path, volume=raw)
                lo, hi = max(16 * k - 1 - halo, 0), min(16 * (k + 1) - 1 + halo, 79)
                assert report(r_path)["samples_read"] == 20 * 18 * (hi - lo + 1) < whole, (k, report(r_path))
    precomputed(tasks, "--assemble", volume=raw)
    same_tree(one, tasks)
    # The final step in batches (--memory-limit: each segment's pieces then a
    # batch of their own), unsharded and sharded: the same bytes.
    precomputed(tasks, "--assemble", "--memory-limit", "1K", "--report", os.path.join(D, "batches.json"), volume=raw)
    same_tree(one, tasks)
    segments = len(ngp.segment_ids(one))
    assert segments > 3 and report(os.path.join(D, "batches.json"))["assemble_batches"] == segments
    sharded_one, sharded_tasks = os.path.join(D, "tall_sharded_one"), os.path.join(D, "tall_sharded_tasks")
    precomputed(sharded_one, "--sharded", volume=raw)
    for k in range(6):
        for j in range(2):
            for i in range(2):
                precomputed(sharded_tasks, "--sharded", "--chunk", i, j, k, volume=raw)
    precomputed(sharded_tasks, "--sharded", "--assemble", "--memory-limit", "1K", volume=raw)
    same_tree(sharded_one, sharded_tasks)
    from_gz, from_raw = os.path.join(D, "tall_gz_task"), os.path.join(D, "tall_raw_task")
    precomputed(from_gz, "--chunk", 1, 0, 3, "--report", os.path.join(D, "gz.json"), volume=gz)
    precomputed(from_raw, "--chunk", 1, 0, 3, volume=raw)
    same_tree(from_gz, from_raw)
    assert report(os.path.join(D, "gz.json"))["samples_read"] == 20 * 18 * (63 + halo - (48 - 1 - halo) + 1)


def test_update_equals_full_run():
    edited = VOLUME.copy()
    edited[0:15, 0:15, 0:15] = 0  # chunk (0, 0, 0) covers samples -1 .. 14
    edited[3:11, 3:11, 3:11] = 9  # a new label there
    new = write_label_nrrd(os.path.join(D, "edited.nrrd"), edited)
    updated = os.path.join(D, "updated")
    precomputed(updated)
    precomputed(updated, "--update", "0,0,0", "--report", os.path.join(D, "update.json"), volume=new)
    full = os.path.join(D, "full")
    precomputed(full, volume=new)
    same_tree(full, updated)
    r = report(os.path.join(D, "update.json"))
    assert r["route"] == "update" and 9 in ngp.segment_ids(updated), r
    assert r["chunks_written"] == 8, r  # the 2 x 2 x 2 within reach, of 3 x 3 x 2


def test_refusals():
    text = os.path.join(D, "a_file")
    with open(text, "w") as f:
        f.write("x")
    for args, expect, words in [
        (["-o", text, "--format", "precomputed"], 2, "not a directory"),
        (["-o", os.path.join(D, "x.vtp"), "--format", "precomputed"], 2, "names a mesh file"),
        (["-o", os.path.join(D, "c"), "--format", "precomputed", "--coarsen"], 2, "--coarsen does not apply"),
        (["-o", os.path.join(D, "m"), "--format", "precomputed", "--memory-limit", "1M"], 2, "--memory-limit"),
        (["-o", os.path.join(D, "l.vtp"), "--lods", "2"], 2, "--lods needs --format precomputed"),
        (["-o", os.path.join(D, "e"), "--format", "precomputed", "--chunk", "0", "0", "0", "--assemble"], 2,
         "exclude each other"),
        (["-o", os.path.join(D, "u"), "--format", "precomputed", "--update", "1,x,2"], 2, "is not a chunk"),
        (["-o", os.path.join(D, "u"), "--format", "precomputed", "--update", "1,1,1"], 1, "no chunk store"),
        (["-o", os.path.join(D, "o"), "--format", "precomputed", "--chunk", "9", "0", "0"], 1, "outside the grid"),
    ]:
        p = run("labels", IN, *args, expect=expect)
        assert words in p.stderr, (args, p.stderr)
        assert len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert not os.path.exists(os.path.join(D, "u")), "a refused --update wrote something"


def test_label_names():
    """A label table beside the input (MRIcron's IN.txt) names the segments; --label-names overrides it;
    a malformed table is refused by file and line with nothing written."""
    d = os.path.join(D, "named")
    os.makedirs(d, exist_ok=True)
    vol = write_label_nrrd(os.path.join(d, "atlas.nrrd"), VOLUME)
    with open(vol + ".txt", "w") as f:
        f.write("# id name\n0\tBackground\n" + "".join(f"{i} region_{i} {i + 1000}\n" for i in range(1, 9)))
    out = os.path.join(d, "ng")
    precomputed(out, volume=vol)
    names = ngp.segment_names(out)
    assert names == {i: f"region_{i}" for i in range(1, 9)}, names  # the background's entry left out
    assert set(ngp.segment_ids(out)) <= set(names)
    other = os.path.join(d, "other.txt")
    with open(other, "w") as f:
        f.write("3 third\n")
    precomputed(out, "--label-names", other, volume=vol)
    assert ngp.segment_names(out) == {3: "third"}
    bad = os.path.join(d, "bad.txt")
    for text, words in (("1 a\nx b\n", "bad.txt line 2: 'x' is not a label id"),
                        ("1 a\n1 b\n", "line 2: label 1 is named twice"), ("2\n", "label 2 has no name")):
        with open(bad, "w") as f:
            f.write(text)
        p = run("labels", vol, "-o", os.path.join(d, "refused"), "--format", "precomputed", *GRID,
                "--label-names", bad, expect=1)
        assert words in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr
        assert not os.path.exists(os.path.join(d, "refused")), "a refused label table left output"


check("info declares the multilod format; every fragment decodes", test_info_and_fragments)
check("a label table names the segments (segment_properties)", test_label_names)
check("neighbouring nodes agree on their common face in the decoded output", test_faces_agree_in_decoded_output)
check("3 levels, 32^3 chunks, discrete-mc, sharded: faces agree", test_issue_settings_discrete_mc_sharded)
check("noise volumes, both methods, 4 levels: faces agree on chunk edge lines too", test_noise_faces_agree_on_edge_lines)
check("chunk tasks + --assemble are byte-identical to one call", test_chunk_tasks_and_assembly_equal_one_call)
check("a chunk task reads only its box's planes (raw and gzip NRRD): the same bytes",
      test_chunk_task_reads_only_its_planes)
check("--update equals a full run on the edited volume", test_update_equals_full_run)
check("refusals name the cause", test_refusals)
finish()
