"""keymesh.labels_precomputed and keymesh.dask.labels_precomputed (issue 37):
Neuroglancer multi-resolution meshes from a label volume in memory and from
a chunked Dask array, every file (the chunks/ store included) byte-identical
to `keymesh labels IN -o DIR --format precomputed` on the same volume written
as NRRD, for any Dask chunking and scheduler; read back by the independent
reader tests/neuroglancer_precomputed.py; bad arguments refused with the
interpreter alive and nothing written."""
import filecmp
import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

import keymesh

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import kmtest  # noqa: E402
import neuroglancer_precomputed as ngp  # noqa: E402

EXE = os.environ.get("KEYMESH")
OPTIONS = dict(lods=3, chunk_shape=(16, 16, 16), smooth=4)
CLI_OPTIONS = ["--lods", "3", "--chunk-shape", "16", "16", "16", "--smooth", "4"]


def atlas(shape=(40, 36, 30), seed=1):
    """tests/cli/test_labels_precomputed_cli.py's atlas."""
    return kmtest.balls_atlas(shape, seed)


def tree(top):
    names = set()
    for root, _, files in os.walk(top):
        names |= {os.path.relpath(os.path.join(root, f), top) for f in files}
    return names


def assert_same_tree(got, want):
    """Every file of two directories byte for byte, names too."""
    names = tree(want)
    assert tree(got) == names, sorted(tree(got) ^ names)[:10]
    assert any(n.startswith("chunks" + os.sep) for n in names) and "info" in names
    for name in sorted(names):
        assert filecmp.cmp(os.path.join(got, name), os.path.join(want, name), shallow=False), f"{name} differs"


@pytest.fixture(scope="module")
def cli_run(tmp_path_factory):
    """The CLI's one-call output and report for the atlas and for a discrete-mc, sharded, named variant."""
    if not EXE or not shutil.which(EXE):
        pytest.skip("no keymesh binary (KEYMESH)")
    d = tmp_path_factory.mktemp("cli")
    volume = atlas()
    nrrd = kmtest.write_label_nrrd(str(d / "atlas.nrrd"), volume)
    table = d / "names.txt"
    table.write_text("0 Background\n" + "".join(f"{i} region_{i}\n" for i in range(1, 9)))
    runs = {}
    for name, extra in (("plain", []), ("dmc", ["--method", "discrete-mc", "--sharded", "--label-names", str(table)])):
        out, report = str(d / name), str(d / f"{name}.json")
        subprocess.run([EXE, "labels", nrrd, "-o", out, "--format", "precomputed", *CLI_OPTIONS, *extra, "-q",
                        "--report", report], check=True)
        with open(report) as f:
            runs[name] = (out, json.load(f))
    return volume, runs, str(table)


def assert_report(got, cli_report):
    assert len(got["segments"]) == cli_report["segments"]
    assert got["pieces"] == cli_report["pieces"] and got["chunks_written"] == cli_report["chunks_written"]
    assert got["triangles_per_lod"] == cli_report["triangles_per_lod"] and len(got["triangles_per_lod"]) == 3


def test_in_memory_equals_the_cli(cli_run, tmp_path):
    volume, runs, _ = cli_run
    want, cli_report = runs["plain"]
    out = tmp_path / "ng"
    for order in ("C", "F"):  # either memory order: the same bytes
        shutil.rmtree(out, ignore_errors=True)
        report = keymesh.labels_precomputed(np.asarray(volume, order=order), out, **OPTIONS, threads=2)
        assert_same_tree(str(out), want)
    assert_report(report, cli_report)
    assert report["segments"] == [int(v) for v in np.unique(volume) if v]


def test_read_back(cli_run, tmp_path):
    """The reader decodes every fragment of the in-memory output (draco_decoder)."""
    if not ngp.DRACO_DECODER:
        pytest.skip("draco_decoder not found (Debian package draco)")
    volume, _, _ = cli_run
    out = str(tmp_path / "ng")
    keymesh.labels_precomputed(volume, out, **OPTIONS)
    info = ngp.read_info(out)
    assert info["@type"] == "neuroglancer_multilod_draco"
    segments = sorted(ngp.segment_ids(out))
    assert segments == [int(v) for v in np.unique(volume) if v]
    for s in segments:
        mesh = ngp.read_segment(out, s, info)
        ngp.check_octree(mesh.manifest)
        assert mesh.manifest.num_lods == 3
        assert sum(len(f.triangles) for f in mesh.fragments if f.lod == 0) > 0


def test_discrete_mc_sharded_named_equals_the_cli(cli_run, tmp_path):
    volume, runs, table = cli_run
    want, cli_report = runs["dmc"]
    out = str(tmp_path / "ng")
    report = keymesh.labels_precomputed(volume, out, **OPTIONS, method="discrete-mc", sharded=True, label_names=table)
    assert_same_tree(out, want)
    assert_report(report, cli_report)
    if ngp.DRACO_DECODER:
        assert ngp.segment_names(out) == {i: f"region_{i}" for i in range(1, 9)}
    # the same names as a dict: the same bytes (the background's entry left out)
    shutil.rmtree(out)
    keymesh.labels_precomputed(volume, out, **OPTIONS, method="discrete_marching_cubes", sharded=True,
                               label_names={i: f"region_{i}" for i in range(0, 9)})
    assert_same_tree(out, want)


