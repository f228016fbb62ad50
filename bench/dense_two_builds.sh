#!/bin/bash
# The dense rows of issue 17 for two builds, alternated, two rounds: bench/dense.py (keymesh.contour
# against vtkFlyingEdges3D in one Python process, default malloc and glibc.malloc.hugetlb=1), then
# bench/contour_bench on the volumes dense.py dumps (KEYMESH_HUGE_PAGES=1 and 0), 2 threads,
# medians of 5. Prints dense.py's ratio lines and the C++ medians; the JSON lines go to
# OUT.ROUND.BUILD_NAME.py{0,1}. A contour_bench built with VTK's C++ package also runs
# vtkFlyingEdges3D in its own process (--peer fe3d) and prints its median and ratio; for
# one without, FE3D's medians are in dense.py's JSON.
#   bench/dense_two_builds.sh OLD_BUILD_DIR NEW_BUILD_DIR [OUT_PREFIX]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
old=$1 new=$2 out=${3:-/tmp/dense}
dumps=$(mktemp -d)
for round in 1 2; do
  for b in "$old" "$new"; do
    name=$(basename "$(dirname "$(readlink -f "$b")")")-$(basename "$b")
    for huge in 0 1; do
      echo "== $(date -u +%T) load $(cut -d' ' -f1 /proc/loadavg) build $b huge $huge round $round"
      if [ $huge = 1 ]; then tunables=glibc.malloc.hugetlb=1; else tunables=; fi
      env ${tunables:+GLIBC_TUNABLES=$tunables} PYTHONPATH="$b/python" /usr/bin/python3 "$here/dense.py" --threads 2 --reps 5 \
        --dump "$dumps" --json "$out.$round.$name.py$huge" | grep "#"
    done
    for c in brain noise head256 sphere512; do
      iso=$(python3 -c "import json,sys; print([json.loads(l) for l in open(sys.argv[1]) if json.loads(l)['case'] == sys.argv[2]][0]['isovalues'][0])" "$out.$round.$name.py1" $c)
      # vtkFlyingEdges3D in the harness's process too where the build has it (libvtk9-dev).
      peer=(); if ! "$b/contour_bench" --peer fe3d --size 4 --reps 1 2>&1 >/dev/null | grep -q "built without VTK"; then peer=(--peer fe3d); fi
      for hp in 1 0; do
        KEYMESH_HUGE_PAGES=$hp "$b/contour_bench" --file "$dumps/$c.nrrd" --iso "$iso" --threads 2 --reps 5 "${peer[@]}" | tail -1 |
          python3 -c "import json,sys; d=json.load(sys.stdin); print('cpp $c huge $hp', round(d['median']*1e3,1), 'first', round(d['first']*1e3,1), *(['fe3d', round(d['peer_median']*1e3,1), 'ratio', round(d['peer_ratio'],2)] if 'peer' in d else []))"
      done
    done
  done
done
rm -rf "$dumps"
