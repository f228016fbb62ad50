"""The benchmark's real datasets, built at bench time into a temporary folder
from Debian packages (nothing is downloaded, nothing is committed).

  head128   brainsmall.den (libvolpack1-dev, 128 x 128 x 84 uint8) resampled
            to 128^3: x and y keep their samples, z is stretched from 84 to
            128 samples (spacing 83/127 so the head keeps its shape)
  head256   ch2.nii.gz (mricron-data, 181 x 217 x 181 uint8) resampled to 256^3
  big432    ch2better.nii.gz (mricron-data, 301 x 370 x 316 uint8) resampled
            to 432^3: a stand-in for the paper's 432^3 supernova, which is not
            freely available

Resampling is trilinear (separable linear interpolation along x, then y,
then z, corner samples aligned: output i sits at input i * (n_in - 1) /
(n_out - 1)), in numpy, to float32. The source files are read by
`keymesh convert` (the library's own readers) into .nrrd; the results are
written as .nrrd (numpy, raw encoding) for keymesh, skimage, OpenVDB and
Thrust, and as .vti (`keymesh convert`) for VTK.

The isovalues are non-integer (no integer source sample lies on the
surface): 37.3 on head128 (the head's skin, the value docs/decisions/
use on brainsmall.den), 90.5 on head256 and big432 (the brain tissue
surface, the value of those tried -- 20.5, 40.5, 60.5, 90.5 -- whose triangle
count comes nearest the paper's). The paper's Table 1 counts are quoted
beside ours by report.py; the volumes are not the paper's, so they differ.
"""
import os
import subprocess

import numpy as np

VOLPACK = "/usr/share/doc/libvolpack1-dev/examples/brainsmall.den"
MRICRON = "/usr/share/mricron/templates"

# name: (source, target dims, isovalue, label, the paper's Table 1 row and triangles)
DATASETS = {
    "head128": (VOLPACK, 128, 37.3, "MRI head 128^3 (brainsmall.den, trilinear)", "MRI Head A", 789440),
    "head256": (os.path.join(MRICRON, "ch2.nii.gz"), 256, 90.5, "MRI head 256^3 (ch2.nii.gz, trilinear)",
                "MRI Head B", 4947294),
    "big432": (os.path.join(MRICRON, "ch2better.nii.gz"), 432, 90.5,
               "MRI 432^3 (ch2better.nii.gz, trilinear), stand-in for the paper's supernova", "Supernova", 7036776),
}
SPHERE_PAPER = {128: 149420, 256: 607388, 512: 2451212}  # the paper's Table 1, Spherical Distance A-C
RESAMPLING = "trilinear (numpy, separable, corner-aligned), float32"


def sphere(n):
    """The Spherical Distance field in numpy, [z, y, x], float32 (as keymesh generate sphere)."""
    c = n // 2
    x = np.arange(n, dtype=np.float64) - c
    return np.sqrt(x[None, None, :] ** 2 + x[None, :, None] ** 2 + x[:, None, None] ** 2).astype(np.float32)


