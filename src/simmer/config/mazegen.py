"""A seeded generator of course-like mazes, and how alike a maze's cells look to the robot
(docs/mazes.md).

**Course style** (the default): a grid of solid and open cells like the course's maze. A 2 x 2
loading zone is opened in a corner, corridors one cell wide grow from it at random (each new
cell touches exactly one open cell, so they form a tree and every open cell is reachable),
then solid cells that join two corridors are opened until the asked share of loops is met.
Four single-cell drop-off zones go on dead ends where it can (as the course's do), at least
``zone_gap`` cells (Manhattan) from each other and from the loading zone. A draw whose dead
ends or ambiguity miss the asked range is drawn again (attempt 1, 2... of the same seed).

**Perfect style**: a micromouse-like perfect maze: cells on the even rows and columns,
joined by a random depth-first walk through the odd ones, so there is exactly one way
between any two cells (odd sizes; no zones).

**Ambiguity** is the share of open cells that look like another open cell to the robot's
sensors: from a cell's centre, the noise-free distances to the walls ahead, right, behind and
left, at some heading, are each within ``tolerance`` inches of another cell's at some heading.
Distances from cell centres differ by whole cells, so a tolerance under one cell means "the
same distances"; found by hashing each cell's distances at its least rotation, it costs
O(cells).

**The same seed gives the same maze on every machine and version**: every draw is Python's
``random.Random(seed_text).random()``, the one part of :mod:`random` whose sequence Python
promises never to change; integers and shuffles are made from it here, in plain arithmetic,
never with ``randrange``/``shuffle``/NumPy (whose algorithms may change between releases).
The files are written from integers alone. ``GENERATOR_VERSION`` is in every file made, and
``tests/config/test_mazegen.py`` pins the bytes of the files of a few seeds.
"""

from __future__ import annotations

import random
from dataclasses import dataclass

import numpy as np

from simmer.config.mazes import MazeSpec
from simmer.config.project import Cell, GenerateSettings
from simmer.errors import GenerateError

GENERATOR_VERSION = 1
"""Changes whenever a seed would give another maze; written into every generated file."""
MAX_ATTEMPTS = 1000
"""Draws of one seed before the generator gives up on meeting the asked ranges."""


@dataclass(frozen=True)
class Figures:
    """What a maze measures: open cells, loops, dead ends and ambiguity (shares of open
    cells), and each open cell's count of look-alikes (-1 on solid cells)."""

    open_cells: int
    loops: int
    dead_ends: int
    ambiguity: float
    alike: np.ndarray

    @property
    def loop_share(self) -> float:
        """Independent loops per open cell."""
        return self.loops / self.open_cells

    @property
    def dead_end_share(self) -> float:
        """Dead ends per open cell."""
        return self.dead_ends / self.open_cells

    def describe(self) -> str:
        """One line: ``22 open cells, 2 loops (0.09), 5 dead ends (0.23), ambiguity 0.27``."""
        return (
            f"{self.open_cells} open cells, {self.loops} loops ({self.loop_share:.2f}), "
            f"{self.dead_ends} dead ends ({self.dead_end_share:.2f}), "
            f"ambiguity {self.ambiguity:.2f}"
        )


# ----------------------------------------------------------------------------- the draws


class _Draws:
    """Seeded draws made only from ``random.Random.random()`` (see the module docstring)."""

    def __init__(self, seed: int, attempt: int) -> None:
        self._random = random.Random(f"simmer-maze-{GENERATOR_VERSION}-{seed}-{attempt}").random

    def below(self, n: int) -> int:
        """A whole number from 0 to n - 1."""
        return min(int(self._random() * n), n - 1)

    def uniform(self, low: float, high: float) -> float:
        """A number from low to high."""
        return low + (high - low) * self._random()

    def shuffled(self, items: list[Cell]) -> list[Cell]:
        """A copy of ``items`` in a drawn order (Fisher-Yates)."""
        items = list(items)
        for i in range(len(items) - 1, 0, -1):
            j = self.below(i + 1)
            items[i], items[j] = items[j], items[i]
        return items


# ----------------------------------------------------------------------------- measuring


def distances(opened: np.ndarray) -> np.ndarray:
    """Open cells beyond each cell towards north, east, south and west (rows, cols, 4): the
    noise-free distance to the wall from the cell's centre is (count + 0.5) cells."""
    rows, cols = opened.shape
    run = np.zeros((rows, cols, 4), dtype=np.int64)
    o = opened.astype(np.int64)
    for r in range(1, rows):  # north: open cells straight above
        run[r, :, 0] = (run[r - 1, :, 0] + 1) * o[r - 1]
    for r in range(rows - 2, -1, -1):  # south
        run[r, :, 2] = (run[r + 1, :, 2] + 1) * o[r + 1]
    for c in range(cols - 2, -1, -1):  # east
        run[:, c, 1] = (run[:, c + 1, 1] + 1) * o[:, c + 1]
    for c in range(1, cols):  # west
        run[:, c, 3] = (run[:, c - 1, 3] + 1) * o[:, c - 1]
    return run


