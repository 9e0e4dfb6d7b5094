"""Scenarios from files, dicts and images: the same reader, the same errors."""

import math
import re

import numpy as np
import pytest

import terracut
from conftest import SCENARIOS, small_exp1_dict


def test_load_reads_the_file(exp1):
    sc = terracut.Scenario.load(exp1)
    assert sc.name == "paper_experiment1"
    assert sc.resolution == (50, 50)
    assert sc.size_m == (1.0, 1.0)
    assert sc.representation == "surface"
    assert sc.rate_hz == 1000.0
    assert sc.blade_length_m == 1.2
    assert sc.cut_names == ["horizontal"]
    assert sc.sequence == ["horizontal"]


def test_dict_of_a_file_is_the_same_scenario(exp1):
    # The file's YAML as a dict, read back as a dict scenario, steps to the
    # bitwise same terrain (images resolve against base_dir).
    mapping = terracut.load_mapping(exp1)
    assert mapping["terrain"]["resolution"] == 50
    assert mapping["cuts"][0]["keyframes"][1]["position_m"] == [0.5, 0.1, 1.1]
    from_file = terracut.Simulation(terracut.Scenario.load(exp1))
    from_dict = terracut.Simulation(terracut.Scenario.from_dict(mapping, base_dir=SCENARIOS))
    a, b = from_file.run(), from_dict.run()
    assert from_file.state_hash == from_dict.state_hash
    np.testing.assert_array_equal(a["contact_length"], b["contact_length"])


def test_cut_poses_follow_the_keyframes(exp1):
    sc = terracut.Scenario.load(exp1)
    poses = sc.cut_poses("horizontal")
    assert poses.shape == (2001, 7)  # 2 s at 1 kHz, both ends included
    np.testing.assert_array_equal(poses[0], [0.5, 0.1, -0.1, 1, 0, 0, 0])
    np.testing.assert_allclose(poses[-1], [0.5, 0.1, 1.1, 1, 0, 0, 0], atol=1e-15)
    # Linear in time: 0.6 m/s along +Z, 0.6 mm per step.
    np.testing.assert_allclose(np.diff(poses[:, 2]), 0.6e-3, rtol=1e-9)
    assert sc.cut_poses(0, rate_hz=10).shape == (21, 7)
    with pytest.raises(terracut.InputError, match="no cut named 'nope'"):
        sc.cut_poses("nope")
    with pytest.raises(terracut.InputError, match="rate_hz must be in"):
        sc.cut_poses(0, rate_hz=0)


def error_of(fn):
    with pytest.raises(terracut.InputError) as info:
        fn()
    return str(info.value)


def test_a_dict_has_the_files_errors_without_the_line(tmp_path):
    bad = small_exp1_dict()
    bad["cuts"][0]["keyframes"][1]["t_s"] = 0.0
    path = tmp_path / "bad.yaml"
    path.write_text(terracut._scenarios.scenario_text(bad))
    from_file = error_of(lambda: terracut.Scenario.load(path))
    from_dict = error_of(lambda: terracut.Scenario.from_dict(bad))
    assert re.match(re.escape(str(path)) + r":\d+: cuts\[0\]\.keyframes\[1\]\.t_s: ", from_file), from_file
    assert from_dict == "scenario dict: " + from_file.split(": ", 1)[1]


@pytest.mark.parametrize("edit, field", [
    (lambda d: d["terrain"].__setitem__("size_m", [1.0, math.nan]), "terrain.size_m[1]"),
    (lambda d: d["blade"].__setitem__("width_m", 1.0), "blade.width_m"),
    (lambda d: d.__setitem__("representation", "boxes"), "representation"),
    (lambda d: d["terrain"].__setitem__("resolution", 0), "terrain.resolution"),
    (lambda d: d.__setitem__("sequence", ["horizontal", "b"]), "sequence[1]"),
])
def test_dict_errors_name_the_field(edit, field):
    d = small_exp1_dict()
    edit(d)
    message = error_of(lambda: terracut.Scenario.from_dict(d))
    assert message.startswith(f"scenario dict: {field}: "), message


