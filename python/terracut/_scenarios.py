"""Scenarios from files and from Python mappings.

A mapping has the scenario file's schema (docs/scenario-format.md). It is
written out as YAML text and read by the same C++ reader as a file, so a
dict gets exactly the file's checks and messages; only the "FILE:LINE:"
prefix becomes the dict's label (the line of generated text would mean
nothing to the reader of the message).
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Union

from ._terracut import InputError, Scenario, _yaml_to_python

DICT_LABEL = "scenario dict"

ScenarioLike = Union[Scenario, Mapping, str, os.PathLike]


def _yaml_text(value: Any, field: str) -> str:
    """One value as YAML flow text (JSON-like; non-finite floats as YAML's)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if hasattr(value, "item") and hasattr(value, "dtype") and getattr(value, "ndim", 0) == 0:
        value = value.item()  # numpy scalar
    if isinstance(value, int):
        return str(int(value))
    if isinstance(value, float):
        if math.isnan(value):
            return ".nan"
        if math.isinf(value):
            return ".inf" if value > 0 else "-.inf"
        return repr(value)
    if isinstance(value, (str, os.PathLike)):
        text = os.fspath(value)
        out = ['"']
        for ch in text:
            if ch == '"' or ch == "\\":
                out.append("\\" + ch)
            elif ord(ch) < 0x20 or ord(ch) == 0x7F:
                out.append("\\x%02x" % ord(ch))
            else:
                out.append(ch)
        out.append('"')
        return "".join(out)
    if isinstance(value, Mapping):
        items = []
        for k, v in value.items():
            if not isinstance(k, str):
                raise InputError(f"{DICT_LABEL}: {field or 'the scenario'}: keys must be strings, got {k!r}")
            items.append(f"{_yaml_text(k, field)}: {_yaml_text(v, f'{field}.{k}' if field else k)}")
        return "{" + ", ".join(items) + "}"
    if hasattr(value, "tolist"):  # numpy array
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_yaml_text(v, f"{field}[{i}]") for i, v in enumerate(value)) + "]"
    raise InputError(f"{DICT_LABEL}: {field}: cannot be written as scenario YAML: {type(value).__name__}")


def scenario_text(mapping: Mapping) -> str:
    """The mapping as scenario YAML text, one top-level key per line."""
    if not isinstance(mapping, Mapping):
        raise InputError(f"{DICT_LABEL}: expected a mapping (dict), got {type(mapping).__name__}")
    lines = []
    for key, value in mapping.items():
        if not isinstance(key, str):
            raise InputError(f"{DICT_LABEL}: keys must be strings, got {key!r}")
        lines.append(f"{_yaml_text(key, '')}: {_yaml_text(value, key)}")
    return "\n".join(lines) + "\n"


def from_dict(mapping: Mapping, base_dir: Union[str, os.PathLike, None] = None,
              label: str = DICT_LABEL) -> Scenario:
    """A scenario from a mapping with the scenario file's schema.

    base_dir: the folder relative paths (terrain.image) are read from; the
    current folder by default. label: names the mapping in error messages.
    Raises terracut.InputError with the file reader's message, e.g.
    "scenario dict: cuts[0].keyframes[1].t_s: must be ...".
    """
    text = scenario_text(mapping)
    source = Path(base_dir if base_dir is not None else ".") / label
    try:
        return Scenario._parse(text, source)
    except InputError as e:
        message = str(e)
        prefix = re.escape(str(source)) + r":\d+: "
        raise InputError(re.sub("^" + prefix, label + ": ", message)) from None


def load_mapping(path: Union[str, os.PathLike]) -> dict:
    """A scenario file's YAML as Python objects (the file is validated first)."""
    Scenario.load(path)
    return _yaml_to_python(Path(path).read_text(), os.fspath(path))


def as_scenario(scenario: ScenarioLike) -> Scenario:
    """A Scenario from a Scenario, a file path or a mapping."""
    if isinstance(scenario, Scenario):
        return scenario
    if isinstance(scenario, Mapping):
        return from_dict(scenario)
    if isinstance(scenario, (str, os.PathLike)):
        return Scenario.load(scenario)
    raise InputError(f"scenario: expected a Scenario, a file path or a dict, got {type(scenario).__name__}")
