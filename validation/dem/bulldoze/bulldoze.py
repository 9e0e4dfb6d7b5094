"""Bulldozing reference runs: bed per seed (pour, settle, strike off,
write_restart), blade STL, one run per case x seed, post-processing into
force.csv / lowering.csv / surface_*.npy / run.json and summary.csv."""

import csv
import json
import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
import dem  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
RES = os.path.join(dem.RESULTS, "bulldoze")

# Bed: steel box [0, LX] x [0, LY], floor z = 0, struck off at H_STRIKE
# (grain centres above it removed).  The box reaches back to x = BXLO (< 0)
# only so that a raked blade's upper part, above the bed and behind the back
# wall, stays inside the simulation box; no grain can get there.
BED = {
    "length_x_m": 0.70,
    "width_y_m": 0.50,
    "strike_height_m": 0.10,
    "box_x_lo_m": -0.15,
    "box_z_hi_m": 0.35,
    "insert_z_lo_m": 0.0065,
    "insert_z_hi_m": 0.30,
    "insert_volume_fraction": 0.25,
    "settle_chunk_steps": 2000,
    "settle_max_chunks": 25,
    "settle2_max_chunks": 10,
    "settle_ke_per_grain_j": 1.0e-8,
}
# Blade and motion
BLADE = {
    "height_m": 0.20,           # vertical extent of the plate above its tip
    "y_centre_m": None,         # LY / 2
    "tip_x_at_push_start_m": 0.15,
    "start_clearance_m": 0.005,  # tip starts this far above the highest grain top allowed by the strike-off
    "lower_speed_m_per_s": 0.10,
    "hold_s": 0.10,
    "push_speed_m_per_s": 0.15,
    "push_total_m": 0.30,
    "push_segments": 3,
    "force_average_steps": 50,   # 2.5 ms
}
GRID_CELL_M = 0.005

CASES = {
    "vertical_w012_d050": {"width_m": 0.12, "depth_m": 0.05, "rake_deg": 90.0},
    "vertical_w012_d030": {"width_m": 0.12, "depth_m": 0.03, "rake_deg": 90.0},
    "vertical_w020_d050": {"width_m": 0.20, "depth_m": 0.05, "rake_deg": 90.0},
    "raked45_w012_d050": {"width_m": 0.12, "depth_m": 0.05, "rake_deg": 45.0},
}

SMOKE_BED = dict(BED, length_x_m=0.16, width_y_m=0.12, strike_height_m=0.04,
                 box_x_lo_m=-0.15, box_z_hi_m=0.30, insert_z_hi_m=0.10,
                 settle_chunk_steps=100, settle_max_chunks=2, settle2_max_chunks=1)


def _workdir(*parts):
    return os.path.join(dem.WORK, "bulldoze", *parts)


# ----------------------------------------------------------------- blade STL
def write_blade_stl(path, width, rake_deg, height, cell=0.02):
    """Zero-thickness plate, tip line on the local y axis (x = z = 0,
    y in [-w/2, w/2]), rising at rake angle alpha from the horizontal,
    face leaning back over -x: points (-s cos a, y, s sin a), s in [0, L],
    L = height / sin a.  Split into near-square triangles."""
    a = math.radians(rake_deg)
    L = height / math.sin(a)
    ny = max(1, int(round(width / cell)))
    ns = max(1, int(round(L / cell)))
    ys = np.linspace(-width / 2, width / 2, ny + 1)
    ss = np.linspace(0.0, L, ns + 1)

    def P(i, j):
        s = ss[j]
        return (-s * math.cos(a) if abs(math.cos(a)) > 1e-12 else 0.0, ys[i], s * math.sin(a))

    # outward normal of the face that meets the soil ahead: (sin a, 0, cos a)
    n = (math.sin(a), 0.0, math.cos(a))
    with open(path, "w") as f:
        f.write("solid blade\n")
        for i in range(ny):
            for j in range(ns):
                p00, p10, p01, p11 = P(i, j), P(i + 1, j), P(i, j + 1), P(i + 1, j + 1)
                for tri in ((p00, p01, p10), (p10, p01, p11)):
                    f.write("  facet normal %.6e %.6e %.6e\n    outer loop\n" % n)
                    for p in tri:
                        f.write("      vertex %.9e %.9e %.9e\n" % p)
                    f.write("    endloop\n  endfacet\n")
        f.write("endsolid blade\n")
    return {"plate_length_m": L, "triangles": 2 * ny * ns}


