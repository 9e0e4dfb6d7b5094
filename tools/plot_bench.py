#!/usr/bin/python3
"""Turns the benchmark suite's JSON into docs/bench/results.md and scaling.png.

Usage (scripts/bench.sh runs it):
  /usr/bin/python3 tools/plot_bench.py --step step.json [--io io.json]
      --machine machine.json --out docs/bench

step.json and io.json are Google Benchmark JSON files written by
terracut_bench and terracut_bench_io; machine.json describes the machine
(cpu, cores, compiler, flags, date). Every figure in the table comes from
those files; the targets are the ones of the performance issue.
"""

import argparse
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

REPS = ("surface", "columns")

# Targets of the performance issue.
TARGET_P50_US = 20.0
TARGET_P99_US = 60.0
TARGET_FLATNESS = 1.3
TARGET_SPEEDUP = 1000.0
TARGET_BYTES_PER_SAMPLE = 12.0
TARGET_RSS_MIB = 1024.0
TARGET_PNG_S = 3.0
TARGET_DIRECTION_RATIO = 1.5  # worst direction's p50 against the blade along X


def load(path):
    with open(path) as f:
        return json.load(f)


def parse(step):
    """Benchmarks by (group, rep, yaw, side) -> entry; skipped ones apart."""
    runs, skipped = {}, []
    # Cases run several times come with a "median" aggregate (of every
    # counter); it stands for the case. Single runs stand for themselves.
    medians = {b["run_name"] for b in step["benchmarks"]
               if b.get("run_type") == "aggregate" and b.get("aggregate_name") == "median"}
    for b in step["benchmarks"]:
        name = b["run_name"] if "run_name" in b else b["name"]
        if name in medians:
            if b.get("run_type") != "aggregate" or b.get("aggregate_name") != "median":
                continue
        elif b.get("run_type") != "iteration":
            continue
        parts = name.split("/")
        group, rep = parts[0], parts[1]
        fields = dict(p.split(":", 1) for p in parts[2:] if ":" in p and not p.startswith("iterations"))
        side = int(fields.get("side", 0))
        # The tilt cases keep their tilt where the others keep their yaw.
        yaw = int(fields.get("yaw", fields.get("tilt", 0)))
        if b.get("error_occurred"):
            skipped.append((group, rep, side, b.get("error_message", "")))
            continue
        runs[(group, rep, yaw, side)] = b
    return runs, skipped


def series(runs, group, rep, yaw=0, key="p50_us"):
    out = sorted((side, b[key]) for (g, r, y, side), b in runs.items()
                 if g == group and r == rep and y == yaw and key in b)
    return [s for s, _ in out], [v for _, v in out]


def loglog_slope(xs, ys):
    """Least-squares slope of log(y) against log(x)."""
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    num = sum((a - mx) * (b - my) for a, b in zip(lx, ly))
    den = sum((a - mx) ** 2 for a in lx)
    return num / den


def fmt_us(v):
    if v >= 1e6:
        return f"{v / 1e6:.2f} s"
    if v >= 1e3:
        return f"{v / 1e3:.2f} ms"
    return f"{v:.1f} us"


def verdict(ok):
    return "met" if ok else "**missed**"


