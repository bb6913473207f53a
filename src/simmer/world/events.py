"""Events the simulation reports to its observers (traces, video, HUD, reports)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from simmer.geometry import Pose


@dataclass(frozen=True)
class CommandEvent:
    """A message was executed; ``replies`` has one value per command."""

    time: float
    message: str
    replies: tuple[float, ...]


@dataclass(frozen=True)
class StepEvent:
    """A step finished; ``pose`` is the robot's pose after it."""

    time: float
    pose: Pose


@dataclass(frozen=True)
class CollisionEvent:
    """The robot ran into a wall or the block (first blocked step of a collision)."""

    time: float
    pose: Pose


@dataclass(frozen=True)
class ResetEvent:
    """The simulation went back to its start."""

    time: float


Event = CommandEvent | StepEvent | CollisionEvent | ResetEvent
Observer = Callable[[Event], None]
