"""``robot.show(points=...)`` with a LiDAR (issue 32): a scan placed at the program's estimate,
or its own map's points, drawn over the maze in the window, videos and replays."""

from __future__ import annotations

import numpy as np
import pygame

from simmer.client import Client, Scan
from simmer.devices.lidar import Lidar
from simmer.localize.belief import MAX_POINTS, BeliefBoard, parse_belief, read_belief
from simmer.runner import LocalLink
from simmer.ui.belief import POINTS_COLOR, paint_belief
from simmer.ui.render import PygameRenderer
from simmer.ui.scene import View
from simmer.world import Simulation

from helpers import default_data, make_config

QUIET = {"range_error": 0.0, "range_error_proportional": 0.0, "angular_jitter": 0.0,
         "dropout": 0.0, "motion_skew": False}  # fmt: skip


def mounted_sim() -> tuple[Simulation, Lidar]:
    """The default rover with a noise-free LiDAR off its centre and turned on the robot."""
    data = default_data()
    data["sensors"]["l0"] = {"type": "lidar", "position": [1.5, -2.0], "rotation": 30} | QUIET
    sim = Simulation(make_config(data), seed=4)
    device = sim.robot.devices["l0"]
    assert isinstance(device, Lidar)
    return sim, device


def test_a_scan_placed_at_the_true_pose_lands_where_the_beams_met_the_walls() -> None:
    sim, device = mounted_sim()
    sim.command("r0-37")
    sim.run_until_idle()
    number = device.number
    while device.number == number:  # a scan made where the robot stands still
        sim.step()
    robot = Client(LocalLink(sim), lockstep=True)
    scan = robot.scan("l0")
    assert np.array_equal(scan.distances, device.distances)
    pose = sim.robot.pose
    placed = scan.points(pose.x, pose.y, pose.heading, mount=(1.5, -2.0, 30.0))
    truth = device.points[~np.isnan(device.points[:, 0])]
    assert len(placed) == len(truth) > 150  # beams nearer than min_range return nothing
    assert np.allclose(placed, truth, atol=1e-6)
    off = scan.points(pose.x + 3, pose.y, pose.heading, mount=(1.5, -2.0, 30.0))
    assert np.allclose(off - placed, [3.0, 0.0])  # placed at an estimate 3 in off: 3 in off


def test_a_shown_scan_reaches_the_belief_rounded_and_bounded() -> None:
    sim, _ = mounted_sim()
    board = BeliefBoard()
    sim.add_observer(board)
    robot = Client(LocalLink(sim), lockstep=True)
    scan = robot.scan("l0")
    pose = sim.robot.pose
    points = scan.points(pose.x, pose.y, pose.heading, mount=(1.5, -2.0, 30.0))
    assert robot.show(points=points, pose=(pose.x, pose.y, pose.heading)) == 0
    assert board.belief is not None
    assert np.allclose(board.belief.points, points, atol=0.006)
    again, cut = parse_belief(board.belief.to_json())  # as a run's events keep it
    assert cut == 0
    assert np.array_equal(again.points, board.belief.points)

    many = np.column_stack((np.arange(MAX_POINTS + 7.0), np.zeros(MAX_POINTS + 7)))
    belief, cut = read_belief({"points": [*many.tolist(), [1.0, float("nan")]]})
    assert len(belief.points) == MAX_POINTS
    assert cut == 8


def test_shown_points_are_drawn_over_the_maze() -> None:
    belief, _ = read_belief({"points": [[10.0, 20.0], [50.0, 30.0]]})
    surface = pygame.Surface((800, 500))
    view = View(8.0, 0.0, 0.0)
    paint_belief(PygameRenderer(surface), view, belief, (96.0, 48.0))
    pixels = pygame.surfarray.array3d(surface)
    for x, y in ((10, 20), (50, 30)):
        px, py = (round(v) for v in view.point(x, y))
        assert tuple(pixels[px, py]) == POINTS_COLOR
    assert (pixels == POINTS_COLOR).all(axis=-1).sum() < 100  # two dots, nothing else
    assert isinstance(Scan(np.zeros(1), np.zeros(1), 1.0).points(0, 0, 0), np.ndarray)
