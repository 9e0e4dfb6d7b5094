"""Shared pieces of the DEM reference runs: the particle/wall parameters (one
place, never tuned to terracut), the Rayleigh timestep check, seed -> LIGGGHTS
prime seeds, the LIGGGHTS runner, dump reading and the upper-envelope height
grid.  Python 3 with numpy/scipy only (/usr/bin/python3)."""

import json
import math
import resource
import os
import re
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
DEM = os.path.dirname(HERE)                      # validation/dem
WORK = os.path.join(DEM, "work")                 # scratch, git-ignored
RESULTS = os.path.join(DEM, "results")
LIGGGHTS = os.environ.get("LIGGGHTS", "liggghts")

# --------------------------------------------------------------------------
# Parameters (SI).  Chosen once from DEM practice, see README.md.
# Atom type 1 = grain, type 2 = steel (floor, walls, blade, plates).
# --------------------------------------------------------------------------
PARTICLE = {
    "radius_min_m": 0.004,
    "radius_max_m": 0.006,
    # uniform number distribution on [4, 6] mm, discretised in 5 equal-number
    # classes at the class mid-points (LIGGGHTS only has constant-radius
    # templates); the mean radius (5 mm) equals the continuous one.
    "radius_classes_m": [0.0042, 0.0046, 0.0050, 0.0054, 0.0058],
    "radius_class_number_fractions": [0.2, 0.2, 0.2, 0.2, 0.2],
    "density_kg_per_m3": 2500.0,
    "youngs_modulus_pa": 1.0e7,
    "poisson_ratio": 0.3,
    "restitution_pp": 0.4,
    "friction_pp": 0.5,
    "rolling_friction_pp": 0.3,
}
WALL = {
    "material": "steel-like (floor, box walls, blade, shear-box frames, plates)",
    # the wall modulus is softened like the grains' (a stiff wall would only
    # change the grain-wall contact stiffness by <= 2x); steel-like in friction
    # and restitution.
    "youngs_modulus_pa": 1.0e7,
    "poisson_ratio": 0.3,
    "restitution_pw": 0.4,
    "friction_pw": 0.4,
    "rolling_friction_pw": 0.3,
}
CONTACT_MODEL = ("pair_style gran model hertz tangential history "
                 "rolling_friction epsd2")
TIMESTEP_S = 5.0e-5
SKIN_M = 0.002
GRAVITY = [0.0, 0.0, -9.81]


def rayleigh_check(dt=TIMESTEP_S):
    """Rayleigh time of the smallest grain and dt / T_R."""
    p = PARTICLE
    nu = p["poisson_ratio"]
    G = p["youngs_modulus_pa"] / (2.0 * (1.0 + nu))
    rmin = p["radius_min_m"]
    tr = math.pi * rmin * math.sqrt(p["density_kg_per_m3"] / G) / (0.1631 * nu + 0.8766)
    return {
        "formula": "T_R = pi r_min sqrt(rho/G) / (0.1631 nu + 0.8766), G = E/(2(1+nu))",
        "r_min_m": rmin,
        "shear_modulus_pa": G,
        "rayleigh_time_s": tr,
        "timestep_s": dt,
        "dt_over_rayleigh": dt / tr,
        "criterion": "dt <= 0.2 T_R",
        "ok": dt <= 0.2 * tr,
    }


def liggghts_version():
    try:
        out = subprocess.run([LIGGGHTS, "-h"], capture_output=True, text=True,
                             timeout=30).stdout
        m = re.search(r"LIGGGHTS \(Version ([^,]+)", out)
        return m.group(1) if m else out.splitlines()[0]
    except Exception as e:  # pragma: no cover
        return "unknown (%s)" % e


def _is_prime(n):
    if n < 2:
        return False
    if n % 2 == 0:
        return n == 2
    f = 3
    while f * f <= n:
        if n % f == 0:
            return False
        f += 2
    return True


def primes_for(seed, salt, count):
    """LIGGGHTS wants distinct primes > 10000 as seeds.  A run seed k (and a
    salt naming the test) maps deterministically to `count` primes."""
    n = 100000 + 7919 * int(seed) + 131 * int(salt)
    out = []
    while len(out) < count:
        n += 1
        if _is_prime(n):
            out.append(n)
    return out


