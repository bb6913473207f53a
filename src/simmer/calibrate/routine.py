"""The calibration routine: a designed experiment a team runs on the real robot, as a program.

From the configuration's start cell and heading the robot reads every sensor :data:`READS`
times (the spread of repeated reads is each sensor's error; their mean at the known start,
its offset), holds still :data:`HOLDS` times for :data:`HOLD` seconds (the gyroscope's
drift), drives straight towards the wall ahead and back :data:`LEGS` times (each leg's
travel, seen by the sensors that face along it, is a draw of the drive's scale: bias and
error), and turns right and back :data:`TURNS` times (each turn, seen by the gyroscope, a
draw of the turn drive's), reading every sensor after each motion.
:func:`routine_program` writes it as a Python program using ``simmer.client`` over the
robot's serial port (the tap's), in the configuration's protocol. :func:`plan` is what the
fit reads back: which devices it used and how far it drove.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from simmer.config.models import SimConfig
from simmer.errors import RoutineError

if TYPE_CHECKING:
    from simmer.world.simulation import Simulation

READS = 12
"""Reads of every sensor at each stop."""
LEGS = 8
"""Straight drives forward and back (each pair returns to the start)."""
TURNS = 6
"""Turns right and back (each pair returns to the start heading)."""
TURN = 90.0
"""Degrees of each turn."""
HOLD = 3.0
"""Seconds of each hold, the robot still, for the gyroscope's drift."""
HOLDS = 4
"""Holds at the start."""
MAX_LEG = 8.0
"""Longest straight drive, inches."""
CLEARANCE = 3.0
"""Inches left between the robot's front and the wall ahead at the end of a leg."""


@dataclass(frozen=True)
class Plan:
    """What the routine does on this configuration's robot."""

    sensors: tuple[str, ...]
    """The ultrasonic sensors read at every stop."""
    gyros: tuple[str, ...]
    drive: str
    """The drive that translates (the legs)."""
    turn: str | None
    """The drive that rotates (the turns), if the robot has one."""
    leg: float
    """Inches of each leg."""
    start: tuple[float, float, float]
    home: tuple[str, float, float] | None = None
    """The sensor that brings the robot back to its start before the turns (the one facing
    the nearest flat wall along the legs), its reading there and its change per inch."""

    @property
    def read_message(self) -> str:
        """One message reading every sensor and gyroscope."""
        return ",".join(self.sensors + self.gyros)


def plan(config: SimConfig) -> Plan:
    """The routine on this robot: its sensors, drives and leg length (RoutineError if it has
    no ultrasonic sensor, no drive that translates, or no room ahead of its start)."""
    from simmer.geometry import Pose, rotate
    from simmer.world.simulation import Simulation

    sim = Simulation(config, seed=0)
    kinds = {spec.id: spec.kind for spec in config.devices}
    sensors = tuple(i for i, k in kinds.items() if k == "ultrasonic")
    gyros = tuple(i for i, k in kinds.items() if k == "gyroscope")
    drives = sim.robot.drives
    straight = [i for i, d in drives.items() if not d.rotational and d.turn == 0.0]
    turning = [i for i, d in drives.items() if d.rotational]
    where = config.source
    if not sensors:
        raise RoutineError(f"{where}: the robot has no ultrasonic sensor; the routine reads them")
    if not straight:
        raise RoutineError(f"{where}: the robot has no drive that goes straight (a velocity)")
    drive = straight[0]
    unit = drives[drive].unit
    start = sim.robot.pose
    # room ahead along the drive: its unit's motion, half an inch at a time, until a wall
    direction = rotate(unit[0], unit[1], start.heading)
    room = 0.0
    for step in range(1, 400):
        distance = step * 0.5
        pose = Pose(
            start.x + direction.x * distance, start.y + direction.y * distance, start.heading
        )
        if sim._blocked(pose):
            break
        room = distance
    leg = min(MAX_LEG, math.floor(room - CLEARANCE))
    if leg < 2.0:
        raise RoutineError(
            f"{where}: only {room:.1f} in ahead of the robot's start; start it facing a "
            f"corridor at least {2 + CLEARANCE:g} in long (robot_start_position, "
            "robot_start_rotation)"
        )
    turn = turning[0] if turning else None
    if turn is not None and any(
        sim._blocked(Pose(start.x, start.y, start.heading + angle)) for angle in range(0, 360, 5)
    ):
        turn = None  # no room to turn at the start: the turns are left out
    origin = (start.x, start.y, start.heading)
    home = _home(sim, sensors, origin, direction.x, direction.y, float(leg))
    return Plan(sensors, gyros, drive, turn, float(leg), origin, home)


