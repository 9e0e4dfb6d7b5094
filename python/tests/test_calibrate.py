"""Calibration of a soil material from Python (terracut.calibrate_tests,
terracut.calibrate_record): an exact Mohr-Coulomb line gives back its angle
and intercept; terracut's own force record on a scenario gives back the
material it was made with, from the scenario's own (wrong) material; bad
input is refused naming what is wrong."""

import math

import numpy as np
import pytest

import terracut
from conftest import SCENARIOS


def test_calibrate_tests_fits_the_mohr_coulomb_line():
    phi, c = 33.0, 450.0
    sigma = np.array([1000.0, 2500.0, 4000.0])
    shear = np.stack([sigma, c + sigma * math.tan(math.radians(phi))], axis=1)
    plate = np.stack([sigma, sigma * math.tan(math.radians(22.0))], axis=1)
    cal = terracut.calibrate_tests({"shear": shear, "plate": plate, "repose_deg": [30, 32],
                                    "bulk_density_kg_per_m3": [1500]}, start="dry_sand")
    m = cal["material"]
    assert m["internal_friction_deg"] == pytest.approx(phi, abs=1e-9)
    assert m["cohesion_pa"] == pytest.approx(c, abs=1e-8)
    assert m["soil_tool_friction_deg"] == pytest.approx(22.0, abs=1e-9)
    assert m["repose_deg"] == pytest.approx(31.0)
    assert m["density_kg_per_m3"] == pytest.approx(1500.0)
    # adhesion is no test's: the start's (dry sand: none)
    assert m["adhesion_pa"] == terracut.soil_preset("dry_sand")["adhesion_pa"]
    names = [f["name"] for f in cal["fields"]]
    assert "internal_friction_deg" in names and "soil_tool_friction_deg" in names
    assert "soil:" in cal["soil_yaml"]


def test_calibrate_tests_reads_the_dem_references_file():
    cal = terracut.calibrate_tests(SCENARIOS.parent / "validation" / "dem" / "results" / "material.json")
    f = {x["name"]: x for x in cal["fields"]}
    assert 20.0 < f["internal_friction_deg"]["value"] < 45.0
    assert f["internal_friction_deg"]["uncertainty"] > 0.0


def test_calibrate_tests_refuses_bad_input():
    with pytest.raises(terracut.InputError, match="two normal stresses"):
        terracut.calibrate_tests({"shear": [[1000.0, 700.0]]})
    with pytest.raises(terracut.InputError, match="shaer: unknown test"):
        terracut.calibrate_tests({"shaer": [[1000.0, 700.0]]})
    with pytest.raises(terracut.InputError, match=r"shear\[1\]"):
        terracut.calibrate_tests({"shear": [[1000.0, 700.0], [-1.0, 5.0]]})
    with pytest.raises(terracut.InputError, match=r"\(N, 2\)"):
        terracut.calibrate_tests({"plate": [1000.0, 700.0]})
    with pytest.raises(terracut.InputError, match="cannot be read"):
        terracut.calibrate_tests("/nonexistent/tests.json")
    with pytest.raises(terracut.InputError, match="expected a JSON file's path or a dict"):
        terracut.calibrate_tests(([1000.0, 700.0],))
    with pytest.raises(terracut.InputError, match="repose_deg: expected a list of numbers"):
        terracut.calibrate_tests({"repose_deg": [[30.0, 31.0]]})


def _record(scenario, steps=600):
    """terracut's own force on the blade of the scenario: 4 cm deep, then 8 cm,
    along -Z at 0.5 m/s (trench_dry_sand's sand is 0.3 m deep)."""
    sim = terracut.Simulation(scenario)
    t, poses, force = [], [], []
    for i in range(steps):
        depth = 0.04 if i < steps // 2 else 0.08
        pose = [0.0, 0.3 - depth, 0.6 - 0.5 * i / 1000.0, 1.0, 0.0, 0.0, 0.0]
        step = sim.step(pose)
        t.append(i / 1000.0)
        poses.append(pose)
        force.append(step.force["total_n"])
    return np.array(t), np.array(poses), np.array(force)


def test_calibrate_record_gives_back_the_material_it_was_made_with():
    mapping = terracut.load_mapping(SCENARIOS / "trench_dry_sand.yaml")
    truth = dict(mapping)
    truth["soil"] = dict(mapping["soil"], internal_friction_deg=37.0, cohesion_pa=1500.0)
    t, poses, force = _record(terracut.Scenario.from_dict(truth))
    start = terracut.Scenario.load(SCENARIOS / "trench_dry_sand.yaml")
    cal = terracut.calibrate_record(start, t, poses, force, from_s=0.01)
    assert cal["material"]["internal_friction_deg"] == pytest.approx(37.0, abs=0.05)
    assert cal["material"]["cohesion_pa"] == pytest.approx(1500.0, abs=10.0)
    assert cal["evaluations"] > 3
    assert cal["rms_relative"] < 1e-2


def test_calibrate_record_refuses_bad_input():
    sc = terracut.Scenario.load(SCENARIOS / "trench_dry_sand.yaml")
    t, poses, force = _record(sc, steps=50)
    with pytest.raises(terracut.InputError, match=r"poses: expected \(N, 7\)"):
        terracut.calibrate_record(sc, t, poses[:, :6], force)
    with pytest.raises(terracut.InputError, match="force_n"):
        terracut.calibrate_record(sc, t, poses, force[:-1])
    bad = force.copy()
    bad[3, 1] = np.nan
    with pytest.raises(terracut.InputError, match=r"force_n\[3\]: not finite"):
        terracut.calibrate_record(sc, t, poses, bad)
    with pytest.raises(terracut.InputError, match="not a field of the soil material"):
        terracut.calibrate_record(sc, t, poses, force, fit=["friction"])
    with pytest.raises(terracut.InputError, match="times must be finite and increase"):
        terracut.calibrate_record(sc, t[::-1].copy(), poses, force)
    with pytest.raises(terracut.InputError, match="cannot be read"):
        terracut.calibrate_record(sc, "/nonexistent/record.csv")
    with pytest.raises(terracut.InputError, match="max_iterations"):
        terracut.calibrate_record(sc, t, poses, force, max_iterations=0)
    with pytest.raises(terracut.InputError, match="given twice"):
        terracut.calibrate_record(sc, t, poses, force, fit=["cohesion_pa", "cohesion_pa"])
