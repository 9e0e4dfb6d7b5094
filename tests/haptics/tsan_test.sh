#!/usr/bin/env bash
# Builds the snapshot-exchange test with ThreadSanitizer and runs it: the
# exchange between the loop thread and a reader must be free of data races.
set -euo pipefail
source=$1 scratch=$2
mkdir -p "$scratch"
g++ -std=c++20 -O1 -g -fsanitize=thread -I"$source/include" \
  "$source/tests/haptics/snapshot_test.cpp" "$source/src/haptics/snapshot.cpp" \
  "$source/src/core/grid.cpp" "$source/src/core/math.cpp" "$source/src/core/format.cpp" \
  -lgtest -lgtest_main -pthread -o "$scratch/snapshot_test_tsan"
TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1" "$scratch/snapshot_test_tsan"
