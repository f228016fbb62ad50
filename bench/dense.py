#!/usr/bin/env python3
"""keymesh against vtkFlyingEdges3D on real and dense volumes, in one process.

    PYTHONPATH=build/python /usr/bin/python3 bench/dense.py [--threads 2] [--reps 5] [--json out.jsonl]

The rows of issue 17, built here from Debian packages (nothing downloaded):
  brain     ch2better.nii.gz (mricron-data), native uint8 301 x 370 x 316, iso 90.5
  brain8    the same volume, 8 isovalues 20.5 + 12 i (i = 0..7) in one call
  noise     Gaussian-smoothed white noise 256^3 float32 (sigma 2, periodic,
            numpy FFT, seed 0), iso 0
  head256   ch2.nii.gz (mricron-data) resampled to 256^3 (trilinear), iso 90.5
  sphere512 the paper's Spherical Distance field 512^3 float32, iso 255.001
Not in the default run, volumes nothing here was tuned on (--cases bet,inia19):
  bet       ch2bet.nii.gz (mricron-data), brain extracted, uint8 181 x 217 x 181,
            iso 92.5 (the median of its non-zero voxels)
  inia19    inia19-t1-brain.nii.gz (mricron-data), a macaque T1 template,
            float32 168 x 206 x 128, iso 90.6 (the same median)
and the other sample types (--cases brain_i16,brain_u16,noise_f64):
  brain_i16 ch2better as int16, 10 v - 500, iso 405 (brain's 90.5)
  brain_u16 ch2better as uint16, 100 v, iso 9050
  noise_f64 smoothed noise 192^3 as float64, iso 0

Both tools see the same array (x fastest in memory) at the same thread count
(vtkSMPTools.Initialize(T), keymesh threads=T) and compute the same arrays:
positions and triangles only (keymesh normals="none", scalars=False;
vtkFlyingEdges3D, which computes normals and scalars by default,
ComputeNormalsOff() and ComputeScalarsOff()), or, with --scalars, both also
the interpolated scalar. Every call returns fresh output arrays, as a user's
call does. Medians of --reps calls, after one warm-up call each. Run twice by
bench/run.py: with GLIBC_TUNABLES=glibc.malloc.hugetlb=1 (huge pages for
both) and without (the default malloc of a Python process). Peak memory is the process's
high-water mark after each tool's calls, from getrusage, minus the inputs.
"""
import argparse
import gzip
import json
import os
import statistics
import struct
import sys
import time

import numpy as np

import peer_common

MRICRON = "/usr/share/mricron/templates"


def read_nifti_gz(path):
    """A gzip NIfTI-1 (uint8 or float32), as an array of shape (nz, ny, nx) (x fastest)."""
    with gzip.open(path, "rb") as f:
        data = f.read()
    dims = struct.unpack("<8h", data[40:56])
    dtype = {2: np.uint8, 4: np.int16, 16: np.float32, 512: np.uint16}[struct.unpack("<h", data[70:72])[0]]
    offset = int(struct.unpack("<f", data[108:112])[0])
    nx, ny, nz = dims[1:4]
    return np.frombuffer(data, dtype=dtype, count=nx * ny * nz, offset=offset).reshape(nz, ny, nx).copy()


def resample(v, n):
    """Trilinear, corner-aligned resampling of a (nz, ny, nx) array to n^3, float32 (as bench/datasets.py)."""
    out = v.astype(np.float32)
    for axis in range(3):
        m = out.shape[axis]
        x = np.arange(n) * (m - 1) / (n - 1)
        i0 = np.minimum(np.floor(x).astype(np.int64), m - 2)
        t = (x - i0).astype(np.float32)
        a = np.take(out, i0, axis=axis)
        b = np.take(out, i0 + 1, axis=axis)
        shape = [1, 1, 1]
        shape[axis] = n
        out = a + (b - a) * t.reshape(shape)
    return np.ascontiguousarray(out)


