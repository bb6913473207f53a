"""Maze files (docs/mazes.md): a maze of its own that a configuration names
(``maze = "mazes/practice.toml"``), in TOML or as a text picture, and the course's mazes by
name (``maze = "mie444"``).

A maze file is data: TOML is read by ``tomllib`` and a picture character by character, so
nothing in one is ever run. Both are checked before anything is built, and every problem is a
:class:`~simmer.errors.ConfigError` naming the file, the line and the column.

A text picture has one character per cell, first row on top::

    ; the course's maze (lines starting with ; are comments)
    cell = 12
    floor_seed = 5489
    LL..#1#2
    LL#.....
    .#3##.#.
    ......#4

``#`` solid, ``.`` open, ``L`` loading zone, ``1``-``9`` drop-off zones ``B1``-``B9`` (a line
``zone 1 = D1`` renames one), ``S`` a start cell (without any ``S``, a drawn start may use
every open cell outside the zones).
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from importlib.resources import files
from pathlib import Path
from typing import Any, NoReturn

from simmer.config.models import MAX_CELLS_PER_SIDE, SIMMER_DEFAULT_WALLS
from simmer.config.project import Cell
from simmer.config.toml_errors import key_lines, toml_issue
from simmer.errors import ConfigError, ConfigIssue

MAX_MAZE_FILE_BYTES = 1_000_000
"""Largest maze file read: a 500 x 500 picture takes 251 kB, its TOML 750 kB."""
MAX_ZONE_NAME = 16
"""Characters of a drop-off zone's name, as in a configuration's ``[zones]``."""
SOLID, OPEN, LOADING, START = "#", ".", "L", "S"
PICTURE_CHARACTERS = "# . L S 1-9"
TEXT_SUFFIXES = (".txt", ".maze")
MAZE_KEYS = (
    "name",
    "wall_segment_length",
    "floor_segment_length",
    "floor_seed",
    "walls",
    "zones",
    "robot_start_position",
    "robot_start_rotation",
)
"""The settings a maze supplies to a configuration (``zones``: its cells, not ``visible``)."""
_ZONE_KEYS = ("loading", "dropoff", "start")
_HEADER_KEYS = {
    "name": "name",
    "cell": "cell",
    "tile": "tile",
    "floor_seed": "floor_seed",
    "start": "start",
}

Where = Callable[[int, int], tuple[int | None, int | None]]
"""A cell's (row, column) -> its (line, column) in the file, for messages."""


