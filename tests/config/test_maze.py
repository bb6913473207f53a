"""Maze walls, the floor pattern and the block (BEHAVIOUR §2-3)."""

from __future__ import annotations

import numpy as np
import pytest

from simmer.config.models import SIMMER_DEFAULT_WALLS
from simmer.world import Maze, floor_pattern

from helpers import default_data, make_sim


def test_default_maze_walls_are_merged_boundary_and_solid_edges() -> None:
    maze = Maze(((1, 0), (1, 1)), 12.0, 3.0, 5489)
    segments = {tuple(map(float, s)) for s in maze.segments}
    assert segments == {
        (0.0, 0.0, 24.0, 0.0),  # top boundary, merged across both columns
        (0.0, 24.0, 24.0, 24.0),  # bottom boundary
        (12.0, 12.0, 24.0, 12.0),  # under the solid cell
        (0.0, 0.0, 0.0, 24.0),  # left boundary
        (12.0, 0.0, 12.0, 12.0),  # left of the solid cell
        (24.0, 0.0, 24.0, 24.0),  # right boundary
    }


def test_edge_between_two_solid_cells_is_not_a_wall() -> None:
    maze = Maze(((0, 0, 1),), 12.0, 3.0, 5489)
    assert not maze.vwall[0, 1]
    assert maze.vwall[0, 2]


def test_default_maze_size() -> None:
    maze = Maze(SIMMER_DEFAULT_WALLS, 12.0, 3.0, 5489)
    assert (maze.width, maze.height) == (96.0, 48.0)
    assert maze.floor_white.shape == (16, 32)


def legacy_floor(cols: int, rows: int, cell: float, tile: float, seed: int) -> np.ndarray:
    """The original's loop, written out: tile (ix, iy) takes draw ix * n_y + iy."""
    n_x, n_y = int(cols * cell / tile), int(rows * cell / tile)
    rng = np.random.RandomState(seed)
    draws = rng.random(n_x * n_y)
    white = np.zeros((n_y, n_x), dtype=bool)
    for ix in range(n_x):
        for iy in range(n_y):
            white[iy, ix] = draws[ix * n_y + iy] >= 0.5
    return white


@pytest.mark.parametrize("seed", [5489, 0, 123456789])
@pytest.mark.parametrize(("cols", "rows"), [(8, 4), (5, 7)])
def test_floor_pattern_matches_legacy_mersenne_twister(seed: int, cols: int, rows: int) -> None:
    expected = legacy_floor(cols, rows, 12.0, 3.0, seed)
    assert np.array_equal(floor_pattern(cols, rows, 12.0, 3.0, seed), expected)


def test_floor_first_tiles_for_seed_5489() -> None:
    white = floor_pattern(8, 4, 12.0, 3.0, 5489)
    # BEHAVIOUR §2: (0,0) white, (0,1) white, (0,2) black, (0,3) white; indexed [row, column].
    assert [bool(white[iy, 0]) for iy in range(4)] == [True, True, False, True]


def test_cast_ray_hits_nearest_wall() -> None:
    maze = Maze(((1, 1, 1),), 12.0, 3.0, 5489)
    assert maze.cast_ray(6.0, 6.0, 270.0) == pytest.approx(30.0, abs=1e-12)  # +x
    assert maze.cast_ray(6.0, 6.0, 0.0) == pytest.approx(6.0, abs=1e-12)  # +y, down
    assert maze.cast_ray(6.0, 6.0, 270.0, limit=10.0) == float("inf")


@pytest.mark.parametrize("cell", [2**64, -(2**70), 3])
def test_a_cell_of_any_other_whole_number_is_floor(cell: int) -> None:
    """An edited manifest with a cell of 2**64 once stopped ``simmer plot`` with a traceback."""
    data = default_data()
    walls = [list(row) for row in SIMMER_DEFAULT_WALLS]
    walls[0][0] = cell
    data["walls"] = walls
    maze = make_sim(data).maze
    assert maze.solid.tolist() == [[value == 0 for value in row] for row in SIMMER_DEFAULT_WALLS]
