"""The drawing interface, in pixels, with a pygame adapter and a recording one for tests.

Like pymunk's "draw options": the scene painter says *what* to draw (in window pixels) and a
renderer decides *how*. :class:`PygameRenderer` draws on a pygame surface;
:class:`RecordingRenderer` only remembers the calls, so tests can assert them exactly.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cache, lru_cache
from typing import Protocol

import pygame
import pygame.freetype

from simmer.colors import Color, Point, Rect
from simmer.untrusted import drawable


class Renderer(Protocol):
    """What the scene and HUD painters draw with; coordinates in window pixels."""

    def fill(self, color: Color) -> None:
        """Paint the whole target one colour."""
        ...

    def draw_rect(self, rect: Rect, color: Color, width: int = 0) -> None:
        """A rectangle (x, y, w, h); ``width`` 0 fills it, else the outline's thickness."""
        ...

    def draw_segment(self, start: Point, end: Point, color: Color, width: int = 1) -> None:
        """A straight line."""
        ...

    def draw_polygon(self, points: Sequence[Point], color: Color, width: int = 0) -> None:
        """A closed polygon; ``width`` 0 fills it."""
        ...

    def draw_lines(self, points: Sequence[Point], color: Color, width: int = 1) -> None:
        """An open polyline through at least two points."""
        ...

    def draw_circle(self, center: Point, radius: float, color: Color, width: int = 0) -> None:
        """A circle; ``width`` 0 fills it."""
        ...

    def draw_text(
        self, text: str, pos: Point, color: Color, size: int, centered: bool = False
    ) -> None:
        """One line of text with its top-left corner (or centre) at ``pos``; ``size`` in px."""
        ...


@dataclass(frozen=True)
class DrawCall:
    """One recorded call: the method name and its arguments."""

    op: str
    args: tuple[object, ...]


@dataclass
class RecordingRenderer:
    """A renderer that draws nothing and records every call (for tests)."""

    calls: list[DrawCall] = field(default_factory=list)

    def of(self, op: str) -> list[tuple[object, ...]]:
        """The arguments of every recorded call of one kind, in order."""
        return [call.args for call in self.calls if call.op == op]

    def fill(self, color: Color) -> None:
        """Record a fill."""
        self.calls.append(DrawCall("fill", (color,)))

    def draw_rect(self, rect: Rect, color: Color, width: int = 0) -> None:
        """Record a rectangle."""
        self.calls.append(DrawCall("rect", (rect, color, width)))

    def draw_segment(self, start: Point, end: Point, color: Color, width: int = 1) -> None:
        """Record a line."""
        self.calls.append(DrawCall("segment", (start, end, color, width)))

    def draw_polygon(self, points: Sequence[Point], color: Color, width: int = 0) -> None:
        """Record a polygon."""
        self.calls.append(DrawCall("polygon", (tuple(points), color, width)))

    def draw_lines(self, points: Sequence[Point], color: Color, width: int = 1) -> None:
        """Record a polyline."""
        self.calls.append(DrawCall("lines", (tuple(points), color, width)))

    def draw_circle(self, center: Point, radius: float, color: Color, width: int = 0) -> None:
        """Record a circle."""
        self.calls.append(DrawCall("circle", (center, radius, color, width)))

    def draw_text(
        self, text: str, pos: Point, color: Color, size: int, centered: bool = False
    ) -> None:
        """Record a line of text."""
        self.calls.append(DrawCall("text", (text, pos, color, size, centered)))


@cache
def _default_face() -> pygame.freetype.Font:
    """pygame's default font (the one :class:`TextCache` draws with), to ask about glyphs."""
    if not pygame.freetype.get_init():
        pygame.freetype.init()
    return pygame.freetype.Font(None, size=12)


@lru_cache(maxsize=4096)
def has_glyph(char: str) -> bool:
    """Whether pygame's default font has a glyph for ``char`` (else it draws an empty box)."""
    return _default_face().get_metrics(char)[0] is not None


