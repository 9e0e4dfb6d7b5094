#!/usr/bin/python3
"""Quick-look figures of the committed results (written to work/plots/, not
committed): force vs push per case (all seeds), surface height maps and the
centre-line profile of one run.   /usr/bin/python3 plot.py [case [seed]]"""

import json
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
RES = os.path.join(HERE, "results", "bulldoze")
OUT = os.path.join(HERE, "work", "plots")


def forces():
    cases = sorted(d for d in os.listdir(RES) if os.path.isdir(os.path.join(RES, d)))
    fig, axs = plt.subplots(len(cases), 1, figsize=(7, 2.6 * len(cases)), squeeze=False)
    for ax, c in zip(axs[:, 0], cases):
        for s in sorted(os.listdir(os.path.join(RES, c))):
            p = os.path.join(RES, c, s, "force.csv")
            if not os.path.exists(p):
                continue
            f = np.genfromtxt(p, delimiter=",", names=True)
            k = 20  # 50 ms running mean
            sm = lambda a: np.convolve(a, np.ones(k) / k, mode="valid")  # noqa: E731
            ax.plot(sm(f["push_m"]), sm(f["fx_n"]), label=s + " fx")
            ax.plot(sm(f["push_m"]), sm(f["fz_n"]), "--", label=s + " fz")
        ax.set_title(c)
        ax.set_xlabel("push (m)")
        ax.set_ylabel("force on blade (N)")
        ax.legend(fontsize=6, ncol=3)
    fig.tight_layout()
    fig.savefig(os.path.join(OUT, "forces.png"), dpi=90)


def surfaces(case, seed):
    d = os.path.join(RES, case, "seed%d" % seed)
    info = json.load(open(os.path.join(d, "run.json")))
    snaps = info["surfaces"]["snapshots"]
    cell = info["surfaces"]["cell_m"]
    H0 = info["bed"]["initial_surface_mean_m"]
    fig, axs = plt.subplots(len(snaps) + 1, 1, figsize=(7, 2.2 * (len(snaps) + 1)))
    ny, nx = info["surfaces"]["shape_rows_cols"]
    yc = int(round(0.5 * (info["blade"]["tip_line_at_push_start"]["y_from_m"]
                          + info["blade"]["tip_line_at_push_start"]["y_to_m"]) / cell))
    for ax, (k, sn) in zip(axs, snaps.items()):
        g = np.load(os.path.join(d, sn["file"]))
        im = ax.imshow(g - H0, origin="lower", extent=[0, nx * cell, 0, ny * cell], vmin=-0.06, vmax=0.08,
                       cmap="RdBu_r")
        ax.set_title("%s push=%s" % (sn["file"], sn["push_m"]), fontsize=8)
        axs[-1].plot((np.arange(nx) + 0.5) * cell, g[yc] - H0, label=sn["file"])
    fig.colorbar(im, ax=axs[:-1].tolist(), shrink=0.6, label="h - H0 (m)")
    axs[-1].legend(fontsize=6)
    axs[-1].set_xlabel("x (m)")
    fig.savefig(os.path.join(OUT, "surf_%s_seed%d.png" % (case, seed)), dpi=80)


if __name__ == "__main__":
    os.makedirs(OUT, exist_ok=True)
    forces()
    if len(sys.argv) > 1:
        surfaces(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 1)
    print(OUT)