def test_things_a_scenario_cannot_hold_are_named():
    d = small_exp1_dict()
    d["blade"]["length_m"] = object()
    assert "blade.length_m" in error_of(lambda: terracut.Scenario.from_dict(d))
    assert "expected a mapping" in error_of(lambda: terracut.Scenario.from_dict([1, 2]))
    assert "keys must be strings" in error_of(lambda: terracut.Scenario.from_dict({1: 2}))


def test_numpy_values_are_accepted():
    d = small_exp1_dict()
    d["terrain"]["resolution"] = np.int64(12)
    d["terrain"]["size_m"] = np.array([1.0, 1.0])
    assert terracut.Scenario.from_dict(d).resolution == (12, 12)


def test_missing_file_and_bad_yaml(tmp_path):
    assert "not found" in error_of(lambda: terracut.Scenario.load(tmp_path / "none.yaml")) or \
        "cannot" in error_of(lambda: terracut.Scenario.load(tmp_path / "none.yaml"))
    bad = tmp_path / "bad.yaml"
    bad.write_text("terrain: [1, 2\n")
    assert str(bad) in error_of(lambda: terracut.Scenario.load(bad))


def test_overrides_are_the_command_lines(exp1):
    sc = terracut.Scenario.load(exp1).with_overrides(resolution="32x16", representation="columns")
    assert sc.resolution == (32, 16)
    assert sc.representation == "columns"
    assert terracut.Scenario.load(exp1).with_overrides(resolution=[8, 4]).resolution == (8, 4)
    assert "resolution" in error_of(lambda: terracut.Scenario.load(exp1).with_overrides(resolution=0))
    assert "representation" in error_of(
        lambda: terracut.Scenario.load(exp1).with_overrides(representation="boxes"))
    assert "unknown cut" in error_of(
        lambda: terracut.Scenario.load(exp1).with_overrides(sequence=["horizontal", "x"]))


def test_from_image_is_the_heightmap_at_its_resolution():
    sc = terracut.Scenario.from_image(SCENARIOS.parent / "data" / "mound.png", extent_m=2.0,
                                      full_scale_m=0.5)
    assert sc.resolution == (256, 256)
    assert sc.size_m == (2.0, 2.0)
    sim = terracut.Simulation(sc)
    # The image is the 0.2 m mound at full scale 1 (a white pixel is its top):
    # at full scale 0.5 the peak is 0.5 m, at the middle of the terrain.
    assert abs(float(sim.heights.max()) - 0.5) < 0.5 * 1e-3
    r, c = np.unravel_index(np.argmax(sim.heights), sim.heights.shape)
    assert abs(r - 127.5) <= 1 and abs(c - 127.5) <= 1
    assert "/no/such.png" in error_of(lambda: terracut.Scenario.from_image("/no/such.png"))
    assert error_of(lambda: terracut.Scenario.from_image("x.png", extent_m=0)).startswith("extent_m must be")


def test_yaml_scalars_keep_their_types():
    text = 'a: 1\nb: -2\nc: 1.5\nd: 1e3\ne: true\nf: ~\ng: "1"\nh: surface\ni: [0.1, x]\nj: .nan\n'
    m = terracut._terracut._yaml_to_python(text, "t.yaml")
    assert m["a"] == 1 and type(m["a"]) is int and m["b"] == -2
    assert m["c"] == 1.5 and m["d"] == 1000.0 and type(m["d"]) is float
    assert m["e"] is True and m["f"] is None
    assert m["g"] == "1" and m["h"] == "surface" and m["i"] == [0.1, "x"]
    assert math.isnan(m["j"])
    with pytest.raises(terracut.InputError, match="t.yaml:"):
        terracut._terracut._yaml_to_python("a: [1,", "t.yaml")
