"""The simulated world: maze, block, robot and the simulation that steps them.

The names below are imported on first use (PEP 562), so ``import simmer.world.events`` (the
event types a recording or a light command reads) does not load NumPy and Numba.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

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


def __getattr__(name: str) -> Any:
    """Import a public name from its module the first time it is used."""
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'simmer.world' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_LAZY])


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
