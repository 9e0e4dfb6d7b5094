#!/usr/bin/python3
"""Figures of `terracut validate`'s DEM section (terracut against LIGGGHTS).

Usage: /usr/bin/python3 tools/plot_validate_dem.py DIR [--quiet]

DIR is the output folder of `terracut validate` (it reads DIR/dem/force.csv,
profiles.csv and cases.csv) and receives:

  soil_dem_force.png     per case, the horizontal force resisting the push
                         against the distance pushed: each DEM seed (thin),
                         terracut on the same beds (dashed), the 0.1 m window
                         means with the DEM's seed scatter and the +-15 % band
  soil_dem_profiles.png  per case, the centre line after 0.3 m of push: the
                         DEM's surface (each seed), terracut's, and the bed
                         before the push
  soil_dem_piles.png     per case, the soil ahead of the blade (net rise) at
                         each 0.1 m: DEM mean +- scatter, terracut, +-15 %
  soil_dem_maps.png      per case (its first seed), the surface's change after
                         the whole push seen from above: the DEM's, terracut's,
                         and their difference (DIR/dem/maps/*.npy)
  soil_dem_sections.png  per case, the surface's change across the push after
                         it, averaged over a band along the push: ahead of the
                         blade's tip (the pile's width and height) and behind
                         it (the trench and the windrows); the DEM's mean and
                         range over its seeds, terracut's mean, the blade's span

Exit codes: 0 done; 2 bad arguments or input folder; 3 numpy or matplotlib missing.
Needs Debian's python3-numpy and python3-matplotlib.
"""
import os
import sys

from plot_common import FigureFolder, import_plotting, make_fail, parse_folder_args

fail = make_fail("plot_validate_dem.py")
np, plt = import_plotting(fail)

FILES = FigureFolder(np, plt, fail, "plot_validate_dem.py", "terracut validate", dpi=110)


def read(out_dir, name):
    return FILES.read_csv(os.path.join(out_dir, "dem", name))


def cases_of(table):
    return sorted(set(str(c) for c in np.atleast_1d(table["case"])))


def grid(n):
    cols = min(n, 2)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(6.4 * cols, 4.2 * rows), squeeze=False)
    return fig, [a for row in axes for a in row]


def force(out_dir):
    f = np.atleast_1d(read(out_dir, "force.csv"))
    c = np.atleast_1d(read(out_dir, "cases.csv"))
    names = cases_of(f)
    fig, axes = grid(len(names))
    for ax, name in zip(axes, names):
        sel = f[f["case"] == name]
        for seed in sorted(set(sel["seed"])):
            d = sel[(sel["seed"] == seed) & (sel["source"] == "dem")]
            t = sel[(sel["seed"] == seed) & (sel["source"] == "terracut")]
            ax.plot(d["push_m"], -d["fx_n"], color="tab:gray", lw=0.6, alpha=0.7,
                    label="DEM (each seed)" if seed == min(sel["seed"]) else None)
            ax.plot(t["push_m"], -t["fx_n"], color="tab:red", lw=0.9, ls="--",
                    label="terracut (same beds)" if seed == min(sel["seed"]) else None)
        w = c[c["case"] == name]
        mid = 0.5 * (w["start_m"] + w["end_m"])
        ax.errorbar(mid, w["dem_fx_n"], yerr=w["dem_fx_std_n"], fmt="o", color="black", capsize=3,
                    label="DEM window mean +- seed scatter")
        ax.plot(mid, w["terracut_fx_n"], "s", color="tab:red", label="terracut window mean")
        ax.fill_between(mid, 0.85 * w["dem_fx_n"], 1.15 * w["dem_fx_n"], color="black", alpha=0.08,
                        label="+-15 % of the DEM")
        ax.set_title(name)
        ax.set_xlabel("distance pushed (m)")
        ax.set_ylabel("horizontal force on the blade (N)")
        ax.set_ylim(bottom=0.0)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper left")
    for ax in axes[len(names):]:
        ax.axis("off")
    FILES.save(fig, out_dir, "soil_dem_force.png", "terracut against a DEM: the force resisting the push")


