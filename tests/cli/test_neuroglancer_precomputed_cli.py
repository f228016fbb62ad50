"""The Neuroglancer multilod writer end to end, read back by the independent
reader (tests/neuroglancer_precomputed.py: its own murmurhash, gzip, and
Debian's draco_decoder for every fragment).

The test program keymesh_neuroglancer_fixture (beside keymesh, built with the
tests) writes a synthetic dataset (box surfaces cut into chunk pieces with
global keys, 3 lods) and dumps its input pieces; each check compares what
the reader finds with those pieces, computed here from the specification."""
import json
import os
import struct
import subprocess
import sys
from collections import Counter, defaultdict

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import kmtest  # noqa: E402
from kmtest import check, finish  # noqa: E402

import numpy as np  # noqa: E402
import neuroglancer_precomputed as ngp  # noqa: E402

FIXTURE = os.path.join(os.path.dirname(os.path.abspath(kmtest.KEYMESH)), "keymesh_neuroglancer_fixture")
TMP = kmtest.tempdir()


def write(name, *args):
    """Runs the fixture into TMP/name; returns (dir, dumped input)."""
    out, dump = os.path.join(TMP, name), os.path.join(TMP, name + ".json")
    p = subprocess.run([FIXTURE, out, "--dump", dump, *map(str, args)], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, f"fixture {args}: exit {p.returncode}: {p.stderr}"
    with open(dump) as f:
        return out, json.load(f)


def expected_nodes(dump):
    """{segment: {(lod, node): [pieces]}} of the pieces with triangles."""
    nodes = defaultdict(lambda: defaultdict(list))
    for p in dump["pieces"]:
        if p["triangles"]:
            lod = p["lod"]
            node = tuple(c >> lod for c in p["chunk"])
            nodes[p["segment"]][(lod, node)].append(p)
    return nodes


def weld(pieces):
    """{key: point} and triangles as key triples, of one node's pieces."""
    points, triangles = {}, []
    for p in sorted(pieces, key=lambda p: p["chunk"]):
        keys = p["keys"]
        for i, k in enumerate(keys):
            points.setdefault(k, np.array(p["points"][3 * i:3 * i + 3], dtype=np.float64))
        t = p["triangles"]
        triangles += [(keys[t[i]], keys[t[i + 1]], keys[t[i + 2]]) for i in range(0, len(t), 3)]
    return points, triangles


def canonical(triangle):
    """A triangle's corners rotated to start at the smallest (orientation kept)."""
    i = triangle.index(min(triangle))
    return triangle[i:] + triangle[:i]


def check_fragment(f, m, bits, pieces):
    """The decoded fragment holds exactly the welded input points, quantized as
    the spec says (within half a step of the input), and the same triangles."""
    origin, size = ngp.node_box(m, f.lod, f.position)
    top = 2 ** bits - 1
    points, triangles = weld(pieces)
    q_of_key = {}
    for k, p in points.items():
        q = np.round((p - origin) / size * top).astype(np.int64)
        assert (q >= 0).all() and (q <= top).all(), f"input point {p} outside node {f.position}"
        assert (np.abs(origin + size * q / top - p) <= size / top / 2 + 1e-9).all()
        q_of_key[k] = tuple(q)
    got = {tuple(q) for q in f.quantized}
    assert got == set(q_of_key.values()), f"lod {f.lod} node {f.position}: point sets differ"
    step = size / top
    for q, x in zip(f.quantized, f.points):
        assert (np.abs(x - (origin + step * q)) < 1e-9 * size).all()
    decoded = Counter(canonical(tuple(tuple(f.quantized[c]) for c in t)) for t in f.triangles)
    expected = Counter(canonical(tuple(q_of_key[k] for k in t)) for t in triangles)
    assert decoded == expected, f"lod {f.lod} node {f.position}: triangles differ"


def check_partition(f, bits):
    """Neuroglancer's 2x2x2 split of a lod > 0 fragment (neuroglancer_draco.cc):
    every triangle fits one octant, a corner on a split plane fitting both."""
    half = ((1 << bits) - 1) // 2 + 1
    for t in f.triangles:
        mask = 0xFF
        for c in t:
            v = f.quantized[c]
            for axis, (low, high) in enumerate(((0x55, 0xAA), (0x33, 0xCC), (0x0F, 0xF0))):
                mask &= low if v[axis] < half else high if v[axis] > half else 0xFF
        assert mask, f"lod {f.lod} node {f.position}: a triangle crosses the 2x2x2 split"


def check_output(path, dump, sharded):
    info = ngp.read_info(path)
    layout = dump["layout"]
    assert info["@type"] == "neuroglancer_multilod_draco"
    assert info["vertex_quantization_bits"] == layout["vertex_quantization_bits"]
    assert info["transform"] == layout["transform"] and info["lod_scale_multiplier"] == 1
    assert ("sharding" in info) == sharded
    expected = expected_nodes(dump)
    assert ngp.segment_ids(path) == sorted(expected), (ngp.segment_ids(path), sorted(expected))
    bits, fragments = layout["vertex_quantization_bits"], 0
    meshes = {}
    for segment in sorted(expected):
        mesh = ngp.read_segment(path, segment, info)
        m = mesh.manifest
        assert m.chunk_shape == tuple(map(float, layout["chunk_shape"])) and m.grid_origin == (0.0, 0.0, 0.0)
        assert m.num_lods == layout["lods"] and m.lod_scales == [2.0 ** k for k in range(m.num_lods)]
        assert all(o == [0.0, 0.0, 0.0] for o in m.vertex_offsets)
        ngp.check_octree(m)
        nonempty = expected[segment]
        listed = [set() for _ in range(m.num_lods)]
        for lod, node in nonempty:
            listed[lod].add(node)
        for lod in range(1, m.num_lods):  # parents of listed nodes, nothing more
            listed[lod] |= {(x >> 1, y >> 1, z >> 1) for x, y, z in listed[lod - 1]}
        assert [set(p) for p in m.positions] == listed, f"segment {segment}: listed nodes"
        for f in mesh.fragments:
            assert (f.size > 0) == ((f.lod, f.position) in nonempty)
            if f.size:
                check_fragment(f, m, bits, nonempty[(f.lod, f.position)])
                if f.lod > 0:
                    check_partition(f, bits)
                fragments += 1
        meshes[segment] = mesh
    assert fragments > 20
    # Segment 9 has a mesh at lod 0 only: its coarser nodes are listed as
    # empty parents (else Neuroglancer never reaches its lod-0 nodes).
    empty = [(f.lod, f.position) for f in meshes[9].fragments if not f.size]
    assert empty and all(lod > 0 for lod, _ in empty), empty
    return meshes


def check_shared_faces(meshes):
    """Neighbouring nodes of one segment and lod have the same points on their
    common face (each quantized over its own box)."""
    pairs = 0
    for mesh in meshes.values():
        by_node = {(f.lod, f.position): f for f in mesh.fragments if f.size}
        for (lod, p), f in by_node.items():
            for axis in range(3):
                q = list(p)
                q[axis] += 1
                g = by_node.get((lod, tuple(q)))
                if g is None:
                    continue
                origin, size = ngp.node_box(mesh.manifest, lod, tuple(q))
                face = origin[axis]
                a = {tuple(x) for x in f.points if abs(x[axis] - face) < 1e-9 * size[axis]}
                b = {tuple(x) for x in g.points if abs(x[axis] - face) < 1e-9 * size[axis]}
                assert a == b, f"segment {mesh.segment} lod {lod}: nodes {p} and {tuple(q)} differ on their face"
                pairs += bool(a)
    assert pairs > 10, f"only {pairs} neighbouring pairs share points"


def same_meshes(a, b):
    assert sorted(a) == sorted(b)
    for s in a:
        assert a[s].manifest_bytes == b[s].manifest_bytes and a[s].data_bytes == b[s].data_bytes, f"segment {s}"


def tree_bytes(path):
    files = {}
    for root, dirs, names in os.walk(path):
        dirs[:] = [d for d in dirs if d != "chunks"]
        for n in names:
            with open(os.path.join(root, n), "rb") as f:
                files[os.path.relpath(os.path.join(root, n), path)] = f.read()
    return files


def main():
    if not ngp.DRACO_DECODER:
        print("skipped: draco_decoder not found (install Debian's draco)")
        sys.exit(77)
    assert os.path.exists(FIXTURE), f"{FIXTURE}: build the tests (cmake --build build --target keymesh_neuroglancer_fixture)"
    results = {}

    def layout_check(name, *args):
        def run():
            path, dump = write(name, *args)
            results[name] = check_output(path, dump, "--sharded" in args)
            check_shared_faces(results[name])
        check(f"{name}: info, listed nodes, every fragment decoded and equal to its pieces", run)

    layout_check("unsharded")
    layout_check("sharded", "--sharded")
    layout_check("unsharded10", "--bits", "10")
    check("sharded and unsharded hold the same manifests and fragments",
          lambda: same_meshes(results["unsharded"], results["sharded"]))

    def chunked_equals_one_call():
        for args in ([], ["--sharded"]):
            one, _ = write("one" + "".join(args), "--names", *args)
            tasks, _ = write("tasks" + "".join(args), "--names", "--chunked", *args)
            a, b = tree_bytes(one), tree_bytes(tasks)
            assert a.keys() == b.keys() and a == b, sorted(set(a) ^ set(b))
            assert os.path.isdir(os.path.join(tasks, "chunks"))
            assert ngp.segment_names(one) == {1: "box 1", 2: "box 2", 3: "box 3", 7: "box 7", 9: "box 9"}
    check("chunk tasks then assembly: the same bytes as the one-call write; segment names", chunked_equals_one_call)

    def many_segments_in_shards():
        path, dump = write("many", "--sharded", "--many", 600)
        info = ngp.read_info(path)
        s = info["sharding"]
        assert (s["shard_bits"], s["minishard_bits"], s["preshift_bits"]) == (2, 3, 0), s
        assert s["minishard_index_encoding"] == "gzip" and s["data_encoding"] == "raw"
        assert sorted(n for n in os.listdir(path) if n.endswith(".shard")) == ["0.shard", "1.shard", "2.shard", "3.shard"]
        expected = expected_nodes(dump)
        assert ngp.segment_ids(path) == sorted(expected) and len(expected) == 600
        for segment in sorted(expected)[::37]:  # a sample decoded; every manifest parsed
            mesh = ngp.read_segment(path, segment, info)
            for f in mesh.fragments:
                if f.size:
                    check_fragment(f, mesh.manifest, 16, expected[segment][(f.lod, f.position)])
        used = Counter()  # bytes of each shard file accounted for by its segments
        for segment in sorted(expected):
            mesh = ngp.read_segment(path, segment, info, decode=False)
            ngp.check_octree(mesh.manifest)
            used[ngp.shard_location(s, segment)[0]] += len(mesh.manifest_bytes) + len(mesh.data_bytes)
        for name in used:  # shard index + minishard indices + every segment's data: nothing else
            with open(os.path.join(path, name), "rb") as f:
                shard = f.read()
            ranges = [struct.unpack_from("<QQ", shard, 16 * i) for i in range(8)]
            assert len(shard) == 8 * 16 + sum(end - start for start, end in ranges) + used[name], name
    check("600 segments: 4 shards of 8 minishards, every segment found by its hash", many_segments_in_shards)

    finish()


if __name__ == "__main__":
    main()
