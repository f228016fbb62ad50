#!/usr/bin/env bash
# `make fuzz-run` (and sanitize-quick's short fuzzing): every libFuzzer target
# of build-fuzz over a copy of its seed corpus, JOBS targets at a time (each
# is one process on one core: two at once halve the wall time on CI's two
# cores, and each run is the same run, bounded by -runs or -max_total_time).
# Reports in the targets' order: the last line of each log, or its last 40
# lines and the crash folder on a failure; exits 1 when any target failed.
#
# Environment (set by the Makefile): FUZZ_SECONDS, FUZZ_FLAGS,
# FUZZ_FORKING_FLAGS, FORKING_FUZZ_TARGETS, JOBS.
set -u
jobs=${JOBS:-1}

# shellcheck disable=SC2317 # run_one is called by xargs through bash -c
run_one() {  # target -> build-fuzz/<target>.log and .status
  local t=$1 more=""
  mkdir -p "build-fuzz/corpus/$t" "build-fuzz/crashes/$t"
  cp -n "tests/fuzz/corpus/$t"/* "build-fuzz/corpus/$t/" 2>/dev/null
  case " ${FORKING_FUZZ_TARGETS:-} " in *" $t "*) more=${FUZZ_FORKING_FLAGS:-};; esac
  # shellcheck disable=SC2086 # the flags are words
  KEYMESH_HUGE_PAGES=0 "build-fuzz/fuzz_$t" "build-fuzz/corpus/$t" -max_total_time="$FUZZ_SECONDS" $FUZZ_FLAGS $more \
    -artifact_prefix="build-fuzz/crashes/$t/" >"build-fuzz/$t.log" 2>&1
  echo $? >"build-fuzz/$t.status"
}
export -f run_one

targets=()
for src in tests/fuzz/*_fuzz.cpp; do targets+=("$(basename "$src" _fuzz.cpp)"); done
rm -f build-fuzz/*.status
echo "make fuzz: ${#targets[@]} targets for $FUZZ_SECONDS s at most each, $jobs at a time"
# shellcheck disable=SC2016 # $1 is expanded by the inner bash
printf '%s\n' "${targets[@]}" | xargs -P "$jobs" -I{} bash -c 'run_one "$1"' _ {}

status=0
for t in "${targets[@]}"; do
  echo "make fuzz: $t"
  if [ "$(cat "build-fuzz/$t.status" 2>/dev/null)" = 0 ]; then
    tail -1 "build-fuzz/$t.log"
  else
    status=1
    tail -40 "build-fuzz/$t.log"
    echo "make fuzz: $t FAILED (build-fuzz/$t.log, build-fuzz/crashes/$t/)"
  fi
done
exit $status