def profiles(out_dir):
    p = np.atleast_1d(read(out_dir, "profiles.csv"))
    names = cases_of(p)
    fig, axes = grid(len(names))
    for ax, name in zip(axes, names):
        sel = p[(p["case"] == name) & (p["push_mm"] == max(p["push_mm"]))]
        seeds = sorted(set(sel["seed"]))
        for seed in seeds:
            s = sel[sel["seed"] == seed]
            first = seed == seeds[0]
            ax.plot(s["x_m"], s["initial_m"] * 1e3, color="tab:gray", lw=0.6, ls=":",
                    label="before the push" if first else None)
            ax.plot(s["x_m"], s["dem_m"] * 1e3, color="black", lw=0.8, label="DEM" if first else None)
            ax.plot(s["x_m"], s["terracut_m"] * 1e3, color="tab:red", lw=0.9, ls="--",
                    label="terracut" if first else None)
        ax.set_title(f"{name}: centre line after {max(p['push_mm'])} mm")
        ax.set_xlabel("x along the push (m)")
        ax.set_ylabel("surface above the floor (mm)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    for ax in axes[len(names):]:
        ax.axis("off")
    FILES.save(fig, out_dir, "soil_dem_profiles.png", "terracut against a DEM: the centre line")


def piles(out_dir):
    c = np.atleast_1d(read(out_dir, "cases.csv"))
    names = cases_of(c)
    fig, axes = grid(len(names))
    for ax, name in zip(axes, names):
        w = c[c["case"] == name]
        x = w["end_m"]
        ax.errorbar(x, w["dem_pile_m3"] * 1e3, yerr=w["dem_pile_std_m3"] * 1e3, fmt="o-", color="black",
                    capsize=3, label="DEM mean +- seed scatter")
        ax.plot(x, w["terracut_pile_m3"] * 1e3, "s--", color="tab:red", label="terracut")
        ax.fill_between(x, 0.85 * w["dem_pile_m3"] * 1e3, 1.15 * w["dem_pile_m3"] * 1e3, color="black",
                        alpha=0.08, label="+-15 % of the DEM")
        ax.set_title(name)
        ax.set_xlabel("distance pushed (m)")
        ax.set_ylabel("soil ahead of the blade, net rise (litres)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    for ax in axes[len(names):]:
        ax.axis("off")
    FILES.save(fig, out_dir, "soil_dem_piles.png", "terracut against a DEM: the soil ahead of the blade")


# The DEM cases' geometry (validation/dem/README.md): the surface grids'
# cell, the blade's centre across the bed and its tip at the push's end.
DEM_CELL_M = 0.005
DEM_CENTRE_Y_M = 0.25
DEM_TIP_END_X_M = 0.45


def map_stems(out_dir):
    """The surfaces' folder and, per case, its runs' file stems (CASE_seedN), sorted."""
    folder = os.path.join(out_dir, "dem", "maps")
    by_case = {}
    if os.path.isdir(folder):
        for stem in sorted(f[: -len("_initial.npy")] for f in os.listdir(folder) if f.endswith("_initial.npy")):
            by_case.setdefault(stem.rsplit("_seed", 1)[0], []).append(stem)
    return folder, by_case


def maps(out_dir):
    folder, by_case = map_stems(out_dir)
    firsts = {case: stems[0] for case, stems in by_case.items()}
    if not firsts:
        return
    fig, axes = plt.subplots(len(firsts), 3, figsize=(15, 3.3 * len(firsts)), squeeze=False)
    cell = DEM_CELL_M
    for row, (case, stem) in zip(axes, sorted(firsts.items())):
        init = np.load(os.path.join(folder, stem + "_initial.npy"))
        dem = np.load(os.path.join(folder, stem + "_dem.npy")) - init
        tc = np.load(os.path.join(folder, stem + "_terracut.npy")) - init
        lim = max(np.abs(dem).max(), np.abs(tc).max()) * 1e3
        extent = [0, init.shape[1] * cell, 0, init.shape[0] * cell]
        for ax, field, title in zip(row, (dem, tc, tc - dem),
                                    ("DEM", "terracut", "terracut - DEM")):
            im = ax.imshow(field * 1e3, origin="lower", extent=extent, cmap="RdBu_r", vmin=-lim, vmax=lim)
            ax.set_title(f"{case} ({stem.rsplit('_', 1)[1]}): {title}", fontsize=9)
            ax.set_xlabel("x along the push (m)")
            ax.set_ylabel("y across (m)")
        fig.colorbar(im, ax=row[2], label="change of the surface (mm)")
    FILES.save(fig, out_dir, "soil_dem_maps.png", "terracut against a DEM: the surface after the push, from above")


def sections(out_dir):
    folder, by_case = map_stems(out_dir)
    if not by_case:
        return
    # Bands along the push (x, m): 0.1 m ahead of the tip, and 0.05 to
    # 0.25 m behind it (clear of the blade and of the push's start).
    bands = (("ahead of the tip: x from 0.45 to 0.55 m", DEM_TIP_END_X_M, DEM_TIP_END_X_M + 0.10),
             ("behind the tip: x from 0.20 to 0.40 m", DEM_TIP_END_X_M - 0.25, DEM_TIP_END_X_M - 0.05))
    fig, axes = plt.subplots(len(by_case), 2, figsize=(12.8, 3.4 * len(by_case)), squeeze=False)
    for row, (case, case_stems) in zip(axes, sorted(by_case.items())):
        # The blade's width from the case's name (..._w012_...: 0.12 m).
        width = next((int(part[1:]) / 100.0 for part in case.split("_") if part[:1] == "w" and part[1:].isdigit()), None)
        # Each run's change of the surface, DEM's and terracut's.
        changes = []
        for stem in case_stems:
            init = np.load(os.path.join(folder, stem + "_initial.npy"))
            changes.append(tuple(np.load(os.path.join(folder, stem + source)) - init
                                 for source in ("_dem.npy", "_terracut.npy")))
        for ax, (title, x0, x1) in zip(row, bands):
            c0 = max(int(round(x0 / DEM_CELL_M)), 0)
            c1 = min(int(round(x1 / DEM_CELL_M)), changes[0][0].shape[1])
            if c1 <= c0:
                ax.axis("off")
                continue
            dem = [d[:, c0:c1].mean(axis=1) for d, _ in changes]
            tc = [t[:, c0:c1].mean(axis=1) for _, t in changes]
            y = (np.arange(len(dem[0])) + 0.5) * DEM_CELL_M
            dem, tc = np.array(dem) * 1e3, np.array(tc) * 1e3
            ax.fill_between(y, dem.min(axis=0), dem.max(axis=0), color="black", alpha=0.15, label="DEM, range over the seeds")
            ax.plot(y, dem.mean(axis=0), color="black", label=f"DEM, mean of {len(dem)} seeds")
            ax.plot(y, tc.mean(axis=0), "--", color="tab:red", label="terracut, mean over the same beds")
            if width is not None:
                ax.axvspan(DEM_CENTRE_Y_M - 0.5 * width, DEM_CENTRE_Y_M + 0.5 * width, color="tab:blue", alpha=0.08,
                           label="the blade's span")
            ax.axhline(0.0, color="0.5", lw=0.6)
            ax.set_title(f"{case}: {title}", fontsize=9)
            ax.set_xlabel("y across the push (m)")
            ax.set_ylabel("change of the surface (mm)")
            ax.grid(alpha=0.3)
            ax.legend(fontsize=7)
    FILES.save(fig, out_dir, "soil_dem_sections.png",
               "terracut against a DEM: the surface across the push, ahead of the blade and behind it")


def main(argv):
    out_dir, FILES.quiet = parse_folder_args(argv, __doc__)
    if not os.path.isfile(os.path.join(out_dir, "dem", "cases.csv")):
        fail(f"{out_dir}/dem/cases.csv not found (run `terracut validate --out {out_dir}` with DEM results)")
    force(out_dir)
    profiles(out_dir)
    piles(out_dir)
    maps(out_dir)
    sections(out_dir)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
