#!/usr/bin/env bash
# The README's test command: installs dependencies, builds everything
# (Release: the programs, the viewer, the Python module, the benchmarks) and
# runs with CTest the suites that need this build (the viewer's renders, the
# install test, the ThreadSanitizer build of the threaded tests); then every
# C++ suite and the Python tests under AddressSanitizer and
# UndefinedBehaviorSanitizer, and every libFuzzer target for 30 s
# (scripts/sanitize.sh, its own build, built while the Release suites run).
# Each test is compiled and run once, in the sanitizer build: compiling the
# C++ suites twice was about a third of the run, and the Python tests ran
# in both builds (docs/reliability.md, "CI time").
#
#   TERRACUT_SANITIZE=0  no sanitizer build: every suite runs in the Release build
#   TERRACUT_FULL_SUITE=1  every suite in the Release build as well
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install-deps.sh"
suites="viewer;install;tsan"
if [[ ${TERRACUT_SANITIZE:-1} == 0 || ${TERRACUT_FULL_SUITE:-0} != 0 ]]; then
  suites="core;io;haptics;net;bullet;session;apps;viewer;install;fuzz;soak;tsan;python"
fi
"$root/scripts/build.sh" -DTERRACUT_TEST_SUITES="$suites"
build=${TERRACUT_BUILD_DIR:-$root/build}
release_tests() {
  ctest --test-dir "$build" --output-on-failure -j"${TERRACUT_JOBS:-$(nproc)}" --timeout 600
}
if [[ ${TERRACUT_SANITIZE:-1} == 0 ]]; then
  release_tests
  exit 0
fi
# The Release tree's suites run while the sanitizer and fuzz trees build:
# each leaves the processors idle part of the time (tests that wait on the
# clock, links, a build's last long file), and on CI's two cores the two
# together take less time than one after the other (docs/reliability.md,
# "CI time"). Their output is printed when both are done.
log=$build/release-tests.log
release_tests >"$log" 2>&1 &
release_pid=$!
build_status=0
TERRACUT_SANITIZE_STEP=build "$root/scripts/sanitize.sh" || build_status=$?
release_status=0
wait "$release_pid" || release_status=$?
echo "== the Release tree's suites ($log)"
cat "$log"
if [[ $release_status != 0 || $build_status != 0 ]]; then
  echo "test.sh: the Release tree's suites exited $release_status, the sanitizer builds $build_status" >&2
  exit 1
fi
TERRACUT_SANITIZE_STEP=test "$root/scripts/sanitize.sh"
