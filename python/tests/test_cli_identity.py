"""Bit-identical to the command line: `terracut run` and the module give the
same numbers for the same scenario."""

import json
import os
import subprocess

import numpy as np

import terracut
from conftest import SOURCE, small_exp1_dict

FIELDS = ["t", None, "x", "y", "z", "qw", "qx", "qy", "qz", "contact_length", "removed_volume",
          "section_area", "max_depth", "cells_visited"]


def cli_run(cli, scenario, out, *args):
    # Under the sanitizers the interpreter has the runtime preloaded; the
    # program carries its own (clang links it in), and two would abort it.
    env = {k: v for k, v in os.environ.items() if k != "LD_PRELOAD"}
    subprocess.run([cli, "run", str(scenario), "--out", str(out), *args], check=True,
                   capture_output=True, env=env)
    return (out / "contact.csv").read_text().splitlines()


def test_simulation_run_matches_the_cli_csv_exactly(cli, exp1, tmp_path):
    lines = cli_run(cli, exp1, tmp_path / "cli", "--resolution", "30", "--representation", "columns")
    sc = terracut.Scenario.load(exp1).with_overrides(resolution=30, representation="columns")
    sim = terracut.Simulation(sc)
    cols = sim.run()
    assert lines[0] == "t,cut,x,y,z,qw,qx,qy,qz,contact_length,removed_volume,section_area,max_depth,cells_visited"
    assert len(lines) - 1 == len(cols["t"])
    names = sc.cut_names
    # contact.csv prints every value with %.9g: format the arrays the same way
    # and the text must be the same, row by row.
    for i, line in enumerate(lines[1:]):
        mine = []
        for f in FIELDS:
            if f is None:
                mine.append(names[int(cols["cut"][i])])
            elif f == "cells_visited":
                mine.append("%d" % cols[f][i])
            else:
                mine.append("%.9g" % cols[f][i])
        assert ",".join(mine) == line, (i, line)
    # The final terrain, bitwise.
    np.testing.assert_array_equal(np.load(tmp_path / "cli" / "height.npy"), sim.heights)
    np.testing.assert_array_equal(np.load(tmp_path / "cli" / "removed.npy"), sim.removed)


def test_terracut_run_writes_the_clis_files(cli, exp1, tmp_path):
    cli_run(cli, exp1, tmp_path / "cli", "--resolution", "25")
    result = terracut.run(terracut.Scenario.load(exp1).with_overrides(resolution=25), tmp_path / "py")
    for name in ["contact.csv", "height.npy", "removed.npy", "height.png", "removed.png"]:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    rec = result["records"]
    assert result["steps"] == len(rec["t"]) == 2001
    # The records are the CSV's values (before %.9g printing).
    csv = np.genfromtxt(tmp_path / "cli" / "contact.csv", delimiter=",", names=True, dtype=None,
                        encoding="utf-8")
    np.testing.assert_allclose(rec["contact_length"], csv["contact_length"], rtol=1e-8, atol=1e-12)
    assert result["cuts"][0]["name"] == "horizontal"
    assert result["removed_volume_m3"] > 0 and abs(result["volume_error_m3"]) < 1e-9


def test_run_returns_the_soils_warnings(tmp_path):
    # Cells of 4:1 and a work cap too small for the cut: the steps the cap
    # stopped, the unsettled end and the cells all named; the same run on
    # square cells with the cap lifted has nothing to say.
    d = small_exp1_dict()
    d["terrain"]["resolution"] = [40, 10]
    d["soil"] = {"model": "flow", "repose_deg": 34, "max_pair_checks_per_step": 1000}
    result = terracut.run(terracut.Scenario.from_dict(d), tmp_path / "oblong")
    warnings = result["warnings"]
    assert len(warnings) == 3, warnings
    assert "work cap" in warnings[0] and "stopped it in" in warnings[0]
    assert result["soil"]["capped_steps"] > 0
    assert "the relaxation was not done at the end" in warnings[1]
    assert "let planes up to 40.9 degrees stand" in warnings[2]
    summary = json.loads((tmp_path / "oblong" / "summary.json").read_text())
    assert summary["warnings"] == warnings
    d["terrain"]["resolution"] = 20
    d["soil"]["max_pair_checks_per_step"] = 1000000000
    assert terracut.run(terracut.Scenario.from_dict(d), tmp_path / "square")["warnings"] == []