def read_nrrd(path):
    """A raw-encoded, attached-header .nrrd as written by keymesh (x fastest)."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"\n\n")
    header = dict(line.split(": ", 1) for line in data[:end].decode().splitlines()[1:]
                  if ": " in line and not line.startswith("#"))
    dims = [int(v) for v in header["sizes"].split()]
    dtype = {"uint8": np.uint8, "float": np.float32, "int16": np.int16, "uint16": np.uint16,
             "short": np.int16, "ushort": np.uint16, "float32": np.float32}[header["type"]]
    arr = np.frombuffer(data, dtype=dtype, offset=end + 2, count=dims[0] * dims[1] * dims[2])
    return arr.reshape(dims[2], dims[1], dims[0])  # z, y, x


def nrrd_spacing(path):
    """The diagonal of 'space directions' (1, 1, 1 when absent)."""
    with open(path, "rb") as f:
        head = f.read(4096).split(b"\n\n")[0].decode(errors="replace")
    for line in head.splitlines():
        if line.startswith("space directions:"):
            vecs = [[float(c) for c in v.strip("() ").split(",")] for v in line.split(":", 1)[1].split()]
            return [vecs[i][i] for i in range(3)]
    return [1.0, 1.0, 1.0]


def write_nrrd(path, vol, spacing):
    """float32 volume indexed [z, y, x]."""
    nz, ny, nx = vol.shape
    header = ("NRRD0004\n# written by keymesh bench/datasets.py\ntype: float\ndimension: 3\n"
              f"sizes: {nx} {ny} {nz}\nspace dimension: 3\n"
              f"space directions: ({spacing[0]!r},0,0) (0,{spacing[1]!r},0) (0,0,{spacing[2]!r})\n"
              "space origin: (0,0,0)\nendian: little\nencoding: raw\n\n")
    with open(path, "wb") as f:
        f.write(header.encode())
        f.write(np.ascontiguousarray(vol, dtype="<f4").tobytes())


def resample_axis(a, axis, n):
    m = a.shape[axis]
    x = np.arange(n, dtype=np.float64) * ((m - 1) / (n - 1))
    i0 = np.minimum(np.floor(x).astype(np.int64), m - 2)
    w = (x - i0).astype(np.float32)
    shape = [1, 1, 1]
    shape[axis] = n
    w = w.reshape(shape)
    return np.take(a, i0, axis=axis) * (1 - w) + np.take(a, i0 + 1, axis=axis) * w


def resample(vol, n):
    """Trilinear resampling of vol [z, y, x] to n^3, corners aligned."""
    out = vol.astype(np.float32)
    for axis in (2, 1, 0):
        out = resample_axis(out, axis, n)
    return np.ascontiguousarray(out, dtype=np.float32)


def build(name, keymesh, work):
    """Writes work/name.nrrd and work/name.vti (once); returns a description."""
    src, n, iso, label, paper_name, paper_tris = DATASETS[name]
    nrrd, vti = os.path.join(work, f"{name}.nrrd"), os.path.join(work, f"{name}.vti")
    if not os.path.exists(vti):
        if not os.path.exists(src):
            raise FileNotFoundError(f"{src} is missing (install the Debian package that ships it)")
        tmp = os.path.join(work, f"{name}-source.nrrd")
        subprocess.run([keymesh, "convert", src, "-o", tmp, "-q"], check=True)
        vol = read_nrrd(tmp)
        src_spacing = nrrd_spacing(tmp)
        os.remove(tmp)
        src_dims = vol.shape[::-1]
        out = resample(vol, n)
        # spacing that keeps the physical extent of the source
        spacing = [s * (d - 1) / (n - 1) for s, d in zip(src_spacing, src_dims)]
        write_nrrd(nrrd, out, spacing)
        del out, vol
        subprocess.run([keymesh, "convert", nrrd, "-o", vti, "-q"], check=True)
    return {"dataset": name, "label": label, "size": n, "iso": iso, "nrrd": nrrd, "vti": vti, "source": src,
            "resampling": RESAMPLING, "paper_dataset": paper_name, "paper_triangles": paper_tris}


def load(desc):
    """The float32 volume [z, y, x] of a built dataset (for skimage, OpenVDB)."""
    return read_nrrd(desc["nrrd"])


if __name__ == "__main__":
    # python3 datasets.py NAME KEYMESH WORK: builds one dataset, prints its
    # description as JSON. bench/run.py builds in this separate process so
    # that its own peak RSS stays small: a child inherits its parent's peak
    # RSS high-water mark through fork and exec, which would otherwise show in
    # every benchmark program's getrusage() peak.
    import json
    import sys
    print(json.dumps(build(sys.argv[1], sys.argv[2], sys.argv[3])))
