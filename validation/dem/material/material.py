"""Material tests of the DEM sand: angle of repose (lifted cylinder), bulk
density (poured bed), internal friction (periodic plane shear cell at several
normal stresses, peak and residual, Mohr-Coulomb fit) and soil-tool friction
(the same cell sliding on a steel plate).  Writes results/material.json."""

import json
import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "common"))
import dem  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))

REPOSE = {
    "cylinder_radius_m": 0.065,        # 13 mean grain diameters across
    "cylinder_height_m": 0.35,
    "cylinder_segments": 48,
    "domain_half_width_m": 0.25,
    "domain_z_m": 0.60,
    "base_layer_z_top_m": 0.03,        # insertion region of the frozen rough base
    "base_insert_volume_fraction": 0.30,
    "base_settle_steps": 3000,
    "fill_z_lo_m": 0.035,
    "fill_z_hi_m": 0.33,
    "fill_volume_fraction": 0.28,
    "lift_speed_m_per_s": 0.03,
    "lift_distance_m": 0.17,
    "settle_chunk_steps": 2000,
    "settle_max_chunks": 20,
    "settle2_max_chunks": 20,
    "settle_ke_per_grain_j": 2.0e-9,
    "radial_bin_m": 0.005,
    "sectors": 8,
    "fit_band": [0.2, 0.8],
}
DENSITY = {
    "length_x_m": 0.30, "width_y_m": 0.30, "strike_height_m": 0.12,
    "box_x_lo_m": 0.0, "box_z_hi_m": 0.35, "insert_z_lo_m": 0.0065, "insert_z_hi_m": 0.30,
    "insert_volume_fraction": 0.25, "settle_chunk_steps": 2000, "settle_max_chunks": 25,
    "settle2_max_chunks": 10, "settle_ke_per_grain_j": 1.0e-8,
    "measure_margin_walls_m": 0.06, "measure_margin_floor_m": 0.02, "measure_margin_top_m": 0.025,
}
SHEAR = {
    "length_x_m": 0.20, "width_y_m": 0.15, "box_z_m": 0.40,
    "insert_z_lo_m": 0.0065, "insert_z_hi_m": 0.30, "insert_volume_fraction": 0.20,
    "settle_chunk_steps": 2000, "settle_max_chunks": 20, "settle_ke_per_grain_j": 1.0e-8,
    "wall_layer_m": 0.014,             # grains with centre within this of the bottom / top form the walls
    "consolidation_s": 0.3,
    "shear_speed_m_per_s": 0.02,
    "shear_distance_m": 0.10,
    "last_window_m": 0.04,             # dumps at (distance - last_window) and distance
    "average_steps": 50,
    "normal_stresses_pa": [500.0, 1000.0, 2000.0, 3000.0],
    "peak_search_to_m": 0.03,
    "peak_smoothing_m": 0.002,
    "residual_window_m": [0.05, 0.10],
}
SOILTOOL = {
    "frame_x_m": [0.05, 0.25], "width_y_m": 0.15,      # grains held in a fixed steel frame 0.20 x 0.15 m
    "plate_x_m": [-0.02, 0.30], "plate_cell_m": 0.02,  # steel plate under it, z = 0, moving +x
    "box_x_m": [-0.05, 0.40], "box_z_m": 0.30,
    "insert_z_lo_m": 0.0065, "insert_z_hi_m": 0.15, "insert_volume_fraction": 0.20,
    "settle_chunk_steps": 2000, "settle_max_chunks": 20, "settle_ke_per_grain_j": 1.0e-8,
    "wall_layer_m": 0.014, "consolidation_s": 0.3,
    "slide_speed_m_per_s": 0.02, "slide_distance_m": 0.06, "average_steps": 50,
    "normal_stresses_pa": [500.0, 1500.0, 3000.0],
    "steady_window_m": [0.02, 0.06],
}
SMOKE = {
    "repose": dict(REPOSE, cylinder_radius_m=0.03, cylinder_height_m=0.10, domain_half_width_m=0.08,
                   domain_z_m=0.25, base_layer_z_top_m=0.02, base_settle_steps=50, fill_z_lo_m=0.025,
                   fill_z_hi_m=0.08, settle_chunk_steps=100, settle_max_chunks=1, settle2_max_chunks=1,
                   lift_distance_m=0.0075, lift_speed_m_per_s=0.05),
    "density": dict(DENSITY, length_x_m=0.10, width_y_m=0.10, strike_height_m=0.04, insert_z_hi_m=0.08,
                    settle_chunk_steps=100, settle_max_chunks=2, settle2_max_chunks=1,
                    measure_margin_walls_m=0.02, measure_margin_floor_m=0.005, measure_margin_top_m=0.005),
    "shear": dict(SHEAR, length_x_m=0.08, width_y_m=0.06, insert_z_hi_m=0.10, settle_chunk_steps=100,
                  settle_max_chunks=2, consolidation_s=0.005, shear_speed_m_per_s=0.2,
                  shear_distance_m=0.002, last_window_m=0.001, normal_stresses_pa=[1000.0],
                  peak_search_to_m=0.002, peak_smoothing_m=0.0002, residual_window_m=[0.0, 0.002]),
    "soiltool": dict(SOILTOOL, frame_x_m=[0.02, 0.10], width_y_m=0.06, plate_x_m=[0.0, 0.12],
                     box_x_m=[-0.02, 0.14], insert_z_hi_m=0.06, settle_chunk_steps=100, settle_max_chunks=1,
                     consolidation_s=0.005, slide_speed_m_per_s=0.2, slide_distance_m=0.002,
                     steady_window_m=[0.0, 0.002], normal_stresses_pa=[1000.0]),
}


