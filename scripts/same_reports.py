#!/usr/bin/env python3
"""Proves that a CLI refactor left what the commands *say* alone, where
same_outputs.py proves the files they write: runs the commands of
same_outputs.py plus check, quality, info, generate and usage errors with two
builds and compares, case by case, the exit code, stdout and stderr (the
lines keymesh prints), the --report JSON (every key; every value except the
timings and memory peaks), and `--help` of every subcommand.

    python3 scripts/same_reports.py --before /path/to/old/keymesh --after build/keymesh

Exits 1 and shows the differences; 0 when every case is the same.
"""
import argparse
import difflib
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import same_outputs as so  # noqa: E402  (its cases, inputs and runner)

# Report values that measure the run rather than describe its result.
TIMING_TREES = {"seconds", "contour_stages", "labels_stages"}
TIMING_FLOATS = {"peak_rss_mib", "device_peak_mib", "read", "contour", "merge", "balance", "wait", "exchange",
                 "output"}

EXTRA = [
    ("check", "check {in:m.vtp}"),
    ("check-closed", "check {in:m.ply} --expect-closed"),
    ("quality", "quality {in:m.vtp}"),
    ("generate", "generate sphere --size 8 -o {out}.vti"),
    ("info-volume", "info {in:s96.vti}"),
    ("info-mesh", "info {in:m.vtp}"),
    ("info-grid", "info {in:tets.vtu}"),
    ("pipeline-tets", "pipeline {in:tets.vtu} -o {out}.vtp --iso 5.3 --subdivide 1"),
    ("raw-contour", "contour {in:s96.raw} -o {out}.vtp --iso 15.3 --dims 40 40 40 --type float32"),
    ("tets24-vweld", "tetrahedralize {in:s24.vti} -o {out}.vtu --scheme 24 --weld vertexweld"),
    ("subdivide-bezier-vweld", "subdivide {in:m.vtp} -o {out}.vtp --weld vertexweld --scheme bezier"),
    ("mpi-pvtp", "mpirun:2 contour {in:s96.vti} -o {out}.pvtp --iso 13.1"),
    # usage errors and refusals: the message and exit code are the contract
    ("bad-iso", "contour {in:s96.vti} -o {out}.vtp --iso nan"),
    ("bad-weld", "contour {in:s96.vti} -o {out}.vtp --iso 3 --weld glue"),
    ("tets-gradient", "contour {in:tets.vtu} -o {out}.vtp --iso 3 --normals gradient"),
    ("tets-curvature", "contour {in:tets.vtu} -o {out}.vtp --iso 3 --curvature"),
    ("pipeline-bezier", "pipeline {in:s96.vti} -o {out}.vtp --iso 3 --scheme bezier --normals none"),
    ("pipeline-cuda", "pipeline {in:s96.vti} -o {out}.vtp --iso 3 --dual --backend cuda"),
    ("contour-cuda", "contour {in:s96.vti} -o {out}.vtp --iso 3 --backend cuda"),
    ("subdivide-bezier-tets", "subdivide {in:tets.vtu} -o {out}.vtu --scheme bezier"),
    ("tets24-grid", "tetrahedralize {in:tets.vtu} -o {out}.vtu --scheme 24"),
    ("mpi-tets", "mpirun:2 contour {in:tets.vtu} -o {out}.vtp --iso 3"),
    ("mpi-memory-limit", "mpirun:2 contour {in:s96.vti} -o {out}.vtp --iso 3 --memory-limit 1M"),
    ("mpi-gather-pvtp", "mpirun:2 contour {in:s96.vti} -o {out}.pvtp --iso 3 --gather"),
]
SUBCOMMANDS = ["", "contour", "pipeline", "convert", "subdivide", "tetrahedralize", "dual", "quality", "check",
               "generate", "info", "labels"]


def without_timings(j, key=None):
    if isinstance(j, dict):
        return {k: "T" if k in TIMING_TREES else without_timings(v, k) for k, v in j.items()}
    if isinstance(j, list):
        return [without_timings(v, key) for v in j]
    return "T" if isinstance(j, float) and key in TIMING_FLOATS else j


