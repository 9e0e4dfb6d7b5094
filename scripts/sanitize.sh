#!/usr/bin/env bash
# The whole test suite under AddressSanitizer and UndefinedBehaviorSanitizer
# (leaks included), in its own build: build-asan/ (or $TERRACUT_ASAN_BUILD_DIR).
# Run by .ci/run after the README's test command. Left out: the viewer and
# its tests (not built: the Mesa GL driver's own allocations would read as
# leaks), the install test (it builds a consumer without the sanitizer
# runtime) and the ThreadSanitizer test (its own build, run by the normal
# suite). The Python
# module's tests run with the runtimes preloaded (python/tests/CMakeLists.txt).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${TERRACUT_ASAN_BUILD_DIR:-$root/build-asan}
jobs=${TERRACUT_JOBS:-$(nproc)}
flags="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPYTHON_EXECUTABLE=/usr/bin/python3 \
  -DTERRACUT_BUILD_BENCH=OFF -DTERRACUT_BUILD_VIEWER=OFF -DCMAKE_CXX_FLAGS="$flags" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DCMAKE_MODULE_LINKER_FLAGS="-fsanitize=address,undefined" >/dev/null
cmake --build "$build" -j"$jobs"
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
ctest --test-dir "$build" --output-on-failure -j"$jobs" --timeout 600 -E "Viewer|install|tsan"
