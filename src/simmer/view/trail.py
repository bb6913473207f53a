"""The trail: the path the robot's centre drove so far, for the window, videos and replays.

:class:`Trail` observes a simulation in its own thread and keeps a point each time the robot has
moved :data:`SPACING` inches from the last one, and where it stops (so the corners of the path
are exact); a robot standing or turning on the spot adds nothing more. Memory is bounded: at
:data:`LIMIT` points every other point is dropped and the spacing doubles. Moving the robot by
hand (a drag) starts a new piece of the trail instead of drawing a line across the maze; a
reset starts a new trail.

Points are only ever appended to a buffer, and a buffer that must change (a reset, thinning)
is replaced by a new one, so the :class:`TrailView` a snapshot carries never changes: another
thread can draw it while the simulation goes on.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from simmer.geometry import FloatArray, Pose
from simmer.world.events import Event, PlaceEvent, ResetEvent, StepEvent

SPACING = 0.2
"""Inches between trail points (one pixel is 1/16 in at the default scale)."""
LIMIT = 4096
"""Points at most (64 KB); beyond that the trail is thinned to half."""


@dataclass(frozen=True)
class TrailView:
    """The trail as it is at one moment: ``points`` (N, 2) in world inches, read-only; a row of
    NaN separates pieces. ``generation`` changes whenever earlier points changed (a reset,
    thinning), so a painter that drew the first K points of the same generation only has the
    rest to draw."""

    points: FloatArray
    generation: int


EMPTY: FloatArray = np.empty((0, 2))
EMPTY.flags.writeable = False


class Trail:
    """An observer keeping the path driven so far (see the module doc).

    ``start``: the robot's pose when observing begins (where the first piece starts).
    """

    def __init__(self, start: Pose | None = None, spacing: float = SPACING, limit: int = LIMIT):
        if limit < 4:
            raise ValueError(f"a trail needs room for at least 4 points, not {limit}")
        self.first_spacing = spacing
        self.spacing = spacing
        self.limit = limit
        self.generation = 0
        self._buffer = np.empty((limit, 2))
        self._count = 0
        self._last: tuple[float, float] | None = None
        """The last point kept."""
        self._previous: tuple[float, float] | None = None
        """Where the robot was after the step before."""
        self._anchor = None if start is None else (start.x, start.y)
        """Where the next piece starts once the robot drives away from it (after a drag, a
        reset or at the start)."""
        self._view = TrailView(EMPTY, 0)

    def __call__(self, event: Event) -> None:
        """Observe one simulation event."""
        if type(event) is StepEvent:
            self._moved_to(event.pose.x, event.pose.y)
        elif isinstance(event, PlaceEvent):
            self._anchor = (event.pose.x, event.pose.y)
        elif isinstance(event, ResetEvent):
            self._renew(np.empty((self.limit, 2)), 0)
            self.spacing = self.first_spacing
            self._last = self._anchor = self._previous = None

    def view(self) -> TrailView:
        """The trail now (the same object until it changes)."""
        view = self._view
        if len(view.points) != self._count or view.generation != self.generation:
            points = self._buffer[: self._count]
            points.flags.writeable = False
            view = self._view = TrailView(points, self.generation)
        return view

    def _moved_to(self, x: float, y: float) -> None:
        anchor = self._anchor
        stopped = self._previous == (x, y)
        self._previous = (x, y)
        if anchor is None and self._last is None:
            self._anchor = (x, y)
        elif anchor is not None:
            if math.dist(anchor, (x, y)) >= self.spacing:
                if self._count:
                    self._append(math.nan, math.nan)
                self._append(*anchor)
                self._append(x, y)
                self._anchor = None
        elif (
            self._last is not None
            and self._last != (x, y)
            and (stopped or math.dist(self._last, (x, y)) >= self.spacing)
        ):
            self._append(x, y)

    def _append(self, x: float, y: float) -> None:
        if self._count == self.limit:
            self._thin()
        self._buffer[self._count] = (x, y)
        self._count += 1
        if not math.isnan(x):
            self._last = (x, y)

    def _thin(self) -> None:
        """Keep every other point (and each piece's ends) in a new buffer, at twice the spacing;
        if pieces are so many that this is not enough, keep the newest half."""
        points = self._buffer
        gap = np.isnan(points[:, 0])
        keep = np.zeros(len(points), dtype=bool)
        keep[::2] = True
        keep[-1] = True
        keep |= gap
        keep[:-1] |= gap[1:]
        keep[1:] |= gap[:-1]
        kept = points[keep][-(self.limit // 2) :]
        buffer = np.empty((self.limit, 2))
        buffer[: len(kept)] = kept
        self.spacing *= 2
        self._renew(buffer, len(kept))

    def _renew(self, buffer: FloatArray, count: int) -> None:
        """Replace the buffer (views of the old one stay as they are)."""
        self._buffer = buffer
        self._count = count
        self.generation += 1
