"""tools/soil_convergence_sweep.py: the capped pushes against the converged
ones, square to the grid and turned (--yaws), and its bad arguments."""

import re
import subprocess
import sys

from conftest import SOURCE

TOOL = SOURCE / "tools" / "soil_convergence_sweep.py"


def sweep(*args):
    return subprocess.run([sys.executable, str(TOOL), *args], capture_output=True, text=True, timeout=300)


def test_a_turned_push_gets_its_own_row_and_small_pushes_converge():
    # A 0.3 m blade pushed 0.2 m on 2 cm cells, square and turned 30 degrees:
    # the cap is never reached there, so the capped pile is the converged one.
    out = sweep("--blades", "0.3", "--cells", "0.02", "--speeds", "1", "--travel", "0.2", "--yaws", "0,30")
    assert out.returncode == 0, out.stderr
    assert "| blade | cells | yaw | 1 m/s |" in out.stdout
    rows = re.findall(r"^\| 0\.3 m \| 20 mm \| (\d+) \| ([+-][\d.]+) %, ([+-][\d.]+) mm", out.stdout, re.M)
    assert [r[0] for r in rows] == ["0", "30"], out.stdout
    for _, rel, peak in rows:
        assert abs(float(rel)) <= 5.0 and abs(float(peak)) <= 1000 * 0.6745 * 0.02
    assert "0 of 2 pushes miss a bound" in out.stdout


def test_a_bad_yaw_is_refused_by_name():
    out = sweep("--yaws", "ten")
    assert out.returncode == 2
    assert "--yaws" in out.stderr and "ten" in out.stderr


def test_the_settle_is_chosen_and_named():
    # --settle fans runs the pushes with soil.settle: fans and says so; a
    # settle the library does not have is refused by name.
    out = sweep("--blades", "0.3", "--cells", "0.02", "--speeds", "1", "--travel", "0.2", "--yaws", "10",
                "--settle", "fans")
    assert out.returncode == 0, out.stderr
    assert "settled by fans" in out.stdout
    assert "0 of 1 pushes miss a bound" in out.stdout
    bad = sweep("--settle", "wet")
    assert bad.returncode == 2
    assert "--settle" in bad.stderr and "wet" in bad.stderr
