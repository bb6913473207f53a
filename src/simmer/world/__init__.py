"""The simulated world: maze, block, robot and the simulation that steps them."""

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
from simmer.world.maze import Block, Maze, floor_pattern
from simmer.world.robot import Robot
from simmer.world.simulation import Simulation

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
