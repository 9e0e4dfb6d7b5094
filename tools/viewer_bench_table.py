#!/usr/bin/python3
"""Turns the viewer benchmark's output into the "Viewer" section of
docs/bench/results.md (scripts/bench.sh runs it).

Usage: /usr/bin/python3 tools/viewer_bench_table.py viewer.txt

viewer.txt holds, for each terrain side, a line "-- SIDE" followed by what
`terracut-viewer SCENARIO --benchmark-frames N --resolution SIDE` printed:
the frame rate, the frame's phases (upload, terrain, scene, panel) and the
haptic loop's period. Every figure of the table is read from those lines.
"""

import re
import sys

FRAME = re.compile(r"(\d+) frames in ([\d.]+) s: ([\d.]+) frames/s \(([\d.]+) ms/frame\).*?"
                   r"([\d.]+) samples/frame")
PHASES = re.compile(r"upload ([\d.]+) ms, terrain ([\d.]+) ms \((\d+) triangles\), scene "
                    r"([-\d.]+) ms .*?panel ([-\d.]+) ms")
LOOP = re.compile(r"period p50 ([\d.]+) us, p99 ([\d.]+) us, max ([\d.]+) us")
CONTEXT = re.compile(r"pixels, panel \w+, (.*)$")


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    rows, context = [], ""
    side = None
    fig = {}
    with open(sys.argv[1]) as f:
        for line in f:
            if line.startswith("-- "):
                if side is not None:
                    rows.append((side, fig))
                side, fig = line.split()[1], {}
                continue
            if m := CONTEXT.search(line):
                context = m.group(1).strip()
            if m := FRAME.search(line):
                fig["fps"], fig["ms"], fig["samples"] = m.group(3), m.group(4), m.group(5)
            if m := PHASES.search(line):
                fig["upload"], fig["terrain"], fig["triangles"] = m.group(1), m.group(2), m.group(3)
                # The panel is a difference of two timed frames: on a busy
                # machine it can come out below zero.
                fig["panel"] = m.group(5) if float(m.group(5)) >= 0 else "< 0 (noise)"
            if (m := LOOP.search(line)) and "loop" not in fig:
                fig["loop"] = f"{float(m.group(1)):.0f} / {float(m.group(2)):.0f} / {float(m.group(3)):.0f}"
    if side is not None:
        rows.append((side, fig))
    print()
    print("## Viewer (`terracut-viewer --benchmark-frames`)")
    print()
    if not rows:
        print("terracut-viewer was not built (no OpenGL, GLFW or ImGui), or no EGL context: not measured.")
        return
    print("`scenarios/paper_experiment1.yaml` at each side, 1280 x 800 pixels with the panel, the")
    print("blade ploughing the terrain layer by layer while the haptic loop runs at 1 kHz; the")
    print(f"phases are medians of frames timed phase by phase (each ended by glFinish). {context}.")
    print()
    print("| terrain | frames/s | ms/frame | upload ms | terrain ms | terrain triangles | panel ms "
          "| samples uploaded/frame | loop period p50 / p99 / max us |")
    print("|---|---|---|---|---|---|---|---|---|")
    for side, f in rows:
        if "fps" not in f:
            print(f"| {side}² | not measured (the viewer failed; see viewer.txt) | | | | | | | |")
            continue
        print(f"| {side}² | {f['fps']} | {f['ms']} | {f.get('upload', '')} | {f.get('terrain', '')} | "
              f"{int(f.get('triangles', 0)):,} | {f.get('panel', '')} | {float(f['samples']):,.0f} | "
              f"{f.get('loop', '')} |")


if __name__ == "__main__":
    main()
