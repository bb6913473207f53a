"""A run's outcome, worked out from the simulation's events (not in the window).

:class:`Outcome` is an observer: attach it with :meth:`Outcome.attach` and it follows the run;
:meth:`Outcome.report` gives the figures the lab asks for (the Task 2 time from the robot's
first motion to reaching the block, collisions, path length, commands, busy and NaN replies,
final pose) for the heads-up display, the end of a headless run, and Python.

"Reached the block": the robot's outline comes within :data:`REACH_DISTANCE` (1 in) of the
block's. The Task 2 stopwatch runs from the robot's first motion (the first step its pose
changes, however it was moved) until then.
"""

from __future__ import annotations

import logging
import math
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from simmer.geometry import Pose, polygon_gap
from simmer.protocol import parse_message
from simmer.world.events import (
    CollisionEvent,
    CommandEvent,
    Event,
    PlaceEvent,
    ReachedEvent,
    ResetEvent,
    StepEvent,
)

if TYPE_CHECKING:
    from simmer.world.simulation import Simulation

log = logging.getLogger("simmer.outcome")

REACH_DISTANCE = 1.0
"""The robot "reaches" the block when its outline comes within this many inches of it."""


@dataclass(frozen=True)
class OutcomeReport:
    """What happened in a run, in simulated seconds and inches."""

    time: float
    """Simulated seconds when the report was made."""
    first_motion: float | None
    """When the robot first moved (the Task 2 stopwatch starts)."""
    reached: bool
    """Whether the robot reached the block."""
    reached_at: float | None
    task2_time: float | None
    """Seconds from the first motion to reaching the block (None if it was not reached)."""
    collisions: int
    first_collision: float | None
    blocked_steps: int
    """Steps whose motion a wall or the block undid."""
    path_length: float
    """Inches the robot's centre travelled."""
    messages: int
    commands: int
    nan_replies: int
    """NaN replies other than busy ones: malformed commands, unknown or switched-off devices."""
    final_pose: Pose
    busy_replies: int = 0
    """Drive commands refused (NaN) because a drive was still moving: a program polling
    ``w0-0`` until its move is done gets these, and nothing is wrong."""

    def as_dict(self) -> dict[str, Any]:
        """Plain data (for JSON and CSV)."""
        data = asdict(self)
        data["final_pose"] = list(self.final_pose)
        return data

    def summary(self) -> str:
        """A few lines a student reads at the end of a run."""
        if self.reached and self.task2_time is not None:
            task2 = (
                f"reached the block at {self.reached_at:.2f} s; Task 2 time {self.task2_time:.2f} s"
            )
        else:
            task2 = "did not reach the block"
        first = (
            f" (first at {self.first_collision:.2f} s)" if self.first_collision is not None else ""
        )
        x, y, heading = self.final_pose
        return "\n".join(
            [
                f"outcome after {self.time:.2f} s: {task2}",
                f"  collisions {self.collisions}{first}, {self.blocked_steps} steps blocked; "
                f"path {self.path_length:.1f} in",
                f"  {self.messages} messages, {self.commands} commands, "
                f"{self.busy_replies} busy (a drive still moving), {self.nan_replies} NaN "
                f"replies; final pose x {x:.2f} in, y {y:.2f} in, heading {heading:.1f} deg",
            ]
        )