@dataclass(frozen=True)
class MazeSpec:
    """A maze as a file holds it: cells (True = open), cell and tile size, zones, start cells.

    ``start`` None means every open cell outside the zones (the project's convention);
    ``start_pose`` (x, y in inches, heading in degrees) is where the robot starts unless a
    configuration says (None: the centre of the first start cell, facing the configuration's
    heading)."""

    open: tuple[tuple[bool, ...], ...]
    cell: float = 12.0
    tile: float = 3.0
    floor_seed: int = 5489
    loading: tuple[Cell, ...] = ()
    dropoff: Mapping[str, tuple[Cell, ...]] = field(default_factory=dict)
    start: tuple[Cell, ...] | None = None
    name: str = ""
    start_pose: tuple[float, float, float] | None = None

    @property
    def rows(self) -> int:
        """Rows of cells."""
        return len(self.open)

    @property
    def cols(self) -> int:
        """Cells in a row."""
        return len(self.open[0]) if self.open else 0

    def zone_of(self) -> dict[Cell, str]:
        """Each zone cell and its zone's name (``loading`` for the loading zone)."""
        found = dict.fromkeys(self.loading, "loading")
        for name, cells in self.dropoff.items():
            found.update(dict.fromkeys(cells, name))
        return found

    def start_cells(self) -> tuple[Cell, ...]:
        """The cells a drawn start may use."""
        if self.start is not None:
            return self.start
        zoned = self.zone_of()
        return tuple(
            (r, c)
            for r, row in enumerate(self.open)
            for c, is_open in enumerate(row)
            if is_open and (r, c) not in zoned
        )

    def walls(self) -> tuple[tuple[int, ...], ...]:
        """The ``walls`` matrix, with the project's codes: 0 solid, 3 loading, 2 drop-off,
        1 open (so the ``project`` convention reads the same zones from it)."""
        zoned = self.zone_of()
        return tuple(
            tuple(
                0
                if not is_open
                else {"loading": 3}.get(zoned.get((r, c), ""), 2 if (r, c) in zoned else 1)
                for c, is_open in enumerate(row)
            )
            for r, row in enumerate(self.open)
        )

    def settings_data(self) -> dict[str, Any]:
        """The configuration settings this maze supplies."""
        zones: dict[str, Any] = {
            "loading": [list(cell) for cell in self.loading],
            "dropoff": {
                name: [list(cell) for cell in cells] for name, cells in self.dropoff.items()
            },
        }
        if self.start is not None:
            zones["start"] = [list(cell) for cell in self.start]
        pose = {} if self.start_pose is None else {"robot_start_rotation": self.start_pose[2]}
        return {
            **self.places(),
            **pose,
            "walls": [list(row) for row in self.walls()],
            "wall_segment_length": self.cell,
            "floor_segment_length": self.tile,
            "floor_seed": self.floor_seed,
            "zones": zones,
        }

    def places(self) -> dict[str, list[float]]:
        """Where the robot and the block are unless a configuration says: the robot in the
        centre of the first start cell, the block in the centre of the loading zone (or of
        the last open cell, with no loading zone)."""
        starts = self.start_cells() or tuple(
            (r, c) for r, row in enumerate(self.open) for c, v in enumerate(row) if v
        )
        block_cells = (
            self.loading
            or ([(r, c) for r, row in enumerate(self.open) for c, v in enumerate(row) if v][-1:])
        )
        rows = [r for r, _ in block_cells]
        cols = [c for _, c in block_cells]

        def centre(r: float, c: float) -> list[float]:
            return [(c + 0.5) * self.cell, (r + 0.5) * self.cell]

        robot = centre(*starts[0]) if self.start_pose is None else list(self.start_pose[:2])
        return {
            "robot_start_position": robot,
            "block_position": centre(sum(rows) / len(rows), sum(cols) / len(cols)),
        }


def from_walls(
    walls: tuple[tuple[int, ...], ...] | list[list[int]], name: str = "", **sizes: Any
) -> MazeSpec:
    """A maze from a ``walls`` matrix, its zones read by the project's convention (3 loading,
    each 2 a drop-off zone B1, B2... in reading order)."""
    loading = tuple((r, c) for r, row in enumerate(walls) for c, v in enumerate(row) if v == 3)
    twos = [(r, c) for r, row in enumerate(walls) for c, v in enumerate(row) if v == 2]
    dropoff = {f"B{i + 1}": (cell,) for i, cell in enumerate(twos)}
    opened = tuple(tuple(v != 0 for v in row) for row in walls)
    return MazeSpec(opened, loading=loading, dropoff=dropoff, name=name, **sizes)


# ----------------------------------------------------------------------------- checks