# ----------------------------------------------------------------------- bed
def bed_paths(seed, smoke=False):
    wd = _workdir("smoke" if smoke else "beds", "seed%d" % seed)
    return wd, os.path.join(wd, "bed.restart"), os.path.join(wd, "bed.dump"), os.path.join(wd, "bed.json")


def make_bed(seed, smoke=False, force=False):
    bed = SMOKE_BED if smoke else BED
    wd, restart, dump, meta = bed_paths(seed, smoke)
    if not force and os.path.exists(meta) and os.path.exists(restart):
        with open(meta) as f:
            return json.load(f)
    v, primes = dem.material_vars(seed, 1)
    v.update({
        "bxlo": bed["box_x_lo_m"], "Lx": bed["length_x_m"], "Ly": bed["width_y_m"],
        "zbox": bed["box_z_hi_m"], "zinslo": bed["insert_z_lo_m"], "zinshi": bed["insert_z_hi_m"],
        "vf": bed["insert_volume_fraction"], "Hstrike": bed["strike_height_m"],
        "chunk": bed["settle_chunk_steps"], "nchunk": bed["settle_max_chunks"],
        "nchunk2": bed["settle2_max_chunks"], "ketol": bed["settle_ke_per_grain_j"],
        "restart": restart, "dumpfile": dump,
    })
    wall = dem.run_liggghts(os.path.join(dem.HERE, "bed.in"), v, wd, "bed")
    d = dem.read_dump(dump)
    x, y, z, r = d["x"], d["y"], d["z"], d["radius"]
    Lx, Ly = bed["length_x_m"], bed["width_y_m"]
    nx, ny = int(round(Lx / GRID_CELL_M)), int(round(Ly / GRID_CELL_M))
    grid, _ = dem.envelope_grid(x, y, z, r, 0.0, 0.0, nx, ny, GRID_CELL_M)
    m = int(round(0.05 / GRID_CELL_M)) if not smoke else 2
    interior = grid[m:ny - m, m:nx - m]
    H0 = float(interior.mean())
    margin = 0.1 if not smoke else 0.03
    box = (margin, Lx - margin, margin, Ly - margin, 0.02 if not smoke else 0.01, H0 - 0.02)
    phi, phi_err = dem.solid_fraction_box(x, y, z, r, box, npts=100000 if not smoke else 5000)
    settle = _settle_log(os.path.join(wd, "screen.bed"))
    info = {
        "seed": seed, "liggghts_seed_primes": primes, "bed": bed,
        "particles": int(len(x)), "restart_step": int(d["_step"]),
        "initial_surface_mean_m": H0,
        "initial_surface_std_m": float(interior.std()),
        "solid_fraction": phi, "solid_fraction_mc_err": phi_err,
        "bulk_density_kg_per_m3": phi * dem.PARTICLE["density_kg_per_m3"],
        "density_box_m": box,
        "settling_ke_per_grain_j": settle,
        "wall_s": wall, "cpu_s": dem.LAST_CPU_S,
    }
    dem.write_json(meta, info)
    if not smoke:
        dem.log_cost("bulldoze_bed", "seed%d" % seed, wall, "%d grains; cpu %.0f s" % (len(x), dem.LAST_CPU_S))
    return info


def _settle_log(screen):
    out = []
    for l in open(screen, errors="replace"):
        if l.startswith("SETTLE chunk"):
            out.append(float(l.split()[-1]))
    return out


