#!/usr/bin/env bash
# The README's test command: installs dependencies, builds everything
# (Release) and runs every test with CTest.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh"
build=${TERRACUT_BUILD_DIR:-$root/build}
ctest --test-dir "$build" --output-on-failure -j"${TERRACUT_JOBS:-$(nproc)}" --timeout 600
