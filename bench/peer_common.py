"""What the bench's peer scripts share (bench/peers/*.py, dense.py,
labels_bench.py): how a VTK filter is read, set up and timed, and the JSON
row that bench/run.py and bench/report.py read back. The module imports no
VTK itself: callers pass VTK's classes, so a peer without VTK can use it too.
"""
import argparse
import json
import resource
import statistics
import time


def peak_rss_mib():
    """The process's peak RSS so far (Linux reports KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def timing(times):
    """The timing columns every peer row ends with, in report.py's order."""
    return {"median": statistics.median(times), "min": min(times), "max": max(times), "first": times[0],
            "reps": len(times), "peak_rss_mib": peak_rss_mib()}


def print_row(row, times):
    """One JSON line: the case's columns, then its timing (bench/run.py keeps lines starting with '{')."""
    print(json.dumps({**row, **timing(times)}), flush=True)


def read(reader_class, path):
    """The output of a VTK reader class on path."""
    reader = reader_class()
    reader.SetFileName(path)
    reader.Update()
    return reader.GetOutput()


def surface_peer_args(reader_class):
    """The arguments of a peer timing a filter on a surface file (--mesh; --size,
    the volume's, names the case; --reps) and the surface, read by reader_class."""
    ap = argparse.ArgumentParser()
    ap.add_argument("--mesh", required=True)
    ap.add_argument("--size", type=int, required=True)
    ap.add_argument("--reps", type=int, default=5)
    a = ap.parse_args()
    return a, read(reader_class, a.mesh)


def contour_filter(filter_class, data, values, scalars=False):
    """A VTK contour filter on data at values, not yet run, computing what
    keymesh's timed rows compute: positions only (no normals, no gradients;
    scalars only when asked). Gradients are off by default in every filter
    used here; switching them off again names what is measured."""
    f = filter_class()
    f.SetInputData(data)
    for i, value in enumerate(values):
        f.SetValue(i, value)
    f.ComputeNormalsOff()
    f.SetComputeScalars(scalars)
    if hasattr(f, "ComputeGradientsOff"):
        f.ComputeGradientsOff()
    return f


def time_updates(make_filter, reps, counts):
    """Times Update() alone on a fresh filter from make_filter(), reps
    times; returns the times and counts(output) of the last run. Each filter
    is dropped before the next is made, so the peak RSS holds one output."""
    times = []
    for _ in range(reps):
        f = make_filter()
        t0 = time.perf_counter()
        f.Update()
        times.append(time.perf_counter() - t0)
        result = counts(f.GetOutput())
        del f
    return times, result


def points_and_cells(output):
    return {"points": output.GetNumberOfPoints(), "cells": output.GetNumberOfCells()}
