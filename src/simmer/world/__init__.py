"""The simulated world: maze, block, robot and the simulation that steps them."""

from simmer.world.events import CollisionEvent, CommandEvent, Event, ResetEvent, StepEvent
from simmer.world.maze import Block, Maze, floor_pattern
from simmer.world.robot import Robot
from simmer.world.simulation import Simulation

__all__ = [
    "Block",
    "CollisionEvent",
    "CommandEvent",
    "Event",
    "Maze",
    "ResetEvent",
    "Robot",
    "Simulation",
    "StepEvent",
    "floor_pattern",
]
