#!/usr/bin/python3
"""Each settle's converged pile against the relaxation's own, in a figure.

Usage: PYTHONPATH=build/python /usr/bin/python3 tools/plot_settle_reference.py
           [--out FILE.png] [--quiet]

Runs, with the terracut module, the push of tools/soil_push.py (a blade
cutting 4 cm into a 20 cm layer of dry sand, pushed 0.8 m at 1 m/s, then
held 0.2 s, the cap lifted) for blades of 0.3, 1 and 2 m turned 0, 10 and
30 degrees to the grid, on 1 cm and 5 mm cells, with each settle of the
displaced pile: the passes alone (soil.settle: passes, the reference: the
relaxation with no construction), the patches and the fans (the default).
It draws, per cell size, the soil each construction leaves ahead of the
blade less the passes' own, in per cent, and prints the table
(docs/soil.md, "The fans by default"). Default output:
docs/images/soil_settle_reference.png. About two minutes.

Exit codes: 0 done; 2 bad arguments; 3 numpy, matplotlib or terracut missing.
"""
import sys

import soil_push
from plot_common import import_plotting, import_terracut, make_fail, parse_out_args, save_figure

fail = make_fail("plot_settle_reference.py")
np, plt = import_plotting(fail)
terracut = import_terracut(fail)

SPEED, TRAVEL, LIFTED = 1.0, 0.8, 1e9
CELLS = (0.01, 0.005)
BLADES = (0.3, 1.0, 2.0)
YAWS = (0.0, 10.0, 30.0)
SETTLES = ("patches", "fans")
COLOURS = {"patches": "tab:orange", "fans": "tab:blue"}


def main(argv):
    out, quiet = parse_out_args(argv, __doc__, "docs/images/soil_settle_reference.png", fail)
    fig, axes = plt.subplots(1, len(CELLS), figsize=(6.5 * len(CELLS), 4.6), sharey=True)
    if not quiet:
        print("| cells | blade | yaw | passes alone (m^3) | patches | fans |")
        print("|---|---|---|---|---|---|")
    for ax, cell in zip(axes, CELLS):
        labels, offs = [], {s: [] for s in SETTLES}
        for width in BLADES:
            for yaw in YAWS:
                ahead = {s: soil_push.push(terracut, np, width, cell, SPEED, LIFTED, TRAVEL, yaw_deg=yaw,
                                           settle=s)["ahead"] for s in ("passes",) + SETTLES}
                for s in SETTLES:
                    offs[s].append(100.0 * (ahead[s] / ahead["passes"] - 1.0))
                labels.append(f"{width:g} m\n{yaw:g} deg")
                if not quiet:
                    print(f"| {1000 * cell:g} mm | {width:g} m | {yaw:g} | {ahead['passes']:.5f} | "
                          f"{ahead['patches']:.5f} ({offs['patches'][-1]:+.1f} %) | "
                          f"{ahead['fans']:.5f} ({offs['fans'][-1]:+.1f} %) |")
        x = np.arange(len(labels))
        for k, s in enumerate(SETTLES):
            ax.bar(x + (k - 0.5) * 0.38, offs[s], 0.38, color=COLOURS[s],
                   label=s + (" (the default)" if s == "fans" else ""))
        ax.axhline(0.0, color="k", lw=0.8)
        ax.axhspan(-5.0, 5.0, color="0.85", zorder=0, label="within 5 %")
        ax.set_xticks(x)
        ax.set_xticklabels(labels, fontsize=7)
        ax.set_title(f"{1000 * cell:g} mm cells, converged (cap lifted)", fontsize=10)
        ax.grid(axis="y", alpha=0.3)
    axes[0].set_ylabel("soil ahead of the blade less the passes' own (%)")
    axes[0].legend(fontsize=8, loc="lower left")
    fig.suptitle("A 0.8 m push at 1 m/s, held 0.2 s: each settle against the relaxation's passes alone", fontsize=10)
    save_figure(fig, out, fail, quiet, "plot_settle_reference.py")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
