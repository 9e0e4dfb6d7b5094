"""Shared fixtures: where the sources, the scenarios and the CLI are."""

import os
from pathlib import Path

import pytest

SOURCE = Path(os.environ.get("TERRACUT_SOURCE_DIR", Path(__file__).resolve().parents[2]))
SCENARIOS = SOURCE / "scenarios"


@pytest.fixture
def exp1():
    """The paper's experiment 1 scenario file."""
    return SCENARIOS / "paper_experiment1.yaml"


@pytest.fixture
def cli():
    """The terracut program of this build."""
    path = os.environ.get("TERRACUT_CLI")
    if not path or not Path(path).exists():
        pytest.skip("TERRACUT_CLI is not set to the built terracut program (run through ctest)")
    return path


def small_exp1_dict(resolution=20):
    """Experiment 1 as a dict: a mound generator instead of the image, a short cut."""
    return {
        "name": "small",
        "terrain": {"generator": "mound", "resolution": resolution, "size_m": [1.0, 1.0],
                    "origin_m": [0.0, 0.0, 0.0], "full_scale_m": 0.2},
        "representation": "surface",
        "rate_hz": 200,
        "blade": {"length_m": 1.2},
        "cuts": [{"name": "horizontal", "keyframes": [
            {"t_s": 0.0, "position_m": [0.5, 0.1, -0.1], "rotation_deg": [0, 0, 0]},
            {"t_s": 1.0, "position_m": [0.5, 0.1, 1.1], "rotation_deg": [0, 0, 0]}]}],
    }