def test_the_steps_say_when_the_work_cap_stopped_the_soil(tmp_path):
    # The run's count of capped steps is the sum of the steps' soil_capped
    # column, no step passed the cap, and the single steps' results say the
    # same as the batched columns.
    d = small_exp1_dict()
    d["soil"] = {"model": "flow", "repose_deg": 34, "max_pair_checks_per_step": 1000}
    scenario = terracut.Scenario.from_dict(d)
    result = terracut.run(scenario, tmp_path / "capped")
    columns = terracut.Simulation(scenario).run()
    capped = columns["soil_capped"]
    assert set(np.unique(capped)) <= {0, 1}
    assert int(capped.sum()) == result["soil"]["capped_steps"] > 0
    assert columns["soil_work"].max() <= 1000
    assert (columns["soil_backlog"] >= 0).all()
    sim = terracut.Simulation(scenario)
    poses = scenario.cut_poses("horizontal")[:200]
    singles = [sim.step(p) for p in poses.tolist()]
    again = terracut.Simulation(scenario).step(poses)
    np.testing.assert_array_equal(again["soil_capped"], [int(s.soil_capped) for s in singles])
    np.testing.assert_array_equal(again["soil_work"], [s.soil_work for s in singles])
    np.testing.assert_array_equal(again["soil_backlog"], [s.soil_backlog for s in singles])
    # Each step's budget is the cap, less up to half of it for what the
    # displacement's walk cost.
    for s in singles:
        assert s.soil_work <= 1000 and s.soil_displace_work >= 0
        assert 1000 - min(s.soil_displace_work, 500) <= s.soil_budget <= 1000
    # Lifted, the cap never stops it.
    d["soil"]["max_pair_checks_per_step"] = 1000000000
    assert terracut.Simulation(terracut.Scenario.from_dict(d)).run()["soil_capped"].sum() == 0


def test_run_names_what_moved(tmp_path):
    # With soil that flows the sum of the steps' cuts counts a pushed pile
    # again at every step: the run also says what the blade cut from the
    # ground, what it pushed and the soil no longer where it was, and the
    # steps' columns hold the ground each step cut.
    # A level layer 5 cm above the edge (a mound's flanks would slump
    # where the blade never was, and count as moved).
    d = small_exp1_dict()
    d["terrain"] = dict(d["terrain"], generator="plane", plane={"height_m": 0.15})
    d["soil"] = {"model": "flow", "repose_deg": 34}
    scenario = terracut.Scenario.from_dict(d)
    result = terracut.run(scenario, tmp_path / "run")
    soil = result["soil"]
    assert soil["net_moved_m3"] > 0
    assert soil["net_moved_m3"] <= soil["cut_from_ground_m3"] + 1e-9
    assert soil["cut_from_ground_m3"] <= result["removed_volume_m3"] + 1e-9
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    for key in ("cut_from_ground_m3", "displaced_volume_m3", "net_moved_m3"):
        assert summary["soil"][key] == soil[key], key
    columns = terracut.Simulation(scenario).run()
    assert abs(columns["cut_from_ground"].sum() - soil["cut_from_ground_m3"]) <= 1e-9
    assert abs(columns["displaced_volume"].sum() - soil["displaced_volume_m3"]) <= 1e-9


def test_run_errors_name_the_output(tmp_path, exp1):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    try:
        terracut.run(exp1, blocker)
    except terracut.InputError as e:
        assert str(blocker) in str(e)
    else:
        raise AssertionError("a file as the output folder was accepted")


def test_the_version_is_the_command_lines(cli):
    env = {k: v for k, v in os.environ.items() if k != "LD_PRELOAD"}
    out = subprocess.run([cli, "--version"], check=True, capture_output=True, text=True, env=env).stdout
    assert out.split() == ["terracut", terracut.__version__]


def test_the_readmes_csv_recipe_reads_the_cut_names_as_text(cli, exp1, tmp_path):
    # The README's line for reading contact.csv, run as written: the cut
    # column must compare equal to the cut's name (bytes would never).
    readme = (SOURCE / "README.md").read_text()
    recipe = next(line for line in readme.splitlines() if "numpy.genfromtxt(" in line)
    call = recipe[recipe.index("numpy.genfromtxt("):]
    call = call[:call.index(")`") + 1].replace("DIR/", str(tmp_path / "cli") + "/")
    cli_run(cli, exp1, tmp_path / "cli", "--resolution", "20")
    rows = eval(call, {"numpy": np})
    assert rows.shape == (2001,)
    assert (rows["cut"] == "horizontal").all()
    assert rows["contact_length"].max() > 0.0

