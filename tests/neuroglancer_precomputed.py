"""Independent reader of Neuroglancer's precomputed multi-resolution meshes.

Written for the tests from the published specification alone (google/neuroglancer
src/datasource/precomputed/meshes.md, sharded.md, segment_properties.md), sharing
no code with keymesh's writer: its own MurmurHash3_x86_128, gzip from Python, and
every fragment decoded by Debian's `draco_decoder` program (package `draco`).

    import neuroglancer_precomputed as ngp
    info = ngp.read_info(path)                      # the info JSON, checked
    for segment in ngp.segment_ids(path):           # every segment with a manifest
        mesh = ngp.read_segment(path, segment)      # SegmentMesh
        for f in mesh.fragments:                    # Fragment: lod, position, size
            f.points      # (n, 3) float64 stored-model coordinates
            f.quantized   # (n, 3) int64, each in [0, 2**bits)
            f.triangles   # (m, 3) int64 indices into points
    ngp.check_octree(mesh.manifest)                 # Z-curve order, every parent listed
    ngp.segment_names(path)                         # {id: label} from segment_properties

Empty listed nodes (0-byte fragments) come back as fragments with no points.
Errors are AssertionError (the output breaks the format) or subprocess errors.
"""
import gzip
import json
import math
import os
import shutil
import struct
import subprocess
import tempfile
from dataclasses import dataclass, field

import numpy as np

DRACO_DECODER = shutil.which("draco_decoder")


# --- MurmurHash3_x86_128 (sharded.md: "hash": "murmurhash3_x86_128") -------

_M32 = 0xFFFFFFFF


def _rotl(x, r):
    return ((x << r) | (x >> (32 - r))) & _M32


def _fmix(h):
    h ^= h >> 16
    h = (h * 0x85EBCA6B) & _M32
    h ^= h >> 13
    h = (h * 0xC2B2AE35) & _M32
    return h ^ (h >> 16)