def maze_problems(maze: MazeSpec) -> list[tuple[Cell | None, str]]:
    """What makes a maze unusable, each with the cell it is at: no open cell, a zone or start
    cell outside the maze or on a solid cell, a cell in two zones, open cells the robot cannot
    reach from the others. The editor refuses to save such a maze; a file is refused."""
    problems: list[tuple[Cell | None, str]] = []
    if not any(any(row) for row in maze.open):
        return [(None, "has no open cell; open at least one ('.' in a picture, 1 in walls)")]
    seen: dict[Cell, str] = {}
    named = [("loading zone", maze.loading), ("start cell", maze.start or ())]
    named += [(f"drop-off zone {name}", cells) for name, cells in maze.dropoff.items()]
    for what, cells in named:
        for r, c in cells:
            if not (0 <= r < maze.rows and 0 <= c < maze.cols):
                problems.append(
                    (
                        None,
                        f"{what} cell [{r}, {c}] is outside the maze "
                        f"({maze.rows} rows of {maze.cols}); rows and columns count from 0",
                    )
                )
            elif not maze.open[r][c]:
                problems.append(((r, c), f"{what} is on a solid cell; open the cell or move it"))
            elif (r, c) in seen and what != "start cell":
                problems.append(
                    (
                        (r, c),
                        f"{what} and {seen[(r, c)]} share the cell; give each cell to one zone",
                    )
                )
            if what != "start cell":
                seen.setdefault((r, c), what)
    for name in maze.dropoff:
        if not name or len(name) > MAX_ZONE_NAME or not name.isascii() or not name.isalnum():
            problems.append(
                (
                    None,
                    f"zone name {name!r} must be 1 to {MAX_ZONE_NAME} letters or digits, like 'B1'",
                )
            )
    if maze.start_pose is not None:
        x, y, heading = maze.start_pose
        r, c = (int(y // maze.cell), int(x // maze.cell)) if math.isfinite(x + y) else (-1, -1)
        if not math.isfinite(heading) or not (0 <= r < maze.rows and 0 <= c < maze.cols):
            problems.append((None, f"the start pose {maze.start_pose} is not inside the maze"))
        elif not maze.open[r][c]:
            problems.append(((r, c), "the start pose is on a solid cell; drag it to an open one"))
    if problems:
        return problems
    apart = unreachable(maze.open)
    if apart:
        r, c = apart[0]
        more = f" (and {len(apart) - 1} more)" if len(apart) > 1 else ""
        problems.append(
            (
                (r, c),
                f"open cell [{r}, {c}]{more} cannot be reached from the "
                "others; open a way to it or make it solid",
            )
        )
    return problems


def unreachable(opened: tuple[tuple[bool, ...], ...]) -> list[Cell]:
    """The open cells outside the largest 4-connected group of open cells (reading order)."""
    rows, cols = len(opened), len(opened[0])
    group_of: dict[Cell, int] = {}
    sizes: list[int] = []
    for start in ((r, c) for r in range(rows) for c in range(cols) if opened[r][c]):
        if start in group_of:
            continue
        group_of[start] = len(sizes)
        todo, size = [start], 0
        while todo:
            r, c = todo.pop()
            size += 1
            for near in ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)):
                nr, nc = near
                if 0 <= nr < rows and 0 <= nc < cols and opened[nr][nc] and near not in group_of:
                    group_of[near] = len(sizes)
                    todo.append(near)
        sizes.append(size)
    biggest = max(range(len(sizes)), key=lambda i: sizes[i]) if sizes else 0
    return sorted(cell for cell, group in group_of.items() if group != biggest)


def _refuse(source: str, problems: list[tuple[Cell | None, str]], where: Where) -> None:
    """Raise the problems as one ConfigError naming each cell's line and column."""
    if not problems:
        return
    issues = []
    for cell, message in problems:
        line, column = where(*cell) if cell is not None else (None, None)
        prefix = f"column {column}: " if column is not None else ""
        issues.append(ConfigIssue("", prefix + message, line))
    raise ConfigError(source, issues)


# ----------------------------------------------------------------------------- text picture


def read_text(text: str, source: str = "<maze>") -> MazeSpec:
    """A maze from its text picture (see the module docstring)."""
    header: dict[str, Any] = {"name": "", "cell": 12.0, "tile": 3.0, "floor_seed": 5489}
    renamed: dict[str, str] = {}
    rows: list[str] = []
    first: list[int] = []  # the line of each row
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith(";"):
            continue
        if "=" in line:
            if rows:
                _fail(
                    source,
                    number,
                    1,
                    "a setting after the picture's rows; put every "
                    "`key = value` line above the picture",
                )
            _header_line(line, number, source, header, renamed)
            continue
        rows.append(raw.rstrip())
        first.append(number)
        if len(rows) > MAX_CELLS_PER_SIDE:
            _fail(
                source,
                number,
                1,
                f"more than {MAX_CELLS_PER_SIDE} rows (MAX_CELLS_PER_SIDE); the lab maze has 4",
            )
    if not rows:
        _fail(
            source,
            None,
            None,
            f"has no picture: write one line of cells per row, using {PICTURE_CHARACTERS}",
        )
    width = len(rows[0])
    opened: list[tuple[bool, ...]] = []
    loading: list[Cell] = []
    dropoff: dict[str, list[Cell]] = {}
    start: list[Cell] = []
    for r, row in enumerate(rows):
        if len(row) > MAX_CELLS_PER_SIDE:
            _fail(
                source,
                first[r],
                MAX_CELLS_PER_SIDE + 1,
                f"more than {MAX_CELLS_PER_SIDE} "
                "cells in a row (MAX_CELLS_PER_SIDE); the lab maze has 8",
            )
        if len(row) != width:
            _fail(
                source,
                first[r],
                min(len(row), width) + 1,
                f"this row has {len(row)} cells "
                f"but the first has {width}; every row needs the same number",
            )
        cells = []
        for c, char in enumerate(row):
            if char == SOLID:
                cells.append(False)
                continue
            cells.append(True)
            if char == LOADING:
                loading.append((r, c))
            elif char == START:
                start.append((r, c))
            elif char in "123456789":
                dropoff.setdefault(renamed.get(char, f"B{char}"), []).append((r, c))
            elif char != OPEN:
                _fail(
                    source,
                    first[r],
                    c + 1,
                    f"unknown character {char!r}; a cell is one of "
                    f"{PICTURE_CHARACTERS} (docs/mazes.md)",
                )
        opened.append(tuple(cells))
    maze = MazeSpec(
        tuple(opened),
        float(header["cell"]),
        float(header["tile"]),
        int(header["floor_seed"]),
        tuple(loading),
        {name: tuple(cells) for name, cells in sorted(dropoff.items(), key=lambda i: i[1][0])},
        tuple(start) or None,
        str(header["name"]),
        header.get("start"),
    )
    _refuse(source, maze_problems(maze), lambda r, c: (first[r], c + 1))
    return maze