def _wd(*p):
    return os.path.join(dem.WORK, "material", *p)


def _steps(t, mult=50):
    return max(mult, int(round(t / dem.TIMESTEP_S / mult)) * mult)


# ----------------------------------------------------------------- repose
def write_cylinder_stl(path, R, H, nseg):
    with open(path, "w") as f:
        f.write("solid cylinder\n")
        for k in range(nseg):
            a0, a1 = 2 * math.pi * k / nseg, 2 * math.pi * (k + 1) / nseg
            p = [(R * math.cos(a0), R * math.sin(a0), 0.0), (R * math.cos(a1), R * math.sin(a1), 0.0),
                 (R * math.cos(a1), R * math.sin(a1), H), (R * math.cos(a0), R * math.sin(a0), H)]
            am = 0.5 * (a0 + a1)
            n = (-math.cos(am), -math.sin(am), 0.0)  # inward
            for tri in ((p[0], p[2], p[1]), (p[0], p[3], p[2])):
                f.write("  facet normal %.6e %.6e %.6e\n    outer loop\n" % n)
                for q in tri:
                    f.write("      vertex %.9e %.9e %.9e\n" % q)
                f.write("    endloop\n  endfacet\n")
        f.write("endsolid cylinder\n")


def run_repose(seed, smoke=False):
    P = SMOKE["repose"] if smoke else REPOSE
    wd = _wd("smoke" if smoke else "repose", "seed%d" % seed)
    c = _cached(os.path.join(wd, "repose.json"), smoke)
    if c:
        return c
    os.makedirs(wd, exist_ok=True)
    stl = os.path.join(wd, "cylinder.stl")
    write_cylinder_stl(stl, P["cylinder_radius_m"], P["cylinder_height_m"], P["cylinder_segments"])
    v, primes = dem.material_vars(seed, 2)
    nlift = _steps(P["lift_distance_m"] / P["lift_speed_m_per_s"])
    vlift = P["lift_distance_m"] / (nlift * dem.TIMESTEP_S)
    if smoke:
        nlift = 100
    v.update({
        "half": P["domain_half_width_m"], "zbox": P["domain_z_m"], "zbase": P["base_layer_z_top_m"],
        "vfbase": P["base_insert_volume_fraction"], "nbase": P["base_settle_steps"], "cylstl": stl,
        "rins": P["cylinder_radius_m"] - 0.0065, "zinslo": P["fill_z_lo_m"], "zinshi": P["fill_z_hi_m"],
        "vf": P["fill_volume_fraction"], "chunk": P["settle_chunk_steps"], "nchunk": P["settle_max_chunks"],
        "nchunk2": P["settle2_max_chunks"], "ketol": P["settle_ke_per_grain_j"],
        "vlift": vlift, "nlift": nlift,
        "dumpfill": os.path.join(wd, "fill.dump"), "dump": os.path.join(wd, "heap.dump"),
        "dumpbase": os.path.join(wd, "base.dump"),
    })
    wall = dem.run_liggghts(os.path.join(HERE, "repose.in"), v, wd, "repose")
    res = heap_angle(dem.read_dump(v["dump"]), dem.read_dump(v["dumpbase"]), P)
    res.update({"seed": seed, "liggghts_seed_primes": primes, "wall_s": wall, "lift_speed_m_per_s": vlift})
    if not smoke:
        dem.log_cost("material_repose", "seed%d" % seed, wall, "%d heap grains" % res["heap_grains"])
    dem.write_json(os.path.join(wd, "repose.json"), res)
    return res


