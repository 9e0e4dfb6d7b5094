#!/usr/bin/python3
"""Figures of `terracut validate` (the soil's physical checks).

Usage: /usr/bin/python3 tools/plot_validate.py DIR [--quiet]

DIR is the output folder of `terracut validate` (it reads DIR/validate.json
and the CSV and .npy files it names) and receives:

  soil_cone.png          the collapsed columns (repose 34 and 45 degrees): radial
                         profiles along 16 directions against the ideal cone at the
                         repose slope, the flank angle per direction with its band,
                         and the cone from above
  soil_slope.png         the 30- and 40-degree ramps before and after relaxing at
                         repose 34, along X and along the diagonal
  soil_bulldozing.png    pile volume against the mass balance w d x, centre-line
                         peak against the 2-D wedge sqrt(2 d x tan), centre-line
                         profiles against the wedge, and the heights from above
  soil_conservation.png  relative volume error at every step of the mixed run,
                         with its tolerance

Exit codes: 0 done; 2 bad arguments or input folder; 3 numpy or matplotlib missing.
Needs Debian's python3-numpy and python3-matplotlib.
"""
import os
import sys

from plot_common import FigureFolder, import_plotting, make_fail, parse_folder_args

fail = make_fail("plot_validate.py")
np, plt = import_plotting(fail)
from matplotlib.colors import TwoSlopeNorm  # noqa: E402 (after the checked import)

FILES = FigureFolder(np, plt, fail, "plot_validate.py", "terracut validate", dpi=110)
WIDTH_COLOURS = {1.0: "tab:blue", 2.0: "tab:red"}


def read_csv(out_dir, name):
    return FILES.read_csv(os.path.join(out_dir, name))


def read_npy(out_dir, name):
    return FILES.read_npy(os.path.join(out_dir, name))


def direction_style(direction):
    """Axes, diagonals and the directions between them, told apart."""
    off = direction % 90.0
    if off == 0.0:
        return dict(color="tab:blue", label="along an axis (0, 90, ...)")
    if off == 45.0:
        return dict(color="tab:green", label="along a diagonal (45, 135, ...)")
    return dict(color="tab:gray", alpha=0.8, label="22.5 deg off them")


