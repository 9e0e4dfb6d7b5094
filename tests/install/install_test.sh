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

# Unoptimised: this build compiles the core and io layers from source again,
# and at -O0 that takes about half the CPU of -O3; without -ffast-math or
# -mfma (neither is used) GCC gives the same floating-point results at every
# level, which the diff below checks.
cmake -S "$source/examples/consumer" -B "$scratch/sub" -DTERRACUT_SOURCE_DIR="$source" \
  -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG=-O0 >/dev/null
cmake --build "$scratch/sub" -j2 --target consumer >/dev/null
"$scratch/sub/consumer" "$source/data/mound.png" > "$scratch/sub.txt"
# Both builds compute the same thing.
diff "$scratch/find.txt" "$scratch/sub.txt"
# Some step is in contact with the mound.
grep -Eq "contact=0\.[0-9]*[1-9]" "$scratch/find.txt"

# The Python module, when this build has it: installed where Debian's
# /usr/bin/python3 looks under that prefix, and importable from there.
if [ -f "$build/python/terracut/__init__.py" ]; then
  py=/usr/bin/python3
  site=$(find "$scratch/prefix/lib" -path '*-packages/terracut/__init__.py' | head -n1)
  [ -n "$site" ] || { echo "the Python package was not installed"; exit 1; }
  site=$(dirname "$(dirname "$site")")
  "$py" -c "import site, sys; sys.exit(0 if sys.argv[1] in site.getsitepackages([sys.argv[2]]) else 1)" \
    "$site" "$scratch/prefix" || { echo "$site is not on $py's path for prefix $scratch/prefix"; exit 1; }
  (cd "$scratch" && PYTHONPATH="$site" "$py" -c "
import sys, numpy as np, terracut
assert terracut.__file__.startswith(sys.argv[1]), terracut.__file__
sim = terracut.Simulation.from_heights(np.full((8, 8), 0.2), blade_length_m=2.0)
print('python contact=%.3f' % sim.step([0.5, 0.1, 0.5, 1, 0, 0, 0]).contact_length_m)
" "$site") | tee "$scratch/python.txt"
  grep -q "python contact=1.000" "$scratch/python.txt"
fi
echo "install test passed"