class TextCache:
    """Rendered text surfaces by (text, colour, size): a HUD line is rasterised once per change.

    Every string drawn in a window, a video or a replay is rendered here, so here it passes
    :func:`~simmer.untrusted.drawable` (a program's belief label may hold anything)."""

    LIMIT = 512

    def __init__(self) -> None:
        if not pygame.font.get_init():
            pygame.font.init()
        self._fonts: dict[int, pygame.font.Font] = {}
        self._surfaces: dict[tuple[str, Color, int], pygame.Surface] = {}

    def font(self, size: int) -> pygame.font.Font:
        """pygame's default font at ``size`` pixels."""
        font = self._fonts.get(size)
        if font is None:
            font = self._fonts[size] = pygame.font.Font(None, size)
        return font

    def get(self, text: str, color: Color, size: int) -> pygame.Surface:
        """The surface for one line of text, rendered on first use."""
        key = (text, color, size)
        surface = self._surfaces.get(key)
        if surface is None:
            if len(self._surfaces) >= self.LIMIT:
                self._surfaces.clear()
            shown = drawable(text, has_glyph)
            surface = self._surfaces[key] = self.font(size).render(shown, True, color)
        return surface


class PygameRenderer:
    """Draws on a pygame surface (the window, or an off-screen surface)."""

    def __init__(self, surface: pygame.Surface, text: TextCache | None = None) -> None:
        self.surface = surface
        self.text = text if text is not None else TextCache()
        self.dirty: list[pygame.Rect] = []
        """Rectangles drawn on since the list was last cleared (for partial redraws)."""

    def fill(self, color: Color) -> None:
        """Paint the whole surface one colour."""
        self.dirty.append(self.surface.fill(color))

    def draw_rect(self, rect: Rect, color: Color, width: int = 0) -> None:
        """A rectangle; ``width`` 0 fills it."""
        self.dirty.append(pygame.draw.rect(self.surface, color, rect, width))

    def draw_segment(self, start: Point, end: Point, color: Color, width: int = 1) -> None:
        """A straight line."""
        self.dirty.append(pygame.draw.line(self.surface, color, start, end, width))

    def draw_polygon(self, points: Sequence[Point], color: Color, width: int = 0) -> None:
        """A closed polygon; ``width`` 0 fills it."""
        self.dirty.append(pygame.draw.polygon(self.surface, color, points, width))

    def draw_lines(self, points: Sequence[Point], color: Color, width: int = 1) -> None:
        """An open polyline."""
        self.dirty.append(pygame.draw.lines(self.surface, color, False, points, width))

    def draw_circle(self, center: Point, radius: float, color: Color, width: int = 0) -> None:
        """A circle; ``width`` 0 fills it."""
        self.dirty.append(pygame.draw.circle(self.surface, color, center, radius, width))

    def draw_text(
        self, text: str, pos: Point, color: Color, size: int, centered: bool = False
    ) -> None:
        """One line of text (cached, so an unchanged line costs one blit)."""
        image = self.text.get(text, color, size)
        if centered:
            pos = (pos[0] - image.get_width() / 2, pos[1] - image.get_height() / 2)
        self.dirty.append(self.surface.blit(image, pos))


def merge_rects(rects: Sequence[pygame.Rect]) -> list[pygame.Rect]:
    """Join runs of consecutive rectangles whose union is no bigger than their areas' sum.

    Consecutive draws are usually neighbours (the rays of one sensor, the lines of the HUD), so
    this one pass turns ~60 rectangles into a handful without the cost of a full merge.
    """
    out: list[pygame.Rect] = []
    if not rects:
        return out
    current = rects[0]
    area = current.w * current.h
    for rect in rects[1:]:
        union = current.union(rect)
        union_area = union.w * union.h
        rect_area = rect.w * rect.h
        if union_area <= area + rect_area:
            current, area = union, union_area
        else:
            out.append(current)
            current, area = rect, rect_area
    out.append(current)
    return out
