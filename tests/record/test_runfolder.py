"""A run folder (issue 11, item 1): manifest, events, trace and report of a run, recorded from
Python and by ``simmer run --record``; a recorded noisy run replays from its folder to the same
trace, and a run killed with SIGKILL leaves an events.jsonl whose every line parses;
report.md defines its terms and takes only well-formed project lines."""

from __future__ import annotations

import csv
import dataclasses
import itertools
import json
import math
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

import simmer
from simmer import Simulation
from simmer.cli import app
from simmer.config import load_config
from simmer.geometry import Pose
from simmer.record import (
    EventLog,
    RunRecorder,
    load_run,
    read_events,
    read_manifest,
    retrace,
    write_report_md,
)
from simmer.record.eventlog import TYPE_NAMES, event_from_dict, event_line
from simmer.record.plots import read_run, sensor_panels
from simmer.record.runfolder import project_lines
from simmer.record.trace import POSE_COLUMNS
from simmer.world.events import (
    BeliefEvent,
    BlockedMoveEvent,
    CollisionEndEvent,
    CollisionEvent,
    CommandEvent,
    EstimateEvent,
    Event,
    KeysEvent,
    PlaceEvent,
    ReachedEvent,
    ResetEvent,
    RunEvent,
    StepEvent,
)
from simmer.world.replay import replay

from helpers import EXAMPLES, LAB_SEQUENCE, SIMMER_PY, drive_noisily, noisy_config, wait_for

pytestmark = pytest.mark.timeout(180)

FILES = ("manifest.json", "events.jsonl", "trace.csv", "report.json", "report.md")
SENSORS = ["u0", "u1", "u2", "u3"]


def record_noisy_run(folder: Path, reset: bool = True) -> Simulation:
    sim = Simulation(noisy_config(), seed=23)
    with RunRecorder(sim, folder):
        drive_noisily(sim, reset)
    return sim


