#!/usr/bin/env bash
# The GPU check (docs/gpu-check.md): run from the repository root on a CUDA
# machine, with build-gpucheck/ (from `make gpu-check-build`) beside it:
#
#   bash scripts/gpu_check.sh
#
# Prints the driver, the GPU and glibc; runs the CUDA tests; compares
# `keymesh contour --backend cuda` with `--backend cpu` byte for byte (cmp of
# the written meshes) on generated inputs from 64^3 to 1024^3, twice, with the
# paper's Table 1 counts; the same for `tetrahedralize` (5 and 24 tets),
# `contour` of a tet grid and `subdivide` (tets, triangles linear and Bezier)
# at a small and a large size, `contour --curvature` and `labels` (smoothed,
# the fold guard acting); runs compute-sanitizer's memcheck on small cases;
# runs the 2^32-triangle checkerboard in its own process; times 512^3 and
# 1024^3 with CUDA events (keymesh_gpu_timing). Writes summary.json and
# gpu_check.log into $OUT (default ./gpu-check-out).
#
# Every step has its own timeout and a failing step does not stop the next;
# the whole check keeps within GPU_CHECK_BUDGET seconds (default 280). On a
# machine without a GPU the GPU steps say "no GPU" and the CPU steps still
# run. When the carried programs do not start, it says why and, where cmake
# and nvcc are found, builds the timing program alone
# (cmake/gpu_check_minimal) and runs its steps.
#
# Environment: OUT, GPU_CHECK_BIN (default build-gpucheck), GPU_CHECK_BACKEND
# (cpu: a dry run of the script where there is no GPU), GPU_CHECK_SIZES
# (default "64 128 256 512 1024"), GPU_CHECK_UNSTRUCTURED_SIZES (default
# "32 96"), GPU_CHECK_BUDGET, GPU_CHECK_MAX_MEMORY
# (default 96G), TMPDIR; GPU_CHECK_PYTHONPATH (a build's python folder:
# runs tests/python/test_dlpack.py with GPU_CHECK_PYTHON, default python3).
set -u
OUT=${OUT:-./gpu-check-out}
BIN=${GPU_CHECK_BIN:-build-gpucheck}
SIZES=${GPU_CHECK_SIZES:-64 128 256 512 1024}
BUDGET=${GPU_CHECK_BUDGET:-280}
# A VM's MemTotal can start below what it grows to: bound the work by hand.
MEM="--max-memory ${GPU_CHECK_MAX_MEMORY:-96G}"
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)
LOG=$OUT/gpu_check.log
: >"$LOG"
WORK=$(mktemp -d "${TMPDIR:-/tmp}/keymesh-gpu-check.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
START=$(date +%s)
STEPS=()    # JSON objects, one per step
FAILED=0

say() { echo "$*" | tee -a "$LOG"; }
json_str() { printf '"%s"' "$(printf '%s' "$1" | tr -d '\000-\037' | sed 's/\\/\\\\/g; s/"/\\"/g')"; }
record() {  # name status seconds detail
  STEPS+=("{\"step\": $(json_str "$1"), \"status\": $(json_str "$2"), \"seconds\": $3, \"detail\": $(json_str "$4")}")
  [ "$2" = fail ] || [ "$2" = timeout ] && FAILED=$((FAILED + 1))
  say "[$2] $1 (${3}s)${4:+: $4}"
}

# step NAME TIMEOUT COMMAND...: runs COMMAND under `timeout`, its output into
# the log; pass on status 0, timeout on 124/137, fail otherwise. Skipped when
# the budget would be passed. Sets STEP_RC and STEP_OUT (its output file).
step() {
  local name=$1 limit=$2
  shift 2
  local now left t0 rc
  now=$(date +%s)
  left=$((BUDGET - (now - START)))
  STEP_OUT=$WORK/step.out
  : >"$STEP_OUT"
  if [ "$left" -lt 5 ]; then
    STEP_RC=125
    record "$name" skip 0 "no time left in the ${BUDGET}s budget"
    return
  fi
  [ "$limit" -gt "$left" ] && limit=$left
  t0=$(date +%s)
  timeout -k 5 "$limit" "$@" >"$STEP_OUT" 2>&1
  rc=$?
  STEP_RC=$rc
  { echo "---- $name: $*"; cat "$STEP_OUT"; echo "---- exit $rc"; } >>"$LOG"
  local took=$(($(date +%s) - t0))
  if [ $rc -eq 0 ]; then record "$name" pass "$took" ""
  elif [ $rc -eq 124 ] || [ $rc -eq 137 ]; then record "$name" timeout "$took" "over ${limit}s"
  else record "$name" fail "$took" "exit $rc: $(tail -n 3 "$STEP_OUT" | tr '\n' ' ' | cut -c1-300)"
  fi
}
skip() { record "$1" skip 0 "$2"; }
# After a step of keymesh_gpu_timing: where nvidia-smi lists a GPU, the
# program saying it found none ({"skipped": ...}, exit 0) is a failure.
expect_device() {
  if [ "$BACKEND" = cuda ] && [ $HAVE_GPU = 1 ] && grep -q '"skipped"' "$STEP_OUT"; then
    record "$1: the GPU is usable" fail 0 "$(grep -o '"skipped": "[^"]*"' "$STEP_OUT" | head -n 1)"
  fi
}

# ---- the machine -------------------------------------------------------------
GLIBC=$(ldd --version 2>/dev/null | head -n 1 | grep -oE '[0-9]+\.[0-9]+$' || echo unknown)
say "keymesh GPU check, $(date -u +%FT%TZ), $(uname -srm), glibc $GLIBC, $(nproc) cores"
say "commit: $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
GPU=none
DRIVER=none
if command -v nvidia-smi >/dev/null 2>&1 && nvidia-smi -L >"$WORK/smi" 2>&1 && grep -q '^GPU' "$WORK/smi"; then
  GPU=$(nvidia-smi --query-gpu=name,memory.total --format=csv,noheader | head -n 1)
  DRIVER=$(nvidia-smi --query-gpu=driver_version --format=csv,noheader | head -n 1)
  nvidia-smi >>"$LOG" 2>&1
fi
say "GPU: $GPU; driver: $DRIVER"
HAVE_GPU=0
[ "$GPU" != none ] && HAVE_GPU=1
# GPU_CHECK_BACKEND=cpu: a dry run of this script's own logic on any machine
# (the "cuda" contour runs use --backend cpu, so every comparison runs).
BACKEND=${GPU_CHECK_BACKEND:-cuda}
if [ "$BACKEND" != cuda ]; then
  HAVE_GPU=1
  say "GPU_CHECK_BACKEND=$BACKEND: a dry run, the 'cuda' contour runs use --backend $BACKEND"
fi
gpu_step() {  # like step, but "no GPU" where there is none
  if [ $HAVE_GPU = 0 ]; then STEP_RC=125; skip "$1" "no GPU"; else step "$@"; fi
}

# ---- the programs ------------------------------------------------------------
KEYMESH=$BIN/keymesh
TESTS=$BIN/keymesh_cuda_tests
TIMING=$BIN/keymesh_gpu_timing
PROGRAMS_RUN=1
for p in "$KEYMESH" "$TESTS" "$TIMING"; do
  if [ ! -x "$p" ]; then
    say "$p: missing (run \`make gpu-check-build\` and carry $BIN/)"
    PROGRAMS_RUN=0
  elif ! "$p" --help >"$WORK/start" 2>&1; then
    say "$p does not start: $(head -n 3 "$WORK/start" | tr '\n' ' ')"
    ldd "$p" >>"$LOG" 2>&1
    PROGRAMS_RUN=0
  fi
done
[ $PROGRAMS_RUN = 1 ] && record "programs start" pass 0 "$BIN" || record "programs start" fail 0 "see the log"
if [ $PROGRAMS_RUN = 0 ]; then
  KEYMESH=""
  TESTS=""
  TIMING=""
  if command -v cmake >/dev/null && { command -v nvcc >/dev/null || [ -x /usr/local/cuda/bin/nvcc ]; }; then
    step "fallback build (cmake/gpu_check_minimal)" 200 sh -c \
      "cmake -S cmake/gpu_check_minimal -B '$WORK/fallback' -DCMAKE_BUILD_TYPE=Release && cmake --build '$WORK/fallback' -j $(nproc)"
    [ $STEP_RC = 0 ] && TIMING=$WORK/fallback/keymesh_gpu_timing
  else
    skip "fallback build (cmake/gpu_check_minimal)" "cmake or nvcc not found"
  fi
fi

# ---- the CUDA tests ----------------------------------------------------------
if [ -n "$TESTS" ]; then
  step "CUDA tests (keymesh_cuda_tests)" 120 "$TESTS" --gtest_brief=1
  if [ "$BACKEND" = cuda ] && [ $HAVE_GPU = 1 ] && grep -qE 'no usable CUDA device|no CUDA device' "$STEP_OUT"; then
    record "CUDA tests: the GPU is usable" fail 0 "$(grep -m 1 -E 'no usable CUDA device|no CUDA device' "$STEP_OUT")"
  fi
else
  skip "CUDA tests (keymesh_cuda_tests)" "the test program does not run here"
fi

# ---- CPU against GPU, byte for byte --------------------------------------------
# Byte for byte: cmp, or equal SHA-256 sums where diffutils is missing (a
# command for `step`, which runs it under timeout: no shell function).
# shellcheck disable=SC2016
SAME_FILE='if command -v cmp >/dev/null; then cmp "$1" "$2"; else
  [ "$(sha256sum <"$1")" = "$(sha256sum <"$2")" ] || { echo "$1 and $2 differ (sha256)"; exit 1; }; fi'
count_of() { grep -oE "\"$1\": *[0-9]+" "$2" 2>/dev/null | grep -oE '[0-9]+$'; }
table1() {  # the paper's Table 1: points triangles at N^3, iso N/2 - 1 + 0.001
  case $1 in 128) echo "74715 149420" ;; 256) echo "303699 607388" ;; 512) echo "1225611 2451212" ;; esac
}
# compare_command NAME EXT COMMAND INPUT ARGS...: `keymesh COMMAND INPUT -o
# OUT.EXT ARGS` on the CPU once and on the GPU twice, the outputs cmp'd; the
# CPU's output stays as $CMP_BASE.cpu.EXT (its caller removes it).
compare_command() {
  local name=$1 ext=$2 command=$3 input=$4
  shift 4
  local base
  base=$WORK/$(echo "$name" | tr -c 'A-Za-z0-9_\n' '_')
  CMP_BASE=$base
  step "$name: cpu" 60 "$KEYMESH" "$command" "$input" -o "$base.cpu.$ext" --report "$base.cpu.json" -q $MEM \
    --backend cpu "$@"
  local cpu_rc=$STEP_RC
  for run in 1 2; do
    gpu_step "$name: cuda run $run" 60 "$KEYMESH" "$command" "$input" -o "$base.gpu$run.$ext" \
      --report "$base.gpu$run.json" -q $MEM --backend "$BACKEND" "$@"
  done
  if [ $HAVE_GPU = 0 ] || [ $cpu_rc != 0 ]; then
    skip "$name: cuda = cpu, byte for byte" "$([ $HAVE_GPU = 0 ] && echo no GPU || echo the CPU run failed)"
    return
  fi
  step "$name: cuda run 1 = cpu, byte for byte" 30 bash -c "$SAME_FILE" same_file "$base.cpu.$ext" "$base.gpu1.$ext"
  step "$name: cuda run 2 = run 1 (deterministic)" 30 bash -c "$SAME_FILE" same_file "$base.gpu1.$ext" "$base.gpu2.$ext"
  rm -f "$base".gpu*."$ext"
}
# compare NAME INPUT CONTOUR-ARGS...: the contour's CPU mesh and two GPU meshes, cmp'd.
compare() {
  local name=$1 input=$2
  shift 2
  compare_command "$name" ply contour "$input" "$@"
}
if [ -n "$KEYMESH" ]; then
  for n in $SIZES; do
    step "generate sphere ${n}^3" 60 "$KEYMESH" generate sphere --size "$n" -o "$WORK/sphere$n.vti" -q $MEM
    [ $STEP_RC = 0 ] || continue
    iso=$(awk -v n="$n" 'BEGIN { printf "%.3f", n / 2 - 1 + 0.001 }')
    compare "sphere ${n}^3 iso $iso" "$WORK/sphere$n.vti" --iso "$iso"
    expect=$(table1 "$n")
    if [ -n "$expect" ]; then
      b=$WORK/$(echo "sphere ${n}^3 iso $iso" | tr -c 'A-Za-z0-9_\n' '_')
      for side in cpu gpu1; do
        [ $side = gpu1 ] && [ $HAVE_GPU = 0 ] && { skip "Table 1 at ${n}^3 ($side)" "no GPU"; continue; }
        got="$(count_of points "$b.$side.json") $(count_of cells "$b.$side.json")"
        if [ "$got" = "$expect" ]; then record "Table 1 at ${n}^3 ($side)" pass 0 "$got"
        else record "Table 1 at ${n}^3 ($side)" fail 0 "points triangles $got, the paper's $expect"; fi
      done
    fi
    if [ "$n" = 256 ]; then
      compare "sphere 256^3, 3 isovalues, averaged normals" "$WORK/sphere$n.vti" \
        --iso 30.5 --iso 60.001 --iso 100 --normals average
      compare "sphere 256^3, gradient normals" "$WORK/sphere$n.vti" --iso 90.25 --normals gradient
      compare_command "sphere 256^3, gradient normals and curvature" vtp contour "$WORK/sphere$n.vti" --iso 90.25 \
        --normals gradient --curvature
    fi
    rm -f "$WORK/sphere$n.vti" "$WORK"/*.cpu.ply "$WORK"/*.cpu.vtp
  done
  # Integer noise with samples on the isovalue (128), and float32 random bits
  # (NaN and inf among them).
  for n in 64 160; do
    head -c $((n * n * n)) /dev/urandom >"$WORK/noise$n.raw"
    compare "uint8 noise ${n}^3 iso 128 (on samples)" "$WORK/noise$n.raw" --dims $n $n $n --type uint8 --iso 128 \
      --normals average
    rm -f "$WORK/noise$n.raw" "$WORK"/*.cpu.ply
  done
  head -c $((4 * 64 * 64 * 64)) /dev/urandom >"$WORK/bits64.raw"
  compare "float32 random bits 64^3 (NaN, inf)" "$WORK/bits64.raw" --dims 64 64 64 --type float32 --iso 0 \
    --normals gradient
  rm -f "$WORK"/*.ply
else
  skip "keymesh contour, cuda against cpu" "the keymesh command does not run here"
fi

# ---- the unstructured generators: CPU against GPU, byte for byte -------------------
# tetrahedralize --scheme 5 and 24 of a volume, marching tetrahedra on the
# 5-tet grid, subdivision of that grid (tets 1 -> 8) and of a contour
# (triangles 1 -> 4, linear and Bezier), each at a small and a large size
# (GPU_CHECK_UNSTRUCTURED_SIZES; the 24-tet split and the tets' subdivision,
# 5 and 8 times the cells, at half of it), each written by the CPU once and
# by the GPU twice, cmp'd (.vtu, .ply).
U_SIZES=${GPU_CHECK_UNSTRUCTURED_SIZES:-32 96}
unstructured() {  # N: the comparisons on a sphere N^3
  local n=$1 half=$(($1 / 2)) v=$WORK/usphere$1.vti h=$WORK/usphere_half$1.vti iso
  iso=$(awk -v n="$n" 'BEGIN { printf "%.3f", n / 2 - 1 + 0.001 }')
  step "generate sphere ${n}^3 and ${half}^3 (unstructured)" 60 sh -c "'$KEYMESH' generate sphere --size $n -o '$v' -q \
    && '$KEYMESH' generate sphere --size $half -o '$h' -q"
  [ $STEP_RC = 0 ] || return
  compare_command "tetrahedralize --scheme 5, sphere ${n}^3" vtu tetrahedralize "$v" --scheme 5
  local tets=$CMP_BASE.cpu.vtu
  compare_command "tetrahedralize --scheme 24, sphere ${half}^3" vtu tetrahedralize "$h" --scheme 24
  compare_command "tetrahedralize --scheme 5, sphere ${half}^3" vtu tetrahedralize "$h" --scheme 5
  local half_tets=$CMP_BASE.cpu.vtu
  if [ -f "$tets" ]; then
    compare_command "contour (marching tetrahedra), 5 tets of sphere ${n}^3, 2 isovalues, averaged normals" ply \
      contour "$tets" --iso "$iso" --iso 10.5 --normals average
  fi
  # One level (8 times the tets; keymesh_cuda_tests runs two): at 48^3, 4.2 M tets written thrice.
  [ -f "$half_tets" ] && compare_command "subdivide tets 1->8, 5 tets of sphere ${half}^3" vtu \
    subdivide "$half_tets" --levels 1
  local surface=$WORK/surface$n.cpu.ply
  step "contour sphere ${n}^3 (the surface to subdivide)" 60 "$KEYMESH" contour "$v" -o "$surface" -q $MEM \
    --iso "$iso" --normals average
  if [ $STEP_RC = 0 ]; then
    compare_command "subdivide triangles linear, sphere ${n}^3 contour, 2 levels" ply subdivide "$surface" --levels 2
    compare_command "subdivide triangles bezier, sphere ${n}^3 contour, 2 levels" ply subdivide "$surface" --levels 2 \
      --scheme bezier
  fi
  rm -f "$v" "$h" "$WORK"/*.cpu.vtu "$WORK"/*.cpu.ply
}
if [ -n "$KEYMESH" ]; then
  for n in $U_SIZES; do unstructured "$n"; done
else
  skip "keymesh tetrahedralize, contour (tets), subdivide: cuda against cpu" "the keymesh command does not run here"
fi

# ---- label surface nets: CPU against GPU, byte for byte ------------------------
# uint8 noise folded to 6 labels (three or more meet in most cells: the fold
# guard shortens many moves): the network smoothed as by default (16
# iterations, the fold guard) at 48^3 and 96^3 (4 M triangles), and 40 strong
# iterations at 48^3, each written by the CPU once and by the GPU twice,
# cmp'd (.vtp).
SIX_LABELS=$(for i in $(seq 0 255); do printf '\\%03o' $((i % 6)); done)
if [ -n "$KEYMESH" ]; then
  for n in 48 96; do
    head -c $((n * n * n)) /dev/urandom | tr '\000-\377' "$SIX_LABELS" >"$WORK/labels$n.raw"
    compare_command "labels, 6 labels of noise ${n}^3, --smooth 16" vtp labels "$WORK/labels$n.raw" \
      --dims $n $n $n --type uint8 --smooth 16
    [ $n = 48 ] && compare_command "labels, 6 labels of noise 48^3, --smooth 40 --relaxation 1" vtp labels \
      "$WORK/labels$n.raw" --dims $n $n $n --type uint8 --smooth 40 --relaxation 1
    rm -f "$WORK/labels$n.raw" "$WORK"/*.cpu.vtp
  done
else
  skip "keymesh labels: cuda against cpu" "the keymesh command does not run here"
fi

# ---- compute-sanitizer ---------------------------------------------------------
SANITIZER=$(command -v compute-sanitizer || echo /usr/local/cuda/bin/compute-sanitizer)
if [ ! -x "$SANITIZER" ]; then
  skip "compute-sanitizer memcheck" "compute-sanitizer not found"
elif [ -n "$KEYMESH" ]; then
  step "generate sphere 64^3 (for memcheck)" 30 "$KEYMESH" generate sphere --size 64 -o "$WORK/s64.vti" -q
  gpu_step "compute-sanitizer memcheck: contour 64^3, 3 isovalues, averaged normals" 90 \
    "$SANITIZER" --tool memcheck --error-exitcode 3 --leak-check full "$KEYMESH" contour "$WORK/s64.vti" \
    -o "$WORK/s64.ply" -q --backend cuda --iso 10.25 --iso 20.001 --iso 31 --normals average
  step "generate sphere 16^3 (for memcheck)" 30 "$KEYMESH" generate sphere --size 16 -o "$WORK/s16.vti" -q
  gpu_step "compute-sanitizer memcheck: tetrahedralize --scheme 24, 16^3" 60 \
    "$SANITIZER" --tool memcheck --error-exitcode 3 --leak-check full "$KEYMESH" tetrahedralize "$WORK/s16.vti" \
    -o "$WORK/t24.vtu" -q --backend cuda --scheme 24
  gpu_step "compute-sanitizer memcheck: tetrahedralize --scheme 5, then subdivide tets, 16^3" 60 sh -c \
    "'$SANITIZER' --tool memcheck --error-exitcode 3 --leak-check full '$KEYMESH' tetrahedralize '$WORK/s16.vti' \
    -o '$WORK/t5.vtu' -q --backend cuda --scheme 5 && '$SANITIZER' --tool memcheck --error-exitcode 3 \
    --leak-check full '$KEYMESH' subdivide '$WORK/t5.vtu' -o '$WORK/t5s.vtu' -q --backend cuda"
  gpu_step "compute-sanitizer memcheck: contour tets, then subdivide bezier, 16^3" 60 sh -c \
    "'$SANITIZER' --tool memcheck --error-exitcode 3 --leak-check full '$KEYMESH' contour '$WORK/t5.vtu' \
    -o '$WORK/t5.ply' -q --backend cuda --iso 5.5 --iso 7.001 --normals average && '$SANITIZER' --tool memcheck \
    --error-exitcode 3 --leak-check full '$KEYMESH' subdivide '$WORK/t5.ply' -o '$WORK/t5s.ply' -q \
    --backend cuda --scheme bezier --levels 2"
elif [ -n "$TIMING" ]; then
  gpu_step "compute-sanitizer memcheck: timing 48^3" 90 "$SANITIZER" --tool memcheck --error-exitcode 3 \
    "$TIMING" sphere 48 --repeat 1 --warmup 0
fi

# ---- past 2^32 triangles, in its own process ------------------------------------
if [ -n "$TIMING" ]; then
  gpu_step "checkerboard 1040^3 uint8 (4,486,489,276 triangles): refused or right" 90 "$TIMING" checkerboard 1040
  expect_device "checkerboard"
  cat "$STEP_OUT" >"$OUT/checkerboard.json"
else
  skip "checkerboard 1040^3" "the timing program does not run here"
fi

# ---- timing ----------------------------------------------------------------------
: >"$OUT/timing.jsonl"
if [ -n "$TIMING" ]; then
  gpu_step "timing sphere 512^3 (CUDA events, median of 7, CPU compared)" 60 "$TIMING" sphere 512 --warmup 2 --repeat 7
  expect_device "timing 512^3"
  cat "$STEP_OUT" >>"$OUT/timing.jsonl"
  gpu_step "timing sphere 1024^3 (CUDA events, median of 5, CPU compared)" 90 "$TIMING" sphere 1024 --warmup 1 --repeat 5
  cat "$STEP_OUT" >>"$OUT/timing.jsonl"
else
  skip "timing" "the timing program does not run here"
fi

# ---- Python: CUDA tensors in and out (optional) -----------------------------------
# The GPU check's programs have no Python module; where one is importable
# (a build's python folder in GPU_CHECK_PYTHONPATH, built for the machine's
# python3), tests/python/test_dlpack.py runs its CuPy / PyTorch CUDA round
# trips (they skip, saying why, where CuPy or PyTorch is missing).
PY=${GPU_CHECK_PYTHON:-python3}
if [ -z "${GPU_CHECK_PYTHONPATH:-}" ]; then
  skip "Python: CUDA tensors in and out (test_dlpack.py)" "GPU_CHECK_PYTHONPATH not set (no keymesh Python module)"
elif ! PYTHONPATH=$GPU_CHECK_PYTHONPATH "$PY" -c "import keymesh, pytest" >>"$LOG" 2>&1; then
  skip "Python: CUDA tensors in and out (test_dlpack.py)" "keymesh or pytest does not import with $PY"
else
  gpu_step "Python: CUDA tensors in and out (test_dlpack.py)" 120 env PYTHONPATH="$GPU_CHECK_PYTHONPATH" \
    "$PY" -m pytest -q -p no:cacheprovider -rs tests/python/test_dlpack.py
fi

# ---- summary ---------------------------------------------------------------------
ELAPSED=$(($(date +%s) - START))
{
  echo "{"
  echo "  \"date\": $(json_str "$(date -u +%FT%TZ)"), \"commit\": $(json_str "$(git rev-parse HEAD 2>/dev/null)"),"
  echo "  \"gpu\": $(json_str "$GPU"), \"driver\": $(json_str "$DRIVER"), \"glibc\": $(json_str "$GLIBC"),"
  echo "  \"programs\": $(json_str "$BIN"), \"programs_start\": $([ $PROGRAMS_RUN = 1 ] && echo true || echo false),"
  echo "  \"seconds\": $ELAPSED, \"failed\": $FAILED,"
  echo "  \"timing\": [$(paste -sd, "$OUT/timing.jsonl")],"
  echo "  \"steps\": ["
  for i in "${!STEPS[@]}"; do
    [ "$i" -gt 0 ] && echo ","
    printf '    %s' "${STEPS[$i]}"
  done
  echo ""
  echo "  ]"
  echo "}"
} >"$OUT/summary.json"
say ""
say "GPU check: $FAILED failed, ${ELAPSED}s; $OUT/summary.json, $OUT/gpu_check.log"
grep -hE '"gpu_ms_median"' "$OUT/timing.jsonl" 2>/dev/null | sed -E 's/.*"size": ([0-9]+).*"triangles": ([0-9]+).*"gpu_ms_median": ([0-9.e+-]+).*"gpu_ms_min": ([0-9.e+-]+).*/  sphere \1^3: \2 triangles, median \3 ms, min \4 ms (CUDA events)/' | tee -a "$LOG"
grep -hE '"device_input_ms_median"' "$OUT/timing.jsonl" 2>/dev/null | sed -E 's/.*"size": ([0-9]+).*"device_input_ms_median": ([0-9.e+-]+).*"device_input_ms_min": ([0-9.e+-]+).*"device_input_identical": ([a-z]+).*/  sphere \1^3, device-resident input: median \2 ms, min \3 ms, same mesh: \4/' | tee -a "$LOG"
[ $FAILED = 0 ]
