"""What an environment's task is, shared by the single and the vector environment: the
spaces, how an action becomes drive commands, the reward and when an episode ends.

Kept apart from Gymnasium's classes so the single environment (over a
:class:`~simmer.Simulation`) and the vector one (over a :class:`~simmer.batch.Batch`) cannot
drift: robot i of the vector environment is the single environment reset with the same seed.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from simmer.batch import BatchError
from simmer.config.loader import as_config
from simmer.config.maze import Block, Maze, robot_outline
from simmer.config.models import SimConfig
from simmer.devices import DriveParams, UltrasonicParams
from simmer.geometry import place_polygon, polygon_gap
from simmer.world.outcome import REACH_DISTANCE

Actions = Literal["discrete", "continuous"]
DISCRETE_MOVES = ("forward", "backward", "left", "right")
"""The discrete actions, in order: the moves students' programs make (``w0-3``, ``w0--3``,
``r0--45``, ``r0-45`` with the default sizes)."""
MAX_EPISODE_STEPS = 100_000
"""The longest episode an environment may be given (``gym_max_steps`` in docs/limits.md)."""


@dataclass(frozen=True)
class Task:
    """The task of an environment over one configuration (see docs/gym.md)."""

    config: SimConfig
    sensors: tuple[str, ...]
    actions: Actions
    forward_drive: str
    turn_drive: str
    forward: float
    turn: float
    forward_frames: int
    turn_frames: int
    pose: bool
    max_steps: int
    reach_reward: float
    collision_penalty: float
    step_penalty: float
    max_range: float

    @classmethod
    def of(
        cls,
        config: SimConfig | str | Path | None = None,
        *,
        overrides: Mapping[str, Any] | None = None,
        sensors: Sequence[str] | None = None,
        actions: Actions = "discrete",
        forward: float = 3.0,
        turn: float = 45.0,
        pose: bool = False,
        max_steps: int = 200,
        reach_reward: float = 10.0,
        collision_penalty: float = 1.0,
        step_penalty: float = 0.01,
    ) -> Task:
        """Check the options and work out the task; BatchError names what to fix."""
        cfg = as_config(config)
        if overrides:
            from simmer.config.overrides import with_overrides

            cfg = with_overrides(cfg, overrides)
        if actions not in ("discrete", "continuous"):
            raise BatchError(f"actions must be 'discrete' or 'continuous', not {actions!r}")
        if not 1 <= max_steps <= MAX_EPISODE_STEPS:
            raise BatchError(
                f"max_steps must be 1 to {MAX_EPISODE_STEPS:,} (gym_max_steps), not {max_steps}"
            )
        if not (forward > 0 and turn > 0 and math.isfinite(forward) and math.isfinite(turn)):
            raise BatchError("forward (inches) and turn (degrees) must be positive numbers")
        drives = {s.id: s.params for s in cfg.devices if isinstance(s.params, DriveParams)}
        ahead = [d for d, p in drives.items() if p.velocity[1] != 0 and p.ang_velocity == 0]
        turning = [d for d, p in drives.items() if p.velocity == (0.0, 0.0)]
        if not ahead or not turning:
            raise BatchError(
                "an environment needs a drive that moves forward (velocity [0, v]) and one that "
                "turns (ang_velocity); this configuration's drives are "
                + (", ".join(drives) or "none")
            )
        fwd, rot = drives[ahead[0]], drives[turning[0]]
        rate = cfg.settings.frame_rate

        def frames(amount: float, speed: float, error: float) -> int:
            # long enough for the move with its error at five standard deviations (2 · error each)
            return max(1, math.ceil(amount * (1.0 + 10.0 * abs(error)) / speed * rate) + 1)

        specs = {s.id: s for s in cfg.devices}
        if sensors is None:
            listed = [n for n in dict.fromkeys(cfg.settings.simulate_list) if n in specs]
            sensors = listed or [
                s.id for s in cfg.devices if isinstance(s.params, UltrasonicParams)
            ]
        ranges = (
            [p.max_range for n in sensors if isinstance(p := specs[n].params, UltrasonicParams)]
            if all(n in specs for n in sensors)
            else []
        )
        return cls(
            config=cfg,
            sensors=tuple(sensors),
            actions=actions,
            forward_drive=ahead[0],
            turn_drive=turning[0],
            forward=float(forward),
            turn=float(turn),
            forward_frames=frames(forward, abs(fwd.velocity[1]), fwd.error.y),
            turn_frames=frames(turn, abs(rot.ang_velocity), rot.error.rotation),
            pose=pose,
            max_steps=max_steps,
            reach_reward=reach_reward,
            collision_penalty=collision_penalty,
            step_penalty=step_penalty,
            max_range=max(ranges, default=math.inf),
        )

    def observation_space(self) -> Any:
        """Each sensor's reading in inches, then (with ``pose``) x, y and heading."""
        from gymnasium import spaces

        low = [0.0] * len(self.sensors)
        high = [self.max_range] * len(self.sensors)
        if self.pose:
            maze = Maze.from_settings(self.config.settings)
            low += [0.0, 0.0, 0.0]
            high += [maze.cols * maze.cell, maze.rows * maze.cell, 360.0]
        return spaces.Box(np.array(low), np.array(high), dtype=np.float64)

    def action_space(self) -> Any:
        """Discrete: forward, backward, turn left, turn right; continuous: [forward, turn]
        in [-1, 1], scaled by ``forward`` inches and ``turn`` degrees."""
        from gymnasium import spaces

        if self.actions == "discrete":
            return spaces.Discrete(len(DISCRETE_MOVES))
        return spaces.Box(-1.0, 1.0, (2,), dtype=np.float64)

    def moves(self, action: Any) -> list[tuple[str, float, int]]:
        """The drive commands an action makes, in order: (drive, amount, frames to run)."""
        if self.actions == "discrete":
            move = DISCRETE_MOVES[int(action)]
            if move in ("forward", "backward"):
                sign = 1.0 if move == "forward" else -1.0
                return [(self.forward_drive, sign * self.forward, self.forward_frames)]
            sign = -1.0 if move == "left" else 1.0
            return [(self.turn_drive, sign * self.turn, self.turn_frames)]
        a = np.clip(np.asarray(action, dtype=np.float64).reshape(2), -1.0, 1.0)
        return [
            (self.turn_drive, float(a[1]) * self.turn, self.turn_frames),
            (self.forward_drive, float(a[0]) * self.forward, self.forward_frames),
        ]

    def observe(self, readings: np.ndarray, pose: np.ndarray) -> np.ndarray:
        """An observation from a robot's readings and pose."""
        obs = np.minimum(np.asarray(readings, dtype=np.float64), self.max_range)
        if self.pose:
            obs = np.concatenate((obs, np.asarray(pose, dtype=np.float64)))
        return obs

    def reward(self, reached: Any, new_collisions: Any) -> Any:
        """The reward of one step (or of each robot's, given arrays): reaching the block, less
        collisions and a step's cost."""
        return (
            self.reach_reward * reached
            - self.collision_penalty * new_collisions
            - self.step_penalty
        )

    def reached(self, poses: np.ndarray, blocks: np.ndarray) -> np.ndarray:
        """(N,) True where a robot's outline is within 1 in of its block (the outcome's
        "reached the block")."""
        settings = self.config.settings
        outline = robot_outline(settings)
        radius = float(np.sqrt((outline**2).sum(axis=1)).max())
        near = radius + settings.block_size * math.sqrt(0.5) + REACH_DISTANCE
        poses = np.asarray(poses).reshape(-1, 3)
        blocks = np.asarray(blocks).reshape(-1, 2)
        out = np.zeros(len(poses), dtype=bool)
        close = np.hypot(poses[:, 0] - blocks[:, 0], poses[:, 1] - blocks[:, 1]) <= near
        placed = np.empty_like(outline)
        for i in np.flatnonzero(close).tolist():
            block = Block(blocks[i, 0], blocks[i, 1], settings.block_rotation, settings.block_size)
            place_polygon(outline, poses[i, 0], poses[i, 1], poses[i, 2], placed)
            out[i] = polygon_gap(placed, block.polygon) <= REACH_DISTANCE
        return out
