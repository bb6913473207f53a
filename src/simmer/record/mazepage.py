"""A maze on a page (``simmer maze show --png``): the floor, solid cells, zones and walls as the
scene draws them, and optionally its ambiguity map. Matplotlib is imported only here, when
something is drawn."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from simmer.config.maze import Maze
from simmer.config.models import Settings
from simmer.config.zones import Zones
from simmer.record.page import draw_items, rgb
from simmer.record.safefile import replacing
from simmer.scene import Look, ambiguity_items, maze_items

PAGE_INCHES = 9.0
"""The longer side of the maze on the page."""


def maze_png(settings: Settings, target: Path, alike: np.ndarray | None, title: str) -> None:
    """Write the maze a configuration's settings describe as a PNG at ``target``; with
    ``alike`` (each cell's count of look-alikes), its ambiguity map over the floor."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    maze = Maze.from_settings(settings)
    scale = max(maze.width, maze.height) / PAGE_INCHES
    fig = Figure(figsize=(maze.width / scale + 0.6, maze.height / scale + 1.0), dpi=100)
    ax = fig.add_subplot()
    ax.set_facecolor(rgb(settings.background_color))
    items = maze_items(maze, settings, Look.PAGE, Zones.from_settings(settings))
    if alike is not None:
        items = sorted(items + ambiguity_items(alike, maze.cell), key=lambda item: item.layer)
    draw_items(ax, items)
    margin = maze.cell * 0.1
    ax.set_xlim(-margin, maze.width + margin)
    ax.set_ylim(maze.height + margin, -margin)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    ax.set_title(title, fontsize=10)
    fig.tight_layout()
    FigureCanvasAgg(fig)
    with replacing(target, run_folder=False) as temp:
        fig.savefig(temp, dpi=fig.dpi, format="png")
