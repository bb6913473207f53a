"""Localization tools (issue 22): the maze for programs, beliefs shown, bounded, recorded and
replayed, and localization measured in served runs and sweeps."""

from __future__ import annotations

import csv
import hashlib
import json
import logging
import math
import socket
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from link_support import read_frame, serving
from simmer.cli import app
from simmer.client import Client, connect
from simmer.geometry import Pose
from simmer.localize.belief import MAX_PARTICLES, SHOWS_PER_SECOND, BeliefBoard, parse_belief
from simmer.options import RunOptions
from simmer.record.reader import read_events
from simmer.runner import LocalLink
from simmer.serve import serve
from simmer.world import Simulation
from simmer.world.events import SHOWN, BeliefEvent, CommandEvent, EstimateEvent, Event, RunEvent
from simmer.world.localization import errors

from helpers import EXAMPLES, REPO

pytestmark = pytest.mark.timeout(180)


EXAMPLE = EXAMPLES / "histogram_localization.py"


def test_the_maze_over_the_persistent_protocol_and_export_map_agree_with_the_config(
    tmp_path: Path,
) -> None:
    sim = Simulation.from_config()
    settings = sim.config.settings
    with serving(sim) as (_runner, link), connect(port=link.stream.port) as robot:
        maze = robot.maze()
        assert robot.read("u0") > 0  # the connection goes on after the document frame
    path = tmp_path / "maze.json"
    result = CliRunner().invoke(app, ["export-map", "-o", str(path)])
    assert result.exit_code == 0, result.output
    assert json.loads(path.read_text()) == maze
    assert maze["walls"] == [list(row) for row in settings.walls]
    assert maze["cell_size"] == settings.wall_segment_length
    assert (maze["rows"], maze["cols"]) == sim.maze.solid.shape
    assert maze["floor"][0] == "".join("1" if w else "0" for w in sim.maze.floor_white[0])
    assert maze["start"]["spec"] == settings.scenario.start
    mounts = {d["id"]: d for d in maze["devices"]}
    for spec in sim.config.devices:
        assert mounts[spec.id]["position"] == list(spec.params.position[:2])
        assert mounts[spec.id]["rotation"] == spec.params.rotation
    assert mounts["u0"]["beamwidth"] == sim.robot.sensors["u0"].settings.beamwidth  # type: ignore[attr-defined]
    assert mounts["u0"]["kind"] == "ultrasonic"


def test_localization_messages_are_one_reply_each_and_bad_ones_answer_nan() -> None:
    with (
        serving() as (_runner, link),
        socket.create_connection(("127.0.0.1", link.stream.port), timeout=10) as sock,
    ):
        sock.sendall(b"%pose 1 2 3\n%pose 1 2\n%nonsense\n%show {bad\nu0\n")
        values = [read_frame(sock) for _ in range(5)]
    assert values[0] == [0.0]
    assert all(math.isnan(v[0]) for v in values[1:4])
    assert values[4][0] > 0


@pytest.mark.slow
def test_a_million_particles_are_cut_to_the_bound_counted_and_logged(
    caplog: pytest.LogCaptureFixture,
) -> None:
    sim = Simulation.from_config()
    board = BeliefBoard()
    sim.add_observer(board)
    robot = Client(LocalLink(sim), lockstep=True)
    rng = np.random.default_rng(1)
    particles = np.column_stack((rng.uniform(0, 96, (10**6, 3)), rng.uniform(0, 1, 10**6)))
    with caplog.at_level(logging.WARNING):
        cut = robot.show(particles)
    assert cut == 10**6 - MAX_PARTICLES
    assert "points cut to fit the bounds" in caplog.text
    assert board.belief is not None
    assert len(board.belief.particles) == MAX_PARTICLES
    assert board.belief.particles[:, 3].min() >= np.sort(particles[:, 3])[-MAX_PARTICLES] - 1e-3


def test_the_simulator_cuts_a_show_over_the_bound_itself(caplog: pytest.LogCaptureFixture) -> None:
    """A program not using simmer.client (or a C one) gets the same cut, count and log line."""
    rows = ",".join(f"[{i % 90},{i % 40},0,1]" for i in range(MAX_PARTICLES + 500))
    with serving() as (runner, link), caplog.at_level(logging.WARNING):
        board = BeliefBoard()
        runner.sim.add_observer(board)
        with socket.create_connection(("127.0.0.1", link.stream.port), timeout=10) as sock:
            sock.sendall(b'%show {"particles":[' + rows.encode() + b"]}\n")
            (cut,) = read_frame(sock)
    assert cut == 500
    assert "500 points of a shown belief cut" in caplog.text
    assert board.belief is not None
    assert len(board.belief.particles) == MAX_PARTICLES