def _header_line(
    line: str, number: int, source: str, header: dict[str, Any], renamed: dict[str, str]
) -> None:
    """One ``key = value`` line above a picture."""
    key, _, value = (part.strip() for part in line.partition("="))
    if key.startswith("zone "):
        digit = key[5:].strip()
        if len(digit) != 1 or digit not in "123456789":
            _fail(
                source, number, 1, f"`{key}`: name a drop-off zone by its digit, like `zone 1 = D1`"
            )
        if not value.isascii() or not value.isalnum() or len(value) > MAX_ZONE_NAME:
            _fail(
                source,
                number,
                _value_column(line),
                f"zone name {value!r} must be 1 to {MAX_ZONE_NAME} letters or digits, like 'B1'",
            )
        renamed[digit] = value
        return
    if key not in _HEADER_KEYS:
        _fail(
            source,
            number,
            1,
            f"unknown setting {key!r}; a picture may set "
            "name, cell, tile, floor_seed, start and `zone N = NAME`",
        )
    if key == "name":
        header["name"] = value.strip("\"'")
        return
    if key == "start":
        header["start"] = _pose(value.split(","), source, number, _value_column(line))
        return
    try:
        number_value = float(value) if key != "floor_seed" else int(value)
    except ValueError:
        number_value = math.nan
    if key == "floor_seed" and not (isinstance(number_value, int) and 0 <= number_value < 2**32):
        _fail(
            source,
            number,
            _value_column(line),
            f"floor_seed must be a whole number from 0 to {2**32 - 1}, not {value!r}",
        )
    if key != "floor_seed" and not (math.isfinite(number_value) and number_value > 0):
        _fail(
            source,
            number,
            _value_column(line),
            f"{key} must be a number of inches above 0, not {value!r}",
        )
    header[key] = number_value


def _pose(
    values: Any, source: str, line: int | None, column: int | None
) -> tuple[float, float, float]:
    """A start pose (x, y in inches, heading in degrees) checked, or a one-line ConfigError."""
    try:
        pose = tuple(float(v) for v in values)
    except (TypeError, ValueError):
        pose = ()
    if len(pose) != 3 or not all(math.isfinite(v) for v in pose):
        _fail(source, line, column, "the start pose is x, y, heading: three numbers (18, 30, 90)")
    return (pose[0], pose[1], pose[2])


def _value_column(line: str) -> int:
    """The column where a ``key = value`` line's value starts."""
    return len(line) - len(line.partition("=")[2].lstrip()) + 1


def _fail(source: str, line: int | None, column: int | None, message: str) -> NoReturn:
    prefix = f"column {column}: " if column is not None else ""
    raise ConfigError(source, [ConfigIssue("", prefix + message, line)])


