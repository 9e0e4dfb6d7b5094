"""Parameter sweeps: one scenario, many cases, locally or on a Dask cluster.

    import terracut
    result = terracut.sweep("scenarios/paper_experiment1.yaml",
                            grid={"resolution": [25, 50, 100],
                                  "representation": ["surface", "columns"]},
                            out_dir="out/sweep")
    result.table()      # numpy structured array, one row per case
    result.failed       # the rows of cases that raised, with their error

Each case is the scenario with its overrides applied, run as `terracut run`
does into OUT_DIR/case_NNN/ (contact.csv, height.npy, ..., summary.json, and
case.json with the case's overrides). The table is also written to
OUT_DIR/sweep.csv and OUT_DIR/sweep.json.

Overrides are named (see OVERRIDES: resolution, representation, rate_hz,
blade_length_m, sequence, soil, repose_deg) or field paths of the scenario
schema in the reader's own notation, e.g. "terrain.size_m[0]" or
"cuts[*].keyframes[*].position_m[1]" ([*]: every element). resolution takes
N, [cols, rows] or the command line's "COLSxROWS". A new name is added with
register_override(). The teleoperation link's conditions (rtt_ms, loss,
deadband, seed) are options of a teleoperation run, not scenario fields: a
case with one of them, or a scenario with an `mmt:` section, runs both
stations (terracut.run_mmt) and its row holds that run's figures.

Without a client the cases run in a local process pool (processes workers,
default: the machine's cores; processes=1 runs them in this process). With a
dask.distributed Client they are submitted to its cluster; the workers must
be able to import terracut (the same build on PYTHONPATH, or installed).
"""

from __future__ import annotations

import copy
import csv
import itertools
import json
import math
import os
import re
import sys
import time
import traceback
from collections.abc import Callable, Iterable, Mapping
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any, Optional, Union

import numpy as np

from ._scenarios import from_dict, load_mapping, scenario_text
from ._terracut import InputError, Scenario, _parse_resolution

# --- Overrides ---------------------------------------------------------------

OverrideFn = Callable[[dict, Any], None]


def _set_path(path: str):
    """A setter for a field path such as 'terrain.size_m[0]' or 'cuts[*].keyframes[*].t_s'."""
    tokens = _parse_path(path)

    def apply(m: dict, value: Any) -> None:
        _assign(m, tokens, value, path, "")

    return apply


_TOKEN = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)|\[(\d+|\*)\]|(\.)")


def _parse_path(path: str) -> list:
    tokens: list = []
    pos = 0
    expect_name = True
    while pos < len(path):
        m = _TOKEN.match(path, pos)
        if not m:
            raise InputError(f"override '{path}': cannot read the field path at '{path[pos:]}'")
        name, index, dot = m.groups()
        if name is not None:
            if not expect_name:
                raise InputError(f"override '{path}': expected '.' or '[' before '{name}'")
            tokens.append(name)
            expect_name = False
        elif index is not None:
            if expect_name and not tokens:
                raise InputError(f"override '{path}': a path starts with a field name")
            tokens.append(Ellipsis if index == "*" else int(index))  # Ellipsis: every element
            expect_name = False
        else:
            if expect_name:
                raise InputError(f"override '{path}': empty field name")
            expect_name = True
        pos = m.end()
    if expect_name or not tokens:
        raise InputError(f"override '{path}': the path ends without a field")
    return tokens


def _assign(node: Any, tokens: list, value: Any, path: str, where: str) -> None:
    head, rest = tokens[0], tokens[1:]
    if isinstance(head, str):
        if not isinstance(node, dict):
            raise InputError(f"override '{path}': {where or 'the scenario'} is not a mapping")
        here = f"{where}.{head}" if where else head
        if not rest:
            node[head] = copy.deepcopy(value)
            return
        if head not in node:
            node[head] = [] if not isinstance(rest[0], str) else {}
        _assign(node[head], rest, value, path, here)
        return
    if not isinstance(node, list):
        raise InputError(f"override '{path}': {where} is not a list")
    indices = range(len(node)) if head is Ellipsis else [head]
    for i in indices:
        if i >= len(node):
            raise InputError(f"override '{path}': {where} has {len(node)} entries, no [{i}]")
        if not rest:
            node[i] = copy.deepcopy(value)
        else:
            _assign(node[i], rest, value, path, f"{where}[{i}]")


