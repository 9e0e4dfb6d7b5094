#!/usr/bin/env bash
# The README's test command: installs dependencies, builds everything
# (Release) and runs every test with CTest; then the same suite under
# AddressSanitizer and UndefinedBehaviorSanitizer and every libFuzzer target
# for 30 s (scripts/sanitize.sh, its own build). TERRACUT_SANITIZE=0 stops
# after the Release suite.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh"
build=${TERRACUT_BUILD_DIR:-$root/build}
ctest --test-dir "$build" --output-on-failure -j"${TERRACUT_JOBS:-$(nproc)}" --timeout 600
if [[ ${TERRACUT_SANITIZE:-1} != 0 ]]; then
  "$root/scripts/sanitize.sh"
fi
