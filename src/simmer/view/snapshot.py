"""What the window draws, as immutable values handed from the simulation thread to the window.

The simulation thread owns the :class:`~simmer.world.Simulation` (DESIGN habit 3); the window
thread never reads it. Instead the simulation thread publishes a :class:`Snapshot` up to 60 times a
second: poses, polygons and measurement shapes already in world inches, read-only arrays, tuples
and frozen dataclasses, so the window can draw one while the next is being built.
:class:`StaticScene` is the part that never changes while a simulation runs (configuration and
maze), captured once before the threads start.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from simmer.colors import Color
from simmer.config.maze import Maze
from simmer.config.models import SimConfig
from simmer.devices.base import Shape
from simmer.geometry import FloatArray, Pose, place_polygon
from simmer.localize.belief import Belief
from simmer.scene import Look, heading_mark
from simmer.view.trail import TrailView
from simmer.world import Simulation
from simmer.world.events import CommandEvent
from simmer.world.outcome import OutcomeReport
from simmer.world.robot import Robot


class HasScene(Protocol):
    """Anything with a configuration and a maze: a :class:`Simulation` or a :class:`StaticScene`."""

    @property
    def config(self) -> SimConfig:
        """The configuration."""
        ...

    @property
    def maze(self) -> Maze:
        """The maze."""
        ...


@dataclass(frozen=True)
class StaticScene:
    """The parts of a simulation that never change while it runs: configuration and maze."""

    config: SimConfig
    maze: Maze

    @classmethod
    def of(cls, sim: Simulation) -> StaticScene:
        """Capture a simulation's static parts (before any other thread runs it)."""
        return cls(sim.config, sim.maze)


def frozen_array(array: FloatArray) -> FloatArray:
    """``array`` made read-only (a copy is not taken: pass a fresh array)."""
    array.flags.writeable = False
    return array


@dataclass(frozen=True)
class RobotLayout:
    """Robot outline, heading mark, visible device outlines and sensor-id anchors stacked in one
    robot-frame array, so one call places them all; the same for every snapshot of a robot."""

    local: FloatArray
    body: int
    """Points ``[0, body)`` are the outline; the next two are the heading mark."""
    devices: tuple[tuple[int, int, Color], ...]
    """(start, stop, colour) of each visible device's outline."""
    labels: tuple[tuple[int, str, Color], ...]
    """(point, id, colour): where to write each off-centre visible sensor's id."""

    @classmethod
    def of(cls, robot: Robot) -> RobotLayout:
        """Stack a robot's shapes."""
        pieces = [robot.outline, heading_mark(robot.outline, Look.WINDOW)]
        devices = []
        start = len(robot.outline) + 2
        for device in robot.devices.values():
            if device.visible:
                placed = np.empty_like(device.outline)
                x, y = device.position
                place_polygon(device.outline, x, y, device.rotation, placed)
                pieces.append(placed)
                devices.append((start, start + len(placed), device.params.color))
                start += len(placed)
        labels = []
        for device in robot.sensors.values():
            x, y = device.position
            if device.visible and math.hypot(x, y) > 0.5:
                pieces.append(np.array([[0.55 * x, 0.55 * y]]))  # inside the body, toward it
                labels.append((start, device.id, device.params.color))
                start += 1
        local = frozen_array(np.concatenate(pieces))
        return cls(local, len(robot.outline), tuple(devices), tuple(labels))

    def place(self, pose: Pose) -> FloatArray:
        """Every point of the layout in the world at ``pose`` (a fresh, read-only array)."""
        out = np.empty_like(self.local)
        place_polygon(self.local, pose.x, pose.y, pose.heading, out)
        return frozen_array(out)


@dataclass(frozen=True)
class Snapshot:
    """Everything one frame draws, in world inches and simulated seconds; never changes."""

    time: float
    pose: Pose
    block: FloatArray
    """The block's outline (K, 2)."""
    layout: RobotLayout
    robot: FloatArray
    """:attr:`layout`'s points placed at :attr:`pose`; ``robot[:layout.body]`` is the outline."""
    shapes: tuple[Shape, ...]
    """Every device's latest measurement (rays, circles)."""
    paused: bool = False
    speed: float | None = 1.0
    held: frozenset[str] = frozenset()
    """Manual-driving keys the simulation is obeying."""
    outcome: OutcomeReport | None = None
    """The run's outcome so far (Task 2 stopwatch, collisions, path, replies); None when no
    :class:`~simmer.world.outcome.Outcome` follows the simulation."""
    commands: tuple[CommandEvent, ...] = ()
    """The last few messages and their replies, oldest first."""
    clients: tuple[str, ...] | None = None
    """Connected clients; None when no runner serves any."""
    ghost: FloatArray | None = None
    """Where a refused drag would have put the robot's outline."""
    switched_off: tuple[tuple[str, str], ...] = ()
    """(device id, reason) of each device switched off because its code raised."""
    recording: str | None = None
    """The name of the video the window is recording, if it is."""
    notice: str | None = None
    """What the window just did that a student must find: the file a screenshot or video went
    to (shown in the HUD for a few seconds)."""
    trail: TrailView | None = None
    """The path driven so far, if something keeps it."""
    target: str | None = None
    """The project's target zone (drawn in yellow), if the run has one."""
    belief: Belief | None = None
    """What the control program showed last of its belief (``robot.show``), if anything."""
    blocked: str | None = None
    """The drive command a wall or the block is stopping now, or stopped just before, in
    words (:meth:`Simulation.blocked_now <simmer.world.simulation.Simulation.blocked_now>`)."""

    @property
    def outline(self) -> FloatArray:
        """The robot's outline in the world."""
        return self.robot[: self.layout.body]

    @classmethod
    def of(
        cls,
        sim: Simulation,
        layout: RobotLayout | None = None,
        *,
        paused: bool = False,
        speed: float | None = 1.0,
        outcome: OutcomeReport | None = None,
        commands: Sequence[CommandEvent] = (),
        clients: Sequence[str] | None = None,
        ghost: FloatArray | None = None,
        recording: str | None = None,
        notice: str | None = None,
        trail: TrailView | None = None,
        belief: Belief | None = None,
    ) -> Snapshot:
        """Read a simulation now (only in the thread that owns it)."""
        robot = sim.robot
        if layout is None:
            layout = RobotLayout.of(robot)
        pose = robot.pose
        shapes = tuple(sim.shapes())
        return cls(
            time=sim.time,
            pose=pose,
            block=frozen_array(np.array(sim.block.polygon, dtype=np.float64)),
            layout=layout,
            robot=layout.place(pose),
            shapes=shapes,
            paused=paused,
            speed=speed,
            held=sim.manual_keys,
            outcome=outcome,
            commands=tuple(commands),
            clients=tuple(clients) if clients is not None else None,
            ghost=ghost,
            switched_off=tuple(sim.switched_off.items()),
            recording=recording,
            notice=notice,
            trail=trail,
            target=sim.scenario.target,
            belief=belief,
            blocked=sim.blocked_now(),
        )
