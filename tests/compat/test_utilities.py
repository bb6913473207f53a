"""SimMeR's utilities helpers for users' device classes, and what those classes can read.

Unit tests check each helper against hand-computed values; the fixture ``tof_device`` is a
config.py whose own time-of-flight sensor (``devices/tof.py``) is written as a student would,
and whose probe (``devices/probe.py``) calls every helper from inside a simulation.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from simmer import Simulation
from simmer.compat import utilities
from simmer.compat.standins import UTILITIES, Vector2
from simmer.compat.template import Environment, config_values
from simmer.config.maze import Maze
from simmer.config.models import Settings

from helpers import SIMMER_PY

TOF_CONFIG = SIMMER_PY / "tof_device" / "config.py"
WALLS = Settings().walls  # SimMeR's default maze, 8 x 4 cells of 12 in
CELL = 12.0


@pytest.fixture
def default_maze_config() -> Iterator[None]:
    """``CONFIG`` holding the default maze, as the adapter sets it while a device runs."""
    saved = utilities.CONTEXT.config
    utilities.CONTEXT.config = SimpleNamespace(walls=WALLS, wall_segment_length=CELL)
    yield
    utilities.CONTEXT.config = saved


def segment_set(segments: list[list[Any]]) -> set[tuple[float, ...]]:
    """Segments as a set of (x1, y1, x2, y2), each with its smaller end first."""
    found = set()
    for a, b in segments:
        ends = sorted([(float(a[0]), float(a[1])), (float(b[0]), float(b[1]))])
        found.add((*ends[0], *ends[1]))
    return found


def flat(points: list[tuple[float, float]]) -> list[float]:
    """Points sorted, then flattened to one list of numbers (for ``pytest.approx``)."""
    return [value for point in sorted(points) for value in point]


def square(x: float, y: float, side: float) -> list[list[Vector2]]:
    """The four edges of a square, corner to corner clockwise on screen."""
    c = [Vector2(x, y), Vector2(x + side, y), Vector2(x + side, y + side), Vector2(x, y + side)]
    return [[c[i], c[(i + 1) % 4]] for i in range(4)]


# ----------------------------------------------------------------------------- the module


def test_stand_in_module_offers_every_helper() -> None:
    offered = {name for name in vars(UTILITIES) if not name.startswith("_")}
    assert offered == set(utilities.__all__)
    assert UTILITIES.collision is utilities.collision
    with pytest.raises(AttributeError, match="closest_fast"):
        _ = UTILITIES.draw_ray


# ----------------------------------------------------------------------------- add_error


def test_add_error_without_error_or_bounds_is_the_value() -> None:
    assert utilities.add_error(7.25, 0) == 7.25
    assert utilities.add_error(7.25, 0, []) == 7.25


def test_add_error_clamps_to_bounds() -> None:
    assert utilities.add_error(10, 0, [0, 5]) == 5
    assert utilities.add_error(-3, 0, [0, 5]) == 0


def test_add_error_draws_from_the_context_generator() -> None:
    saved = utilities.CONTEXT.rng
    try:
        utilities.CONTEXT.rng = np.random.default_rng(3)
        noisy = [utilities.add_error(20, 0.1, sigma=3) for _ in range(3)]
    finally:
        utilities.CONTEXT.rng = saved
    draws = np.random.default_rng(3).normal(0.0, 3.0, 3)
    assert noisy == pytest.approx([20 + d * 0.1 * 20 for d in draws])
    assert len(set(noisy)) == 3


# ----------------------------------------------------------------------------- collision

CASES: list[tuple[str, list[list[float]], list[list[float]], list[tuple[float, float]]]] = [
    ("crossing", [[0, 0], [2, 2]], [[0, 2], [2, 0]], [(1, 1)]),
    ("crossing off-centre", [[0, 0], [4, 2]], [[1, 3], [3, -1]], [(2, 1)]),
    ("parallel", [[0, 0], [2, 0]], [[0, 1], [2, 1]], []),
    ("lines meet beyond both", [[0, 0], [1, 1]], [[3, 0], [2, 1]], []),
    ("end touches the middle", [[0, 0], [2, 0]], [[1, 0], [1, 5]], [(1, 0)]),
    ("ends touch at a corner", [[0, 0], [1, 0]], [[1, 0], [1, 1]], [(1, 0)]),
    ("vertical crossing", [[3, -1], [3, 4]], [[0, 2], [6, 2]], [(3, 2)]),
    ("vertical short of it", [[3, -1], [3, 1]], [[0, 2], [6, 2]], []),
    ("collinear overlap", [[0, 0], [3, 0]], [[1, 0], [5, 0]], [(1, 0), (3, 0)]),
    ("collinear contained", [[0, 0], [4, 0]], [[2, 0], [1, 0]], [(1, 0), (2, 0)]),
    ("collinear end to end", [[0, 0], [1, 0]], [[1, 0], [2, 0]], [(1, 0)]),
    ("collinear apart", [[0, 0], [1, 0]], [[2, 0], [3, 0]], []),
    ("collinear vertical", [[5, 0], [5, 6]], [[5, 4], [5, 9]], [(5, 4), (5, 6)]),
    ("collinear sloped", [[0, 0], [2, 2]], [[1, 1], [3, 3]], [(1, 1), (2, 2)]),
    ("same segment", [[0, 0], [2, 1]], [[2, 1], [0, 0]], [(0, 0), (2, 1)]),
]


@pytest.mark.parametrize(
    ("first", "second", "expected"), [c[1:] for c in CASES], ids=[c[0] for c in CASES]
)
def test_collision(
    first: list[list[float]], second: list[list[float]], expected: list[Any]
) -> None:
    assert flat(utilities.collision(first, second)) == pytest.approx(flat(expected))
    assert flat(utilities.collision(second, first)) == pytest.approx(flat(expected))
    as_vectors = [Vector2(p) for p in first], [tuple(p) for p in second]
    assert flat(utilities.collision(*as_vectors)) == pytest.approx(flat(expected))
    assert utilities.check_collision_fast(first, second) is bool(expected)
    assert utilities.check_collision_fast(second, first) is bool(expected)


def test_collision_points_are_plain_tuples_listed_once() -> None:
    assert utilities.collision([[0, 0], [1, 0]], [[1, 0], [2, 0]]) == [(1.0, 0.0)]
    assert utilities.collision([[0, 0], [0, 0]], [[0, 0], [1, 1]]) == [(0.0, 0.0)]
    assert utilities.collision([[0, 0], [0, 0]], [[1, 0], [1, 1]]) == []


def test_collision_of_a_rotated_beam_with_a_wall() -> None:
    start = Vector2(6, 39.5)
    beam = [start, start + Vector2(0, 100).rotate(180)]  # heading 180: straight up the screen
    (hit,) = utilities.collision(beam, [Vector2(0, 0), Vector2(96, 0)])
    assert hit == pytest.approx((6, 0))


def test_check_collision_fast_agrees_with_collision_on_grid_segments() -> None:
    rng = np.random.default_rng(0)
    ends = rng.integers(0, 4, size=(4000, 2, 2, 2)).tolist()  # many collinear and touching pairs
    touching = 0
    for first, second in ends:
        met = bool(utilities.collision(first, second))
        assert utilities.check_collision_fast(first, second) is met, (first, second)
        touching += met
    assert 0 < touching < len(ends)


# ----------------------------------------------------------------------------- nearest point


def test_closest_and_closest_fast() -> None:
    points = [(3, 4), Vector2(1, 1), [-2, 0]]
    point, distance = utilities.closest((0, 0), points)
    assert point is points[1]
    assert distance == pytest.approx(math.sqrt(2))
    point, squared = utilities.closest_fast(Vector2(0, 0), points)
    assert point is points[1]
    assert squared == pytest.approx(2)
    assert utilities.closest((4, 4), points)[0] is points[0]


def test_closest_of_nothing() -> None:
    for helper in (utilities.closest, utilities.closest_fast):
        point, distance = helper((0, 0), [])
        assert point == []
        assert math.isnan(distance)


# ----------------------------------------------------------------------------- angle


@pytest.mark.parametrize(
    ("direction", "expected"),
    [
        ((1, 0), 0),  # parallel
        ((-1, 0), 0),  # opposite
        ((0, 1), 90),  # perpendicular
        ((0, -3), 90),
        ((1, 1), 45),
        ((-1, 1), 45),  # 135 between the directions: the acute angle is 45
        ((math.sqrt(3), 1), 30),  # the original returned None for this one
        ((-math.cos(math.radians(10)), math.sin(math.radians(10))), 10),  # 170 apart
    ],
)
def test_angle_is_acute(direction: tuple[float, float], expected: float) -> None:
    horizontal = [[2, 5], [7, 5]]
    assert utilities.angle(horizontal, [[1, 1], [1 + direction[0], 1 + direction[1]]]) == (
        pytest.approx(expected)
    )
    assert utilities.angle([[0, 0], list(direction)], horizontal) == pytest.approx(expected)


# ----------------------------------------------------------------------------- robot and maze


def test_simulate_sensors_reads_each_listed_sensor_present() -> None:
    calls: list[tuple[str, float, Any]] = []

    class Sensor:
        def __init__(self, name: str) -> None:
            self.name = name

        def simulate(self, value: float, environment: Any) -> float:
            calls.append((self.name, value, environment))
            return 1.0

    environment = {"ROBOT": SimpleNamespace(sensors={"u0": Sensor("u0"), "u1": Sensor("u1")})}
    utilities.simulate_sensors(environment, ["u1", "zz"])
    assert calls == [("u1", 0, environment)]


@pytest.mark.usefixtures("default_maze_config")
@pytest.mark.parametrize(
    ("point", "solid"),
    [
        ((6, 42), False),  # the robot's start cell (row 3, column 0)
        ((54, 30), True),  # row 2, column 4
        ((54, 6), True),  # row 0, column 4
        ((30, 6), False),  # row 0, column 2
        ((48, 24), True),  # a corner belongs to the cell to its right and below
        ((47.9, 23.9), False),  # row 1, column 3
        ((95.9, 47.9), False),  # the last cell
        ((-1, 5), False),  # outside the maze
        ((100, 5), False),
        ((5, 50), False),
    ],
)
def test_in_block_on_the_default_maze(point: tuple[float, float], solid: bool) -> None:
    assert utilities.in_block(Vector2(point)) is solid
    assert utilities.in_block(point) is solid


def test_in_block_outside_a_simulation_says_where_to_call_it() -> None:
    saved = utilities.CONTEXT.config
    utilities.CONTEXT.config = None
    try:
        with pytest.raises(RuntimeError, match="simulate or update"):
            utilities.in_block(Vector2(6, 42))
    finally:
        utilities.CONTEXT.config = saved


# ----------------------------------------------------------------------------- wall lists


def test_is_vertical() -> None:
    assert utilities.is_vertical([[2, 0], [2, 5]])
    assert utilities.is_vertical([Vector2(2, 5), (2.0, -1)])
    assert not utilities.is_vertical([[2, 0], [3, 5]])
    assert not utilities.is_vertical([[0, 1], [4, 1]])


def test_slope_intercept() -> None:
    assert utilities.slopeIntercept([[0, 1], [2, 5]]) == (2, 1)
    assert utilities.slopeIntercept([[3, 7], [1, 3]]) == (2, 1)
    assert utilities.slopeIntercept([[1, 1], [3, 1]]) == (0, 1)
    assert utilities.slopeIntercept([[2, 4], [4, 3]]) == (-0.5, 5)
    assert utilities.slopeIntercept([[4, 0], [4, 9]]) == (math.inf, 4)


def test_remove_duplicates_keeps_what_occurs_once() -> None:
    assert utilities.remove_duplicates([1, 2, 2, 3, 4, 4, 4, 5]) == [1, 3, 5]
    assert utilities.remove_duplicates([]) == []
    assert utilities.remove_duplicates([2, 2]) == []
    a, b, c = [[0, 0], [1, 0]], [Vector2(0, 0), Vector2(1, 0)], [[1, 0], [2, 0]]
    assert utilities.remove_duplicates([a, b, c]) == [c]  # a list and a Vector2 pair are equal


def test_merge_sloped_line_segments() -> None:
    segments = [
        [(0, 0), (1, 1)],
        [(2, 2), (1, 1)],  # touches the first: one segment (0,0)-(2,2)
        [(3, 3), (5, 5)],  # same line, apart
        [(0, 1), (1, 2)],  # parallel line
        [(0, 5), (2, 5)],
        [(3, 5), (1, 5)],  # overlaps the one before
        [(-1, 5), (4, 5)],  # contains both
        [(7, 0), (7, 1)],  # vertical: passed through
    ]
    merged = utilities.merge_sloped_line_segments(segments)
    assert merged == [
        [(0, 0), (2, 2)],
        [(3, 3), (5, 5)],
        [(0, 1), (1, 2)],
        [(-1, 5), (4, 5)],
        [(7, 0), (7, 1)],
    ]


def test_merge_vertical_line_segments() -> None:
    segments = [
        [(0, 0), (0, 1)],
        [(0, 2), (0, 1)],
        [(0, 3), (0, 4)],
        [(1, 0), (1, 3)],
        [(1, 2), (1, 5)],
        [(0, 0), (1, 1)],  # not vertical: passed through
    ]
    assert utilities.merge_vertical_line_segments(segments) == [
        [(0, 0), (1, 1)],
        [(0, 0), (0, 2)],
        [(0, 3), (0, 4)],
        [(1, 0), (1, 5)],
    ]


def test_optimize_walls_on_two_adjacent_squares() -> None:
    edges = square(0, 0, 1) + square(1, 0, 1)  # the shared edge x = 1 comes once each way
    walls = utilities.optimize_walls(edges)
    assert len(walls) == 4
    assert segment_set(walls) == {(0, 0, 2, 0), (0, 1, 2, 1), (0, 0, 0, 1), (2, 0, 2, 1)}
    assert all(isinstance(end, Vector2) for wall in walls for end in wall)


def test_optimize_walls_drops_an_edge_given_twice_the_same_way() -> None:
    walls = utilities.optimize_walls([[(0, 0), (1, 0)], [(0, 0), (1, 0)], [(0, 1), (1, 1)]])
    assert walls == [[(0, 1), (1, 1)]]


def test_optimize_walls_gives_the_default_maze_walls() -> None:
    edges = [
        edge
        for r, row in enumerate(WALLS)
        for c, cell in enumerate(row)
        if cell == 0
        for edge in square(c * CELL, r * CELL, CELL)
    ]
    width, height = len(WALLS[0]) * CELL, len(WALLS) * CELL
    corners = [(0, 0), (width, 0), (width, height), (0, height)]
    edges += [[Vector2(corners[i]), Vector2(corners[(i + 1) % 4])] for i in range(4)]
    maze = Maze(WALLS, CELL, 3.0, 5489)
    expected = {tuple(s) for s in maze.segments.tolist()}
    assert segment_set(utilities.optimize_walls(edges)) == expected
    assert len(expected) == 21


# ----------------------------------------------------------------------------- in a simulation


def test_time_of_flight_device_reads_the_wall_ahead() -> None:
    sim = Simulation.from_config(TOF_CONFIG)
    assert sim.config.device("t0").kind == "simmer_device"
    # u0's mounting: 2.5 in ahead of the robot at (6, 42) facing up, so 39.5 in from y = 0
    assert sim.command("t0") == [pytest.approx(39.5)]
    assert sim.command("t0,u0") == [pytest.approx(39.5)] * 2


def test_time_of_flight_device_matches_a_one_ray_ultrasonic() -> None:
    sim = Simulation.from_config(TOF_CONFIG)
    maze = sim.maze
    block_cell = (int(sim.block.y // CELL), int(sim.block.x // CELL))
    compared = 0
    for row in range(maze.rows):
        for col in range(maze.cols):
            if maze.solid[row, col] or (row, col) == block_cell:
                continue
            for heading in range(3, 360, 10):  # never through a grid corner from a cell centre
                assert sim.place_robot((col + 0.5) * CELL, (row + 0.5) * CELL, heading)
                tof, ultrasonic = sim.command("t0,u0")
                assert tof == pytest.approx(ultrasonic, abs=1e-9), (row, col, heading)
                compared += 1
    assert compared == 36 * (int((~maze.solid).sum()) - 1)


def test_noisy_time_of_flight_device_is_seeded_and_centred() -> None:
    first = Simulation.from_config(TOF_CONFIG, seed=4)
    second = Simulation.from_config(TOF_CONFIG, seed=4)
    readings = [first.command("t1")[0] for _ in range(300)]
    assert readings[:10] == [second.command("t1")[0] for _ in range(10)]
    assert min(readings) != max(readings)
    assert abs(sum(readings) / len(readings) - 39.5) < 1.0


def test_device_using_every_helper_gets_the_expected_numbers() -> None:
    sim = Simulation.from_config(TOF_CONFIG)
    vertical = sum(1 for x1, _, x2, _ in sim.maze.segments.tolist() if x1 == x2)

    def probe(value: int) -> float:
        (reply,) = sim.command(f"p0-{value}")
        return reply

    assert probe(0) == pytest.approx(39.5)  # closest() over collision() points
    assert probe(1) == 1  # check_collision_fast: only the top wall is in the way
    assert probe(2) == pytest.approx(90)  # angle() between the beam and that wall
    assert probe(3) == 0  # in_block() at the sensor
    assert probe(4) == 1  # in_block() in row 2, column 4
    assert probe(5) == 21  # optimize_walls() of the solid cells' edges and the boundary
    assert probe(10) == vertical  # is_vertical()
    assert probe(11) == pytest.approx(0)  # slopeIntercept() of the top wall
    assert probe(12) == 5  # add_error() clamped
    assert probe(13) == 422  # 4 sensors, 2 drives, 2 motors
    assert probe(14) == 96  # CONFIG.maze_dim_x
    assert math.isnan(probe(99))
    assert sim.place_robot(30, 30, 90)  # facing -x: the wall ahead is vertical
    assert probe(11) == math.inf
    assert probe(0) == pytest.approx(3.5)  # from x = 27.5 to the solid cell in column 1


def test_simulate_sensors_from_a_device_reaches_the_real_sensors() -> None:
    sim = Simulation.from_config(TOF_CONFIG)
    sim.step(3)
    ultrasonic = sim.robot.devices["u0"]
    assert ultrasonic.last_time == -math.inf  # type: ignore[attr-defined]
    assert sim.command("p0-6") == [pytest.approx(39.5)]
    assert ultrasonic.last_time == sim.time  # type: ignore[attr-defined]
    assert sim.robot.devices["t0"].instance.reading == pytest.approx(39.5)  # type: ignore[attr-defined]


def test_device_drives_the_robot_and_reads_buffer_and_odometer() -> None:
    sim = Simulation.from_config(TOF_CONFIG)
    assert sim.command("p0-7,p0-8") == [0, 0]
    assert sim.command("p0-9") == [math.inf]  # the w0 view started a 12 in move
    assert sim.command("p0-9") == [pytest.approx(math.nan, nan_ok=True)]  # busy
    assert sim.command("p0-7") == [pytest.approx(12)]
    sim.step(60)  # one second at 6 in/s
    assert sim.command("p0-7,p0-8") == [pytest.approx(6), pytest.approx(6)]
    assert sim.run_until_idle()
    assert sim.command("p0-7,p0-8,t0") == [0, pytest.approx(12), pytest.approx(27.5)]


def test_environment_robot_lists_every_device() -> None:
    sim = Simulation.from_config(TOF_CONFIG)
    robot = Environment(sim)["ROBOT"]
    assert list(robot.sensors) == ["u0", "t0", "t1", "p0"]
    assert list(robot.drives) == ["w0", "r0"]
    assert list(robot.motors) == ["m0", "m1"]
    assert {v.d_type for v in robot.sensors.values()} == {"sensor"}
    assert robot.drives["r0"].d_type == "drive"
    assert robot.motors["m1"].d_type == "motor"
    assert robot.motors["m1"].id == "m1"
    assert robot.motors["m1"].position == Vector2(-3.125, 0)
    assert robot.sensors["u0"].rotation == 0
    assert robot.sensors["u0"].position_global == Vector2(6, 39.5)
    assert robot.sensors["u0"].rotation_global == 180
    assert robot.motors["m0"].simulate(0, None) == 0  # the odometer
    assert robot.position == Vector2(6, 42)
    assert robot.height == 6


def test_config_gives_every_setting_and_the_maze_size() -> None:
    sim = Simulation.from_config(TOF_CONFIG)
    values = config_values(sim)
    assert set(Settings.model_fields) <= set(values)
    assert values["maze_dim_x"] == 96
    assert values["maze_dim_y"] == 48
    assert values["frame_rate"] == 60
    assert values["wall_segment_length"] == 12
    assert values["block_size"] == 3
    assert values["walls"] == WALLS
    for name in ("ppi", "border_pixels"):
        assert values[name] == getattr(sim.config.settings, name)
