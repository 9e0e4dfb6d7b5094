"""Fit the soil of the earthmoving force model (McKyes' Fundamental
Earthmoving Equation) to a table of measured blade forces: the cohesion c
(Pa) and the internal friction angle phi (degrees; soil-tool friction
2/3 phi), with the unit weight known. scipy's least_squares when scipy is
installed, a Gauss-Newton fit with numpy's lstsq otherwise.

The table (CSV: a comment line, then width_m, depth_m, rake_angle_deg,
horizontal_n) is yours;
the one shipped, blade_forces.csv, is SYNTHETIC: the FEE for
c = 1.3 kPa, phi = 31.1 deg (terracut's dry sand) with 5 % Gaussian noise,
made by `calibrate_forces.py --synthesize blade_forces.csv`. The fit must
recover those values, which is what the example shows.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/calibrate_forces.py --out out/calibration
"""
import argparse
from pathlib import Path

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import terracut

TABLE = Path(__file__).with_name("blade_forces.csv")
UNIT_WEIGHT = 16.25e3  # N/m^3, known (weighed)


def model(params, width, depth, rake):
    """Horizontal FEE force (N) for soil params = (cohesion Pa, friction deg)."""
    cohesion, phi = params
    soil = {"unit_weight_n_per_m3": UNIT_WEIGHT, "cohesion_pa": cohesion, "adhesion_pa": 0.0,
            "internal_friction_deg": phi, "soil_tool_friction_deg": 2 * phi / 3}
    out = np.empty_like(width)
    for r in np.unique(rake):  # one call per rake angle, arrays inside
        sel = rake == r
        # The table's blades are wide against their depths: the 2-D equation
        # (side_failure=False) that made the synthetic table.
        out[sel] = terracut.earthmoving_force(width[sel], depth[sel], soil=soil, rake_angle_deg=r,
                                              side_failure=False)["horizontal_n"]
    return out


def fit(width, depth, rake, force, start=(500.0, 25.0)):
    residual = lambda p: (model(p, width, depth, rake) - force) / force  # relative error
    try:
        from scipy.optimize import least_squares
    except ImportError:
        least_squares = None
    if least_squares is not None:
        r = least_squares(residual, start, bounds=([0.0, 1.0], [1e5, 60.0]), x_scale=[1000.0, 10.0])
        return r.x, "scipy.optimize.least_squares"
    p = np.array(start, dtype=float)  # Gauss-Newton, forward-difference Jacobian
    for _ in range(50):
        r0 = residual(p)
        jac = np.column_stack([(residual(p + dp) - r0) / dp[k] for k, dp in
                               enumerate(np.diag([1.0, 1e-3]))])
        step = np.linalg.lstsq(jac, -r0, rcond=None)[0]
        p = np.clip(p + step, [0.0, 1.0], [1e5, 60.0])
        if np.all(np.abs(step) < [1e-3, 1e-7]):
            break
    return p, "numpy.linalg.lstsq (Gauss-Newton)"


def synthesize(path):
    rng = np.random.default_rng(1)
    width, depth, rake = np.meshgrid([0.3, 0.6, 1.0], np.linspace(0.02, 0.2, 8), [60.0, 90.0])
    width, depth, rake = width.ravel(), depth.ravel(), rake.ravel()
    force = model((1300.0, 31.1), width, depth, rake) * (1 + 0.05 * rng.standard_normal(width.size))
    with open(path, "w") as f:
        f.write("# SYNTHETIC blade forces: McKyes FEE, c = 1300 Pa, phi = 31.1 deg, delta = 2/3 phi, "
                "gamma = 16250 N/m^3, 5 % noise (seed 1); made by calibrate_forces.py --synthesize\n")
        f.write("width_m,depth_m,rake_angle_deg,horizontal_n\n")
        for row in zip(width, depth, rake, force):
            f.write(",".join("%.6g" % v for v in row) + "\n")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--table", default=str(TABLE))
    parser.add_argument("--out", default="out/calibration")
    parser.add_argument("--synthesize", metavar="CSV", help="write a synthetic table and stop")
    args = parser.parse_args()
    if args.synthesize:
        synthesize(args.synthesize)
        return

    data = np.genfromtxt(args.table, delimiter=",", names=True, skip_header=1)  # line 1: a comment
    width, depth, rake, force = (data[k] for k in ["width_m", "depth_m", "rake_angle_deg", "horizontal_n"])
    (cohesion, phi), method = fit(width, depth, rake, force)
    predicted = model((cohesion, phi), width, depth, rake)
    rms = float(np.sqrt(np.mean(((predicted - force) / force) ** 2)))
    print(f"{method}: cohesion {cohesion:.0f} Pa, friction {phi:.2f} deg, RMS relative error {100 * rms:.1f} %")

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    fine = np.linspace(0.0, depth.max() * 1.05, 100)
    for (w, r), colour in zip(sorted(set(zip(width, rake))), plt.cm.viridis(np.linspace(0, 0.9, 6))):
        sel = (width == w) & (rake == r)
        ax.plot(depth[sel], force[sel], "o", color=colour, ms=4)
        ax.plot(fine, model((cohesion, phi), np.full_like(fine, w), fine, np.full_like(fine, r)), "-",
                color=colour, label=f"w {w:.1f} m, rake {r:.0f} deg")
    ax.set_xlabel("cutting depth (m)")
    ax.set_ylabel("horizontal force (N)")
    ax.set_title(f"FEE fit: c = {cohesion:.0f} Pa, phi = {phi:.1f} deg (dots: table)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "calibration.png", dpi=120)
    print(f"wrote {out / 'calibration.png'}")


if __name__ == "__main__":
    main()
