"""tools/plot_soil_settle.py and tools/plot_settle_reference.py: their usage
and their bad arguments (the figures themselves take about 15 s and two
minutes of pushes; docs/images/soil_settle_fans.png and
docs/images/soil_settle_reference.png are them)."""

import subprocess
import sys

import pytest

from conftest import SOURCE

TOOLS = {"plot_soil_settle.py": ("settle", "fans"), "plot_settle_reference.py": ("passes", "patches", "fans")}


def run(tool, *args):
    return subprocess.run([sys.executable, str(SOURCE / "tools" / tool), *args], capture_output=True, text=True,
                          timeout=60)


@pytest.mark.parametrize("tool", sorted(TOOLS))
def test_help_says_what_it_plots(tool):
    out = run(tool, "--help")
    assert out.returncode == 0
    for word in TOOLS[tool]:
        assert word in out.stdout


@pytest.mark.parametrize("tool", sorted(TOOLS))
def test_a_bad_argument_is_refused_by_name(tool):
    out = run(tool, "--colour", "red")
    assert out.returncode == 2
    assert "--colour" in out.stderr
    out = run(tool, "--out")
    assert out.returncode == 2
    assert "--out" in out.stderr