def plot(runs, machine, path):
    fig, ax = plt.subplots(figsize=(8.5, 6.0))
    # One colour per representation; solid: ours with a full-width blade,
    # dotted: ours with a 256-cell blade, dashed: the paper's brute force.
    styles = {
        ("full_width", "surface"): ("C0", "o", "-", "ours, full-width blade, surface"),
        ("full_width", "columns"): ("C1", "s", "-", "ours, full-width blade, columns"),
        ("blade256", "surface"): ("C0", "o", ":", "ours, 256-cell blade, surface"),
        ("blade256", "columns"): ("C1", "s", ":", "ours, 256-cell blade, columns"),
        ("brute_force", "surface"): ("C0", "^", "--", "brute force (the paper's), full width, surface"),
        ("brute_force", "columns"): ("C1", "v", "--", "brute force (the paper's), full width, columns"),
    }
    all_sides = []
    for (group, rep), (color, marker, line, label) in styles.items():
        xs, ys = series(runs, group, rep)
        if not xs:
            continue
        all_sides += xs
        ax.plot(xs, ys, color=color, marker=marker, linestyle=line, label=label)
    # Reference slopes through the 64^2 full-width surface point.
    xs, ys = series(runs, "full_width", "surface")
    if xs:
        lo, hi = min(all_sides), max(all_sides)
        x0, y0 = xs[0], ys[0]
        for power, text in ((1, "∝ side"), (2, "∝ side² (area)")):
            ax.plot([lo, hi], [y0 * (lo / x0) ** power, y0 * (hi / x0) ** power],
                    color="0.6", linewidth=0.8, linestyle="-.")
            ax.annotate(text, (hi, y0 * (hi / x0) ** power), fontsize=8, color="0.4",
                        ha="right", va="bottom")
    ax.axhline(1000.0, color="0.3", linewidth=0.8)
    ax.annotate("1 ms: the 1 kHz budget", (min(all_sides or [64]), 1000.0), fontsize=8,
                color="0.3", va="bottom")
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    sides = sorted(set(all_sides))
    ax.set_xticks(sides)
    ax.set_xticklabels([str(x) for x in sides])
    ax.minorticks_off()
    ax.set_xlabel("terrain side (samples; the terrain is side x side, 1 mm cells)")
    ax.set_ylabel("time per 1 kHz step, median (us)")
    ax.set_title("contact + swept cut per step, blade cutting through material\n"
                 f"{machine.get('cpu', '?')}, {machine.get('cores', '?')} cores, "
                 f"{machine.get('compiler', '?')}", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--step", required=True)
    ap.add_argument("--io")
    ap.add_argument("--machine", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--command", default="scripts/bench.sh")
    args = ap.parse_args()

    step = load(args.step)
    machine = load(args.machine)
    io = load(args.io) if args.io and os.path.exists(args.io) else None
    runs, skipped = parse(step)
    os.makedirs(args.out, exist_ok=True)

    lines = []
    w = lines.append
    w("# Benchmark results")
    w("")
    w(f"Written by `{args.command}` (tools/plot_bench.py) from the Google Benchmark JSON next to")
    w("this file; do not edit by hand. What the cases are and where the time goes:")
    w("[docs/performance.md](../performance.md).")
    w("")
    w("## Machine")
    w("")
    w(f"- CPU: {machine.get('cpu', '?')} ({machine.get('cores', '?')} cores, "
      f"{machine.get('threads_per_core', '?')} thread(s) per core)")
    w(f"- Compiler: {machine.get('compiler', '?')}, flags `{machine.get('flags', '?')}`")
    w(f"- Kernel: {machine.get('kernel', '?')}; date: {machine.get('date', '?')}")
    ctx = step.get("context", {})
    if "load_avg" in ctx:
        w(f"- Load average when the suite started: {', '.join(f'{x:.2f}' for x in ctx['load_avg'])} "
          "(other work on the machine shows in p99 and max)")
    w("")
    w("Each step case runs thousands of consecutive steps (a 0.6 mm move at 1 kHz, i.e. 0.6 m/s)")
    w("and times every step on its own; p50/p99/max are over those steps. The cases with targets")
    w("(the 4096² headline and the 256-cell blade) run three times and show the median of the")
    w("three runs' figures.")
    w("")

    # ---- Targets
    w("## Targets")
    w("")
    w("| figure | target | measured | |")
    w("|---|---|---|---|")
    for rep in REPS:
        for yaw in (0, 30):
            b = runs.get(("headline", rep, yaw, 4096))
            if not b:
                continue
            ok = b["p50_us"] <= TARGET_P50_US and b["p99_us"] <= TARGET_P99_US
            what = "blade along X" if yaw == 0 else f"blade yawed {yaw} degrees (diagonal traversal)"
            w(f"| step, full-width blade, 4096², {rep}, {what} | p50 <= {TARGET_P50_US:g} us, "
              f"p99 <= {TARGET_P99_US:g} us | p50 {b['p50_us']:.1f} us, p99 {b['p99_us']:.1f} us | {verdict(ok)} |")
    for rep in REPS:
        dirs = sorted((y, b) for (g, r, y, side), b in runs.items() if g == "direction" and r == rep)
        if not dirs:
            continue
        for yaw, b in dirs:
            ok = b["p50_us"] <= TARGET_P50_US and b["p99_us"] <= TARGET_P99_US
            w(f"| step, 0.7 x 4096 mm blade along its normal, 4096², {rep}, yaw {yaw} degrees | "
              f"p50 <= {TARGET_P50_US:g} us, p99 <= {TARGET_P99_US:g} us | p50 {b['p50_us']:.1f} us, "
              f"p99 {b['p99_us']:.1f} us | {verdict(ok)} |")
        base = dict(dirs).get(0)
        if base:
            worst_yaw, worst = max(dirs, key=lambda yb: yb[1]["p50_us"])
            ratio = worst["p50_us"] / base["p50_us"]
            w(f"| worst direction against the blade along X, {rep} | <= {TARGET_DIRECTION_RATIO:g}x | "
              f"{ratio:.2f}x (yaw {worst_yaw}: {worst['p50_us']:.1f} vs {base['p50_us']:.1f} us) | "
              f"{verdict(ratio <= TARGET_DIRECTION_RATIO)} |")
    for rep in REPS:
        xs, ys = series(runs, "blade256", rep)
        if 256 in xs and 8192 in xs:
            ratio = ys[xs.index(8192)] / ys[xs.index(256)]
            w(f"| step, 256-cell blade, 8192² vs 256², {rep} | <= {TARGET_FLATNESS}x | "
              f"{ratio:.2f}x ({ys[xs.index(256)]:.2f} -> {ys[xs.index(8192)]:.2f} us) | "
              f"{verdict(ratio <= TARGET_FLATNESS)} |")
    for rep in REPS:
        xs, ys = series(runs, "full_width", rep)
        pts = [(x, y) for x, y in zip(xs, ys) if x >= 256]
        if len(pts) >= 3:
            slope = loglog_slope([p[0] for p in pts], [p[1] for p in pts])
            w(f"| step, full-width blade, 256² .. 8192², {rep}: log-log slope of time vs side | "
              f"1 (linear in side; 2 would be area) | {slope:.2f} | {verdict(0.8 <= slope <= 1.2)} |")
    for rep in REPS:
        ours = runs.get(("full_width", rep, 0, 1024))
        brute = runs.get(("brute_force", rep, 0, 1024))
        if ours and brute:
            speedup = brute["p50_us"] / ours["p50_us"]
            w(f"| speed-up over the paper's brute force, full-width blade, 1024², {rep} | "
              f">= {TARGET_SPEEDUP:g}x | {speedup:,.0f}x ({fmt_us(brute['p50_us'])} vs "
              f"{fmt_us(ours['p50_us'])}) | {verdict(speedup >= TARGET_SPEEDUP)} |")
    for rep in REPS:
        b = runs.get(("memory", rep, 0, 8192))
        if b:
            ok = b["bytes_per_sample"] <= TARGET_BYTES_PER_SAMPLE + 0.1 and b["rss_mib"] < TARGET_RSS_MIB
            w(f"| memory of a run, 8192², {rep} | <= {TARGET_BYTES_PER_SAMPLE:g} bytes/sample + constant, "
              f"< 1 GiB | {b['bytes_per_sample']:.3f} bytes/sample (layers: "
              f"{b['grid_bytes_per_sample']:g}), constant {b['constant_mib']:.1f} MiB, "
              f"RSS {b['rss_mib']:.0f} MiB | {verdict(ok)} |")
    if io:
        for b in io["benchmarks"]:
            if b.get("run_type") != "iteration" or "read_resample" not in b["name"]:
                continue
            secs = b["real_time"] / {"ms": 1e3, "us": 1e6, "ns": 1e9, "s": 1.0}[b["time_unit"]]
            w(f"| read + resample an 8192² 16-bit PNG to {int(b['target_side'])}² | < {TARGET_PNG_S:g} s | "
              f"{secs:.2f} s | {verdict(secs < TARGET_PNG_S)} |")
    w("")

    # ---- Detail tables
    def table(title, group, yaws=(0,), note=None):
        rows = [(k, b) for k, b in runs.items() if k[0] == group and k[2] in yaws]
        if not rows:
            return
        w(f"## {title}")
        w("")
        if note:
            w(note)
            w("")
        w("| representation | yaw | side | p50 | p99 | max | contact p50 | cut p50 | cells/step | ns/cell |")
        w("|---|---|---|---|---|---|---|---|---|---|")
        for (g, rep, yaw, side), b in sorted(rows, key=lambda kv: (kv[0][1], kv[0][2], kv[0][3])):
            contact = fmt_us(b["contact_p50_us"]) if "contact_p50_us" in b else "-"
            cut = fmt_us(b["cut_p50_us"]) if "cut_p50_us" in b else "-"
            w(f"| {rep} | {yaw} | {side} | {fmt_us(b['p50_us'])} | {fmt_us(b['p99_us'])} | "
              f"{fmt_us(b['max_us'])} | {contact} | {cut} | {b['cells_per_step']:,.0f} | {b['ns_per_cell']:.2f} |")
        w("")

    table("Full-width blade on 4096² (the headline case)", "headline", yaws=(0, 30))
    table("Every direction: a 0.7 x side blade moving along its normal, 4096²", "direction",
          yaws=(0, 10, 30, 45, 60, 90),
          note="The blade (2867 mm) crosses the middle of the terrain along its own normal at "
               "0.6 mm per step; yaw is its rotation about +Y from along X.")
    table("Tilted blade: 400 cells, rotated about its travel (the yaw column is the tilt)", "tilt",
          yaws=(0, 20))
    table("256-cell blade, terrain side 256 .. 8192", "blade256")
    table("Full-width blade, terrain side 64 .. 8192", "full_width")
    table("The paper's brute force (every cell, every step), full-width blade", "brute_force",
          note="Contact by the slab method against every column (or every triangle) and the cut "
               "tested at every sample. Sides whose step would take more than about 1 s are skipped "
               "(listed below).")
    if skipped:
        w("Skipped: " + "; ".join(f"{g} {r} {s}²: {m}" for g, r, s, m in skipped))
        w("")
    mem = [(k, b) for k, b in runs.items() if k[0] == "memory"]
    if mem:
        w("## Memory")
        w("")
        w("| representation | side | bytes/sample (RSS) | grid layers | constant | RSS | peak RSS |")
        w("|---|---|---|---|---|---|---|")
        for (g, rep, yaw, side), b in sorted(mem):
            w(f"| {rep} | {side} | {b['bytes_per_sample']:.3f} | {b['grid_bytes_per_sample']:g} | "
              f"{b['constant_mib']:.1f} MiB | {b['rss_mib']:.0f} MiB | {b['peak_rss_mib']:.0f} MiB |")
        w("")
    if io:
        w("## Loading a terrain image")
        w("")
        w("| case | time (mean of 3) |")
        w("|---|---|")
        for b in io["benchmarks"]:
            if b.get("run_type") != "iteration":
                continue
            secs = b["real_time"] / {"ms": 1e3, "us": 1e6, "ns": 1e9, "s": 1.0}[b["time_unit"]]
            w(f"| {b['name'].split('/iterations')[0]} | {secs:.2f} s |")
        w("")
    w("## Scaling plot")
    w("")
    w("![time per step against terrain side](scaling.png)")
    w("")

    with open(os.path.join(args.out, "results.md"), "w") as f:
        f.write("\n".join(lines))
    plot(runs, machine, os.path.join(args.out, "scaling.png"))
    print(f"wrote {os.path.join(args.out, 'results.md')} and scaling.png")


if __name__ == "__main__":
    sys.exit(main())
