#!/usr/bin/python3
"""Plot a `terracut mmt` output folder.

Usage: /usr/bin/python3 tools/plot_mmt.py DIR [--out FILE.png] [--quiet]

A single run (DIR/operator.csv, DIR/remote.csv, DIR/terrain_error.csv,
DIR/summary.json), or the report of a two-process session (`terracut mmt
--report`), gives DIR/mmt.png, against the operator's time:
  - the horizontal physical force of the operator's local model (MMT), the
    remote's measured force for the same command (its first tick following
    it, and its arm's lag later unless the operator's model moves as the
    arm does, summary.json's aligned_after_s: what the operator should feel for the same
    motion), and the remote's force as it arrives (direct force
    reflection); the window of the "after 1 s of cutting" figures shaded;
  - the remote's estimate of its soil's cohesion and adhesion (kPa) with
    their standard uncertainties, what the operator's model uses, and the
    remote's true values (dashed); the remote's ticks drawn at the
    operator's time of the command they followed plus half the round trip;
  - the same for the friction angles (degrees) and the unit weight;
  - the RMS of local minus remote heights over the worked region.
A study (DIR/study.csv, from `terracut mmt --sweep`) gives DIR/study.png:
the force error after the first second of cutting, in % of the remote's
force RMS, against round-trip delay for MMT and for direct force
reflection (mean over the seeds, bars from the best to the worst seed), one
line per loss, and the update packet rate with and without the perceptual
deadband.

Exit codes: 0 done; 2 bad arguments or input folder; 3 numpy or matplotlib missing.
Needs Debian's python3-numpy and python3-matplotlib.
"""
import json
import os
import sys

from plot_common import import_plotting, make_fail, over_seeds, parse_dir_args

fail = make_fail("plot_mmt.py")
np, plt = import_plotting(fail)


def read_csv(path):
    if not os.path.isfile(path):
        fail(f"{path} not found (is this a `terracut mmt --out` folder?)")
    return np.genfromtxt(path, delimiter=",", names=True)


def band(ax, t, value, sd, color, label):
    """A line with a +-1 sd band (an unbounded sd draws no band)."""
    ax.plot(t, value, color=color, label=label)
    finite = sd < 1e3 * np.maximum(np.abs(value), 1.0)
    ax.fill_between(t, np.where(finite, value - sd, np.nan), np.where(finite, value + sd, np.nan),
                    color=color, alpha=0.2, lw=0)