def material_vars(seed, salt):
    """-var values shared by every script (materials.in, particles.in)."""
    p, w = PARTICLE, WALL
    pr = primes_for(seed, salt, 8)
    v = {
        "E": p["youngs_modulus_pa"], "Ew": w["youngs_modulus_pa"],
        "nu": p["poisson_ratio"], "nuw": w["poisson_ratio"],
        "epp": p["restitution_pp"], "epw": w["restitution_pw"],
        "mupp": p["friction_pp"], "mupw": w["friction_pw"],
        "murpp": p["rolling_friction_pp"], "murpw": w["rolling_friction_pw"],
        "dt": TIMESTEP_S, "skin": SKIN_M, "rho": p["density_kg_per_m3"],
        "incdir": HERE,
    }
    for i, r in enumerate(p["radius_classes_m"]):
        v["r%d" % (i + 1)] = r
        v["pt%d" % (i + 1)] = pr[i]
    v["pdd"] = pr[5]
    v["seedins"] = pr[6]
    v["seedins2"] = pr[7]
    return v, pr


def parameters_json():
    return {
        "particle": PARTICLE,
        "wall": WALL,
        "contact_model": CONTACT_MODEL + " (fix wall/gran likewise)",
        "timestep_s": TIMESTEP_S,
        "neighbor_skin_m": SKIN_M,
        "gravity_m_per_s2": GRAVITY,
        "rayleigh_check": rayleigh_check(),
        "liggghts_version": liggghts_version(),
        "frame": "LIGGGHTS frame: z up (gravity -z), x push/shear direction, y across",
    }


# --------------------------------------------------------------------------
# Running LIGGGHTS
# --------------------------------------------------------------------------
class LiggghtsError(RuntimeError):
    pass


LAST_CPU_S = None   # CPU seconds (user+sys) of the last LIGGGHTS process


def _child_cpu():
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def run_liggghts(script, variables, workdir, tag, timeout=None):
    """Run `nice -n 19 liggghts -in script -var ...` in workdir (one process,
    no MPI).  Returns wall-clock seconds.  Raises LiggghtsError when the exit
    status is non-zero or the log holds an ERROR line."""
    workdir = os.path.abspath(workdir)
    os.makedirs(workdir, exist_ok=True)
    log = os.path.join(workdir, "log.%s" % tag)
    screen = os.path.join(workdir, "screen.%s" % tag)
    script = os.path.abspath(script)
    cmd = ["nice", "-n", "19", LIGGGHTS, "-in", script, "-log", log, "-nocite"]
    for k, v in variables.items():
        cmd += ["-var", k, _fmt(v)]
    with open(os.path.join(workdir, "cmd.%s" % tag), "w") as f:
        f.write(" ".join(cmd) + "\n")
    global LAST_CPU_S
    c0 = _child_cpu()
    t0 = time.time()
    with open(screen, "w") as out:
        proc = subprocess.run(cmd, cwd=workdir, stdout=out, stderr=subprocess.STDOUT,
                              timeout=timeout)
    wall = time.time() - t0
    LAST_CPU_S = _child_cpu() - c0
    text = open(screen, errors="replace").read()
    if os.path.exists(log):
        text += open(log, errors="replace").read()
    err = [l for l in text.splitlines() if l.startswith("ERROR")]
    if proc.returncode != 0 or err:
        tail = "\n".join(text.splitlines()[-25:])
        raise LiggghtsError("LIGGGHTS %s failed (rc=%s): %s\n%s"
                            % (tag, proc.returncode, "; ".join(err), tail))
    return wall


def _fmt(v):
    if isinstance(v, float):
        return repr(v)
    return str(v)


# --------------------------------------------------------------------------
# Dumps and the upper-envelope height grid
# --------------------------------------------------------------------------
def read_dump(path):
    """Read a LIGGGHTS custom text dump (one snapshot) into a dict of arrays."""
    with open(path) as f:
        lines = f.readlines()
    i = next(k for k, l in enumerate(lines) if l.startswith("ITEM: ATOMS"))
    cols = lines[i].split()[2:]
    data = np.loadtxt(lines[i + 1:], ndmin=2) if len(lines) > i + 1 else np.zeros((0, len(cols)))
    step = int(lines[1].split()[0]) if lines[0].startswith("ITEM: TIMESTEP") else -1
    out = {c: data[:, j] for j, c in enumerate(cols)}
    out["_step"] = step
    return out


