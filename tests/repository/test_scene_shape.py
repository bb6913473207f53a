"""One scene description (issue 29): only :mod:`simmer.scene` decides what the maze, its zones,
the block and the robot are drawn as. The window, videos, replays, a run's plots and a sweep's
pictures draw its items through their adapters (``ui/scene.py``'s ``paint_items``,
``record/page.py``'s ``draw_items``) and never read the maze's or robot's geometry to draw it
themselves, as the window, plots.py and pictures.py each once did."""

from __future__ import annotations

import ast
from pathlib import Path

from helpers import REPO

SRC = REPO / "src" / "simmer"

DRAWING = ("ui", "view", "record", "sweep", "serve.py")
"""The code that draws pictures (or models them), above the scene's layer."""
MAZE_GEOMETRY = {"floor_white", "segments", "solid", "hwall", "vwall"}
"""A maze's (or block's) drawable parts: what the scene makes items of."""
SHAPE_MAKERS = {"robot_outline", "Block", "ZONE_INSET", "ZONE_LINE"}
"""Where the robot's outline, the block's polygon and a zone's outline come from."""


def drawing_modules() -> list[Path]:
    return sorted(
        path
        for part in DRAWING
        for path in ((SRC / part).rglob("*.py") if (SRC / part).is_dir() else [SRC / part])
    )


def offences(path: Path) -> list[str]:
    """Each place ``path`` reads maze geometry or names a shape maker, as ``line: what``."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Attribute) and node.attr in MAZE_GEOMETRY:
            found.append(f"{node.lineno}: .{node.attr}")
        elif isinstance(node, ast.Name) and node.id in SHAPE_MAKERS:
            found.append(f"{node.lineno}: {node.id}")
        elif isinstance(node, ast.ImportFrom):
            found += [
                f"{node.lineno}: import {a.name}" for a in node.names if a.name in SHAPE_MAKERS
            ]
    return found


def test_only_the_scene_decides_what_the_maze_zones_block_and_robot_are_drawn_as() -> None:
    modules = drawing_modules()
    assert SRC / "ui" / "scene.py" in modules
    assert SRC / "record" / "plots.py" in modules
    assert SRC / "sweep" / "pictures.py" in modules
    found = {str(path.relative_to(SRC)): said for path in modules if (said := offences(path))}
    assert found == {}, "draw it through simmer.scene's items instead"


def test_the_check_sees_a_module_that_draws_the_walls_itself(tmp_path: Path) -> None:
    """What pictures.py did before the scene: its own loop over the maze's wall segments."""
    path = tmp_path / "own_walls.py"
    path.write_text(
        "from simmer.config.maze import Block, Maze\n"
        "def draw(ax, maze: Maze) -> None:\n"
        "    for x1, y1, x2, y2 in maze.segments:\n"
        "        ax.plot([x1, x2], [y1, y2], color='black', lw=2)\n",
        encoding="utf-8",
    )
    assert offences(path) == ["1: import Block", "3: .segments"]
