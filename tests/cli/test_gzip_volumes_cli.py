"""gzip volumes (.nii.gz, gzip NRRD attached and detached) end to end: the
gzip members are written here by hand (raw deflate from Python's zlib, CRC-32
and length from zlib.crc32 and len) around samples from numpy, and what
`keymesh convert` reads back is compared with those samples. Covers what
zlib's gzread accepts and refuses: several members (split inside the NIfTI
header, empty ones, headers with a name, a comment, an extra field, a
header CRC), a stream longer than declared and bytes after the last member
(read: only the declared samples count), and damaged files, each refused
with one line naming the file: a wrong CRC-32, length or header CRC, a
truncated member, members missing, junk between members."""
import os
import struct
import subprocess
import sys
import zlib

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from kmtest import KEYMESH, check, finish, run, tempdir  # noqa: E402

import numpy as np  # noqa: E402

D = tempdir()
SHAPE = (7, 30, 41)  # z, y, x
SAMPLES = (np.random.default_rng(20261124).integers(-3000, 3000, SHAPE)).astype("<i2")
VOX_OFFSET = 400  # 348 header bytes, the 4-byte extension flag, 48 more: a skip past the header


def nifti(samples, vox_offset=VOX_OFFSET):
    """An int16 NIfTI-1 single file: header, padding up to vox_offset, samples."""
    h = bytearray(348)
    struct.pack_into("<i", h, 0, 348)
    z, y, x = samples.shape
    struct.pack_into("<8h", h, 40, 3, x, y, z, 1, 1, 1, 1)
    struct.pack_into("<h", h, 70, 4)  # int16
    struct.pack_into("<8f", h, 76, 1, 1, 1, 1, 1, 1, 1, 1)
    struct.pack_into("<f", h, 108, float(vox_offset))
    h[344:348] = b"n+1\0"
    return bytes(h) + bytes(vox_offset - 348) + samples.tobytes()


def member(data, name=None, comment=None, extra=None, header_crc=None, crc=None, length=None):
    """One gzip member (RFC 1952) of `data`: header with the optional fields,
    raw deflate, CRC-32 and length (either replaceable to damage it).
    header_crc: True for the right CRC-16 of the header, an int for that value."""
    flags = (4 if extra is not None else 0) | (8 if name is not None else 0) | (16 if comment is not None else 0)
    flags |= 2 if header_crc is not None else 0
    head = bytes([0x1F, 0x8B, 8, flags]) + struct.pack("<I", 0) + bytes([0, 255])
    if extra is not None:
        head += struct.pack("<H", len(extra)) + extra
    if name is not None:
        head += name + b"\0"
    if comment is not None:
        head += comment + b"\0"
    if header_crc is not None:
        head += struct.pack("<H", zlib.crc32(head) & 0xFFFF if header_crc is True else header_crc)
    z = zlib.compressobj(6, zlib.DEFLATED, -15)
    body = z.compress(data) + z.flush()
    crc = zlib.crc32(data) if crc is None else crc
    length = len(data) & 0xFFFFFFFF if length is None else length
    return head + body + struct.pack("<II", crc, length)


def members(data, cuts, **fields):
    """data cut at `cuts` (offsets, repeats giving empty members), one member each."""
    bounds = [0, *cuts, len(data)]
    return b"".join(member(data[a:b], **fields) for a, b in zip(bounds, bounds[1:]))


NRRD_HEAD = ("NRRD0004\ntype: short\ndimension: 3\nsizes: %d %d %d\nendian: little\nencoding: gzip\n"
             % (SHAPE[2], SHAPE[1], SHAPE[0])).encode()


def write(name, data):
    path = os.path.join(D, name)
    with open(path, "wb") as f:
        f.write(data)
    return path


def gzip_volumes(name, stream_of):
    """The same samples as a .nii.gz, an attached gzip NRRD and a .nhdr with
    its .raw.gz, each stream made by stream_of(uncompressed bytes)."""
    nhdr_data = write(name + ".raw.gz", stream_of(SAMPLES.tobytes()))
    return [write(name + ".nii.gz", stream_of(nifti(SAMPLES))),
            write(name + ".nrrd", NRRD_HEAD + b"\n" + stream_of(SAMPLES.tobytes())),
            write(name + ".nhdr", NRRD_HEAD + b"data file: " + os.path.basename(nhdr_data).encode() + b"\n\n")]


def samples_read(path):
    """The samples keymesh reads from path, through a raw NRRD it writes."""
    out = path + ".out.nrrd"
    run("convert", path, "-o", out, "-q")
    head, body = open(out, "rb").read().split(b"\n\n", 1)
    assert b"type: int16" in head or b"type: short" in head, head
    return body


