#!/bin/bash
# One-shot commands as a user runs them, a fresh process each: two builds side by side
# (hyperfine -N, medians), 2 threads. Usage: bench/oneshot.sh OLD_BUILD_DIR NEW_BUILD_DIR
# (RUNS=9 by default). Inputs from Debian packages: mricron-data, libvolpack1-dev.
OLD=$(realpath "${1:?old build dir}")
NEW=$(realpath "${2:?new build dir}")
C=/usr/share/mricron/templates/ch2better.nii.gz
B=/usr/share/doc/libvolpack1-dev/examples/brainsmall.den
cd /tmp
$NEW/keymesh contour $C --iso 90.5 -o /tmp/m_ch.ply -q --threads 2
date -u +%H:%M:%S; uptime
run() { # name, args...
  local name=$1; shift
  hyperfine -N -w 2 -r ${RUNS:-9} --export-json /tmp/hf_$name.json "$OLD/keymesh $*" "$NEW/keymesh $*" > /dev/null 2>&1
  python3 - "$name" <<'PY'
import json,sys
d=json.load(open(f"/tmp/hf_{sys.argv[1]}.json"))["results"]
print(f"{sys.argv[1]:28s} before {d[0]['median']*1e3:8.1f} ms   after {d[1]['median']*1e3:8.1f} ms   ({d[0]['median']/d[1]['median']:.2f}x)")
PY
}
run version --version
run info_brainsmall info $B
run contour_brainsmall_coarsen contour $B --iso 37.3 --coarsen -o /tmp/m1.ply -q --threads 2
run contour_ch_ply contour $C --iso 90.5 -o /tmp/m2.ply -q --threads 2
run contour_ch_coarsen_ply contour $C --iso 90.5 --coarsen -o /tmp/m3.ply -q --threads 2
run contour_ch_vtp contour $C --iso 90.5 -o /tmp/m4.vtp -q --threads 2
run contour_ch_stl contour $C --iso 90.5 -o /tmp/m5.stl -q --threads 2
run contour_ch_obj contour $C --iso 90.5 -o /tmp/m6.obj -q --threads 2
run check_ch_ply check /tmp/m_ch.ply -q --threads 2
run info_ch info $C
uptime; date -u +%H:%M:%S
