#!/usr/bin/python3
"""The direction benchmark (issue 31.4) before and after a change: a figure
of the step's p50 against the yaw, both representations, with the target
(1.5x the step at yaw 0), and the table of docs/bench/direction.md.

Usage:
  /usr/bin/python3 tools/plot_direction.py --before B1.json [B2.json ...]
      --after A1.json [A2.json ...] [--json SUMMARY.json] --out FIGURE.png
  /usr/bin/python3 tools/plot_direction.py --from SUMMARY.json --out FIGURE.png

B*.json and A*.json are Google Benchmark JSON files of
`terracut_bench --benchmark_filter=direction/`; each figure is the mean of
the runs' medians (step p50, contact p50, cut p50, p99). --json keeps those
means (a few kB) so that the figure can be drawn again with --from. The
table (markdown) goes to standard output.
"""

import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plot_common import import_plotting, make_fail, save_figure  # noqa: E402

SCRIPT = "plot_direction.py"
REPS = ("surface", "columns")
TARGET_RATIO = 1.5  # issue 31.4: every yaw within 1.5x the step at yaw 0
FIELDS = ("p50_us", "contact_p50_us", "cut_p50_us", "p99_us")

fail = make_fail(SCRIPT)


def medians(path):
    """{(rep, yaw): {field: value}} of one benchmark run's median aggregates."""
    try:
        with open(path) as f:
            data = json.load(f)
    except (OSError, ValueError) as e:
        fail(f"{path}: cannot read the benchmark JSON: {e}")
    out = {}
    for b in data.get("benchmarks", []):
        name = b.get("run_name", "")
        if not name.startswith("direction/") or b.get("aggregate_name") != "median":
            continue
        parts = name.split("/")
        if len(parts) < 3 or not parts[2].startswith("yaw:"):
            fail(f"{path}: unexpected case name '{name}'")
        try:
            key = (parts[1], int(parts[2][4:]))
            out[key] = {k: float(b[k]) for k in FIELDS}
        except (KeyError, ValueError) as e:
            fail(f"{path}: case '{name}' lacks a field or its yaw: {e}")
    if not out:
        fail(f"{path}: no direction/ medians (run with --benchmark_filter=direction/)")
    return out


def mean_of(paths):
    """The mean over the runs of each case's medians (cases in every run only)."""
    runs = [medians(p) for p in paths]
    keys = set(runs[0])
    for r in runs[1:]:
        keys &= set(r)
    return {k: {f: sum(r[k][f] for r in runs) / len(runs) for f in FIELDS} for k in keys}


def table(before, after):
    lines = [
        "| representation | yaw (deg) | before: step p50 (contact + cut), us | after: step p50 (contact + cut), us "
        "| after p99, us | before / after: step / step at yaw 0 |",
        "|---|---|---|---|---|---|",
    ]
    for rep in REPS:
        yaws = sorted(y for (r, y) in after if r == rep and (r, y) in before)
        if (rep, 0) not in after or (rep, 0) not in before:
            fail(f"no yaw-0 case for {rep}: the ratios need it")
        b0, a0 = before[(rep, 0)]["p50_us"], after[(rep, 0)]["p50_us"]
        for y in yaws:
            b, a = before[(rep, y)], after[(rep, y)]
            lines.append(
                f"| {rep} | {y} | {b['p50_us']:.1f} ({b['contact_p50_us']:.1f} + {b['cut_p50_us']:.1f}) "
                f"| {a['p50_us']:.1f} ({a['contact_p50_us']:.1f} + {a['cut_p50_us']:.1f}) | {a['p99_us']:.1f} "
                f"| {b['p50_us'] / b0:.2f}x / {a['p50_us'] / a0:.2f}x |"
            )
    return "\n".join(lines)


def figure(before, after, out, quiet):
    _, plt = import_plotting(fail)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    for ax, rep in zip(axes, REPS):
        yaws = sorted(y for (r, y) in after if r == rep and (r, y) in before)
        for data, label, colour in ((before, "before", "tab:grey"), (after, "after", "tab:blue")):
            ax.plot(yaws, [data[(rep, y)]["p50_us"] for y in yaws], "o-", color=colour, label=f"step, {label}")
            ax.plot(yaws, [data[(rep, y)]["contact_p50_us"] for y in yaws], "s--", color=colour, ms=4,
                    label=f"contact, {label}")
            ax.plot(yaws, [data[(rep, y)]["cut_p50_us"] for y in yaws], "^:", color=colour, ms=4,
                    label=f"cut, {label}")
        target = TARGET_RATIO * after[(rep, 0)]["p50_us"]
        ax.axhline(target, color="tab:red", lw=1, label=f"target: {TARGET_RATIO:g}x the step at yaw 0")
        ax.set_title(f"{rep}, 4096², blade 0.7 x side along its normal")
        ax.set_xlabel("yaw (degrees; 0 = blade along the rows)")
        # 89 and 90 would overlap: every yaw is plotted, 89 is not labelled.
        ax.set_xticks([y for y in yaws if y != 89])
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("p50 per step (us)")
    axes[1].legend(fontsize=8, loc="upper left")
    save_figure(fig, out, fail, quiet, SCRIPT)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--before", nargs="+", help="benchmark JSON files of the code before")
    ap.add_argument("--after", nargs="+", help="benchmark JSON files of the code after")
    ap.add_argument("--from", dest="summary_in", help="a summary written by --json, instead of the runs")
    ap.add_argument("--json", dest="summary_out", help="write the runs' means here")
    ap.add_argument("--out", required=True, help="the figure (PNG)")
    ap.add_argument("--quiet", action="store_true")
    args = ap.parse_args()
    if args.summary_in:
        try:
            with open(args.summary_in) as f:
                s = json.load(f)
            before = {(c["rep"], c["yaw"]): c["before"] for c in s["cases"]}
            after = {(c["rep"], c["yaw"]): c["after"] for c in s["cases"]}
        except (OSError, ValueError, KeyError, TypeError) as e:
            fail(f"{args.summary_in}: cannot read the summary: {e}")
    elif args.before and args.after:
        before, after = mean_of(args.before), mean_of(args.after)
    else:
        fail("give --before and --after benchmark files, or --from a summary")
    if args.summary_out:
        cases = [{"rep": r, "yaw": y, "before": before[(r, y)], "after": after[(r, y)]}
                 for (r, y) in sorted(after) if (r, y) in before]
        try:
            with open(args.summary_out, "w") as f:
                json.dump({"runs_before": args.before, "runs_after": args.after, "cases": cases}, f, indent=1)
        except OSError as e:
            fail(f"{args.summary_out}: cannot write: {e}")
    print(table(before, after))
    figure(before, after, args.out, args.quiet)


if __name__ == "__main__":
    main()
