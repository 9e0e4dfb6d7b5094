#!/usr/bin/python3
"""Plot a `terracut mmt` output folder.

Usage: /usr/bin/python3 tools/plot_mmt.py DIR [--out FILE.png] [--quiet]

A single run (DIR/operator.csv, DIR/remote.csv, DIR/terrain_error.csv), or
the report of a two-process session (`terracut mmt --report`), gives
DIR/mmt.png, against the operator's time:
  - the horizontal force the operator's local model renders (MMT), the
    remote's measured force for the same command (its first tick following
    it: what the operator should feel for the same motion), and the remote's
    force as it arrives (direct force reflection);
  - the soil factor the remote estimated and the one the operator applied;
  - the RMS of local minus remote heights over the worked region.
A study (DIR/study.csv, from `terracut mmt --sweep`) gives DIR/study.png:
force error (RMS) against round-trip delay for MMT and for direct force
reflection, one line per loss, and the update packet rate with and without
the perceptual deadband.

Exit codes: 0 done; 2 bad arguments or input folder; 3 numpy or matplotlib missing.
Needs Debian's python3-numpy and python3-matplotlib.
"""
import json
import os
import sys

from plot_common import import_plotting, make_fail, parse_dir_args

fail = make_fail("plot_mmt.py")
np, plt = import_plotting(fail)


def read_csv(path):
    if not os.path.isfile(path):
        fail(f"{path} not found (is this a `terracut mmt --out` folder?)")
    return np.genfromtxt(path, delimiter=",", names=True)


def plot_run(folder, out):
    op = read_csv(os.path.join(folder, "operator.csv"))
    rm = read_csv(os.path.join(folder, "remote.csv"))
    te = read_csv(os.path.join(folder, "terrain_error.csv"))
    with open(os.path.join(folder, "summary.json")) as f:
        summary = json.load(f)
    hz = lambda x, z: np.hypot(x, z)
    t = op["t"]
    f_op = hz(op["fx"], op["fz"])
    f_dfr = hz(op["remote_fx"], op["remote_fz"])
    # The remote's force for the same commanded motion: its first tick that
    # followed the operator's command (or a newer one), by command sequence,
    # as summary.json's force error. The remote's own ticks are drawn at the
    # operator's time of the command they followed and half the measured
    # round trip (its clock, in a two-process session, is its own).
    f_rm = np.full_like(t, np.nan)
    seq_rm = np.where(rm["active"] > 0, rm["command_sequence"], -1.0)
    first = np.searchsorted(np.maximum.accumulate(seq_rm), op["command_sequence"], side="left")
    ok = first < len(rm)
    f_rm[ok] = hz(rm["fx"][first[ok]], rm["fz"][first[ok]])
    rtt = summary["link"].get("rtt_measured_s") or summary["link"]["rtt_s"]
    t_rm = np.interp(rm["command_sequence"], op["command_sequence"], t) + 0.5 * rtt
    fig, ax = plt.subplots(3, 1, figsize=(9, 9), sharex=True)
    ax[0].plot(t, f_rm, color="black", lw=2.0, label="remote, measured (for the same command)")
    ax[0].plot(t, f_op, color="tab:blue", label="operator, local model (MMT)")
    ax[0].plot(t, f_dfr, color="tab:red", lw=0.8, label="direct force reflection (as received)")
    ax[0].set_ylabel("horizontal force (N)")
    fe = summary["force_error"]
    ax[0].set_title(f"RTT {rtt * 1e3:.0f} ms (measured), loss "
                    f"{summary['link']['loss'] * 100:.0f} %: force error RMS "
                    f"MMT {fe['mmt_rms_n']:.1f} N, direct {fe['direct_rms_n']:.1f} N")
    ax[0].legend(loc="upper right", fontsize=8)
    active = rm["active"] > 0
    ax[1].plot(t_rm[active], rm["force_scale"][active], color="black", label="remote's estimate")
    ax[1].plot(t, op["scale_applied"], color="tab:blue", label="applied by the operator")
    ax[1].set_ylabel("soil factor")
    ax[1].legend(loc="lower right", fontsize=8)
    te_t, te_v = np.atleast_1d(te["t"]), np.atleast_1d(te["rms_m"]) * 1e3
    ax[2].plot(te_t, te_v, color="tab:green", marker="o" if len(te_t) == 1 else None)
    ax[2].set_ylim(bottom=0.0)
    ax[2].set_ylabel("terrain RMS error (mm)")
    ax[2].set_xlabel("time (s)")
    for a in ax:
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def plot_study(folder, out):
    s = read_csv(os.path.join(folder, "study.csv"))
    full = s[s["deadband"] == 0]
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.6))
    losses = sorted(set(full["loss"]))
    styles = ["-", "--", ":"]
    for i, loss in enumerate(losses):
        rows = full[full["loss"] == loss]
        order = np.argsort(rows["rtt_ms"])
        r = rows[order]
        ls = styles[i % len(styles)]
        ax[0].plot(r["rtt_ms"], r["direct_rms_n"], ls, color="tab:red", marker="o",
                   label=f"direct reflection, loss {loss * 100:.0f} %")
        ax[0].plot(r["rtt_ms"], r["mmt_rms_n"], ls, color="tab:blue", marker="s",
                   label=f"MMT, loss {loss * 100:.0f} %")
    ax[0].plot(full["rtt_ms"], full["force_rms_remote_n"], ".", color="gray",
               label="RMS of the remote force itself")
    ax[0].set_xscale("symlog", linthresh=50)
    ax[0].set_xlabel("round-trip delay (ms)")
    ax[0].set_ylabel("force error, RMS (N)")
    ax[0].set_title("force error against delay")
    ax[0].legend(fontsize=7)
    ax[0].grid(alpha=0.3)
    db = s[s["deadband"] > 0]
    base = full[full["loss"] == losses[0]]
    ob = np.argsort(base["rtt_ms"])
    ax[1].plot(base["rtt_ms"][ob], base["update_packets_per_s"][ob], "-o", color="tab:blue",
               label="every change")
    if len(db):
        od = np.argsort(db["rtt_ms"])
        ax[1].plot(db["rtt_ms"][od], db["update_packets_per_s"][od], "-s", color="tab:orange",
                   label=f"deadband {db['deadband'][0] * 100:.0f} %")
    ax[1].set_xscale("symlog", linthresh=50)
    ax[1].set_xlabel("round-trip delay (ms)")
    ax[1].set_ylabel("model-update packets per second")
    ax[1].set_title(f"model updates (loss {losses[0] * 100:.0f} %)")
    ax[1].set_ylim(bottom=0)
    ax[1].legend(fontsize=8)
    ax[1].grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def main(argv):
    folder, out, quiet = parse_dir_args(argv, __doc__, "", fail, "plot_mmt.py")
    if not os.path.isdir(folder):
        fail(f"{folder} is not a folder")
    given = "--out" in argv  # --out names the one figure drawn (the study's when both could be)
    if os.path.isfile(os.path.join(folder, "study.csv")):
        path = out if given else os.path.join(folder, "study.png")
        plot_study(folder, path)
    elif os.path.isfile(os.path.join(folder, "operator.csv")):
        path = out if given else os.path.join(folder, "mmt.png")
        plot_run(folder, path)
    else:
        fail(f"{folder} has neither study.csv nor operator.csv (a `terracut mmt --out` folder?)")
    if not quiet:
        print(f"plot_mmt.py: wrote {path}")


if __name__ == "__main__":
    main(sys.argv)