# ----------------------------------------------------------------------- run
def run_case(case, seed, smoke=False, force=False):
    c = CASES[case]
    bed = SMOKE_BED if smoke else BED
    binfo = make_bed(seed, smoke)
    _, restart, _, _ = bed_paths(seed, smoke)
    outdir = os.path.join(RES, case, "seed%d" % seed) if not smoke else _workdir("smoke", "out", case)
    if not smoke and not force and os.path.exists(os.path.join(outdir, "run.json")):
        print("exists:", outdir)
        return json.load(open(os.path.join(outdir, "run.json")))
    wd = _workdir("smoke" if smoke else "runs", case, "seed%d" % seed)
    os.makedirs(wd, exist_ok=True)
    dt = dem.TIMESTEP_S
    B = dict(BLADE)
    width, depth, rake = c["width_m"], c["depth_m"], c["rake_deg"]
    height = B["height_m"]
    if smoke:
        width, depth, height = 0.04, 0.02, 0.08
    yc = bed["width_y_m"] / 2
    a = math.radians(rake)
    u = (math.cos(a), 0.0, -math.sin(a))           # lowering direction: along the plate
    H0 = binfo["initial_surface_mean_m"]
    z_tip = H0 - depth
    z_start = bed["strike_height_m"] + dem.PARTICLE["radius_max_m"] + B["start_clearance_m"]
    if smoke:  # a tiny unsettled bed: keep the geometry sane, not meaningful
        z_start = max(z_start, z_tip + 0.01)
    dist = (z_start - z_tip) / math.sin(a)
    x_tip = B["tip_x_at_push_start_m"] if not smoke else 0.05
    start = (x_tip - dist * u[0], yc, z_start)
    navg = B["force_average_steps"]

    def steps(t):
        return max(navg, int(round(t / dt / navg)) * navg)
    nlow = steps(dist / B["lower_speed_m_per_s"])
    vl = dist / (nlow * dt)
    nhold = steps(B["hold_s"])
    seg = B["push_total_m"] / B["push_segments"]
    nseg = steps(seg / B["push_speed_m_per_s"])
    vpush = seg / (nseg * dt)
    if smoke:
        nlow, nhold, nseg = 100, 50, 50
        vl = dist / (nlow * dt)
        vpush = 0.1
        seg = vpush * nseg * dt
    stl = os.path.join(wd, "blade.stl")
    stlinfo = write_blade_stl(stl, width, rake, height)
    files = {k: os.path.join(wd, k + ".dump") for k in ("init", "p0", "p1", "p2", "p3")}
    v, primes = dem.material_vars(seed, 1)
    v.update({
        "restart": restart, "stl": stl, "Lx": bed["length_x_m"], "Ly": bed["width_y_m"],
        "bx0": start[0], "by0": start[1], "bz0": start[2],
        "vlx": vl * u[0], "vlz": vl * u[2], "nlow": nlow, "nhold": nhold,
        "vpush": vpush, "nseg": nseg, "navg": navg, "nthermo": 1000 if not smoke else 50,
        "dumpinit": files["init"], "dump0": files["p0"], "dump1": files["p1"],
        "dump2": files["p2"], "dump3": files["p3"],
        "lowfile": os.path.join(wd, "lowering.txt"), "forcefile": os.path.join(wd, "force.txt"),
    })
    wall = dem.run_liggghts(os.path.join(HERE, "push.in"), v, wd, "push")
    cpu = dem.LAST_CPU_S
    os.makedirs(outdir, exist_ok=True)
    # forces
    sr = binfo["restart_step"]
    if sr % navg:
        raise RuntimeError("bed restart step %d is not a multiple of %d" % (sr, navg))
    s0 = sr + nlow + nhold
    fl = _read_avetime(v["lowfile"])
    with open(os.path.join(outdir, "lowering.csv"), "w") as f:
        f.write("t_s,lower_m,fx_n,fy_n,fz_n\n")
        for st, fx, fy, fz in fl:
            t = (st - sr - (navg - 1) / 2.0) * dt
            f.write("%.5f,%.6f,%.5g,%.5g,%.5g\n" % (t, min(vl * t, dist), fx, fy, fz))
    fp = _read_avetime(v["forcefile"])
    with open(os.path.join(outdir, "force.csv"), "w") as f:
        f.write("t_s,push_m,fx_n,fy_n,fz_n\n")
        for st, fx, fy, fz in fp:
            t = (st - s0 - (navg - 1) / 2.0) * dt
            f.write("%.5f,%.6f,%.5g,%.5g,%.5g\n" % (t, vpush * t, fx, fy, fz))
    # surfaces
    Lx, Ly = bed["length_x_m"], bed["width_y_m"]
    nx, ny = int(round(Lx / GRID_CELL_M)), int(round(Ly / GRID_CELL_M))
    surf = {}
    names = {"init": "surface_initial.npy", "p0": "surface_0.npy",
             "p1": "surface_%d.npy" % round(1000 * seg), "p2": "surface_%d.npy" % round(2000 * seg),
             "p3": "surface_%d.npy" % round(3000 * seg)}
    if smoke:  # tiny pushes would give colliding names
        names = {k: "surface_smoke_%s.npy" % k for k in names}
    pushes = {"init": None, "p0": 0.0, "p1": seg, "p2": 2 * seg, "p3": 3 * seg}
    grains = {}
    for k, fn in names.items():
        d = dem.read_dump(files[k])
        g, nfill = dem.envelope_grid(d["x"], d["y"], d["z"], d["radius"], 0.0, 0.0, nx, ny, GRID_CELL_M)
        np.save(os.path.join(outdir, fn), g)
        surf[k] = {"file": fn, "push_m": pushes[k], "step": d["_step"], "cells_filled_from_neighbours": nfill,
                   "grains": int(len(d["x"]))}
        grains[k] = d
    blade_top_back = height / math.tan(a) if rake < 89.999 else 0.0
    info = {
        "case": case, "seed": seed, "smoke": smoke,
        "description": ("thin steel plate blade lowered into a poured bed to tip depth d below the mean "
                        "initial surface (vertical blade: straight down; raked blade: along its own plane, "
                        "so that the plate slices in without ploughing), held, then pushed along +x"),
        "liggghts_seed_primes": primes,
        "frame": ("LIGGGHTS frame: x = push direction, y across, z up (gravity -z); bed floor z = 0, "
                  "bed box x in [0, Lx], y in [0, Ly]"),
        "bed": {**bed, "particles": binfo["particles"],
                "initial_surface_mean_m": H0, "initial_surface_std_m": binfo["initial_surface_std_m"],
                "bulk_density_kg_per_m3": binfo["bulk_density_kg_per_m3"],
                "solid_fraction": binfo["solid_fraction"],
                "grains_at_push_start": surf["p0"]["grains"]},
        "blade": {"width_m": width, "height_m": height, "rake_deg": rake,
                  "rake_definition": ("angle of the plate from the horizontal; tip leading (+x), the "
                                      "plate rising backwards (-x) over the soil it lifts; 90 = vertical"),
                  "plate_length_m": stlinfo["plate_length_m"], "thickness_m": 0.0,
                  "stl_triangles": stlinfo["triangles"], "material": "steel-like (atom type 2)",
                  "depth_m": depth,
                  "tip_line_at_push_start": {"x_m": x_tip, "z_m": z_tip,
                                             "y_from_m": yc - width / 2, "y_to_m": yc + width / 2},
                  "tip_line_at_lowering_start": {"x_m": start[0], "z_m": start[2]},
                  "rear_top_edge_x_offset_m": -blade_top_back,
                  "tip_x_at_push_end_m": x_tip + 3 * seg},
        "motion": {"lowering_direction": u, "lowering_distance_m": dist, "lowering_speed_m_per_s": vl,
                   "lowering_steps": nlow, "hold_steps": nhold, "hold_s": nhold * dt,
                   "push_speed_m_per_s": vpush, "push_steps_per_segment": nseg,
                   "push_total_m": 3 * seg, "push_start_step": s0, "restart_step": sr,
                   "quasi_static_note": "push speed 0.15 m/s (~1.5 grain diameters per 0.1 s)"},
        "force_output": {"file": "force.csv", "columns": "t_s,push_m,fx_n,fy_n,fz_n",
                         "meaning": ("total force the grains exert ON the blade (mesh module stress), "
                                     "LIGGGHTS frame; fx < 0 resists the push, fz < 0 presses the blade down"),
                         "averaging": ("each row is the mean over %d consecutive steps (%.4g s); t_s is the "
                                       "window centre measured from the start of the push; push_m = "
                                       "push speed * t_s" % (navg, navg * dt)),
                         "lowering_file": "lowering.csv (t_s from the start of lowering, lower_m along "
                                          "the lowering direction; includes the hold)"},
        "surfaces": {"cell_m": GRID_CELL_M, "origin_xy_m": [0.0, 0.0], "shape_rows_cols": [ny, nx],
                     "layout": ("float32 array [row j, column i]; rows along y, columns along x; cell (j, i) "
                                "centre at (x = (i+0.5)*cell, y = (j+0.5)*cell); value = upper envelope of "
                                "the spheres, metres above the bed floor; cells no sphere covers are filled "
                                "with the mean of their covered neighbours"),
                     "snapshots": surf},
        "timestep_s": dt, "rayleigh_check": dem.rayleigh_check(),
        "parameters": dem.parameters_json(),
        "wall_clock_s": wall,
        "cpu_s": cpu,
        "cost_note": "one LIGGGHTS process under nice -n 19 on a 2-core machine shared with C++ builds; "
                     "wall-clock includes waiting for the CPU, cpu_s is the process's own CPU time",
    }
    info["metrics"] = window_metrics(info, outdir, grains)
    dem.write_json(os.path.join(outdir, "run.json"), info)
    if not smoke:
        dem.log_cost("bulldoze_run", "%s/seed%d" % (case, seed), wall,
                     "%d grains; %d steps; cpu %.0f s" % (binfo["particles"], s0 + 3 * nseg, cpu))
    return info


