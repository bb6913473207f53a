"""The course project: zones, the scenario drawn from the seed, the gripper, milestones, score."""

from __future__ import annotations

import copy
import math
import tomllib
from typing import Any

import pytest

from link_support import serving, two_port_raw, two_port_send
from simmer import Simulation
from simmer.config.models import SimConfig
from simmer.config.scenario import robot_fits
from simmer.config.zones import Zones
from simmer.errors import ConfigError
from simmer.geometry import polygon_hits_grid
from simmer.record.runfolder import project_lines
from simmer.world.outcome import Outcome

from helpers import EXAMPLES, make_config

PROJECT = EXAMPLES / "project.toml"
START = (6.0, 42.0)  # heading 180: facing -y; the jaws' back is at y = 38, x from 4 to 8


def project_data(**scenario: str) -> dict[str, Any]:
    """examples/project.toml as data, with scenario settings replaced."""
    data = tomllib.loads(PROJECT.read_text(encoding="utf-8"))
    data = copy.deepcopy(data)
    data["scenario"].update(scenario)
    return data


def project_sim(seed: int = 1, **scenario: str) -> Simulation:
    return Simulation(make_config(project_data(**scenario)), seed=seed)


def block_at(x: float, y: float) -> Simulation:
    return project_sim(block=f"{x},{y}", target="B1")


# ----------------------------------------------------------------------------- zones


def test_project_convention_zones_of_the_default_maze() -> None:
    zones = Zones.from_settings(make_config(project_data()).settings)
    assert zones.loading is not None
    assert zones.loading.cells == ((0, 0), (0, 1), (1, 0), (1, 1))
    assert {name: z.cells for name, z in zones.dropoff.items()} == {
        "B1": ((0, 5),),
        "B2": ((0, 7),),
        "B3": ((2, 2),),
        "B4": ((3, 7),),
    }
    assert (3, 0) in zones.start
    assert (0, 0) not in zones.start
    assert (0, 5) not in zones.start


def test_lab2023_convention_and_named_zones() -> None:
    data = project_data()
    data["zones"] = {"convention": "lab2023"}
    zones = Zones.from_settings(make_config(data).settings)
    assert zones.loading is not None
    assert zones.loading.cells == ((0, 5), (0, 7), (2, 2), (3, 7))
    assert list(zones.dropoff) == ["D1"]
    assert zones.start == ((0, 0), (0, 1), (1, 0), (1, 1))
    data["zones"] = {"loading": [[3, 0]], "dropoff": {"HOME": [[3, 1], [3, 2]]}}
    data["scenario"]["target"] = "HOME"
    zones = Zones.from_settings(make_config(data).settings)
    assert zones.loading is not None
    assert zones.loading.cells == ((3, 0),)
    assert zones.dropoff["HOME"].contains(30.0, 40.0, 12.0)


@pytest.mark.parametrize(
    ("zones", "key", "words"),
    [
        ({"loading": [[9, 0]]}, "zones.loading[0]", "outside the maze"),
        ({"dropoff": {"B1": [[0, 4]]}}, "zones.dropoff.B1[0]", "is solid"),
        ({"dropoff": {"B-1": [[0, 5]]}}, "zones.dropoff", "letters or digits"),
        ({"convention": "2025"}, "zones.convention", "project"),
    ],
)
def test_bad_zones_are_named_plainly(zones: dict[str, Any], key: str, words: str) -> None:
    data = project_data()
    data["zones"] = zones
    with pytest.raises(ConfigError) as caught:
        make_config(data)
    text = str(caught.value)
    assert key in text
    assert words in text


# ----------------------------------------------------------------------------- scenario


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


# ----------------------------------------------------------------------------- gripper
# The project rover starts at [6, 42] facing -y; its mouth (and the jaws) spans x 4 to 8 and
# y 41 (the jaws' back) to 38 (the robot's front edge).


def small_block_at(x: float, y: float) -> Simulation:
    """A 2 in block and jaws 1.8 in apart, so the block's centre can reach the jaws' sides."""
    data = project_data(block=f"{x},{y}", target="B1")
    data["block_size"] = 2.0
    data["drives"]["g0"]["opening"] = 1.8
    return Simulation(make_config(data), seed=1)


@pytest.mark.parametrize(
    ("x", "y", "holds"),
    [
        (6.0, 39.0, True),  # centred, 2 in into the 3 in jaws
        (6.9, 39.0, True),  # centre exactly on a jaw: edges count
        (5.1, 38.0, True),  # on the other jaw, at its tip
        (6.95, 39.0, False),  # just outside a jaw
        (6.0, 37.9, False),  # beyond the tips
    ],
)
def test_closing_picks_the_block_up_only_between_the_jaws(x: float, y: float, holds: bool) -> None:
    sim = small_block_at(x, y)
    assert sim.command("g0-1") == [1.0 if holds else 0.0]
    assert (sim.block.held is not None) is holds
    assert sim.command("g0-1") == [1.0 if holds else 0.0]  # closing again changes nothing


