"""The examples run, draw their figures, and say what they should."""

import os
import re
import subprocess
import sys

import numpy as np
import pytest

from conftest import SOURCE

EXAMPLES = SOURCE / "examples" / "python"


def run(script, *args, env=None):
    out = subprocess.run([sys.executable, str(EXAMPLES / script), *map(str, args)], check=True,
                         capture_output=True, text=True, env=env, timeout=120)
    return out.stdout + out.stderr


def test_experiment1_draws_its_figure(tmp_path):
    run("experiment1.py", tmp_path / "e1.png")
    assert (tmp_path / "e1.png").stat().st_size > 10000


def test_calibration_recovers_the_synthetic_soil(tmp_path):
    # The shipped table is the FEE for c = 1300 Pa, phi = 31.1 deg with 5 %
    # noise on 48 points: the fit must land within the noise's reach of them.
    text = run("calibrate_forces.py", "--out", tmp_path)
    m = re.search(r"cohesion (\d+) Pa, friction ([\d.]+) deg", text)
    assert m, text
    assert abs(float(m.group(1)) - 1300) < 0.15 * 1300
    assert abs(float(m.group(2)) - 31.1) < 1.5
    assert (tmp_path / "calibration.png").exists()


def test_calibration_without_scipy_gives_the_same_fit(tmp_path):
    # A sitecustomize that hides scipy: the numpy Gauss-Newton path.
    hide = tmp_path / "hide"
    hide.mkdir()
    (hide / "sitecustomize.py").write_text("import sys\nsys.modules['scipy'] = None\n")
    env = dict(os.environ, PYTHONPATH=f"{hide}{os.pathsep}{os.environ.get('PYTHONPATH', '')}")
    text = run("calibrate_forces.py", "--out", tmp_path, env=env)
    assert "numpy.linalg.lstsq" in text
    try:
        import scipy.optimize  # noqa: F401
    except ImportError:
        pytest.skip("scipy is not installed: nothing to compare the numpy fit with")
    with_scipy = run("calibrate_forces.py", "--out", tmp_path)
    numbers = lambda t: [float(x) for x in re.search(r"cohesion (\d+) Pa, friction ([\d.]+)", t).groups()]
    a, b = numbers(text), numbers(with_scipy)
    assert abs(a[0] - b[0]) <= 2 and abs(a[1] - b[1]) <= 0.02


def test_convergence_sweep_converges(tmp_path):
    text = run("convergence_sweep.py", "--out", tmp_path)
    assert (tmp_path / "convergence.png").exists() and (tmp_path / "sweep.csv").exists()
    # The contact error against the exact chord converges at first order in
    # the cell size (a sampled surface is off by a fraction of a cell).
    rms = {(rep, int(n)): float(e) for rep, n, e in re.findall(r"(\w+)\s+(\d+)\^2  RMS error ([\d.]+)", text)}
    for rep in ["surface", "columns"]:
        n = np.array(sorted(k[1] for k in rms if k[0] == rep))
        slope = np.polyfit(np.log(1.0 / n), np.log([rms[(rep, k)] for k in n]), 1)[0]
        assert 0.7 < slope < 1.4, (rep, slope, rms)