def cone(out_dir, meta):
    c = meta["cone"]
    profiles = read_csv(out_dir, c["profiles_csv"])
    flanks = read_csv(out_dir, c["flanks_csv"])
    runs = c["runs"]
    fig, axes = plt.subplots(len(runs), 3, figsize=(16, 5.2 * len(runs)),
                             gridspec_kw=dict(width_ratios=[1.25, 1.0, 0.95]))
    axes = np.atleast_2d(axes)
    for row, run in zip(axes, runs):
        repose = run["repose_deg"]
        tan = np.tan(np.radians(repose))
        # Profiles by direction.
        ax = row[0]
        mine = profiles[profiles["repose_deg"] == repose]
        seen = set()
        for direction in np.unique(mine["direction_deg"]):
            p = mine[mine["direction_deg"] == direction]
            style = direction_style(direction)
            label = style.pop("label")
            ax.plot(p["r_m"], p["h_m"], lw=1.0, label=None if label in seen else label, **style)
            seen.add(label)
        r = np.linspace(0.0, run["ideal_radius_m"], 50)
        ax.plot(r, run["ideal_peak_m"] - tan * r, color="black", ls="--", lw=1.4,
                label=f"ideal cone of the same volume at the repose slope ({repose:g} deg)")
        ax.axvspan(0, c["column_radius_m"], color="tab:brown", alpha=0.08,
                   label=f"the column before: r < {c['column_radius_m']:g} m, "
                         f"{c['column_height_m']:.2g} m tall")
        ax.set_xlim(0, 0.45)
        ax.set_ylim(0, 1.15 * max(run["ideal_peak_m"], float(mine["h_m"].max())))
        ax.set_xlabel("distance from the column's axis r (m)")
        ax.set_ylabel("height (m)")
        ax.set_title(f"repose {repose:g} deg: radial profiles along 16 directions", fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
        # Flank angle per direction with its band.
        ax = row[1]
        f = flanks[flanks["repose_deg"] == repose]
        d = f["direction_deg"]
        ax.bar(d, f["max_deg"] - f["min_deg"], bottom=f["min_deg"], width=14.0,
               color="tab:green", alpha=0.2, label="allowed: stencil band + 2 % of tan")
        ax.axhline(repose, color="black", ls="--", lw=1.2, label=f"repose angle {repose:g} deg")
        ok = f["pass"] == 1
        ax.plot(d[ok], f["measured_deg"][ok], "o", color="tab:blue", label="measured flank (pass)")
        if (~ok).any():
            ax.plot(d[~ok], f["measured_deg"][~ok], "x", color="tab:red", ms=9,
                    label="measured flank (FAIL)")
        ax.set_xticks(np.arange(0, 360, 45))
        ax.set_xlim(-15, 352.5)
        ax.set_xlabel("direction from +X towards +Z (deg)")
        ax.set_ylabel("flank angle (deg)")
        ax.set_title("flank angle: least-squares slope between "
                     f"{c['flank_fraction'][1]:.0%} and {c['flank_fraction'][0]:.0%} of the peak",
                     fontsize=10)
        ax.set_ylim(repose - 4, repose + 4.5)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
        # From above.
        ax = row[2]
        h = read_npy(out_dir, run["height_npy"])
        n = h.shape[0]
        half = 0.5 * n * c["cell_m"]
        extent = [-half, half, -half, half]
        image = ax.imshow(h, origin="lower", extent=extent, cmap="viridis",
                          interpolation="nearest")
        levels = np.linspace(0.05, 0.95, 7) * float(h.max())
        ax.contour(h, levels=levels, origin="lower", extent=extent, colors="white",
                   linewidths=0.6)
        ax.add_patch(plt.Circle((0, 0), run["ideal_radius_m"], fill=False, ls="--", color="red",
                                lw=1.0))
        ax.set_xlim(-0.45, 0.45)
        ax.set_ylim(-0.45, 0.45)
        ax.set_xlabel("X (m)")
        ax.set_ylabel("Z (m)")
        ax.set_title("from above; dashed: the ideal cone's toe", fontsize=10)
        fig.colorbar(image, ax=ax, label="height (m)", shrink=0.85)
    FILES.save(fig, out_dir, "soil_cone.png",
               "Check 1: a column of sand (1 cm cells) collapses into a cone at the angle of "
               "repose")


def slope(out_dir, meta):
    s = meta["slope"]
    profiles = read_csv(out_dir, s["profiles_csv"])
    tan = np.tan(np.radians(s["repose_deg"]))
    cases = np.asarray(profiles["case"]).astype(str)
    fig, axes = plt.subplots(1, 2, figsize=(13, 5), sharey=True)
    for ax, along in zip(axes, ["x", "diagonal"]):
        for angle, colour in [("30", "tab:blue"), ("40", "tab:red")]:
            name = f"ramp{angle}_{along}"
            p = profiles[cases == name]
            ax.plot(p["s_m"], p["initial_m"], color=colour, ls=":", lw=1.4,
                    label=f"{angle}-deg ramp before")
            ax.plot(p["s_m"], p["final_m"], color=colour, lw=1.6,
                    label=f"{angle}-deg ramp after relaxing"
                          + (" (unchanged)" if angle == "30" else ""))
            if angle == "40":
                mid = len(p) // 2
                s0, h0 = p["s_m"][mid], p["final_m"][mid]
                ss = np.array([p["s_m"][0], p["s_m"][-1]])
                ax.plot(ss, h0 + tan * (ss - s0), color="black", ls="--", lw=1.0,
                        label=f"repose slope {s['repose_deg']:g} deg through its middle")
        ax.axvspan(0.25 * float(p["s_m"][-1]), 0.75 * float(p["s_m"][-1]), color="gray",
                   alpha=0.08, label="fitted: the middle half")
        ax.set_xlabel(f"distance along {'the diagonal' if along == 'diagonal' else 'X'} (m)")
        ax.set_title(f"ramps along {'the diagonal' if along == 'diagonal' else 'X'}", fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper left")
    axes[0].set_ylabel("height (m)")
    FILES.save(fig, out_dir, "soil_slope.png",
               f"Check 2: slopes below and above the repose angle ({s['repose_deg']:g} deg), "
               "1 cm cells; the grid's edges are walls")


def bulldozing(out_dir, meta):
    b = meta["bulldozing"]
    pile = read_csv(out_dir, b["pile_csv"])
    centre = read_csv(out_dir, b["centre_csv"])
    d = b["depth_m"]
    tan = np.tan(np.radians(b["repose_deg"]))
    runs = b["runs"]
    fig = plt.figure(figsize=(17, 10.5))
    grid = fig.add_gridspec(2, 3)
    ax_v, ax_h, ax_p = (fig.add_subplot(grid[0, k]) for k in range(3))
    x_line = np.linspace(0, b["push_m"], 200)
    for run in runs:
        w = run["width_m"]
        colour = WIDTH_COLOURS.get(w, "tab:green")
        p = pile[pile["width_m"] == w]
        # Volume.
        ax_v.plot(x_line, w * d * x_line, color=colour, ls="--", lw=1.2,
                  label=f"w d x, w = {w:g} m (mass balance)")
        ax_v.plot(p["pushed_m"], p["pile_m3"], "o-", color=colour, ms=4, lw=1.3,
                  label=f"pile ahead of the {w:g} m blade")
        ax_v.plot(p["pushed_m"], p["windrow_m3"], "s:", color=colour, ms=3, lw=1.0,
                  label="windrows beside it")
        ax_v.plot(p["pushed_m"], p["refill_m3"], "^:", color=colour, ms=3, lw=0.8, alpha=0.7,
                  label="back in the trench")
        # Peak.
        ok = (p["centre_peak_m"] >= p["wedge_min_m"]) & (p["centre_peak_m"] <= p["wedge_max_m"])
        ax_h.plot(p["pushed_m"], p["centre_peak_m"], "-", color=colour, lw=1.0, alpha=0.6)
        ax_h.plot(p["pushed_m"][ok], p["centre_peak_m"][ok], "o", color=colour, ms=5,
                  label=f"{w:g} m blade: centre-line peak (in band)")
        if (~ok).any():
            ax_h.plot(p["pushed_m"][~ok], p["centre_peak_m"][~ok], "x", color=colour, ms=7,
                      label=f"{w:g} m blade: centre-line peak (outside the band)")
    p0 = pile[pile["width_m"] == runs[0]["width_m"]]
    ax_h.plot(x_line, np.sqrt(2 * d * x_line * tan), color="black", ls="--", lw=1.4,
              label="2-D wedge h = sqrt(2 d x tan(repose))")
    ax_h.fill_between(p0["pushed_m"], p0["wedge_min_m"], p0["wedge_max_m"], color="gray",
                      alpha=0.2, label="band: -tan dx, +1 % + tan dx")
    ax_v.set_xlabel("distance pushed x (m)")
    ax_v.set_ylabel("volume (m$^3$)")
    ax_v.set_title(f"volume above the layer, d = {d:g} m", fontsize=10)
    ax_v.grid(alpha=0.3)
    ax_v.legend(fontsize=7.5, loc="upper left")
    ax_h.set_xlabel("distance pushed x (m)")
    ax_h.set_ylabel("pile height above the layer (m)")
    ax_h.set_title("centre-line peak against the 2-D wedge", fontsize=10)
    ax_h.grid(alpha=0.3)
    ax_h.legend(fontsize=7.5, loc="upper left")
    # Centre-line profiles of the widest blade against the wedge's triangle.
    w = runs[-1]["width_m"]
    mine = centre[centre["width_m"] == w]
    pushes = np.unique(mine["pushed_m"])
    picks = [pushes[np.argmin(np.abs(pushes - target))] for target in (0.25, 0.5, 0.75, 1.0)]
    colours = ["tab:cyan", "tab:blue", "tab:purple", "tab:red"]
    for x, colour in zip(picks, colours):
        q = mine[mine["pushed_m"] == x]
        ax_p.plot(q["s_m"], q["h_m"] - b["layer_m"], color=colour, lw=1.4,
                  label=f"x = {x:.2f} m")
        h = np.sqrt(2 * d * x * tan)
        ax_p.plot([0, 0, h / tan], [-d, h, 0], color=colour, ls="--", lw=0.9)
    ax_p.plot([], [], color="gray", ls="--", label="wedge: vertical face, repose front")
    ax_p.axvline(0, color="black", lw=0.8)
    ax_p.set_xlim(-0.15, 0.55)
    ax_p.set_xlabel("distance ahead of the blade's edge (m)")
    ax_p.set_ylabel("height above the layer (m)")
    ax_p.set_title(f"centre line, {w:g} m blade (behind: the trench at -d)", fontsize=10)
    ax_p.grid(alpha=0.3)
    ax_p.legend(fontsize=8, loc="upper right")
    # From above, after the push.
    for k, run in enumerate(runs[:2]):
        ax = fig.add_subplot(grid[1, k])
        h = read_npy(out_dir, run["height_npy"]) - b["layer_m"]
        rows, cols = h.shape
        extent = [0, cols * b["cell_m"], 0, rows * b["cell_m"]]
        # Blue below the layer (the trench, d deep), red above it (the pile).
        norm = TwoSlopeNorm(vmin=min(float(h.min()), -1e-6), vcenter=0.0,
                            vmax=max(float(h.max()), 1e-6))
        image = ax.imshow(h, origin="lower", extent=extent, cmap="RdBu_r", norm=norm,
                          interpolation="nearest")
        xc, wz = run["x_centre_m"], run["width_m"]
        ax.plot([xc - wz / 2, xc + wz / 2], [run["final_z_m"]] * 2, color="black", lw=2.5,
                label="the blade at the end")
        ax.set_xlabel("X (m)")
        ax.set_ylabel("Z (m)")
        ax.set_title(f"{wz:g} m blade after {b['push_m']:g} m along +Z, from above", fontsize=10)
        ax.legend(fontsize=8, loc="lower right")
        fig.colorbar(image, ax=ax, label="height above the initial layer (m)", shrink=0.9)
    # The budget at the end.
    ax = fig.add_subplot(grid[1, 2])
    parts = [("pile_m3", "pile ahead", "tab:orange"), ("windrow_m3", "windrows", "tab:green"),
             ("behind_m3", "above the layer behind", "tab:gray"),
             ("refill_m3", "back in the trench", "tab:blue")]
    names = []
    for k, run in enumerate(runs):
        p = pile[pile["width_m"] == run["width_m"]][-1]
        bottom = 0.0
        for key, label, colour in parts:
            share = 100 * p[key] / p["mass_balance_m3"]
            ax.bar(k, share, bottom=bottom, width=0.5, color=colour,
                   label=label if k == 0 else None)
            bottom += share
        share = 100 * p["walls_m3"] / p["mass_balance_m3"]
        ax.bar(k, -share, width=0.5, color="tab:brown",
               label="taken from the walls (below 0)" if k == 0 else None)
        names.append(f"{run['width_m']:g} m blade")
    ax.axhline(100, color="black", ls="--", lw=1.2, label="w d x")
    ax.set_xticks(range(len(runs)))
    ax.set_xticklabels(names)
    ax.set_xlim(-0.5, len(runs) + 0.9)
    ax.set_ylabel("% of the mass balance w d x")
    ax.set_title(f"where the dug-out soil is after {b['push_m']:g} m", fontsize=10)
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=8, loc="center right")
    FILES.save(fig, out_dir, "soil_bulldozing.png",
               f"Check 3: bulldozing, blades cutting d = {d:g} m into a {b['layer_m']:g} m "
               f"layer, repose {b['repose_deg']:g} deg, {b['cell_m'] * 100:g} cm cells")


def conservation(out_dir, meta):
    c = meta["conservation"]
    v = read_csv(out_dir, c["volume_csv"])
    cuts = np.asarray(v["cut"]).astype(str)
    fig, ax = plt.subplots(figsize=(11, 5))
    palette = ["tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown", "tab:pink"]
    colour_of = {}
    start = 0
    for i in range(1, len(cuts) + 1):
        if i == len(cuts) or cuts[i] != cuts[start]:
            name = cuts[start]
            if name not in colour_of:
                colour_of[name] = palette[len(colour_of) % len(palette)]
                label = f"cut {name}"
            else:
                label = None
            ax.plot(v["step"][start:i], v["relative_error"][start:i], color=colour_of[name],
                    lw=1.3, label=label)
            if i < len(cuts):
                ax.axvline(v["step"][i], color="gray", ls=":", lw=0.8)
            start = i
    ax.plot(v["step"], v["tolerance_rel"], color="red", ls="--", lw=1.1,
            label="tolerance: float rounding of the height updates so far")
    ax.plot(v["step"], -v["tolerance_rel"], color="red", ls="--", lw=1.1)
    ax.axhline(0, color="black", lw=0.6)
    ax.set_xlabel("step (1 ms each)")
    ax.set_ylabel("volume / initial volume - 1")
    ax.ticklabel_format(axis="y", style="sci", scilimits=(0, 0))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    ax.set_title("Check 4: total volume over a long mixed run on flow soil "
                 f"({', '.join(c['sequence'])})", fontsize=10)
    fig.tight_layout()
    FILES.save(fig, out_dir, "soil_conservation.png")


def bucket(out_dir, meta):
    b = meta["bucket"]
    v = read_csv(out_dir, b["volume_csv"])
    phases = np.asarray(v["phase"]).astype(str)
    t = np.asarray(v["t_s"], dtype=float)
    load = np.asarray(v["load_m3"], dtype=float)
    grid = np.asarray(v["grid_m3"], dtype=float)
    fig, (ax, ax_map) = plt.subplots(1, 2, figsize=(12, 4.6), gridspec_kw={"width_ratios": [1.5, 1]})
    initial = grid[0] + load[0]
    ax.plot(t, load * 1e3, color="tab:orange", lw=1.6, label="in the bucket")
    ax.plot(t, (initial - grid) * 1e3, color="tab:blue", lw=1.2, ls="--",
            label="taken from the grid (initial - grid volume)")
    ax.axhline(b["capacity_m3"] * 1e3, color="gray", ls=":", lw=1, label="what the bucket holds level")
    start = 0
    for i in range(1, len(phases) + 1):
        if i == len(phases) or phases[i] != phases[start]:
            ax.text(0.5 * (t[start] + t[i - 1]), b["capacity_m3"] * 1e3 * 1.04, phases[start],
                    ha="center", fontsize=8)
            if i < len(phases):
                ax.axvline(t[i], color="gray", lw=0.6)
            start = i
    ax.set_xlabel("time (s)")
    ax.set_ylabel("volume (litres, 1e-3 m^3)")
    ax.set_ylim(bottom=0, top=b["capacity_m3"] * 1e3 * 1.12)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="center right")
    err = np.max(np.abs(grid + load - initial))
    ax.set_title(f"Check 5: bucket cycle; grid + load within {err:.1e} m^3 of the start", fontsize=10)
    h = read_npy(out_dir, b["height_npy"]) - b["layer_m"]
    n_rows, n_cols = h.shape
    cell = b["cell_m"]
    lim = max(abs(float(h.min())), abs(float(h.max())), 1e-6)
    im = ax_map.imshow(h, origin="lower", extent=[0, n_cols * cell, 0, n_rows * cell], cmap="RdBu_r",
                       vmin=-lim, vmax=lim)
    ax_map.set_xlabel("x (m)")
    ax_map.set_ylabel("z (m)")
    ax_map.set_title("the end: the scoop's trench (blue), the dump (red)", fontsize=10)
    fig.colorbar(im, ax=ax_map, label="height - layer (m)")
    fig.tight_layout()
    FILES.save(fig, out_dir, "soil_bucket.png")


def main(argv):
    out_dir, FILES.quiet = parse_folder_args(argv, __doc__)
    meta = FILES.read_meta(out_dir, "validate.json")
    cone(out_dir, meta)
    slope(out_dir, meta)
    bulldozing(out_dir, meta)
    conservation(out_dir, meta)
    bucket(out_dir, meta)
    # The DEM section's figures, when it ran (terracut validate with DEM results).
    if os.path.isfile(os.path.join(out_dir, "dem", "cases.csv")):
        import plot_validate_dem

        plot_validate_dem.FILES.quiet = FILES.quiet
        plot_validate_dem.force(out_dir)
        plot_validate_dem.profiles(out_dir)
        plot_validate_dem.piles(out_dir)
        plot_validate_dem.maps(out_dir)  # the report shows soil_dem_maps.png too
        plot_validate_dem.sections(out_dir)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