def _soil(m: dict, value: Any) -> None:
    m["soil"] = {"model": value} if isinstance(value, str) else copy.deepcopy(value)


def _repose(m: dict, value: Any) -> None:
    soil = m.setdefault("soil", {})
    soil["model"] = "flow"
    soil["repose_deg"] = value


def _resolution(m: dict, value: Any) -> None:
    """N, [cols, rows], or the command line's text "N" / "COLSxROWS" (read by
    the command line's own parser, io::parse_resolution)."""
    if isinstance(value, str):
        value = list(_parse_resolution(value))
    m.setdefault("terrain", {})["resolution"] = value


OVERRIDES: dict[str, OverrideFn] = {
    "resolution": _resolution,
    "representation": _set_path("representation"),
    "rate_hz": _set_path("rate_hz"),
    "blade_length_m": _set_path("blade.length_m"),
    "sequence": _set_path("sequence"),
    "soil": _soil,
    "repose_deg": _repose,
}
"""Named overrides: name -> function(mapping, value) that edits the scenario mapping."""
_BUILTIN = frozenset(OVERRIDES)


def register_override(name: str, apply: OverrideFn) -> None:
    """Adds a named override: apply(mapping, value) edits the scenario's mapping in place.

    This is the hook for parameters whose scenario section arrives later
    (e.g. the teleoperation link's network delay). Functions given here must
    be importable by the workers of a distributed sweep (a module-level
    function of an importable module).
    """
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name):
        raise InputError(f"register_override: '{name}' is not a valid override name")
    if not callable(apply):
        raise InputError(f"register_override: the override '{name}' needs a function")
    OVERRIDES[name] = apply


def _override_fn(name: str) -> OverrideFn:
    if name in OVERRIDES:
        return OVERRIDES[name]
    if "." in name or "[" in name:
        return _set_path(name)
    raise InputError(
        f"override '{name}': not a named override ({', '.join(sorted(OVERRIDES))}) "
        f"nor a field path such as 'terrain.size_m[0]'"
    )


def apply_overrides(mapping: Mapping, overrides: Mapping[str, Any]) -> dict:
    """A deep copy of the scenario mapping with the overrides applied, in order."""
    out = copy.deepcopy(dict(mapping))
    for name, value in overrides.items():
        _override_fn(name)(out, value)
    return out


# --- Cases -------------------------------------------------------------------

def _summary_row(index: int, overrides: dict, result: dict, wall_s: float, out_dir: str) -> dict:
    records = result["records"]
    contact = records["contact_length"]
    return {
        "case": index,
        "status": "ok",
        "error": "",
        "overrides": overrides,
        "steps": int(result["steps"]),
        "removed_volume_m3": float(result["removed_volume_m3"]),
        "initial_volume_m3": float(result["initial_volume_m3"]),
        "final_volume_m3": float(result["final_volume_m3"]),
        "volume_error_m3": float(result["volume_error_m3"]),
        "max_sample_error_m": float(result["max_sample_error_m"]),
        "peak_contact_m": float(contact.max()) if contact.size else 0.0,
        "mean_contact_m": float(contact.mean()) if contact.size else 0.0,
        "step_p50_us": float(result["step_timing"]["p50_us"]),
        "wall_s": wall_s,
        "out_dir": out_dir,
    }


def _error_row(index: int, overrides: dict, error: str, wall_s: float, out_dir: str) -> dict:
    return {"case": index, "status": "error", "error": error, "overrides": overrides,
            "wall_s": wall_s, "out_dir": out_dir}


# The teleoperation link's conditions: not fields of the scenario but options
# of its run (`terracut mmt --rtt-ms ... --loss ...`); a case that has one, or
# a scenario with an `mmt:` section, runs both stations (terracut.run_mmt).
NETWORK_OVERRIDES = ("rtt_ms", "loss", "deadband", "seed")


