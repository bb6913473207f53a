"""The scene on a page: :mod:`simmer.scene`'s items drawn on a matplotlib ``Axes`` (a run's
path plot, a sweep's pictures), in world inches, each item at its layer (its z-order).

Matplotlib is imported only when something is drawn, so importing this costs nothing.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING, Any

from simmer.scene import Arrow, Cells, Grid, Item, Label, Outline, Walls

if TYPE_CHECKING:
    from matplotlib.axes import Axes

LABEL_BOX = {"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.8}
"""The pale box behind a boxed label."""


def rgb(color: Sequence[int]) -> tuple[float, float, float]:
    """A 0-255 RGB colour as matplotlib's 0-1."""
    r, g, b = color[:3]
    return r / 255, g / 255, b / 255


def draw_items(ax: Axes, items: Iterable[Item]) -> None:
    """Draw a page scene's items (:attr:`~simmer.scene.Look.PAGE` or ``MAP``) on ``ax``."""
    from matplotlib.collections import LineCollection
    from matplotlib.patches import Polygon, Rectangle

    for item in items:
        if isinstance(item, Grid):
            rows, cols = item.rgba.shape[:2]
            extent = (0.0, cols * item.cell, rows * item.cell, 0.0)
            image = ax.imshow(item.rgba, extent=extent, interpolation="nearest", zorder=item.layer)
            clip = Rectangle((0, 0), item.width, item.height, transform=ax.transData)
            image.set_clip_path(clip)
        elif isinstance(item, Walls):
            lines = list(item.lines.reshape(-1, 2, 2))
            colors = [rgb(item.color)]
            walls = LineCollection(lines, colors=colors, lw=item.width, zorder=item.layer)
            walls.set_capstyle("projecting")  # a slab: its ends reach past the segment's
            ax.add_collection(walls)
        elif isinstance(item, Cells):
            for x, y, w, h in item.rects:
                fill = (*rgb(item.color), item.alpha)
                ax.add_patch(Rectangle((x, y), w, h, fc=fill, ec="none", zorder=item.layer))
        elif isinstance(item, Label):
            style: dict[str, Any] = {"va": "top", "fontsize": item.size, "zorder": item.layer}
            if item.boxed:
                style |= {"fontweight": "bold", "bbox": LABEL_BOX}
            ax.text(*item.at, item.text, color=rgb(item.color), **style)
        elif isinstance(item, Outline):
            ax.add_patch(
                Polygon(
                    item.points,
                    closed=True,
                    fill=item.fill is not None,
                    fc=rgb(item.fill) if item.fill is not None else "none",
                    ec=rgb(item.edge) if item.edge is not None else "none",
                    lw=item.width,
                    ls="--" if item.dashed else "-",
                    zorder=item.layer,
                )
            )
        elif isinstance(item, Arrow):
            props = {"arrowstyle": "-|>", "color": rgb(item.color), "lw": item.width}
            ax.annotate("", xy=item.end, xytext=item.start, arrowprops=props, zorder=item.layer)
        else:
            raise ValueError(f"a page does not draw {type(item).__name__}")