def test_jaws_closed_on_nothing_grip_nothing_until_opened() -> None:
    sim = block_at(6.0, 30.0)
    assert sim.command("g0-1") == [0.0]  # closed on air
    sim.command("w0-12")
    sim.run_until_idle()  # the block is now between the closed jaws
    assert sim.command("g0-1") == [0.0]
    assert sim.command("g0-0,g0-1") == [0.0, 1.0]


def test_bad_gripper_values_answer_nan() -> None:
    sim = block_at(6.0, 39.0)
    (answer,) = sim.answer(sim.parse("g0-2"), "g0-2")
    assert math.isnan(answer.value)
    assert answer.why is not None
    assert "1 closes, 0 opens" in answer.why


def test_picking_up_while_moving_and_carrying_it() -> None:
    sim = block_at(6.0, 30.0)  # 11 in ahead of the jaws' back
    sim.command("w0-24")
    sim.step(30)  # half a second: 3 in, the block not yet between the jaws
    assert sim.command("g0-1") == [0.0]
    sim.command("g0-0")
    sim.step(100)  # the block is in the mouth, the robot stopped against it, the drive busy
    assert sim.robot.any_drive_moving
    assert sim.collisions == 1
    assert sim.command("g0-1") == [1.0]
    held = sim.block.held
    gap = sim.robot.pose.y - sim.block.y
    stopped_at = sim.robot.pose.y
    sim.run_until_idle()  # the rest of the 24 in (less the blocked steps'), with the block
    assert sim.robot.pose.y < stopped_at - 5.0
    assert sim.robot.pose.y - sim.block.y == pytest.approx(gap)
    assert sim.block.x == 6.0
    assert sim.block.held == held
    sim.command("r0-90")  # it turns with the robot (clockwise): now facing +x
    sim.run_until_idle()
    assert sim.robot.pose.heading == pytest.approx(270.0)
    assert sim.collisions == 1
    assert sim.block.x == pytest.approx(sim.robot.pose.x + gap)
    assert sim.block.y == pytest.approx(sim.robot.pose.y)


def carried_into_the_top_wall() -> Simulation:
    sim = block_at(6.0, 38.0)  # at the jaws' tips: half of it sticks out of the mouth
    assert sim.command("g0-1") == [1.0]
    sim.command("w0-40")  # up the open column 0 into the maze's top edge
    sim.run_until_idle()
    return sim


def test_a_carried_block_collides_with_a_wall_before_the_robot() -> None:
    sim = carried_into_the_top_wall()
    assert sim.collisions == 1
    top = sim.block.polygon[:, 1].min()
    assert 0.0 < top < 0.2  # the block stopped at the wall, within one step
    robot_front = sim.robot.polygon()[:, 1].min()
    assert robot_front == pytest.approx(top + 1.5)  # the robot itself never reached it
    maze = sim.maze
    assert not polygon_hits_grid(sim.block.polygon, maze.hwall, maze.vwall, maze.solid, maze.cell)


def test_a_carried_block_blocks_a_turn_into_a_wall() -> None:
    sim = carried_into_the_top_wall()
    sim.command("r0-90")
    sim.run_until_idle()
    assert sim.collisions == 2  # the block's corner soon cuts into the top wall
    assert 180.0 < sim.robot.pose.heading < 190.0
    assert sim.block.polygon[:, 1].min() > 0.0


def test_release_leaves_the_block_where_it_is_and_it_is_an_obstacle_again() -> None:
    sim = block_at(6.0, 39.0)
    sim.command("g0-1")
    sim.command("w0-12")
    sim.run_until_idle()
    x, y = sim.block.x, sim.block.y
    assert y == pytest.approx(27.0)
    assert sim.command("g0-0") == [0.0]
    sim.command("w0--6")
    sim.run_until_idle()
    assert (sim.block.x, sim.block.y) == (x, y)
    assert sim.block.held is None
    sim.command("w0-12")  # forward again: stopped by the block, never pushing it
    sim.run_until_idle()
    assert (sim.block.x, sim.block.y) == (x, y)
    assert sim.collisions == 1


def test_the_low_sensor_sees_a_carried_block_and_the_high_one_does_not() -> None:
    sim = block_at(6.0, 39.0)
    sim.command("g0-1")
    high, low = sim.command("u0,u4")
    assert low == pytest.approx(41.0 - 40.5)  # from the sensor to the block's near face
    assert high == pytest.approx(41.0)  # over the block to the top wall


def project_config(**settings: object) -> SimConfig:
    return make_config({**project_data(block="6,39", target="B1"), **settings})


