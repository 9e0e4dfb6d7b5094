#!/usr/bin/python3
"""Plot one `terracut run` output folder.

Usage: /usr/bin/python3 tools/plot_run.py DIR [--out FILE.png] [--quiet]

Reads DIR/contact.csv, DIR/height.npy, DIR/removed.npy and DIR/summary.json
and writes one figure (default DIR/run.png) with:
  - the contact length over time, one colour per cut;
  - the blade centre's x, y, z over time;
  - the cumulative volume the blade's edge cut over time (with soil that
    flows, a pile cut and pushed again counts again: the title gives what
    it cut from the ground, what it displaced and the net volume moved);
  - the final heights and the removed material as maps (X right, Z up, metres).

Exit codes: 0 done; 2 bad arguments or input folder; 3 numpy or matplotlib missing.
Needs Debian's python3-numpy and python3-matplotlib.
"""
import json
import os
import sys

from plot_common import import_plotting, make_fail, parse_dir_args, save_figure

fail = make_fail("plot_run.py")
np, plt = import_plotting(fail)

PALETTE = ["tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown",
           "tab:pink", "tab:olive", "tab:cyan"]


def parse_args(argv):
    return parse_dir_args(argv, __doc__, "run.png", fail, "plot_run.py")


def need(path):
    if not os.path.isfile(path):
        fail(f"{path} not found (is this a `terracut run --out` folder?)")
    return path


def segments(cuts):
    """(start, stop, name) of each run of equal cut names."""
    out, start = [], 0
    for i in range(1, len(cuts) + 1):
        if i == len(cuts) or cuts[i] != cuts[start]:
            out.append((start, i, cuts[start]))
            start = i
    return out


def main(argv):
    run_dir, out, quiet = parse_args(argv)
    data = np.genfromtxt(need(os.path.join(run_dir, "contact.csv")), delimiter=",", names=True,
                         dtype=None, encoding="utf-8")
    data = np.atleast_1d(data)
    height = np.load(need(os.path.join(run_dir, "height.npy")))
    removed = np.load(need(os.path.join(run_dir, "removed.npy")))
    with open(need(os.path.join(run_dir, "summary.json")), encoding="utf-8") as f:
        summary = json.load(f)
    terrain = summary["inputs"]["terrain"]
    sx, sz = terrain["size_m"]
    ox, _, oz = terrain["origin_m"]
    extent = [ox, ox + sx, oz, oz + sz]

    t = data["t"]
    cuts = np.asarray(data["cut"]).astype(str)
    names = list(dict.fromkeys(cuts))
    colour = {n: PALETTE[i % len(PALETTE)] for i, n in enumerate(names)}

    fig = plt.figure(figsize=(12, 11))
    grid = fig.add_gridspec(3, 2, height_ratios=[1.2, 1.0, 1.6])
    ax_contact = fig.add_subplot(grid[0, :])
    ax_pose = fig.add_subplot(grid[1, 0], sharex=ax_contact)
    ax_volume = fig.add_subplot(grid[1, 1], sharex=ax_contact)
    ax_height = fig.add_subplot(grid[2, 0])
    ax_removed = fig.add_subplot(grid[2, 1])

    # Contact length, one colour per cut (a repeated cut keeps its colour).
    labelled = set()
    for start, stop, name in segments(cuts):
        ax_contact.plot(t[start:stop], data["contact_length"][start:stop], color=colour[name],
                        lw=1.2, label=None if name in labelled else f"cut {name}")
        labelled.add(name)
        if start > 0:
            ax_contact.axvline(t[start], color="gray", ls=":", lw=1)
    ax_contact.set_ylabel("contact length (m)")
    ax_contact.grid(alpha=0.3)
    ax_contact.legend(loc="upper right", fontsize=8, ncol=min(len(names), 6))

    for key, c in (("x", "tab:red"), ("y", "tab:green"), ("z", "tab:blue")):
        ax_pose.plot(t, data[key], color=c, lw=1.2, label=f"blade {key}")
    ax_pose.set_ylabel("blade centre (m)")
    ax_pose.set_xlabel("time (s)")
    ax_pose.grid(alpha=0.3)
    ax_pose.legend(fontsize=8)

    soil = summary.get("soil")
    ax_volume.plot(t, np.cumsum(data["removed_volume"]), color="black", lw=1.2)
    ax_volume.set_ylabel("cut by the edge, each pass (m$^3$)" if soil else "removed volume (m$^3$)")
    ax_volume.set_xlabel("time (s)")
    ax_volume.grid(alpha=0.3)

    # Maps: row r of the arrays runs along +Z, so origin="lower". Both
    # colour scales start at zero (a scale starting at the smallest value
    # would show 0.5 m removed as nothing) and say their unit.
    for ax, layer, label, cmap in ((ax_height, height, "final height (m)", "viridis"),
                                   (ax_removed, removed, "removed material (m)", "magma")):
        top = float(np.nanmax(layer)) if layer.size else 0.0
        image = ax.imshow(layer, origin="lower", extent=extent, cmap=cmap,
                          interpolation="nearest", vmin=0.0, vmax=top if top > 0.0 else 1.0)
        ax.set_xlabel("X (m)")
        ax.set_ylabel("Z (m)")
        ax.set_title(label, fontsize=10)
        fig.colorbar(image, ax=ax, label=label)

    inputs = summary["inputs"]
    res = terrain["resolution"]
    if soil and "cut_from_ground_m3" in soil:
        # Soil that flows is not removed: say what the blade cut out of the
        # ground, what it pushed (a pile pushed on counts at every step) and
        # what is no longer where it was.
        volumes = (f"cut from the ground {soil['cut_from_ground_m3']:.4g} m$^3$, displaced "
                   f"{soil['displaced_volume_m3']:.4g} m$^3$ (each push counted), net moved "
                   f"{soil['net_moved_m3']:.4g} m$^3$")
    else:
        volumes = f"removed {summary['removed_volume_m3']:.4g} m$^3$"
    fig.suptitle(f"{inputs['name']}: {res[0]}x{res[1]} {inputs['representation']}, "
                 f"{inputs['rate_hz']:g} Hz, sequence ({', '.join(inputs['sequence'])});\n{volumes}")
    save_figure(fig, out, fail, quiet, "plot_run.py")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
