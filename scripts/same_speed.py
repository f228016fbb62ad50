#!/usr/bin/env python3
"""Shows that a change left keymesh's speed alone: runs bench/contour_bench and
bench/ops_bench of two builds side by side, alternating which goes first,
and prints the median time of each and new/old per case.

    python3 scripts/same_speed.py --before OLD_BUILD_DIR --after build [--rounds 4] [--threads 2]

Each round runs every harness once per build (each harness reports the
median of its own --reps 5). Counts (cells) are printed too: they must be
equal. Measure on a quiet machine (`uptime`); quote the load with the ratios.
"""
import argparse
import json
import statistics
import subprocess

BRAIN = "/usr/share/mricron/templates/ch2better.nii.gz"


def cases(threads):
    t = ["--threads", str(threads), "--reps", "5"]
    return [
        ("contour_bench", ["--size", "256"] + t, "sphere 256 contour"),
        ("contour_bench", ["--size", "256", "--normals", "average"] + t, "sphere 256 contour, averaged normals"),
        ("contour_bench", ["--file", BRAIN, "--iso", "90.5"] + t, "brain (ch2better) contour"),
        ("contour_bench", ["--size", "256", "--coarsen", "on"] + t, "sphere 256 contour + coarsen"),
        ("contour_bench", ["--size", "64", "--grid", "tet5", "--normals", "average"] + t, "tets 64 contour"),
        ("ops_bench", ["--op", "subdivide", "--size", "128"] + t, "subdivide 128"),
        ("ops_bench", ["--op", "tet24", "--size", "96"] + t, "tetrahedralize 24, 96"),
        ("ops_bench", ["--op", "tet5", "--size", "128"] + t, "tetrahedralize 5, 128"),
        ("ops_bench", ["--op", "dual", "--size", "128"] + t, "dual 128"),
        ("ops_bench", ["--op", "coarsen", "--size", "128"] + t, "coarsen 128"),
    ]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--before", required=True, help="build folder (or folder holding contour_bench, ops_bench)")
    ap.add_argument("--after", required=True)
    ap.add_argument("--rounds", type=int, default=4)
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    for exe, args, name in cases(a.threads):
        times = {"old": [], "new": []}
        cells = {}
        for r in range(a.rounds):
            order = (("new", a.after), ("old", a.before)) if r % 2 == 0 else (("old", a.before), ("new", a.after))
            for tag, folder in order:
                p = subprocess.run([f"{folder}/{exe}"] + args, capture_output=True, text=True)
                if p.returncode != 0:
                    raise SystemExit(f"{name} ({tag}): exit {p.returncode}: {p.stderr.strip()[:300]}")
                row = json.loads(p.stdout.strip().splitlines()[-1])
                times[tag].append(row["median"])
                cells[tag] = row.get("cells")
        o, n = statistics.median(times["old"]), statistics.median(times["new"])
        print(f"{name:40s} old {o * 1e3:8.2f} ms  new {n * 1e3:8.2f} ms  new/old {n / o:5.3f}  "
              f"cells {cells['old']} / {cells['new']}")


if __name__ == "__main__":
    main()
