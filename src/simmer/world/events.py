"""One stream of events: every input to a run and every outcome, in simulated time.

Each event carries the simulated ``time`` and the ``step`` number (steps done so far) at which
it happened. Inputs (:data:`INPUTS`: commands with the client they came from, manual keys,
placing the robot, resets) are everything a run depends on besides its configuration and seed,
so feeding them back into a fresh simulation reproduces every reply and pose
(:func:`simmer.world.replay.replay`). Outcomes (replies, collisions starting and ending, the
block reached) and what the loop around the simulation did (pause, speed, clock advances, a
control program starting and exiting) are events too, so the heads-up display, the outcome,
recordings and sweeps are all observers of the one stream.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from simmer.pose import Pose


@dataclass(frozen=True)
class CommandEvent:
    """A message was executed; ``replies`` has one value per command."""

    time: float
    message: str
    replies: tuple[float, ...]
    step: int = 0
    client: str = ""
    """Who sent it (``stream 127.0.0.1:50312``), "" from Python."""


@dataclass(frozen=True)
class StepEvent:
    """A step finished; ``pose`` is the robot's pose after it."""

    time: float
    pose: Pose
    step: int = 0


@dataclass(frozen=True)
class CollisionEvent:
    """The robot ran into a wall or the block (first blocked step of a collision)."""

    time: float
    pose: Pose
    step: int = 0


@dataclass(frozen=True)
class CollisionEndEvent:
    """The robot moved again after a collision (its first unblocked step)."""

    time: float
    pose: Pose
    step: int = 0


@dataclass(frozen=True)
class BlockedMoveEvent:
    """A drive command ended (done, stopped by ``xx``) after some of its steps moved nothing: a
    wall or the block was in the way. ``command`` is its text, ``started`` when it was
    accepted, ``blocked_steps`` its steps that moved nothing, and it got ``done`` of ``amount``
    (``unit``: in, or deg for a turning drive). Not an input: its reply stays the original's
    (+inf, accepted), and the run's outcome, the HUD and the log say it."""

    time: float
    command: str
    started: float
    blocked_steps: int
    done: float
    amount: float
    unit: str
    step: int = 0

    def describe(self) -> str:
        """One line: the command, when, and how far it got."""
        share = self.done / self.amount if self.amount else 0.0
        return (
            f"'{self.command}' at {self.started:.2f} s was blocked for {self.blocked_steps} "
            f"steps: it got {self.done:.2f} of {self.amount:.2f} {self.unit} ({share:.0%})"
        )


@dataclass(frozen=True)
class ResetEvent:
    """The simulation went back to its start."""

    time: float
    step: int = 0


@dataclass(frozen=True)
class KeysEvent:
    """The manual-driving keys held changed (the window's W A S D Q E)."""

    time: float
    keys: frozenset[str]
    step: int = 0


@dataclass(frozen=True)
class PlaceEvent:
    """The robot was put somewhere by hand (dragged or turned with the mouse)."""

    time: float
    pose: Pose
    step: int = 0


@dataclass(frozen=True)
class ReachedEvent:
    """The robot reached the block (the Task 2 stopwatch stops)."""

    time: float
    task2_time: float
    step: int = 0


@dataclass(frozen=True)
class RunEvent:
    """Something the loop around the simulation did: ``pause``, ``resume``, ``speed``
    (``value`` the new multiple of real time, NaN for as fast as possible), ``clock`` (a clock
    message: ``value`` the seconds asked, NaN for idle), ``program-start`` or ``program-exit``
    (``value`` its exit status)."""

    time: float
    what: str
    value: float = 0.0
    step: int = 0
    detail: str = ""


@dataclass(frozen=True)
class BeliefEvent:
    """A control program showed its belief (``robot.show``): ``belief`` is its JSON, already
    cut to the documented bounds (:mod:`simmer.localize.belief`); ``cut`` counts the points
    cut from it, ``skipped`` the whole show messages dropped since the last one shown. Not an
    input: nothing the simulation answers depends on it."""

    time: float
    belief: str
    cut: int = 0
    skipped: int = 0
    step: int = 0
    client: str = ""


@dataclass(frozen=True)
class EstimateEvent:
    """A control program reported where it believes it is (``robot.report_pose``, or the
    pose it showed); ``truth`` is the robot's pose then. Not an input."""

    time: float
    pose: Pose
    truth: Pose
    step: int = 0
    client: str = ""


Event = (
    CommandEvent
    | StepEvent
    | CollisionEvent
    | CollisionEndEvent
    | BlockedMoveEvent
    | ResetEvent
    | KeysEvent
    | PlaceEvent
    | ReachedEvent
    | RunEvent
    | BeliefEvent
    | EstimateEvent
)
Observer = Callable[[Event], None]

INPUTS = (CommandEvent, KeysEvent, PlaceEvent, ResetEvent)
"""The events a run's result depends on (with its configuration and seed)."""
SHOWN = (BeliefEvent, EstimateEvent)
"""What a program showed of its own belief: a replay shows them again at their steps, and
nothing else in a run depends on them."""
