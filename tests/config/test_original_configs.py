"""Configurations the original SimMeR runs also run here (BEHAVIOUR §6.3, issue 8 item 4).

Each quirk is the lab rover's config.py (``lab_rover_quiet.py``) with one edit. Loaded from a
config.py it gives warnings, with line and key like errors, and runs; written in the native
TOML form, the same setting is still an error.
"""

from __future__ import annotations

import math
import os
import struct
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

import pytest
from typer.testing import CliRunner

from link_support import serving, two_port_raw
from simmer import Simulation
from simmer.cli import app
from simmer.config import load_config
from simmer.config.loader import ORIGINAL_RUNS
from simmer.devices import Ultrasonic
from simmer.errors import ConfigError
from simmer.ui import render_scene
from simmer.view.snapshot import Snapshot

from helpers import SIMMER_PY, default_data, make_config

QUIET = SIMMER_PY / "lab_rover_quiet.py"
SENSORS_END = "    'u3': Ultrasonic(u3_info)\n}"
U0_POSITION = "    'position': [0, 2.5],\n"
M1_ROTATION = "    'position': [-3.125, 0],\n    'rotation': 0,\n"


@dataclass(frozen=True)
class Quirk:
    """One edit of the lab rover's config.py and the warnings it must give."""

    name: str
    old: str
    new: str
    warnings: tuple[tuple[str, str, str], ...]
    """(key, message fragment, text on the warning's line)."""


QUIRKS = [
    Quirk("block outside the maze", "block_position = [66, 5]", "block_position = [120, 5]",
          (("block_position", "is outside the maze, so the robot can neither reach nor see it",
            "block_position = [120, 5]"),)),
    Quirk("block in a solid cell", "block_position = [66, 5]", "block_position = [54, 6]",
          (("block_position", "is inside a solid cell, so the robot can neither reach nor see",
            "block_position = [54, 6]"),)),
    Quirk("block across a wall", "block_position = [66, 5]", "block_position = [12, 30]",
          (("block_position", "overlaps a wall, a solid cell or the maze edge, so the robot "
            "cannot reach it as usual", "block_position = [12, 30]"),)),
    Quirk("block under the robot", "block_position = [66, 5]", "block_position = [6, 42]",
          (("block_position", "overlaps the robot's start position", "block_position = [6, 42]"),
           )),
    Quirk("beamwidth 0", U0_POSITION, U0_POSITION + "    'beamwidth': 0,\n    'error': 0,\n",
          (("sensors.u0.beamwidth", "reads like a single ray", "'beamwidth': 0"),)),
    Quirk("omni-wheel directions", "'motor_direction': [1, 1]",
          "'motor_direction': [0.866, -0.866]",
          (("drives.w0.motor_direction[0]", "not 0.866; another value multiplies the motor's "
            "odometer", "'motor_direction': [0.866"),
           ("drives.w0.motor_direction[1]", "not -0.866", "'motor_direction': [0.866"))),
    Quirk("arc drive", "    'ang_velocity': 0,\n", "    'ang_velocity': 120,\n",
          (("drives.w0.ang_velocity", "turns it 1 degree (an arc)", "'ang_velocity': 120,"),)),
    Quirk("motor also among the sensors", SENSORS_END,
          "    'u3': Ultrasonic(u3_info),\n    'm0': motors['m0']\n}",
          (("sensors.m0", "'motor' 'm0' is listed among the motors and again among the sensors",
            "'m0': motors['m0']"),)),
    Quirk("motor only among the sensors", SENSORS_END,
          "    'u3': Ultrasonic(u3_info),\n"
          "    'm2': MotorSimple({'id': 'm2', 'position': [0, -3], 'rotation': 0})\n}",
          (("sensors.m2", "is a 'motor', which belongs among the motors, not the sensors; "
            "SimMeR 2 moves it there (it still answers commands as 'm2')", "'m2': MotorSimple"),
           )),
]  # fmt: skip


