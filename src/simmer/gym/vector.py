"""``SimMeR/Maze-v0`` as a Gymnasium ``VectorEnv``: N robots in one
:class:`~simmer.batch.Batch`, stepped in one compiled call per drive command, autoreset as
Gymnasium 1.x defines it (next step). Robot i reset with seed s is the single environment
reset with seed s, step for step."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from simmer.batch import Batch, BatchError
from simmer.config.models import SimConfig
from simmer.gym.env import SEED_RANGE
from simmer.gym.task import Actions, Task


class MazeVectorEnv(VectorEnv[np.ndarray, Any, np.ndarray]):
    """``num_envs`` robots of :class:`~simmer.gym.MazeEnv`'s task, stepped together; the
    options are :class:`~simmer.gym.MazeEnv`'s."""

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}  # noqa: RUF012

    def __init__(
        self,
        num_envs: int = 16,
        config: SimConfig | str | Path | None = None,
        *,
        overrides: Mapping[str, Any] | None = None,
        actions: Actions = "discrete",
        sensors: list[str] | None = None,
        forward: float = 3.0,
        turn: float = 45.0,
        pose: bool = False,
        max_steps: int = 200,
        reach_reward: float = 10.0,
        collision_penalty: float = 1.0,
        step_penalty: float = 0.01,
        success: str | None = None,
        render_mode: str | None = None,
    ) -> None:
        if success is not None:
            raise BatchError(
                "success= needs a run's outcome, which a batch does not keep: use the single "
                'environment (gym.make_vec(..., vectorization_mode="sync") steps single ones)'
            )
        if render_mode is not None:
            raise ValueError("the vector environment does not render; use SimMeR/Maze-v0")
        self.task = task = Task.of(
            config,
            overrides=overrides,
            sensors=sensors,
            actions=actions,
            forward=forward,
            turn=turn,
            pose=pose,
            max_steps=max_steps,
            reach_reward=reach_reward,
            collision_penalty=collision_penalty,
            step_penalty=step_penalty,
        )
        self.num_envs = num_envs
        self.render_mode = None
        self.single_observation_space = task.observation_space()
        self.single_action_space = task.action_space()
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self.batch = Batch(task.config, [0] * num_envs, list(task.sensors))
        self._rngs = [np.random.default_rng() for _ in range(num_envs)]
        self._forward = self.batch.drive_index(task.forward_drive)
        self._turn = self.batch.drive_index(task.turn_drive)
        self._episode_steps = np.zeros(num_envs, dtype=np.int64)
        self._autoreset = np.zeros(num_envs, dtype=bool)

    def _observe(self) -> np.ndarray:
        obs: np.ndarray = np.minimum(self.batch.readings, self.task.max_range)
        if self.task.pose:
            obs = np.concatenate((obs, self.batch.poses), axis=1)
        return obs

    def _restart(self, robots: np.ndarray) -> None:
        """New episodes for ``robots``: each one's next seed from its own generator, and one
        step that reads their sensors (as the single environment's reset does)."""
        seeds = [int(self._rngs[i].integers(SEED_RANGE)) for i in robots.tolist()]
        self.batch.reset(robots, seeds)
        active = np.zeros(self.num_envs, dtype=bool)
        active[robots] = True
        self.batch.step(active=active)
        self._episode_steps[robots] = 0

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start every robot's episode; ``seed`` s seeds robot i's generator with s + i (a
        list: one seed each), as Gymnasium's vector environments do."""
        if seed is None:
            seeds: list[int | None] = [None] * self.num_envs
        elif isinstance(seed, int):
            seeds = [seed + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
        for i, s in enumerate(seeds):
            if s is not None or seed is None:
                self._rngs[i] = np.random.default_rng(s)
        self._restart(np.arange(self.num_envs))
        self._autoreset[:] = False
        return self._observe(), self._info()

    def _info(self) -> dict[str, Any]:
        return {"pose": self.batch.poses.copy(), "collisions": self.batch.collisions.copy()}

    def step(
        self, actions: Any
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Every robot takes its action; robots whose episode ended last step start a new one
        instead (their action is ignored, reward 0, not terminated nor truncated)."""
        task = self.task
        batch = self.batch
        n = self.num_envs
        active = ~self._autoreset
        if not active.all():
            self._restart(np.flatnonzero(self._autoreset))
        before = batch.collisions.copy()
        if active.any():
            if task.actions == "discrete":
                self._discrete(np.asarray(actions, dtype=np.int64).reshape(n), active)
            else:
                self._continuous(np.asarray(actions, dtype=np.float64).reshape(n, 2), active)
        self._episode_steps[active] += 1
        reached = task.reached(batch.poses, batch.block_poses) & active
        rewards = np.where(active, task.reward(reached, batch.collisions - before), 0.0)
        truncated = (self._episode_steps >= task.max_steps) & ~reached & active
        self._autoreset = reached | truncated
        return self._observe(), rewards, reached, truncated, self._info()

    def _discrete(self, actions: np.ndarray, active: np.ndarray) -> None:
        """Forward/backward robots and turning robots run their own frames: the forward
        ones first, then the turning ones (robots are independent, so the order is free)."""
        task = self.task
        ahead = active & (actions <= 1)
        sign = np.where(actions % 2 == 0, 1.0, -1.0)
        if ahead.any():
            drive = np.where(ahead, self._forward, -1)
            self.batch.step(drive, sign * task.forward, task.forward_frames, ahead)
        turning = active & (actions >= 2)
        if turning.any():
            drive = np.where(turning, self._turn, -1)
            turn = np.where(actions == 2, -task.turn, task.turn)
            self.batch.step(drive, turn, task.turn_frames, turning)

    def _continuous(self, actions: np.ndarray, active: np.ndarray) -> None:
        task = self.task
        a = np.clip(actions, -1.0, 1.0)
        drive = np.where(active, self._turn, -1)
        self.batch.step(drive, a[:, 1] * task.turn, task.turn_frames, active)
        drive = np.where(active, self._forward, -1)
        self.batch.step(drive, a[:, 0] * task.forward, task.forward_frames, active)
