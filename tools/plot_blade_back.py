#!/usr/bin/python3
"""A wobbling blade's back: the floor behind a plunging blade, the edge kept
in its cutting plane against the edge turned about the vertical.

Usage: PYTHONPATH=build/python /usr/bin/python3 tools/plot_blade_back.py
           [--out FILE.png] [--quiet]

Runs, with the terracut module, a 2 m blade spanning a 1 m terrain of dry sand
(a 20 cm layer, 5 mm cells), plunging along a ramp fixed in space (the edge
from 1 to 5 cm deep over 0.3 m of travel along +Z, slope 0.133) at 0.28 m/s
with a hand's tremor (3 mm along the travel, 9 Hz) and wobble (1 degree about
the blade's centre, 10.2 Hz), the trench behind its start already dug to the
ramp. Twice:
- turned about the vertical, the edge level: the half the wobble takes back
  passes over a floor it cut higher (the ramp falls as the blade goes on),
  cuts it with its back and pushes it behind the blade, as a real blade does;
- rolled about its normal at each yaw so that its edge stays in the ramp's
  plane (what `terracut validate`'s check 3.3 does): no part comes back below
  the floor it cut.
It maps the soil above the ramp behind the blade at the end (mm), and prints
the worst and the volume above it.
Default output: docs/images/soil_blade_back.png.

Exit codes: 0 done; 2 bad arguments; 3 numpy, matplotlib or terracut missing.
"""
import math
import os
import sys

from plot_common import import_plotting, import_terracut, make_fail, parse_out_args, save_figure

fail = make_fail("plot_blade_back.py")
np, plt = import_plotting(fail)
terracut = import_terracut(fail)

CELL, SIDE, LAYER = 0.005, 1.0, 0.2
TRAVEL, SPEED = 0.3, 0.28
TREMOR_M, TREMOR_HZ = 0.003, 9.0
WOBBLE_DEG, WOBBLE_HZ = 1.0, 10.2
Y0, SLOPE = LAYER - 0.01, -0.04 / TRAVEL  # the ramp: its height at the start, its slope along +Z
Z_START = 0.5 * SIDE - 0.5 * TRAVEL


def ramp_y(z):
    """The ramp's height (m) at z (m along the travel)."""
    return Y0 + SLOPE * (z - Z_START)


def quat_mul(a, b):
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)


def poses(in_plane):
    """(N, 7) poses, one a step at 1 kHz."""
    steps = int(round(TRAVEL / SPEED * 1000.0))
    seconds = TRAVEL / SPEED
    rows = []
    for i in range(steps + 1):
        s = i / steps
        t = seconds * s
        z = Z_START + TRAVEL * s + TREMOR_M * math.sin(2.0 * math.pi * TREMOR_HZ * t)
        yaw = math.radians(WOBBLE_DEG) * math.sin(2.0 * math.pi * WOBBLE_HZ * t)
        # The edge's direction in plan at this yaw is (cos, -sin): in the
        # plane, it rises SLOPE * (-sin yaw) along it.
        roll = math.atan(SLOPE * -math.sin(yaw)) if in_plane else 0.0
        qy = (math.cos(0.5 * yaw), 0.0, math.sin(0.5 * yaw), 0.0)
        qz = (math.cos(0.5 * roll), 0.0, 0.0, math.sin(0.5 * roll))
        q = quat_mul(qy, qz)
        rows.append([0.5 * SIDE, ramp_y(z), z, *q])
    return np.array(rows)


def run(in_plane):
    """(soil above the ramp behind the blade, m, NaN elsewhere; the edge's z at the end)."""
    n = int(round(SIDE / CELL))
    centres = (np.arange(n) + 0.5) * CELL
    zz = np.repeat(centres[:, None], n, axis=1)
    floor = ramp_y(zz)
    h = np.full((n, n), LAYER)
    h = np.where(zz < Z_START, np.minimum(h, floor), h)  # the trench dug behind the start
    sim = terracut.Simulation.from_heights(h.astype(np.float32), size_m=(SIDE, SIDE), blade_length_m=2.0 * SIDE,
                                           soil_model="flow", soil={"repose_deg": 34.0})
    p = poses(in_plane)
    sim.step(p)
    end_z = p[-1, 2]
    above = np.asarray(sim.heights, dtype=float) - floor
    # Behind the blade: more than a cell and a half behind the edge at the
    # end, and behind every place the wobble took it (its ends swing 1.7 cm).
    behind = zz < end_z - 0.02 - 1.5 * CELL
    return np.where(behind, above, np.nan), end_z


def main(argv):
    out, quiet = parse_out_args(argv, __doc__, os.path.join("docs", "images", "soil_blade_back.png"), fail)
    fig, axes = plt.subplots(1, 2, figsize=(12, 5.2), sharey=True)
    cases = [(False, "turned about the vertical, the edge level"),
             (True, "rolled so that the edge stays in the ramp's plane")]
    for ax, (in_plane, label) in zip(axes, cases):
        above, end_z = run(in_plane)
        mm = above * 1000.0
        worst = np.nanmax(mm)
        volume_l = np.nansum(np.clip(above, 0.0, None)) * CELL * CELL * 1000.0
        if not quiet:
            print(f"{label}: worst {worst:.3f} mm above the ramp behind the blade, {volume_l:.4f} l above it")
        image = ax.imshow(mm, origin="lower", extent=(0.0, SIDE, 0.0, SIDE), cmap="magma", vmin=0.0,
                          vmax=max(1.0, worst))
        ax.axhline(end_z, color="c", lw=1.0, label="edge at the end")
        ax.axhline(Z_START, color="w", lw=0.8, ls="--", label="its start (dug behind)")
        ax.set_ylim(Z_START - 0.1, end_z + 0.05)
        ax.set_title(f"{label}\nworst {worst:.2f} mm, {volume_l:.3f} l above the ramp", fontsize=10)
        ax.set_xlabel("x (m)")
        ax.legend(loc="upper right", fontsize=8)
        fig.colorbar(image, ax=ax, label="soil above the ramp behind the blade (mm)")
    axes[0].set_ylabel("z (m), the travel")
    fig.suptitle("A 2 m blade plunging at 0.28 m/s on 5 mm cells, 3 mm tremor, 1-degree wobble", fontsize=11)
    save_figure(fig, out, fail, quiet, "plot_blade_back.py")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