def alike_counts(opened: np.ndarray, cell: float, tolerance: float) -> np.ndarray:
    """For each open cell, how many other open cells look like it (-1 on solid cells)."""
    slack = int(tolerance // cell)  # readings differ by whole cells
    run = distances(opened)[opened]  # (n, 4)
    n = len(run)
    counts = np.full(opened.shape, -1, dtype=np.int64)
    if n == 0:
        return counts
    turns = np.stack([np.roll(run, -k, axis=1) for k in range(4)], axis=1)  # (n, 4 turns, 4)
    if slack == 0:
        base = int(run.max()) + 1
        keys = turns @ (base ** np.arange(3, -1, -1, dtype=np.int64))  # (n, 4)
        least = keys.min(axis=1)
        _, inverse, sizes = np.unique(least, return_inverse=True, return_counts=True)
        counts[opened] = sizes[inverse] - 1
        return counts
    found = np.zeros(n, dtype=np.int64)
    for start in range(0, n, 512):
        block = run[start : start + 512]
        near = (np.abs(block[:, None, None, :] - turns[None, :, :, :]).max(axis=3) <= slack).any(
            axis=2
        )
        found[start : start + 512] = near.sum(axis=1) - 1
    counts[opened] = found
    return counts


def measure(opened: np.ndarray, cell: float, tolerance: float, *, loading_zone: bool) -> Figures:
    """The figures of a maze (``loading_zone``: its 2 x 2 open square is not counted a loop)."""
    opened = opened.astype(bool)
    n = int(opened.sum())
    neighbours = np.zeros(opened.shape, dtype=np.int64)
    neighbours[1:] += opened[:-1]
    neighbours[:-1] += opened[1:]
    neighbours[:, 1:] += opened[:, :-1]
    neighbours[:, :-1] += opened[:, 1:]
    edges = int((opened[1:] & opened[:-1]).sum() + (opened[:, 1:] & opened[:, :-1]).sum())
    loops = edges - n + 1 - (1 if loading_zone else 0)
    dead = int((opened & (neighbours == 1)).sum())
    alike = alike_counts(opened, cell, tolerance)
    ambiguity = float((alike > 0).sum() / n) if n else 0.0
    return Figures(n, loops, dead, ambiguity, alike)


# ----------------------------------------------------------------------------- generating


@dataclass(frozen=True)
class Generated:
    """A generated maze, its figures, and the attempt of its seed that met the ranges."""

    maze: MazeSpec
    figures: Figures
    attempt: int
    settings: GenerateSettings

    def comment(self) -> str:
        """The lines a generated file starts with: how it was made and what it measures."""
        s = self.settings
        knobs = (
            f"style={s.style} rows={s.rows} cols={s.cols} loops={list(s.loops)} "
            f"dead_ends={list(s.dead_ends)} ambiguity={list(s.ambiguity)} "
            f"tolerance={s.tolerance:g} dropoff={s.dropoff} zone_gap={s.zone_gap}"
        )
        return (
            f"made by simmer maze generate --seed {s.seed} (generator {GENERATOR_VERSION}, "
            f"attempt {self.attempt})\n{knobs}\n{self.figures.describe()}"
        )


def generate(settings: GenerateSettings) -> Generated:
    """The maze of ``settings.seed`` meeting the asked ranges (GenerateError if no draw of
    the seed does in :data:`MAX_ATTEMPTS`)."""
    s = settings
    floor_seed = s.floor_seed if s.floor_seed is not None else s.seed % 2**32
    for attempt in range(MAX_ATTEMPTS):
        draws = _Draws(s.seed, attempt)
        if s.style == "perfect":
            opened = _perfect(s.rows, s.cols, draws)
            maze = MazeSpec(_rows(opened), s.cell, 3.0, floor_seed, name=f"perfect-{s.seed}")
            figures = measure(opened, s.cell, s.tolerance, loading_zone=False)
        else:
            made = _course(s, draws)
            if made is None:
                continue
            opened, loading, dropoff = made
            maze = MazeSpec(
                _rows(opened),
                s.cell,
                3.0,
                floor_seed,
                loading,
                {f"B{i + 1}": (cell,) for i, cell in enumerate(dropoff)},
                name=f"course-{s.seed}",
            )
            figures = measure(opened, s.cell, s.tolerance, loading_zone=True)
            if not s.loops[0] <= figures.loop_share <= s.loops[1]:
                continue
        if (
            s.dead_ends[0] <= figures.dead_end_share <= s.dead_ends[1]
            and s.ambiguity[0] <= figures.ambiguity <= s.ambiguity[1]
        ):
            return Generated(maze, figures, attempt, s)
    raise GenerateError(
        f"no {s.style} maze of seed {s.seed} met the asked ranges in {MAX_ATTEMPTS} draws "
        f"(MAX_ATTEMPTS): loops {list(s.loops)}, dead_ends {list(s.dead_ends)}, "
        f"ambiguity {list(s.ambiguity)}; widen a range or change the size"
    )


def _rows(opened: np.ndarray) -> tuple[tuple[bool, ...], ...]:
    return tuple(tuple(bool(v) for v in row) for row in opened)


def _course(
    s: GenerateSettings, draws: _Draws
) -> tuple[np.ndarray, tuple[Cell, ...], list[Cell]] | None:
    """One draw of a course-style maze: its open cells, loading zone and drop-off cells, or
    None if the drop-off zones do not fit apart."""
    rows, cols = s.rows, s.cols
    opened = np.zeros((rows, cols), dtype=bool)
    top = (rows - 2) * draws.below(2)
    left = (cols - 2) * draws.below(2)
    loading = tuple((top + dr, left + dc) for dr in (0, 1) for dc in (0, 1))
    # ``opened`` again as lists with a solid border: neighbour counts without NumPy's
    # per-element cost (the generator's hottest line).
    bordered = [[False] * (cols + 2) for _ in range(rows + 2)]

    def open_cell(r: int, c: int) -> None:
        opened[r, c] = True
        bordered[r + 1][c + 1] = True

    def open_near(r: int, c: int) -> int:
        above, here, below = bordered[r], bordered[r + 1], bordered[r + 2]
        return above[c + 1] + below[c + 1] + here[c] + here[c + 2]

    for r, c in loading:
        open_cell(r, c)

    def neighbours(r: int, c: int) -> list[Cell]:
        return [
            (nr, nc)
            for nr, nc in ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1))
            if 0 <= nr < rows and 0 <= nc < cols
        ]

    # Corridors: randomised Prim's over cells touching exactly one open cell.
    frontier: list[Cell] = []
    listed: set[Cell] = set()
    for cell in loading:
        for near in neighbours(*cell):
            if not opened[near] and near not in listed:
                frontier.append(near)
                listed.add(near)
    while frontier:
        i = draws.below(len(frontier))
        frontier[i], frontier[-1] = frontier[-1], frontier[i]
        r, c = frontier.pop()
        listed.discard((r, c))
        if open_near(r, c) != 1:
            continue
        open_cell(r, c)
        for near in neighbours(r, c):
            if not opened[near] and near not in listed and open_near(*near) == 1:
                frontier.append(near)
                listed.add(near)

    # Loops: open solid cells joining two corridors, no 2 x 2 open square, up to the target.
    target = draws.uniform(*s.loops)
    n = int(opened.sum())
    loops = 0
    candidates = draws.shuffled(
        [(r, c) for r in range(rows) for c in range(cols) if not opened[r, c]]
    )
    for r, c in candidates:
        if loops / n >= target:
            break
        k = open_near(r, c)
        if k < 2 or _makes_square(opened, r, c):
            continue
        if (loops + k - 1) / (n + 1) > s.loops[1]:
            continue
        open_cell(r, c)
        n, loops = n + 1, loops + k - 1

    # Drop-off zones: dead ends first, then any open cell, apart from each other.
    zone_cells = list(loading)
    dead = [
        (r, c)
        for r in range(rows)
        for c in range(cols)
        if opened[r, c] and (r, c) not in loading and open_near(r, c) == 1
    ]
    others = [
        (r, c)
        for r in range(rows)
        for c in range(cols)
        if opened[r, c] and (r, c) not in loading and open_near(r, c) != 1
    ]
    dropoff: list[Cell] = []
    for cell in draws.shuffled(dead) + draws.shuffled(others):
        if len(dropoff) == s.dropoff:
            break
        if all(abs(cell[0] - z[0]) + abs(cell[1] - z[1]) >= s.zone_gap for z in zone_cells):
            dropoff.append(cell)
            zone_cells.append(cell)
    if len(dropoff) < s.dropoff or int(opened.sum()) <= len(zone_cells):
        return None
    dropoff.sort()
    return opened, loading, dropoff


