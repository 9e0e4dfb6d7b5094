#!/usr/bin/python3
"""When the remote's soil estimate reaches the operator, and the force error before and after.

Usage: /usr/bin/python3 tools/plot_mmt_arrival.py --out FILE.png DIR [DIR ...] [--quiet]

Each DIR is a single `terracut mmt SCENARIO --out DIR` run (operator.csv,
remote.csv, summary.json). Every operator tick is paired with the remote's
first tick that followed its command (and the arm's lag later, as the run's
summary says: force_error.aligned_after_s), as `terracut mmt` compares them,
and drawn at that remote tick's time. On the remote's clock:

  - cut: the remote's first tick that cuts with a force sample;
  - identifiable: its first tick whose estimate has every field identifiable;
  - within 5 %: its first tick whose estimate predicts the horizontal force
    it measures within 5 %;
  - arrived: the first operator tick whose material differs from the one it
    started with (an estimate arrived), at the time of its remote tick;
  - adopted: the first tick from then on whose material blend is complete;
  - window: the start of the "after 1 s of cutting" figures (from_s).

Printed, one line per DIR: those times, and the MMT force error (RMS of
|F_operator - F_remote|, in % of the remote's force RMS over the same
ticks) in the window before the estimate was adopted, after it, and over
the whole window (the run's figure). The figure: per DIR, the magnitude of
the MMT error and of the remote's force against the remote's time, with
those times marked.

Exit codes: 0 done; 2 bad arguments or input folder; 3 numpy or matplotlib missing.
"""
import json
import os
import sys

from plot_common import import_plotting, make_fail, parse_dirs_args, save_figure

fail = make_fail("plot_mmt_arrival.py")
np, plt = import_plotting(fail)

ALL_FIELDS = 0b11111


def read(folder, name):
    path = os.path.join(folder, name)
    if not os.path.isfile(path):
        fail(f"{path} not found (a `terracut mmt SCENARIO --out` folder?)")
    if name.endswith(".json"):
        with open(path) as f:
            return json.load(f)
    return np.genfromtxt(path, delimiter=",", names=True)


def first(t, mask):
    i = np.flatnonzero(mask)
    return float(t[i[0]]) if len(i) else float("nan")


def rel(err, ref):
    return 100.0 * np.sqrt(np.mean(err ** 2)) / np.sqrt(np.mean(ref ** 2)) if len(ref) else float("nan")


