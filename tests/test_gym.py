"""simmer.gym (issue 36): the registered environments pass Gymnasium's checker, are seeded as
Gymnasium specifies, pickle, take keyword overrides; the vector environment is the single one
robot for robot, with autoreset on the next step."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")
from gymnasium.utils.env_checker import check_env  # noqa: E402

import simmer.gym  # noqa: E402
from simmer.errors import ConfigError, SweepError  # noqa: E402
from simmer.gym import ENVIRONMENTS, MazeEnv, MazeVectorEnv, ProjectEnv  # noqa: E402

from helpers import EXAMPLES  # noqa: E402

SHAPES = {"SimMeR/Maze-v0": 7, "SimMeR/Lab1-v0": 7, "SimMeR/Project-v0": 13}
"""Observations with ``pose=True``: four sensors and the pose; the project's five sensors,
whether the block is held, the target among four zones, and the pose."""


def rollout(env, seed: int, actions) -> list[tuple]:
    obs, _ = env.reset(seed=seed)
    out = [(obs.copy(), 0.0, False, False)]
    for action in actions:
        obs, reward, terminated, truncated, _ = env.step(action)
        out.append((obs.copy(), reward, terminated, truncated))
        if terminated or truncated:
            break
    return out


@pytest.mark.parametrize("env_id", sorted(ENVIRONMENTS))
@pytest.mark.parametrize("actions", ["discrete", "continuous"])
def test_every_registered_environment_passes_the_checker(env_id: str, actions: str) -> None:
    env = gym.make(env_id, actions=actions, pose=True, max_steps=20)
    check_env(env.unwrapped, skip_render_check=True)
    assert env.observation_space.shape == (SHAPES[env_id],)


@pytest.mark.parametrize("env_id", sorted(ENVIRONMENTS))
def test_the_same_seed_gives_the_same_trajectory(env_id: str) -> None:
    env = gym.make(env_id, max_steps=30)
    actions = np.random.default_rng(0).integers(0, 4, 30)
    first = rollout(env, 11, actions)
    second = rollout(env, 11, actions)
    assert len(first) == len(second) > 1
    for a, b in zip(first, second, strict=True):
        np.testing.assert_array_equal(a[0], b[0])
        assert a[1:] == b[1:]
    other = rollout(env, 12, actions)
    if env_id == "SimMeR/Lab1-v0":  # noise on: another seed reads otherwise
        assert not all(np.array_equal(a[0], b[0]) for a, b in zip(first, other, strict=False))


@pytest.mark.parametrize(
    ("env_id", "kwargs"),
    [("SimMeR/Lab1-v0", {}), ("SimMeR/Project-v0", {"success": "score > 20"})],
)
def test_an_environment_pickles_and_goes_on_as_before(env_id: str, kwargs: dict) -> None:
    """The copy goes on identically (the project's with its run outcome, which the reward
    and the success condition read)."""
    env = gym.make(env_id, **kwargs)
    env.reset(seed=3)
    env.step(0)
    copy = pickle.loads(pickle.dumps(env))
    for action in (0, 2, 0, 3, 1, 0):
        a = env.step(action)
        b = copy.step(action)
        np.testing.assert_array_equal(a[0], b[0])
        assert a[1:4] == b[1:4]


def test_keyword_overrides_reach_the_configuration() -> None:
    env = gym.make("SimMeR/Maze-v0", overrides={"sensors.u0.max_range": 20.0}, forward=2.0)
    inner = env.unwrapped
    assert isinstance(inner, MazeEnv)
    assert inner.task.config.settings is not None
    assert inner.task.forward == 2.0
    obs, _ = env.reset(seed=0)
    assert obs[0] <= 20.0
    with pytest.raises(ConfigError, match=r"sensors\.u0"):
        gym.make("SimMeR/Maze-v0", overrides={"sensors.u0.max_range": -1})


def test_bad_options_say_what_to_fix() -> None:
    with pytest.raises(Exception, match="gym_max_steps"):
        MazeEnv(max_steps=0)
    with pytest.raises(Exception, match=r"'discrete' or 'continuous'"):
        MazeEnv(actions="joystick")  # type: ignore[arg-type]


def test_reaching_the_block_ends_the_episode_with_the_reward() -> None:
    """With the block put ahead of the robot, driving forward reaches it."""
    env = MazeEnv(max_steps=100, overrides={"block_position": [6.0, 20.0]})
    _, info = env.reset(seed=0)
    terminated = False
    for _ in range(100):
        before = info["collisions"]
        _, reward, terminated, truncated, info = env.step(0)
        if terminated or truncated:
            break
    assert terminated, "driving straight at the block never reached it"
    bumped = info["collisions"] - before  # its last 3 in move ran into the block
    assert reward == pytest.approx(10.0 - 1.0 * bumped - 0.01)
    assert env.sim.robot.pose.y < 32.0  # it drove there (it started at y = 42)


@pytest.mark.slow  # pygame's fonts and the first frame: about 2 CPU seconds
def test_rgb_array_is_the_off_screen_frame() -> None:
    env = MazeEnv(render_mode="rgb_array")
    env.reset(seed=0)
    frame = env.render()
    assert frame is not None
    assert frame.ndim == 3
    assert frame.shape[2] == 3
    assert frame.dtype == np.uint8
    assert len(np.unique(frame.reshape(-1, 3), axis=0)) > 3  # maze, floor, robot drawn


def test_the_vector_environment_is_the_single_one_robot_for_robot() -> None:
    n = 6
    envs = MazeVectorEnv(n, overrides=simmer.gym.LAB_NOISE, pose=True, max_steps=15)
    singles = [MazeEnv(overrides=simmer.gym.LAB_NOISE, pose=True, max_steps=15) for _ in range(n)]
    obs, _ = envs.reset(seed=100)
    for i, env in enumerate(singles):
        single_obs, _ = env.reset(seed=100 + i)
        np.testing.assert_array_equal(obs[i], single_obs)
    rng = np.random.default_rng(5)
    for _ in range(15):
        actions = rng.integers(0, 4, n)
        obs, rewards, terminated, truncated, _ = envs.step(actions)
        for i, env in enumerate(singles):
            s_obs, s_reward, s_term, s_trunc, _ = env.step(int(actions[i]))
            np.testing.assert_array_equal(obs[i], s_obs)
            assert rewards[i] == pytest.approx(s_reward, abs=0)
            assert (terminated[i], truncated[i]) == (s_term, s_trunc)
    assert truncated.any()


def test_autoreset_comes_on_the_next_step() -> None:
    envs = MazeVectorEnv(3, max_steps=2)
    obs, _ = envs.reset(seed=1)
    start = obs.copy()
    envs.step(np.array([0, 0, 0]))
    _, _, _, truncated, _ = envs.step(np.array([0, 0, 0]))
    assert truncated.all()
    obs, rewards, terminated, truncated, _ = envs.step(np.array([0, 0, 0]))
    # the next step resets: the start's readings again, reward 0, neither flag set
    np.testing.assert_array_equal(rewards, 0.0)
    assert not terminated.any()
    assert not truncated.any()
    np.testing.assert_array_equal(obs, start)  # no noise in the default: the same start


def test_make_vec_uses_the_batched_environment() -> None:
    envs = gym.make_vec("SimMeR/Maze-v0", num_envs=4, vectorization_mode="vector_entry_point")
    assert isinstance(envs.unwrapped, MazeVectorEnv)
    obs, _ = envs.reset(seed=0)
    assert obs.shape == (4, 4)
    assert envs.action_space.shape == (4,)


# ----------------------------------------------------------------- the project's task

PROJECT_HERE = {  # the block ahead of the lab's start, the zone ahead of it: a short delivery
    "zones.loading": [[3, 0], [2, 0]],
    "zones.dropoff": {"B1": [[1, 0]]},
    "scenario.block": "6,32",
    "scenario.target": "B1",
}


def test_the_project_pays_its_score_as_milestones_come_and_ends_on_delivery() -> None:
    """Drive up to the block, close the jaws, carry it out of the loading zone into B1, open:
    each milestone pays the rubric's points on its step, the rewards add up to the run's
    project score, and delivering ends the episode."""
    env = ProjectEnv(overrides=PROJECT_HERE, pose=True)
    obs, info = env.reset(seed=0)
    assert info["target"] == "B1"
    assert list(obs[5:7]) == [0.0, 1.0]  # not held; the target, one-hot over B1
    plan = [0, 0, 4, 0, 0, 0, 0, 0, 0, 5]  # forward x2, close, forward x6, open
    rewards, held = [], []
    for action in plan:
        obs, reward, terminated, truncated, info = env.step(action)
        rewards.append(reward)
        held.append(obs[5])
        assert not truncated
    assert terminated
    # entered at the start (paid on the first step), picked up, left holding it, delivered
    assert rewards == [10.0, 0.0, 20.0, 0.0, 0.0, 0.0, 10.0, 0.0, 0.0, 60.0]
    assert held == [0.0, 0.0] + [1.0] * 7 + [0.0]
    assert env.outcome is not None
    report = env.outcome.project_report()
    assert report is not None
    assert report.delivered
    assert sum(rewards) == report.score == info["score"] == 100.0


def test_collisions_cost_the_rubrics_points_and_the_time_limit_truncates() -> None:
    env = ProjectEnv(overrides={**PROJECT_HERE, "score.time_limit": 3.0}, max_steps=50)
    env.reset(seed=0)
    rewards, truncated, terminated = [], False, False
    while not (truncated or terminated):
        _, reward, terminated, truncated, _ = env.step(1)  # backward, into the wall behind
        rewards.append(reward)
    assert truncated
    assert not terminated
    assert env.sim.time >= 3.0  # the time limit, not max_steps
    assert len(rewards) < 50
    collisions = env.sim.collisions
    assert collisions > 0
    assert sum(rewards) == pytest.approx(10.0 - 2.0 * collisions)


def test_the_project_environment_says_what_it_needs() -> None:
    with pytest.raises(Exception, match="needs a gripper"):
        ProjectEnv(EXAMPLES / "lab1_rover.toml")


def test_the_project_environment_steps_as_single_ones_in_make_vec() -> None:
    envs = gym.make_vec("SimMeR/Project-v0", num_envs=2)
    obs, _ = envs.reset(seed=4)
    assert obs.shape == (2, 10)
    obs, rewards, *_ = envs.step(np.array([0, 2]))
    assert rewards.shape == (2,)


# ----------------------------------------------------------------- a success condition


def test_a_success_condition_pays_1_and_ends_the_episode_when_it_becomes_true() -> None:
    env = MazeEnv(success="path_length > 5 and collisions == 0")
    env.reset(seed=0)
    _, reward, terminated, truncated, _ = env.step(0)  # 3 in
    assert (reward, terminated, truncated) == (0.0, False, False)
    _, reward, terminated, truncated, _ = env.step(0)  # 6 in
    assert (reward, terminated, truncated) == (1.0, True, False)


def test_a_project_success_condition_names_the_milestones() -> None:
    env = ProjectEnv(overrides=PROJECT_HERE, success="picked_up and not delivered")
    env.reset(seed=0)
    steps = [env.step(action)[1:3] for action in (0, 0, 4)]
    assert steps == [(0.0, False), (0.0, False), (1.0, True)]


def test_a_bad_success_condition_is_refused_before_the_first_step() -> None:
    with pytest.raises(SweepError, match="'reachd' is not one of"):
        MazeEnv(success="reachd")
    with pytest.raises(SweepError, match="not allowed"):
        gym.make("SimMeR/Maze-v0", success="__import__('os')")
    with pytest.raises(Exception, match="vectorization_mode"):
        MazeVectorEnv(2, success="reached")