def murmurhash3_x86_128(data: bytes, seed: int = 0):
    """The four 32-bit words (h1, h2, h3, h4) of MurmurHash3_x86_128."""
    c = (0x239B961B, 0xAB0E9789, 0x38B34AE5, 0xA1E38B93)
    rot_k = (15, 16, 17, 18)
    rot_h = (19, 17, 15, 13)
    add_h = (0x561CCD1B, 0x0BCAA747, 0x96CD1C35, 0x32AC3B17)
    h = [seed & _M32] * 4
    n = len(data)

    def mix(k, lane):
        k = (k * c[lane]) & _M32
        k = _rotl(k, rot_k[lane])
        return (k * c[(lane + 1) % 4]) & _M32

    for b in range(n // 16):
        for lane in range(4):
            k = int.from_bytes(data[16 * b + 4 * lane:16 * b + 4 * lane + 4], "little")
            h[lane] ^= mix(k, lane)
            h[lane] = _rotl(h[lane], rot_h[lane])
            h[lane] = (h[lane] + h[(lane + 1) % 4]) & _M32
            h[lane] = (h[lane] * 5 + add_h[lane]) & _M32
    tail = data[16 * (n // 16):]
    for lane in range(4):
        chunk = tail[4 * lane:4 * lane + 4]
        if chunk:
            h[lane] ^= mix(int.from_bytes(chunk, "little"), lane)
    h = [x ^ n for x in h]
    h[0] = (h[0] + h[1] + h[2] + h[3]) & _M32
    h[1], h[2], h[3] = [(x + h[0]) & _M32 for x in h[1:]]
    h = [_fmix(x) for x in h]
    h[0] = (h[0] + h[1] + h[2] + h[3]) & _M32
    h[1], h[2], h[3] = [(x + h[0]) & _M32 for x in h[1:]]
    return tuple(h)


def sharding_hash(segment: int) -> int:
    """The low 8 bytes of MurmurHash3_x86_128(segment as uint64le, seed 0)."""
    h = murmurhash3_x86_128(struct.pack("<Q", segment), 0)
    return h[1] << 32 | h[0]


# --- info and manifests ---------------------------------------------------------

def read_info(path):
    with open(os.path.join(path, "info")) as f:
        info = json.load(f)
    assert info.get("@type") == "neuroglancer_multilod_draco", info.get("@type")
    assert info["vertex_quantization_bits"] in (10, 16), info["vertex_quantization_bits"]
    assert len(info["transform"]) == 12 and all(isinstance(x, (int, float)) for x in info["transform"])
    assert isinstance(info["lod_scale_multiplier"], (int, float))
    if "sharding" in info:
        s = info["sharding"]
        assert s["@type"] == "neuroglancer_uint64_sharded_v1", s
        assert s["hash"] in ("murmurhash3_x86_128", "identity"), s
        assert s.get("minishard_index_encoding", "raw") in ("raw", "gzip")
        assert s.get("data_encoding", "raw") in ("raw", "gzip")
    return info


@dataclass
class Manifest:
    chunk_shape: tuple
    grid_origin: tuple
    num_lods: int
    lod_scales: list
    vertex_offsets: list          # [num_lods][3]
    positions: list               # per lod: list of (x, y, z), in file order
    sizes: list                   # per lod: fragment byte sizes


def parse_manifest(data: bytes) -> Manifest:
    """The manifest's fields (meshes.md); asserts that the bytes end where the fields do."""
    at = 0

    def take(fmt):
        nonlocal at
        size = struct.calcsize(fmt)
        assert at + size <= len(data), f"manifest truncated at byte {at}"
        values = struct.unpack_from(fmt, data, at)
        at += size
        return values

    chunk_shape = take("<3f")
    grid_origin = take("<3f")
    (num_lods,) = take("<I")
    lod_scales = list(take(f"<{num_lods}f"))
    offsets = take(f"<{3 * num_lods}f")
    counts = take(f"<{num_lods}I")
    positions, sizes = [], []
    for n in counts:
        xyz = take(f"<{3 * n}I")  # C order [3, n]: every x, every y, every z
        positions.append([(xyz[i], xyz[n + i], xyz[2 * n + i]) for i in range(n)])
        sizes.append(list(take(f"<{n}I")))
    assert at == len(data), f"manifest has {len(data) - at} bytes after its last field"
    return Manifest(chunk_shape, grid_origin, num_lods, lod_scales,
                    [list(offsets[3 * i:3 * i + 3]) for i in range(num_lods)], positions, sizes)


def morton(p):
    """Z-curve code of (x, y, z): bits interleaved, x the lowest of each level."""
    code = 0
    for bit in range(32):
        for axis in range(3):
            code |= ((p[axis] >> bit) & 1) << (3 * bit + axis)
    return code


def check_octree(m: Manifest):
    """What Neuroglancer's reader needs of the listed nodes: each lod in strictly
    increasing Z-curve order (no repeats), and the parent of every node below the
    top lod listed (else it is an orphan that is never drawn)."""
    for lod, nodes in enumerate(m.positions):
        codes = [morton(p) for p in nodes]
        assert all(a < b for a, b in zip(codes, codes[1:])), f"lod {lod} not in Z-curve order: {nodes}"
    for lod in range(m.num_lods - 1):
        above = set(m.positions[lod + 1])
        for p in m.positions[lod]:
            parent = (p[0] >> 1, p[1] >> 1, p[2] >> 1)
            assert parent in above, f"lod {lod} node {p}: parent {parent} not listed at lod {lod + 1}"


# --- storage: unsharded files or shards ------------------------------------------

def _decode(data, encoding):
    return gzip.decompress(data) if encoding == "gzip" else data


def shard_location(sharding, segment):
    """(shard file name, minishard number) of a segment under a sharding spec."""
    h = segment >> sharding["preshift_bits"]
    if sharding["hash"] == "murmurhash3_x86_128":
        h = sharding_hash(h)
    mb, sb = sharding["minishard_bits"], sharding["shard_bits"]
    minishard = h & ((1 << mb) - 1)
    shard = (h >> mb) & ((1 << sb) - 1)
    name = format(shard, "x").rjust(math.ceil(sb / 4), "0") + ".shard"
    return name, minishard


def read_minishard(path, sharding, shard_name, minishard):
    """{segment: (start, size)} of one minishard, offsets from the shard file's start."""
    with open(os.path.join(path, shard_name), "rb") as f:
        shard = f.read()
    index_end = (1 << sharding["minishard_bits"]) * 16
    assert len(shard) >= index_end, f"{shard_name}: shorter than its shard index"
    start, end = struct.unpack_from("<QQ", shard, 16 * minishard)
    assert start <= end <= len(shard) - index_end, f"{shard_name}: minishard {minishard} index out of the file"
    if start == end:
        return {}
    raw = _decode(shard[index_end + start:index_end + end], sharding.get("minishard_index_encoding", "raw"))
    assert len(raw) % 24 == 0, f"{shard_name}: minishard index of {len(raw)} bytes"
    n = len(raw) // 24
    a = np.frombuffer(raw, dtype="<u8").reshape(3, n).astype(object)
    entries, segment, offset = {}, 0, index_end
    for i in range(n):
        segment += a[0, i]
        offset += a[1, i]
        entries[int(segment)] = (int(offset), int(a[2, i]))
        offset += a[2, i]
    return entries


def segment_ids(path):
    """Every segment id the output holds a manifest for, increasing."""
    info = read_info(path)
    if "sharding" not in info:
        return sorted(int(n[:-6]) for n in os.listdir(path) if n.endswith(".index") and n[:-6].isdigit())
    sharding = info["sharding"]
    ids = []
    for name in sorted(os.listdir(path)):
        if name.endswith(".shard"):
            for minishard in range(1 << sharding["minishard_bits"]):
                for segment in read_minishard(path, sharding, name, minishard):
                    assert shard_location(sharding, segment) == (name, minishard), \
                        f"segment {segment} stored in {name} minishard {minishard}, its hash says otherwise"
                    ids.append(segment)
    return sorted(ids)


def read_segment_bytes(path, segment, info=None):
    """(manifest bytes, fragment data bytes) of one segment, either layout."""
    info = info or read_info(path)
    if "sharding" not in info:
        with open(os.path.join(path, f"{segment}.index"), "rb") as f:
            manifest = f.read()
        with open(os.path.join(path, str(segment)), "rb") as f:
            data = f.read()
        return manifest, data
    sharding = info["sharding"]
    name, minishard = shard_location(sharding, segment)
    entries = read_minishard(path, sharding, name, minishard)
    assert segment in entries, f"segment {segment} not in {name} minishard {minishard}"
    start, size = entries[segment]
    with open(os.path.join(path, name), "rb") as f:
        shard = f.read()
    manifest = _decode(shard[start:start + size], sharding.get("data_encoding", "raw"))
    total = sum(sum(s) for s in parse_manifest(manifest).sizes)
    assert total <= start, f"segment {segment}: fragment data would start before the shard file"
    return manifest, shard[start - total:start]  # the fragments sit right before the manifest


# --- fragments ------------------------------------------------------------------

_PLY_TYPES = {"char": "b", "uchar": "B", "int8": "b", "uint8": "B", "short": "h", "ushort": "H", "int16": "h",
              "uint16": "H", "int": "i", "uint": "I", "int32": "i", "uint32": "I", "float": "f", "float32": "f",
              "double": "d", "float64": "d"}


def _read_binary_ply(data: bytes):
    """(vertex x y z array, face index array) of a binary little-endian PLY."""
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    assert "format binary_little_endian 1.0" in header, header[:3]
    elements = []  # (name, count, [(prop name, type or ('list', count type, item type))])
    for line in header:
        words = line.split()
        if words[:1] == ["element"]:
            elements.append((words[1], int(words[2]), []))
        elif words[:1] == ["property"]:
            elements[-1][2].append((words[-1], ("list", words[2], words[3]) if words[1] == "list" else words[1]))
    at, vertices, faces = end, None, []
    for name, count, props in elements:
        rows = []
        for _ in range(count):
            row = {}
            for pname, ptype in props:
                if isinstance(ptype, tuple):
                    (k,) = struct.unpack_from("<" + _PLY_TYPES[ptype[1]], data, at)
                    at += struct.calcsize(_PLY_TYPES[ptype[1]])
                    fmt = f"<{k}{_PLY_TYPES[ptype[2]]}"
                    row[pname] = struct.unpack_from(fmt, data, at)
                    at += struct.calcsize(fmt)
                else:
                    fmt = "<" + _PLY_TYPES[ptype]
                    (row[pname],) = struct.unpack_from(fmt, data, at)
                    at += struct.calcsize(fmt)
            rows.append(row)
        if name == "vertex":
            vertices = np.array([[r["x"], r["y"], r["z"]] for r in rows], dtype=np.int64).reshape(-1, 3)
        elif name == "face":
            for r in rows:
                corners = next(iter(r.values()))
                assert len(corners) == 3, f"a face of {len(corners)} corners"
                faces.append(corners)
    return vertices, np.array(faces, dtype=np.int64).reshape(-1, 3)


def decode_draco(fragment: bytes):
    """(quantized positions (n, 3) int64, triangles (m, 3)) decoded by `draco_decoder`."""
    assert DRACO_DECODER, "draco_decoder not found (Debian package draco)"
    with tempfile.TemporaryDirectory() as tmp:
        src, dst = os.path.join(tmp, "f.drc"), os.path.join(tmp, "f.ply")
        with open(src, "wb") as f:
            f.write(fragment)
        p = subprocess.run([DRACO_DECODER, "-i", src, "-o", dst], capture_output=True, text=True)
        assert p.returncode == 0, f"draco_decoder failed: {p.stdout} {p.stderr}"
        with open(dst, "rb") as f:
            return _read_binary_ply(f.read())


@dataclass
class Fragment:
    lod: int
    position: tuple       # octree node (x, y, z) at this lod
    size: int             # bytes; 0 for an empty listed node
    quantized: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), np.int64))
    points: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    triangles: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), np.int64))


