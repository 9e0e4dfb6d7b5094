#!/usr/bin/env bash
# Installs terracut from the build tree into a scratch prefix, then builds the
# example consumer against it twice: with find_package(terracut) and with
# add_subdirectory. Each consumer must run and print a contact length.
set -euo pipefail
build=$1 source=$2 scratch=$3
rm -rf "$scratch"
mkdir -p "$scratch"
cmake --install "$build" --prefix "$scratch/prefix" >/dev/null

cmake -S "$source/examples/consumer" -B "$scratch/find" -DCMAKE_PREFIX_PATH="$scratch/prefix" \
  -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$scratch/find" -j2 >/dev/null
"$scratch/find/consumer" "$source/data/mound.png" | tee "$scratch/find.txt"
grep -q "contact=" "$scratch/find.txt"

cmake -S "$source/examples/consumer" -B "$scratch/sub" -DTERRACUT_SOURCE_DIR="$source" \
  -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$scratch/sub" -j2 --target consumer >/dev/null
"$scratch/sub/consumer" "$source/data/mound.png" > "$scratch/sub.txt"
# Both builds compute the same thing.
diff "$scratch/find.txt" "$scratch/sub.txt"
# Some step is in contact with the mound.
grep -Eq "contact=0\.[0-9]*[1-9]" "$scratch/find.txt"
echo "install test passed"
