"""Fuzzed run folders and sweep files (issue 18): whatever a folder or a sweep file holds,
``simmer replay --check``, ``simmer plot`` and ``simmer sweep``'s reading answer with a result
or a plain refusal, never an exception, a traceback or a hang; nothing in a folder is imported.

Run folders start from a short recorded run (with a reset, collisions, NaN replies) and get one
to three mutations: a JSON value replaced by an odd one (NaN, huge, negative, text, a list, a
deep list) or removed, a line of events.jsonl cut, doubled or spoilt, a cell of trace.csv made
odd, a file emptied or filled with bytes that are not text. Sweep files start from the example
and get keys, values and text drawn the same way. A hang fails the test at its timeout; how
fast a refusal comes is measured in benchmarks/bench_limits.py, not here (a busy machine would
make any bound on its time flaky, and tracing its memory tripled the test's time).
"""

from __future__ import annotations

import json
import math
import shutil
import time
from contextlib import suppress
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from simmer import Simulation
from simmer.cli import app
from simmer.errors import SweepError
from simmer.record import RunRecorder
from simmer.sweep import sweep_from_dict
from simmer.sweep.spec import KNOWN_KEYS, MAX_RUNS, load_sweep

from helpers import EXAMPLES, drive_noisily, noisy_config

pytestmark = pytest.mark.timeout(600)

ODD: list[Any] = [
    math.nan, math.inf, -math.inf, 1e308, -1e308, 1e10, -1, 0, 10**12, 2**64, True, None, "",
    "abc", "nan", "inf", [], {}, [[[[1]]]], [1e308] * 3, {"a": {"b": {}}}, "../../etc/passwd",
    ["evil.py"], 99,
]  # fmt: skip


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("fuzz") / "run"
    sim = Simulation(noisy_config(), seed=11)
    with RunRecorder(sim, folder):
        drive_noisily(sim)
    return folder


