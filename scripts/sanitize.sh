#!/usr/bin/env bash
# The whole test suite under AddressSanitizer and UndefinedBehaviorSanitizer
# (leaks included), then every libFuzzer target for a bounded time, from one
# build: build-asan/ (or $TERRACUT_ASAN_BUILD_DIR). Run by scripts/test.sh
# in two steps: its builds while the Release suites run, then its tests
# (TERRACUT_SANITIZE=0 there skips it).
#
# With clang (installed by scripts/install-deps.sh): a clang build, and the
# fuzz programs in build-fuzz/ (scripts/fuzz.sh: only the library layers
# they link, also instrumented for libFuzzer's coverage, which would slow
# the suite's real-time tests about threefold if it shared this build);
# without clang a gcc build, and the fuzz runs are skipped (the corpus
# replays still run in CTest). The library at -O1 with line tables only:
# sanitizer reports keep file:line, and the build costs about half of -O2
# -g; the programs' own code at -O0 (TERRACUT_PROGRAM_CXX_FLAGS: the test
# programs, the tools, the soak program and the Python module are set-up,
# parsing, reports and assertions; a third to two fifths of -O1's compile
# CPU).
#
# Built and run: every C++ suite but three (TERRACUT_TEST_SUITES), and the
# Python tests with the runtime preloaded (python/tests/CMakeLists.txt). Left
# to the Release build of scripts/test.sh: the viewer and its tests (the Mesa
# GL driver's own allocations would read as leaks), the install test (it
# builds a consumer without the sanitizer runtime) and the ThreadSanitizer
# build of the threaded tests.
#
#   scripts/sanitize.sh          # build, CTest, 30 s per fuzz target
#   TERRACUT_FUZZ_SECONDS=0 scripts/sanitize.sh   # no fuzz build or runs
#   TERRACUT_SANITIZE_STEP=build scripts/sanitize.sh   # only the two builds
#   TERRACUT_SANITIZE_STEP=test scripts/sanitize.sh    # only CTest and the fuzz runs
# (scripts/test.sh builds while the Release tree's suites run, then tests.)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${TERRACUT_ASAN_BUILD_DIR:-$root/build-asan}
jobs=${TERRACUT_JOBS:-$(nproc)}
sanitizers=address,undefined
compiler=()
fuzz=OFF
if command -v clang >/dev/null && command -v clang++ >/dev/null; then
  compiler=(-DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++)
  fuzz=ON
  flags="-fsanitize=$sanitizers -gline-tables-only"
else
  echo "sanitize.sh: clang not found: a gcc build, and the libFuzzer runs are skipped"
  flags="-fsanitize=$sanitizers -g1"
fi
flags="$flags -fno-omit-frame-pointer -fno-sanitize-recover=undefined"
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# ccache caches a file built with a precompiled header only when told to.
export CCACHE_SLOPPINESS=pch_defines,time_macros
step=${TERRACUT_SANITIZE_STEP:-all}
case $step in all | build | test) ;; *) echo "sanitize.sh: TERRACUT_SANITIZE_STEP must be all, build or test, not '$step'" >&2; exit 2 ;; esac
seconds=${TERRACUT_FUZZ_SECONDS:-30}
if [[ $step != test ]]; then
  CCACHE_BASEDIR=$root cmake -S "$root" -B "$build" "${compiler[@]}" "${launcher[@]}" \
    -DCMAKE_BUILD_TYPE=Sanitize -DCMAKE_CXX_FLAGS_SANITIZE="-O1" -DCMAKE_C_FLAGS_SANITIZE="-O1" \
    -DPYTHON_EXECUTABLE=/usr/bin/python3 \
    -DTERRACUT_BUILD_BENCH=OFF -DTERRACUT_BUILD_VIEWER=OFF -DCMAKE_CXX_FLAGS="$flags" \
    -DTERRACUT_TEST_SUITES="core;io;haptics;net;bullet;session;validation;apps;fuzz;soak;python" -DTERRACUT_PROGRAM_CXX_FLAGS=-O0 \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=$sanitizers" \
    -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=$sanitizers" \
    -DCMAKE_MODULE_LINKER_FLAGS="-fsanitize=$sanitizers" >/dev/null
  CCACHE_BASEDIR=$root cmake --build "$build" -j"$jobs"
  # The fuzz programs' own build (fuzz.sh with 0 seconds builds and runs nothing).
  if [[ $fuzz == ON && $seconds != 0 ]]; then
    echo "== $(date -u +%H:%M:%S) sanitize.sh: the fuzz programs' build"
    "$root/scripts/fuzz.sh" 0
  fi
fi
[[ $step == build ]] && exit 0
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
ctest --test-dir "$build" --output-on-failure -j"$jobs" --timeout 600
# Every fuzz target for a bounded time (30 s of wall time, all seven at once;
# docs/reliability.md).
if [[ $fuzz == ON && $seconds != 0 ]]; then
  echo "== $(date -u +%H:%M:%S) sanitize.sh: the fuzz runs"
  TERRACUT_FUZZ_JOBS=${TERRACUT_FUZZ_JOBS:-7} "$root/scripts/fuzz.sh" "$seconds"
fi