def _read_avetime(path):
    rows = []
    for l in open(path):
        if l.startswith("#") or not l.strip():
            continue
        p = l.split()
        rows.append((int(p[0]), float(p[1]), float(p[2]), float(p[3])))
    return rows


def window_metrics(info, outdir, grains):
    """Per 0.1 m push window: mean force, and at the window's end the pile
    ahead of the blade.  Pile region = cells with x >= tip line, plus, for a
    raked blade, the cells over the plate (between its rear top edge and the
    tip, within the blade width) whose surface lies above the plate, i.e.
    the grains carried on the face (not the cut floor seen under the plate).  pile_volume = sum over the region of
    (h - h_initial) * cell^2 (net rise of the surface, bulk volume incl. pores);
    peak height = max over the region of h - H0 (H0 mean initial surface);
    pile_grain_volume = solid volume of grains in the region whose centre is
    above H0, minus the same in the initial bed ahead of the tip line (the
    undisturbed surface grains that already stick out above H0)."""
    cell = info["surfaces"]["cell_m"]
    ny, nx = info["surfaces"]["shape_rows_cols"]
    H0 = info["bed"]["initial_surface_mean_m"]
    b = info["blade"]
    w = b["width_m"]
    yc = 0.5 * (b["tip_line_at_push_start"]["y_from_m"] + b["tip_line_at_push_start"]["y_to_m"])
    back = b["rear_top_edge_x_offset_m"]
    xs = (np.arange(nx) + 0.5) * cell
    ys = (np.arange(ny) + 0.5) * cell
    X, Y = np.meshgrid(xs, ys)
    h_init = np.load(os.path.join(outdir, info["surfaces"]["snapshots"]["init"]["file"])).astype(float)
    force = np.genfromtxt(os.path.join(outdir, "force.csv"), delimiter=",", names=True)
    seg = info["motion"]["push_total_m"] / 3
    out = []
    for k in range(3):
        lo, hi = k * seg, (k + 1) * seg
        sel = (force["push_m"] >= lo) & (force["push_m"] < hi)
        snap = info["surfaces"]["snapshots"]["p%d" % (k + 1)]
        h = np.load(os.path.join(outdir, snap["file"])).astype(float)
        xt = b["tip_line_at_push_start"]["x_m"] + hi
        zt = b["tip_line_at_push_start"]["z_m"]
        tana = math.tan(math.radians(b["rake_deg"])) if b["rake_deg"] < 89.999 else 0.0
        over = (X >= xt + back) & (X < xt) & (np.abs(Y - yc) <= w / 2)
        region = (X >= xt) | (over & (h > zt + (xt - X) * tana))
        vol = float(((h - h_init) * region).sum() * cell * cell)
        peak = float((h[region] - H0).max())
        g = grains["p%d" % (k + 1)]
        gx, gy, gz, gr = g["x"], g["y"], g["z"], g["radius"]
        greg = (gx >= xt) | ((gx >= xt + back) & (gx < xt) & (np.abs(gy - yc) <= w / 2)
                             & (gz > zt + (xt - gx) * tana))
        gsel = greg & (gz > H0)
        gi = grains["init"]
        gsel0 = (gi["x"] >= xt) & (gi["z"] > H0)   # the same count in the initial bed ahead of the tip
        gvol = float((4.0 / 3.0 * math.pi * gr[gsel] ** 3).sum()
                     - (4.0 / 3.0 * math.pi * gi["radius"][gsel0] ** 3).sum())
        out.append({"window_start_m": lo, "window_end_m": hi,
                    "fx_mean_n": float(force["fx_n"][sel].mean()),
                    "fy_mean_n": float(force["fy_n"][sel].mean()),
                    "fz_mean_n": float(force["fz_n"][sel].mean()),
                    "fx_std_n": float(force["fx_n"][sel].std()),
                    "samples": int(sel.sum()),
                    "tip_x_at_window_end_m": xt,
                    "pile_volume_m3": vol, "pile_grain_volume_m3": gvol,
                    "pile_peak_height_m": peak,
                    "swept_volume_m3": w * b["depth_m"] * hi})
    return out