def smoothed_noise(n, sigma, seed=0):
    rng = np.random.default_rng(seed)
    v = rng.standard_normal((n, n, n), dtype=np.float32)
    k = np.fft.fftfreq(n).astype(np.float32)
    g = np.exp(-2 * (np.pi * sigma * k) ** 2).astype(np.float32)
    f = np.fft.rfftn(v)
    f *= g[:, None, None] * g[None, :, None] * g[None, None, : n // 2 + 1]
    return np.ascontiguousarray(np.fft.irfftn(f, s=v.shape).astype(np.float32))


def sphere(n):
    c = n // 2
    x = np.arange(n, dtype=np.float64) - c
    return np.sqrt(x[None, None, :] ** 2 + x[None, :, None] ** 2 + x[:, None, None] ** 2).astype(np.float32)


def cases(names):
    brain = None
    for name in names:
        if name in ("brain", "brain8"):
            if brain is None:
                brain = read_nifti_gz(os.path.join(MRICRON, "ch2better.nii.gz"))
            isos = [90.5] if name == "brain" else [20.5 + 12 * i for i in range(8)]
            yield name, "ch2better.nii.gz uint8 301x370x316", brain, isos
        elif name == "noise":
            yield name, "smoothed noise 256^3 float32 sigma 2", smoothed_noise(256, 2.0), [0.0]
        elif name == "head256":
            v = resample(read_nifti_gz(os.path.join(MRICRON, "ch2.nii.gz")), 256)
            yield name, "ch2.nii.gz resampled 256^3 float32", v, [90.5]
        elif name == "bet":  # volumes no keymesh code was tuned on (issue 17's "other real volumes")
            v = read_nifti_gz(os.path.join(MRICRON, "ch2bet.nii.gz"))
            yield name, "ch2bet.nii.gz uint8 181x217x181 (brain extracted)", v, [92.5]
        elif name == "inia19":
            v = read_nifti_gz(os.path.join(MRICRON, "inia19-t1-brain.nii.gz"))
            yield name, "inia19-t1-brain.nii.gz float32 168x206x128 (macaque)", v, [90.6]
        elif name in ("brain_i16", "brain_u16"):  # the same brain in the 16-bit types CT and MR scanners write
            if brain is None:
                brain = read_nifti_gz(os.path.join(MRICRON, "ch2better.nii.gz"))
            if name == "brain_i16":
                yield name, "ch2better.nii.gz as int16 (10 v - 500)", (brain.astype(np.int16) * 10 - 500), [405.0]
            else:
                yield name, "ch2better.nii.gz as uint16 (100 v)", brain.astype(np.uint16) * 100, [9050.0]
        elif name == "noise_f64":
            yield name, "smoothed noise 192^3 float64 sigma 2", smoothed_noise(192, 2.0).astype(np.float64), [0.0]
        elif name == "sphere512":
            yield name, "Spherical Distance 512^3 float32", sphere(512), [255.001]
        else:
            raise SystemExit(f"unknown case {name}")


def write_nrrd(path, v):
    """A raw, attached-header .nrrd of a (nz, ny, nx) array (x fastest)."""
    kind = {np.dtype(np.uint8): "uint8", np.dtype(np.float32): "float", np.dtype(np.int16): "short",
            np.dtype(np.uint16): "ushort", np.dtype(np.float64): "double"}[v.dtype]
    nz, ny, nx = v.shape
    with open(path, "wb") as f:
        f.write(f"NRRD0004\ntype: {kind}\ndimension: 3\nsizes: {nx} {ny} {nz}\nencoding: raw\n"
                f"endian: little\n\n".encode())
        f.write(np.ascontiguousarray(v).tobytes())


# The warm-up call's seconds (the first call of a case: code paths, thread
# pools, and for keymesh no kept output blocks of this size yet), recorded
# as "first" beside the medians.
last_first = 0.0


def timed(fn, reps):
    global last_first
    t0 = time.perf_counter()
    fn()  # warm-up
    last_first = time.perf_counter() - t0
    times = []
    out = None
    for _ in range(reps):
        out = None
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return times, out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--cases", default="brain,brain8,noise,head256,sphere512")
    ap.add_argument("--tools", default="keymesh,vtkFlyingEdges3D")
    ap.add_argument("--single-isos", action="store_true",
                    help="also time each isovalue of multi-isovalue cases alone (the sum is reported)")
    ap.add_argument("--scalars", action="store_true",
                    help="both tools also carry the interpolated scalar (keymesh's default, and VTK's)")
    ap.add_argument("--json", help="append one JSON line per measurement to this file")
    ap.add_argument("--dump", help="also write each case's volume to DIR/CASE.nrrd (for bench/contour_bench)")
    a = ap.parse_args()
    tools = a.tools.split(",")
    huge = "glibc.malloc.hugetlb=1" in os.environ.get("GLIBC_TUNABLES", "")
    import keymesh
    if "vtkFlyingEdges3D" in tools:
        import vtk
        from vtk.util import numpy_support as ns
        vtk.vtkSMPTools.Initialize(a.threads)
    out = open(a.json, "a") if a.json else None
    for name, label, v, isos in cases(a.cases.split(",")):
        nz, ny, nx = v.shape
        rows = []

        def record(tool, times, points, cells, extra=None):
            r = {"bench": "dense", "case": name, "label": label, "tool": tool, "threads": a.threads,
                 "huge_pages": huge, "scalars": a.scalars, "isovalues": isos, "points": int(points), "cells": int(cells),
                 "median": statistics.median(times), "min": min(times), "max": max(times), "reps": len(times),
                 "peak_rss_mib": peer_common.peak_rss_mib(), "input_mib": v.nbytes / 2**20}
            r.update(extra or {})
            rows.append(r)
            print(json.dumps(r), flush=True)
            if out:
                out.write(json.dumps(r) + "\n")
                out.flush()

        dump = None
        if a.dump:
            dump = os.path.join(a.dump, name + ".nrrd")
            if not os.path.exists(dump):
                write_nrrd(dump, v)
        if "keymesh" in tools:
            grid = v.T  # shape (nx, ny, nz), Fortran order: keymesh's axis 0 = x, read in place
            def km(iso):
                return keymesh.contour(grid, iso, normals="none", scalars=a.scalars, threads=a.threads)

            times, m = timed(lambda: km(isos), a.reps)
            extra = {"first": last_first, "stages": dict(keymesh.last_contour_info), "dump": dump,
                     "output_mib": (m.points.nbytes + m.cells.nbytes +
                                    sum(v.nbytes for v in m.point_data.values())) / 2**20}
            n_points, n_cells = m.n_points, m.n_cells
            del m
            if a.single_isos and len(isos) > 1:
                extra["sum_single"] = sum(
                    statistics.median(timed(lambda: km(iso), a.reps)[0]) for iso in isos)
            record("keymesh", times, n_points, n_cells, extra)
        if "vtkFlyingEdges3D" in tools:
            img = vtk.vtkImageData()
            img.SetDimensions(nx, ny, nz)
            arr = ns.numpy_to_vtk(v.ravel(), deep=False)
            arr.SetName("v")
            img.GetPointData().SetScalars(arr)

            def fe():
                f = peer_common.contour_filter(vtk.vtkFlyingEdges3D, img, isos, scalars=a.scalars)
                f.Update()
                return f.GetOutput()

            times, poly = timed(fe, a.reps)
            record("vtkFlyingEdges3D", times, poly.GetNumberOfPoints(), poly.GetNumberOfCells(), {"first": last_first})
            del poly
        if len(rows) == 2:
            print(f"# {name}: vtkFlyingEdges3D / keymesh = {rows[1]['median'] / rows[0]['median']:.2f}"
                  f" (first calls {rows[1]['first'] / rows[0]['first']:.2f})"
                  f" (huge pages {huge}, scalars {a.scalars}, {a.threads} threads)", flush=True)


if __name__ == "__main__":
    main()