def write_quirk(tmp_path: Path, *edits: tuple[str, str]) -> Path:
    """The lab rover's config.py with each (old, new) edit made once, as tmp_path/config.py."""
    text = QUIET.read_text(encoding="utf-8")
    for old, new in edits:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    path = tmp_path / "config.py"
    path.write_text(text, encoding="utf-8")
    return path


def line_of(path: Path, text: str) -> int:
    """1-based number of the first line of ``path`` containing ``text``."""
    lines = path.read_text(encoding="utf-8").splitlines()
    return next(n for n, line in enumerate(lines, 1) if text in line)


def load_quirk(tmp_path: Path, name: str) -> Simulation:
    quirk = next(q for q in QUIRKS if q.name == name)
    return Simulation(load_config(write_quirk(tmp_path, (quirk.old, quirk.new))), seed=3)


# ----------------------------------------------------------------------------- each quirk


@pytest.mark.parametrize("quirk", QUIRKS, ids=lambda q: q.name)
def test_quirk_loads_with_warnings_and_runs(quirk: Quirk, tmp_path: Path) -> None:
    path = write_quirk(tmp_path, (quirk.old, quirk.new))
    config = load_config(path)
    found = [(w.key, w.line) for w in config.warnings]
    assert found == [(key, line_of(path, text)) for key, _, text in quirk.warnings]
    for warning, (_, fragment, _) in zip(config.warnings, quirk.warnings, strict=True):
        assert fragment in warning.message
        assert warning.message.endswith(ORIGINAL_RUNS)
        assert warning.render(str(path)).startswith(f"{path}:{warning.line}: {warning.key}: ")
    sim = Simulation(config, seed=3)
    assert sim.command("w0-3") == [math.inf]
    assert sim.run_until_idle(max_seconds=10)
    readings = sim.command("u0,u1,u2,u3,m0,m1")
    assert all(math.isfinite(r) for r in readings)
    sim.command("r0-45")
    sim.step(10)
    snapshot = Snapshot.of(sim)
    assert len(snapshot.shapes) == 4 * 7  # the rays of the four reads are drawn
    render_scene(sim)


def test_native_config_gives_no_warnings() -> None:
    assert load_config(QUIET).warnings == ()
    assert make_config(default_data()).warnings == ()


# ----------------------------------------------------------------------------- what runs


def test_hidden_block_outside_the_maze_is_never_seen_or_touched(tmp_path: Path) -> None:
    path = write_quirk(
        tmp_path,
        ("block_position = [66, 5]", "block_position = [120, 5]"),
        (U0_POSITION, U0_POSITION + "    'error': 0,\n"),
    )
    sim = Simulation(load_config(path))
    u0 = sim.robot.devices["u0"]
    assert sim.place_robot(90, 6, 270)  # top-right cell, u0 facing the block beyond the edge
    assert isinstance(u0, Ultrasonic)
    assert u0.sees_block(sim, *u0.world_pose(sim.robot.pose)[:2])  # low enough to see it
    assert sim.command("u0") == [pytest.approx(96 - 92.5)]  # the maze's edge, not the block
    assert sim.command("w0-100") == [math.inf]
    assert sim.run_until_idle()
    assert sim.robot.pose.x < 96  # stopped by the maze's edge
    assert sim.collisions == 1


def test_block_under_the_robot_blocks_every_move(tmp_path: Path) -> None:
    sim = load_quirk(tmp_path, "block under the robot")
    start = sim.robot.pose
    sim.command("w0-6")
    assert sim.run_until_idle()
    assert sim.robot.pose == start  # each step would still touch the block, so it is undone
    assert sim.robot.motors["m0"].odometer == pytest.approx(6.0)  # the wheels slip