class Outcome:
    """Follows a simulation's events and keeps the run's outcome; reset with the simulation.

    When the robot reaches the block it adds a :class:`~simmer.world.events.ReachedEvent` to
    the stream, for recordings and other observers.
    """

    def __init__(self, sim: Simulation) -> None:
        self.sim = sim
        robot_radius = float(np.sqrt((sim.robot.outline**2).sum(axis=1)).max())
        self._near = robot_radius + sim.block.size * math.sqrt(0.5) + REACH_DISTANCE
        self._clear()

    @classmethod
    def attach(cls, sim: Simulation) -> Outcome:
        """An outcome observing ``sim`` from now on."""
        outcome = cls(sim)
        sim.add_observer(outcome)
        return outcome

    def _clear(self) -> None:
        self.first_motion: float | None = None
        self.reached_at: float | None = None
        self.collisions = 0
        self.first_collision: float | None = None
        self.path_length = 0.0
        self.messages = 0
        self.commands = 0
        self.nan_replies = 0
        self.busy_replies = 0
        self._blocked_before = self.sim.blocked_steps
        self._last_pose: Pose = self.sim.robot.pose

    def __call__(self, event: Event) -> None:
        """Observe one simulation event."""
        if isinstance(event, StepEvent):
            pose = event.pose
            last = self._last_pose
            if pose != last:
                self.path_length += math.hypot(pose.x - last.x, pose.y - last.y)
                self._last_pose = pose
                if self.first_motion is None:
                    self.first_motion = event.time - self.sim.dt
            if self.first_motion is not None and self.reached_at is None and self.reached():
                self.reached_at = event.time
                task2 = event.time - self.first_motion
                log.info("reached the block at %.2f s (Task 2 time %.2f s)", event.time, task2)
                self.sim.emit(ReachedEvent(event.time, task2, event.step))
        elif isinstance(event, CommandEvent):
            self.messages += 1
            self.commands += len(event.replies)
            nan = sum(math.isnan(value) for value in event.replies)
            busy = self._busy(event) if nan else 0
            self.busy_replies += busy
            self.nan_replies += nan - busy
        elif isinstance(event, CollisionEvent):
            self.collisions += 1
            if self.first_collision is None:
                self.first_collision = event.time
        elif isinstance(event, PlaceEvent):
            self._placed(event.pose)
        elif isinstance(event, ResetEvent):
            self._clear()

    def _busy(self, event: CommandEvent) -> int:
        """How many of a message's NaN replies are drive commands refused because a drive is
        moving (the event comes just after the message ran, so the robot is as it found it)."""
        sim = self.sim
        robot = sim.robot
        if not robot.any_drive_moving:
            return 0
        commands = parse_message(event.message, lenient=sim.config.settings.lenient_commands)
        if len(commands) != len(event.replies):
            return 0
        return sum(
            math.isnan(reply)
            and command.error is None
            and command.device in robot.drives
            and command.device not in sim.switched_off
            for command, reply in zip(commands, event.replies, strict=True)
        )

    def _placed(self, pose: Pose) -> None:
        """The robot was put somewhere by hand (dragged in the window): that is no motion (no
        path length), and if it moved the robot, the Task 2 stopwatch starts again at the next
        motion; collisions, commands and replies stand."""
        if pose != self._last_pose:
            self._last_pose = pose
            self.first_motion = None
            self.reached_at = None

    def reached(self) -> bool:
        """True if the robot's outline is within :data:`REACH_DISTANCE` of the block now."""
        sim = self.sim
        pose = sim.robot.pose
        if math.hypot(pose.x - sim.block.x, pose.y - sim.block.y) > self._near:
            return False
        return polygon_gap(sim.robot.polygon(), sim.block.polygon) <= REACH_DISTANCE

    def task2_time(self) -> float | None:
        """The Task 2 stopwatch: from the first motion to reaching the block (or to now)."""
        if self.first_motion is None:
            return None
        end = self.reached_at if self.reached_at is not None else self.sim.time
        return end - self.first_motion

    def report(self) -> OutcomeReport:
        """The outcome so far."""
        reached = self.reached_at is not None
        return OutcomeReport(
            time=self.sim.time,
            first_motion=self.first_motion,
            reached=reached,
            reached_at=self.reached_at,
            task2_time=self.task2_time() if reached else None,
            collisions=self.collisions,
            first_collision=self.first_collision,
            blocked_steps=self.sim.blocked_steps - self._blocked_before,
            path_length=self.path_length,
            messages=self.messages,
            commands=self.commands,
            nan_replies=self.nan_replies,
            final_pose=self.sim.robot.pose,
            busy_replies=self.busy_replies,
        )
