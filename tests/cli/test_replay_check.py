"""``simmer replay --check`` of many run folders at once (a TA's whole class), with a count."""

from __future__ import annotations

import json
from pathlib import Path

from typer.testing import CliRunner

from simmer import Simulation
from simmer.cli import app
from simmer.record import RunRecorder


def _record(folder: Path, seed: int) -> Path:
    sim = Simulation.from_config(seed=seed)
    with RunRecorder(sim, folder):
        sim.command("u0,w0-6")
        sim.run_until_idle()
        sim.command("u0")
    return folder


def _tamper(folder: Path) -> None:
    """Change the last command's recorded reading: the re-simulation then differs."""
    events = folder / "events.jsonl"
    lines = events.read_text(encoding="utf-8").splitlines()
    for i in reversed(range(len(lines))):
        event = json.loads(lines[i])
        if event["type"] == "command":
            event["replies"] = [event["replies"][0] + 1.0]
            lines[i] = json.dumps(event)
            break
    events.write_text("\n".join(lines) + "\n", encoding="utf-8")


def test_every_folder_is_checked_and_counted(tmp_path: Path) -> None:
    good = [_record(tmp_path / f"run{seed}", seed) for seed in (1, 2)]
    result = CliRunner().invoke(app, ["replay", "--check", *map(str, good)])
    assert result.exit_code == 0, result.output
    assert result.output.count("matches the recording") == 2
    assert "2 of 2 runs match their recordings" in result.output


def test_one_differing_or_unreadable_folder_fails_the_check_and_is_named(tmp_path: Path) -> None:
    good = _record(tmp_path / "good", 1)
    bad = _record(tmp_path / "bad", 2)
    _tamper(bad)
    empty = tmp_path / "empty"
    empty.mkdir()
    result = CliRunner().invoke(app, ["replay", "--check", str(good), str(bad), str(empty)])
    assert result.exit_code == 1, result.output
    assert "1 of 3 runs match their recordings; not:" in result.output
    assert str(bad) in result.output.splitlines()[-1]
    assert str(empty) in result.output.splitlines()[-1]
    assert "Traceback" not in result.output


def test_more_folders_than_side_by_side_shows_are_refused_in_one_line(tmp_path: Path) -> None:
    folders = [str(tmp_path / f"run{index}") for index in range(7)]
    result = CliRunner().invoke(app, ["replay", *folders])
    assert result.exit_code == 1
    assert "7 run folders: side by side shows 2 to 6 runs (MAX_COMPARED" in result.output