def heap_angle(d, base, P):
    """Flank angle of the heap grains d above the frozen base grains.  Heights are measured from
    the base surface (mean top of the base grains).  In each of P['sectors']
    azimuthal sectors, the upper envelope max(z + r) is taken in radial bins;
    bins whose envelope lies between 20 % and 80 % of the heap height are
    fitted by least squares h = a - tan(theta) rho; the angle is the mean over
    sectors."""
    zb = float((base["z"] + base["radius"]).mean())
    x, y, z, r = (d[k] for k in ("x", "y", "z", "radius"))
    rho = np.hypot(x, y)
    top = z + r - zb
    H = float(top.max())
    lo, hi = P["fit_band"]
    nb = P["radial_bin_m"]
    angles = []
    prof = []
    az = np.arctan2(y, x)
    for s in range(P["sectors"]):
        a0 = -math.pi + 2 * math.pi * s / P["sectors"]
        a1 = a0 + 2 * math.pi / P["sectors"]
        sel = (az >= a0) & (az < a1)
        if sel.sum() < 10:
            continue
        bins = np.floor(rho[sel] / nb).astype(int)
        env = {}
        for b, t in zip(bins, top[sel]):
            env[b] = max(env.get(b, -1e9), t)
        bs = np.array(sorted(env))
        hs = np.array([env[b] for b in bs])
        rs = (bs + 0.5) * nb
        # keep the outer flank: from the bin of the sector's highest envelope outwards
        k0 = int(np.argmax(hs))
        rs, hs = rs[k0:], hs[k0:]
        band = (hs >= lo * H) & (hs <= hi * H)
        if band.sum() < 3:
            continue
        slope, icpt = np.polyfit(rs[band], hs[band], 1)
        angles.append(math.degrees(math.atan(-slope)))
        prof.append({"sector": s, "angle_deg": angles[-1], "points": int(band.sum())})
    return {
        "repose_deg": float(np.mean(angles)) if angles else float("nan"),
        "repose_sector_std_deg": float(np.std(angles)) if angles else float("nan"),
        "sectors": prof, "heap_height_m": H, "base_surface_z_m": zb,
        "heap_grains": int(len(x)), "base_grains": int(len(base["x"])),
    }


# ---------------------------------------------------------------- density
def run_density(seed, smoke=False):
    P = SMOKE["density"] if smoke else DENSITY
    wd = _wd("smoke" if smoke else "density", "seed%d" % seed)
    c = _cached(os.path.join(wd, "density.json"), smoke)
    if c:
        return c
    v, primes = dem.material_vars(seed, 3)
    restart, dump = os.path.join(wd, "bed.restart"), os.path.join(wd, "bed.dump")
    v.update({
        "bxlo": P["box_x_lo_m"], "Lx": P["length_x_m"], "Ly": P["width_y_m"], "zbox": P["box_z_hi_m"],
        "zinslo": P["insert_z_lo_m"], "zinshi": P["insert_z_hi_m"], "vf": P["insert_volume_fraction"],
        "Hstrike": P["strike_height_m"], "chunk": P["settle_chunk_steps"], "nchunk": P["settle_max_chunks"],
        "nchunk2": P["settle2_max_chunks"], "ketol": P["settle_ke_per_grain_j"],
        "restart": restart, "dumpfile": dump,
    })
    wall = dem.run_liggghts(os.path.join(dem.HERE, "bed.in"), v, wd, "bed")
    d = dem.read_dump(dump)
    x, y, z, r = d["x"], d["y"], d["z"], d["radius"]
    cell = 0.005
    nx, ny = int(round(P["length_x_m"] / cell)), int(round(P["width_y_m"] / cell))
    g, _ = dem.envelope_grid(x, y, z, r, 0.0, 0.0, nx, ny, cell)
    mw = P["measure_margin_walls_m"]
    m = int(round(mw / cell))
    H0 = float(g[m:ny - m, m:nx - m].mean())
    box = (mw, P["length_x_m"] - mw, mw, P["width_y_m"] - mw,
           P["measure_margin_floor_m"], H0 - P["measure_margin_top_m"])
    phi, err = dem.solid_fraction_box(x, y, z, r, box, npts=200000 if not smoke else 5000)
    res = {"seed": seed, "liggghts_seed_primes": primes, "solid_fraction": phi, "solid_fraction_mc_err": err,
           "bulk_density_kg_per_m3": phi * dem.PARTICLE["density_kg_per_m3"], "measure_box_m": box,
           "surface_mean_m": H0, "grains": int(len(x)), "wall_s": wall}
    if not smoke:
        dem.log_cost("material_density", "seed%d" % seed, wall, "%d grains" % len(x))
    dem.write_json(os.path.join(wd, "density.json"), res)
    return res