def analyse(folder):
    op, rm, js = read(folder, "operator.csv"), read(folder, "remote.csv"), read(folder, "summary.json")
    rate = 1.0 / np.median(np.diff(op["t"]))
    lag = int(round(js["force_error"]["aligned_after_s"] * rate))
    from_s = js["force_error_after_1s"]["from_s"]
    # The pairing of compare_records: op tick i -> remote's first active tick
    # with command_sequence >= its own, plus the lag.
    seq_rm = np.where(rm["active"] > 0, rm["command_sequence"], -1).astype(np.int64)
    seq_best = np.maximum.accumulate(seq_rm)
    j = np.searchsorted(seq_best, op["command_sequence"].astype(np.int64), side="left") + lag
    ok = j < len(rm)
    op, j = op[ok], j[ok]
    r = rm[j]
    f_op = np.stack([op["fx"], op["fy"], op["fz"]], axis=1)
    f_rm = np.stack([r["fx"], r["fy"], r["fz"]], axis=1)
    err = np.linalg.norm(f_op - f_rm, axis=1)
    ref = np.linalg.norm(f_rm, axis=1)
    t = r["t"]
    felt = (np.linalg.norm(f_op, axis=1) > 0) | (ref > 0) | \
        (np.linalg.norm(np.stack([op["remote_fx"], op["remote_fy"], op["remote_fz"]], axis=1), axis=1) > 0)
    cutting = (rm["active"] > 0) & (rm["cut_depth"] > 0) & (rm["estimate_error"] >= 0)
    cut_s = first(rm["t"], cutting)
    ident_s = first(rm["t"], cutting & ((rm["identifiable"].astype(np.int64) & ALL_FIELDS) == ALL_FIELDS))
    within_s = first(rm["t"], cutting & (rm["estimate_error"] >= 0) & (rm["estimate_error"] < 0.05))
    m0 = np.array([op[k][0] for k in ("unit_weight", "cohesion", "adhesion", "phi", "delta")])
    moved = np.zeros(len(op), bool)
    for k, v in zip(("unit_weight", "cohesion", "adhesion", "phi", "delta"), m0):
        moved |= op[k] != v
    arrived_i = np.flatnonzero(moved)
    arrived_s = float(t[arrived_i[0]]) if len(arrived_i) else float("nan")
    adopted_s = float("nan")
    if len(arrived_i):
        done = np.flatnonzero((np.arange(len(op)) >= arrived_i[0]) & (op["material_blend"] >= 1.0))
        adopted_s = float(t[done[0]]) if len(done) else float("nan")
    window = felt & (t >= from_s) if from_s >= 0 else np.zeros(len(t), bool)
    left = js["force_error_after_1s"]
    if left["left_out_to_s"] > left["left_out_from_s"]:
        window &= ~((t >= left["left_out_from_s"]) & (t < left["left_out_to_s"]))
    before = window & ~(t >= adopted_s)
    after = window & (t >= adopted_s)
    return {
        "name": os.path.basename(os.path.normpath(folder)),
        "rtt_ms": 1e3 * js["round_trip"]["emulated_s"] if "round_trip" in js else float("nan"),
        "cut": cut_s, "ident": ident_s, "within": within_s, "arrived": arrived_s,
        "adopted": adopted_s, "from": from_s,
        "before_s": before.sum() / rate, "before": rel(err[before], ref[before]),
        "after_s": after.sum() / rate, "after": rel(err[after], ref[after]),
        "all": rel(err[window], ref[window]),
        "t": t, "err": err, "ref": ref,
    }


def main(argv):
    folders, out, quiet = parse_dirs_args(argv, __doc__, fail, "plot_mmt_arrival.py")
    runs = [analyse(f) for f in folders]
    print("run | cut s | identifiable | within 5 % | arrived | adopted | window from | "
          "before adoption: s, % | after: s, % | window %")
    for a in runs:
        print(f"{a['name']} | {a['cut']:.3f} | {a['ident'] - a['cut']:+.3f} | {a['within'] - a['cut']:+.3f} | "
              f"{a['arrived'] - a['cut']:+.3f} | {a['adopted'] - a['cut']:+.3f} | {a['from'] - a['cut']:+.3f} | "
              f"{a['before_s']:.3f}, {a['before']:.1f} | {a['after_s']:.3f}, {a['after']:.2f} | {a['all']:.1f}")
    fig, axes = plt.subplots(len(runs), 1, figsize=(9, 2.6 * len(runs)), squeeze=False)
    for ax, a in zip(axes[:, 0], runs):
        ax.plot(a["t"], a["ref"], color="k", lw=1, label="|F| remote")
        ax.plot(a["t"], a["err"], color="tab:blue", lw=1, label="|F operator - F remote| (MMT)")
        for key, colour, label in (("cut", "0.5", "remote cuts"), ("within", "tab:green", "estimate within 5 %"),
                                   ("arrived", "tab:orange", "arrives"), ("adopted", "tab:red", "adopted"),
                                   ("from", "k", "window from")):
            if np.isfinite(a[key]):
                ax.axvline(a[key], color=colour, ls="--" if key != "from" else ":", lw=1, label=label)
        ax.set_title(f"{a['name']}: window {a['all']:.1f} % = {a['before_s']:.2f} s before adoption at "
                     f"{a['before']:.0f} % + {a['after_s']:.2f} s after at {a['after']:.1f} %", fontsize=9)
        ax.set_ylabel("N")
        t0 = a["cut"] - 0.3 if np.isfinite(a["cut"]) else a["t"][0]
        ax.set_xlim(t0, a["t"][-1])
        ax.legend(fontsize=7, loc="upper right")
    axes[-1, 0].set_xlabel("remote time, s")
    save_figure(fig, out, fail, quiet, "plot_mmt_arrival.py")


if __name__ == "__main__":
    main(sys.argv)
