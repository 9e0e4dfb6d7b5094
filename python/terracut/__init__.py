"""terracut: soil cutting for haptic teleoperation, from Python.

SI units throughout (metres, seconds, newtons, kilograms); the world frame
is right-handed with Y up and the ground plane X-Z. A blade pose is 7
numbers [x, y, z, qw, qx, qy, qz]: the blade's centre in world metres and
its orientation as a unit quaternion (the blade lies along its local X).

    import terracut
    sc = terracut.Scenario.load("scenarios/paper_experiment1.yaml")
    sim = terracut.Simulation(sc)
    cols = sim.run()                  # dict of numpy columns, one row per step
    sim.heights                       # (rows, cols) float32 view of the terrain, metres

Scenarios come from files (Scenario.load), dicts with the same schema
(Scenario.from_dict) or PNG heightmaps (Scenario.from_image); a Simulation
also from a numpy array (Simulation.from_heights). terracut.run() is
`terracut run` (the same files on disk); terracut.sweep() runs many cases,
locally or on a Dask cluster. Errors are terracut.InputError (a ValueError)
with the C++ library's messages. terracut.__version__ is the library's
version, as `terracut --version` prints it.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Union

from ._terracut import (  # noqa: F401
    __version__,
    ForceModel,
    InputError,
    SafetyLimiter,
    Scenario,
    Simulation,
    StepResult,
    bodies_available,
    calibrate_record,
    calibrate_tests,
    earthmoving_force,
    soil_preset,
)
from ._scenarios import as_scenario, from_dict, load_mapping  # noqa: F401

Scenario.from_dict = staticmethod(from_dict)
Scenario.from_dict.__doc__ = from_dict.__doc__


def run(scenario, out_dir: Union[str, os.PathLike], realtime: bool = False) -> dict[str, Any]:
    """Runs a scenario as `terracut run SCENARIO --out OUT_DIR` does.

    scenario: a Scenario, a file path or a dict. Writes the same files
    (contact.csv, height.npy, removed.npy, PNGs, summary.json, bodies.csv)
    and returns the run's figures: steps, volumes (m^3), max_sample_error_m,
    per-cut figures ("cuts"), step timing ("step_timing", microseconds), and
    "records": contact.csv's columns as numpy arrays (t in s, cut index,
    x, y, z in m, qw..qz, contact_length m, removed_volume m^3,
    section_area m^2, max_depth m; with soil that flows removed_volume
    counts a pushed pile again at every step). With soil that flows, "soil"
    (cut_from_ground_m3: the cut below the initial surface;
    displaced_volume_m3: what the blade pushed, each push counted;
    net_moved_m3: soil no longer where it was at the end; over_top_m3: soil
    that fell over the blade's top (blade.height_m); left_over_edge_m3,
    passes, final_backlog_cells, capped_steps: steps the work cap stopped)
    and "warnings": readable lines, as summary.json's and `terracut run`'s
    (steps the work cap stopped, soil left steeper than its
    repose angle by the work cap, cells too far from square for the repose
    angle to hold in every direction); [] when there is nothing to say.
    The GIL is released during the run.
    """
    from ._terracut import _run

    return _run(as_scenario(scenario), Path(out_dir), realtime)


def run_mmt(scenario, out_dir: Union[str, os.PathLike, None] = None, rtt_ms: Union[float, None] = None,
            loss: Union[float, None] = None, deadband: Union[float, None] = None,
            seed: Union[int, None] = None) -> dict[str, Any]:
    """Runs a teleoperation scenario (one with an `mmt:` section) as
    `terracut mmt SCENARIO [--out OUT_DIR]` does: both stations in one
    process over the emulated link, with the round trip (rtt_ms,
    milliseconds), independent loss (a fraction in [0, 1)), the perceptual
    deadband and the seed overriding the scenario's. Returns the summary's
    figures: force errors of MMT and of direct force reflection (N, RMS and
    max), terrain and tracking errors (m), packets per second, update
    count, passivity (J), the soil estimate. Writes operator.csv,
    remote.csv, terrain_error.csv and summary.json into out_dir when given.
    The GIL is released during the run.
    """
    from ._terracut import _run_mmt

    return _run_mmt(as_scenario(scenario), None if out_dir is None else Path(out_dir),
                    None if rtt_ms is None else float(rtt_ms) / 1000.0, loss, deadband, seed)


from .sweep import SweepResult, register_override, sweep  # noqa: E402,F401

__all__ = [
    "run_mmt",
    "ForceModel", "InputError", "SafetyLimiter", "Scenario", "Simulation", "StepResult",
    "SweepResult", "bodies_available", "calibrate_record", "calibrate_tests", "earthmoving_force",
    "from_dict", "load_mapping", "register_override", "run", "soil_preset", "sweep",
]