def write_text(maze: MazeSpec, comment: str = "") -> str:
    """The maze as a text picture (``read_text`` reads it back to the same maze)."""
    if len(maze.dropoff) > 9:
        raise ValueError(
            f"{len(maze.dropoff)} drop-off zones: a picture has the digits 1-9; "
            "save the maze as TOML"
        )
    lines = [f"; {part}" for part in comment.splitlines()] if comment else []
    lines.append(f"; {maze.cols} x {maze.rows} cells; {PICTURE_CHARACTERS} (docs/mazes.md)")
    if maze.name:
        lines.append(f"name = {maze.name}")
    lines += [f"cell = {maze.cell:g}", f"tile = {maze.tile:g}", f"floor_seed = {maze.floor_seed}"]
    if maze.start_pose is not None:
        lines.append("start = " + ", ".join(f"{v!r}" for v in maze.start_pose))
    chars: dict[Cell, str] = dict.fromkeys(maze.loading, LOADING)
    for i, (name, cells) in enumerate(maze.dropoff.items()):
        digit = str(i + 1)
        if name != f"B{digit}":
            lines.append(f"zone {digit} = {name}")
        chars.update(dict.fromkeys(cells, digit))
    for cell in maze.start or ():
        chars.setdefault(cell, START)
    for r, row in enumerate(maze.open):
        lines.append("".join(chars.get((r, c), OPEN) if v else SOLID for c, v in enumerate(row)))
    return "\n".join(lines) + "\n"


# ----------------------------------------------------------------------------- TOML


