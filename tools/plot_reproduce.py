#!/usr/bin/python3
"""Figures of `terracut reproduce`.

Usage: /usr/bin/python3 tools/plot_reproduce.py DIR [--quiet]

DIR is the output folder of `terracut reproduce` (it reads DIR/reproduce.json,
the runs' contact.csv and height.npy/removed.npy, DIR/exp1/exact.csv and
DIR/exp1/errors.csv) and receives:

  fig8_<rep>.png        contact length over time at 5x5 ... 50x50 with the exact
                        chord, and the blade's Z over time (the paper's Fig. 8)
  fig9_<rep>.png        contact length over time for the orders (A,B,C), (C,A,B),
                        (B,C,A) (the paper's Fig. 9)
  fig13_<rep>.png       heights and removed material after cuts (A,B) (Fig. 13)
  fig14_<rep>.png       heights and removed material after all cuts (Fig. 14)
  convergence.png       RMS and mean absolute contact error against resolution,
                        log-log, both representations

Exit codes: 0 done; 2 bad input folder; 3 numpy or matplotlib missing.
Needs Debian's python3-numpy and python3-matplotlib.
"""
import os
import sys

from plot_common import FigureFolder, import_plotting, make_fail, parse_folder_args

fail = make_fail("plot_reproduce.py")
np, plt = import_plotting(fail)

CUT_COLOURS = {"A": "tab:blue", "B": "tab:orange", "C": "tab:green"}
RES_COLOURS = ["tab:red", "tab:orange", "tab:green", "tab:blue", "tab:purple", "tab:brown",
               "tab:pink"]
REP_STYLE = {"columns": dict(color="tab:red", marker="s"),
             "surface": dict(color="tab:blue", marker="o")}
FILES = FigureFolder(np, plt, fail, "plot_reproduce.py", "terracut reproduce", dpi=110)


def fig8(out_dir, meta, rep):
    """Contact length vs time, one panel per resolution, and blade Z vs time."""
    exact = FILES.read_csv(os.path.join(out_dir, meta["exp1"]["exact_csv"]))
    resolutions = meta["exp1"]["fig8_resolutions"]
    fig, axes = plt.subplots(len(resolutions) + 1, 1, sharex=True, figsize=(10, 11),
                             gridspec_kw=dict(height_ratios=[2] * len(resolutions) + [1.4]))
    peak = float(np.max(exact["exact_contact"]))
    for ax, n, colour in zip(axes, resolutions, RES_COLOURS):
        run = FILES.read_csv(os.path.join(out_dir, "exp1", rep, str(n), "contact.csv"))
        ax.plot(exact["t"], exact["exact_contact"], color="black", lw=1.2, ls="--",
                label="exact chord")
        ax.plot(run["t"], run["contact_length"], color=colour, lw=1.0,
                label=f"{n}x{n} measured")
        ax.set_ylim(-0.05 * peak, 1.25 * peak)
        ax.set_ylabel("contact (m)")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8, framealpha=0.9)
    ax = axes[-1]
    ax.plot(exact["t"], exact["z"], color="black", lw=1.2)
    ax.set_ylabel("blade z (m)")
    ax.set_xlabel("time (s)")
    ax.grid(alpha=0.3)
    fig.suptitle(f"Experiment 1, {rep} representation: contact length of a horizontal cut "
                 f"through the mound\n(blade at y = half the peak; X and Y constant)")
    fig.tight_layout()
    FILES.save(fig, out_dir, f"fig8_{rep}.png")


def fig9(out_dir, meta, rep):
    """Contact length vs time for the three orders, coloured by cut."""
    sequences = meta["exp2"]["sequences"]
    fig, axes = plt.subplots(len(sequences), 1, sharex=True, sharey=True, figsize=(10, 8))
    for ax, seq in zip(axes, sequences):
        run = FILES.read_csv(os.path.join(out_dir, "exp2", rep, seq, "contact.csv"))
        cuts = np.asarray(run["cut"]).astype(str)
        t = run["t"]
        # One line per cut, and a dotted line where the next cut starts.
        start = 0
        for i in range(1, len(cuts) + 1):
            if i == len(cuts) or cuts[i] != cuts[start]:
                name = cuts[start]
                ax.plot(t[start:i], run["contact_length"][start:i],
                        color=CUT_COLOURS.get(name, "tab:gray"), lw=1.3, label=f"cut {name}")
                if i < len(cuts):
                    ax.axvline(t[i], color="gray", ls=":", lw=1)
                start = i
        ax.set_title(f"sequence ({', '.join(seq)})", fontsize=10, loc="left")
        ax.set_ylabel("contact (m)")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8, ncol=3, framealpha=0.9)
    axes[-1].set_xlabel("time (s)")
    fig.suptitle(f"Experiment 2, {rep} representation: contact length for three orders of "
                 f"cuts A, B, C (2 s each)")
    fig.tight_layout()
    FILES.save(fig, out_dir, f"fig9_{rep}.png")