def truth_line(ax, summary, key, scale, color):
    """The remote's true value of a field (dashed), and after a change of soil the new one."""
    # A two-process report has the remote's truth at its end only.
    soil = summary.get("remote_soil") or {"material": summary["estimate"]["truth"]}
    t_change = soil.get("changed_at_s")
    ax.axhline(soil["material"][key] * scale, color=color, ls="--", lw=1.0)
    if soil.get("changed_to") and t_change is not None:
        ax.axhline(soil["changed_to"][key] * scale, color=color, ls=":", lw=1.2)


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
    # The remote's force for the same commanded motion: its first tick that
    # followed the operator's command (or a newer one), by command sequence,
    # and the arm's lag later, as summary.json's force error. The remote's
    # own ticks are drawn at the operator's time of the command they
    # followed and half the measured round trip (its clock, in a
    # two-process session, is its own).
    f_rm = np.full_like(t, np.nan)
    dt = t[1] - t[0] if len(t) > 1 else 1e-3
    aligned = summary["force_error"].get("aligned_after_s", 0.0)
    lag = int(round(aligned / dt))
    seq_rm = np.where(rm["active"] > 0, rm["command_sequence"], -1.0)
    first = np.searchsorted(np.maximum.accumulate(seq_rm), op["command_sequence"], side="left") + lag
    ok = first < len(rm)
    f_rm[ok] = hz(rm["fx"][first[ok]], rm["fz"][first[ok]])
    rtt = summary["link"].get("rtt_measured_s") or summary["link"]["rtt_s"]
    t_rm = np.interp(rm["command_sequence"], op["command_sequence"], t) + 0.5 * rtt
    # A remote time in the operator's: its command's time and the arm's lag before.
    shift = 0.5 * rtt + aligned

    fig, ax = plt.subplots(4, 1, figsize=(9, 11.5), sharex=True,
                           gridspec_kw={"height_ratios": [3, 2, 2, 1.2]})
    after = summary["force_error_after_1s"]
    if after["from_s"] >= 0:
        ax[0].axvspan(after["from_s"] - shift, t[-1], color="tab:green", alpha=0.07,
                      label="after 1 s of cutting (the study's window)")
    if after["left_out_to_s"] > after["left_out_from_s"]:
        ax[0].axvspan(after["left_out_from_s"] - shift, after["left_out_to_s"] - shift,
                      color="gray", alpha=0.25, label="left out: a round trip + 0.5 s after the change")
    ax[0].plot(t, f_rm, color="black", lw=2.0, label="remote, measured (for the same command)")
    ax[0].plot(t, f_op, color="tab:blue", label="operator, local model (MMT)")
    ax[0].plot(t, f_dfr, color="tab:red", lw=0.8, label="direct force reflection (as received)")
    ax[0].set_ylabel("horizontal force (N)")
    ax[0].set_title(f"RTT {rtt * 1e3:.0f} ms (measured), loss "
                    f"{summary['link']['loss'] * 100:.0f} %: after 1 s of cutting MMT "
                    f"{after['mmt_relative'] * 100:.1f} %, direct {after['direct_relative'] * 100:.1f} % "
                    f"of the remote's {after['remote_force_rms_n']:.0f} N RMS", fontsize=10)
    ax[0].legend(loc="upper right", fontsize=7)

    act = rm["active"] > 0
    rt = t_rm[act]
    est = {k: rm[k][act] for k in rm.dtype.names}
    band(ax[1], rt, est["est_cohesion"] * 1e-3, est["sd_cohesion"] * 1e-3, "tab:purple",
         "cohesion, remote's estimate")
    band(ax[1], rt, est["est_adhesion"] * 1e-3, est["sd_adhesion"] * 1e-3, "tab:orange",
         "adhesion, remote's estimate")
    ax[1].plot(t, op["cohesion"] * 1e-3, color="tab:purple", lw=0.8, alpha=0.6, ls="-.",
               label="cohesion, operator's model")
    truth_line(ax[1], summary, "cohesion_pa", 1e-3, "tab:purple")
    truth_line(ax[1], summary, "adhesion_pa", 1e-3, "tab:orange")
    ax[1].set_ylabel("kPa")
    ax[1].set_ylim(-0.5, 1.6 * max(np.nanmax(op["cohesion"]) * 1e-3, 1.0))
    ax[1].legend(loc="upper right", fontsize=7, ncol=2)

    band(ax[2], rt, est["est_phi"], est["sd_phi"], "tab:brown", "internal friction, estimate")
    band(ax[2], rt, est["est_delta"], est["sd_delta"], "tab:gray", "soil-tool friction, estimate")
    band(ax[2], rt, est["est_unit_weight"] * 1e-3, est["sd_unit_weight"] * 1e-3, "tab:cyan",
         "unit weight (kN/m3), estimate")
    truth_line(ax[2], summary, "internal_friction_deg", 1.0, "tab:brown")
    truth_line(ax[2], summary, "soil_tool_friction_deg", 1.0, "tab:gray")
    truth_line(ax[2], summary, "unit_weight_n_per_m3", 1e-3, "tab:cyan")
    ax[2].set_ylabel("degrees; kN/m3")
    ax[2].set_ylim(0, 50)
    ax[2].legend(loc="upper right", fontsize=7, ncol=2)

    te_t, te_v = np.atleast_1d(te["t"]), np.atleast_1d(te["rms_m"]) * 1e3
    ax[3].plot(te_t, te_v, color="tab:green", marker="o" if len(te_t) == 1 else None)
    ax[3].set_ylim(bottom=0.0)
    ax[3].set_ylabel("terrain RMS error (mm)")
    ax[3].set_xlabel("time (s); dashed: the remote's true values (dotted: beyond the change of soil)")
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
        for key, color, marker, name in (("after_1s_direct_rel", "tab:red", "o", "direct reflection"),
                                         ("after_1s_mmt_rel", "tab:blue", "s", "MMT")):
            x, mean, down, up = over_seeds(np, rows, key, 100.0)
            ax[0].errorbar(x, mean, yerr=[down, up], ls=styles[i % 3], color=color,
                           marker=marker, capsize=3, label=f"{name}, loss {loss * 100:.0f} %")
    ax[0].axhline(5.0, color="black", lw=0.8, ls="--", label="target: 5 %")
    ax[0].set_xscale("symlog", linthresh=50)
    ax[0].set_xlabel("round-trip delay (ms)")
    ax[0].set_ylabel("force error after 1 s of cutting (% of the remote's RMS)")
    ax[0].set_title("force error against delay (bars: best to worst seed)")
    ax[0].legend(fontsize=7)
    ax[0].grid(alpha=0.3)
    db = s[s["deadband"] > 0]
    base = full[(full["loss"] == losses[0]) & (full["seed"] == full["seed"][0])]
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
