"""The program's belief drawn over the maze (``robot.show``): particles, cell probabilities,
the pose estimate with its uncertainty ellipse, a planned path, points and labels, under
the true robot. The window toggles it with B; videos and replays draw it too."""

from __future__ import annotations

import math

import numpy as np

from simmer.colors import Color, tint
from simmer.localize.belief import Belief
from simmer.ui.render import Renderer
from simmer.ui.scene import View

BELIEF_COLOR: Color = (140, 40, 200)
"""The belief's colour: purple, unlike anything the simulator draws of the truth."""
ESTIMATE_COLOR: Color = (230, 0, 140)
"""The pose estimate and its ellipse: magenta, over the purple cloud."""
PATH_COLOR: Color = (40, 90, 220)
POINTS_COLOR: Color = (0, 150, 150)
"""World points the program shows (a scan it placed, its map): teal, unlike the LiDAR's own
magenta points, so where the program believes the walls are and where they are both show."""
LABEL_BACK: Color = (250, 248, 255)
"""A label's box: a label is usually where the cloud is thickest, where purple on purple
could not be read."""
LABEL_LETTER = 0.5
"""A letter's width in em, generously: the box is wider than its text, never narrower."""
PARTICLE_LENGTH = 1.5
"""Inches of a particle's heading tick."""


def paint_belief(r: Renderer, view: View, belief: Belief, size: tuple[float, float]) -> None:
    """Draw ``belief`` over a maze ``size`` (width, height) inches."""
    if belief.cells is not None:
        rows, cols = belief.cells.shape
        cw, ch = size[0] / cols, size[1] / rows
        side = min(cw, ch) * view.ppi
        for (row, col), p in np.ndenumerate(belief.cells):
            if p > 0.01:
                x, y = view.point((col + 0.5) * cw, (row + 0.5) * ch)
                half = 0.45 * side * math.sqrt(p)
                r.draw_rect((x - half, y - half, 2 * half, 2 * half), tint(BELIEF_COLOR, 0.55))
    if len(belief.path) >= 2:
        r.draw_lines(
            view.points(belief.path.astype(np.float64)), PATH_COLOR, max(1, round(view.ppi / 8))
        )
    if len(belief.points):
        dot = max(1.5, view.ppi * 0.3)
        for point in view.points(belief.points.astype(np.float64)):
            r.draw_circle(point, dot, POINTS_COLOR, 0)
    particles = belief.particles
    if len(particles):
        ppi, ox, oy = view.ppi, view.ox, view.oy
        rad = np.radians(particles[:, 2])
        start = np.column_stack((ox + particles[:, 0] * ppi, oy + particles[:, 1] * ppi))
        tick = PARTICLE_LENGTH * ppi
        end = start + tick * np.column_stack((-np.sin(rad), np.cos(rad)))
        shades = np.round((1.0 - particles[:, 3]) * 4).astype(int)  # 5 shades by weight
        colors = [tint(BELIEF_COLOR, 0.15 * k) for k in range(5)]
        for a, b, k in zip(start.tolist(), end.tolist(), shades.tolist(), strict=True):
            r.draw_segment((a[0], a[1]), (b[0], b[1]), colors[k], 1)
    if belief.pose is not None:
        x, y, heading = belief.pose
        centre = view.point(x, y)
        if belief.ellipse is not None:
            a, b, angle = belief.ellipse
            t = np.linspace(0.0, 2 * math.pi, 48, endpoint=False)
            c, s = math.cos(math.radians(angle)), math.sin(math.radians(angle))
            ex, ey = a * np.cos(t), b * np.sin(t)
            ring = np.column_stack((x + ex * c - ey * s, y + ex * s + ey * c))
            r.draw_polygon(view.points(ring), ESTIMATE_COLOR, 3)
        h = math.radians(heading)
        tip = view.point(x - 2.5 * math.sin(h), y + 2.5 * math.cos(h))
        r.draw_circle(centre, max(3.0, 0.6 * view.ppi), ESTIMATE_COLOR, 3)
        r.draw_segment(centre, tip, ESTIMATE_COLOR, 3)
    size_px = max(16, round(view.ppi * 1.1))
    for x, y, text in belief.labels:
        cx, cy = view.point(x, y)
        width, height = len(text) * size_px * LABEL_LETTER + 8, size_px + 4
        box = (cx - width / 2, cy - height / 2, width, height)
        r.draw_rect(box, LABEL_BACK)
        r.draw_rect(box, BELIEF_COLOR, 1)
        r.draw_text(text, (cx, cy), BELIEF_COLOR, size_px, centered=True)
