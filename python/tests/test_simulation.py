"""The simulation from Python: zero-copy views, steps single and batched,
the validated edit, queries, errors that never abort."""

import gc
import math
import pydoc

import numpy as np
import pytest

import terracut
from conftest import small_exp1_dict

POSE = [0.5, 0.1, 0.55, 1.0, 0.0, 0.0, 0.0]  # through the centres of row 5 of a 10x10 grid


def flat(n=10, h=0.5, **kw):
    return terracut.Simulation.from_heights(np.full((n, n), h, dtype=np.float32), **kw)


def test_layers_share_memory_with_the_grid_and_are_read_only():
    sim = flat(blade_length_m=2.0)
    h = sim.heights
    assert h.shape == (10, 10) and h.dtype == np.float32
    assert np.shares_memory(h, sim.heights)  # the same C++ array, no copy
    assert not h.flags.writeable
    with pytest.raises(ValueError):
        h[0, 0] = 1.0
    with pytest.raises(ValueError):
        h.flags.writeable = True
    # The view sees the cut as it happens: one step across row 5 at y = 0.2.
    before = sim.removed
    sim.step([0.5, 0.2, 0.55, 1, 0, 0, 0])
    assert h[5].max() <= 0.2 + 1e-6 and h[0].min() == 0.5
    np.testing.assert_array_equal(sim.heights + sim.removed, sim.initial)
    # removed is derived by the grid, so it is a read-only copy taken when
    # read: one read before the step still shows nothing removed.
    assert not before.flags.writeable and before.shape == (10, 10) and before.dtype == np.float32
    assert not np.shares_memory(before, sim.removed)
    assert before.max() == 0.0 and sim.removed[5].min() >= 0.3 - 1e-6


def test_a_view_keeps_the_simulation_alive():
    sim = flat()
    h = sim.heights
    del sim
    gc.collect()
    assert float(h.sum()) == 50.0  # still the grid's memory, still valid
    assert h.base is not None


def test_edit_heights_reports_the_rectangle_and_refuses_bad_values():
    sim = flat(representation="columns", blade_length_m=2.0)
    before = sim.state_hash
    assert sim.edit_heights(np.full((2, 3), 0.1), c0=4, r0=6) == (4, 6, 7, 8)
    assert float(sim.heights[6:8, 4:7].max()) == pytest.approx(0.1)
    np.testing.assert_allclose(sim.removed[6:8, 4:7], 0.4, rtol=1e-6)
    assert sim.state_hash != before
    edited = sim.state_hash
    with pytest.raises(terracut.InputError, match="inside the 10 x 10 grid"):
        sim.edit_heights(np.zeros((2, 2)), c0=9, r0=0)
    with pytest.raises(terracut.InputError, match=r"\(col 1, row 0\)"):
        sim.edit_heights(np.array([[0.1, np.nan]]))
    with pytest.raises(terracut.InputError, match="finite and >= 0"):
        sim.edit_heights(np.array([[-1.0]]))
    with pytest.raises(terracut.InputError, match="2-D"):
        sim.edit_heights(np.zeros(3))
    with pytest.raises(terracut.InputError, match="inside the 10 x 10 grid"):
        sim.edit_heights(np.zeros((1, 1)), c0=2**31 - 1)
    assert sim.state_hash == edited  # a refused edit writes nothing


def test_batched_steps_equal_single_steps(exp1):
    sc = terracut.Scenario.load(exp1).with_overrides(resolution=25)
    poses = sc.cut_poses("horizontal")
    one, many = terracut.Simulation(sc), terracut.Simulation(sc)
    singles = [one.step(p) for p in poses.tolist()]
    cols = many.step(poses)
    assert set(cols) >= {"step", "t", "x", "contact_length", "removed_volume", "changed_c0", "step_s"}
    assert len(cols["t"]) == len(poses)
    np.testing.assert_array_equal(cols["contact_length"], [s.contact_length_m for s in singles])
    np.testing.assert_array_equal(cols["removed_volume"], [s.removed_volume_m3 for s in singles])
    np.testing.assert_array_equal(cols["cells_visited"], [s.cells_visited for s in singles])
    np.testing.assert_array_equal(cols["t"], np.arange(len(poses)) / 1000.0)
    assert one.state_hash == many.state_hash
    # Geometry: the peak is the chord of the 0.3464 m section circle (2 * 0.3464),
    # to within a few cells of the 25x25 grid.
    assert abs(cols["contact_length"].max() - 2 * 0.4 * math.sqrt(0.75)) < 3 * (1 / 25)
    # The changed rectangle of a cutting step holds its cut samples.
    i = int(np.argmax(cols["removed_volume"]))
    assert cols["changed_c1"][i] > cols["changed_c0"][i] and cols["changed_r1"][i] > cols["changed_r0"][i]