def _makes_square(opened: np.ndarray, r: int, c: int) -> bool:
    """True if opening (r, c) completes a 2 x 2 square of open cells."""
    rows, cols = opened.shape
    for dr in (-1, 0):
        for dc in (-1, 0):
            r0, c0 = r + dr, c + dc
            if 0 <= r0 < rows - 1 and 0 <= c0 < cols - 1:
                square = [(r0, c0), (r0 + 1, c0), (r0, c0 + 1), (r0 + 1, c0 + 1)]
                if all(opened[cell] or cell == (r, c) for cell in square):
                    return True
    return False


def _perfect(rows: int, cols: int, draws: _Draws) -> np.ndarray:
    """A perfect maze: cells on even places, a random depth-first walk opening the walls."""
    opened = np.zeros((rows, cols), dtype=bool)
    start = (2 * draws.below((rows + 1) // 2), 2 * draws.below((cols + 1) // 2))
    opened[start] = True
    stack = [start]
    while stack:
        r, c = stack[-1]
        ways = [
            (r + dr, c + dc)
            for dr, dc in ((-2, 0), (2, 0), (0, -2), (0, 2))
            if 0 <= r + dr < rows and 0 <= c + dc < cols and not opened[r + dr, c + dc]
        ]
        if not ways:
            stack.pop()
            continue
        nr, nc = ways[draws.below(len(ways))]
        opened[(r + nr) // 2, (c + nc) // 2] = True
        opened[nr, nc] = True
        stack.append((nr, nc))
    return opened