# Dask chunkings of the (40, 36, 30) atlas: even, uneven, and chunks of one plane.
CHUNKINGS = [
    (13, 12, 10),
    ((7, 1, 25, 7), (36,), (2, 17, 11)),
    ((40,), (36,), (1,) * 30),
]


@pytest.mark.parametrize("chunks", CHUNKINGS)
@pytest.mark.parametrize("scheduler", ["threads", "synchronous"])
def test_dask_equals_the_cli(cli_run, tmp_path, chunks, scheduler):
    da = pytest.importorskip("dask.array")
    import keymesh.dask
    volume, runs, _ = cli_run
    want, cli_report = runs["plain"]
    out = str(tmp_path / "ng")
    array = da.from_array(volume, chunks=chunks)
    report = keymesh.dask.labels_precomputed(array, out, **OPTIONS, scheduler=scheduler)
    assert_same_tree(out, want)
    assert_report(report, cli_report)


def test_dask_delayed_discrete_mc_sharded(cli_run, tmp_path):
    """compute=False: a Delayed whose result is the report; nothing is written before it runs."""
    da = pytest.importorskip("dask.array")
    from dask.delayed import Delayed
    import keymesh.dask
    volume, runs, table = cli_run
    want, cli_report = runs["dmc"]
    out = str(tmp_path / "ng")
    graph = keymesh.dask.labels_precomputed(da.from_array(volume, chunks=(11, 9, 8)), out, **OPTIONS,
                                            method="discrete-mc", sharded=True, label_names=table, compute=False)
    assert isinstance(graph, Delayed) and not os.path.exists(out)
    report = graph.compute(scheduler="threads")
    assert_same_tree(out, want)
    assert_report(report, cli_report)


def with_negative_label(volume):
    v = volume.astype(np.int16)
    v[5, 4, 3] = -2
    return v


def test_bad_arguments(tmp_path):
    volume = atlas((12, 10, 9))
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    cases = [
        (dict(path=a_file), ValueError, "is not a directory"),
        (dict(path=tmp_path / "x.vtp"), ValueError, "names a mesh file"),
        (dict(lods=0), ValueError, "lods must be in \\[1, 20\\]"),
        (dict(lods=21), ValueError, "lods must be in \\[1, 20\\]"),
        (dict(chunk_shape=(16, 1, 16)), ValueError, "chunk_shape\\[1\\] must be in \\[2, 1048576\\]"),
        (dict(chunk_shape=(16, 16)), ValueError, "chunk_shape must be 3 integers"),
        (dict(method="marching"), ValueError, "method must be"),
        (dict(smooth=-1), ValueError, "smooth must be in"),
        (dict(relaxation=0), ValueError, "relaxation must be in"),
        (dict(volume=volume.astype(np.float32)), keymesh.Error, "not a label map"),
        (dict(volume=with_negative_label(volume)), keymesh.Error, "label -2 is negative"),
        (dict(volume=volume[0]), ValueError, "3-D"),
        (dict(label_names=42), TypeError, "label_names must be"),
        (dict(label_names=tmp_path / "none.txt"), keymesh.Error, "none.txt"),
    ]
    for change, error, words in cases:
        args = dict(volume=volume, path=tmp_path / "out", lods=2, chunk_shape=(8, 8, 8))
        args.update(change)
        with pytest.raises(error, match=words):
            keymesh.labels_precomputed(args.pop("volume"), args.pop("path"), **args)
        assert not os.path.exists(tmp_path / "out"), (change, "a refused call wrote output")
    assert keymesh.labels_precomputed(volume, tmp_path / "out", lods=2, chunk_shape=(8, 8, 8))["pieces"] > 0


def test_dask_bad_arguments(tmp_path):
    da = pytest.importorskip("dask.array")
    import keymesh.dask
    volume = atlas((12, 10, 9))
    with pytest.raises(keymesh.Error, match="not a label map"):
        keymesh.dask.labels_precomputed(da.from_array(volume.astype(np.float64)), tmp_path / "o")
    with pytest.raises(ValueError, match="lods must be"):
        keymesh.dask.labels_precomputed(da.from_array(volume), tmp_path / "o", lods=30)
    with pytest.raises(ValueError, match="names a mesh file"):
        keymesh.dask.labels_precomputed(da.from_array(volume), tmp_path / "o.ply")
    # a refusal of the data itself comes from the chunk task that meets it; no output is assembled
    negative = da.from_array(with_negative_label(volume), chunks=4)
    with pytest.raises(keymesh.Error, match="label -2 is negative"):
        keymesh.dask.labels_precomputed(negative, tmp_path / "neg", lods=2, chunk_shape=(8, 8, 8),
                                        scheduler="synchronous")
    assert not os.path.exists(tmp_path / "neg" / "info")


