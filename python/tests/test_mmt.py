"""Teleoperation from Python: terracut.run_mmt runs both stations as
`terracut mmt` does, and a sweep varies the link's round trip."""

import json

import pytest

import terracut
from conftest import SCENARIOS

TRENCH_CLAY = SCENARIOS / "mmt_trench_clay.yaml"


def test_run_mmt_gives_the_summary_and_the_files(tmp_path):
    s = terracut.run_mmt(TRENCH_CLAY, tmp_path / "mmt", rtt_ms=200, loss=0.01, seed=3)
    assert s["rtt_s"] == pytest.approx(0.2)
    assert s["loss"] == pytest.approx(0.01)
    for name in ("operator.csv", "remote.csv", "terrain_error.csv", "summary.json"):
        assert (tmp_path / "mmt" / name).exists(), name
    on_disk = json.loads((tmp_path / "mmt" / "summary.json").read_text())
    assert json.dumps(on_disk)  # valid JSON
    assert s["force_rms_remote_n"] > 0.0
    # The same run twice gives the same figures (a seeded link).
    again = terracut.run_mmt(TRENCH_CLAY, rtt_ms=200, loss=0.01, seed=3)
    assert again["force_error_rms_mmt_n"] == s["force_error_rms_mmt_n"]


def test_a_sweep_over_the_round_trip_shows_direct_reflection_degrade(tmp_path):
    result = terracut.sweep(TRENCH_CLAY, grid={"rtt_ms": [0, 500]}, out_dir=tmp_path / "sweep", processes=1)
    assert [r["status"] for r in result.rows] == ["ok", "ok"], [r.get("error") for r in result.rows]
    fast, slow = result.rows
    assert fast["rtt_s"] == 0.0 and slow["rtt_s"] == pytest.approx(0.5)
    # Direct force reflection's error grows with the delay; the local
    # model's does not follow it (it renders at once and is corrected).
    assert slow["force_error_rms_dfr_n"] > 3.0 * fast["force_error_rms_dfr_n"]
    assert slow["force_error_rms_mmt_n"] < slow["force_error_rms_dfr_n"]
    assert (tmp_path / "sweep" / "case_001" / "operator.csv").exists()
    # The table and sweep.csv hold the teleoperation figures, as the rows do.
    table = result.table()
    for name in ("force_error_rms_mmt_n", "force_error_rms_dfr_n", "update_packets_per_s", "wall_s"):
        assert list(table[name]) == [fast[name], slow[name]], name
    assert "steps" not in table.dtype.names  # a batch run's figures are not a teleoperation run's
    lines = (tmp_path / "sweep" / "sweep.csv").read_text().splitlines()
    head = lines[0].split(",")
    k = head.index("force_error_rms_dfr_n")
    assert [float(line.split(",")[k]) for line in lines[1:]] == [fast["force_error_rms_dfr_n"],
                                                                 slow["force_error_rms_dfr_n"]]


def test_a_bad_network_value_is_the_case_error_not_a_crash(tmp_path):
    result = terracut.sweep(TRENCH_CLAY, cases=[{"loss": 1.5}, {"rtt_ms": 0}], out_dir=tmp_path / "s", processes=1)
    assert result.rows[0]["status"] == "error" and "loss" in result.rows[0]["error"]
    assert result.rows[1]["status"] == "ok"
