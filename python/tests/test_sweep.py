"""Sweeps: a table with a row per case, outputs on disk, a failed case kept
apart, progress, a local pool and a Dask cluster giving the same rows."""

import json

import numpy as np
import pytest

import terracut
from conftest import small_exp1_dict


def test_grid_sweep_in_a_local_pool(tmp_path):
    seen = []
    result = terracut.sweep(small_exp1_dict(),
                            grid={"resolution": [10, 0, 20], "representation": ["surface", "columns"]},
                            out_dir=tmp_path / "s", processes=2,
                            progress=lambda done, total, row: seen.append((done, total, row["case"])))
    assert len(result.rows) == 6
    assert [r["case"] for r in result.rows] == list(range(6))
    assert [r["overrides"] for r in result.rows][:2] == [
        {"resolution": 10, "representation": "surface"}, {"resolution": 10, "representation": "columns"}]
    # Resolution 0 fails, with the reader's message, and costs no other case.
    assert [r["case"] for r in result.failed] == [2, 3]
    assert result.failed[0]["error"].startswith("scenario dict: terrain.resolution: ")
    assert len(result.ok) == 4
    assert sorted(s[0] for s in seen) == list(range(1, 7)) and all(s[1] == 6 for s in seen)
    for row in result.ok:
        out = tmp_path / "s" / f"case_{row['case']:03d}"
        assert (out / "contact.csv").exists() and (out / "summary.json").exists()
        assert json.loads((out / "case.json").read_text())["overrides"] == row["overrides"]
        summary = json.loads((out / "summary.json").read_text())
        assert summary["removed_volume_m3"] == row["removed_volume_m3"]
        assert summary["inputs"]["terrain"]["resolution"][0] == row["overrides"]["resolution"]
        assert row["steps"] == 201 and row["removed_volume_m3"] > 0
    table = result.table()
    assert table.shape == (6,)
    np.testing.assert_array_equal(table["resolution"], [10, 10, 0, 0, 20, 20])
    assert list(table["status"]) == ["ok", "ok", "error", "error", "ok", "ok"]
    assert np.isnan(table["removed_volume_m3"][2])
    assert (tmp_path / "s" / "sweep.csv").read_text().splitlines()[0].startswith("case,status,error,resolution")
    # A finer grid cuts the half-mound's volume more precisely: the removed
    # volume of the cut above y = 0.1 of a mound of radius 0.4 and height 0.2
    # is pi R^2 H (2/3 - 1/2 + 1/24) ... known in closed form:
    # V = pi R^2 (H/3) (1 - y/H)^2 (2 + y/H) with y/H = 1/2 -> pi R^2 H 5/24.
    exact = np.pi * 0.4 ** 2 * 0.2 * 5 / 24
    surface = {r["overrides"]["resolution"]: r["removed_volume_m3"] for r in result.ok
               if r["overrides"]["representation"] == "surface"}
    assert abs(surface[20] - exact) < abs(surface[10] - exact) + 1e-12
    assert abs(surface[20] - exact) < 0.1 * exact


def test_case_list_path_overrides_and_a_registered_override(tmp_path):
    def depth(mapping, value):
        for k in mapping["cuts"][0]["keyframes"]:
            k["position_m"][1] = 0.2 - value

    terracut.register_override("cut_depth_m", depth)
    result = terracut.sweep(small_exp1_dict(), cases=[
        {"cut_depth_m": 0.05}, {"cut_depth_m": 0.1},
        {"cuts[*].keyframes[*].position_m[1]": 0.1},
        {"terrain.size_m[7]": 1.0}], out_dir=tmp_path / "c", processes=1)
    v = [r.get("removed_volume_m3") for r in result.rows]
    assert v[0] < v[1]  # deeper removes more
    assert v[1] == v[2]  # the same blade height by the path
    assert "terrain.size_m has 2 entries" in result.rows[3]["error"]


