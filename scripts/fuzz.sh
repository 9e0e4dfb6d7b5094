#!/usr/bin/env bash
# Builds the libFuzzer targets of tests/fuzz/ with clang (build-fuzz/, or
# $TERRACUT_FUZZ_BUILD_DIR; the library sources they need instrumented with
# -fsanitize=fuzzer-no-link,address,undefined, nothing else built) and runs
# each for SECONDS (default 3600), TERRACUT_FUZZ_JOBS (default: the number
# of processors) at a time, from the
# repository root. Each run starts from the checked-in seeds
# (tests/fuzz/corpus/<target>/) and grows its own corpus in
# build-fuzz/corpus/<target>/; a crash, leak, hang (-timeout, 10 s) or
# sanitizer report is written to build-fuzz/artifacts/<target>/ and fails the
# script. The executions of each target are in build-fuzz/logs/<target>.log.
#
#   scripts/fuzz.sh            # an hour per target
#   scripts/fuzz.sh 30         # the bounded run of scripts/sanitize.sh
#   scripts/fuzz.sh 60 png     # only the named targets
#   scripts/fuzz.sh 0          # only the build
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
seconds=${1:-3600}
shift || true
targets=("$@")
[[ ${#targets[@]} -gt 0 ]] || targets=(scenario png npy bridge differential link secure)
build=${TERRACUT_FUZZ_BUILD_DIR:-$root/build-fuzz}
jobs=${TERRACUT_JOBS:-$(nproc)}            # for the build
fuzz_jobs=${TERRACUT_FUZZ_JOBS:-$(nproc)}  # targets run at once
cc=${TERRACUT_FUZZ_CC:-clang}
cxx=${TERRACUT_FUZZ_CXX:-clang++}
# -O1 with line tables only (libFuzzer's documentation builds its targets at
# -O1): reports keep file:line, assertions stay on (Release's NDEBUG is gone),
# and the build takes about 10 % less CPU than -O3 -g.
flags="-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer -gline-tables-only"
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
CCACHE_BASEDIR=$root cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Fuzz -DCMAKE_CXX_FLAGS_FUZZ="-O1" \
  -DCMAKE_C_FLAGS_FUZZ="-O1" -DCMAKE_C_COMPILER="$cc" \
  -DCMAKE_CXX_COMPILER="$cxx" "${launcher[@]}" -DTERRACUT_FUZZ=ON -DTERRACUT_BUILD_TESTS=OFF \
  -DTERRACUT_BUILD_APPS=OFF -DTERRACUT_BUILD_BENCH=OFF -DTERRACUT_BUILD_PYTHON=OFF -DCMAKE_CXX_FLAGS="$flags" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" >/dev/null
CCACHE_BASEDIR=$root cmake --build "$build" -j"$jobs" --target "${targets[@]/#/fuzz_}"
[[ $seconds == 0 ]] && exit 0

export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:allocator_may_return_null=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
run_one() {
  local t=$1
  mkdir -p "$build/corpus/$t" "$build/artifacts/$t" "$build/logs"
  # -rss_limit_mb: a reader must refuse what would take more (the issue's 4 GB PNG).
  (cd "$root" && "$build/tests/fuzz/fuzz_$t" "$build/corpus/$t" "$root/tests/fuzz/corpus/$t" \
    -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1 \
    -artifact_prefix="$build/artifacts/$t/" >"$build/logs/$t.log" 2>&1)
}
report() {
  local t=$1 result=$2 runs
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$build/logs/$t.log" | grep -o '[0-9]*$' || echo "?")
  echo "fuzz_$t: $result, $runs executions in ${seconds} s ($(ls "$build/corpus/$t" | wc -l) corpus files)"
  if [[ $result == FAILED ]]; then
    tail -n 40 "$build/logs/$t.log"
    echo "artifacts: $build/artifacts/$t/ (copy each into tests/fuzz/corpus/$t/ once fixed)"
  fi
}
# In batches of $fuzz_jobs targets at once.
status=0
for ((i = 0; i < ${#targets[@]}; i += fuzz_jobs)); do
  batch=("${targets[@]:i:fuzz_jobs}")
  pids=()
  for t in "${batch[@]}"; do
    run_one "$t" &
    pids+=($!)
  done
  for k in "${!batch[@]}"; do
    if wait "${pids[$k]}"; then report "${batch[$k]}" ok; else report "${batch[$k]}" FAILED; status=1; fi
  done
done
exit $status