def json_paths(value: Any, path: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    found = []
    items = value.items() if isinstance(value, dict) else enumerate(value)
    for key, inner in items:
        found.append((*path, key))
        if isinstance(inner, dict | list) and len(found) < 2000:
            found += json_paths(inner, (*path, key))
    return found


def mutate_json(text: str, data: st.DataObject) -> str:
    value = json.loads(text)
    where = data.draw(st.sampled_from(json_paths(value)))
    parent = value
    for key in where[:-1]:
        parent = parent[key]
    if data.draw(st.booleans()) and isinstance(parent, dict):
        del parent[where[-1]]
    else:
        parent[where[-1]] = data.draw(st.sampled_from(ODD))
    return json.dumps(value)  # NaN and infinities as JSON's NaN and Infinity, as an editor might


def mutate_lines(text: str, data: st.DataObject, csv: bool) -> str:
    lines = text.splitlines(keepends=True)
    i = data.draw(st.integers(0, len(lines) - 1))
    how = data.draw(st.sampled_from(["cut", "double", "odd", "drop", "junk"]))
    if how == "cut":
        lines[i] = lines[i][: data.draw(st.integers(0, len(lines[i])))]
    elif how == "double":
        lines.insert(i, lines[i] * data.draw(st.sampled_from([2, 1000])))
    elif how == "drop":
        del lines[i]
    elif how == "junk":
        lines[i] = data.draw(st.text(max_size=40)) + "\n"
    elif csv:
        cells = lines[i].rstrip("\n").split(",")
        cells[data.draw(st.integers(0, len(cells) - 1))] = str(data.draw(st.sampled_from(ODD)))
        lines[i] = ",".join(cells) + "\n"
    else:
        try:
            lines[i] = mutate_json(lines[i], data) + "\n"
        except (ValueError, TypeError):
            lines[i] = "{}\n"
    return "".join(lines)


def mutate_folder(folder: Path, data: st.DataObject) -> None:
    for _ in range(data.draw(st.integers(1, 3))):
        name = data.draw(
            st.sampled_from(["manifest.json", "events.jsonl", "trace.csv", "report.json"])
        )
        path = folder / name
        if not path.exists():
            continue
        how = data.draw(st.sampled_from(["edit", "edit", "edit", "empty", "bytes", "remove"]))
        if how == "empty":
            path.write_text("")
        elif how == "bytes":
            path.write_bytes(data.draw(st.binary(max_size=200)))
        elif how == "remove":
            path.unlink()
        elif name.endswith(".json"):
            with suppress(ValueError, TypeError, UnicodeError):  # not JSON any more: as it is
                path.write_text(mutate_json(path.read_text(), data))
        else:
            text = path.read_text(errors="replace")
            if text:
                path.write_text(mutate_lines(text, data, name.endswith(".csv")))


def assert_answered(args: list[str]) -> None:
    result = CliRunner().invoke(app, args)
    assert result.exit_code in (0, 1), (args, result.output)
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(
        result.exception
    )
    assert "Traceback" not in result.output


@pytest.mark.slow
@settings(
    max_examples=80,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(data=st.data())
def test_a_fuzzed_run_folder_is_replayed_or_refused(
    recorded: Path, tmp_path: Path, data: st.DataObject
) -> None:
    folder = tmp_path / f"run-{time.monotonic_ns()}"
    shutil.copytree(recorded, folder)
    mutate_folder(folder, data)
    assert_answered(["replay", str(folder), "--check"])


@pytest.mark.slow
@settings(
    max_examples=25,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(data=st.data())
def test_a_fuzzed_run_folder_is_plotted_or_refused(
    recorded: Path, tmp_path: Path, data: st.DataObject
) -> None:
    folder = tmp_path / f"run-{time.monotonic_ns()}"
    shutil.copytree(recorded, folder)
    mutate_folder(folder, data)
    assert_answered(["plot", str(folder)])


SWEEP = (EXAMPLES / "sweep_dead_reckoning.toml").read_text()
BASE: dict[str, Any] = {
    "config": "lab1_rover.toml",
    "program": "python3 -u dead_reckoning.py",
    "seeds": 10,
    "success": "reached and collisions == 0",
    "grid": {"drives.w0.error.y": [0.0, 0.02]},
    "sample": {"count": 3, "drives.r0.error.rotation": {"uniform": [0, 0.05]}},
}
KEYS = sorted(KNOWN_KEYS | {"count", "grid.x", "sample.count", "policy", "nonsense"})


@pytest.mark.slow
@settings(max_examples=300, deadline=None)
@given(data=st.data())
def test_a_fuzzed_sweep_is_read_or_refused(data: st.DataObject) -> None:
    sweep = json.loads(json.dumps(BASE))
    for _ in range(data.draw(st.integers(1, 3))):
        key = data.draw(st.sampled_from(KEYS))
        table = sweep
        if "." in key:
            outer, key = key.split(".", 1)
            table = sweep.setdefault(outer, {}) if isinstance(sweep.get(outer), dict) else sweep
        if data.draw(st.booleans()):
            table.pop(key, None)
        else:
            table[key] = data.draw(st.sampled_from(ODD))
    try:
        spec = sweep_from_dict(sweep, EXAMPLES)
    except SweepError as exc:
        message = str(exc)
    else:
        assert spec.run_count <= MAX_RUNS
        assert sum(1 for _ in spec.settings_to_check()) <= spec.run_count + 64
        return
    assert "\n" not in message


@pytest.mark.slow
@settings(max_examples=200, deadline=None)
@given(cut=st.integers(0, len(SWEEP)), junk=st.text(max_size=30))
def test_a_sweep_file_spoilt_anywhere_is_read_or_refused(
    tmp_path_factory: pytest.TempPathFactory, cut: int, junk: str
) -> None:
    folder = tmp_path_factory.mktemp("sweep")
    shutil.copy(EXAMPLES / "lab1_rover.toml", folder)
    path = folder / "sweep.toml"
    path.write_text(SWEEP[:cut] + junk + SWEEP[cut:])
    try:
        spec = load_sweep(path)
    except SweepError as exc:
        message = str(exc)
    else:
        assert spec.run_count <= MAX_RUNS
        return
    assert message.startswith((str(path), f"cannot read {path}"))
