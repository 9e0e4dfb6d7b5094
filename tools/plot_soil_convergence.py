#!/usr/bin/python3
"""The pile a push leaves at the default work cap against the converged one.

Usage: PYTHONPATH=build/python /usr/bin/python3 tools/plot_soil_convergence.py
           [--travel METRES] [--out FILE.png] [--quiet]

Runs, with the terracut module, a 1 m blade cutting 4 cm into a 20 cm layer
of dry sand (repose 34 degrees) on 5 mm cells, pushed 0.8 m (--travel: 0.1 to
3 m) along +Z and then held still for 0.2 s, at 0.25 m/s and at 1 m/s, each twice: at the default
work cap (soil.max_pair_checks_per_step's default, what a 1 kHz step does) and
with the cap lifted (1e9: the converged answer). It plots the centre-line
profiles of the four piles, their sections across the push 10 cm ahead of
the edge (where they differ: the pile's ends), and prints, for each speed, the soil above the
layer ahead of the blade within its width and the pile's peak.
Default output: docs/images/soil_capped_vs_converged.png, or with --travel
docs/images/soil_capped_vs_converged_<travel>m.png.

Exit codes: 0 done; 2 bad arguments; 3 numpy, matplotlib or terracut missing.
"""
import os
import sys

import soil_push
from plot_common import import_plotting, import_terracut, make_fail, save_figure

fail = make_fail("plot_soil_convergence.py")
np, plt = import_plotting(fail)
terracut = import_terracut(fail)

CELL, WIDTH, TRAVEL = 0.005, 1.0, 0.8
COLS, ROWS = soil_push.grid_shape(WIDTH, CELL, TRAVEL)
LAYER, Z0 = soil_push.LAYER, soil_push.Z0
ACROSS_M = 0.1


def push(speed, cap):
    """(heights (rows, cols), soil ahead m^3, peak m) after the push and the hold."""
    p = soil_push.push(terracut, np, WIDTH, CELL, speed, cap, TRAVEL)
    return p["heights"], p["ahead"], p["peak"]


def main(argv):
    global TRAVEL, COLS, ROWS
    out, quiet, suffix = None, False, ""
    args = argv[1:]
    while args:
        a = args.pop(0)
        if a == "--out" and args:
            out = args.pop(0)
        elif a == "--travel" and args:
            value = args.pop(0)
            try:
                TRAVEL = float(value)
            except ValueError:
                fail(f"--travel {value!r} is not a number of metres")
            if not 0.1 <= TRAVEL <= 3.0:
                fail(f"--travel {value!r} is outside 0.1 to 3 m")
            COLS, ROWS = soil_push.grid_shape(WIDTH, CELL, TRAVEL)
            suffix = f"_{TRAVEL:g}m"
        elif a == "--quiet":
            quiet = True
        elif a in ("-h", "--help"):
            print(__doc__)
            return 0
        else:
            fail(f"unknown argument {a!r} (see --help)")
    if out is None:
        out = os.path.join("docs", "images", f"soil_capped_vs_converged{suffix}.png")
    fig, grid = plt.subplots(2, 2, figsize=(12, 8.0), sharey="row")
    axes, across = grid[0], grid[1]
    z = (np.arange(ROWS) + 0.5) * CELL - (Z0 + TRAVEL)
    x_blade = soil_push.push_x(WIDTH, CELL)
    x = (np.arange(COLS) + 0.5) * CELL - x_blade
    centre = int(x_blade / CELL)
    # The row ACROSS_M ahead of the edge: the pile's ends, where the capped
    # run differs (the centre line is the same in both).
    row = int((Z0 + TRAVEL + ACROSS_M) / CELL)
    for ax, ax_x, speed in zip(axes, across, (0.25, 1.0)):
        lines = []
        for cap, label, style in ((None, "default work cap (1 kHz)", "-"), (10**9, "cap lifted (converged)", "--")):
            h, ahead, peak = push(speed, cap)
            ax.plot(z, h[:, centre] - LAYER, style, lw=1.4, label=f"{label}: {ahead * 1e3:.2f} l ahead, peak {peak * 100:.1f} cm")
            ax_x.plot(x, h[row, :] - LAYER, style, lw=1.4, label=label)
            lines.append((ahead, peak))
        ax_x.axvline(-0.5 * WIDTH, color="gray", lw=0.8)
        ax_x.axvline(0.5 * WIDTH, color="gray", lw=0.8)
        ax_x.set_xlabel("across the push, from the blade's centre (m); grey: the blade's ends")
        ax_x.set_title(f"{speed:g} m/s: the section {100 * ACROSS_M:g} cm ahead of the edge", fontsize=10)
        ax_x.grid(alpha=0.3)
        ax_x.legend(fontsize=8, loc="upper right")
        rel = lines[0][0] / lines[1][0] - 1.0
        if not quiet:
            print(f"{speed:g} m/s: ahead {lines[0][0]:.6f} (capped) vs {lines[1][0]:.6f} m^3 (converged), "
                  f"{100 * rel:+.1f} %; peak {lines[0][1]:.4f} vs {lines[1][1]:.4f} m")
        ax.axvline(0.0, color="gray", lw=0.8)
        ax.set_xlim(-0.3, 0.5)
        ax.set_xlabel("ahead of the blade's edge (m)")
        ax.set_title(f"{speed:g} m/s: capped {100 * rel:+.1f} % of the converged soil ahead", fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
    axes[0].set_ylabel("height above the layer, centre line (m)")
    across[0].set_ylabel("height above the layer (m)")
    fig.suptitle(f"1 m blade, 4 cm cut, {TRAVEL:g} m push on 5 mm cells, then 0.2 s still: "
                 "the pile at the default work cap and with the cap lifted", fontsize=10)
    save_figure(fig, out, fail, quiet, "plot_soil_convergence.py")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