def layers(out_dir, rep, seq):
    run_dir = os.path.join(out_dir, "exp2", rep, seq)
    return (FILES.read_npy(os.path.join(run_dir, "height.npy")),
            FILES.read_npy(os.path.join(run_dir, "removed.npy")))


def heightmap_figure(out_dir, meta, rep, seq, name, title, compare_seq, show_difference):
    """Remaining height and removed material of one run, X right, Z up, on the
    colour ranges shared with run compare_seq; with show_difference, a third
    panel shows what this run removed beyond compare_seq."""
    height, removed = layers(out_dir, rep, seq)
    other = layers(out_dir, rep, compare_seq)
    # One colour range for the figures of both runs, so Figs. 13 and 14 compare.
    all_heights = [height, other[0]]
    all_removed = [removed, other[1]]
    h_range = (min(float(a.min()) for a in all_heights), max(float(a.max()) for a in all_heights))
    r_range = (min(float(a.min()) for a in all_removed), max(float(a.max()) for a in all_removed))
    sx, sz = meta["exp2"]["size_m"]
    ox, _, oz = meta["exp2"]["origin_m"]
    extent = [ox, ox + sx, oz, oz + sz]
    panels = [(height, "remaining height (m)", "viridis", h_range),
              (removed, "removed material (m)", "magma", r_range)]
    if show_difference:
        diff = other[0] - height
        panels.append((diff, f"removed after ({', '.join(compare_seq)}) by the rest (m)", "Greens",
                       (0.0, max(float(diff.max()), 1e-9))))
    fig, axes = plt.subplots(1, len(panels), figsize=(5.6 * len(panels), 4.8))
    for ax, (data, label, cmap, (lo, hi)) in zip(axes, panels):
        # Row r of the arrays runs along +Z: origin="lower" puts row 0 at the bottom.
        image = ax.imshow(data, origin="lower", extent=extent, cmap=cmap, vmin=lo,
                          vmax=hi if hi > lo else lo + 1e-9, interpolation="nearest")
        ax.set_xlabel("X (m)")
        ax.set_ylabel("Z (m)")
        ax.set_title(label, fontsize=10)
        fig.colorbar(image, ax=ax, label=label, shrink=0.9)
    fig.suptitle(title)
    fig.tight_layout()
    FILES.save(fig, out_dir, name)


def convergence(out_dir, meta):
    """RMS and mean absolute error against resolution, log-log."""
    table = FILES.read_csv(os.path.join(out_dir, meta["exp1"]["errors_csv"]))
    reps = np.asarray(table["representation"]).astype(str)
    fig, ax = plt.subplots(figsize=(8, 5.5))
    for rep in meta["representations"]:
        rows = reps == rep
        n = table["resolution"][rows]
        style = REP_STYLE.get(rep, dict(color="tab:gray", marker="^"))
        ax.loglog(n, table["rms_m"][rows], lw=1.5, label=f"{rep}: RMS error", **style)
        ax.loglog(n, table["mean_abs_m"][rows], lw=1.0, ls="--", mfc="none",
                  label=f"{rep}: mean |error|", **style)
    n_all = np.asarray(sorted(set(int(v) for v in table["resolution"])), dtype=float)
    ref = table["rms_m"][reps == meta["representations"][-1]]
    if len(ref):
        ax.loglog(n_all, ref[0] * n_all[0] / n_all, color="gray", lw=1, ls=":",
                  label="slope -1 (error ~ cell size)")
    ax.set_xlabel("resolution N (N x N samples over 1 m)")
    ax.set_ylabel("contact length error (m)")
    ax.set_xticks(n_all)
    ax.set_xticklabels([str(int(v)) for v in n_all])
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=9)
    ax.set_title("Experiment 1: contact length error against the exact chord")
    fig.tight_layout()
    FILES.save(fig, out_dir, "convergence.png")


def main(argv):
    out_dir, FILES.quiet = parse_folder_args(argv, __doc__)
    meta = FILES.read_meta(out_dir, "reproduce.json")
    for rep in meta["representations"]:
        fig8(out_dir, meta, rep)
        fig9(out_dir, meta, rep)
        ab = meta["exp2"]["after_ab"]
        everything = meta["exp2"]["after_all"]
        heightmap_figure(out_dir, meta, rep, ab, f"fig13_{rep}.png",
                         f"Experiment 2, {rep}: after cuts ({', '.join(ab)})", everything, False)
        heightmap_figure(out_dir, meta, rep, everything, f"fig14_{rep}.png",
                         f"Experiment 2, {rep}: after all cuts (every order gives this; "
                         f"shown: {', '.join(everything)})", ab, True)
    convergence(out_dir, meta)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
