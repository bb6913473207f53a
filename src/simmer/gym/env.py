"""``SimMeR/Maze-v0``: one robot in one maze as a Gymnasium environment, over a
:class:`~simmer.Simulation` (so it runs any configuration, and renders)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any, ClassVar

import gymnasium
import numpy as np

from simmer.config.models import SimConfig
from simmer.gym.task import Actions, Task
from simmer.world.outcome import Outcome
from simmer.world.simulation import Simulation

SEED_RANGE = 2**63
"""Simulation seeds are drawn from [0, 2**63) by the environment's own generator."""


class MazeEnv(gymnasium.Env[np.ndarray, Any]):
    """Drive the robot to the block: observations are the sensors' readings (and with
    ``pose=True`` the true pose), actions drive commands, the reward is reaching the block
    (``reach_reward``) less ``collision_penalty`` per collision and ``step_penalty`` per step;
    an episode ends on reaching the block or after ``max_steps`` actions (truncated).
    With ``success`` (a condition over the run's outcome, as ``simmer sweep``'s ``success``)
    the reward is 1 on the step it becomes true, which ends the episode, and 0 otherwise.

    ``config``: a configuration file, a :class:`~simmer.SimConfig` or None (the built-in
    default). See docs/gym.md for every option.
    """

    metadata = {"render_modes": ["rgb_array", "human"], "render_fps": 10}  # noqa: RUF012
    keeps_outcome: ClassVar[bool] = False
    """Whether the run's :class:`~simmer.world.outcome.Outcome` follows every episode (it does
    whenever ``success`` is given)."""

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
        max_steps: int = 200,
        reach_reward: float = 10.0,
        collision_penalty: float = 1.0,
        step_penalty: float = 0.01,
        success: str | None = None,
        render_mode: str | None = None,
    ) -> None:
        if success is not None:
            from simmer.sweep.success import success_condition

            success_condition(success)  # a bad condition: SweepError naming what to fix
        self.success = success
        self.task = Task.of(
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
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode is 'rgb_array', 'human' or None, not {render_mode!r}")
        self.render_mode = render_mode
        self.observation_space = self.task.observation_space()
        self.action_space = self.task.action_space()
        self.sim = Simulation(self.task.config, seed=0)
        self.outcome = (
            Outcome.attach(self.sim) if self.keeps_outcome or success is not None else None
        )
        self._steps = 0
        self._window: Any = None

    def _observe(self) -> np.ndarray:
        sim = self.sim
        readings = [getattr(sim.robot.devices[s], "reading", np.nan) for s in self.task.sensors]
        return self.task.observe(np.array(readings), np.array(sim.robot.pose))

    def _info(self) -> dict[str, Any]:
        sim = self.sim
        return {"pose": np.array(sim.robot.pose), "collisions": sim.collisions, "seed": sim.seed}

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start a new episode; the simulation's seed comes from the environment's generator
        (``seed`` seeds that generator, as Gymnasium specifies)."""
        super().reset(seed=seed)
        self.sim.reset(seed=int(self.np_random.integers(SEED_RANGE)))
        self._steps = 0
        self.sim.step()  # one step reads the sensors, as a batch's reset does
        if self.render_mode == "human":
            self.render()
        return self._observe(), self._info()

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Execute the action's drive commands, each followed by the frames it needs."""
        before = self.sim.collisions
        self._act(action)
        self._steps += 1
        reward, terminated, time_up = self._judge(before)
        if self.success is not None:
            terminated = self._succeeded()
            reward = 1.0 if terminated else 0.0
        truncated = not terminated and (time_up or self._steps >= self.task.max_steps)
        if self.render_mode == "human":
            self.render()
        return self._observe(), reward, terminated, truncated, self._info()

    def _act(self, action: Any) -> None:
        """Run the action's drive commands, each followed by the frames it takes."""
        sim = self.sim
        for drive, amount, frames in self.task.moves(action):
            sim.command(f"{drive}-{amount!r}")
            sim.step(frames)

    def _judge(self, before: int) -> tuple[float, bool, bool]:
        """The step's reward, whether the task is done, and whether time is up (never: only
        ``max_steps`` truncates this task); ``before``: the collisions before the step."""
        sim = self.sim
        pose = np.array(sim.robot.pose)
        block = np.array([[sim.block.x, sim.block.y]])
        reached = bool(self.task.reached(pose, block)[0])
        return float(self.task.reward(reached, sim.collisions - before)), reached, False

    def _succeeded(self) -> bool:
        """Whether the success condition holds over the run's outcome so far (the evaluator
        ``simmer sweep`` uses, over the same fields)."""
        from simmer.sweep.success import flat_outcome, success_condition

        assert self.outcome is not None
        assert self.success is not None
        return success_condition(self.success)(flat_outcome(self.outcome.report().as_dict()))

    def render(self) -> np.ndarray | None:
        """``rgb_array``: the off-screen renderer's frame (H, W, 3); ``human``: show it in a
        window."""
        if self.render_mode is None:
            return None
        from simmer.ui.frames import FrameWindow, frame_pixels

        if self.render_mode == "rgb_array":
            return frame_pixels(self.sim)
        if self._window is None:
            self._window = FrameWindow()
        self._window.show(self.sim)
        return None

    def close(self) -> None:
        """Close the window, if one is open."""
        if self._window is not None:
            self._window.close()
            self._window = None

    def __getstate__(self) -> dict[str, Any]:
        """Pickle without the window (a new one opens when rendered)."""
        state = self.__dict__.copy()
        state["_window"] = None
        return state
