#!/usr/bin/python3
"""Pushes at the default work cap against the same pushes with it lifted.

Usage: PYTHONPATH=build/python /usr/bin/python3 tools/soil_convergence_sweep.py
           [--travel METRES] [--blades 0.3,0.5,...] [--cells 0.005,0.01]
           [--speeds 0.25,0.5,0.75,1] [--yaws 0,10,...] [--cap VISITS]
           [--settle patches|passes|fans]

For every blade width, cell size and speed, the push of tools/soil_push.py
(a 4 cm cut into a 20 cm layer of dry sand, pushed --travel metres, 0.8 by
default, then 0.2 s still) is run twice: at the work cap (--cap, by default
the library's, soil.max_pair_checks_per_step) and with the cap lifted (1e9: the converged
answer). Prints a Markdown table: the capped soil ahead of the blade against
the converged (per cent), the capped peak less the converged (mm), the steps
the cap stopped (the push's and the 0.2 s hold's) over the push's steps, and
the converged run's work; a miss of the bounds
(5 % of the soil ahead, one cell's repose rise at the peak: tan 34 x the
cell) is in bold, and the last line counts them. Defaults: the blades 0.3,
0.5, 0.75, 1, 1.5 and 2 m, cells of 5 and 10 mm, 0.25 to 1 m/s (48 pushes,
twice each: 14 s on one core of the build machine), the blade square to the
grid (yaw 0). --yaws turns it (degrees about the vertical; soil_push.py's
push_at_yaw: a square grid, the soil ahead measured across the turned
edge); a yaw column is added to the table. --settle chooses how the
displaced pile settles (the scenario's soil.settle; by default the
library's).

Exit codes: 0 done (misses or not); 2 bad arguments; 3 numpy or terracut
missing; 4 a converged push left no soil ahead (a blade above the layer).
"""
import math
import sys

from plot_common import import_terracut, make_fail
from soil_push import push

fail = make_fail("soil_convergence_sweep.py")
try:
    import numpy as np
except ImportError:
    fail("missing Python module 'numpy' (Debian: apt-get install python3-numpy)", 3)
terracut = import_terracut(fail)


def number(flag, text, lo, hi):
    try:
        value = float(text)
    except ValueError:
        fail(f"{flag} {text!r}: not a number")
    if not lo <= value <= hi:
        fail(f"{flag}: {value:g} is outside {lo:g} to {hi:g}")
    return value


def numbers(flag, text, lo, hi):
    return [number(flag, v, lo, hi) for v in text.split(",")]


def main(argv):
    travel, cap, yaws, settle = 0.8, None, [0.0], None
    blades, cells, speeds = [0.3, 0.5, 0.75, 1.0, 1.5, 2.0], [0.005, 0.01], [0.25, 0.5, 0.75, 1.0]
    args = argv[1:]
    while args:
        a = args.pop(0)
        if a in ("-h", "--help"):
            print(__doc__)
            return 0
        if a not in ("--travel", "--blades", "--cells", "--speeds", "--yaws", "--cap", "--settle"):
            fail(f"unknown argument {a!r} (see --help)")
        if not args:
            fail(f"{a} needs a value (see --help)")
        value = args.pop(0)
        if a == "--travel":
            travel = number(a, value, 0.1, 3.0)
        elif a == "--blades":
            blades = numbers(a, value, 0.05, 4.0)
        elif a == "--cells":
            cells = numbers(a, value, 0.002, 0.05)
        elif a == "--speeds":
            speeds = numbers(a, value, 0.01, 2.0)
        elif a == "--yaws":
            yaws = numbers(a, value, -360.0, 360.0)
        elif a == "--settle":
            if value not in ("patches", "passes", "fans"):
                fail(f"--settle {value!r}: one of patches, passes, fans")
            settle = value
        else:
            cap = number(a, value, 1000, 1e9)
    slope = math.tan(math.radians(34.0))
    at = "the default cap" if cap is None else f"{int(cap)} visits a step"
    how = "" if settle is None else f"; settled by {settle}"
    print(f"Pushes of {travel:g} m, 0.2 s held; capped at {at} against the cap lifted{how}.\n")
    turned = yaws != [0.0]
    print("| blade | cells | " + ("yaw | " if turned else "") + " | ".join(f"{v:g} m/s" for v in speeds)
          + " | converged work (M visits), " + " / ".join(f"{v:g}" for v in speeds) + " m/s |")
    print("|---" * (3 + turned + len(speeds)) + "|")
    misses = worst_rel = worst_peak = 0.0
    for cell, width, yaw in [(c, w, y) for c in cells for w in blades for y in yaws]:
        row, works = [], []
        for speed in speeds:
            capped = push(terracut, np, width, cell, speed, cap, travel, yaw_deg=yaw, settle=settle)
            lifted = push(terracut, np, width, cell, speed, 1e9, travel, yaw_deg=yaw, settle=settle)
            if not lifted["ahead"] > 0.0:
                fail(f"the {width:g} m blade's converged push left no soil ahead of it "
                     f"({1000 * cell:g} mm cells, {speed:g} m/s): no ratio to give", 4)
            rel = capped["ahead"] / lifted["ahead"] - 1.0
            peak_mm = 1000.0 * (capped["peak"] - lifted["peak"])
            miss = abs(rel) > 0.05 or abs(peak_mm) > 1000.0 * slope * cell
            misses += miss
            worst_rel, worst_peak = max(worst_rel, abs(rel)), max(worst_peak, abs(peak_mm))
            steps = int(round(travel / speed * 1000.0))
            text = f"{100 * rel:+.1f} %, {peak_mm:+.1f} mm, {capped['capped']}/{steps}"
            row.append(f"**{text}**" if miss else text)
            works.append(f"{lifted['work'] / 1e6:.1f}")
        print(f"| {width:g} m | {1000 * cell:g} mm | " + (f"{yaw:g} | " if turned else "") + " | ".join(row)
              + " | " + " / ".join(works) + " |")
        sys.stdout.flush()
    print(f"\n{int(misses)} of {len(cells) * len(blades) * len(yaws) * len(speeds)} pushes miss a bound; "
          f"worst {100 * worst_rel:.2f} % of the soil ahead, {worst_peak:.1f} mm at the peak.")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