def test_arc_drive_matches_a_hand_computation(tmp_path: Path) -> None:
    sim = load_quirk(tmp_path, "arc drive")
    # velocity [0, 6] and ang_velocity 120 at 60 Hz: (6 + 120) / 60 = 2.1 units per step; each
    # unit moves 1 in along the robot's +y and turns it 1 degree clockwise. w0-10 takes 5 steps
    # (2.1 x 4 + 1.6), each moving along the heading at the start of the step.
    x, y, heading = 6.0, 42.0, 180.0
    for step in (2.1, 2.1, 2.1, 2.1, 1.6):
        x += -math.sin(math.radians(heading)) * step
        y += math.cos(math.radians(heading)) * step
        heading += step
    assert (x, y, heading) == pytest.approx((6.6949, 32.0369, 190.0), abs=1e-4)
    assert sim.command("w0-10") == [math.inf]
    assert sim.run_until_idle()
    assert sim.steps == 5
    assert tuple(sim.robot.pose) == pytest.approx((x, y, heading), abs=1e-9)
    # near the true arc of radius 180/pi in (1 in per degree), 10 degrees round; each step
    # moves along its starting heading, so the path lies up to half a step's turn inside it
    radius = 180 / math.pi
    chord_x = radius * (1 - math.cos(math.radians(10)))
    chord_y = radius * math.sin(math.radians(10))
    assert (x - 6, 42 - y) == pytest.approx((chord_x, chord_y), abs=0.25)
    # odometers: the translation gain (m0 points along the velocity: 1 in per unit)
    assert sim.command("m0,m1") == [pytest.approx(10.0), pytest.approx(10.0)]


def test_arc_drive_error_and_bias_apply_per_unit(tmp_path: Path) -> None:
    path = write_quirk(
        tmp_path,
        ("    'ang_velocity': 0,\n", "    'ang_velocity': 120,\n"),
        (
            "    'motor_direction': [1, 1]\n"
            "    # 'bias': {'x': 0, 'y': 0, 'rotation': 0.2},\n"
            "    # 'error': {'x': 0.02, 'y': 0.05, 'rotation': 1}\n",
            "    'motor_direction': [1, 1],\n"
            "    'bias': {'x': 0.1, 'y': 0, 'rotation': 0.5},\n"
            "    'error': {'x': 0.02, 'y': 0.05, 'rotation': 1},\n",
        ),
    )
    sim = Simulation(load_config(path), seed=2)
    draw = float(sim.stream("device:w0").normal(0.0, 2.0))  # w0's own stream, fresh
    assert sim.command("w0-6") == [math.inf]
    amount = 6 + draw * (0.05 + 1) * 6  # unit velocity . (x, y) error + rotation error
    assert sim.robot.drives["w0"].remaining == pytest.approx(amount)
    sim.step(1)
    step = min(abs(amount), 126 / 60)
    pose = sim.robot.pose
    # robot +x is world -x at heading 180; bias adds 0.1 in sideways and 0.5 degree per unit
    assert (pose.x, pose.y, pose.heading) == pytest.approx(
        (6 - 0.1 * step, 42 - step, 180 + 1.5 * step)
    )


def test_omni_wheel_directions_scale_the_odometers(tmp_path: Path) -> None:
    omni = next(q for q in QUIRKS if q.name == "omni-wheel directions")
    path = write_quirk(
        tmp_path,
        (omni.old, omni.new),
        (M1_ROTATION, M1_ROTATION.replace("'rotation': 0", "'rotation': 60")),
    )
    sim = Simulation(load_config(path), seed=1)
    assert sim.command("w0-10") == [math.inf]
    assert sim.run_until_idle()
    # gain = direction / |cos a|: m0 points along w0 (a = 0), m1 is turned 60 degrees
    assert sim.command("m0,m1") == [pytest.approx(8.66), pytest.approx(-0.866 * 10 / 0.5)]
    assert tuple(sim.robot.pose) == pytest.approx((6.0, 32.0, 180.0))  # the motion is unchanged