def recompute_metrics(case, seed):
    """Recompute the window metrics of a finished run from its committed
    files and the dumps still in work/ (after a change of definition)."""
    outdir = os.path.join(RES, case, "seed%d" % seed)
    info = json.load(open(os.path.join(outdir, "run.json")))
    wd = _workdir("runs", case, "seed%d" % seed)
    grains = {k: dem.read_dump(os.path.join(wd, k + ".dump")) for k in ("init", "p1", "p2", "p3")}
    info["metrics"] = window_metrics(info, outdir, grains)
    dem.write_json(os.path.join(outdir, "run.json"), info)
    return info


# ------------------------------------------------------------------- summary
def write_summary():
    rows = []
    for case in CASES:
        cdir = os.path.join(RES, case)
        if not os.path.isdir(cdir):
            continue
        per_seed = {}
        for s in sorted(os.listdir(cdir)):
            p = os.path.join(cdir, s, "run.json")
            if os.path.exists(p):
                per_seed[s] = json.load(open(p))
        for s, info in per_seed.items():
            for m in info["metrics"]:
                rows.append([case, s.replace("seed", ""), m["window_start_m"], m["window_end_m"],
                             m["fx_mean_n"], m["fy_mean_n"], m["fz_mean_n"], m["pile_volume_m3"],
                             m["pile_grain_volume_m3"], m["pile_peak_height_m"], m["swept_volume_m3"], 1])
        if per_seed:
            for k in range(3):
                ms = [info["metrics"][k] for info in per_seed.values()]
                for stat in ("mean", "std"):
                    row = [case, stat, ms[0]["window_start_m"], ms[0]["window_end_m"]]
                    for key in ("fx_mean_n", "fy_mean_n", "fz_mean_n", "pile_volume_m3",
                                "pile_grain_volume_m3", "pile_peak_height_m"):
                        mu, sd = dem.mean_std([m[key] for m in ms])
                        row.append(mu if stat == "mean" else sd)
                    row += [ms[0]["swept_volume_m3"], len(ms)]
                    rows.append(row)
    path = os.path.join(RES, "summary.csv")
    os.makedirs(RES, exist_ok=True)
    with open(path, "w", newline="") as f:
        wr = csv.writer(f)
        wr.writerow(["case", "seed", "window_start_m", "window_end_m", "fx_mean_n", "fy_mean_n", "fz_mean_n",
                     "pile_volume_m3", "pile_grain_volume_m3", "pile_peak_height_m", "swept_volume_m3",
                     "n_seeds"])
        for r in rows:
            wr.writerow([("%.6g" % x) if isinstance(x, float) else x for x in r])
    return path