# ------------------------------------------------------------ shear cells
def _cached(path, smoke):
    if not smoke and os.path.exists(path):
        with open(path) as f:
            return json.load(f)
    return None


def run_shear_cell(seed, sigma, rough=1, smoke=False):
    """Periodic plane shear cell (internal friction).  shear.in also has a
    smooth-floor variant (rough=0), not used for the results: with the
    sample's weight on the plate the cell then shears under the lid at low
    load instead of sliding on the plate (see run_soiltool)."""
    P = SMOKE["shear"] if smoke else SHEAR
    kind = "shear" if rough else "shear_smooth"
    wd = _wd("smoke" if smoke else kind, "seed%d_s%04d" % (seed, int(sigma)))
    if smoke:
        wd = _wd("smoke", "%s_seed%d" % (kind, seed))
    c = _cached(os.path.join(wd, "result.json"), smoke)
    if c:
        return c
    os.makedirs(wd, exist_ok=True)
    v, primes = dem.material_vars(seed, 4 if rough else 5)
    dt = dem.TIMESTEP_S
    navg = P["average_steps"]
    ncons = _steps(P["consolidation_s"])
    n2 = _steps(P["last_window_m"] / P["shear_speed_m_per_s"])
    n1 = _steps((P["shear_distance_m"] - P["last_window_m"]) / P["shear_speed_m_per_s"])
    vs = P["shear_distance_m"] / ((n1 + n2) * dt)
    v.update({
        "Lx": P["length_x_m"], "Ly": P["width_y_m"], "zbox": P["box_z_m"], "zinslo": P["insert_z_lo_m"],
        "zinshi": P["insert_z_hi_m"], "vf": P["insert_volume_fraction"], "chunk": P["settle_chunk_steps"],
        "nchunk": P["settle_max_chunks"], "ketol": P["settle_ke_per_grain_j"], "layer": P["wall_layer_m"],
        "rough": 1 if rough else 0, "sigma": sigma, "ncons": ncons, "vshear": vs, "navg": navg,
        "nshear1": n1, "nshear2": n2, "outfile": os.path.join(wd, "shear.txt"),
        "dumpa": os.path.join(wd, "a.dump"), "dumpb": os.path.join(wd, "b.dump"),
    })
    wall = dem.run_liggghts(os.path.join(HERE, "shear.in"), v, wd, "shear")
    grp = None
    for l in open(os.path.join(wd, "screen.shear"), errors="replace"):
        if l.startswith("GROUPS"):
            p = l.split()
            grp = {p[i]: float(p[i + 1]) for i in range(1, len(p) - 1, 2)}
    A = P["length_x_m"] * P["width_y_m"]
    g = 9.81
    rows = np.loadtxt(v["outfile"], comments="#", ndmin=2)
    # rows: step, fx_top, fy_top, fz_top(before aveforce), z_lid
    s_shear0 = None
    # the shear starts after: 1 + 49 + settling chunks + ncons; recover from the first ave/time row
    s_shear0 = rows[0, 0] - navg
    u = (rows[:, 0] - s_shear0 - (navg - 1) / 2.0) * dt * vs
    tau = rows[:, 1] / A
    da, db = dem.read_dump(v["dumpa"]), dem.read_dump(v["dumpb"])
    prof = velocity_profile(da, db, (n2) * dt, vs, P, grp)
    if rough:
        # normal stress on the shear band: load + lid weight + weight of the grains above the band centre
        sig_n = sigma + (grp["mtop"] * g + prof["mass_above_band_kg"] * g) / A
    else:
        # normal stress on the steel plate: load + lid + whole sample
        sig_n = sigma + (grp["mtop"] + grp["msample"]) * g / A
    mu = tau / sig_n
    res = {"seed": seed, "kind": kind, "sigma_applied_pa": sigma, "sigma_normal_pa": sig_n,
           "area_m2": A, "shear_speed_m_per_s": vs, "groups": grp, "liggghts_seed_primes": primes,
           "velocity_profile": prof, "wall_s": wall}
    w = max(1, int(round(P["peak_smoothing_m"] / (vs * navg * dt))))
    mus = np.convolve(mu, np.ones(w) / w, mode="same")
    pk = u <= P["peak_search_to_m"]
    edge = slice(w // 2, len(mus) - w // 2) if w > 1 else slice(None)
    mus_e = np.full_like(mus, -np.inf)
    mus_e[edge] = mus[edge]
    ipk = int(np.argmax(np.where(pk, mus_e, -np.inf)))
    rw = (u >= P["residual_window_m"][0]) & (u <= P["residual_window_m"][1])
    res.update({
        "tau_peak_pa": float(mus[ipk] * sig_n), "mu_peak": float(mus[ipk]), "u_peak_m": float(u[ipk]),
        "tau_residual_pa": float(tau[rw].mean()), "mu_residual": float(mu[rw].mean()),
        "mu_residual_window_std": float(mu[rw].std()),
        "lid_rise_m": float(rows[-1, 4] - rows[0, 4]),
    })
    np.savetxt(os.path.join(wd, "mu_u.txt"), np.column_stack([u, mu]), header="u_m mu", fmt="%.6g")
    if not smoke:
        dem.log_cost("material_" + kind, "seed%d/sigma%d" % (seed, sigma), wall,
                     "%d grains" % int(grp["ntop"] + (grp["msample"] + grp["mbottom"]) / 1.37e-3))
    dem.write_json(os.path.join(wd, "result.json"), res)
    return res


def velocity_profile(da, db, dt_ab, vdrive, P, grp):
    """Mean x-velocity of grains over the last window, binned in z; the shear
    band centre is where it crosses half the drive speed (its position sets
    the normal stress on the band: grains above it load it)."""
    ia = np.argsort(da["id"])
    ib = np.argsort(db["id"])
    za = da["z"][ia]
    vx = (db["xu"][ib] - da["xu"][ia]) / dt_ab
    m = da["mass"][ia]
    h = 0.005
    nb = int(math.ceil(za.max() / h)) + 1
    k = np.floor(za / h).astype(int)
    prof = []
    for b in range(nb):
        s = k == b
        if s.sum() >= 3:
            prof.append(((b + 0.5) * h, float(vx[s].mean() / vdrive)))
    zs = np.array([p[0] for p in prof])
    vs = np.array([p[1] for p in prof])
    # first crossing of 0.5 from the top down
    zband = float("nan")
    for j in range(len(vs) - 1, 0, -1):
        if (vs[j] - 0.5) * (vs[j - 1] - 0.5) <= 0 and vs[j] != vs[j - 1]:
            zband = float(zs[j - 1] + (0.5 - vs[j - 1]) * (zs[j] - zs[j - 1]) / (vs[j] - vs[j - 1]))
            break
    if not np.isfinite(zband):
        zband = float(zs[len(zs) // 2])
    above = za > zband
    # grains of the top layer are counted separately (their weight is in mtop)
    ztop_cut = za.max() - P["wall_layer_m"] - 0.02
    mass_above = float(m[above].sum())
    return {"z_m": zs.tolist(), "vx_over_drive": vs.tolist(), "band_z_m": zband,
            "mass_above_band_incl_lid_kg": mass_above,
            "mass_above_band_kg": max(0.0, mass_above - grp["mtop"])}


# -------------------------------------------------------------- soil-tool
def write_plate_stl(path, x0, x1, y0, y1, cell):
    nx = max(1, int(round((x1 - x0) / cell)))
    ny = max(1, int(round((y1 - y0) / cell)))
    xs, ys = np.linspace(x0, x1, nx + 1), np.linspace(y0, y1, ny + 1)
    with open(path, "w") as f:
        f.write("solid plate\n")
        for i in range(nx):
            for j in range(ny):
                a, b, c, d = ((xs[i], ys[j]), (xs[i + 1], ys[j]), (xs[i + 1], ys[j + 1]), (xs[i], ys[j + 1]))
                for tri in ((a, b, c), (a, c, d)):
                    f.write("  facet normal 0 0 1\n    outer loop\n")
                    for q in tri:
                        f.write("      vertex %.9e %.9e 0.0\n" % q)
                    f.write("    endloop\n  endfacet\n")
        f.write("endsolid plate\n")


def run_soiltool(seed, sigma, smoke=False):
    P = SMOKE["soiltool"] if smoke else SOILTOOL
    wd = _wd("smoke", "soiltool_seed%d" % seed) if smoke else _wd("soiltool", "seed%d_s%04d" % (seed, int(sigma)))
    c = _cached(os.path.join(wd, "result.json"), smoke)
    if c:
        return c
    os.makedirs(wd, exist_ok=True)
    Ly = P["width_y_m"]
    stl = os.path.join(wd, "plate.stl")
    write_plate_stl(stl, P["plate_x_m"][0], P["plate_x_m"][1], -0.01, Ly + 0.01, P["plate_cell_m"])
    v, primes = dem.material_vars(seed, 5)
    dt = dem.TIMESTEP_S
    navg = P["average_steps"]
    ncons = _steps(P["consolidation_s"])
    nsl = _steps(P["slide_distance_m"] / P["slide_speed_m_per_s"])
    vs = P["slide_distance_m"] / (nsl * dt)
    v.update({
        "bxlo": P["box_x_m"][0], "bxhi": P["box_x_m"][1], "byhi": Ly + 0.02, "zbox": P["box_z_m"],
        "platestl": stl, "fx0": P["frame_x_m"][0], "fx1": P["frame_x_m"][1], "Ly": Ly,
        "zinslo": P["insert_z_lo_m"], "zinshi": P["insert_z_hi_m"], "vf": P["insert_volume_fraction"],
        "chunk": P["settle_chunk_steps"], "nchunk": P["settle_max_chunks"], "ketol": P["settle_ke_per_grain_j"],
        "layer": P["wall_layer_m"], "sigma": sigma, "ncons": ncons, "vshear": vs, "navg": navg, "nshear": nsl,
        "outfile": os.path.join(wd, "plate.txt"),
    })
    wall = dem.run_liggghts(os.path.join(HERE, "soiltool.in"), v, wd, "soiltool")
    grp = None
    for l in open(os.path.join(wd, "screen.soiltool"), errors="replace"):
        if l.startswith("GROUPS"):
            p = l.split()
            grp = {p[i]: float(p[i + 1]) for i in range(1, len(p) - 1, 2)}
    rows = np.loadtxt(v["outfile"], comments="#", ndmin=2)   # step fx fy fz zlid
    s0 = rows[0, 0] - navg
    u = (rows[:, 0] - s0 - (navg - 1) / 2.0) * dt * vs
    w = (u >= P["steady_window_m"][0]) & (u <= P["steady_window_m"][1])
    fx, fz = rows[w, 1], rows[w, 3]
    A = (P["frame_x_m"][1] - P["frame_x_m"][0]) * Ly
    with np.errstate(invalid="ignore", divide="ignore"):  # a smoke run may not touch the plate yet
        tan_d = float(abs(fx.mean()) / abs(fz.mean()))
        ratio_std = float(np.std(fx / fz))
        ratio = rows[:, 1] / rows[:, 3]
    res = {"seed": seed, "sigma_applied_pa": sigma, "sigma_normal_pa": float(abs(fz.mean()) / A),
           "tan_delta": tan_d, "delta_deg": math.degrees(math.atan(tan_d)),
           "tan_delta_window_std": ratio_std, "plate_fx_mean_n": float(fx.mean()),
           "plate_fz_mean_n": float(fz.mean()), "slide_speed_m_per_s": vs, "groups": grp,
           "liggghts_seed_primes": primes, "wall_s": wall}
    np.savetxt(os.path.join(wd, "ratio_u.txt"), np.column_stack([u, ratio]),
               header="u_m fx/fz", fmt="%.6g")
    if not smoke:
        dem.log_cost("material_soiltool", "seed%d/sigma%d" % (seed, sigma), wall,
                     "%d grains" % int(grp["ntop"] + grp["msample"] / 1.37e-3))
    dem.write_json(os.path.join(wd, "result.json"), res)
    return res


# ----------------------------------------------------------------- driver
def mohr_coulomb(sig, tau):
    sig, tau = np.asarray(sig), np.asarray(tau)
    slope, c = np.polyfit(sig, tau, 1)
    return math.degrees(math.atan(slope)), float(c)


def tests_of(seeds, smoke=False):
    """Every material test of the seeds, in order, as (kind, seed, normal
    stress): the units of work a cluster can run side by side (each writes
    its own work folder)."""
    tests = []
    for s in seeds:
        tests.append(("repose", s, 0.0))
        tests.append(("density", s, 0.0))
        tests += [("shear", s, sg) for sg in (SMOKE["shear"] if smoke else SHEAR)["normal_stresses_pa"]]
        tests += [("soiltool", s, sg) for sg in (SMOKE["soiltool"] if smoke else SOILTOOL)["normal_stresses_pa"]]
    return tests


def run_test(test, smoke=False):
    """One material test (an item of tests_of): its result dict."""
    kind, seed, sigma = test
    if kind == "repose":
        return run_repose(seed, smoke)
    if kind == "density":
        return run_density(seed, smoke)
    if kind == "shear":
        return run_shear_cell(seed, sigma, 1, smoke)
    if kind == "soiltool":
        return run_soiltool(seed, sigma, smoke)
    raise ValueError("unknown material test %r" % (kind,))


def run_all(seeds, smoke=False, outpath=None, map_tests=None):
    """Every material test of the seeds, then material.json.  map_tests, when
    given, runs a list of tests and returns their results in order (a Dask
    cluster's map: run.py material --scheduler/--local-workers); else they
    run here one after the other."""
    t0 = time.time()
    tests = tests_of(seeds, smoke)
    results = map_tests(tests) if map_tests else [run_test(t, smoke) for t in tests]
    if len(results) != len(tests):
        raise RuntimeError("%d material tests gave %d results" % (len(tests), len(results)))
    rep, den = {}, {}
    sh, st = {s: [] for s in seeds}, {s: [] for s in seeds}
    for (kind, seed, _), r in zip(tests, results):
        if kind == "repose":
            rep[seed] = r
        elif kind == "density":
            den[seed] = r
        elif kind == "shear":
            sh[seed].append(r)
        else:
            st[seed].append(r)
    return assemble(seeds, rep, den, sh, st, time.time() - t0, smoke, outpath)


def assemble(seeds, rep, den, sh, st, wall_total, smoke=False, outpath=None):
    out = {"description": {
        "repose_deg": ("lifted cylinder (radius %.3f m = 13 mean grain diameters, steel) on a rough base "
                       "(frozen grain layer), filled by pouring, lifted at %.2f m/s; flank angle by least "
                       "squares on the upper envelope max(z+r) in 5 mm radial bins between 20%% and 80%% "
                       "of the heap height, mean over 8 azimuthal sectors"
                       % (REPOSE["cylinder_radius_m"], REPOSE["lift_speed_m_per_s"])),
        "bulk_density_kg_per_m3": ("bed poured like the bulldozing beds (grains released at rest at random "
                                   "in a region up to 0.30 m high, volume fraction 0.25, fall and settle, "
                                   "struck off at 0.12 m) in a 0.30 x 0.30 m steel box; solid fraction by "
                                   "Monte-Carlo points in a box 0.06 m from the walls, 0.02 m above the "
                                   "floor and 0.025 m below the mean surface, times the grain density"),
        "internal_friction": ("periodic plane shear cell (0.20 x 0.15 m, periodic in x and y, ~0.08 m of "
                              "grains): the bottom grain layer is driven along x at 0.02 m/s, the top grain "
                              "layer is a rough lid under constant normal load that moves only vertically; "
                              "tau = x-force on the lid / area; normal stress on the shear band = load + lid "
                              "weight + weight of the grains above the band centre (from the velocity "
                              "profile); peak = max of tau/sigma (smoothed over 2 mm) in the first 30 mm, "
                              "residual = mean over 50-100 mm of displacement; Mohr-Coulomb straight-line "
                              "fit tau = c + sigma tan(phi) over the normal stresses; chosen over a split "
                              "box because it has no side-wall friction, no area correction and reaches "
                              "the critical state"),
        "soil_tool_friction_deg": ("grains (~0.05 m deep) held in a fixed steel frame 0.20 x 0.15 m, pressed by "
                                   "a rough grain lid under a constant load, on a steel plate (the blade's "
                                   "material) sliding under them at 0.02 m/s; tan(delta) = |Fx| / |Fz| of the "
                                   "force the grains exert on the plate, averaged over steady sliding "
                                   "(20-60 mm); mean over the normal stresses"),
    }}
    out["seeds"] = list(seeds)
    R = [rep[s]["repose_deg"] for s in seeds]
    out.update(_ms("repose_deg", R))
    out.update(_ms("bulk_density_kg_per_m3", [den[s]["bulk_density_kg_per_m3"] for s in seeds]))
    out.update(_ms("solid_fraction", [den[s]["solid_fraction"] for s in seeds]))
    pk, rs, cp, cr = [], [], [], []
    for s in seeds:
        sig = [r["sigma_normal_pa"] for r in sh[s]]
        p_, c_ = mohr_coulomb(sig, [r["tau_peak_pa"] for r in sh[s]]) if len(sig) > 1 else (
            math.degrees(math.atan(sh[s][0]["mu_peak"])), 0.0)
        r_, cr_ = mohr_coulomb(sig, [r["tau_residual_pa"] for r in sh[s]]) if len(sig) > 1 else (
            math.degrees(math.atan(sh[s][0]["mu_residual"])), 0.0)
        pk.append(p_); cp.append(c_); rs.append(r_); cr.append(cr_)
    out.update(_ms("internal_friction_peak_deg", pk))
    out.update(_ms("cohesion_pa", cp))
    out.update(_ms("internal_friction_residual_deg", rs))
    out.update(_ms("cohesion_residual_pa", cr))
    out["shear_tests"] = {str(s): [{k: r[k] for k in ("sigma_applied_pa", "sigma_normal_pa", "tau_peak_pa",
                                                      "mu_peak", "u_peak_m", "tau_residual_pa", "mu_residual",
                                                      "lid_rise_m")} | {
        "band_z_m": r["velocity_profile"]["band_z_m"],
        "mobilised_peak_deg": math.degrees(math.atan(r["mu_peak"])),
        "mobilised_residual_deg": math.degrees(math.atan(r["mu_residual"]))} for r in sh[s]] for s in seeds}
    d = []
    for s in seeds:
        d.append(float(np.mean([r["delta_deg"] for r in st[s]])))
    out.update(_ms("soil_tool_friction_deg", d))
    out["soil_tool_tests"] = {str(s): [{k: r[k] for k in ("sigma_applied_pa", "sigma_normal_pa", "tan_delta",
                                                          "delta_deg", "tan_delta_window_std")}
                                       for r in st[s]] for s in seeds}
    out["repose_tests"] = {str(s): {k: rep[s][k] for k in ("repose_deg", "repose_sector_std_deg",
                                                           "heap_height_m", "heap_grains")} for s in seeds}
    out["density_tests"] = {str(s): {k: den[s][k] for k in ("bulk_density_kg_per_m3", "solid_fraction",
                                                            "solid_fraction_mc_err", "measure_box_m",
                                                            "grains")} for s in seeds}
    out["test_parameters"] = {"repose": REPOSE, "density": DENSITY, "shear": SHEAR, "soil_tool": SOILTOOL}
    out["parameters"] = dem.parameters_json()
    per = ([rep[s]["wall_s"] for s in seeds] + [den[s]["wall_s"] for s in seeds]
           + [r["wall_s"] for s in seeds for r in sh[s]] + [r["wall_s"] for s in seeds for r in st[s]])
    out["wall_clock_s"] = {
        "sum_of_liggghts_runs": float(sum(per)),
        "note": "one core, nice -n 19, machine shared with a C++ build; per-run values below",
        "repose_per_seed": [rep[s]["wall_s"] for s in seeds],
        "density_per_seed": [den[s]["wall_s"] for s in seeds],
        "shear_per_test": [r["wall_s"] for s in seeds for r in sh[s]],
        "soil_tool_per_test": [r["wall_s"] for s in seeds for r in st[s]],
    }
    out["smoke"] = smoke
    if outpath is None:
        outpath = os.path.join(dem.RESULTS, "material.json") if not smoke else _wd("smoke", "material.json")
    dem.write_json(outpath, out)
    return out


def _ms(key, vals):
    mu, sd = dem.mean_std(vals)
    base = key
    for unit in ("_deg", "_pa", "_kg_per_m3"):
        if key.endswith(unit):
            base = key[: -len(unit)]
            std_key = base + "_std" + unit
            break
    else:
        std_key = key + "_std"
    return {key: mu, std_key: sd, key + "_per_seed": [float(v) for v in vals]}
