"""The gripper (``g0-1`` closes, ``g0-0`` opens): it holds a block only between its jaws, and a
carried block collides and is seen as part of the robot."""

from __future__ import annotations

import math
from typing import Any

import pytest

from link_support import serving, two_port_raw, two_port_send
from simmer import Simulation
from simmer.config.models import SimConfig
from simmer.geometry import polygon_hits_grid

from helpers import make_config, project_data, project_sim


def block_at(x: float, y: float) -> Simulation:
    return project_sim(block=f"{x},{y}", target="B1")


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
    values, (answer,) = sim.replies(sim.parse("g0-2"), "g0-2")
    assert math.isnan(values[0])
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
