#!/usr/bin/env bash
# Configures and builds terracut (Release) into build/ (or $TERRACUT_BUILD_DIR).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${TERRACUT_BUILD_DIR:-$root/build}
jobs=${TERRACUT_JOBS:-$(nproc)}
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DPYTHON_EXECUTABLE=/usr/bin/python3 "$@" >/dev/null
cmake --build "$build" -j"$jobs"