@dataclass
class SegmentMesh:
    segment: int
    manifest: Manifest
    fragments: list       # Fragment per listed node, manifest order
    manifest_bytes: bytes = b""
    data_bytes: bytes = b""


def node_box(m: Manifest, lod, position):
    """(origin, size) of a node in stored-model coordinates (meshes.md)."""
    scale = 2 ** lod
    size = np.array(m.chunk_shape, dtype=np.float64) * scale
    return np.array(m.grid_origin, dtype=np.float64) + np.array(position) * size, size


def read_segment(path, segment, info=None, decode=True):
    """One segment's manifest and its fragments, decoded (decode=False: sizes only)."""
    info = info or read_info(path)
    manifest_bytes, data = read_segment_bytes(path, segment, info)
    m = parse_manifest(manifest_bytes)
    assert sum(sum(s) for s in m.sizes) == len(data), "fragment sizes do not sum to the data"
    bits = info["vertex_quantization_bits"]
    fragments, at = [], 0
    for lod in range(m.num_lods):
        for position, size in zip(m.positions[lod], m.sizes[lod]):
            f = Fragment(lod, position, size)
            if size and decode:
                q, tri = decode_draco(data[at:at + size])
                assert q.size == 0 or (q.min() >= 0 and q.max() < 2 ** bits), f"lod {lod} {position}: value out of range"
                origin, box = node_box(m, lod, position)
                f.quantized, f.triangles = q, tri
                f.points = origin + np.array(m.vertex_offsets[lod]) + box * (q / (2 ** bits - 1))
            fragments.append(f)
            at += size
    return SegmentMesh(segment, m, fragments, manifest_bytes, data)


def segment_names(path):
    """{segment id: label} from the segment_properties the info names ({} if none)."""
    info = read_info(path)
    if "segment_properties" not in info:
        return {}
    with open(os.path.join(path, info["segment_properties"], "info")) as f:
        props = json.load(f)
    assert props["@type"] == "neuroglancer_segment_properties", props["@type"]
    inline = props["inline"]
    labels = [p for p in inline["properties"] if p["type"] == "label"]
    assert len(labels) == 1 and len(labels[0]["values"]) == len(inline["ids"])
    return {int(i): v for i, v in zip(inline["ids"], labels[0]["values"])}
