"""Force models and the safety limiter from Python."""

import math

import numpy as np
import pytest

import terracut
from conftest import SCENARIOS


def test_earthmoving_scales_as_the_equation_says():
    # The 2-D equation, cohesionless, no adhesion or surcharge: P = gamma d^2
    # N_gamma w, so P is linear in width and quadratic in depth, with beta*
    # independent of both.
    soil = {"cohesion_pa": 0.0, "adhesion_pa": 0.0}
    f = terracut.earthmoving_force(np.array([0.5, 1.0, 1.0]), np.array([0.1, 0.1, 0.2]), soil=soil,
                                   side_failure=False)
    assert f["total_n"][1] == pytest.approx(2 * f["total_n"][0], rel=1e-9)
    assert f["total_n"][2] == pytest.approx(4 * f["total_n"][1], rel=1e-9)
    assert np.ptp(f["beta_rad"]) < 1e-8
    # Broadcasting: one depth for many widths.
    assert terracut.earthmoving_force([0.1, 0.2, 0.3], 0.1)["total_n"].shape == (3,)
    zero = terracut.earthmoving_force(0.0, 0.1)
    assert float(zero["total_n"]) == 0.0
    # Side failure: a narrow blade meets more per metre than the 2-D equation.
    narrow = terracut.earthmoving_force(0.1, 0.1)
    flat = terracut.earthmoving_force(0.1, 0.1, side_failure=False)
    assert float(narrow["horizontal_n"]) > 1.5 * float(flat["horizontal_n"])
    assert float(narrow["side_total_n"]) > 0.0 and float(flat["side_total_n"]) == 0.0
    # A surcharge is an argument, not a property of the soil.
    with pytest.raises(terracut.InputError, match="surcharge_pa"):
        terracut.earthmoving_force(1.0, 0.1, soil={"surcharge_pa": 10.0})
    piled = terracut.earthmoving_force(1.0, 0.1, surcharge_pa=1600.0)
    assert float(piled["total_n"]) > float(terracut.earthmoving_force(1.0, 0.1)["total_n"])


def test_soil_presets_and_bad_soils():
    dry = terracut.soil_preset("dry_sand")
    assert dry["internal_friction_deg"] == pytest.approx(31.1)
    with pytest.raises(terracut.InputError, match="unknown preset 'mud'"):
        terracut.soil_preset("mud")
    with pytest.raises(terracut.InputError, match="soil.colour: unknown field"):
        terracut.earthmoving_force(1.0, 0.1, soil={"colour": 1.0})
    with pytest.raises(terracut.InputError, match="unit_weight"):
        terracut.earthmoving_force(1.0, 0.1, soil={"unit_weight_n_per_m3": -1.0})


def test_force_model_renders_a_steps_physical_force():
    sc = terracut.Scenario.load(SCENARIOS / "trench_dry_sand.yaml")
    model = terracut.ForceModel(sc)
    assert model.cutting_model == "earthmoving"
    # A 0.4 m blade 5 cm into the 0.3 m sand, moving along +Z at 0.2 m/s.
    sim = terracut.Simulation(sc)
    sim.step([0.0, 0.25, -0.5, 1.0, 0.0, 0.0, 0.0])
    step = sim.step([0.0, 0.25, -0.5 + 0.2e-3, 1.0, 0.0, 0.0, 0.0])
    force = step.force
    fx, fy, fz = force["total_n"]
    assert fz < -100.0 and abs(fx) < 1e-9  # the physical force, against the motion
    assert force["cut_depth_m"] == pytest.approx(0.05, abs=0.02 * 0.05 + 1e-6)
    out = model.compute(step)
    # The rendering at the step's own speed: under the low-speed cap, along the motion.
    assert out["cutting_n"][2] < 0 and abs(out["cutting_n"][2]) <= abs(fz) + 1e-9
    assert out["device_n"][2] == pytest.approx(out["world_n"][2] * model.force_scale)
    # The physical force does not depend on the device's speed; the rendering does.
    fast = model.compute(step, velocity_m_per_s=(0.0, 0.0, 10.0))
    assert fast["cutting_n"][2] == pytest.approx(fz, rel=1e-9)


def test_safety_limiter_clamps_and_catches_nonfinite():
    s = terracut.SafetyLimiter(max_force_n=2.0, rise_time_s=0.0, max_force_rate_n_per_s=1e6)
    force, gain, flags = s.update(0.0, (10.0, 0.0, 0.0), 0.0)
    force, gain, flags = s.update(0.001, (10.0, 0.0, 0.0), 0.001)
    assert math.hypot(*force) == pytest.approx(2.0) and flags & 1
    force, gain, flags = s.update(0.002, (math.nan, 0.0, 0.0), 0.002)
    assert force == (0.0, 0.0, 0.0) and flags & 16
    assert s.counters["nonfinite"] == 1
    with pytest.raises(terracut.InputError, match="max_force_n"):
        terracut.SafetyLimiter(max_force_n=-1.0)