def read_toml(text: str, source: str = "<maze>") -> MazeSpec:
    """A maze from a TOML maze file: ``walls`` (0 solid, any other whole number open; the
    project's codes give zones unless ``[zones]`` names them), ``wall_segment_length``,
    ``floor_segment_length``, ``floor_seed``, ``name`` and ``[zones]`` (``loading``,
    ``dropoff``, ``start``), as in a configuration."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(source, [toml_issue(exc, text)]) from None
    except RecursionError:
        _fail(source, None, None, "lists are nested too deeply to read; walls nests 2 deep")
    lines = key_lines(text)
    for key in data:
        if key not in MAZE_KEYS:
            _fail(
                source,
                lines.get((key,)),
                1,
                f"unknown key {key!r}; a maze file has {', '.join(MAZE_KEYS)} (docs/mazes.md)",
            )
    rows_at = _row_places(text)
    where: Where = lambda r, c: rows_at[r] if r < len(rows_at) else (lines.get(("walls",)), None)  # noqa: E731
    walls = data.get("walls")
    walls_line = lines.get(("walls",))
    if not isinstance(walls, list) or not walls or not all(isinstance(r, list) for r in walls):
        _fail(
            source,
            walls_line,
            None,
            "walls must be a list of rows of whole numbers, "
            "e.g. walls = [[1, 1], [0, 1]] (0 solid, 1 open)",
        )
    if len(walls) > MAX_CELLS_PER_SIDE:
        _fail(
            source,
            walls_line,
            None,
            f"walls has {len(walls):,} rows, more than "
            f"{MAX_CELLS_PER_SIDE} (MAX_CELLS_PER_SIDE); the lab maze has 4",
        )
    width = len(walls[0])
    for r, row in enumerate(walls):
        line, column = where(r, 0)
        if len(row) > MAX_CELLS_PER_SIDE:
            _fail(
                source,
                line,
                column,
                f"walls[{r}] has {len(row):,} cells, more than "
                f"{MAX_CELLS_PER_SIDE} (MAX_CELLS_PER_SIDE); the lab maze has 8",
            )
        if len(row) != width or not row:
            _fail(
                source,
                line,
                column,
                f"walls[{r}] has {len(row)} cells but walls[0] has "
                f"{width}; every row needs the same number",
            )
        for c, value in enumerate(row):
            if isinstance(value, bool) or not isinstance(value, int) or value < 0:
                _fail(
                    source,
                    line,
                    column,
                    f"walls[{r}][{c}] is {value!r}; a cell is a whole "
                    "number: 0 solid, 1 open, 2 drop-off zone, 3 loading zone",
                )
    maze = from_walls(walls)
    zones = data.get("zones", {})
    if not isinstance(zones, dict):
        _fail(source, lines.get(("zones",)), None, "zones must be a table ([zones])")
    for key in zones:
        if key not in _ZONE_KEYS:
            _fail(
                source,
                lines.get(("zones", key)),
                1,
                f"unknown key zones.{key}; a maze names {', '.join(_ZONE_KEYS)}",
            )
    loading = _cells(zones.get("loading", maze.loading), "zones.loading", source, lines)
    start = zones.get("start")
    raw_dropoff = zones.get("dropoff")
    if raw_dropoff is not None and not isinstance(raw_dropoff, dict):
        _fail(
            source,
            lines.get(("zones", "dropoff")),
            None,
            "zones.dropoff must be a table: { B1 = [[0, 5]], ... }",
        )
    dropoff = (
        maze.dropoff
        if raw_dropoff is None
        else {
            str(name): _cells(cells, f"zones.dropoff.{name}", source, lines)
            for name, cells in raw_dropoff.items()
        }
    )
    sizes = {}
    for key, default in (("wall_segment_length", 12.0), ("floor_segment_length", 3.0)):
        value = data.get(key, default)
        if isinstance(value, bool) or not isinstance(value, int | float) or not 0 < value < 1e6:
            _fail(
                source,
                lines.get((key,)),
                None,
                f"{key} must be a number of inches above 0, not {value!r}",
            )
        sizes[key] = float(value)
    seed = data.get("floor_seed", 5489)
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**32:
        _fail(
            source,
            lines.get(("floor_seed",)),
            None,
            f"floor_seed must be a whole number from 0 to {2**32 - 1}, not {seed!r}",
        )
    name = data.get("name", "")
    if not isinstance(name, str):
        _fail(source, lines.get(("name",)), None, "name must be text in quotes")
    pose = None
    if "robot_start_position" in data or "robot_start_rotation" in data:
        xy = data.get("robot_start_position")
        at = lines.get(("robot_start_position",)) or lines.get(("robot_start_rotation",))
        if isinstance(xy, bool) or not isinstance(xy, list) or any(isinstance(v, bool) for v in xy):
            xy = [math.nan]
        pose = _pose([*xy, data.get("robot_start_rotation", 0.0)], source, at, None)
    spec = MazeSpec(
        maze.open,
        sizes["wall_segment_length"],
        sizes["floor_segment_length"],
        seed,
        loading,
        dropoff,
        None if start is None else _cells(start, "zones.start", source, lines),
        name,
        pose,
    )
    _refuse(source, maze_problems(spec), where)
    return spec


def _cells(
    value: Any, key: str, source: str, lines: dict[tuple[str, ...], int]
) -> tuple[Cell, ...]:
    """``[[row, col], ...]`` checked, or a one-line ConfigError at the key's line."""
    ok = isinstance(value, list | tuple) and all(
        isinstance(cell, list | tuple)
        and len(cell) == 2
        and all(isinstance(v, int) and not isinstance(v, bool) for v in cell)
        for cell in value
    )
    if not ok:
        line = lines.get(tuple(key.split(".")))
        if line is None:
            line = lines.get(tuple(key.split(".")[:2]))
        _fail(
            source,
            line,
            None,
            f"{key} must be a list of [row, column] cells, e.g. [[0, 0], [0, 1]]",
        )
    return tuple((int(r), int(c)) for r, c in value)


def _row_places(text: str) -> list[tuple[int | None, int | None]]:
    """The (line, column) where each row of ``walls = [[...], ...]`` opens, by a scan of the
    text (for messages: the file is already known to parse)."""
    places: list[tuple[int | None, int | None]] = []
    start = text.find("walls")
    while start >= 0 and text[:start].rstrip(" \t").rsplit("\n", 1)[-1].strip():
        start = text.find("walls", start + 1)  # a key starts its line
    if start < 0:
        return places
    depth, in_comment = 0, False
    line = text.count("\n", 0, start) + 1
    line_start = text.rfind("\n", 0, start) + 1
    for i in range(text.index("=", start) + 1, len(text)):
        char = text[i]
        if char == "\n":
            line, line_start, in_comment = line + 1, i + 1, False
        elif in_comment:
            continue
        elif char == "#":
            in_comment = True
        elif char == "[":
            depth += 1
            if depth == 2:
                places.append((line, i - line_start + 1))
        elif char == "]":
            depth -= 1
            if depth == 0:
                break
    return places


