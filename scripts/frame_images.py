"""Draw docs/img/coordinate_frame.png (SimMeR's coordinate frame: x, y, heading, a positive
turn, as the window shows them) and docs/img/blocked_move.png (the window with the axes mark,
the heading dial and a blocked move), so the pictures in the docs are made by code, not by hand.

    .venv/bin/python scripts/frame_images.py            # writes both into docs/img
"""

from __future__ import annotations

import math
import os
import sys
from pathlib import Path

IMG = Path(__file__).resolve().parent.parent / "docs" / "img"


def coordinate_frame(path: Path) -> None:
    """The frame as the window shows it: origin top left, x right, y down; headings 0, 90,
    180 and 270 and which way a positive turn goes; a move's dx and dy."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import FancyArrowPatch, Polygon

    fig, ax = plt.subplots(figsize=(10, 5.2), dpi=110)
    ax.set_xlim(-3, 84)
    ax.set_ylim(38, -5)  # y grows downward, as in the window
    ax.set_aspect("equal")
    ax.axis("off")
    ax.add_patch(Polygon([(0, 0), (54, 0), (54, 36), (0, 36)], fill=False, lw=2, ec="#c00000"))
    arrow = {"arrowstyle": "-|>", "mutation_scale": 16, "lw": 2, "color": "black"}
    ax.add_patch(FancyArrowPatch((0, 0), (14, 0), **arrow))
    ax.add_patch(FancyArrowPatch((0, 0), (0, 14), **arrow))
    ax.text(14.6, -1.2, "+x (inches)", va="center", fontsize=11)
    ax.text(0.8, 16.0, "+y (inches):\ndown the\nscreen", va="top", fontsize=11)
    ax.text(-0.6, -3.2, "origin (0, 0): the maze's top-left corner", fontsize=10)

    cx, cy = 29.0, 17.0  # the robot, heading 0
    body = [(-2.9, -4), (-2.9, 2.75), (-1.7, 4), (1.7, 4), (2.9, 2.75), (2.9, -4)]
    ax.add_patch(Polygon([(cx + x, cy + y) for x, y in body], fc="#c8c8ff", ec="#0000c0", lw=2))
    headings = (
        (0, "0: faces +y\n(down)"),
        (90, "90: faces -x\n(left)"),
        (180, "180: faces -y (up)"),
        (270, "270: faces +x\n(right)"),
    )
    for heading, words in headings:
        rad = math.radians(heading)
        dx, dy = -math.sin(rad), math.cos(rad)
        tip = (cx + dx * 11, cy + dy * 11)
        style = {**arrow, "color": "#0000c0" if heading == 0 else "#555555"}
        ax.add_patch(FancyArrowPatch((cx + dx * 5, cy + dy * 5), tip, **style))
        ax.text(tip[0] + dx * 1.5, tip[1] + dy * 2.2, f"heading {words}", ha="center",
                va="center", fontsize=10)  # fmt: skip
    turn = {**arrow, "color": "#d07000", "connectionstyle": "arc3,rad=-0.6"}
    ax.add_patch(FancyArrowPatch((cx + 7.5, cy + 6), (cx - 7.5, cy + 6), **turn))
    ax.text(cx + 7.5, cy + 9.0, "r0-90: heading\ngrows by 90:\nclockwise\non screen",
            color="#d07000", fontsize=10)  # fmt: skip
    ax.text(56, 1.0,
            "Robot frame: +y forward\n(w0-6 drives 6 in ahead),\n+x to the robot's left.\n\n"
            "A move of d inches at heading h:\n  dx = -d sin h,  dy = d cos h\n"
            "\nWith y up, as in a maths\nbook, the same headings\nturn counter-clockwise.",
            fontsize=9.5, va="top", family="monospace")  # fmt: skip
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def blocked_move(path: Path) -> None:
    """The window on the default scene after ``w0-24``, ``r0-90`` and a ``w0-30`` that runs
    into a wall: the axes mark, the heading dial and the blocked move in red."""
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    import pygame

    from simmer import Simulation
    from simmer.ui.offscreen import OffscreenRenderer
    from simmer.view.snapshot import Snapshot, StaticScene
    from simmer.world.outcome import Outcome

    pygame.init()
    sim = Simulation.from_config()
    outcome = Outcome.attach(sim)
    for command in ("w0-24", "r0-90"):
        sim.command(command)
        sim.run_until_idle()
    sim.command("w0-30")
    sim.step(200)
    offscreen = OffscreenRenderer(StaticScene.of(sim))
    offscreen.draw(Snapshot.of(sim, outcome=outcome.report()))
    pygame.image.save(offscreen.surface, str(path))


def main() -> None:
    """Write both pictures (into the folder given, default docs/img)."""
    folder = Path(sys.argv[1]) if len(sys.argv) > 1 else IMG
    coordinate_frame(folder / "coordinate_frame.png")
    blocked_move(folder / "blocked_move.png")
    print(f"wrote {folder / 'coordinate_frame.png'} and {folder / 'blocked_move.png'}")


if __name__ == "__main__":
    main()
