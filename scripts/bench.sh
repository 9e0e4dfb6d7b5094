#!/usr/bin/env bash
# Runs the benchmark suite and writes docs/bench/: results.md (the table),
# scaling.png (time per step against terrain side, log-log), the raw Google
# Benchmark JSON (step.json, io.json) and machine.json.
#
#   scripts/bench.sh                 # the whole suite, about 5 minutes on 2 cores
#   BENCH_FILTER='headline' scripts/bench.sh   # only matching step cases
#
# Environment: BUILD_DIR (default build-bench), JOBS (build jobs, default 2),
# OUT_DIR (default docs/bench), BENCH_FILTER (a Google Benchmark regex for the
# step cases). The build is Release with the project's portable flags; pass
# CMAKE_ARGS (e.g. -DCMAKE_CXX_FLAGS=-march=native) to change that.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
build=${BUILD_DIR:-$root/build-bench}
out=${OUT_DIR:-$root/docs/bench}
jobs=${JOBS:-2}
python=/usr/bin/python3   # the one with matplotlib (another python3 may come first on PATH)

# shellcheck disable=SC2086
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DTERRACUT_BUILD_BENCH=ON ${CMAKE_ARGS:-} >/dev/null
cmake --build "$build" -j"$jobs" --target terracut_bench terracut_bench_io terracut_bench_soil
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
