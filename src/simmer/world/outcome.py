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
from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from simmer.config.zones import project_run
from simmer.geometry import Pose, polygon_gap
from simmer.protocol import parse_message
from simmer.world.events import (
    BlockedMoveEvent,
    CollisionEvent,
    CommandEvent,
    EstimateEvent,
    Event,
    PlaceEvent,
    ReachedEvent,
    ResetEvent,
    StepEvent,
)
from simmer.world.localization import LocalizationReport, Tracker

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
    over_limit: int = 0
    """Messages refused whole at a message limit (``MAX_MESSAGE_BYTES``, ``MAX_COMMANDS``):
    a line without end, a flood of commands in one message. Not in :attr:`messages`."""
    project: ProjectReport | None = None
    """The course project's milestones and score (None unless the robot has a gripper and the
    maze has zones: a Lab 1 run's outcome is as before)."""
    localization: LocalizationReport | None = None
    """How well the program's reported poses matched the truth (None if it reported none)."""
    link: dict[str, float] | None = None
    """What the link model did (messages, bytes, seconds, lost, corrupted, dropouts; None
    when it is off): see :class:`simmer.transport.link.LinkCounts`."""
    blocked_moves: int = 0
    """Drive commands some of whose steps a wall or the block stopped (each replied +inf,
    accepted, as in the original: only here, the HUD and the log say so)."""
    first_blocked_move: str | None = None
    """The first of them: the command, when it started, its blocked steps, how far it got."""
    last_blocked_move: str | None = None
    """The last of them, in the same words."""

    def as_dict(self) -> dict[str, Any]:
        """Plain data (for JSON and CSV)."""
        data = asdict(self)
        data["final_pose"] = list(self.final_pose)
        project = data.pop("project")
        data.update(project or {})
        data.pop("localization")
        if self.localization is not None:
            data.update(self.localization.as_dict())
        link = data.pop("link")
        data.update({f"link_{key}": value for key, value in (link or {}).items()})
        return data

    def link_text(self) -> str | None:
        """One line on what the link model did (None when it is off)."""
        if self.link is None:
            return None
        c = self.link
        return (
            f"link: {c['bytes']:.0f} bytes delayed ({c['seconds']:.2f} s in all), "
            f"{c['lost']:.0f} lost, {c['corrupted']:.0f} corrupted, {c['dropouts']:.0f} dropouts"
        )

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
        project = [self.project.summary()] if self.project is not None else []
        if self.localization is not None:
            project.append(self.localization.summary())
        link = [f"  {text}"] if (text := self.link_text()) is not None else []
        return "\n".join(
            [
                f"outcome after {self.time:.2f} s: {task2}",
                *project,
                f"  collisions {self.collisions}{first}, {self.blocked_steps} steps blocked; "
                f"path {self.path_length:.1f} in",
                *self._blocked_lines(),
                f"  {self.messages} messages, {self.commands} commands, "
                f"{self.busy_replies} busy (a drive still moving), {self.nan_replies} NaN "
                f"replies; final pose x {x:.2f} in, y {y:.2f} in, heading {heading:.1f} deg",
                *link,
            ]
        )

    def _blocked_lines(self) -> list[str]:
        """The blocked moves, if any: how many, the first and the last."""
        if not self.blocked_moves:
            return []
        lines = [f"  blocked moves {self.blocked_moves}: first {self.first_blocked_move}"]
        if self.blocked_moves > 1:
            lines.append(f"    last {self.last_blocked_move}")
        return lines


MILESTONES = ("entered_loading", "picked_up", "left_loading", "delivered")
"""The project's milestones in the order a run meets them (each has an ``_at`` time)."""
MILESTONE_WORDS = {
    "entered_loading": "entered the loading zone",
    "picked_up": "picked up the block",
    "left_loading": "left the loading zone holding it",
    "delivered": "delivered it",
}


@dataclass(frozen=True)
class ProjectReport:
    """The course project's milestones (simulated seconds, None if not met) and score."""

    target: str | None
    start_x: float
    start_y: float
    start_heading: float
    block_x: float
    block_y: float
    """Where the run started and where the block lay (the scenario: drawn or given)."""
    entered_loading: bool
    entered_loading_at: float | None
    picked_up: bool
    picked_up_at: float | None
    left_loading: bool
    left_loading_at: float | None
    delivered: bool
    delivered_at: float | None
    wrong_zone: str | None
    """The drop-off zone the block was put down in instead of the target (None if none)."""
    wrong_zone_at: float | None
    score: float

    def summary(self) -> str:
        """One line: milestones with their times, then the score."""
        met = [
            f"{MILESTONE_WORDS[name]} at {at:.2f} s"
            for name in MILESTONES
            if (at := getattr(self, f"{name}_at")) is not None
        ]
        if self.wrong_zone is not None and not self.delivered:
            met.append(
                f"put it down in {self.wrong_zone} (not the target) at {self.wrong_zone_at:.2f} s"
            )
        said = "; ".join(met) if met else "no milestone"
        return f"  project (target {self.target or 'none'}): {said}; score {self.score:g}"