@pytest.mark.slow
def test_beamwidth_zero_reads_like_a_single_ray(tmp_path: Path) -> None:
    sim = load_quirk(tmp_path, "beamwidth 0")
    assert sim.place_robot(68, 18, 190)  # the fan's outer rays meet a nearer wall
    reading = sim.command("u0")[0]
    u0 = sim.robot.devices["u0"]
    assert isinstance(u0, Ultrasonic)
    assert len(set(u0.rays.tolist())) == 1  # the seven rays coincide
    x, y, heading = u0.world_pose(sim.robot.pose)
    assert reading == pytest.approx(sim.maze.cast_ray(x, y, heading))
    data = default_data()
    data["sensors"]["u0"] |= {"num_rays": 1}
    single = Simulation(make_config(data))
    assert single.place_robot(68, 18, 190)
    assert single.command("u0") == [pytest.approx(reading)]
    fan = Simulation(make_config(default_data()))
    assert fan.place_robot(68, 18, 190)
    assert fan.command("u0")[0] < reading - 3  # a real fan sees the nearer wall


def test_motor_among_the_sensors_answers_by_id(tmp_path: Path) -> None:
    sim = load_quirk(tmp_path, "motor only among the sensors")
    assert sim.config.device("m2").group == "motors"
    assert "m2" in sim.robot.motors
    assert sim.command("m2") == [0.0]
    again = load_quirk(tmp_path, "motor also among the sensors")
    assert [d.id for d in again.config.devices].count("m0") == 1
    again.command("w0-4")
    again.run_until_idle()
    assert again.command("m0") == [pytest.approx(4.0)]


def test_drive_may_turn_a_motor_listed_only_among_the_sensors(tmp_path: Path) -> None:
    path = write_quirk(
        tmp_path,
        (SENSORS_END, "    'u3': Ultrasonic(u3_info),\n    'm2': m2\n}"),
        ("motors = {", "m2 = MotorSimple({'id': 'm2', 'position': [0, -3], 'rotation': 0})\n"
         "motors = {"),
        ("'motors': [motors['m0'], motors['m1']],\n    'motor_direction': [1, 1]",
         "'motors': [motors['m0'], motors['m1'], m2],\n    'motor_direction': [1, 1, 1]"),
    )  # fmt: skip
    sim = Simulation(load_config(path))
    assert sim.config.device("w0").params.motors == ("m0", "m1", "m2")
    sim.command("w0-5")
    sim.run_until_idle()
    assert sim.command("m2") == [pytest.approx(5.0)]


# ----------------------------------------------------------------------------- still errors


def set_in(*path: str, value: Any) -> Callable[[dict[str, Any]], None]:
    def mutate(data: dict[str, Any]) -> None:
        target: Any = data
        for part in path[:-1]:
            target = target[part]
        target[path[-1]] = value

    return mutate


NATIVE = [
    ("block outside the maze", set_in("block_position", value=[120, 5]), "block_position",
     "put it inside an open cell"),
    ("block under the robot", set_in("block_position", value=[6, 42]), "block_position",
     "overlaps the robot's start"),
    ("beamwidth 0", set_in("sensors", "u0", "beamwidth", value=0), "sensors.u0.beamwidth",
     "must be greater than 0; a beamwidth of 0 sends every ray along the sensor's heading"),
    ("omni-wheel direction", set_in("drives", "w0", "motor_direction", value=[0.866, 1]),
     "drives.w0.motor_direction[0]", "must be 1 or -1, not 0.866"),
    ("arc drive", set_in("drives", "w0", "ang_velocity", value=120), "drives.w0.ang_velocity",
     "never both"),
    ("motor among the sensors", set_in("sensors", "m2", value={"type": "motor"}),
     "sensors.m2.type", "belongs in [motors.m2]"),
]  # fmt: skip