def test_a_flood_of_shows_keeps_the_bound_per_simulated_second_and_counts_the_rest(
    caplog: pytest.LogCaptureFixture,
) -> None:
    sim = Simulation.from_config()
    shown: list[BeliefEvent] = []
    sim.add_observer(lambda e: shown.append(e) if isinstance(e, BeliefEvent) else None)
    robot = Client(LocalLink(sim), lockstep=True)
    start = sim.time
    with caplog.at_level(logging.WARNING):
        replies = [robot.show([[1, 2, 3, 1]]) for _ in range(100)]
    assert sim.time == start  # showing costs no simulated time
    assert replies == [0] * SHOWS_PER_SECOND + [-1] * (100 - SHOWS_PER_SECOND)
    assert len(shown) == SHOWS_PER_SECOND
    assert caplog.text.count(f"over {SHOWS_PER_SECOND} show messages a simulated second") == 1
    robot.sleep(1.0)
    assert robot.show([[1, 2, 3, 1]]) == 0
    assert shown[-1].skipped == 100 - SHOWS_PER_SECOND


def test_a_belief_that_is_not_one_is_one_line() -> None:
    for text, words in [
        ("{bad", "a belief is not readable JSON"),
        ("[1, 2]", "a belief is a JSON object"),
        ('{"particles": [[1, 2]]}', "rows of 4 numbers"),
        ('{"pose": [1, "x", 3]}', "pose must be 3 finite numbers"),
        ('{"shape": 1}', "unknown key 'shape'"),
        ('{"cells": [[1, 2], [3]]}', "rows of equal length"),
        ("x" * 300_000, "over"),
    ]:
        with pytest.raises(ValueError, match=words) as info:
            parse_belief(text)
        assert "\n" not in str(info.value)
    belief, cut = parse_belief('{"particles": [[1, 2, 3, "nan"], [1, 2, 3, 0.5]], "labels": []}')
    assert cut == 1
    assert belief.particles.tolist() == [[1, 2, 3, 1.0]]


def fingerprint(events: list[Event]) -> str:
    """A hash of every event but what the program showed (its belief and estimates), with
    neither the client's port nor the program's command line (they differ from run to run)."""
    digest = hashlib.sha256()
    for event in events:
        kept = event
        if isinstance(event, CommandEvent):
            kept = replace(event, client="")
        elif isinstance(event, RunEvent) and event.what == "program-start":
            kept = replace(event, detail="")
        if not isinstance(kept, SHOWN):
            digest.update(repr(kept).encode())
    return digest.hexdigest()


def example_run(tmp_path: Path, *options: str, record: Path | None = None) -> list[Event]:
    sim = Simulation.from_config(EXAMPLES / "lab1_rover.toml", seed=4)
    events: list[Event] = []
    sim.add_observer(events.append)
    config = EXAMPLES / "lab1_rover.toml"
    program = f"{sys.executable} {EXAMPLE} {config} --sensors u0 --moves 5 {' '.join(options)}"
    served = serve(
        sim,
        RunOptions.free_ports(
            speed=None, program=program, timeout=120, clock="lockstep", record=record
        ),
        echo=lambda _line: None,
    )
    assert served.ended_by == "program"
    assert served.exit_status == 0
    return events


@pytest.mark.slow
def test_showing_changes_no_reply_and_no_timing_under_lockstep(tmp_path: Path) -> None:
    # Both runs find Numba's compiled kernels on disk: a program's clock reads while Numba
    # compiles (its timers follow the simulated clock too) would differ from the next run's.
    Simulation.from_config().expected([[6.0, 42.0, 0.0]])
    shown = example_run(tmp_path)
    hidden = example_run(tmp_path, "--no-show")
    assert sum(isinstance(e, BeliefEvent) for e in shown) == 6
    assert not any(isinstance(e, BeliefEvent) for e in hidden)
    assert sum(isinstance(e, EstimateEvent) for e in hidden) == 6  # report_pose instead
    assert fingerprint(shown) == fingerprint(hidden)


