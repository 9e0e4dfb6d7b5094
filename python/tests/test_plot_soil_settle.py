"""tools/plot_soil_settle.py: its usage and its bad arguments (the figure
itself takes about 15 s of pushes; docs/images/soil_settle_fans.png is it)."""

import subprocess
import sys

from conftest import SOURCE

TOOL = SOURCE / "tools" / "plot_soil_settle.py"


def run(*args):
    return subprocess.run([sys.executable, str(TOOL), *args], capture_output=True, text=True, timeout=60)


def test_help_says_what_it_plots():
    out = run("--help")
    assert out.returncode == 0
    assert "settle" in out.stdout and "fans" in out.stdout


def test_a_bad_argument_is_refused_by_name():
    out = run("--colour", "red")
    assert out.returncode == 2
    assert "--colour" in out.stderr
    out = run("--out")
    assert out.returncode == 2
    assert "--out" in out.stderr
