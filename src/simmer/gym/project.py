"""``SimMeR/Project-v0``: the course project's task (docs/project.md) as a Gymnasium
environment: find the block in the loading zone, pick it up, deliver it to the target zone.

A single environment over a :class:`~simmer.Simulation` with the run's own
:class:`~simmer.world.outcome.Outcome` attached, so the reward is the project's score as a run
reports it (the ``[score]`` rubric: milestones, a wrong zone, collisions, the time limit),
paid as it changes: an episode's rewards add up to the run's score. A :class:`~simmer.batch.Batch`
has no gripper, so there is no batched project environment (``gym.make_vec`` with the default
``vectorization_mode`` steps single ones).
"""

from __future__ import annotations

from collections.abc import Mapping
from importlib.resources import files
from pathlib import Path
from typing import Any

import numpy as np

from simmer.batch import BatchError
from simmer.config.loader import as_config
from simmer.config.models import SimConfig
from simmer.devices import UltrasonicParams
from simmer.gym.env import MazeEnv
from simmer.gym.task import DISCRETE_MOVES, Actions

PROJECT_MOVES = (*DISCRETE_MOVES, "close", "open")
"""The project environment's discrete actions, in order: the four moves, then closing and
opening the gripper's jaws (``g0-1``, ``g0-0``)."""
GRIP_THRESHOLD = 0.5
"""Continuous actions: a third component above this closes the jaws, below minus this opens
them, between leaves them as they are."""


def project_config() -> Path:
    """The example project rover's file, as ``simmer new --project`` copies it."""
    return Path(str(files("simmer").joinpath("data/new/project.toml")))


class ProjectEnv(MazeEnv):
    """The course project: observations are the ultrasonic sensors' readings, whether the
    robot holds the block, and the target zone (one-hot over the drop-off zones, in name
    order); actions the four moves and the gripper (discrete ``Discrete(6)``, or continuous
    ``[forward, turn, grip]``); the reward is the project's score as it changes (less
    ``step_penalty`` a step); the episode ends on delivery (terminated), or at the rubric's
    ``time_limit`` in simulated seconds or after ``max_steps`` actions (truncated).

    ``config``: a project configuration (a robot with a gripper, a maze with drop-off zones);
    None is ``examples/project.toml``. Other options are :class:`MazeEnv`'s.
    """

    keeps_outcome = True

    def __init__(
        self,
        config: SimConfig | str | Path | None = None,
        *,
        overrides: Mapping[str, Any] | None = None,
        actions: Actions = "discrete",
        sensors: list[str] | None = None,
        forward: float = 3.0,
        turn: float = 45.0,
        pose: bool = False,
        max_steps: int = 2000,
        step_penalty: float = 0.0,
        success: str | None = None,
        render_mode: str | None = None,
    ) -> None:
        cfg = as_config(project_config() if config is None else config)
        if overrides:
            from simmer.config.overrides import with_overrides

            cfg = with_overrides(cfg, overrides)
        grippers = [s.id for s in cfg.devices if s.kind == "gripper"]
        if not grippers:
            raise BatchError(
                'the project environment needs a gripper ([drives.g0] type = "gripper", '
                "docs/project.md); this configuration has none"
            )
        if sensors is None:  # every ultrasonic sensor, read every step
            sensors = [s.id for s in cfg.devices if isinstance(s.params, UltrasonicParams)]
        from simmer.config.overrides import with_overrides

        cfg = with_overrides(cfg, {"simulate_list": list(sensors)})
        super().__init__(
            cfg,
            actions=actions,
            sensors=sensors,
            forward=forward,
            turn=turn,
            pose=pose,
            max_steps=max_steps,
            reach_reward=0.0,
            collision_penalty=0.0,
            step_penalty=step_penalty,
            success=success,
            render_mode=render_mode,
        )
        self.gripper = grippers[0]
        self.zones = tuple(sorted(self.sim.zones.dropoff))
        if not self.zones:
            raise BatchError(
                "the project environment needs drop-off zones ([zones], docs/project.md); "
                "this maze has none"
            )
        self.time_limit = cfg.settings.score.time_limit
        self.observation_space = self._space()
        from gymnasium import spaces

        self.action_space = (
            spaces.Discrete(len(PROJECT_MOVES))
            if actions == "discrete"
            else spaces.Box(-1.0, 1.0, (3,), dtype=np.float64)
        )
        self._score = 0.0

    def _space(self) -> Any:
        """The readings, then held (0 or 1) and the target's one-hot, then the pose."""
        from gymnasium import spaces

        box = self.task.observation_space()
        n = len(self.task.sensors)
        extra = 1 + len(self.zones)
        low = np.concatenate((box.low[:n], np.zeros(extra), box.low[n:]))
        high = np.concatenate((box.high[:n], np.ones(extra), box.high[n:]))
        return spaces.Box(low, high, dtype=np.float64)

    def _observe(self) -> np.ndarray:
        sim = self.sim
        base = super()._observe()
        n = len(self.task.sensors)
        target = np.array([zone == sim.scenario.target for zone in self.zones], dtype=np.float64)
        held = [1.0 if sim.block.held is not None else 0.0]
        return np.concatenate((base[:n], held, target, base[n:]))

    def _info(self) -> dict[str, Any]:
        info = super()._info()
        report = self._report()
        info["score"] = report.score if report is not None else 0.0
        info["target"] = self.sim.scenario.target
        return info

    def _report(self) -> Any:
        assert self.outcome is not None
        return self.outcome.project_report()

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start a new episode: a new scenario (block place and target) from the seed."""
        self._score = 0.0
        return super().reset(seed=seed, options=options)

    def _act(self, action: Any) -> None:
        """Run the action: moves through the task, the gripper's command after them."""
        sim = self.sim
        if self.task.actions == "discrete":
            move = PROJECT_MOVES[int(action)]
            moves, grip = ([], move) if move in ("close", "open") else (self.task.moves(action), "")
        else:
            a = np.clip(np.asarray(action, dtype=np.float64).reshape(3), -1.0, 1.0)
            moves = self.task.moves(a[:2])
            grip = "close" if a[2] > GRIP_THRESHOLD else "open" if a[2] < -GRIP_THRESHOLD else ""
        for drive, amount, frames in moves:
            sim.command(f"{drive}-{amount!r}")
            sim.step(frames)
        if grip:
            sim.command(f"{self.gripper}-{1 if grip == 'close' else 0}")
            sim.step()  # the sensors read once more (the held block is in their view)

    def _judge(self, before: int) -> tuple[float, bool, bool]:
        """The score's change (less the step's cost), delivered, and the time limit."""
        report = self._report()
        score = float(report.score) if report is not None else 0.0
        reward = score - self._score - self.task.step_penalty
        self._score = score
        delivered = bool(report is not None and report.delivered)
        return reward, delivered, self.sim.time >= self.time_limit
