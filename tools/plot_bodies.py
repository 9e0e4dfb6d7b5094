#!/usr/bin/python3
"""Plot the rigid bodies of a run: heights and tilts over time.

Usage: /usr/bin/python3 tools/plot_bodies.py DIR [--out FILE.png] [--quiet]

Reads DIR/bodies.csv (t,body,name,x,y,z,qw,qx,qy,qz,vx,vy,vz; see
include/terracut/bullet/bodies_csv.hpp) and writes one figure (default
DIR/bodies.png) with, one colour per body:
  - the height y of each body's centre over time, metres;
  - the tilt of each body over time: the angle between its local +Y axis and
    the world's +Y, degrees (a box lying on its side reads 90);
  - the horizontal distance of each body's centre from where it started, metres.
When DIR/contact.csv of the same run is present, the cuts are shaded and named.

Exit codes: 0 done; 2 bad arguments or input folder; 3 numpy or matplotlib missing.
Needs Debian's python3-numpy and python3-matplotlib.
"""
import csv
import os
import sys


def fail(message, code=2):
    print(f"plot_bodies.py: error: {message}", file=sys.stderr)
    sys.exit(code)


try:
    import numpy as np
except ImportError:
    fail("missing Python module 'numpy' (Debian: apt-get install python3-numpy)", 3)
try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    fail("missing Python module 'matplotlib' (Debian: apt-get install python3-matplotlib)", 3)

COLUMNS = ["t", "body", "name", "x", "y", "z", "qw", "qx", "qy", "qz", "vx", "vy", "vz"]


def read_bodies(path):
    """Returns {body index: (name, array of shape (steps, 12))} in file order."""
    bodies = {}
    with open(path, newline="") as f:
        reader = csv.reader(f)
        header = next(reader, None)
        if header != COLUMNS:
            fail(f"{path}: expected the header {','.join(COLUMNS)}, got {header}")
        rows = {}
        for line_no, row in enumerate(reader, start=2):
            if len(row) != len(COLUMNS):
                fail(f"{path}:{line_no}: expected {len(COLUMNS)} values, got {len(row)}")
            try:
                index = int(row[1])
                values = [float(v) for v in row[0:1] + row[3:]]
            except ValueError as e:
                fail(f"{path}:{line_no}: {e}")
            if index not in rows:
                rows[index] = []
                bodies[index] = row[2]
            rows[index].append(values)
    if not rows:
        fail(f"{path}: no rows")
    # Columns of each array: t, x, y, z, qw, qx, qy, qz, vx, vy, vz.
    return {i: (bodies[i], np.array(rows[i])) for i in sorted(rows)}


def read_cuts(path):
    """Returns [(name, t_start, t_end)] from a run's contact.csv, or []."""
    if not os.path.exists(path):
        return []
    spans = []
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        if not reader.fieldnames or "t" not in reader.fieldnames or "cut" not in reader.fieldnames:
            return []
        for row in reader:
            t, cut = float(row["t"]), row["cut"]
            if spans and spans[-1][0] == cut:
                spans[-1][2] = t
            else:
                spans.append([cut, t, t])
    return [tuple(s) for s in spans]


def tilt_deg(q):
    """Angle between the body's +Y axis (rotated by q = w, x, y, z) and world +Y."""
    qx, qz = q[:, 1], q[:, 3]
    up_y = 1.0 - 2.0 * (qx * qx + qz * qz)
    return np.degrees(np.arccos(np.clip(up_y, -1.0, 1.0)))


def main(argv):
    args = [a for a in argv[1:] if not a.startswith("--")]
    quiet = "--quiet" in argv
    out = None
    if "--out" in argv:
        i = argv.index("--out")
        if i + 1 >= len(argv):
            fail("--out needs a file name")
        out = argv[i + 1]
        args = [a for a in args if a != out]
    if len(args) != 1:
        fail("usage: plot_bodies.py DIR [--out FILE.png] [--quiet]")
    folder = args[0]
    path = os.path.join(folder, "bodies.csv")
    if not os.path.isfile(path):
        fail(f"{path} not found (write it with a run that has bodies)")
    out = out or os.path.join(folder, "bodies.png")

    bodies = read_bodies(path)
    cuts = read_cuts(os.path.join(folder, "contact.csv"))

    fig, axes = plt.subplots(3, 1, figsize=(10, 9), sharex=True)
    for index, (name, a) in bodies.items():
        t = a[:, 0]
        axes[0].plot(t, a[:, 2], label=f"{index}: {name}")
        axes[1].plot(t, tilt_deg(a[:, 4:8]))
        axes[2].plot(t, np.hypot(a[:, 1] - a[0, 1], a[:, 3] - a[0, 3]))
    for k, (cut, t0, t1) in enumerate(cuts):
        for ax in axes:
            ax.axvspan(t0, t1, color="0.9" if k % 2 == 0 else "0.82", zorder=0)
        axes[0].text(0.5 * (t0 + t1), 1.0, cut, transform=axes[0].get_xaxis_transform(),
                     ha="center", va="bottom", fontsize=8)
    axes[0].set_ylabel("centre height y (m)")
    axes[0].legend(loc="best", fontsize=8)
    axes[1].set_ylabel("tilt (degrees)")
    axes[2].set_ylabel("horizontal displacement (m)")
    axes[2].set_xlabel("time (s)")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    fig.suptitle(f"Rigid bodies: {os.path.abspath(folder)}", y=0.995, fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    if not quiet:
        print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
