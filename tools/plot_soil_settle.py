#!/usr/bin/python3
"""The pile a push leaves with each settle, square to the grid and turned.

Usage: PYTHONPATH=build/python /usr/bin/python3 tools/plot_soil_settle.py
           [--out FILE.png] [--quiet]

Runs, with the terracut module, the push of tools/soil_push.py (a 1 m blade
cutting 4 cm into a 20 cm layer of dry sand on 5 mm cells, pushed 0.8 m at
1 m/s, then held 0.2 s) five times: with soil.settle: patches (the default
until 2026-12-07), square to the grid and turned 10 degrees, converged (the
cap lifted); with the fans (the default), the same two and the turned one
at the default cap. It
maps each one's heights above the layer and titles it with the soil ahead
of the blade (docs/soil.md, "The settle follows the fall lines"). Default
output: docs/images/soil_settle_fans.png. About 15 s.

Exit codes: 0 done; 2 bad arguments; 3 numpy, matplotlib or terracut missing.
"""
import sys

import soil_push
from plot_common import import_plotting, import_terracut, make_fail, parse_out_args, save_figure

fail = make_fail("plot_soil_settle.py")
np, plt = import_plotting(fail)
terracut = import_terracut(fail)

CELL, WIDTH, SPEED, TRAVEL, YAW = 0.005, 1.0, 1.0, 0.8, 10.0
RUNS = [("patches", 0.0, 1e9, "patches, square, converged"),
        ("patches", YAW, 1e9, f"patches, turned {YAW:g} deg, converged"),
        ("fans", 0.0, 1e9, "fans, square, converged"),
        ("fans", YAW, 1e9, f"fans, turned {YAW:g} deg, converged"),
        ("fans", YAW, None, f"fans, turned {YAW:g} deg, default cap")]


def main(argv):
    out, quiet = parse_out_args(argv, __doc__, "docs/images/soil_settle_fans.png", fail)
    import matplotlib.colors
    fig, axes = plt.subplots(1, len(RUNS), figsize=(4.2 * len(RUNS), 4.6))
    half = int(round(0.9 / CELL))
    for ax, (settle, yaw, cap, title) in zip(axes, RUNS):
        p = soil_push.push(terracut, np, WIDTH, CELL, SPEED, cap, TRAVEL, yaw_deg=yaw, settle=settle)
        h = p["heights"] - soil_push.LAYER
        r, c = h.shape[0] // 2, h.shape[1] // 2
        im = ax.imshow(1000.0 * h[max(0, r - half):r + half, max(0, c - half):c + half], origin="lower",
                       cmap="RdBu_r", norm=matplotlib.colors.TwoSlopeNorm(0.0, -60.0, 220.0),
                       extent=(-half * CELL, half * CELL, -half * CELL, half * CELL))
        ax.set_title(f"{title}\n{1000 * p['ahead']:.1f} litres ahead", fontsize=9)
        ax.set_xlabel("from the grid's centre, x (m)")
        if not quiet:
            print(f"{title}: {1000 * p['ahead']:.2f} litres ahead, peak {1000 * p['peak']:.1f} mm")
    axes[0].set_ylabel("z (m)")
    fig.colorbar(im, ax=axes[-1], shrink=0.8, label="height above the layer (mm)")
    save_figure(fig, out, fail, quiet, "plot_soil_settle.py")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
