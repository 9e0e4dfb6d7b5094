#!/usr/bin/python3
"""A blade's top: the pile a 1 m blade pushes, with the blade 0.1 m tall and
with a wall as tall as any pile (the default, blade.height_m left out).

Usage: PYTHONPATH=build/python /usr/bin/python3 tools/plot_blade_top.py
           [--out FILE.png] [--quiet]

Runs, with the terracut module, a 1 m blade square to the grid cutting 5 cm
of a 0.2 m layer of dry sand (repose 34 degrees) on 1 cm cells and pushing it
1.5 m along +Z at 1 m/s, then holding 0.2 s; once with blade_height_m=0.1
(its top 5 cm above the layer) and once unbounded. It draws the section
along the push through the blade's middle at the end (heights, the edge and
the top), and prints the soil ahead of the blade, behind it and over the
top for each.
Default output: docs/images/soil_blade_top.png.

Exit codes: 0 done; 2 bad arguments; 3 numpy, matplotlib or terracut missing.
"""
import math
import os
import sys

from plot_common import import_plotting, import_terracut, make_fail, parse_out_args, save_figure

fail = make_fail("plot_blade_top.py")
np, plt = import_plotting(fail)
terracut = import_terracut(fail)

CELL, COLS, ROWS = 0.01, 150, 250
LAYER, DEPTH, BLADE, HEIGHT = 0.2, 0.05, 1.0, 0.1
Z0, TRAVEL, SPEED, HOLD_S = 0.3, 1.5, 1.0, 0.2
EDGE_Y = LAYER - DEPTH


def run(height_m):
    """(heights at the end, (ROWS, COLS); edge z at the end; metres over the top)."""
    sim = terracut.Simulation.from_heights(
        np.full((ROWS, COLS), LAYER, dtype=np.float32), size_m=(COLS * CELL, ROWS * CELL),
        blade_length_m=BLADE, soil_model="flow", soil={"repose_deg": 34.0}, blade_height_m=height_m)
    steps = int(round(TRAVEL / SPEED * 1000.0))
    over = 0.0
    z = Z0
    for i in range(steps + int(HOLD_S * 1000.0) + 1):
        z = Z0 + TRAVEL * min(i, steps) / steps
        over += sim.step([0.5 * COLS * CELL, EDGE_Y, z, 1.0, 0.0, 0.0, 0.0]).over_top_m3
    return np.asarray(sim.heights, dtype=float), z, over


def volumes(h, end_z):
    """(soil ahead of the blade above the layer, soil behind it above the edge), m^3."""
    zc = (np.arange(ROWS) + 0.5) * CELL
    xc = (np.arange(COLS) + 0.5) * CELL
    beside = np.abs(xc - 0.5 * COLS * CELL)[None, :] <= 0.5 * BLADE
    ahead = (zc > end_z)[:, None]
    behind = ((zc < end_z) & (zc >= Z0))[:, None] & beside
    area = CELL * CELL
    return (float(np.clip(h - LAYER, 0.0, None)[np.broadcast_to(ahead, h.shape)].sum() * area),
            float(np.clip(h - EDGE_Y, 0.0, None)[behind].sum() * area))


def main(argv):
    out, quiet = parse_out_args(argv, __doc__, os.path.join("docs", "images", "soil_blade_top.png"), fail)
    fig, ax = plt.subplots(figsize=(11, 4.6))
    zc = (np.arange(ROWS) + 0.5) * CELL
    mid = COLS // 2
    for height_m, colour, label in ((math.inf, "0.45", "unbounded (the default)"),
                                    (HEIGHT, "C1", f"{HEIGHT:g} m tall")):
        h, end_z, over = run(height_m)
        ahead, behind = volumes(h, end_z)
        if not quiet:
            print(f"{label}: ahead {ahead:.5f} m^3, behind {behind:.5f} m^3, over the top {over:.5f} m^3, "
                  f"highest {h.max():.4f} m")
        ax.plot(zc, h[:, mid], color=colour, lw=1.6,
                label=f"{label}: {ahead * 1000:.1f} l ahead, {behind * 1000:.1f} l behind, "
                      f"{over * 1000:.1f} l over the top")
    ax.plot([end_z, end_z], [EDGE_Y, EDGE_Y + HEIGHT], color="k", lw=3, label="the 0.1 m blade at the end")
    ax.axhline(LAYER, color="0.7", lw=0.8, ls=":", label="the layer")
    ax.axhline(EDGE_Y, color="0.7", lw=0.8, ls="--", label="the edge (the trench floor)")
    ax.set_xlim(Z0 - 0.1, ROWS * CELL)
    ax.set_xlabel("z (m), the push")
    ax.set_ylabel("height (m)")
    ax.set_title("A 1 m blade pushing 5 cm of dry sand 1.5 m at 1 m/s on 1 cm cells: "
                 "the section through its middle", fontsize=10)
    ax.legend(loc="upper left", fontsize=8)
    save_figure(fig, out, fail, quiet, "plot_blade_top.py")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
