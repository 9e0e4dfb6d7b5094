"""The paper's experiment 1 in a dozen lines: the contact length of a horizontal
cut through a mound at the paper's five resolutions, against the exact chord.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/experiment1.py [OUT.png]
"""
import sys
from pathlib import Path

import matplotlib; matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import terracut

scenario = terracut.Scenario.load(Path(__file__).parents[2] / "scenarios" / "paper_experiment1.yaml")
for n in [5, 15, 25, 35, 50]:
    steps = terracut.Simulation(scenario.with_overrides(resolution=n)).run()  # numpy columns
    plt.plot(steps["t"], steps["contact_length"], label=f"{n}x{n}")
radius = 0.4 * np.sqrt(1 - 0.5**2)  # the mound's section at half its height
plt.plot(steps["t"], 2 * np.sqrt(np.clip(radius**2 - (steps["z"] - 0.5)**2, 0, None)), "k--", label="exact chord")
plt.xlabel("t (s)"); plt.ylabel("contact length (m)"); plt.title("Experiment 1, surface"); plt.legend()
plt.savefig(sys.argv[1] if len(sys.argv) > 1 else "experiment1.png", dpi=120)