def _run_case(spec: dict) -> dict:
    """Runs one case (in a worker process or on a Dask worker); never raises."""
    start = time.perf_counter()
    index, overrides, out_dir = spec["case"], spec["overrides"], spec["out_dir"]
    try:
        import terracut

        for name, fn in spec.get("extra_overrides", {}).items():
            OVERRIDES[name] = fn  # the client's, which may be newer than this worker's
        network = {k: v for k, v in overrides.items() if k in NETWORK_OVERRIDES}
        fields = {k: v for k, v in overrides.items() if k not in NETWORK_OVERRIDES}
        mapping = apply_overrides(spec["mapping"], fields)
        scenario = from_dict(mapping, base_dir=spec["base_dir"], label=spec["label"])
        os.makedirs(out_dir, exist_ok=True)
        with open(os.path.join(out_dir, "case.json"), "w") as f:
            json.dump({"case": index, "overrides": overrides}, f, indent=2, default=str)
        if network or "mmt" in mapping:
            figures = terracut.run_mmt(scenario, out_dir, **network)
            return {"case": index, "status": "ok", "error": "", "overrides": overrides, **figures,
                    "wall_s": time.perf_counter() - start, "out_dir": out_dir}
        result = terracut.run(scenario, out_dir)
        return _summary_row(index, overrides, result, time.perf_counter() - start, out_dir)
    except Exception as e:  # a failed case is a row, not a lost sweep
        message = str(e) if isinstance(e, InputError) else f"{type(e).__name__}: {e}"
        return _error_row(index, overrides, message, time.perf_counter() - start, out_dir)


def _cases(grid: Optional[Mapping[str, Iterable]], cases: Optional[Iterable[Mapping]]) -> list[dict]:
    if (grid is None) == (cases is None):
        raise InputError("sweep: give either grid= (a dict of value lists) or cases= (a list of override dicts)")
    if grid is not None:
        if not isinstance(grid, Mapping) or not grid:
            raise InputError("sweep: grid must be a non-empty dict of name -> list of values")
        names = list(grid)
        values = []
        for n in names:
            v = grid[n]
            if isinstance(v, (str, bytes)) or not isinstance(v, Iterable):
                raise InputError(f"sweep: grid['{n}'] must be a list of values")
            v = list(v)
            if not v:
                raise InputError(f"sweep: grid['{n}'] is empty")
            values.append(v)
        return [dict(zip(names, combo)) for combo in itertools.product(*values)]
    out = []
    for i, c in enumerate(cases):
        if not isinstance(c, Mapping):
            raise InputError(f"sweep: cases[{i}] must be a dict of overrides")
        out.append(dict(c))
    if not out:
        raise InputError("sweep: cases is empty")
    return out


