#!/usr/bin/env python3
"""Checks that the GPU check's programs (`make gpu-check-build`) can travel.

Usage: gpu_check_linkage.py PROGRAM... (run in build-gpucheck/)

For each program: its shared libraries (readelf -d NEEDED) are only glibc's
(libc, libm, libdl, libpthread, librt, ld-linux) -- cudart_static opens the
driver's libcuda.so.1 at run time; the newest GLIBC_ symbol version it needs
(objdump -T), which the GPU machine's glibc must provide; and, for programs
holding device code, the fatbinary's entries (.nv_fatbin: sm_90 machine code
and compute_90 PTX), read from the fatbinary headers, since this machine's
CUDA toolkit has no cuobjdump. Together the programs stay under 40 MB (the
device tool carries at most 64 MiB). Prints one line per program and a JSON
summary (build-gpucheck/linkage.json); exits 1 when a check fails.
"""
import json
import os
import re
import struct
import subprocess
import sys

ALLOWED = re.compile(r"^(libc|libm|libdl|libpthread|librt|ld-linux-x86-64)\.so\.\d+$")
LIMIT_BYTES = 40 * 1000 * 1000
FATBIN_MAGIC = 0xBA55ED50
KINDS = {1: "ptx", 2: "elf"}


def needed(path):
    out = subprocess.run(["readelf", "-d", path], capture_output=True, text=True, check=True).stdout
    return re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", out)


def newest_glibc(path):
    out = subprocess.run(["objdump", "-T", path], capture_output=True, text=True, check=True).stdout
    versions = {tuple(int(x) for x in v.split(".")) for v in re.findall(r"GLIBC_(\d+(?:\.\d+)+)", out)}
    return ".".join(map(str, max(versions))) if versions else None


def fatbin_entries(path):
    """(kind, sm) of every entry of every fatbinary in the .nv_fatbin section."""
    with open(path, "rb") as f:
        data = f.read()
    out = subprocess.run(["readelf", "-S", "-W", path], capture_output=True, text=True, check=True).stdout
    m = re.search(r"\.nv_fatbin\s+\S+\s+[0-9a-f]+\s+([0-9a-f]+)\s+([0-9a-f]+)", out)
    if not m:
        return []
    offset, size = int(m.group(1), 16), int(m.group(2), 16)
    section, entries, at = data[offset:offset + size], [], 0
    while at + 16 <= len(section):
        magic, _version, header_size, fat_size = struct.unpack_from("<IHHQ", section, at)
        if magic != FATBIN_MAGIC:
            at += 8  # fatbinaries are 8-byte aligned
            continue
        entry, end = at + header_size, at + header_size + fat_size
        while entry + 32 <= end:
            kind, _v, entry_header, payload = struct.unpack_from("<HHIQ", section, entry)
            sm = struct.unpack_from("<I", section, entry + 28)[0]
            entries.append((KINDS.get(kind, str(kind)), sm))
            entry += entry_header + payload
        at = end
    return sorted(set(entries))


def main(programs):
    summary, ok, total = {}, True, 0
    for p in programs:
        libs = needed(p)
        bad = [lib for lib in libs if not ALLOWED.match(lib)]
        glibc = newest_glibc(p)
        device = fatbin_entries(p)
        size = os.path.getsize(p)
        total += size
        has_device = bool(device)
        sm90 = ("elf", 90) in device and ("ptx", 90) in device
        summary[p] = {"bytes": size, "needed": libs, "not_allowed": bad, "newest_glibc": glibc,
                      "fatbin": [f"{k} sm_{s}" for k, s in device]}
        print(f"{p}: {size / 1e6:.1f} MB, NEEDED {' '.join(libs)}, newest GLIBC_{glibc}, device code: "
              f"{', '.join(summary[p]['fatbin']) or 'none'}")
        if bad:
            print(f"  FAIL: {p} needs {' '.join(bad)}, which a bare CUDA machine may lack")
            ok = False
        if has_device and not sm90:
            print(f"  FAIL: {p} holds no sm_90 machine code plus compute_90 PTX")
            ok = False
    if total > LIMIT_BYTES:
        print(f"FAIL: the programs take {total / 1e6:.1f} MB together, over {LIMIT_BYTES / 1e6:.0f} MB")
        ok = False
    summary["total_bytes"] = total
    with open("linkage.json", "w") as f:
        json.dump(summary, f, indent=1)
    print(f"together {total / 1e6:.1f} MB: {'ok' if ok else 'FAILED'} (linkage.json)")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]) if len(sys.argv) > 1 else "usage: gpu_check_linkage.py PROGRAM...")
