"""Force models and the safety limiter from Python."""

import math

import numpy as np
import pytest

import terracut
from conftest import SCENARIOS


def test_earthmoving_scales_as_the_equation_says():
    # Cohesionless, no adhesion or surcharge: P = gamma d^2 N_gamma w, so P is
    # linear in width and quadratic in depth, with beta* independent of both.
    soil = {"cohesion_pa": 0.0, "adhesion_pa": 0.0, "surcharge_pa": 0.0}
    f = terracut.earthmoving_force(np.array([0.5, 1.0, 1.0]), np.array([0.1, 0.1, 0.2]), soil=soil)
    assert f["total_n"][1] == pytest.approx(2 * f["total_n"][0], rel=1e-9)
    assert f["total_n"][2] == pytest.approx(4 * f["total_n"][1], rel=1e-9)
    assert np.ptp(f["beta_rad"]) < 1e-8
    # Broadcasting: one depth for many widths.
    assert terracut.earthmoving_force([0.1, 0.2, 0.3], 0.1)["total_n"].shape == (3,)
    zero = terracut.earthmoving_force(0.0, 0.1)
    assert float(zero["total_n"]) == 0.0


def test_soil_presets_and_bad_soils():
    dry = terracut.soil_preset("dry_sand")
    assert dry["internal_friction_deg"] == pytest.approx(31.1)
    with pytest.raises(terracut.InputError, match="unknown preset 'mud'"):
        terracut.soil_preset("mud")
    with pytest.raises(terracut.InputError, match="soil.colour: unknown field"):
        terracut.earthmoving_force(1.0, 0.1, soil={"colour": 1.0})
    with pytest.raises(terracut.InputError, match="unit_weight"):
        terracut.earthmoving_force(1.0, 0.1, soil={"unit_weight_n_per_m3": -1.0})


def test_force_model_of_a_scenario_resists_the_motion():
    sc = terracut.Scenario.load(SCENARIOS / "trench_dry_sand.yaml")
    model = terracut.ForceModel(sc)
    assert model.cutting_model == "earthmoving"
    out = model.compute(velocity_m_per_s=(0.0, 0.0, 0.2), contact_length_m=0.5, cut_depth_m=0.05,
                        edge_direction=(1.0, 0.0, 0.0))
    fx, fy, fz = out["cutting_n"]
    assert fz < 0 and abs(fx) < 1e-9  # against the motion along +Z
    assert out["device_n"][2] == pytest.approx(out["world_n"][2] * model.force_scale)


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