def refused(path, fragment):
    p = subprocess.run([KEYMESH, "convert", path, "-o", path + ".out.nrrd", "-q"], capture_output=True, text=True,
                       stdin=subprocess.DEVNULL, timeout=120)
    lines = [line for line in p.stderr.splitlines() if line.strip()]
    assert p.returncode == 1, f"{path}: exit {p.returncode}, expected 1\n{p.stderr}"
    assert len(lines) == 1 and path in lines[0] and fragment in lines[0], (path, fragment, p.stderr)
    assert not os.path.exists(path + ".out.nrrd")


def reads_samples(name, stream_of):
    for path in gzip_volumes(name, stream_of):
        assert samples_read(path) == SAMPLES.tobytes(), path


def one_member():
    reads_samples("one", lambda d: member(d))


def several_members():
    # Cut inside the NIfTI header, twice at the same place (an empty member),
    # mid-sample, and a last member of 7 bytes.
    reads_samples("several", lambda d: members(d, [100, 100, 5001, len(d) - 7]))
    reads_samples("bytes", lambda d: members(d, list(range(1, 64))))


def member_header_fields():
    reads_samples("named", lambda d: members(d, [3000], name=b"volume.nii", comment=b"a comment",
                                             extra=b"KM\x04\x00abcd"))
    reads_samples("hcrc", lambda d: members(d, [3000], header_crc=True))


def only_the_declared_samples():
    # A stream longer than the header declares, then bytes that are not gzip:
    # neither is read.
    reads_samples("longer", lambda d: member(d + bytes(range(256)) * 40) + b"not gzip at all")
    reads_samples("trailing", lambda d: members(d, [2000]) + b"\x1f\x8b junk after the samples")


def damaged_refused():
    n_samples = SAMPLES.nbytes
    header = "truncated (header: 0 of 348 bytes)"

    def each(name, stream_of, fragment, in_nifti_header=None):
        """in_nifti_header: the message when the damage is in the member
        holding the NIfTI header, which the header's read meets first."""
        for path in gzip_volumes(name, stream_of):
            refused(path, in_nifti_header if in_nifti_header and path.endswith(".nii.gz") else fragment)

    each("crc", lambda d: members(d[:3000], [1000]) + member(d[3000:], crc=zlib.crc32(d[3000:]) ^ 1),
         "incorrect data check")
    each("crcmid", lambda d: member(d[:1000]) + member(d[1000:5000], crc=zlib.crc32(d[1000:5000]) ^ 0x80000000)
         + member(d[5000:]), "incorrect data check")
    # A damaged first member: a .nii.gz's header read reports it whether the
    # member inflates to less or more than the first 8 KiB.
    each("crcfirst", lambda d: member(d[:3000], crc=zlib.crc32(d[:3000]) ^ 1) + member(d[3000:]),
         "incorrect data check", header)
    each("crcbig", lambda d: member(d[:12000], crc=zlib.crc32(d[:12000]) ^ 1) + member(d[12000:]),
         "incorrect data check", header)
    each("length", lambda d: member(d[:1000]) + member(d[1000:], length=len(d) - 999), "incorrect length check")
    each("lengthone", lambda d: member(d, length=len(d) + 1), "incorrect length check", header)
    each("hcrcbad", lambda d: member(d[:3000]) + member(d[3000:], header_crc=0x1234), "header crc mismatch")
    each("cut", lambda d: member(d)[:-40], "ends after")
    each("halfcut", lambda d: member(d)[: len(member(d)) // 2], "ends after")
    # Members missing at the end, and junk where the next member should start:
    # what the members present hold is all there is.
    each("missing", lambda d: members(d[: len(d) - 900], [1500]), f"ends after {n_samples - 900} of {n_samples} bytes")
    each("junk", lambda d: members(d[: len(d) - 900], [1500]) + b"junk" + member(d[len(d) - 900:]),
         f"ends after {n_samples - 900} of {n_samples} bytes")


def trailer_lie_refused():
    # The last member's trailer claims the declared length; the stream holds 3000 bytes.
    for path in gzip_volumes("liar", lambda d: member(d[:2000]) + member(d[2000:3000], length=len(d))):
        refused(path, "incorrect length check")


check("one gzip member: the samples written", one_member)
check("several members (split in the header, empty, one byte each): the samples written", several_members)
check("member headers with name, comment, extra field, header CRC: the samples written", member_header_fields)
check("a longer stream and bytes after the members: only the declared samples read", only_the_declared_samples)
check("wrong CRC-32, length, header CRC; truncated; members missing; junk between: refused", damaged_refused)
check("a trailer claiming the declared length over a short stream: refused", trailer_lie_refused)
finish()
