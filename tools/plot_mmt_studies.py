#!/usr/bin/python3
"""Draw several `terracut mmt --sweep` studies side by side.

Usage: /usr/bin/python3 tools/plot_mmt_studies.py --out FILE.png DIR [DIR ...] [--quiet]

Each DIR is a `terracut mmt SCENARIO --sweep --out DIR` folder (study.csv,
and summary.json files are not needed). One panel per study: the force error
after the first second of cutting, in % of the remote's force RMS, against
round-trip delay, for MMT (the local model learning the remote's soil) and
for direct force reflection, at each loss (mean over the seeds, bars from
the best to the worst seed), with the 5 % target; the panel is titled with
the folder's name (less a leading "study_"). A last panel: model-update packets per second with and
without the perceptual deadband, every study at its first loss.

Exit codes: 0 done; 2 bad arguments or input folder; 3 numpy or matplotlib missing.
"""
import os
import sys

from plot_common import import_plotting, make_fail, over_seeds, parse_dirs_args

fail = make_fail("plot_mmt_studies.py")
np, plt = import_plotting(fail)


def main(argv):
    folders, out, quiet = parse_dirs_args(argv, __doc__, fail, "plot_mmt_studies.py")
    studies = []
    for f in folders:
        path = os.path.join(f, "study.csv")
        if not os.path.isfile(path):
            fail(f"{path} not found (a `terracut mmt --sweep --out` folder?)")
        name = os.path.basename(os.path.normpath(f))
        studies.append((name[6:] if name.startswith("study_") else name,
                        np.genfromtxt(path, delimiter=",", names=True)))
    n = len(studies) + 1
    fig, axes = plt.subplots(1, n, figsize=(4.3 * n, 4.4))
    styles = ["-", "--", ":"]
    for ax, (name, s) in zip(axes, studies):
        full = s[s["deadband"] == 0]
        for k, loss in enumerate(sorted(set(full["loss"]))):
            rows = full[full["loss"] == loss]
            for key, color, marker, label in (("after_1s_direct_rel", "tab:red", "o", "direct"),
                                              ("after_1s_mmt_rel", "tab:blue", "s", "MMT")):
                x, mean, down, up = over_seeds(np, rows, key, 100.0)
                ax.errorbar(x, mean, yerr=[down, up], ls=styles[k % 3], color=color,
                            marker=marker, ms=4, capsize=2, label=f"{label}, loss {loss * 100:.0f} %")
        ax.axhline(5.0, color="black", lw=0.8, ls="--", label="target 5 %")
        ax.set_xscale("symlog", linthresh=20)
        ax.set_xlim(left=0)
        ax.set_yscale("log")
        ax.set_xlabel("round-trip delay (ms)")
        ax.set_title(name, fontsize=10)
        ax.grid(alpha=0.3, which="both")
    axes[0].set_ylabel("force error after 1 s of cutting\n(% of the remote's force RMS)")
    axes[0].legend(fontsize=6, loc="upper left")
    ax = axes[-1]
    for name, s in studies:
        full = s[s["deadband"] == 0]
        base = full[(full["loss"] == min(full["loss"])) & (full["seed"] == full["seed"][0])]
        o = np.argsort(base["rtt_ms"])
        line, = ax.plot(base["rtt_ms"][o], base["update_packets_per_s"][o], "-o", ms=3, label=f"{name}")
        db = s[s["deadband"] > 0]
        if len(db):
            od = np.argsort(db["rtt_ms"])
            ax.plot(db["rtt_ms"][od], db["update_packets_per_s"][od], "--s", ms=3, color=line.get_color(),
                    label=f"{name}, deadband {db['deadband'][0] * 100:.0f} %")
    ax.set_xscale("symlog", linthresh=20)
    ax.set_xlim(left=0)
    ax.set_ylim(bottom=0)
    ax.set_xlabel("round-trip delay (ms)")
    ax.set_ylabel("model-update packets per second")
    ax.set_title("model updates", fontsize=10)
    ax.legend(fontsize=6)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    if not quiet:
        print(f"plot_mmt_studies.py: wrote {out}")


if __name__ == "__main__":
    main(sys.argv)
