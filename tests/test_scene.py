"""The one scene description (issue 29): what the maze, zones, block and robot are drawn as,
in inches, for the window, a run's path plot and a sweep's map."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simmer.colors import (
    BLACK_TILE,
    DROPOFF_COLOR,
    LOADING_COLOR,
    MAP_SOLID,
    TARGET_COLOR,
    WHITE_TILE,
)
from simmer.config import load_config
from simmer.config.maze import Block, Maze, robot_outline
from simmer.config.zones import Zones
from simmer.geometry import heading_vector, place_polygon
from simmer.scene import (
    Arrow,
    Cells,
    Grid,
    Label,
    Lines,
    Look,
    Outline,
    Palette,
    Walls,
    block_items,
    maze_items,
    placed_block,
    placed_robot,
    robot_items,
    target_items,
)

from helpers import PROJECT


@pytest.fixture(scope="module")
def project() -> tuple[Maze, Zones]:
    settings = load_config(PROJECT).settings
    return Maze.from_settings(settings), Zones.from_settings(settings)


@pytest.mark.parametrize("look", list(Look))
def test_the_walls_are_the_mazes_segments_on_top_of_the_floor(look: Look) -> None:
    settings = load_config(PROJECT).settings
    maze = Maze.from_settings(settings)
    items = maze_items(maze, settings, look, Zones.from_settings(settings))
    walls = [item for item in items if isinstance(item, Walls)]
    assert len(walls) == 1
    assert len(walls[0].lines) == len(maze.segments) > 4
    np.testing.assert_array_equal(walls[0].lines, maze.segments)
    under = [item for item in items if not isinstance(item, Label)]  # zone names may be over
    assert all(item.layer <= walls[0].layer for item in under)
    assert [item.layer for item in items] == sorted(item.layer for item in items)


def test_the_floor_and_solid_cells_are_grids_of_the_mazes_cells(
    project: tuple[Maze, Zones],
) -> None:
    maze, _ = project
    settings = load_config(PROJECT).settings
    floor, solid, *_ = maze_items(maze, settings, Look.WINDOW)
    assert isinstance(floor, Grid)
    assert isinstance(solid, Grid)
    assert floor.rgba.shape[:2] == maze.floor_white.shape
    assert (floor.cell, floor.width, floor.height) == (maze.tile, maze.width, maze.height)
    row, col = np.argwhere(maze.floor_white)[0]
    assert tuple(floor.rgba[row, col]) == (*WHITE_TILE, 255)
    row, col = np.argwhere(~maze.floor_white)[0]
    assert tuple(floor.rgba[row, col]) == (*BLACK_TILE, 255)
    np.testing.assert_array_equal(solid.rgba[..., 3] > 0, maze.solid)
    assert tuple(solid.rgba[maze.solid][0, :3]) == Palette.of(settings).solid_cell
    # A sweep's map has no floor, and greys its solid cells.
    first = maze_items(maze, settings, Look.MAP)[0]
    assert isinstance(first, Grid)
    assert tuple(first.rgba[maze.solid][0, :3]) == MAP_SOLID


@pytest.mark.parametrize("look", list(Look))
def test_every_zone_is_drawn_and_named(look: Look, project: tuple[Maze, Zones]) -> None:
    maze, zones = project
    settings = load_config(PROJECT).settings
    items = maze_items(maze, settings, look, zones, target="B3")
    names = [item.text for item in items if isinstance(item, Label)]
    assert names == [zone.name for zone in zones.all()] == ["loading", "B1", "B2", "B3", "B4"]
    assert not any(isinstance(item, Label) for item in maze_items(maze, settings, look))
    if look is Look.WINDOW:  # outlines: a one-cell drop-off zone has four sides
        outlines = [item for item in items if isinstance(item, Lines)]
        assert [item.color for item in outlines] == [LOADING_COLOR] + [DROPOFF_COLOR] * 4
        assert [len(item.lines) for item in outlines[1:]] == [4] * 4
    else:  # tinted cells, the target in its own colour on a run's plot
        cells = [item for item in items if isinstance(item, Cells)]
        assert [len(item.rects) for item in cells] == [len(z.cells) for z in zones.all()]
        if look is Look.PAGE:
            colors = [item.color for item in cells]
            assert colors[0] == LOADING_COLOR
            assert colors[1:] == [DROPOFF_COLOR, DROPOFF_COLOR, TARGET_COLOR, DROPOFF_COLOR]


def test_the_windows_target_mark_is_the_target_zones_outline(project: tuple[Maze, Zones]) -> None:
    maze, zones = project
    mark = target_items(zones, "B2", maze.cell)
    assert [type(item) for item in mark] == [Lines, Label]
    assert all(item.color == TARGET_COLOR for item in mark)
    ((_, col),) = zones.dropoff["B2"].cells
    assert isinstance(mark[0], Lines)
    xs = [x for line in mark[0].lines for x, _ in line]
    assert col * maze.cell < min(xs) < max(xs) < (col + 1) * maze.cell  # inside its cell
    assert target_items(zones, None, maze.cell) == target_items(zones, "loading", maze.cell) == []


def test_the_robot_outline_is_at_its_pose() -> None:
    settings = load_config(PROJECT).settings
    pose = (30.0, 18.0, 90.0)
    placed = placed_robot(settings, pose)
    outline = robot_outline(settings)
    expected = np.empty_like(outline)
    place_polygon(outline, *pose, expected)
    body, arrow = robot_items(placed, settings, Look.PAGE, (1, 2, 3), dashed=True)
    assert isinstance(body, Outline)
    assert isinstance(arrow, Arrow)
    np.testing.assert_allclose(body.points, expected)
    assert (body.fill, body.edge, body.dashed) == (None, (1, 2, 3), True)
    assert arrow.start == pytest.approx(pose[:2])
    dx, dy = heading_vector(pose[2])  # ahead: -x at 90 degrees
    reach = math.dist(arrow.start, arrow.end)
    assert reach > float(np.abs(outline).max())  # past the body
    assert arrow.end == pytest.approx((pose[0] + dx * reach, pose[1] + dy * reach))
    fill, mark = robot_items(placed, settings, Look.WINDOW)
    assert isinstance(fill, Outline)
    assert isinstance(mark, Lines)
    assert fill.fill == Palette.of(settings).robot_fill
    assert fill.edge == mark.color == settings.robot_color


def test_the_block_is_where_the_settings_or_the_scenario_put_it() -> None:
    settings = load_config(PROJECT).settings
    np.testing.assert_allclose(placed_block(settings), Block.from_settings(settings).polygon)
    moved = placed_block(settings, (40.0, 20.0))
    assert moved.mean(axis=0) == pytest.approx((40.0, 20.0))
    (window,) = block_items(moved, settings, Look.WINDOW)
    (page,) = block_items(moved, settings, Look.PAGE)
    assert isinstance(window, Outline)
    assert isinstance(page, Outline)
    assert window.fill == page.fill == settings.block_color
    assert window.edge == Palette.of(settings).block_edge
    assert page.edge == (0, 0, 0)
