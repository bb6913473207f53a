"""Colours (RGB) and pixel types the window, videos and plots share: a leaf module with no
pygame, so the scene (:mod:`simmer.scene`) colours the floor and zones of every picture alike
without importing the window."""

from __future__ import annotations

Color = tuple[int, int, int]
Point = tuple[float, float]
Rect = tuple[float, float, float, float]

WHITE_TILE: Color = (235, 235, 235)
BLACK_TILE: Color = (30, 30, 30)
GHOST_COLOR: Color = (255, 90, 90)
RULER_COLOR: Color = (220, 235, 235)
TRAIL_COLOR: Color = (255, 140, 0)
"""The path driven so far: orange, as on path.png, visible on white and black tiles."""
LOADING_COLOR: Color = (40, 110, 230)
"""The loading zone's outline on the floor: blue."""
DROPOFF_COLOR: Color = (20, 170, 60)
"""A drop-off zone's outline: green."""
TARGET_COLOR: Color = (250, 200, 0)
"""The run's target zone: yellow, over its green outline."""
START_COLOR: Color = (26, 152, 80)
"""The robot at its start on a run's path plot: green."""
MAP_SOLID: Color = (85, 85, 85)
"""A solid cell on a sweep's map of the maze: grey."""
MAP_ZONE: Color = (221, 230, 245)
"""A zone's cells on a sweep's map: pale blue, under the picture's own colours."""
MAP_INK: Color = (0, 0, 0)
"""Walls and zone names on a sweep's map: black."""
RUN_COLORS: tuple[Color, ...] = (
    (230, 60, 200),
    (0, 185, 230),
    (255, 140, 0),
    (140, 90, 240),
    (150, 210, 30),
    (0, 150, 140),
)
"""Runs side by side (``simmer replay RUN_A RUN_B``): one each, in order; none is the zones'
blue, green or yellow, nor the red that marks a collision."""
COLLISION_COLOR: Color = (255, 40, 40)
"""The mark on a run side by side that has collided: red."""


def tint(color: Color, amount: float, toward: Color = (255, 255, 255)) -> Color:
    """``color`` moved ``amount`` (0..1) of the way toward ``toward``."""
    r, g, b = (round(c + (t - c) * amount) for c, t in zip(color, toward, strict=True))
    return (r, g, b)
