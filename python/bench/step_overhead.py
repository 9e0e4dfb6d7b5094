"""Per-call overhead of Simulation.step(pose) from Python against the C++ step.

The same poses (experiment 1's cut) are stepped three ways on fresh
simulations, several rounds each, and the median of the rounds is kept:

  cpp      the C++ step alone: Simulation's own timer (StepOutput timers.total_s,
           the 'step_s' column), inside one batched call
  batched  step(poses) with an (N, 7) array: wall time per step of one call
           that loops in C++ (the step plus filling the columns)
  single   step(pose) once per pose from a Python loop, poses as tuples:
           wall time per call (argument parsing, the GIL released and taken
           back, the StepResult made)

overhead = single - cpp is what a Python caller pays per step. On a busy
machine the rounds spread; the fastest round is the quiet-machine figure.

    PYTHONPATH=build/python /usr/bin/python3 python/bench/step_overhead.py [--resolution 50] [--rounds 7]
"""
import argparse
import statistics
import time
from pathlib import Path

import numpy as np

import terracut

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "paper_experiment1.yaml"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--resolution", type=int, default=50)
    parser.add_argument("--rounds", type=int, default=7)
    args = parser.parse_args()

    sc = terracut.Scenario.load(SCENARIO).with_overrides(resolution=args.resolution)
    poses = sc.cut_poses("horizontal")
    tuples = [tuple(p) for p in poses.tolist()]
    n = len(poses)
    cpp, batched, single = [], [], []
    for _ in range(args.rounds):
        sim = terracut.Simulation(sc)
        t0 = time.perf_counter()
        cols = sim.step(poses)
        batched.append((time.perf_counter() - t0) / n)
        cpp.append(float(np.mean(cols["step_s"])))

        sim = terracut.Simulation(sc)
        step = sim.step
        t0 = time.perf_counter()
        for p in tuples:
            step(p)
        single.append((time.perf_counter() - t0) / n)

    med = lambda xs: statistics.median(xs) * 1e6
    low = lambda xs: min(xs) * 1e6
    print(f"experiment 1 at {args.resolution}x{args.resolution}, {n} steps, {args.rounds} rounds: "
          "median (fastest round)")
    print(f"  C++ step (its own timer)      {med(cpp):7.2f} us ({low(cpp):.2f})")
    print(f"  batched step(poses), per step {med(batched):7.2f} us ({low(batched):.2f})")
    print(f"  single step(pose), per call   {med(single):7.2f} us ({low(single):.2f})")
    print(f"  overhead of a Python call     {med(single) - med(cpp):7.2f} us ({low(single) - low(cpp):.2f})")


if __name__ == "__main__":
    main()
