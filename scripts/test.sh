#!/usr/bin/env bash
# The README's test command: installs dependencies, builds everything
# (Release) and runs every test with CTest.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh"
build=${TERRACUT_BUILD_DIR:-$root/build}
ctest --test-dir "$build" --output-on-failure -j"${TERRACUT_JOBS:-$(nproc)}" --timeout 600
# Every fuzz target for a bounded time (all at once, 30 s of wall time each;
# docs/reliability.md) when clang is here; the corpus replays ran in CTest.
if command -v clang >/dev/null && command -v clang++ >/dev/null; then
  TERRACUT_FUZZ_JOBS=${TERRACUT_FUZZ_JOBS:-5} "$root/scripts/fuzz.sh" "${TERRACUT_FUZZ_SECONDS:-30}"
else
  echo "test.sh: clang not found: the libFuzzer runs are skipped (the corpus replays ran in CTest)"
fi
