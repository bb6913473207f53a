"""The off-screen renderer: snapshots of one scene drawn on a pygame surface, no display needed.

The window draws on its display surface through it; the video (:mod:`simmer.ui.video`),
screenshots and :func:`render_scene` draw on plain surfaces through the same code, so a frame of
a video is exactly what the window showed. It keeps the static layer (floor, walls, rulers, HUD
labels) cached per surface size and restores only what the previous frame drew over it.
Creating one needs no pygame display (only fonts), so it works on a machine without a screen.

The trail (:mod:`simmer.view.trail`) is painted into the static layer as it grows, each new
piece once, under the robot; the layer is put back to its clean copy only when the trail
starts again (a reset, thinning, a replay seeking backwards) or is hidden.
"""

from __future__ import annotations

import io
from collections.abc import Sequence

import pygame

from simmer.ui.belief import paint_belief
from simmer.ui.hud import HELP, paint_blocked, paint_help, paint_hud, paint_hud_static
from simmer.ui.render import PygameRenderer, TextCache, merge_rects
from simmer.ui.scene import ScenePainter, View, default_window_size
from simmer.view.snapshot import HasScene, Snapshot
from simmer.view.trail import TrailView

__all__ = ["OffscreenRenderer", "even_size", "static_layer"]


def even_size(size: tuple[int, int]) -> tuple[int, int]:
    """``size`` rounded down to even width and height (H.264 in yuv420p needs both even)."""
    width, height = size
    if width < 2 or height < 2:
        raise ValueError(f"a frame must be at least 2 × 2 pixels, not {width} × {height}")
    return (width - width % 2, height - height % 2)


def static_layer(size: tuple[int, int], like: pygame.Surface) -> pygame.Surface:
    """A surface for the cached static layer, in ``like``'s pixel format.

    It is a subsurface one pixel into a slightly wider surface: when source and destination
    rows start at the same offset within a memory page, SDL's row copies run into 4K aliasing
    and restoring a rectangle costs up to 20 times more (measured: a 33 × 64 px restore took
    23 µs instead of 0.5 µs; a full-window copy 364 µs instead of 154 µs).
    """
    parent = pygame.Surface((size[0] + 1, size[1]), 0, like)
    return parent.subsurface((1, 0, size[0], size[1]))


class OffscreenRenderer:
    """Draws snapshots of ``scene`` on ``surface`` (default: a new surface of the window's
    default size), each frame only where the previous one drew over the static layer.

    ``show_trail``: draw the snapshots' trails (videos do; the window's T key switches it).
    """

    def __init__(
        self,
        scene: HasScene,
        surface: pygame.Surface | None = None,
        text: TextCache | None = None,
        *,
        show_trail: bool = True,
        show_belief: bool = True,
        keys: bool = True,
    ) -> None:
        self.scene = scene
        if surface is None:
            surface = pygame.Surface(default_window_size(scene))
        self.surface = surface
        self.renderer = PygameRenderer(self.surface, text)
        self.painter = ScenePainter(scene)
        self.view = View(1.0, 0.0, 0.0)
        self.keys = keys
        """Draw the window's key caps, help hint and speed (False: a headless run's video)."""
        self.show_trail = show_trail
        self.show_belief = show_belief
        """Draw the program's belief (``robot.show``) when the snapshot has one."""
        self.static = pygame.Surface((1, 1))
        self._clean = self.static
        """The static layer without the trail."""
        self._drawn: list[pygame.Rect] = []  # what the last frame drew over the static layer
        self._trail: tuple[int, int] | None = None
        """(generation, points) of the trail painted into the static layer; None: none is."""
        self.layout()

    def use(self, surface: pygame.Surface) -> None:
        """Draw on another surface from now on (the window was resized)."""
        self.surface = self.renderer.surface = surface
        self.layout()

    def layout(self) -> None:
        """Fit the scene to the surface's size and repaint the cached static layer."""
        size = self.surface.get_size()
        self.view = View.fit(self.scene, size)
        self.static = static_layer(size, self.surface)
        static = PygameRenderer(self.static, self.renderer.text)
        self.painter.paint_static(static, self.view, size)
        paint_hud_static(static, self.scene, size[0], keys=self.keys)
        self._clean = self.static.copy()
        self._trail = None
        self.invalidate()

    def png(self, shrink: int = 1) -> bytes:
        """The surface as PNG bytes, smoothly shrunk ``shrink`` times (a sweep's small frames)."""
        width, height = self.surface.get_size()
        small = pygame.transform.smoothscale(self.surface, (width // shrink, height // shrink))
        data = io.BytesIO()
        pygame.image.save(small, data, "png")
        return data.getvalue()

    def invalidate(self) -> None:
        """Repaint the whole surface at the next :meth:`draw` (something else drew on it)."""
        self._drawn = [self.static.get_rect()]

    def draw(
        self,
        snap: Snapshot,
        *,
        show_help: bool = False,
        keys: Sequence[tuple[str, str]] = HELP,
    ) -> list[pygame.Rect] | None:
        """Draw ``snap`` (with the help for ``keys`` over it if ``show_help``); return the
        rectangles that changed since the previous frame, or None if the whole surface was
        repainted.

        Only what the previous frame drew (and the trail's new piece) is restored from the
        cached static layer, so a frame costs the size of the robot, rays and HUD values, not
        of the surface.
        """
        surface = self.surface
        static = self.static
        trail = self._paint_trail(snap.trail if self.show_trail else None)
        previous = self._drawn + trail
        everything = self._drawn == [static.get_rect()]
        if everything:
            surface.blit(static, (0, 0))
        else:
            for rect in previous:
                surface.blit(static, rect, rect)
        r = self.renderer
        r.dirty.clear()
        if self.show_belief and snap.belief is not None:
            maze = self.scene.maze
            paint_belief(r, self.view, snap.belief, (maze.width, maze.height))
            if len(r.dirty) > 1:  # thousands of particles: one rectangle to restore
                r.dirty[:] = [r.dirty[0].unionall(r.dirty[1:])]
        shown = snap.trail if self.show_trail else None
        self.painter.paint_dynamic(r, self.view, snap, shown.points if shown else None)
        paint_blocked(r, self.view, snap)
        paint_hud(r, snap, surface.get_width(), keys=self.keys)
        if show_help:
            paint_help(r, surface.get_size(), keys)
        self._drawn = merge_rects(r.dirty)
        return None if everything else previous + self._drawn

    def _paint_trail(self, trail: TrailView | None) -> list[pygame.Rect]:
        """Bring the static layer's trail up to ``trail`` (None: no trail); return where it
        was painted on, or invalidate the surface if the layer was put back to clean."""
        painted = self._trail
        if trail is None or len(trail.points) == 0:
            if painted is not None:
                self._restart_trail(None)
            return []
        generation, count = trail.generation, len(trail.points)
        if painted is None or painted[0] != generation or painted[1] > count:
            self._restart_trail(generation)
            start = 0
        else:
            start = max(0, painted[1] - 1)  # the new piece joins the last point painted
        self._trail = (generation, count)
        if count - start < 2:
            return []
        static = PygameRenderer(self.static, self.renderer.text)
        self.painter.paint_trail(static, self.view, trail.points[start:])
        return merge_rects(static.dirty)

    def _restart_trail(self, generation: int | None) -> None:
        """Put the static layer back to clean (no trail) and repaint the whole surface."""
        self.static.blit(self._clean, (0, 0))
        self._trail = None if generation is None else (generation, 0)
        self.invalidate()
