#!/usr/bin/env python3
"""Coarsening's cost over the plain contour (issue 17, Table 5's question), two builds side by side:
bench/contour_bench --coarsen off, then on, 2 threads, 15 calls a process, medians of the last 10
(a harness process's first calls run slow on these VMs: 53 ms, then 8.5-16 ms for about ten calls,
then 6.9-7.0 ms on ch2bet, 2026-11-25), on the sphere (256^3, 512^3), brainsmall.den
(libvolpack1-dev) and ch2better.nii.gz (mricron-data). Prints a Markdown table.

    python3 bench/coarsen_cost.py OLD_BUILD_DIR build"""
import json, subprocess, sys, os
old, new = sys.argv[1], sys.argv[2]
cases = [("sphere 256^3", ["--size", "256"]), ("sphere 512^3", ["--size", "512"]),
         ("brainsmall.den iso 37.3", ["--file", "/usr/share/doc/libvolpack1-dev/examples/brainsmall.den", "--iso", "37.3"]),
         ("ch2better uint8 iso 90.5", ["--file", "/usr/share/mricron/templates/ch2better.nii.gz", "--iso", "90.5"])]
def run(d, args, c):
    p = subprocess.run([os.path.join(d, "contour_bench"), *args, "--threads", "2", "--reps", "15", "--coarsen", c],
                       capture_output=True, text=True, check=True)
    d = json.loads(p.stdout.strip().splitlines()[-1])
    warm = sorted(d["times_ms"][5:])
    d["median"] = warm[len(warm) // 2] / 1e3
    return d
print("| volume | build | contour ms | + coarsening ms | cost | triangles | peak MiB (coarsened) |")
print("| --- | --- | ---: | ---: | ---: | ---: | ---: |")
for name, args in cases:
    for label, d in (("before", old), ("after", new)):
        off = run(d, args, "off"); on = run(d, args, "on")
        print(f"| {name} | {label} | {off['median']*1e3:.1f} | {on['median']*1e3:.1f} | "
              f"{(on['median']/off['median']-1)*100:+.0f}% | {off['cells']:,} → {on['cells']:,} | {on['peak_rss_mib']:.0f} |", flush=True)
print("load", os.getloadavg())