@pytest.mark.slow
def test_a_recorded_run_replays_with_the_same_beliefs(tmp_path: Path) -> None:
    from simmer.view.replay_model import Recording

    folder = tmp_path / "run"
    example_run(tmp_path, record=folder)
    events = read_events(folder / "events.jsonl")
    recorded = [e for e in events if isinstance(e, BeliefEvent)]
    assert len(recorded) == 6  # before each of the 5 moves, and after the last
    moves = [e for e in events if isinstance(e, CommandEvent) and e.message[:2] in ("w0", "r0")]
    assert recorded[-1].time > moves[-1].time  # the last frame's estimate is where it ends
    recording = Recording.load(folder)
    assert recording.check.matches
    last = recording.frames[-1].belief
    assert last is not None
    assert last.to_json() == recorded[-1].belief
    first = recording.timeline.frame_at(recorded[0].time)
    assert all(frame.belief is None for frame in recording.frames[:first])
    assert recording.frames[first + 1].belief is not None  # the next frame shows it
    report = json.loads((folder / "report.json").read_text())["outcome"]
    assert report["estimates"] == 6
    assert "localized_at" in report
    result = CliRunner().invoke(app, ["plot", str(folder)])
    assert result.exit_code == 0, result.output
    assert (folder / "localization.png").stat().st_size > 10_000


@pytest.mark.slow
def test_a_hostile_belief_in_a_run_folder_is_one_line_and_the_rest_replays(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    from simmer.view.replay_model import Recording

    folder = tmp_path / "run"
    example_run(tmp_path, record=folder)
    events = folder / "events.jsonl"
    lines = events.read_text().splitlines(keepends=True)
    index = next(i for i, line in enumerate(lines) if '"type":"belief"' in line)
    data = json.loads(lines[index])
    data["belief"] = '{"particles": "not rows"}'
    lines[index] = json.dumps(data) + "\n"
    events.write_text("".join(lines))
    with caplog.at_level(logging.WARNING):
        recording = Recording.load(folder)
    assert recording.frames[-1].belief is not None
    problems = [r for r in caplog.records if "could not be read" in r.getMessage()]
    assert len(problems) == 1
    assert "\n" not in problems[0].getMessage()


def test_the_example_localizes_with_all_four_sensors_in_process() -> None:
    sys.path.insert(0, str(EXAMPLES))
    try:
        from histogram_localization import localize
    finally:
        sys.path.remove(str(EXAMPLES))
    sim = Simulation.from_config(REPO / "examples" / "lab1_rover.toml")
    robot = Client(LocalLink(sim), lockstep=True)
    x, y, heading, p = localize(robot, sim, 3)
    truth = sim.robot.pose
    assert p >= 0.9 - 1e-9  # certain, but for the chance the last move failed
    assert errors(Pose(x, y, heading), truth) == pytest.approx((0.0, 0.0), abs=1e-6)


@pytest.mark.slow
def test_a_sweep_reports_time_to_localize_per_start_cell(tmp_path: Path) -> None:
    sweep = tmp_path / "sweep.toml"
    config = EXAMPLES / "project.toml"
    sweep.write_text(
        f'config = "{config}"\n'
        f'program = "{sys.executable} -u {EXAMPLE} {config} --sensors u0 --moves 8"\n'
        'seeds = 1\nseconds = 60\nwall_seconds = 60\nsuccess = "localized_at < 60"\n'
        'keep = "nothing"\n[grid]\n"scenario.start" = ["3,0,0", "3,5,90", "0,2,180"]\n',
        encoding="utf-8",
    )
    out = tmp_path / "out"
    result = CliRunner().invoke(app, ["sweep", str(sweep), "-o", str(out), "--workers", "1"])
    assert result.exit_code in (0, 1), result.output
    with (out / "results.csv").open(newline="") as file:
        rows = list(csv.DictReader(file))
    assert [row["estimates"] for row in rows] == ["9", "9", "9"]
    assert all(float(row["localized_at"]) < 60 for row in rows)
    summary = (out / "summary.md").read_text()
    assert "time to localize median" in summary
    assert "localized_start_cells.png" in summary
    assert (out / "localized_start_cells.png").stat().st_size > 5_000


def test_a_belief_the_simulator_refuses_raises_with_its_reason() -> None:
    with serving() as (_runner, link), connect(port=link.stream.port) as robot:
        with pytest.raises(ValueError, match="at most 4096 probabilities"):
            robot.show(cells=[[0.5] * 65] * 65)
        assert robot.show(cells=[[0.5] * 64] * 64) == 0  # the connection goes on
