"""The project's scenario drawn from the seed: the same seed gives the same scenario, each part has
its own stream, every drawn start and block is valid."""

from __future__ import annotations

import pytest

from simmer import Simulation
from simmer.config.scenario import robot_fits
from simmer.errors import ConfigError
from simmer.geometry import polygon_hits_grid

from helpers import make_config, project_data, project_sim


@pytest.mark.slow
def test_the_same_seed_gives_the_same_scenario_and_seeds_differ() -> None:
    a = project_sim(seed=7, start="random")
    b = project_sim(seed=7, start="random")
    assert a.scenario == b.scenario
    a.reset()
    assert a.scenario == b.scenario  # a reset draws the same again
    drawn = {project_sim(seed=s, start="random").scenario for s in range(30)}
    assert len({s.start for s in drawn}) > 5
    assert len({s.block for s in drawn}) == 30
    assert {s.target for s in drawn} == {"B1", "B2", "B3", "B4"}


def test_each_part_has_its_own_stream() -> None:
    # naming the target outright leaves the start and block draws as they were
    a = project_sim(seed=3, start="random", target="random")
    b = project_sim(seed=3, start="random", target="B4")
    assert a.scenario.start == b.scenario.start
    assert a.scenario.block == b.scenario.block


@pytest.mark.slow
@pytest.mark.parametrize("where", ["random", "open"])
def test_every_drawn_start_and_block_is_valid(where: str) -> None:
    config = make_config(project_data(start=where))
    settings = config.settings
    for seed in range(200):
        sim = Simulation(config, seed=seed)
        pose = sim.scenario.start
        assert pose.heading in (0.0, 90.0, 180.0, 270.0)
        assert robot_fits(settings, sim.maze, *pose), (seed, pose)
        block = sim.block
        maze = sim.maze
        assert not polygon_hits_grid(block.polygon, maze.hwall, maze.vwall, maze.solid, maze.cell)
        assert sim.zones.in_loading(block.x, block.y)
        if where == "random":
            assert not sim.zones.in_loading(pose.x, pose.y)
        # the robot fits where it starts: a step of no motion is not blocked
        assert sim.place_robot(*pose)


@pytest.mark.parametrize(
    ("scenario", "key", "words"),
    [
        ({"start": "0,4"}, "scenario.start", "cell [0, 4] is solid"),
        ({"start": "7,2"}, "scenario.start", "outside the maze"),
        ({"start": "here"}, "scenario.start", "not a cell"),
        ({"target": "B9"}, "scenario.target", "no drop-off zone 'B9'; the zones are B1, B2"),
        ({"block": "0,0"}, "scenario.block", "overlaps a wall"),
        ({"block": "six"}, "scenario.block", "not a place"),
    ],
)
def test_bad_scenario_overrides_get_plain_errors(
    scenario: dict[str, str], key: str, words: str
) -> None:
    with pytest.raises(ConfigError) as caught:
        make_config(project_data(**scenario))
    text = str(caught.value)
    assert key in text, text
    assert words in text, text


def test_a_named_start_and_block() -> None:
    sim = project_sim(start="3,5,90", block="6,8", target="B2")
    assert tuple(sim.scenario.start) == (66.0, 42.0, 90.0)
    assert (sim.block.x, sim.block.y) == (6.0, 8.0)
    assert sim.scenario.target == "B2"
