#!/usr/bin/env bash
# The README's test command: installs dependencies, builds everything
# (Release: the programs, the viewer, the Python module, the benchmarks) and
# runs with CTest the suites that need this build (the viewer's renders, the
# install test, the ThreadSanitizer build of the threaded tests, the Python
# tests); then every C++ suite and the Python tests again under
# AddressSanitizer and UndefinedBehaviorSanitizer, and every libFuzzer target
# for 30 s (scripts/sanitize.sh, its own build). Each C++ test is compiled
# and run once, in the sanitizer build: compiling the C++ suites twice was
# about a third of the run (docs/reliability.md, "CI time").
#
#   TERRACUT_SANITIZE=0  no sanitizer build: every suite runs in the Release build
#   TERRACUT_FULL_SUITE=1  every suite in the Release build as well
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install-deps.sh"
suites="viewer;install;tsan;python"
if [[ ${TERRACUT_SANITIZE:-1} == 0 || ${TERRACUT_FULL_SUITE:-0} != 0 ]]; then
  suites="core;io;haptics;net;bullet;session;apps;viewer;install;fuzz;soak;tsan;python"
fi
"$root/scripts/build.sh" -DTERRACUT_TEST_SUITES="$suites"
build=${TERRACUT_BUILD_DIR:-$root/build}
ctest --test-dir "$build" --output-on-failure -j"${TERRACUT_JOBS:-$(nproc)}" --timeout 600
if [[ ${TERRACUT_SANITIZE:-1} != 0 ]]; then
  "$root/scripts/sanitize.sh"
fi
