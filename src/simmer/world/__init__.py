"""The simulated world: maze, block, robot and the simulation that steps them.

The names below are imported on first use (PEP 562), so ``import simmer.world.events`` (the
event types a recording or a light command reads) does not load NumPy and Numba.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from simmer.lazy import lazy_names

_LAZY = {
    "Block": "simmer.config.maze",
    "Maze": "simmer.config.maze",
    "floor_pattern": "simmer.config.maze",
    "Robot": "simmer.world.robot",
    "Simulation": "simmer.world.simulation",
    **dict.fromkeys(
        (
            "CollisionEndEvent",
            "CollisionEvent",
            "CommandEvent",
            "Event",
            "KeysEvent",
            "PlaceEvent",
            "ReachedEvent",
            "ResetEvent",
            "RunEvent",
            "StepEvent",
        ),
        "simmer.world.events",
    ),
}

if TYPE_CHECKING:
    from simmer.config.maze import Block, Maze, floor_pattern
    from simmer.world.events import (
        CollisionEndEvent,
        CollisionEvent,
        CommandEvent,
        Event,
        KeysEvent,
        PlaceEvent,
        ReachedEvent,
        ResetEvent,
        RunEvent,
        StepEvent,
    )
    from simmer.world.robot import Robot
    from simmer.world.simulation import Simulation


__getattr__, __dir__ = lazy_names(__name__, _LAZY, globals())

__all__ = [
    "Block",
    "CollisionEndEvent",
    "CollisionEvent",
    "CommandEvent",
    "Event",
    "KeysEvent",
    "Maze",
    "PlaceEvent",
    "ReachedEvent",
    "ResetEvent",
    "Robot",
    "RunEvent",
    "Simulation",
    "StepEvent",
    "floor_pattern",
]
