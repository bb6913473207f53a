"""The compiled kernels of ``simmer.geometry`` (issue 29, item 8), each against a plain Python
reference written here another way (exact fractions, a separating axis, the plain rotation), on
generated inputs; and the grid walk ``ray_grid`` against ``ray_segments`` on generated mazes.

Inputs within a hair of a tie (a ray through a wall's end or a grid corner, a point on an edge,
outlines that just touch) are left out: there either answer is right. No deadline: the first
example loads the compiled kernels."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from simmer.config.maze import Maze
from simmer.geometry import (
    FloatArray,
    cast_fan,
    heading_vector,
    place_polygon,
    point_in_polygon,
    polygon_hits_grid,
    polygons_overlap,
    ray_grid,
    ray_grid_inverse,
    ray_segments,
    rectangle,
    robot_blocked,
    rotate,
    white_fraction,
)

HAIR = 1e-6
"""Inches within which an input counts as a tie (left out)."""
coordinate = st.floats(-20.0, 20.0, allow_nan=False)
heading = st.floats(0.0, 360.0, exclude_max=True)
segment_rows = st.lists(st.tuples(coordinate, coordinate, coordinate, coordinate), max_size=8)
cells_grid = st.integers(2, 6).flatmap(
    lambda rows: st.integers(2, 6).flatmap(
        lambda cols: st.lists(
            st.lists(st.integers(0, 1), min_size=cols, max_size=cols),
            min_size=rows,
            max_size=rows,
        )
    )
)


def maze_of(cells: list[list[int]], cell: float = 12.0) -> Maze:
    """A maze of ``cells`` (0 solid, 1 open) as the configuration builds it, walls and all."""
    return Maze(tuple(tuple(row) for row in cells), cell, cell / 2, 0)


def exact_ray_segment(
    origin: tuple[float, float], direction: tuple[float, float], segment: tuple[float, ...]
) -> tuple[float, bool]:
    """Distance along the ray to ``segment`` in exact arithmetic (inf if it misses), and
    whether the case is a tie: parallel, or the crossing within a hair of its ends or origin."""
    ox, oy, dx, dy = (Fraction(value) for value in (*origin, *direction))
    x1, y1, x2, y2 = (Fraction(value) for value in segment)
    sx, sy = x2 - x1, y2 - y1
    denom = dx * sy - dy * sx
    length = math.hypot(float(sx), float(sy))
    if denom == 0 or abs(float(denom)) < 1e-9 or length < HAIR:
        return math.inf, True
    t = ((x1 - ox) * sy - (y1 - oy) * sx) / denom
    u = ((x1 - ox) * dy - (y1 - oy) * dx) / denom
    tie = abs(float(t)) < HAIR or min(abs(float(u)), abs(float(u) - 1)) * length < HAIR
    return (float(t) if t >= 0 and 0 <= u <= 1 else math.inf), tie


def plain_ray_segments(
    origin: tuple[float, float], direction: tuple[float, float], segments: FloatArray
) -> tuple[float, bool]:
    """The nearest of ``segments`` along the ray, and whether any of them is a tie."""
    found = [exact_ray_segment(origin, direction, tuple(row)) for row in segments]
    return min((t for t, _ in found), default=math.inf), any(tie for _, tie in found)


@settings(deadline=None, max_examples=200)
@given(x=coordinate, y=coordinate, angle=heading, rows=segment_rows)
def test_ray_segments_is_the_nearest_crossing(
    x: float, y: float, angle: float, rows: list[tuple[float, float, float, float]]
) -> None:
    direction = heading_vector(angle)
    segments = np.array(rows, dtype=np.float64).reshape(-1, 4)
    expected, tie = plain_ray_segments((x, y), direction, segments)
    assume(not tie)
    assert math.isclose(ray_segments(x, y, *direction, segments), expected, abs_tol=1e-9)


def near_a_corner(maze: Maze, x: float, y: float, direction: tuple[float, float]) -> bool:
    """Whether the ray passes within a hair of a grid corner (a wall's end may be either)."""
    dx, dy = direction
    for r in range(maze.rows + 1):
        for c in range(maze.cols + 1):
            px, py = c * maze.cell - x, r * maze.cell - y
            if px * dx + py * dy > 0 and abs(px * dy - py * dx) < HAIR:
                return True
    return False


@settings(deadline=None, max_examples=150)
@given(cells=cells_grid, fx=st.floats(0, 1), fy=st.floats(0, 1), angle=heading)
def test_ray_grid_agrees_with_ray_segments_on_random_mazes(
    cells: list[list[int]], fx: float, fy: float, angle: float
) -> None:
    maze = maze_of(cells)
    x, y = fx * maze.width, fy * maze.height
    assume(x < maze.width and y < maze.height)
    assume(min(x % maze.cell, y % maze.cell) > HAIR)  # not on a grid line
    direction = heading_vector(angle)
    assume(not near_a_corner(maze, x, y, direction))
    walked = ray_grid(maze.hwall, maze.vwall, maze.cell, x, y, *direction, math.inf)
    assert math.isclose(walked, ray_segments(x, y, *direction, maze.segments), abs_tol=1e-9)
    assert ray_grid(maze.hwall, maze.vwall, maze.cell, -1.0, y, *direction, math.inf) == -1.0
    # The LiDAR's setup of the same walk (reciprocals from one division) finds the same wall.
    inverse = ray_grid_inverse(maze.hwall, maze.vwall, maze.cell, x, y, *direction, math.inf)
    assert math.isclose(inverse, walked, abs_tol=1e-9)
    assert ray_grid_inverse(maze.hwall, maze.vwall, maze.cell, -1.0, y, *direction, 9.0) == -1.0


def test_ray_grid_inverse_walks_along_the_axes_and_stops_at_its_limit() -> None:
    # Rays along an axis (one direction component 0: no reciprocal) and a limit cut short.
    maze = maze_of([[1, 1, 1], [1, 1, 1]])
    for angle in (0.0, 90.0, 180.0, 270.0, 45.0, 135.0):
        direction = heading_vector(angle)
        for limit in (math.inf, 5.0):
            args = (maze.hwall, maze.vwall, maze.cell, 13.0, 7.0, *direction, limit)
            assert math.isclose(ray_grid_inverse(*args), ray_grid(*args), abs_tol=1e-12), angle


@settings(deadline=None, max_examples=60)
@given(
    cells=cells_grid,
    fx=st.floats(0.01, 0.99),
    fy=st.floats(0.01, 0.99),
    angle=heading,
    rays=st.integers(1, 7),
    limit=st.floats(1.0, 100.0),
)
def test_cast_fan_casts_each_ray_of_the_fan(
    cells: list[list[int]], fx: float, fy: float, angle: float, rays: int, limit: float
) -> None:
    maze = maze_of(cells)
    x, y = fx * maze.width, fy * maze.height
    block = np.array([[x + 3, y - 1, x + 3, y + 1]], dtype=np.float64)  # a wall of the block
    out = np.empty(rays)
    best = cast_fan(
        maze.hwall, maze.vwall, maze.cell, maze.segments, block, True, x, y, angle, 30.0, limit,
        out,
    )  # fmt: skip
    expected = []
    for k in range(rays):
        direction = heading_vector(angle + ((k - (rays - 1) / 2) / rays) * 30.0)
        walls = np.vstack((maze.segments, block))
        t, tie = plain_ray_segments((x, y), direction, walls)
        assume(not tie and abs(t - limit) > HAIR)
        expected.append(t if t <= limit else math.inf)
    assert np.allclose(out, expected, rtol=0, atol=1e-9)
    assert best == min(out)


def winding_number(px: float, py: float, poly: FloatArray) -> int:
    """How many times ``poly`` winds around the point (exact): 0 outside."""
    point = (Fraction(px), Fraction(py))
    winding = 0
    corners = [(Fraction(x), Fraction(y)) for x, y in poly]
    for (ax, ay), (bx, by) in zip(corners, corners[1:] + corners[:1], strict=True):
        side = (bx - ax) * (point[1] - ay) - (point[0] - ax) * (by - ay)
        if ay <= point[1] < by and side > 0:
            winding += 1
        elif by <= point[1] < ay and side < 0:
            winding -= 1
    return winding


def distance_to_outline(px: float, py: float, poly: FloatArray) -> float:
    """The distance from the point to the nearest edge of ``poly``."""
    point = np.array([[px, py]])
    return min(
        _point_segment(point[0], poly[i], poly[(i + 1) % len(poly)]) for i in range(len(poly))
    )


def _point_segment(p: FloatArray, a: FloatArray, b: FloatArray) -> float:
    edge = b - a
    t = float(np.clip(np.dot(p - a, edge) / max(float(np.dot(edge, edge)), 1e-300), 0, 1))
    return float(np.hypot(*(p - (a + t * edge))))


def convex_polygon(
    centre: tuple[float, float], sides: int, radius: float, turn: float
) -> FloatArray:
    """A regular polygon: convex, as the robot and the block are."""
    angles = np.radians(turn) + 2 * np.pi * np.arange(sides) / sides
    return np.column_stack(
        (centre[0] + radius * np.cos(angles), centre[1] + radius * np.sin(angles))
    )


polygons = st.builds(
    convex_polygon,
    st.tuples(coordinate, coordinate),
    st.integers(3, 8),
    st.floats(0.5, 10.0),
    st.floats(0.0, 360.0),
)


@settings(deadline=None, max_examples=200)
@given(x=coordinate, y=coordinate, poly=polygons)
def test_point_in_polygon_is_the_winding_number(x: float, y: float, poly: FloatArray) -> None:
    assume(distance_to_outline(x, y, poly) > HAIR)
    assert point_in_polygon(x, y, poly) == (winding_number(x, y, poly) != 0)


@settings(deadline=None)
@given(local=polygons, x=coordinate, y=coordinate, angle=heading)
def test_place_polygon_rotates_then_moves(
    local: FloatArray, x: float, y: float, angle: float
) -> None:
    out = np.empty_like(local)
    place_polygon(local, x, y, angle, out)
    expected = [
        (x + turned.x, y + turned.y) for turned in (rotate(px, py, angle) for px, py in local)
    ]
    assert np.allclose(out, expected, rtol=0, atol=1e-12)


def separation(a: FloatArray, b: FloatArray) -> float:
    """Separating axis test for convex outlines: positive (the gap along the best axis) if they
    are apart, negative (the least overlap) if they overlap."""
    best = -math.inf
    for poly in (a, b):
        for i in range(len(poly)):
            edge = poly[(i + 1) % len(poly)] - poly[i]
            if float(np.hypot(*edge)) < HAIR:
                continue
            axis = np.array([-edge[1], edge[0]]) / np.hypot(*edge)
            pa, pb = a @ axis, b @ axis
            best = max(best, pb.min() - pa.max(), pa.min() - pb.max())
    return float(best)


@settings(deadline=None, max_examples=200)
@given(a=polygons, b=polygons)
def test_polygons_overlap_is_the_separating_axis_test(a: FloatArray, b: FloatArray) -> None:
    gap = separation(a, b)
    assume(abs(gap) > HAIR)
    assert polygons_overlap(a, b) == (gap < 0)


def plain_hits_grid(poly: FloatArray, maze: Maze) -> bool | None:
    """Whether the convex outline touches a wall segment or a vertex is off the floor or in a
    solid cell (None: a tie)."""
    for px, py in poly:
        cx, cy = math.floor(px / maze.cell), math.floor(py / maze.cell)
        if not (0 <= cx < maze.cols and 0 <= cy < maze.rows) or maze.solid[cy, cx]:
            return True
    gaps = [separation(poly, np.array([row[:2], row[2:]])) for row in maze.segments]
    if any(abs(gap) <= HAIR for gap in gaps):
        return None
    return any(gap < 0 for gap in gaps)


@settings(deadline=None, max_examples=100)
@given(cells=cells_grid, fx=st.floats(0, 1), fy=st.floats(0, 1), poly=polygons)
def test_polygon_hits_grid_is_a_test_against_every_wall(
    cells: list[list[int]], fx: float, fy: float, poly: FloatArray
) -> None:
    maze = maze_of(cells)
    placed = poly - poly.mean(axis=0) + (fx * maze.width, fy * maze.height)
    expected = plain_hits_grid(placed, maze)
    assume(expected is not None)
    assert polygon_hits_grid(placed, maze.hwall, maze.vwall, maze.solid, maze.cell) == expected


@settings(deadline=None, max_examples=100)
@given(cells=cells_grid, fx=st.floats(0, 1), fy=st.floats(0, 1), angle=heading)
def test_robot_blocked_places_then_tests_walls_and_block(
    cells: list[list[int]], fx: float, fy: float, angle: float
) -> None:
    maze = maze_of(cells)
    local = rectangle(6.0, 8.0)
    x, y = fx * maze.width, fy * maze.height
    placed = np.array([(x + p.x, y + p.y) for p in (rotate(px, py, angle) for px, py in local)])
    block = rectangle(3.0, 3.0) + np.array([maze.width / 2, maze.height / 2])
    walls = plain_hits_grid(placed, maze)
    gap = separation(placed, block)
    assume(walls is not None and abs(gap) > HAIR)
    scratch = np.empty_like(local)
    got = robot_blocked(
        local, x, y, angle, scratch, maze.hwall, maze.vwall, maze.solid, maze.cell, block
    )
    assert got == (walls or gap < 0)


@settings(deadline=None)
@given(
    floor=st.lists(st.lists(st.booleans(), min_size=4, max_size=4), min_size=3, max_size=3),
    cx=st.floats(-2.0, 14.0),
    cy=st.floats(-2.0, 11.0),
    radius=st.floats(0.0, 4.0),
    count=st.integers(1, 40),
)
def test_white_fraction_counts_the_white_samples(
    floor: list[list[bool]], cx: float, cy: float, radius: float, count: int
) -> None:
    white = np.array(floor, dtype=bool)
    samples = np.random.default_rng(count).uniform(-1, 1, size=(count, 2))
    counted = 0
    for sx, sy in samples:
        col, row = math.floor((cx + radius * sx) / 3.0), math.floor((cy + radius * sy) / 3.0)
        counted += 0 <= col < 4 and 0 <= row < 3 and bool(white[row, col])
    assert white_fraction(white, 3.0, cx, cy, radius, samples) == counted / count