def write_toml(maze: MazeSpec, comment: str = "") -> str:
    """The maze as a TOML maze file (``read_toml`` reads it back to the same maze)."""
    lines = [f"# {part}" for part in comment.splitlines()] if comment else []
    lines.append(f"# SimMeR maze file: {maze.cols} x {maze.rows} cells (docs/mazes.md)")
    if maze.name:
        lines.append(f"name = {_quoted(maze.name)}")
    lines += [
        f"wall_segment_length = {maze.cell!r}",
        f"floor_segment_length = {maze.tile!r}",
        f"floor_seed = {maze.floor_seed}",
        *(
            [
                f"robot_start_position = [{maze.start_pose[0]!r}, {maze.start_pose[1]!r}]",
                f"robot_start_rotation = {maze.start_pose[2]!r}",
            ]
            if maze.start_pose is not None
            else []
        ),
        "walls = [   # 0 solid, 1 open, 2 drop-off zone, 3 loading zone",
    ]
    lines += [f"    [{', '.join(map(str, row))}]," for row in maze.walls()]
    lines += ["]", "", "[zones]", f"loading = {_cell_list(maze.loading)}"]
    if maze.start is not None:
        lines.append(f"start = {_cell_list(maze.start)}")
    lines += ["", "[zones.dropoff]"]
    lines += [f"{name} = {_cell_list(cells)}" for name, cells in maze.dropoff.items()]
    return "\n".join(lines) + "\n"


def _cell_list(cells: tuple[Cell, ...]) -> str:
    return "[" + ", ".join(f"[{r}, {c}]" for r, c in cells) + "]"


def _quoted(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


# ----------------------------------------------------------------------------- files, names


COURSE_MAZES: dict[str, str] = {
    "mie444": "The maze every SimMeR release's config.py has: 8 x 4 cells of 12 in, the "
    "2023 lab's and the 2024-25 project's (loading zone top left, drop-off zones B1-B4).",
}
"""The course's mazes by name, each a picture in ``simmer/data/mazes/NAME.txt``."""


def course_maze(name: str) -> MazeSpec:
    """One of the course's mazes by name (KeyError if there is none)."""
    if name not in COURSE_MAZES:
        raise KeyError(name)
    text = files("simmer").joinpath(f"data/mazes/{name}.txt").read_text(encoding="utf-8")
    return read_text(text, name)


def read_maze(path: str | Path) -> MazeSpec:
    """A maze file (TOML, or a text picture if it ends in .txt or .maze), checked; every
    problem a one-line ConfigError with the file, line and column."""
    path = Path(path)
    if not path.is_file():
        what = "is not a regular file" if path.exists() else "no such maze file"
        names = ", ".join(COURSE_MAZES)
        raise ConfigError(
            path,
            [
                ConfigIssue(
                    "", f"{what}; give a .toml or .txt maze file, or a course maze's name ({names})"
                )
            ],
        )
    size = path.stat().st_size
    if size > MAX_MAZE_FILE_BYTES:
        raise ConfigError(
            path,
            [
                ConfigIssue(
                    "",
                    f"is {size:,} bytes, more than any maze file "
                    f"({MAX_MAZE_FILE_BYTES:,} at most, "
                    "MAX_MAZE_FILE_BYTES); is this the right file?",
                )
            ],
        )
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(
            path, [ConfigIssue("", f"cannot read the file: {exc}; save it as UTF-8 text")]
        ) from None
    if path.suffix.lower() in TEXT_SUFFIXES:
        return read_text(text, str(path))
    return read_toml(text, str(path))


def write_maze(maze: MazeSpec, path: str | Path, comment: str = "") -> None:
    """Save a maze: a text picture for .txt or .maze, TOML otherwise; its folder is made if
    missing (``-o mazes/m7.toml`` from a folder with no ``mazes/`` yet, as docs/mazes.md has it)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    text = (
        write_text(maze, comment)
        if path.suffix.lower() in TEXT_SUFFIXES
        else write_toml(maze, comment)
    )
    path.write_text(text, encoding="utf-8", newline="\n")


def default_maze() -> MazeSpec:
    """The built-in default configuration's maze (SimMeR's, the course's)."""
    return from_walls(SIMMER_DEFAULT_WALLS, "mie444")