def test_run_steps_the_sequence_as_separate_strokes():
    d = small_exp1_dict()
    d["cuts"].append({"name": "back", "keyframes": [
        {"t_s": 0.0, "position_m": [0.5, 0.05, 1.1]}, {"t_s": 0.5, "position_m": [0.5, 0.05, -0.1]}]})
    d["sequence"] = ["horizontal", "back", "horizontal"]
    sim = terracut.Simulation(terracut.Scenario.from_dict(d))
    cols = sim.run()
    n1, n2 = 201, 101
    assert len(cols["t"]) == 2 * n1 + n2
    np.testing.assert_array_equal(cols["cut"], [0] * n1 + [1] * n2 + [0] * n1)
    # The repeated pass only meets what the deeper pass left: nothing.
    assert cols["removed_volume"][n1 + n2:].sum() == 0.0
    assert sim.conservation_error_m < 1e-6
    only = terracut.Simulation(terracut.Scenario.from_dict(d)).run(["back"])
    assert len(only["t"]) == n2
    assert len(terracut.Simulation(terracut.Scenario.from_dict(d)).run("back,back")["t"]) == 2 * n2
    with pytest.raises(terracut.InputError, match="no cut named 'nope'"):
        terracut.Simulation(terracut.Scenario.from_dict(d)).run(["nope"])


def test_contact_query_does_not_cut():
    sim = flat(representation="columns", blade_length_m=2.0)
    before = sim.state_hash
    c = sim.contact([0.5, 0.25, 0.55, 1, 0, 0, 0])
    assert c["length_m"] == pytest.approx(1.0)  # through all 10 columns of 0.1 m
    assert c["max_depth_m"] == pytest.approx(0.25)
    assert sim.state_hash == before and sim.step_count == 0


def test_surface_y_reads_the_terrain():
    sim = terracut.Simulation.from_heights(np.full((4, 4), 0.3), origin_m=(0.0, 1.0, 0.0))
    assert sim.surface_y(0.5, 0.5) == pytest.approx(1.3)
    ys = sim.surface_y(np.array([0.5, 2.0]), 0.5)
    np.testing.assert_allclose(ys, [1.3, 1.0])  # outside the terrain: the ground


@pytest.mark.parametrize("pose, match", [
    ([0, 0, 0], "expected 7 numbers"),
    ([0, 0, 0, 0, 0, 0, 0], "quaternion"),
    ([math.nan, 0, 0, 1, 0, 0, 0], "finite"),
    ("pose", "expected 7 numbers|numbers"),
    (np.zeros((3, 6)), r"got shape \(3, 6\)"),
])
def test_bad_poses_are_input_errors(pose, match):
    sim = flat()
    with pytest.raises(terracut.InputError, match=match):
        sim.step(pose)
    assert sim.step_count == 0


def test_a_bad_pose_in_a_batch_stops_nothing_half_way():
    sim = flat()
    poses = np.tile(POSE, (5, 1))
    poses[3, 0] = np.inf
    with pytest.raises(terracut.InputError, match=r"poses\[3\]"):
        sim.step(poses)
    assert sim.step_count == 0


def test_cpp_errors_keep_their_messages():
    with pytest.raises(terracut.InputError, match="blade.length_m must be finite and > 0"):
        flat(blade_length_m=-1)
    with pytest.raises(terracut.InputError, match=r"\(col 1, row 0\)"):
        terracut.Simulation.from_heights(np.array([[0.0, -1.0]]))
    with pytest.raises(terracut.InputError, match="representation"):
        flat(representation="boxes")
    assert issubclass(terracut.InputError, ValueError)


