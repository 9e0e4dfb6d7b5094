#!/usr/bin/python3
"""Plot one `terracut haptics` output folder.

Usage: /usr/bin/python3 tools/plot_haptics.py DIR [--out FILE.png] [--quiet]

Reads DIR/haptics.csv and DIR/summary.json and writes one figure (default
DIR/haptics.png) with, against loop time:
  - the force sent to the device (device frame x, y, z and magnitude) with
    the safety limit, and shading where the safety limiter acted
    (clamped, rate-limited, watchdog) or the device sample was bad;
  - the force models' world force on the tool (X, Y, Z and magnitude);
  - the contact length and the cut depth;
  - the loop period and compute time (real clock) with the nominal period.

Exit codes: 0 done; 2 bad arguments or input folder; 3 numpy or matplotlib missing.
Needs Debian's python3-numpy and python3-matplotlib.
"""
import json
import os
import sys

from plot_common import import_plotting, make_fail, parse_dir_args, save_figure

fail = make_fail("plot_haptics.py")
np, plt = import_plotting(fail)


def parse_args(argv):
    return parse_dir_args(argv, __doc__, "haptics.png", fail, "plot_haptics.py")


def need(path):
    if not os.path.isfile(path):
        fail(f"{path} not found (is this a `terracut haptics --out` folder?)")
    return path


def spans(mask):
    """(start, stop) index pairs of the runs where mask is true."""
    out, start = [], None
    for i, m in enumerate(mask):
        if m and start is None:
            start = i
        elif not m and start is not None:
            out.append((start, i))
            start = None
    if start is not None:
        out.append((start, len(mask)))
    return out


def shade(ax, t, mask, colour, label):
    """Shades the time spans where mask holds; one legend entry."""
    first = True
    for a, b in spans(mask):
        ax.axvspan(t[a], t[min(b, len(t) - 1)], color=colour, alpha=0.18, lw=0,
                   label=label if first else None)
        first = False


def main(argv):
    run_dir, out, quiet = parse_args(argv)
    try:
        data = np.genfromtxt(need(os.path.join(run_dir, "haptics.csv")), delimiter=",",
                             names=True)
    except ValueError as e:
        fail(f"haptics.csv: cannot read it: {e}")
    data = np.atleast_1d(data)
    if data.size == 0 or "fd_x" not in data.dtype.names:
        fail("haptics.csv holds no ticks")
    with open(need(os.path.join(run_dir, "summary.json")), encoding="utf-8") as f:
        summary = json.load(f)

    t = data["t"]
    fd = np.stack([data["fd_x"], data["fd_y"], data["fd_z"]], axis=1)
    fw = np.stack([data["fw_x"], data["fw_y"], data["fw_z"]], axis=1)
    limits = summary["forces"]["safety_limits"]

    fig, axes = plt.subplots(4, 1, figsize=(11, 12), sharex=True,
                             gridspec_kw={"height_ratios": [1.4, 1.2, 1.0, 0.8]})
    ax_dev, ax_world, ax_contact, ax_time = axes

    # Device force (what the hand feels) and where the limiter acted.
    for i, (name, colour) in enumerate((("x (toward operator)", "tab:red"),
                                        ("y (right)", "tab:green"), ("z (up)", "tab:blue"))):
        ax_dev.plot(t, fd[:, i], color=colour, lw=1.0, label=f"device {name}")
    ax_dev.plot(t, np.linalg.norm(fd, axis=1), color="black", lw=1.2, label="|force|")
    ax_dev.axhline(limits["max_force_n"], color="gray", ls="--", lw=1,
                   label=f"max {limits['max_force_n']:g} N")
    shade(ax_dev, t, data["clamped"] > 0, "tab:red", "clamped")
    shade(ax_dev, t, data["rate_limited"] > 0, "tab:orange", "rate-limited")
    shade(ax_dev, t, data["watchdog"] > 0, "tab:purple", "watchdog")
    shade(ax_dev, t, data["bad_sample"] > 0, "black", "bad sample")
    ax_dev.set_ylabel("force on the device (N)")
    ax_dev.grid(alpha=0.3)
    ax_dev.legend(loc="upper right", fontsize=8, ncol=4)

    # World force from the models.
    for i, (name, colour) in enumerate((("X", "tab:red"), ("Y", "tab:green"), ("Z", "tab:blue"))):
        ax_world.plot(t, fw[:, i], color=colour, lw=1.0, label=f"world {name}")
    ax_world.plot(t, np.linalg.norm(fw, axis=1), color="black", lw=1.2, label="|force|")
    ax_world.set_ylabel("force on the tool, world (N)")
    ax_world.grid(alpha=0.3)
    ax_world.legend(loc="upper right", fontsize=8, ncol=4)

    # Contact length and cut depth.
    ax_contact.plot(t, data["contact_length"], color="tab:brown", lw=1.2, label="contact length")
    ax_contact.set_ylabel("contact length (m)", color="tab:brown")
    ax_contact.grid(alpha=0.3)
    ax_depth = ax_contact.twinx()
    ax_depth.plot(t, data["cut_depth"], color="tab:cyan", lw=1.0, label="cut depth")
    ax_depth.set_ylabel("cut depth (m)", color="tab:cyan")

    # Loop timing (meaningful with the real clock).
    nominal_us = 1e6 / summary["rate_hz"]
    ax_time.plot(t[1:], data["period"][1:] * 1e6, color="tab:gray", lw=0.6, label="period")
    ax_time.plot(t, data["compute"] * 1e6, color="tab:olive", lw=0.6, label="compute")
    ax_time.axhline(nominal_us, color="black", ls=":", lw=1, label=f"nominal {nominal_us:g} us")
    ax_time.set_ylabel("time (us)")
    ax_time.set_xlabel("loop time (s)")
    ax_time.grid(alpha=0.3)
    ax_time.legend(loc="upper right", fontsize=8, ncol=3)

    timing = summary["timing_us"]
    fig.suptitle(
        f"{summary['scenario']}: {summary['device']} device, {summary['forces']['cutting']} "
        f"cutting, {summary['clock']} clock at {summary['rate_hz']:g} Hz\n"
        f"period jitter p99 {timing['period_jitter']['p99']:.1f} us, compute p99 "
        f"{timing['compute']['p99']:.1f} us, {timing['missed_deadlines']} missed deadlines; "
        f"max device force {summary['forces']['max_device_force_n']:.3g} N", fontsize=11)
    save_figure(fig, out, fail, quiet, "plot_haptics.py")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
