"""The course project end to end: an unchanged student-style program told its target at its
prompt, a recorded run replayed bit for bit, a video frame with the carried block and the zones,
and sweeps over scenarios."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import av
import numpy as np
import pytest
from PIL import Image

from link_support import run_program
from simmer import Simulation
from simmer.colors import DROPOFF_COLOR, LOADING_COLOR, TARGET_COLOR
from simmer.errors import SweepError
from simmer.record.plots import plot_run, read_run, write_path_plot
from simmer.record.runfolder import load_run, retrace
from simmer.sweep.spec import load_sweep, sweep_from_dict
from simmer.sweep.success import success_condition
from simmer.ui.scene import ScenePainter, View, default_window_size
from simmer.world.events import CommandEvent, Event
from simmer.world.replay import replay, same_replies

from helpers import EXAMPLES, REPO

pytestmark = pytest.mark.timeout(300)

PROGRAM = f"{sys.executable} {EXAMPLES / 'project_delivery.py'}"
STUDENT = REPO / "tests" / "fixtures" / "project" / "student.py"


def cli(*args: str, cwd: Path = REPO) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "simmer", "run", str(EXAMPLES / "project.toml"), "--headless",
         "--port", "0", "--port-rx", "0", "--port-tx", "0", *args],
        capture_output=True, text=True, timeout=240, check=False, cwd=cwd, stdin=subprocess.DEVNULL,
    )  # fmt: skip


@pytest.mark.slow
def test_an_unchanged_student_program_is_told_its_target_and_delivers() -> None:
    # plain two-port sockets, the target read at input(), the gripper's command as any other
    result = cli("--seed", "3", "--block", "6,14", "--target", "B3",
                 "--program", f"{sys.executable} {STUDENT}", "--answer", "B3")  # fmt: skip
    out = result.stdout
    assert result.returncode == 0, out + result.stderr
    assert "Enter a valid drop-off zone (B1, B2, B3, or B4): " in out
    assert "gripper says 1.0" in out  # the packed reply, as the program unpacked it
    assert "scenario: start [6, 42] heading 180; block [6.00, 14.00]; target B3" in out
    assert "delivered it at" in out
    assert "score 100" in out
    assert "collisions 0" in out


@pytest.mark.slow
def test_answer_types_the_runs_own_drawn_target() -> None:
    result = cli("--seed", "11", "--program", PROGRAM, "--answer", "{target}")
    out = result.stdout
    assert result.returncode == 0, out + result.stderr
    target = out.split("; target ")[1].split()[0]
    assert f"delivered to {target}" in out
    assert f"project (target {target})" in out
    assert "delivered it at" in out


@pytest.mark.slow
@pytest.mark.parametrize(
    ("flag", "value", "words"),
    [
        ("--start", "0,4", "--start: cell [0, 4] is solid (0 in walls); choose an open cell"),
        ("--start", "9,9,90", "--start: cell [9, 9] is outside the maze"),
        ("--block", "0.5,0.5", "--block: the block at [0.5, 0.5] overlaps a wall"),
        ("--target", "B7", "--target: no drop-off zone 'B7'; the zones are B1, B2, B3, B4"),
    ],
)
def test_bad_overrides_are_one_plain_line(flag: str, value: str, words: str) -> None:
    result = cli("--seconds", "1", flag, value)
    assert result.returncode == 1
    assert words in result.stderr
    assert "Traceback" not in result.stderr + result.stdout


@pytest.mark.slow
def test_a_recorded_project_run_replays_bit_for_bit(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    sim = Simulation.from_config(EXAMPLES / "project.toml", seed=21)
    served = run_program(sim, PROGRAM, record=folder, answer=sim.scenario.target)
    assert served.ended_by == "program"
    assert served.exit_status == 0
    report = json.loads((folder / "report.json").read_text())
    assert report["outcome"]["delivered"] is True
    manifest = json.loads((folder / "manifest.json").read_text())
    assert manifest["scenario"]["target"] == report["outcome"]["target"]
    config, seed, events = load_run(folder)
    replayed = replay(config, seed, events)
    assert not replayed.differences
    recorded = [e for e in events if isinstance(e, CommandEvent)]
    assert any("g0-1" in e.message for e in recorded)
    again: list[CommandEvent] = []

    def collect(event: Event) -> None:
        if isinstance(event, CommandEvent):
            again.append(event)

    replay(config, seed, events, [collect])
    assert len(again) == len(recorded)
    assert all(same_replies(a.replies, b.replies) for a, b in zip(again, recorded, strict=True))
    assert (replayed.sim.block.x, replayed.sim.block.y) == (sim.block.x, sim.block.y)
    assert replayed.sim.robot.pose == sim.robot.pose
    retrace(folder, tmp_path / "again.csv")
    assert (tmp_path / "again.csv").read_text() == (folder / "trace.csv").read_text()
    plot_run(folder)  # path.png with the zones, the drawn start and block
    assert (folder / "path.png").is_file()
    # the block drawn where it was delivered (solid) and where it lay (faint), with marks
    run = read_run(folder)
    assert run.handled is not None
    assert run.handled.delivered
    assert run.handled.put_down == pytest.approx(report["outcome"]["delivered_at"])
    pixels = write_path_plot(run, tmp_path / "path.png")
    image = np.asarray(Image.open(tmp_path / "path.png").convert("RGB")).astype(int)
    colour = np.array(run.settings.block_color[:3])

    def solid(x: float, y: float) -> bool:
        column, row = pixels.pixel(x, y)
        patch = image[int(row) - 3 : int(row) + 4, int(column) - 3 : int(column) + 4]
        return bool((np.abs(patch - colour).sum(axis=2) < 40).sum() > 30)

    delivered = (sim.block.x, sim.block.y)  # where the simulation left it
    assert delivered != tuple(manifest["scenario"]["block"])
    assert solid(*delivered), "the block is not drawn where it was delivered"
    assert not solid(*manifest["scenario"]["block"]), "the block is drawn solid where it lay"
    for mark in ("#1a9850", "#6a3d9a"):  # the pickup and delivery marks
        rgb = np.array([int(mark[i : i + 2], 16) for i in (1, 3, 5)])
        assert (np.abs(image - rgb).sum(axis=2) < 30).sum() > 40, mark
    report_md = (folder / "report.md").read_text()
    assert "## Project" in report_md
    assert "| Delivered it |" in report_md
    assert "**Score: 100**" in report_md


@pytest.mark.slow
def test_a_video_frame_shows_the_zones_and_the_carried_block(tmp_path: Path) -> None:
    path = tmp_path / "project.mp4"
    result = cli("--seed", "5", "--target", "B3", "--program", PROGRAM, "--answer", "{target}",
                 "--video", str(path))  # fmt: skip
    assert result.returncode == 0, result.stdout + result.stderr
    sim = Simulation.from_config(EXAMPLES / "project.toml", seed=5)
    view = View.fit(sim, default_window_size(sim))
    block = ScenePainter(sim).settings.block_color

    def near(frame: np.ndarray, point: tuple[float, float], color: tuple[int, int, int]) -> bool:
        x, y = view.point(*point)
        patch = frame[int(y) - 2 : int(y) + 3, int(x) - 2 : int(x) + 3].astype(int)
        return bool((np.abs(patch - np.array(color)).sum(axis=2) < 60).any())

    carried = None  # a frame while the block is carried along the bottom row, beside the robot
    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        half = stream.frames // 2
        for index, frame in enumerate(container.decode(stream)):
            if index == 0:
                first = frame.to_ndarray(format="rgb24")
                assert near(first, (0.7, 12.0), LOADING_COLOR)  # the loading zone's left side
                assert near(first, (60.7, 6.0), DROPOFF_COLOR)  # B1's
                assert near(first, (24.7, 30.0), TARGET_COLOR)  # B3, the target
            elif index >= half and near(
                image := frame.to_ndarray(format="rgb24"), (20.0, 42.0), block
            ):
                carried = image
                break
    assert half > 0
    assert carried is not None, "no frame shows the block carried along the bottom row"
    Image.fromarray(carried).save(tmp_path / "frame.png")


# ----------------------------------------------------------------------------- sweeps


@pytest.mark.slow
def test_scenario_all_expands_to_every_start_and_zone(tmp_path: Path) -> None:
    data = {
        "config": str(EXAMPLES / "project.toml"),
        "program": "python3 x.py",
        "answer": "{target}",
        "success": "delivered and collisions == 0",
        "grid": {"scenario": {"start": "all", "target": "all"}},
    }
    spec = sweep_from_dict(data, tmp_path)
    grid = dict(spec.grid)
    assert len(grid["scenario.start"]) == 16 * 4
    assert "3,0,180" in grid["scenario.start"]
    assert grid["scenario.target"] == ("B1", "B2", "B3", "B4")
    assert spec.project
    assert spec.answer == "{target}"
    assert len(spec.runs()) == 16 * 4 * 4
    spec.check_settings()
    policy = {key: value for key, value in data.items() if key != "program"}
    with pytest.raises(SweepError, match="a policy has none"):
        sweep_from_dict({**policy, "policy": "m:f"}, tmp_path)


def test_success_conditions_may_name_milestones() -> None:
    condition = success_condition("delivered and collisions == 0 and score >= 90")
    assert condition({"delivered": True, "collisions": 0, "score": 100.0})
    assert not condition({"delivered": False, "collisions": 0, "score": 40.0})
    assert not condition({"collisions": 0})  # a Lab 1 run has no milestones
    with pytest.raises(SweepError, match="'deliverd' is not one of"):
        success_condition("deliverd")


@pytest.mark.slow
def test_a_sweep_over_targets_and_starts(tmp_path: Path) -> None:
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(
        f'config = "{EXAMPLES / "project.toml"}"\n'
        f'program = "{sys.executable} {EXAMPLES / "project_delivery.py"}"\n'
        'answer = "{target}"\nseeds = 1\nseconds = 200\nwall_seconds = 60\n'
        'success = "delivered and collisions == 0"\nkeep = "nothing"\n'
        '[grid]\n"scenario.target" = ["B2", "B4"]\n"scenario.start" = ["3,0,180", "3,3,90"]\n'
    )
    load_sweep(sweep)
    out = tmp_path / "out"
    result = subprocess.run(
        [sys.executable, "-m", "simmer", "sweep", str(sweep), "-o", str(out), "--workers", "2"],
        capture_output=True, text=True, timeout=280, check=False,
    )  # fmt: skip
    assert result.returncode in (0, 1), result.stdout + result.stderr
    rows = list(csv.DictReader((out / "results.csv").read_text().splitlines()))
    assert len(rows) == 4
    by = {(r["scenario.start"], r["scenario.target"]): r for r in rows}
    for target in ("B2", "B4"):
        good = by[("3,0,180", target)]
        assert good["success"] == "True"
        assert good["delivered"] == "True"
        assert good["target"] == target
        assert good["picked_up"] == "True"
        assert by[("3,3,90", target)]["success"] == "False"  # it assumes the lab's start
    assert (out / "start_cells.png").is_file()
    assert "start_cells.png" in (out / "summary.md").read_text()
