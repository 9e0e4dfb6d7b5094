#!/usr/bin/env bash
# Runs the benchmark suite and writes docs/bench/: results.md (the table),
# scaling.png (time per step against terrain side, log-log), the raw Google
# Benchmark JSON (step.json, io.json), machine.json, and the rigid bodies'
# (bodies.md) and the viewer's (viewer.txt) outputs.
#
#   scripts/bench.sh                 # the whole suite, about 8 minutes on 2 cores
#   BENCH_FILTER='headline' scripts/bench.sh   # only matching step cases
#
# Environment: BUILD_DIR (default build-bench), JOBS (build jobs, default 2),
# OUT_DIR (default docs/bench), BENCH_FILTER (a Google Benchmark regex for the
# step cases), BENCH_NO_VIEWER=1 (leave out the viewer's cases, about 4
# minutes). The build is Release with the project's portable flags; pass
# CMAKE_ARGS (e.g. -DCMAKE_CXX_FLAGS=-march=native) to change that.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
build=${BUILD_DIR:-$root/build-bench}
out=${OUT_DIR:-$root/docs/bench}
jobs=${JOBS:-2}
python=/usr/bin/python3   # the one with matplotlib (another python3 may come first on PATH)

# shellcheck disable=SC2086
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DTERRACUT_BUILD_BENCH=ON -DPYTHON_EXECUTABLE=$python ${CMAKE_ARGS:-} >/dev/null
cmake --build "$build" -j"$jobs" --target terracut_bench terracut_bench_io terracut_bench_soil
# The rigid bodies' and the viewer's cases need Bullet and OpenGL; without
# them those sections say so.
cmake --build "$build" -j"$jobs" --target terracut_bench_bodies 2>/dev/null || true
cmake --build "$build" -j"$jobs" --target terracut-viewer 2>/dev/null || true
mkdir -p "$out"

# The machine the figures belong to.
compiler_path=$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$build/CMakeCache.txt")
compiler=$("$compiler_path" --version | head -n 1)
flags="$(sed -n 's/^CMAKE_CXX_FLAGS:[A-Z]*=//p' "$build/CMakeCache.txt") $(sed -n 's/^CMAKE_CXX_FLAGS_RELEASE:[A-Z]*=//p' "$build/CMakeCache.txt")"
cpu=$(lscpu | sed -n 's/^Model name: *//p' | head -n 1)
cores=$(lscpu | sed -n 's/^CPU(s): *//p' | head -n 1)
threads=$(lscpu | sed -n 's/^Thread(s) per core: *//p' | head -n 1)
"$python" - "$out/machine.json" "$cpu" "$cores" "$threads" "$compiler" "$flags" "$(uname -sr)" <<'PY'
import json, sys, datetime
path, cpu, cores, threads, compiler, flags, kernel = sys.argv[1:]
json.dump({"cpu": cpu, "cores": int(cores), "threads_per_core": int(threads), "compiler": compiler,
           "flags": " ".join(flags.split()), "kernel": kernel,
           "date": datetime.datetime.now().astimezone().isoformat(timespec="seconds")},
          open(path, "w"), indent=1)
PY

echo "== step cases (contact + cut, scaling, brute force, memory)"
"$build/bench/terracut_bench" --benchmark_out="$out/step.json" --benchmark_out_format=json \
  ${BENCH_FILTER:+--benchmark_filter="$BENCH_FILTER"}
echo "== loading an 8192x8192 16-bit PNG"
"$build/bench/terracut_bench_io" --benchmark_out="$out/io.json" --benchmark_out_format=json

echo "== the soil phase (soil: flow)"
"$build/bench/terracut_bench_soil" "$out/soil.md"

"$python" "$root/tools/plot_bench.py" --step "$out/step.json" --io "$out/io.json" \
  --machine "$out/machine.json" --out "$out" --command "scripts/bench.sh"
# The soil table goes under the step tables.
{ echo; echo "## Soil flow (\`terracut_bench_soil\`)"; echo; cat "$out/soil.md"; } >> "$out/results.md"

echo "== rigid bodies (the rescue scenario, Bullet)"
if [ -x "$build/bench/terracut_bench_bodies" ]; then
  "$build/bench/terracut_bench_bodies" "$out/bodies.md"
else
  echo "terracut_bench_bodies was not built (no Bullet)." > "$out/bodies.md"
fi
{ echo; echo "## Rigid bodies (\`terracut_bench_bodies\`)"; echo
  echo "The Bullet world's step (\`TerrainWorld::step\`: terrain change, tool plate, one Bullet step)"
  echo "over every step of \`scenarios/rescue.yaml\` (10804 steps), median of three runs."
  echo; cat "$out/bodies.md"; } >> "$out/results.md"

echo "== the viewer on the software renderer (llvmpipe, headless EGL)"
viewer="$build/apps/viewer/terracut-viewer"
: > "$out/viewer.txt"
if [ -x "$viewer" ] && [ "${BENCH_NO_VIEWER:-0}" != 1 ]; then
  for side in 256 1024 4096 8192; do
    frames=40; [ "$side" = 8192 ] && frames=24
    echo "-- $side" >> "$out/viewer.txt"
    "$viewer" "$root/scenarios/paper_experiment1.yaml" --benchmark-frames "$frames" \
      --resolution "$side" >> "$out/viewer.txt" 2>&1 || echo "exit $?" >> "$out/viewer.txt"
  done
fi
"$python" "$root/tools/viewer_bench_table.py" "$out/viewer.txt" >> "$out/results.md"