def test_run_from_heights_has_no_scenario():
    with pytest.raises(terracut.InputError, match="not from a scenario"):
        flat().run()


def test_save_writes_the_layers(tmp_path):
    sim = flat()
    sim.step(POSE)
    sim.save(tmp_path / "out")
    np.testing.assert_array_equal(np.load(tmp_path / "out" / "height.npy"), sim.heights)
    np.testing.assert_array_equal(np.load(tmp_path / "out" / "removed.npy"), sim.removed)
    assert (tmp_path / "out" / "height.png").stat().st_size > 0


def test_reset_restores_the_terrain():
    sim = flat()
    start = sim.state_hash
    sim.step(POSE)
    assert sim.state_hash != start
    sim.reset()
    assert sim.state_hash == start and sim.step_count == 0


@pytest.mark.skipif(not terracut.bodies_available(), reason="this build has no Bullet")
def test_an_edit_under_a_resting_body_drops_it():
    # A scenario's world with a body: a 0.2 m cube resting on a 0.3 m soil
    # layer; an edit lowers a 0.3 m square under it by 0.1 m and the cube
    # follows (the Bullet listener hears the edit), to within Bullet's margin.
    d = small_exp1_dict(resolution=50)
    d["terrain"] = {"generator": "plane", "resolution": 50, "size_m": [1.0, 1.0], "full_scale_m": 0.3}
    d["bodies"] = [{"name": "cube", "shape": "box", "size_m": [0.2, 0.2, 0.2], "mass_kg": 8.0,
                    "position_m": [0.3, 0.4, 0.3]}]
    sim = terracut.Simulation(terracut.Scenario.from_dict(d))
    away = np.tile([0.8, 3.0, 0.8, 1, 0, 0, 0], (1500, 1))  # the blade far above
    sim.step(away)
    y0 = sim.bodies()["position_m"][0, 1]
    assert abs(y0 - 0.4) < 0.01
    assert sim.edit_heights(np.full((15, 15), 0.2), c0=8, r0=8) == (8, 8, 23, 23)
    sim.step(away[:1000])
    assert abs(sim.bodies()["position_m"][0, 1] - 0.3) < 0.01


def test_help_explains_the_units():
    text = pydoc.render_doc(terracut.Simulation, renderer=pydoc.plaintext)
    for word in ["metres", "seconds", "unit quaternion", "read-only", "GIL", "edit_heights", "(rows, cols)"]:
        assert word in text, word


def test_a_blade_with_a_top_lets_what_stands_higher_fall_over_it():
    # A 0.6 m blade 8 cm tall (its top 3 cm above the layer) cuts 5 cm of a
    # 0.2 m layer on 1 cm cells and pushes 0.5 m along +Z: the pile reaches
    # the top, and what stands higher falls over behind it, into the trench.
    # The volume is kept, and no cell against the blade's face stands above
    # its top.
    n, cell, top = 80, 0.01, 0.15 + 0.08
    sim = terracut.Simulation.from_heights(
        np.full((n, n), 0.2, dtype=np.float32), size_m=(n * cell, n * cell),
        blade_length_m=0.6, soil_model="flow", blade_height_m=0.08)
    before = float(sim.heights.astype(np.float64).sum())
    over = 0.0
    for i in range(501):
        z = 0.1 + 0.001 * i
        over += sim.step([0.4, 0.15, z, 1.0, 0.0, 0.0, 0.0]).over_top_m3
    assert over > 0.0
    h = sim.heights
    rows = [r for r in range(n) if abs((r + 0.5) * cell - z) <= 1.5 * cell]
    assert h[rows, 10:70].max() == pytest.approx(top, abs=1e-6)
    assert float(h.astype(np.float64).sum()) == pytest.approx(before, rel=1e-6)


def test_a_bad_blade_height_is_refused_by_name():
    for bad in (0.0, -1.0, math.nan, -math.inf):
        with pytest.raises(terracut.InputError, match="blade.height_m"):
            flat(soil_model="flow", blade_height_m=bad)
    # Infinity, given or left out, is the unbounded wall (the default).
    flat(soil_model="flow", blade_height_m=math.inf)