def _plain(value: Any) -> Any:
    """A JSON-friendly copy (numpy scalars and arrays as Python numbers and lists)."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if hasattr(value, "tolist"):
        return value.tolist()
    return value


# --- The result --------------------------------------------------------------

_NUMERIC = ["steps", "removed_volume_m3", "initial_volume_m3", "final_volume_m3",
            "volume_error_m3", "max_sample_error_m", "peak_contact_m", "mean_contact_m",
            "step_p50_us", "wall_s"]


_NOT_FIGURES = frozenset({"case", "status", "error", "overrides", "out_dir"})


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)


def _figure_names(rows: list[dict], teleoperation: bool, overrides: Iterable[str] = ()) -> list[str]:
    """The table's figure columns: a run's (_NUMERIC) unless the sweep is of
    teleoperation runs, then every other number the rows that ran hold, in
    the order they hold them (a teleoperation case's force errors, packet
    rates, ...), and wall_s. A figure named as an override (a teleoperation
    run's loss) is the override's column."""
    names = [] if teleoperation else list(_NUMERIC)
    skip = _NOT_FIGURES | set(overrides)
    for r in rows:
        if r["status"] != "ok":
            continue
        for k, v in r.items():
            if k not in skip and k not in names and _is_number(v):
                names.append(k)
    if "wall_s" not in names:
        names.append("wall_s")
    return names


class SweepResult:
    """The rows of a sweep, one per case in case order.

    rows: list of dicts: case, status ('ok' or 'error'), error (the message),
    overrides (the case's dict), the case's figures and out_dir. A run's
    figures: steps, removed/initial/final_volume_m3 (m^3), volume_error_m3,
    max_sample_error_m (m), peak_contact_m and mean_contact_m (m),
    step_p50_us (us), wall_s (s); a teleoperation case's: terracut.run_mmt's
    (force errors of MMT and of direct force reflection, N; terrain and
    tracking errors, m; packet rates, per s; passivity, J; ...) and wall_s.
    figures: the table's figure columns (default: those the rows hold).
    """

    def __init__(self, rows: list[dict], out_dir: Path, names: list[str],
                 figures: Optional[list[str]] = None):
        self.rows = rows
        self.out_dir = out_dir
        self.override_names = names
        if figures is None:
            figures = _figure_names(rows, any(r["status"] == "ok" and "steps" not in r for r in rows), names)
        self.figures = list(figures)

    @property
    def ok(self) -> list[dict]:
        return [r for r in self.rows if r["status"] == "ok"]

    @property
    def failed(self) -> list[dict]:
        return [r for r in self.rows if r["status"] != "ok"]

    def column(self, name: str) -> np.ndarray:
        """One figure or override over the cases, one entry per case: float64 when
        every value is a number (NaN where a case failed or lacks it), else text
        (a string as it is, anything else, such as [cols, rows], as its JSON)."""
        if name in self.override_names:
            vals = [r["overrides"].get(name) for r in self.rows]
        else:
            vals = [r.get(name) for r in self.rows]
        if all(v is None or _is_number(v) for v in vals):
            return np.array([np.nan if v is None else float(v) for v in vals], dtype=float)
        return np.array(["" if v is None else v if isinstance(v, str) else json.dumps(_plain(v))
                         for v in vals], dtype=str)

    def table(self) -> np.ndarray:
        """The rows as a numpy structured array: case, status, error, one field per
        override (numbers as float64, anything else as its JSON text), the figures."""
        fields: list[tuple[str, Any]] = [("case", np.int64)]
        data: dict[str, np.ndarray] = {"case": np.array([r["case"] for r in self.rows], dtype=np.int64)}
        for name in ["status", "error"] + self.override_names:
            col = self.column(name) if name in self.override_names else np.array([r[name] for r in self.rows])
            data[name] = col
        for name in self.figures:
            data[name] = self.column(name)
        for name in ["status", "error"] + self.override_names + self.figures:
            col = data[name]
            fields.append((name, col.dtype if col.dtype.kind != "U" else f"U{max(1, col.dtype.itemsize // 4)}"))
        out = np.empty(len(self.rows), dtype=fields)
        for name, _ in fields:
            out[name] = data[name]
        return out

    def __repr__(self) -> str:
        return f"<SweepResult {len(self.rows)} cases, {len(self.failed)} failed, in {self.out_dir}>"


def _write_table(result: SweepResult) -> None:
    table = result.table()
    with open(result.out_dir / "sweep.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(table.dtype.names)
        for row in table:
            w.writerow([repr(float(v)) if isinstance(v, np.floating) else v for v in row.tolist()])
    with open(result.out_dir / "sweep.json", "w") as f:
        json.dump(_plain(result.rows), f, indent=2, default=str)


# --- Progress ----------------------------------------------------------------

def _stderr_progress(done: int, total: int, row: dict) -> None:
    state = "ok" if row["status"] == "ok" else "FAILED: " + row["error"]
    print(f"sweep: {done}/{total} case {row['case']} {row['overrides']} {state} ({row['wall_s']:.2f} s)",
          file=sys.stderr, flush=True)


# --- The sweep ---------------------------------------------------------------

def sweep(scenario: Union[str, os.PathLike, Mapping],
          grid: Optional[Mapping[str, Iterable]] = None,
          cases: Optional[Iterable[Mapping[str, Any]]] = None,
          out_dir: Union[str, os.PathLike] = "out/sweep",
          *,
          client: Any = None,
          processes: Optional[int] = None,
          progress: Union[bool, Callable[[int, int, dict], None], None] = None) -> SweepResult:
    """Runs every case of a sweep and returns its table (SweepResult).

    scenario: a scenario file or a dict with its schema. grid: name -> list
    of values (every combination is a case, in order) or cases: a list of
    override dicts. out_dir: case_NNN/ folders and sweep.csv / sweep.json.
    client: a dask.distributed Client: the cases go to its cluster; else a
    local process pool of `processes` workers (default os.cpu_count(); 1:
    in this process). progress: True for a line on stderr per finished
    case, or a function(done, total, row). A case that fails is a row with
    status 'error' and its message; the others are kept.
    """
    if isinstance(scenario, Scenario):
        raise InputError("sweep: give the scenario as a file path or a dict (its overrides edit the mapping)")
    if isinstance(scenario, Mapping):
        mapping, base_dir, label = dict(scenario), os.getcwd(), "scenario dict"
        scenario_text(mapping)  # refuses what cannot be written, before any case runs
    else:
        path = Path(scenario)
        mapping = load_mapping(path)
        base_dir, label = str(path.parent.resolve()), f"{path.name} with overrides"
    case_list = _cases(grid, cases)
    names: list[str] = []
    for c in case_list:
        for n in c:
            if n not in NETWORK_OVERRIDES:
                _override_fn(n)  # an unknown name fails now, not in every case
            if n not in names:
                names.append(n)
    if processes is not None and (not isinstance(processes, int) or processes < 1):
        raise InputError(f"sweep: processes must be an integer >= 1, got {processes!r}")
    report = _stderr_progress if progress is True else (progress or None)

    root = Path(out_dir)
    root.mkdir(parents=True, exist_ok=True)
    width = max(3, len(str(len(case_list) - 1)))
    # Overrides registered in this process travel to Dask workers with the
    # case (a local pool's forked workers inherit them).
    extra = {n: OVERRIDES[n] for n in names if n in OVERRIDES and n not in _BUILTIN}
    specs = [{"case": i, "overrides": _plain(c), "mapping": mapping, "base_dir": base_dir,
              "label": label, "out_dir": str((root / f"case_{i:0{width}d}").resolve()),
              "extra_overrides": extra if client is not None else {}}
             for i, c in enumerate(case_list)]
    rows: list[Optional[dict]] = [None] * len(specs)
    done = 0

    def finished(i: int, row: dict) -> None:
        nonlocal done
        rows[i] = row
        done += 1
        if report:
            report(done, len(specs), row)

    if client is not None:
        from distributed import as_completed as dask_completed

        futures = client.map(_run_case, specs, pure=False)
        index = {f.key: i for i, f in enumerate(futures)}
        for f in dask_completed(futures):
            i = index[f.key]
            try:
                row = f.result()
            except Exception as e:  # the worker died or could not run the case
                row = _error_row(i, specs[i]["overrides"], f"{type(e).__name__}: {e}", math.nan,
                                 specs[i]["out_dir"])
            finished(i, row)
    elif processes == 1 or len(specs) == 1:
        for i, s in enumerate(specs):
            finished(i, _run_case(s))
    else:
        with ProcessPoolExecutor(max_workers=min(processes or os.cpu_count() or 1, len(specs))) as pool:
            futures = {pool.submit(_run_case, s): i for i, s in enumerate(specs)}
            for f in as_completed(futures):
                i = futures[f]
                try:
                    row = f.result()
                except Exception as e:  # a worker process died (e.g. killed)
                    row = _error_row(i, specs[i]["overrides"],
                                     f"{type(e).__name__}: {e}\n{traceback.format_exc(limit=1)}",
                                     math.nan, specs[i]["out_dir"])
                finished(i, row)

    done_rows = [r for r in rows if r is not None]
    teleoperation = "mmt" in mapping or any(n in NETWORK_OVERRIDES for n in names)
    result = SweepResult(done_rows, root, names, _figure_names(done_rows, teleoperation, names))
    _write_table(result)
    return result