@pytest.mark.parametrize(("release", "expected"), [("1.0", None), ("1.2", b"[0.:Not Found,")])
def test_a_device_id_the_original_ran_warns_and_is_unreachable_as_there(
    tmp_path: Path, release: str, expected: bytes | None
) -> None:
    v12 = "\nframe_start = '['\nframe_end = ']'\nround_digits = 3\nstr_encoding = 'ascii'"
    path = write_quirk(
        tmp_path,
        (SENSORS_END, "    '90.0 deg': Ultrasonic(u3_info)\n}"),
        (
            "block_position = [66, 5]",
            "block_position = [66, 5]" + (v12 if release == "1.2" else ""),
        ),
    )
    config = load_config(path)
    (warning,) = config.warnings
    assert (warning.key, warning.line) == ("sensors.90.0 deg", line_of(path, "'90.0 deg'"))
    assert "no command can reach it" in warning.message
    with serving(Simulation(config, seed=3)) as (_, link):
        reply = two_port_raw(link, b"[0.0 deg,u0]" if expected else b"90.0 deg,u0")
    if expected is None:  # v1.0: 8-byte doubles, NaN for a device not found
        first, second = struct.unpack("<2d", reply)
        assert math.isnan(first)
        assert math.isfinite(second)
    else:
        assert reply.startswith(expected)
    data = default_data()
    data["sensors"]["90.0 deg"] = data["sensors"].pop("u0")
    with pytest.raises(ConfigError, match="must be exactly two ASCII characters"):
        make_config(data)  # the native form stays strict


@pytest.mark.parametrize(
    ("mutate", "key", "fragment"), [pytest.param(m, k, f, id=n) for n, m, k, f in NATIVE]
)
def test_native_form_is_still_an_error(
    mutate: Callable[[dict[str, Any]], None], key: str, fragment: str
) -> None:
    data = default_data()
    mutate(data)
    with pytest.raises(ConfigError) as caught:
        make_config(data)
    assert [issue.key for issue in caught.value.issues] == [key]
    assert fragment in caught.value.issues[0].message
    assert ORIGINAL_RUNS not in caught.value.issues[0].message


@pytest.mark.parametrize(
    ("edit", "key", "fragment"),
    [
        pytest.param(
            ("'motor_direction': [1, 1]", "'motor_direction': [1]"),
            "drives.w0.motor_direction",
            "has 1 entries but motors has 2",
            id="motor_direction length",
        ),
        pytest.param(
            ("'velocity': [0, 6],", "'velocity': [0, 0],"),
            "drives.w0.velocity",
            "never moves",
            id="drive that never moves",
        ),
        pytest.param(
            ("robot_start_position = [6, 42]", "robot_start_position = [18, 30]"),
            "robot_start_position",
            "overlaps a wall",
            id="robot in a wall",
        ),
    ],
)
def test_what_would_crash_stays_an_error_in_a_config_py(
    edit: tuple[str, str], key: str, fragment: str, tmp_path: Path
) -> None:
    path = write_quirk(tmp_path, edit)
    with pytest.raises(ConfigError) as caught:
        load_config(path)
    assert [issue.key for issue in caught.value.issues] == [key]
    assert fragment in caught.value.issues[0].message
    assert caught.value.issues[0].line == line_of(path, edit[1])


# ----------------------------------------------------------------------------- simmer check


def test_simmer_check_prints_the_warnings_and_ok(tmp_path: Path) -> None:
    path = write_quirk(
        tmp_path,
        ("'motor_direction': [1, 1]", "'motor_direction': [0.866, 0.866]"),
        ("    'ang_velocity': 0,\n", "    'ang_velocity': 120,\n"),
    )
    result = CliRunner().invoke(app, ["check", str(path)])
    assert result.exit_code == 0, result.output
    text = " ".join(result.output.split())
    assert f"3 warnings in {path}:" in text
    assert f"{path}:{line_of(path, 'ang_velocity')}: drives.w0.ang_velocity: a drive" in text
    line = line_of(path, "'motor_direction': [0.866")
    assert f"{path}:{line}: drives.w0.motor_direction[1]: must be 1 or -1, not 0.866" in text
    assert f"OK {path}" in text
    assert text.index("warnings in") < text.index("OK")
