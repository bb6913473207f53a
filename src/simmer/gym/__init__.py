"""Gymnasium environments over SimMeR (``pip install simmer[gym]``).

``import simmer.gym`` registers ``SimMeR/Maze-v0`` (the default configuration) and
``SimMeR/Lab1-v0`` (the lab rover with the lab's noise on its sensors and drives), each with
a single environment (:class:`MazeEnv`, over a :class:`~simmer.Simulation`) and a vector one
(:class:`MazeVectorEnv`, over a :class:`~simmer.batch.Batch`), and ``SimMeR/Project-v0``
(the course project's task, :class:`ProjectEnv`: single environments only)::

    import gymnasium as gym
    import simmer.gym

    env = gym.make("SimMeR/Maze-v0", actions="continuous", pose=True)
    envs = gym.make_vec("SimMeR/Maze-v0", num_envs=1024, vectorization_mode="vector_entry_point")

docs/gym.md gives the spaces, the reward, seeding and the figures.
"""

from __future__ import annotations

from typing import Any

from simmer.gym.env import MazeEnv
from simmer.gym.project import PROJECT_MOVES, ProjectEnv
from simmer.gym.task import DISCRETE_MOVES
from simmer.gym.vector import MazeVectorEnv

__all__ = [
    "DISCRETE_MOVES",
    "ENVIRONMENTS",
    "LAB_NOISE",
    "PROJECT_MOVES",
    "MazeEnv",
    "MazeVectorEnv",
    "ProjectEnv",
    "register_environments",
]

LAB_NOISE: dict[str, Any] = {
    "sensors.u0.error": 0.02,
    "sensors.u1.error": 0.02,
    "sensors.u2.error": 0.02,
    "sensors.u3.error": 0.02,
    "drives.w0.error.y": 0.02,
    "drives.r0.error.rotation": 0.02,
}
"""``SimMeR/Lab1-v0``'s overrides of the default rover: Lab 1's 2% error on the four
ultrasonic sensors and both drives."""
ENVIRONMENTS: dict[str, dict[str, Any]] = {
    "SimMeR/Maze-v0": {},
    "SimMeR/Lab1-v0": {"overrides": LAB_NOISE},
    "SimMeR/Project-v0": {},
}
"""The registered environment ids and the keyword arguments each is made with."""
_ENTRY_POINTS: dict[str, tuple[str, str | None]] = {
    "SimMeR/Project-v0": ("simmer.gym.project:ProjectEnv", None),
}
"""Ids not made by :class:`MazeEnv` (and :class:`MazeVectorEnv`): their entry points."""


def register_environments() -> None:
    """Register :data:`ENVIRONMENTS` with Gymnasium (importing ``simmer.gym`` does)."""
    from gymnasium.envs.registration import register, registry

    for env_id, kwargs in ENVIRONMENTS.items():
        if env_id in registry:
            continue
        entry, vector = _ENTRY_POINTS.get(
            env_id, ("simmer.gym.env:MazeEnv", "simmer.gym.vector:MazeVectorEnv")
        )
        register(id=env_id, entry_point=entry, vector_entry_point=vector, kwargs=kwargs)


register_environments()