def edited_and_full_run(volume, tmp_path):
    """The update tests' edit inside chunk (0, 0, 0), and the directory a full CLI run on it writes."""
    edited = volume.copy()
    edited[2:10, 3:11, 2:9] = 5  # inside chunk (0, 0, 0): samples [-1, 15) along each axis
    edited[4:7, 5:8, 4:7] = 0  # a hole: segment 5 gains an inner surface
    want = str(tmp_path / "full")
    nrrd = kmtest.write_label_nrrd(str(tmp_path / "edited.nrrd"), edited)
    subprocess.run([EXE, "labels", nrrd, "-o", want, "--format", "precomputed", *CLI_OPTIONS, "-q"], check=True)
    return edited, want


def test_dask_update_equals_a_full_run(cli_run, tmp_path):
    """update=CHUNKS (keymesh labels --update): after an edit inside chunk (0, 0, 0), re-meshing only
    the 8 chunks it can reach (the halo, 8 samples, is under a chunk) gives the directory a full CLI
    run on the edited volume gives."""
    da = pytest.importorskip("dask.array")
    import keymesh.dask
    volume, runs, _ = cli_run
    before, _ = runs["plain"]
    edited, want = edited_and_full_run(volume, tmp_path)
    out = str(tmp_path / "updated")
    shutil.copytree(before, out)
    report = keymesh.dask.labels_precomputed(da.from_array(edited, chunks=(9, 10, 11)), out, **OPTIONS,
                                             update=[(0, 0, 0)])
    assert_same_tree(out, want)
    assert report["chunks_written"] == 8 and 5 in report["segments"]
    # refusals: no chunk store; a chunk outside the grid
    with pytest.raises(keymesh.Error, match="no chunk store"):
        keymesh.dask.labels_precomputed(da.from_array(edited), str(tmp_path / "empty"), **OPTIONS, update=[(0, 0, 0)])
    with pytest.raises(keymesh.Error, match="outside"):
        keymesh.dask.labels_precomputed(da.from_array(edited), out, **OPTIONS, update=[(9, 0, 0)])
    assert_same_tree(out, want)


def test_in_memory_update_equals_a_full_run(cli_run, tmp_path):
    """keymesh.labels_precomputed(update=CHUNKS) is `keymesh labels --update`, in memory: after an edit
    inside chunk (0, 0, 0), re-meshing only the 8 chunks it can reach gives, byte for byte, the
    directory a full CLI run on the edited volume gives (a numpy array and a keymesh.Volume); an
    update naming no chunk the edit touched leaves the directory as it was."""
    volume, runs, _ = cli_run
    before, _ = runs["plain"]
    edited, want = edited_and_full_run(volume, tmp_path)
    for name, given in (("array", edited), ("Volume", keymesh.Volume(np.asfortranarray(edited)))):
        out = str(tmp_path / name)
        shutil.copytree(before, out)
        assert not filecmp.cmp(os.path.join(out, "5"), os.path.join(want, "5"), shallow=False)
        report = keymesh.labels_precomputed(given, out, **OPTIONS, update=[(0, 0, 0)])
        assert_same_tree(out, want)
        assert report["chunks_written"] == 8 and 5 in report["segments"], report
    # the unedited volume updated at (0, 0, 0): its chunks and segments rewritten as they were
    out = str(tmp_path / "unchanged")
    shutil.copytree(before, out)
    keymesh.labels_precomputed(volume, out, **OPTIONS, update=np.array([[0, 0, 0]]))
    assert_same_tree(out, before)
    # refusals, nothing written: no chunk store; a chunk outside the grid; not chunks
    with pytest.raises(keymesh.Error, match="no chunk store"):
        keymesh.labels_precomputed(edited, str(tmp_path / "empty"), **OPTIONS, update=[(0, 0, 0)])
    assert not os.path.exists(tmp_path / "empty" / "info")
    with pytest.raises(keymesh.Error, match="outside"):
        keymesh.labels_precomputed(edited, out, **OPTIONS, update=[(9, 0, 0)])
    with pytest.raises(ValueError, match="update must be chunks"):
        keymesh.labels_precomputed(edited, out, **OPTIONS, update=[(0, 0)])
    assert_same_tree(out, before)


def test_dask_worker_processes(cli_run, tmp_path):
    """dask.distributed workers in processes of their own (tasks pickled, chunk files written by two
    processes side by side): the same directory."""
    da = pytest.importorskip("dask.array")
    distributed = pytest.importorskip("distributed")
    import keymesh.dask
    volume, runs, _ = cli_run
    want, cli_report = runs["plain"]
    out = str(tmp_path / "ng")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=2, processes=True,
                                  dashboard_address=":0") as cluster, distributed.Client(cluster):
        report = keymesh.dask.labels_precomputed(da.from_array(volume, chunks=(20, 18, 15)), out, **OPTIONS)
    assert_same_tree(out, want)
    assert_report(report, cli_report)