def envelope_grid(x, y, z, r, x0, y0, nx, ny, h):
    """Upper envelope of spheres on a grid: cell (j, i) (row j along y, column
    i along x) holds max over spheres of z + sqrt(r^2 - d^2), d the horizontal
    distance from the sphere centre to the cell centre (x0 + (i+1/2)h,
    y0 + (j+1/2)h).  Cells no sphere covers are filled with the mean of their
    covered neighbours, repeatedly.  Returns float32 (ny, nx) and the count of
    filled cells."""
    grid = np.full((ny, nx), -np.inf)
    xc = x0 + (np.arange(nx) + 0.5) * h
    yc = y0 + (np.arange(ny) + 0.5) * h
    order = np.argsort(z + r)  # no effect on the max; keeps it deterministic
    for k in order:
        i0 = max(int(math.floor((x[k] - r[k] - x0) / h)), 0)
        i1 = min(int(math.floor((x[k] + r[k] - x0) / h)), nx - 1)
        j0 = max(int(math.floor((y[k] - r[k] - y0) / h)), 0)
        j1 = min(int(math.floor((y[k] + r[k] - y0) / h)), ny - 1)
        if i1 < i0 or j1 < j0:
            continue
        dx = xc[i0:i1 + 1] - x[k]
        dy = yc[j0:j1 + 1] - y[k]
        d2 = dy[:, None] ** 2 + dx[None, :] ** 2
        inside = d2 <= r[k] ** 2
        top = np.where(inside, z[k] + np.sqrt(np.maximum(r[k] ** 2 - d2, 0.0)), -np.inf)
        sub = grid[j0:j1 + 1, i0:i1 + 1]
        np.maximum(sub, top, out=sub)
    missing = ~np.isfinite(grid)
    nfill = int(missing.sum())
    guard = 0
    while missing.any() and guard < max(nx, ny):
        guard += 1
        g = np.where(missing, 0.0, grid)
        w = (~missing).astype(float)
        s = np.zeros_like(g)
        c = np.zeros_like(g)
        for dj, di in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            s += np.roll(np.roll(g, dj, 0), di, 1) * _edge_mask(ny, nx, dj, di)
            c += np.roll(np.roll(w, dj, 0), di, 1) * _edge_mask(ny, nx, dj, di)
        fill = missing & (c > 0)
        grid[fill] = s[fill] / c[fill]
        missing = ~np.isfinite(grid)
    grid[~np.isfinite(grid)] = 0.0  # an empty bed: floor level
    return grid.astype(np.float32), nfill


def _edge_mask(ny, nx, dj, di):
    m = np.ones((ny, nx))
    if dj == 1:
        m[0, :] = 0
    elif dj == -1:
        m[-1, :] = 0
    if di == 1:
        m[:, 0] = 0
    elif di == -1:
        m[:, -1] = 0
    return m


def solid_fraction_box(x, y, z, r, box, npts=200000, seed=12345):
    """Monte-Carlo solid fraction inside an axis-aligned box
    (xlo, xhi, ylo, yhi, zlo, zhi): the fraction of uniformly drawn points
    that lie inside a sphere.  Deterministic (fixed generator seed)."""
    from scipy.spatial import cKDTree
    rng = np.random.default_rng(seed)
    lo = np.array(box[0::2])
    hi = np.array(box[1::2])
    pts = lo + (hi - lo) * rng.random((npts, 3))
    tree = cKDTree(np.column_stack([x, y, z]))
    rmax = float(r.max())
    hits = tree.query_ball_point(pts, rmax)
    inside = np.zeros(npts, bool)
    centres = np.column_stack([x, y, z])
    for n, lst in enumerate(hits):
        if lst:
            d2 = ((centres[lst] - pts[n]) ** 2).sum(1)
            inside[n] = bool((d2 <= r[lst] ** 2).any())
    phi = inside.mean()
    return float(phi), float(math.sqrt(phi * (1 - phi) / npts))


def write_json(path, obj):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        json.dump(obj, f, indent=1, sort_keys=False, default=_jsonable)
        f.write("\n")


def _jsonable(o):
    if isinstance(o, (np.floating,)):
        return float(o)
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.bool_):
        return bool(o)
    raise TypeError(type(o))


def mean_std(values):
    a = np.asarray(values, float)
    return float(a.mean()), float(a.std(ddof=1)) if a.size > 1 else 0.0


def log_cost(kind, tag, wall_s, extra=None):
    """Append one line per LIGGGHTS run to work/costs.log and
    results/costs.csv (the committed wall-clock log)."""
    os.makedirs(RESULTS, exist_ok=True)
    path = os.path.join(RESULTS, "costs.csv")
    new = not os.path.exists(path)
    with open(path, "a") as f:
        if new:
            f.write("date_utc,kind,tag,wall_s,note\n")
        f.write("%s,%s,%s,%.1f,%s\n" % (time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
                                        kind, tag, wall_s, (extra or "").replace(",", ";")))