@pytest.mark.parametrize(
    ("settings", "width"),
    [({"reply_bytes": 8}, 8), ({"reply_bytes": 4}, 4)],
    ids=["v1.0 8-byte", "v1.1 4-byte"],
)
def test_gripper_replies_packed(settings: dict[str, Any], width: int) -> None:
    sim = Simulation(project_config(**settings), seed=1)
    with serving(sim) as (_, link):
        assert two_port_send(link, b"g0-0", width) == [0.0]
        assert two_port_send(link, b"g0-1", width) == [1.0]
        raw = two_port_raw(link, b"g0-1")
        assert len(raw) == width
        assert two_port_send(link, b"g0-0,g0-0", width) == [0.0, 0.0]


def test_gripper_replies_framed_v12() -> None:
    sim = Simulation(project_config(protocol="framed"), seed=1)
    with serving(sim) as (_, link):
        assert two_port_raw(link, b"[g0:0]") == b"[g0:False]"
        assert two_port_raw(link, b"[g0:1]") == b"[g0:True]"
        assert two_port_raw(link, b"[g0:1,u4]") == b"[g0:True,u4:0.5]"
        assert two_port_raw(link, b"[g0:0]") == b"[g0:False]"


# ----------------------------------------------------------------------------- milestones


DELIVER_TO_B3 = ["w0-25", "g0-1", "w0--25", "r0-90", "w0-24", "r0--90", "w0-6", "g0-0"]
"""From the lab's start: up into the loading zone around a block at [6, 14], back to the
bottom row, right two cells, up into B3 (cell [2, 2]) and let go."""


@pytest.mark.parametrize(("target", "score"), [("B3", 100.0), ("B1", 50.0)])
def test_milestones_and_score_of_a_delivery(target: str, score: float) -> None:
    sim = project_sim(block="6,14", target=target)
    outcome = Outcome.attach(sim)
    times = []
    for message in DELIVER_TO_B3:
        sim.command(message)
        sim.run_until_idle()
        times.append(sim.time)
    project = outcome.report().project
    assert project is not None
    assert project.target == target
    assert sim.collisions == 0
    assert sim.zones.dropoff_at(sim.block.x, sim.block.y) == "B3"
    assert project.entered_loading
    assert project.picked_up
    assert project.left_loading
    assert project.entered_loading_at is not None
    assert project.entered_loading_at < times[0]
    assert project.picked_up_at == times[0]  # the command at the end of the first move
    assert project.left_loading_at is not None
    assert times[1] < project.left_loading_at < times[2]
    assert project.delivered is (target == "B3")
    assert project.delivered_at == (times[-1] if target == "B3" else None)
    assert project.wrong_zone == (None if target == "B3" else "B3")
    assert project.score == score
    line = outcome.report().summary()
    assert f"project (target {target})" in line
    assert f"score {score:g}" in line
    flat = outcome.report().as_dict()
    assert flat["delivered"] is (target == "B3")
    assert flat["score"] == score


def test_collisions_and_the_time_limit_cost_points() -> None:
    data = project_data(block="6,14", target="B3")
    data["score"] = {"collision": -5, "time_limit": 10}
    sim = Simulation(make_config(data), seed=1)
    outcome = Outcome.attach(sim)
    sim.command("w0--10")  # backwards into the bottom wall
    sim.run_until_idle()
    assert sim.place_robot(6.0, 42.0, 180.0)  # back to the start, by hand
    for message in DELIVER_TO_B3:
        sim.command(message)
        sim.run_until_idle()
    project = outcome.report().project
    assert project is not None
    assert project.delivered
    assert project.left_loading_at is not None
    assert project.left_loading_at < 10
    assert project.delivered_at is not None
    assert project.delivered_at > 10
    assert project.score == 10 + 20 + 10 - 5  # the delivery came too late; one collision


def test_a_lab1_run_has_no_project_in_its_outcome() -> None:
    sim = Simulation.from_config(EXAMPLES / "lab1_rover.toml")
    outcome = Outcome.attach(sim)
    sim.step()
    report = outcome.report()
    assert report.project is None
    assert "project" not in report.summary()
    assert "score" not in report.as_dict()


def test_report_md_project_lines_take_only_what_is_well_formed() -> None:
    outcome = {"entered_loading_at": 4.5, "picked_up_at": "soon", "score": 30.0}
    good = project_lines(outcome, {"start": [6, 42, 180], "block": [7.25, 8.5], "target": "B2"})
    assert "Started at [6, 42] heading 180 deg; the block at [7.25, 8.50]; target zone B2." in good
    assert "| Entered the loading zone | 4.50 s |" in good
    assert "| Picked up the block | no |" in good  # not a number: said as not met
    assert "**Score: 30** (the rubric is in the manifest)." in good
    hostile = project_lines({"score": "x", "wrong_zone": 5}, {"start": "here", "block": None})
    assert not any("Started" in line or "Score" in line or "another" in line for line in hostile)
