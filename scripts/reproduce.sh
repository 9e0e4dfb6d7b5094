#!/usr/bin/env bash
# The README's main command: installs dependencies, builds, and reproduces the
# paper's two experiments into out/reproduce (or the folder given).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$root/out/reproduce}
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh"
build=${TERRACUT_BUILD_DIR:-$root/build}
"$build/apps/terracut/terracut" reproduce --out "$out"
echo "Figures and report: $out/report.md"
