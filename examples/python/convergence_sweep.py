"""Resolution convergence of experiment 1 as a sweep: the RMS error of the
contact length against the exact chord, for both representations, from
10x10 to 320x320 samples. Runs in a local process pool, or on a Dask
cluster with --scheduler ADDRESS (e.g. tcp://10.0.0.5:8786, a scheduler
started with `dask scheduler` and workers with `dask worker ADDRESS` on
machines that can import terracut).

    PYTHONPATH=build/python /usr/bin/python3 examples/python/convergence_sweep.py --out out/convergence
"""
import argparse
from pathlib import Path

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import terracut

SCENARIO = Path(__file__).parents[2] / "scenarios" / "paper_experiment1.yaml"
RESOLUTIONS = [10, 20, 40, 80, 160, 320]


def exact_chord(z):
    radius = 0.4 * np.sqrt(1 - 0.5**2)  # section of the 0.4 m, 0.2 m mound at y = 0.1
    return 2 * np.sqrt(np.clip(radius**2 - (z - 0.5) ** 2, 0, None))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/convergence")
    parser.add_argument("--scheduler", help="address of a Dask scheduler; default: a local process pool")
    args = parser.parse_args()

    client = None
    if args.scheduler:
        from distributed import Client
        client = Client(args.scheduler)
    result = terracut.sweep(SCENARIO, grid={"representation": ["surface", "columns"],
                                            "resolution": RESOLUTIONS},
                            out_dir=args.out, client=client, progress=True)
    for row in result.failed:
        print(f"case {row['case']} failed: {row['error']}")

    # Each case's contact.csv, against the exact chord of the mound's section.
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for rep, marker in [("surface", "o"), ("columns", "s")]:
        cells, rms = [], []
        for row in result.ok:
            if row["overrides"]["representation"] != rep:
                continue
            csv = np.genfromtxt(Path(row["out_dir"]) / "contact.csv", delimiter=",", names=True,
                                dtype=None, encoding="utf-8")
            err = csv["contact_length"] - exact_chord(csv["z"])
            cells.append(1.0 / row["overrides"]["resolution"])
            rms.append(float(np.sqrt(np.mean(err**2))))
            print(f"{rep:8s} {row['overrides']['resolution']:4d}^2  RMS error {rms[-1]:.5f} m")
        slope = np.polyfit(np.log(cells), np.log(rms), 1)[0]
        ax.loglog(cells, rms, marker=marker, label=f"{rep} (slope {slope:.2f})")
    ax.loglog(cells, np.array(cells) * rms[-1] / cells[-1], "k:", label="first order")
    ax.set_xlabel("cell size (m)")
    ax.set_ylabel("RMS contact error (m)")
    ax.set_title("Experiment 1: convergence with resolution")
    ax.legend()
    fig.tight_layout()
    fig.savefig(Path(args.out) / "convergence.png", dpi=120)
    print(f"wrote {Path(args.out) / 'convergence.png'} and {Path(args.out) / 'sweep.csv'}")


if __name__ == "__main__":
    main()
