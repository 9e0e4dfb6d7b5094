#!/bin/sh
# CI smoke test of the DEM reference scripts: every LIGGGHTS script and every
# post-processing step runs a few hundred steps on tiny beds.  Needs the
# `liggghts` executable (LIGGGHTS-PUBLIC 3.8) and python3 with numpy+scipy.
# Exits non-zero when LIGGGHTS or the post-processing fails.
set -e
cd "$(dirname "$0")"
PY=${PYTHON:-/usr/bin/python3}
exec "$PY" run.py smoke