def said(text, exe, tag):
    """keymesh's own lines (mpirun's job ids left out), with the build's paths neutralised."""
    lines = [l for l in text.replace(exe, "K").replace(tag, ".X").splitlines()
             if l.startswith(("keymesh", "/")) or (l.startswith("  ") and not l.lstrip().startswith(("Process", "Exit")))]
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--before", required=True)
    ap.add_argument("--after", required=True)
    a = ap.parse_args()
    builds = {"before": os.path.abspath(a.before), "after": os.path.abspath(a.after)}
    cases = [c for c in so.CASES if "labels" not in c[1]] + EXTRA
    if not so.MPIRUN:
        cases = [c for c in cases if not c[1].startswith("mpirun:")]
    tmp = tempfile.mkdtemp(prefix="keymesh-reports-")
    inputs = os.path.join(tmp, "inputs")
    os.makedirs(inputs)
    before = builds["before"]
    for args in (["generate", "sphere", "--size", "40", "-o", "s96.vti"], ["convert", "s96.vti", "-o", "s96.nrrd"],
                 ["convert", "s96.vti", "-o", "s96.raw"], ["convert", so.HEAD, "-o", "head.nrrd"],
                 ["generate", "sphere", "--size", "16", "-o", "s24.vti"],
                 ["tetrahedralize", "s24.vti", "-o", "tets.vtu"],
                 ["contour", "s96.vti", "-o", "m.vtp", "--iso", "15.3", "--normals", "average"],
                 ["contour", "s96.vti", "-o", "m.ply", "--iso", "15.3"],
                 ["contour", "s96.vti", "-o", "sphere-vtp-avg.vtp", "--iso", "15.3", "--normals", "average"],
                 ["contour", "s96.vti", "-o", "sphere-ply.ply", "--iso", "15.3"]):
        so.run(before, [os.path.join(inputs, x) if x.endswith((".vti", ".nrrd", ".raw", ".vtu", ".vtp", ".ply")) and not x.startswith("/") else x for x in args]
               + ["-q"])
    named = {"tets": "tets.vtu", "sphere-vtp-avg": "sphere-vtp-avg.vtp", "sphere-ply": "sphere-ply.ply"}
    differ = []
    for name, template in cases:
        seen = {}
        for build, exe in builds.items():
            args = template
            for key in [k.split("}")[0] for k in template.split("{in:")[1:]]:
                args = args.replace("{in:" + key + "}", os.path.join(inputs, named.get(key, key)))
            tag = f".{build}"
            args = args.replace("{out}", os.path.join(tmp, name + tag))
            report = os.path.join(tmp, f"{name}{tag}.json")
            r = so.run(exe, args.split() + ["--threads", "2", "--report", report], check=False)
            j = None
            if os.path.exists(report):
                with open(report) as f:
                    j = json.loads(json.dumps(without_timings(json.load(f))).replace(tag, ".X"))
            seen[build] = (r.returncode, said(r.stdout, exe, tag), said(r.stderr, exe, tag), j)
        same = seen["before"] == seen["after"]
        print(f"{'same ' if same else 'DIFF '} {name} (exit {seen['after'][0]})")
        if not same:
            differ.append(name)
            for i, what in enumerate(("exit", "stdout", "stderr", "report")):
                if seen["before"][i] != seen["after"][i]:
                    print(f"    {what} before: {seen['before'][i]}\n    {what} after:  {seen['after'][i]}")
    for sub in SUBCOMMANDS:
        helps = {b: subprocess.run([exe] + ([sub] if sub else []) + ["--help"], capture_output=True,
                                   text=True).stdout.replace(exe, "K") for b, exe in builds.items()}
        same = helps["before"] == helps["after"]
        print(f"{'same ' if same else 'DIFF '} --help {sub}")
        if not same:
            differ.append(f"--help {sub}")
            sys.stdout.writelines(difflib.unified_diff(helps["before"].splitlines(True),
                                                       helps["after"].splitlines(True)))
    print(f"{len(differ)} differ" + (": " + ", ".join(differ) if differ else ""))
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
