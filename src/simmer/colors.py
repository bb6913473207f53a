"""Colours (RGB) and pixel types the window, videos and plots share: a leaf module with no
pygame, so the run's plots (:mod:`simmer.record.plots`) colour the floor and zones as the
window paints them without importing the window."""

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