class Outcome:
    """Follows a simulation's events and keeps the run's outcome; reset with the simulation.

    When the robot reaches the block it adds a :class:`~simmer.world.events.ReachedEvent` to
    the stream, for recordings and other observers.
    """

    def __init__(self, sim: Simulation) -> None:
        self.sim = sim
        robot_radius = float(np.sqrt((sim.robot.outline**2).sum(axis=1)).max())
        self._near = robot_radius + sim.block.size * math.sqrt(0.5) + REACH_DISTANCE
        zones = sim.zones
        self._zoned = project_run(sim.config) and bool(zones.loading or zones.dropoff)
        self._loading = frozenset(zones.loading.cells if zones.loading else ())
        self._cell = zones.cell
        self._clear()

    @classmethod
    def attach(cls, sim: Simulation) -> Outcome:
        """An outcome observing ``sim`` from now on."""
        outcome = cls(sim)
        sim.add_observer(outcome)
        return outcome

    link_counts: Callable[[], dict[str, float]] | None = None
    """What the run's link model did so far (set by the run that serves a link model)."""
    over_limit_count: Callable[[], int] | None = None
    """Messages refused at a message limit so far (set by the run that serves them)."""

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
        self.blocked_moves = 0
        self.first_blocked_move: BlockedMoveEvent | None = None
        self.last_blocked_move: BlockedMoveEvent | None = None
        self._blocked_before = self.sim.blocked_steps
        self._last_pose: Pose = self.sim.robot.pose
        self.milestones: dict[str, float] = {}
        self.wrong_zone: tuple[str, float] | None = None
        self._held = False
        self.localization = Tracker()
        """The program's reported poses against the truth."""

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
            if self._zoned:
                self._moved(event.time)
        elif isinstance(event, CommandEvent):
            if self._zoned:
                self._gripped(event.time)
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
        elif isinstance(event, BlockedMoveEvent):
            self.blocked_moves += 1
            self.first_blocked_move = self.first_blocked_move or event
            self.last_blocked_move = event
        elif isinstance(event, EstimateEvent):
            self.localization.add(event.time, event.pose, event.truth)
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

    def _gripped(self, time: float) -> None:
        """After a command: the block picked up, or put down (delivered, or in another zone)."""
        sim = self.sim
        held = sim.block.held is not None
        if held == self._held:
            return
        self._held = held
        met = self.milestones
        if held:
            met.setdefault("picked_up", time)
        elif "delivered" not in met:
            zone = sim.zones.dropoff_at(sim.block.x, sim.block.y)
            if zone is not None and zone == sim.scenario.target:
                met["delivered"] = time
            elif zone is not None and self.wrong_zone is None:
                self.wrong_zone = (zone, time)

    def _moved(self, time: float) -> None:
        """After a step: the loading zone entered, or left holding the block (checked only
        while one of them is still to come: a step costs little)."""
        met = self.milestones
        entering = "entered_loading" not in met
        leaving = self._held and "left_loading" not in met
        if not (entering or leaving):
            return
        pose = self.sim.robot.pose
        inside = (int(pose.y // self._cell), int(pose.x // self._cell)) in self._loading
        if inside and entering:
            met["entered_loading"] = time
        elif leaving and not inside:
            met["left_loading"] = time

    def project_report(self) -> ProjectReport | None:
        """The milestones and score so far (None unless this is a project run with zones)."""
        if not self._zoned:
            return None
        rubric = self.sim.config.settings.score
        met = {k: t for k, t in self.milestones.items() if t <= rubric.time_limit}
        delivered = "delivered" in met
        wrong = (
            self.wrong_zone if self.wrong_zone and self.wrong_zone[1] <= rubric.time_limit else None
        )
        score = sum(getattr(rubric, name) for name in met)
        if wrong is not None and not delivered:
            score += rubric.wrong_zone
        score += rubric.collision * self.collisions
        at = self.milestones.get
        scenario = self.sim.scenario
        return ProjectReport(
            target=scenario.target,
            start_x=scenario.start.x,
            start_y=scenario.start.y,
            start_heading=scenario.start.heading,
            block_x=scenario.block[0],
            block_y=scenario.block[1],
            entered_loading="entered_loading" in self.milestones,
            entered_loading_at=at("entered_loading"),
            picked_up="picked_up" in self.milestones,
            picked_up_at=at("picked_up"),
            left_loading="left_loading" in self.milestones,
            left_loading_at=at("left_loading"),
            delivered="delivered" in self.milestones,
            delivered_at=at("delivered"),
            wrong_zone=self.wrong_zone[0] if self.wrong_zone else None,
            wrong_zone_at=self.wrong_zone[1] if self.wrong_zone else None,
            score=round(score, 6),
        )

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
            over_limit=0 if self.over_limit_count is None else self.over_limit_count(),
            project=self.project_report(),
            localization=self.localization.report(),
            link=None if self.link_counts is None else self.link_counts(),
            blocked_moves=self.blocked_moves,
            first_blocked_move=_said(self.first_blocked_move),
            last_blocked_move=_said(self.last_blocked_move),
        )


def _said(event: BlockedMoveEvent | None) -> str | None:
    """A blocked move in words (None: none)."""
    return None if event is None else event.describe()
