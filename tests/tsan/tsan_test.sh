#!/usr/bin/env bash
# Builds every test that runs threads with ThreadSanitizer and runs them (a
# build of its own in SCRATCH, configured with TERRACUT_TSAN: only the
# libraries those tests need, and the tests of tests/tsan/CMakeLists.txt):
# the snapshot exchange, the haptic loop, the pacer, the UDP device and
# bridge, PNG reads from several threads, the viewer's loop driver with a
# drawing thread, and a short soak (a hostile sender thread against the
# loop). Any data race fails the test. The library at -O1 -g1, the test
# programs at -O0 (TERRACUT_PROGRAM_CXX_FLAGS: their code is set-up and
# assertions).
set -euo pipefail
source=$1 scratch=$2
jobs=${TERRACUT_JOBS:-2}
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# ccache caches a file built with a precompiled header only when told to.
export CCACHE_SLOPPINESS=pch_defines,time_macros
CCACHE_BASEDIR=$source cmake -S "$source" -B "$scratch" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" -DTERRACUT_PROGRAM_CXX_FLAGS=-O0 "${launcher[@]}" \
  -DCMAKE_CXX_FLAGS="-fsanitize=thread -Wno-tsan" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=thread" \
  -DTERRACUT_TSAN=ON -DTERRACUT_BUILD_TESTS=OFF -DTERRACUT_BUILD_APPS=OFF -DTERRACUT_BUILD_BENCH=OFF \
  -DTERRACUT_BUILD_PYTHON=OFF >/dev/null
CCACHE_BASEDIR=$source cmake --build "$scratch" -j"$jobs" --target tsan_all >/dev/null
export TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1"
bin=$scratch/tests/tsan
cd "$source"
for t in snapshot loop pacer udp image loop_driver; do
  echo "== tsan_$t"
  "$bin/tsan_$t" --gtest_brief=1
done
echo "== tsan_soak"
"$bin/tsan_soak" --duration 3