def trace_rows(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as file:
        return list(csv.DictReader(file))


# ----------------------------------------------------------------------------- replay


@pytest.mark.slow
def test_a_recorded_noisy_run_replays_from_its_folder_to_the_same_trace(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    original = record_noisy_run(folder)
    recorded = read_events(folder / "events.jsonl")
    kinds = {type(event) for event in recorded}
    assert {CommandEvent, KeysEvent, PlaceEvent, ResetEvent, CollisionEvent} <= kinds
    assert isinstance(recorded[-1], StepEvent)  # the run's last step says where it stopped
    assert recorded[-1].step == original.steps

    config, seed, events = load_run(folder)
    assert (config.settings, config.devices) == (original.config.settings, original.config.devices)
    result = retrace(folder, tmp_path / "replayed.csv")
    assert result.differences == []
    assert result.sim.robot.pose == original.robot.pose
    replayed = trace_rows(tmp_path / "replayed.csv")
    assert replayed == trace_rows(folder / "trace.csv")
    assert len(replayed) > 100

    log = tmp_path / "replayed.jsonl"
    again = EventLog(log)
    replay(config, seed, events, [again])
    again.close()
    assert log.read_bytes() == (folder / "events.jsonl").read_bytes()


@pytest.mark.slow
def test_a_different_seed_replays_to_a_different_trace(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    record_noisy_run(folder, reset=False)
    config, seed, events = load_run(folder)
    assert replay(config, seed + 1, events).differences
    manifest = json.loads((folder / "manifest.json").read_text())
    manifest["seed"] = seed + 1
    (folder / "manifest.json").write_text(json.dumps(manifest))
    retrace(folder, tmp_path / "other.csv")
    assert trace_rows(tmp_path / "other.csv") != trace_rows(folder / "trace.csv")


@pytest.mark.parametrize(
    "path",
    [EXAMPLES / "bumper_rover.toml", SIMMER_PY / "lab_rover_noisy.py", None],
    ids=["plug-in", "config.py", "built-in"],
)
def test_the_manifest_rebuilds_the_configuration(tmp_path: Path, path: Path | None) -> None:
    sim = Simulation(load_config(path), seed=5)
    with RunRecorder(sim, tmp_path / "run"):
        sim.step(3)
    config, seed, _ = load_run(tmp_path / "run", trust=True)  # our own run: trusted
    assert seed == 5
    assert config.settings == sim.config.settings
    assert config.devices == sim.config.devices
    assert config.origin == sim.config.origin
    manifest = read_manifest(tmp_path / "run")
    assert manifest["config"]["path"] == (None if path is None else str(path.resolve()))
    assert manifest["simmer_version"] == simmer.__version__
    assert manifest["platform"]["python"] == ".".join(map(str, sys.version_info[:3]))
    groups = {device["id"]: device["group"] for device in manifest["config"]["devices"]}
    assert groups == {spec.id: spec.group for spec in sim.config.devices}


# ----------------------------------------------------------------------------- events.jsonl


def test_every_event_type_round_trips_with_nan_and_infinities() -> None:
    nan, inf = math.nan, math.inf
    pose = Pose(1.5, -0.0, 359.99999999999994)
    events: list[Event] = [
        CommandEvent(0.1, 'u0,w0-6,"x"\u00e9', (12.345678901234567, inf, nan, -inf), 6, "c"),
        StepEvent(0.1, pose, 6),
        CollisionEvent(0.2, pose, 12),
        CollisionEndEvent(0.3, pose, 18),
        BlockedMoveEvent(0.35, "w0-36", 0.1, 15, 4.25, 36.0, "in", 21),
        ResetEvent(0.4, 24),
        KeysEvent(0.5, frozenset("wd"), 30),
        PlaceEvent(0.6, pose, 36),
        ReachedEvent(0.7, 0.65, 42),
        RunEvent(0.8, "speed", nan, 48, "max"),
        BeliefEvent(0.9, '{"pose":[1.5,2,90]}', 3, 1, 54, "c"),
        EstimateEvent(1.0, pose, Pose(1.0, 2.0, 3.0), 60, "c"),
    ]
    assert {type(event) for event in events} == set(TYPE_NAMES)
    for event in events:
        line = event_line(event)
        assert line.endswith("}\n")
        assert line.count("\n") == 1
        data = json.loads(line)  # standard JSON: no bare NaN or Infinity
        assert data["type"] == TYPE_NAMES[type(event)]
        back = event_from_dict(data)
        assert type(back) is type(event)
        assert event_line(back) == line  # the same values, NaN and -0.0 included
    command = json.loads(event_line(events[0]))
    # a command's line is spelt out for speed: it must have every field, in the class's order
    assert list(command) == ["type", *(f.name for f in dataclasses.fields(CommandEvent))]
    assert command["replies"] == [12.345678901234567, "inf", "nan", "-inf"]
    assert json.loads(event_line(events[1]))["pose"] == [1.5, -0.0, 359.99999999999994]
    assert math.copysign(1, event_from_dict(json.loads(event_line(events[1]))).pose.y) < 0


def test_a_cut_off_last_line_is_left_out_and_a_bad_line_named(tmp_path: Path) -> None:
    good = event_line(CommandEvent(0.0, "u0", (3.5,), 0)) + event_line(ResetEvent(0.5, 30))
    path = tmp_path / "events.jsonl"
    path.write_text(good + '{"type":"command","time":1.0,"mess')
    assert [type(e) for e in read_events(path)] == [CommandEvent, ResetEvent]
    path.write_text(good + '{"type":"teleport","time":1.0}\n' + good)
    with pytest.raises(ValueError, match="line 3: unknown event type 'teleport'"):
        read_events(path)


# ----------------------------------------------------------------------------- trace.csv


def test_the_trace_has_pose_collisions_and_each_sensors_last_reading(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    sim = record_noisy_run(folder, reset=False)
    rows = trace_rows(folder / "trace.csv")
    assert list(rows[0]) == [*POSE_COLUMNS, *SENSORS]
    first = rows[0]
    assert (float(first["time"]), first["step"], first["collisions"]) == (0.0, "0", "0")
    assert [float(first[c]) for c in ("x", "y", "heading")] == [6.0, 42.0, 180.0]
    assert all(first[sensor] == "" for sensor in SENSORS)  # blank until the first reading
    times = [float(row["time"]) for row in rows]
    assert all(a < b for a, b in itertools.pairwise(times))
    steps = [int(row["step"]) for row in rows]
    assert steps[:4] == [0, 2, 4, 6]  # 30 rows a simulated second at 60 steps a second
    assert steps[-1] == sim.steps
    assert int(rows[-1]["collisions"]) == sim.collisions >= 1
    last = rows[-1]
    assert [float(last[c]) for c in ("x", "y", "heading")] == pytest.approx(list(sim.robot.pose))
    # u0 was last read by "u0,w0-0,u9"; u1 by "w0-30,u1" after the drag: the trace has both
    replies = [e for e in read_events(folder / "events.jsonl") if isinstance(e, CommandEvent)]
    u0 = next(e.replies[0] for e in reversed(replies) if e.message.startswith("u0"))
    u1 = next(e.replies[1] for e in reversed(replies) if e.message == "w0-30,u1")
    assert float(last["u0"]) == pytest.approx(u0, rel=1e-9)
    assert float(last["u1"]) == pytest.approx(u1, rel=1e-9)


def test_after_a_reset_the_trace_starts_again(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    record_noisy_run(folder)
    rows = trace_rows(folder / "trace.csv")
    times = [float(row["time"]) for row in rows]
    back = [i for i in range(1, len(rows)) if times[i] < times[i - 1]]
    assert len(back) == 1  # one reset: time goes back once
    after = rows[back[0]]
    assert after["collisions"] == "0"
    assert after["u1"] == ""  # no reading of u1 since the reset
    report = json.loads((folder / "report.json").read_text())
    assert report["resets"] == 1


# ----------------------------------------------------------------------------- report


def test_the_report_has_the_outcome_and_the_runs_facts(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    sim = Simulation.from_config(seed=4)
    with RunRecorder(sim, folder):
        for message in LAB_SEQUENCE:
            sim.command("u0")
            sim.command(message)
            sim.run_until_idle()
    report = json.loads((folder / "report.json").read_text())
    outcome = report["outcome"]
    assert outcome["reached"] is True
    assert outcome["reached_at"] >= outcome["task2_time"] > 20
    assert outcome["collisions"] == 0
    assert outcome["messages"] == 2 * len(LAB_SEQUENCE)
    assert outcome["nan_replies"] == 0
    assert outcome["path_length"] == pytest.approx(114.0)
    assert outcome["final_pose"] == list(sim.robot.pose)
    assert (report["seed"], report["steps"], report["ended_by"]) == (4, sim.steps, "closed")
    assert report["duration"] == sim.time
    text = (folder / "report.md").read_text()
    assert "| Reached the block | yes, at " in text
    assert f"{outcome['task2_time']:.2f} s" in text
    assert "simmer plot" in text
    assert "](path.png)" not in text
    (folder / "path.png").write_bytes(b"")  # what `simmer plot` draws: now the report shows it
    write_report_md(folder)
    assert "![The robot's true path](path.png)" in (folder / "report.md").read_text()


def test_a_folder_with_a_run_and_a_simulation_already_stepped_are_refused(tmp_path: Path) -> None:
    sim = Simulation.from_config()
    RunRecorder(sim, tmp_path / "run").close()
    with pytest.raises(FileExistsError, match="already holds a recorded run"):
        RunRecorder(Simulation.from_config(), tmp_path / "run")
    sim.step()
    with pytest.raises(ValueError, match="at step 1"):
        RunRecorder(sim, tmp_path / "other")
    assert not (tmp_path / "other" / "manifest.json").exists()


def interrupted(sim: Simulation, folder: Path) -> None:
    """Record a little driving, then Ctrl-C."""
    with RunRecorder(sim, folder):
        sim.command("w0-12")
        sim.step(30)
        raise KeyboardInterrupt


def test_ctrl_c_closes_the_files_and_writes_the_report(tmp_path: Path) -> None:
    sim = Simulation.from_config()
    with pytest.raises(KeyboardInterrupt):
        interrupted(sim, tmp_path / "run")
    report = json.loads((tmp_path / "run" / "report.json").read_text())
    assert report["ended_by"] == "quit"
    assert report["outcome"]["path_length"] == pytest.approx(3.0)
    sim.step()  # the recorder, and the outcome it attached, no longer observe
    assert sim.observers == []
    assert read_events(tmp_path / "run" / "events.jsonl")[-1].step == 30


# ----------------------------------------------------------------------------- simmer run


def test_simmer_run_record_creates_every_file(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    ports = ["--port", "0", "--port-rx", "0", "--port-tx", "0"]
    command = ["run", "--headless", "--seconds", "1", "--speed", "max", "--record", str(folder)]
    result = CliRunner().invoke(app, [*command, *ports])
    assert result.exit_code == 0, result.output
    assert f"recorded in {folder}" in result.output
    assert sorted(p.name for p in folder.iterdir()) == sorted(FILES)
    manifest = read_manifest(folder)
    assert (manifest["clock"], manifest["speed"], manifest["window"]) == ("realtime", None, False)
    assert manifest["config"]["source"] == "<built-in default>"
    report = json.loads((folder / "report.json").read_text())
    assert (report["ended_by"], report["steps"]) == ("seconds", 60)
    rows = trace_rows(folder / "trace.csv")
    assert (len(rows), rows[-1]["step"]) == (31, "60")
    again = CliRunner().invoke(app, [*command, *ports])
    assert again.exit_code == 1
    assert "already holds a recorded run" in again.output


FOREVER = """\
from simmer.client import connect

with connect() as robot:
    while True:
        robot.send("u0,u1,u2,u3")
        robot.send("w0-1")
        robot.send("r0-5")
"""


@pytest.mark.slow
def test_a_run_killed_with_sigkill_leaves_events_whose_every_line_parses(tmp_path: Path) -> None:
    program = tmp_path / "forever.py"
    program.write_text(FOREVER)
    folder = tmp_path / "run"
    command = [sys.executable, "-m", "simmer", "run", "--headless", "--record", str(folder),
               "--program", f"{sys.executable} {program}"]  # fmt: skip
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy"}
    process = subprocess.Popen(
        command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env
    )
    events = folder / "events.jsonl"
    try:
        wait_for(
            lambda: events.exists() and events.read_bytes().count(b"\n") >= 2000,
            "the recorded run to write 2000 events",
            60,
        )
        os.kill(process.pid, signal.SIGKILL)
    finally:
        process.kill()
        process.wait(10)
    assert process.returncode == -signal.SIGKILL
    data = events.read_bytes()
    assert data.endswith(b"\n")
    lines = data.decode().splitlines()
    assert len(lines) >= 2000
    parsed = [json.loads(line) for line in lines]  # every line, the last one too
    assert parsed[0]["type"] == "run"  # the program started
    assert "command" in {p["type"] for p in parsed[1:]}
    assert len(read_events(events)) == len(lines)
    assert not (folder / "report.json").exists()  # killed: no report, the events are whole
    config, seed, recorded = load_run(folder)
    assert replay(config, seed, recorded).differences == []


def test_report_md_defines_reached_and_the_stopwatch(tmp_path: Path) -> None:
    from simmer.record import RunRecorder

    sim = Simulation.from_config(seed=1)
    with RunRecorder(sim, tmp_path / "run"):
        sim.command("w0-6")
        sim.command("w0-0")  # busy
        sim.run_until_idle()
    report = (tmp_path / "run" / "report.md").read_text(encoding="utf-8")
    assert "within 1 in of the block's" in report
    assert "first motion" in report
    assert "| Busy replies (a drive still moving), NaN replies | 1, 0 |" in report
    outcome = json.loads((tmp_path / "run" / "report.json").read_text(encoding="utf-8"))
    assert outcome["outcome"]["busy_replies"] == 1


def test_report_md_project_lines_take_only_what_is_well_formed() -> None:
    outcome = {"entered_loading_at": 4.5, "picked_up_at": "soon", "score": 30.0}
    good = project_lines(outcome, {"start": [6, 42, 180], "block": [7.25, 8.5], "target": "B2"})
    assert "Started at [6, 42] heading 180 deg; the block at [7.25, 8.50]; target zone B2." in good
    assert "| Entered the loading zone | 4.50 s |" in good
    assert "| Picked up the block | no |" in good  # not a number: said as not met
    assert "**Score: 30** (the rubric is in the manifest)." in good
    hostile = project_lines({"score": "x", "wrong_zone": 5}, {"start": "here", "block": None})
    assert not any("Started" in line or "Score" in line or "another" in line for line in hostile)


def test_an_imus_axes_are_columns_of_their_own_and_plotted_by_unit(tmp_path: Path) -> None:
    config = load_config(EXAMPLES / "motion_rover.toml")
    sim = Simulation(config, seed=4)
    folder = tmp_path / "run"
    with RunRecorder(sim, folder):
        sim.command("w0-6")
        sim.step(20)
        replies = sim.command("i0-2,e0-1,i0,i0-1,i0-7,e1")
        sim.step(4)
    rows = trace_rows(folder / "trace.csv")
    assert list(rows[0])[len(POSE_COLUMNS) :] == ["i0", "i0-1", "i0-2", "e0", "e1"]
    last = rows[-1]
    got = [float(last[c]) for c in ("i0-2", "e0", "i0", "i0-1", "e1")]
    assert got == pytest.approx([replies[0], replies[1], replies[2], replies[3], replies[5]])
    assert math.isnan(replies[4])  # i0-7: no such axis, and no column
    assert sensor_panels(read_run(folder)) == [
        ("imu: yaw rate (°/s)", ["i0"]),
        ("imu: acceleration (in/s²)", ["i0-1", "i0-2"]),
        ("encoder: wheel counts", ["e0", "e1"]),
    ]
