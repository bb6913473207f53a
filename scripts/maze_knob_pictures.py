"""Draw docs/img/maze_knobs.png: what the maze generator's knobs do (docs/mazes.md), each
maze with its ambiguity map. Run: .venv/bin/python scripts/maze_knob_pictures.py [OUT.png]"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from simmer.config.maze import Maze
from simmer.config.mazegen import generate, measure
from simmer.config.models import Settings
from simmer.config.project import GenerateSettings
from simmer.config.zones import Zones
from simmer.record.page import draw_items
from simmer.scene import Look, ambiguity_items, maze_items

PANELS = (
    ("defaults (seed 2)", {"seed": 2}),
    ("loops = [0, 0]: a tree", {"seed": 2, "loops": [0, 0]}),
    ("loops = [0.1, 0.15]", {"seed": 2, "loops": [0.1, 0.15]}),
    ("ambiguity = [0, 0.25]: easy to localize", {"seed": 2, "ambiguity": [0, 0.25]}),
    ("ambiguity = [0.6, 1]: hard", {"seed": 2, "ambiguity": [0.6, 1]}),
    ("rows = 6, cols = 12", {"seed": 2, "rows": 6, "cols": 12}),
    ("dead_ends = [0, 0.08]", {"seed": 2, "dead_ends": [0, 0.08]}),
    ("style = perfect (5 x 9)", {"seed": 2, "style": "perfect"}),
    ("style = perfect, 9 x 15", {"seed": 2, "style": "perfect", "rows": 9, "cols": 15}),
)


def main(target: Path) -> None:
    """Draw every panel's maze into one PNG at ``target``."""
    fig = Figure(figsize=(15, 8.6), layout="constrained")
    for i, (title, knobs) in enumerate(PANELS):
        made = generate(GenerateSettings.model_validate(knobs)).maze
        settings = Settings.model_validate(made.settings_data())
        maze = Maze.from_settings(settings)
        opened = np.array(made.open)
        figures = measure(opened, made.cell, 1.0, loading_zone=len(made.loading) == 4)
        ax = fig.add_subplot(3, 3, i + 1)
        items = maze_items(maze, settings, Look.MAP, Zones.from_settings(settings))
        items = sorted(items + ambiguity_items(figures.alike, maze.cell), key=lambda it: it.layer)
        draw_items(ax, items)
        ax.set_xlim(-1, maze.width + 1)
        ax.set_ylim(maze.height + 1, -1)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_title(
            f"{title}\nloops {figures.loop_share:.2f}, dead ends {figures.dead_end_share:.2f}, "
            f"ambiguity {figures.ambiguity:.2f}",
            fontsize=9,
        )
    FigureCanvasAgg(fig)
    fig.savefig(target, dpi=90)
    print(f"wrote {target}")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "docs/img/maze_knobs.png"))