def _home(
    sim: Simulation,
    sensors: tuple[str, ...],
    start: tuple[float, float, float],
    dx: float,
    dy: float,
    leg: float,
) -> tuple[str, float, float] | None:
    """The sensor facing the nearest flat wall along the legs, its reading at the start and
    its change per inch (None: no sensor faces one)."""
    import numpy as np

    from simmer.world.expected import expected

    along = np.linspace(0.0, leg, 9)
    poses = [(start[0] + dx * a, start[1] + dy * a, start[2]) for a in along]
    maze = expected(sim, poses, list(sensors))
    best: tuple[str, float, float] | None = None
    for i, sensor in enumerate(sensors):
        slope, intercept = np.polyfit(along, maze[:, i], 1)
        straight = float(np.max(np.abs(maze[:, i] - (slope * along + intercept)))) <= 0.25
        if abs(abs(slope) - 1.0) <= 0.1 and straight and (best is None or maze[0, i] < best[1]):
            best = (sensor, float(maze[0, i]), float(slope))
    return best


PROGRAM = '''\
"""SimMeR's calibration routine for {source}: run it on the real robot through simmer tap.

Put the robot at its configured start: x {x:g} in, y {y:g} in, heading {heading:g} deg
(docs/calibration.md). It reads {read} {reads} times at each stop, holds still {holds} times for
{hold:g} s, drives {drive} {leg:g} in forward and back {legs} times{turns_words}.

    simmer tap PORT --config {config_name} --record runs/calibration \\
        --program "python {name} {{port}}"
"""

import os
import sys

from simmer.client import connect

PORT = sys.argv[1] if len(sys.argv) > 1 else os.environ["SIMMER_TAP_PORT"]
READ = {read!r}


def stop(robot):
    """Read every sensor {reads} times where the robot stands."""
    for _ in range({reads}):
        robot.send(READ)


def move(robot, drive, amount):
    robot.drive(drive, amount)
    robot.wait_idle(drive)
    stop(robot)


with connect(serial=PORT, framed={framed}, width={width}, baudrate={baud}) as robot:
    stop(robot)
    for _ in range({holds}):
        robot.sleep({hold!r})
        stop(robot)
    for _ in range({legs}):
        move(robot, {drive!r}, {leg!r})
        move(robot, {drive!r}, {back!r})
{home_lines}{turn_lines}    print("calibration routine done")
'''


def routine_program(
    config: SimConfig,
    routine: Plan,
    name: str = "calibration_routine.py",
    baud: int = 9600,
    hold: float = HOLD,
) -> str:
    """The routine as a Python program for this robot (its protocol, devices and start);
    ``hold``: seconds of each hold (shorter ones state the drift less tightly)."""
    from pathlib import Path

    s = config.settings
    turn_lines = ""
    turns_words = ""
    if routine.turn is not None:
        turn_lines = (
            f"    for _ in range({TURNS}):\n"
            f"        move(robot, {routine.turn!r}, {TURN!r})\n"
            f"        move(robot, {routine.turn!r}, {-TURN!r})\n"
        )
        turns_words = f", and turns {routine.turn} {TURN:g} deg and back {TURNS} times"
    home_lines = ""
    if routine.home is not None and routine.turn is not None:
        sensor, reading, per_inch = routine.home
        index = routine.read_message.split(",").index(sensor)
        home_lines = (
            f"    # back to the start ({sensor} read {reading:.2f} in there) before turning\n"
            f"    now = sum(robot.send(READ)[{index}] for _ in range({READS})) / {READS}\n"
            f"    if abs(now - {reading!r}) > 0.1:\n"
            f"        amount = round(({reading!r} - now) / {per_inch!r}, 2)\n"
            f"        move(robot, {routine.drive!r}, amount)\n"
        )
    x, y, heading = routine.start
    return PROGRAM.format(
        home_lines=home_lines,
        source=Path(config.source).name,
        config_name=Path(config.source).name,
        name=name,
        x=x,
        y=y,
        heading=heading,
        read=routine.read_message,
        reads=READS,
        hold=hold,
        holds=HOLDS,
        drive=routine.drive,
        leg=routine.leg,
        back=-routine.leg,
        legs=LEGS,
        turns_words=turns_words,
        turn_lines=turn_lines,
        framed=s.protocol == "framed",
        width=s.reply_bytes,
        baud=baud,
    )