def test_bad_sweeps_are_refused_before_running(tmp_path):
    with pytest.raises(terracut.InputError, match="not a named override"):
        terracut.sweep(small_exp1_dict(), grid={"nonsense": [1]}, out_dir=tmp_path)
    with pytest.raises(terracut.InputError, match="either grid"):
        terracut.sweep(small_exp1_dict(), out_dir=tmp_path)
    with pytest.raises(terracut.InputError, match="grid\\['resolution'\\] is empty"):
        terracut.sweep(small_exp1_dict(), grid={"resolution": []}, out_dir=tmp_path)
    with pytest.raises(terracut.InputError, match="processes"):
        terracut.sweep(small_exp1_dict(), grid={"resolution": [4]}, out_dir=tmp_path, processes=0)
    with pytest.raises(terracut.InputError, match="cannot read the field path"):
        terracut.sweep(small_exp1_dict(), grid={"terrain.size_m[x]": [4]}, out_dir=tmp_path)


def test_a_scenario_file_sweeps_with_images_relative_to_it(exp1, tmp_path):
    result = terracut.sweep(exp1, grid={"resolution": [5, 15]}, out_dir=tmp_path / "f", processes=1)
    assert [r["status"] for r in result.rows] == ["ok", "ok"]
    bad = terracut.sweep(exp1, cases=[{"rate_hz": -1}], out_dir=tmp_path / "g", processes=1)
    assert bad.rows[0]["error"].startswith("paper_experiment1.yaml with overrides: rate_hz: ")


def test_dask_local_cluster_gives_the_pools_rows(tmp_path):
    try:
        from distributed import Client, LocalCluster
    except ImportError as e:  # python3-distributed is in scripts/install-deps.sh
        pytest.skip(f"dask.distributed cannot be imported: {e}")
    def blade_height(mapping, value):  # registered here, so it must travel to the workers
        for k in mapping["cuts"][0]["keyframes"]:
            k["position_m"][1] = value

    terracut.register_override("dask_test_blade_y_m", blade_height)
    cases = [{"resolution": 8}, {"resolution": 0}, {"resolution": 16, "dask_test_blade_y_m": 0.05}]
    local = terracut.sweep(small_exp1_dict(), cases=cases, out_dir=tmp_path / "local", processes=1)
    assert local.rows[2]["removed_volume_m3"] > local.rows[0]["removed_volume_m3"]
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        seen = []
        remote = terracut.sweep(small_exp1_dict(), cases=cases, out_dir=tmp_path / "dask", client=client,
                                progress=lambda d, t, r: seen.append(d))
        workers = {w for w in client.run(lambda: __import__("os").getpid()).values()}
    assert len(workers) == 2
    assert sorted(seen) == [1, 2, 3]
    for a, b in zip(local.rows, remote.rows):
        assert a["status"] == b["status"] and a["error"] == b["error"]
        if a["status"] == "ok":
            assert a["removed_volume_m3"] == b["removed_volume_m3"]
            assert (tmp_path / "dask" / f"case_{a['case']:03d}" / "height.npy").read_bytes() == \
                (tmp_path / "local" / f"case_{a['case']:03d}" / "height.npy").read_bytes()


def test_list_valued_and_command_line_resolutions_make_a_table(tmp_path):
    # [cols, rows] and the command line's "COLSxROWS" are the same override;
    # a list value is one text field of the table, not a broadcast error.
    result = terracut.sweep(small_exp1_dict(), grid={"resolution": [[12, 8], "12x8", [8, 12], "8x"]},
                            out_dir=tmp_path / "r", processes=1)
    assert [r["status"] for r in result.rows] == ["ok", "ok", "ok", "error"], result.failed
    assert "resolution" in result.rows[3]["error"]
    table = result.table()
    assert table.shape == (4,)
    assert list(table["resolution"]) == ["[12, 8]", "12x8", "[8, 12]", "8x"]
    # The text form runs exactly the scenario the list form does.
    a, b = (tmp_path / "r" / f"case_00{i}" for i in (0, 1))
    assert np.array_equal(np.load(a / "height.npy"), np.load(b / "height.npy"))
    assert np.load(a / "height.npy").shape == (8, 12)  # (rows, cols)
    assert np.load(tmp_path / "r" / "case_002" / "height.npy").shape == (12, 8)
    assert table["removed_volume_m3"][0] == table["removed_volume_m3"][1]
    lines = (tmp_path / "r" / "sweep.csv").read_text().splitlines()
    assert len(lines) == 5 and lines[0].startswith("case,status,error,resolution,steps")

