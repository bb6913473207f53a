"""Video of a run without a display: what the window shows, at a fixed rate in simulated time.

:class:`VideoRecorder` is an observer of a :class:`~simmer.world.Simulation`. A frame is due
each time a step's simulated time reaches the next multiple of ``1 / fps`` (counted from when
recording started, going on across resets), so a lockstep run that takes one second of wall
time still gives a video that plays at real speed, and a paused run adds no frames. In the
simulation's thread the observer only builds the immutable
:class:`~simmer.view.snapshot.Snapshot`; a writer thread draws it with the window's own drawing
code (:class:`~simmer.ui.offscreen.OffscreenRenderer`) and encodes it at once, so memory does
not grow with the run's length and the simulation never waits for the encoder unless the
writer falls a bounded number of frames behind.

Formats, by the file's suffix (PyAV and Pillow are imported only when a video is written):

- ``.mp4``: H.264 (``libx264`` from PyAV's wheel, no system ffmpeg), ``yuv420p``, time base
  ``1 / fps``; the frame size is the window's, rounded down to even numbers.
- ``.gif``: streamed frame by frame with Pillow's GIF encoder (Pillow's own animated-GIF
  writer keeps every frame until the end): one palette for the whole video (the scene's and
  HUD's own colours exactly, the rest fitted to the first frame, and one index for
  "transparent"), and each later frame only the rectangle drawn over, its unchanged pixels
  transparent. GIF delays are whole centiseconds, so they alternate (3, 3, 4 cs at 30
  frames/s) to keep real speed; at most 50 frames/s.
"""

from __future__ import annotations

import logging
import queue
import sys
import threading
from collections.abc import Sequence
from fractions import Fraction
from pathlib import Path
from typing import TYPE_CHECKING, BinaryIO, Protocol, cast

import numpy as np
import pygame

from simmer.colors import Color
from simmer.record.safefile import SafeFile
from simmer.ui.hud import HUD_COLORS, legend
from simmer.ui.offscreen import OffscreenRenderer, even_size
from simmer.ui.scene import ScenePainter, default_window_size
from simmer.view.frames import FPS, FrameClock, check_video_path
from simmer.view.maker import Controls, LocalControls, SnapshotMaker
from simmer.view.snapshot import HasScene, Snapshot, StaticScene
from simmer.world import Simulation
from simmer.world.events import Event

if TYPE_CHECKING:
    import av.container
    from PIL import Image

    from simmer.localize.belief import Belief

__all__ = ["VideoRecorder"]

log = logging.getLogger("simmer.video")

BACKLOG = 32
"""Snapshots waiting for the writer at most; then the simulation waits (bounded memory)."""
ENCODER_BACKLOG = 4
"""Converted frames waiting for the H.264 encoder at most (2 MB each at 1576 × 920)."""
BT709 = 1
"""FFmpeg's number for BT.709 colours (the H.264 stream says so; players assume it for HD)."""
H264_OPTIONS = {
    "preset": "ultrafast",
    "crf": "23",
    "x264-params": "aq-mode=1:mbtree=1:rc-lookahead=10",
}
"""x264 settings for a screen of flat colours, mostly still: the fastest preset, with adaptive
quantization and the macroblock tree put back (they halve the file for a little more time)."""
TRANSPARENT = 255
"""The GIF palette index of a pixel unchanged since the frame before."""


class FrameWriter(Protocol):
    """Encodes frames into a file as they come."""

    def write(self, surface: pygame.Surface, changed: Sequence[pygame.Rect] | None) -> None:
        """Add one frame: ``surface``'s pixels; ``changed``: where it differs from the last
        frame (None: anywhere)."""
        ...

    def close(self) -> None:
        """Finish the file."""
        ...


class Mp4Writer:
    """H.264 in an MP4 file through PyAV (``size`` even), written beside ``target``'s name and
    put there when closed (:class:`~simmer.record.safefile.SafeFile`).

    :meth:`write` converts the surface to BT.709 ``yuv420p``; a thread of its own encodes
    and stores the frames, outside the GIL, while the next one is drawn and converted.
    """

    def __init__(self, target: SafeFile, size: tuple[int, int], fps: int) -> None:
        import av
        from av.video.reformatter import ColorRange, VideoReformatter

        self.target = target
        try:
            self.container: av.container.OutputContainer = av.open(str(target.temp), mode="w")
        except BaseException:
            target.discard()
            raise
        try:
            stream = self.container.add_stream("libx264", rate=fps, options=H264_OPTIONS)
            stream.width, stream.height = size
            stream.pix_fmt = "yuv420p"
            context = stream.codec_context
            context.time_base = Fraction(1, fps)
            context.thread_count = 1  # drawing runs beside it; x264's own threads cost more
            context.colorspace = context.color_primaries = context.color_trc = BT709
            context.color_range = int(ColorRange.MPEG)
        except BaseException:
            self.container.close()
            target.discard()
            raise
        self.stream = stream
        self.count = 0
        self.failure: BaseException | None = None
        # Surfaces are 32-bit XRGB words: bytes B, G, R, X on a little-endian machine.
        layout = "bgra" if sys.byteorder == "little" else "argb"
        self._pixels = av.VideoFrame(size[0], size[1], layout)
        self._reformatter = VideoReformatter()
        self._frames: queue.Queue[av.VideoFrame | None] = queue.Queue(ENCODER_BACKLOG)
        self._thread = threading.Thread(target=self._encode, name="simmer-h264", daemon=True)
        self._thread.start()

    def write(self, surface: pygame.Surface, changed: Sequence[pygame.Rect] | None) -> None:
        """Convert one frame and queue it for the encoder (waiting if it is behind)."""
        from av.video.reformatter import ColorRange, Colorspace, Interpolation

        if self.failure is not None:
            raise self.failure
        # Any buffer will do (its stub says bytes): one copy, straight from the surface.
        self._pixels.planes[0].update(cast(bytes, surface.get_buffer()))
        frame = self._reformatter.reformat(
            self._pixels,
            format="yuv420p",
            dst_colorspace=Colorspace.ITU709,
            dst_color_range=ColorRange.MPEG,
            # Chroma by point sampling: for flat colours and sharp edges it is closer to the
            # drawing (PSNR 44 dB against 34 for FAST_BILINEAR) and a third cheaper.
            interpolation=Interpolation.POINT,
        )
        frame.pts = self.count
        self.count += 1
        self._frames.put(frame)

    def _encode(self) -> None:
        """The encoder thread: encode and store each frame; after a failure, drain."""
        while (frame := self._frames.get()) is not None:
            if self.failure is None:
                try:
                    self.container.mux(self.stream.encode(frame))
                except Exception as exc:  # raised by the next write() or close()
                    self.failure = exc

    def close(self) -> None:
        """Encode what is left, flush the encoder and write the MP4 index."""
        self._frames.put(None)
        self._thread.join()
        try:
            try:
                if self.failure is None:
                    self.container.mux(self.stream.encode(None))
            finally:
                self.container.close()
            if self.failure is not None:
                raise self.failure
        except BaseException:
            self.target.discard()  # not half a video at the name: what was there stays
            raise
        self.target.commit()


def scene_colors(scene: HasScene) -> list[Color]:
    """The flat colours the scene and HUD are painted with, each once."""
    colors = [
        *ScenePainter(scene).colors(),
        *HUD_COLORS,
        *(color for color, _ in legend(scene)),
        *(spec.params.color for spec in scene.config.devices),
    ]
    return list(dict.fromkeys(colors))


class GifWriter:
    """An animated GIF written frame by frame with Pillow (see the module doc).

    Each frame after the first is the rectangle around what was drawn, with the pixels that
    kept their colour left transparent, so long runs of one index compress to little.
    """

    def __init__(
        self, target: SafeFile, size: tuple[int, int], fps: int, colors: list[Color]
    ) -> None:
        self.target = target
        self.file: BinaryIO = target.temp.open("wb")
        self.fps = fps
        self.colors = colors
        self.palette: Image.Image | None = None
        self.shown = np.zeros((size[1], size[0]), np.uint8)
        """Palette indices of the picture the GIF shows so far."""
        self.count = 0

    def write(self, surface: pygame.Surface, changed: Sequence[pygame.Rect] | None) -> None:
        """Quantize the changed rectangle to the palette and append it with its delay."""
        from PIL import GifImagePlugin, Image

        first = self.palette is None
        whole = surface.get_rect()
        if changed is None or first:
            box = whole
        elif changed:
            box = changed[0].unionall(list(changed[1:])).clip(whole)
        else:
            box = pygame.Rect(0, 0, 0, 0)
        if box.w == 0 or box.h == 0:  # unchanged: one pixel carries the frame's delay
            box = pygame.Rect(0, 0, 1, 1)
        rgb = Image.frombytes("RGB", box.size, pygame.image.tobytes(surface.subsurface(box), "RGB"))
        if self.palette is None:
            self.palette = self._make_palette(rgb)
        indices = np.asarray(rgb.quantize(palette=self.palette, dither=Image.Dither.NONE))
        shown = self.shown[box.top : box.bottom, box.left : box.right]
        same = indices == shown
        shown[...] = indices
        image = Image.fromarray(np.where(same, TRANSPARENT, indices).astype(np.uint8), "P")
        image.putpalette(self.palette.getpalette() or [])
        if first:
            header, _ = GifImagePlugin.getheader(image, info={"loop": 0})
            self.file.write(b"".join(header))
        centiseconds = round(100 * (self.count + 1) / self.fps) - round(100 * self.count / self.fps)
        self.count += 1
        data = GifImagePlugin.getdata(
            image, offset=box.topleft, duration=10 * centiseconds, transparency=TRANSPARENT
        )
        self.file.write(b"".join(data))

    def _make_palette(self, first: Image.Image) -> Image.Image:
        """The scene's own colours, then the first frame's most telling others: 255 in all
        (the last index is :data:`TRANSPARENT`)."""
        from PIL import Image

        known = self.colors[:128]
        fitted = first.quantize(colors=TRANSPARENT - len(known), method=Image.Quantize.MEDIANCUT)
        flat = [c for color in known for c in color] + (fitted.getpalette() or [])
        palette = Image.new("P", (1, 1))
        palette.putpalette((flat + [0] * 3 * TRANSPARENT)[: 3 * TRANSPARENT])
        return palette

    def close(self) -> None:
        """Write the GIF trailer and put the file at its name."""
        try:
            with self.file:
                if self.palette is not None:
                    self.file.write(b";")
        except BaseException:
            self.target.discard()
            raise
        self.target.commit()


def open_writer(
    path: Path, size: tuple[int, int], fps: int, scene: HasScene, *, run_folder: bool = False
) -> FrameWriter:
    """The writer for ``path``'s format; :class:`~simmer.errors.UnsafeOutput` if a link or
    anything but a regular file is at its name (or, with ``run_folder``, its folder is a link:
    :func:`~simmer.record.safefile.check_target`)."""
    target = SafeFile(path, run_folder=run_folder)
    if path.suffix.lower() == ".gif":
        try:
            return GifWriter(target, size, fps, scene_colors(scene))
        except BaseException:
            target.discard()
            raise
    return Mp4Writer(target, size, fps)


class VideoRecorder:
    """Records ``sim`` into a video file at ``path`` (``.mp4`` or ``.gif``) while it runs.

    ``fps``: frames per simulated second. ``size``: the frame size (default: the window's),
    rounded down to even numbers. ``controls``: what the HUD shows of the loop around the
    simulation (the :class:`~simmer.runner.Runner`: speed, pause, clients); default: none.
    ``window`` False: the run has no window, so the frames show no key caps and no speed
    (a headless run's "speed max" and keys nobody could press said nothing true of the video).
    Create it, and :meth:`close` it, in the thread that owns ``sim``; the first frame is the
    simulation as it is now. :meth:`close` finishes the file (also after Ctrl-C) and raises
    whatever stopped the writer, if anything did.
    """

    def __init__(
        self,
        sim: Simulation,
        path: str | Path,
        *,
        fps: int = FPS,
        size: tuple[int, int] | None = None,
        controls: Controls | None = None,
        window: bool = True,
    ) -> None:
        self.path = check_video_path(path, fps)
        self.fps = fps
        self.sim = sim
        scene = StaticScene.of(sim)
        self.size = even_size(size or default_window_size(scene))
        self.controls: Controls = controls if controls is not None else LocalControls(sim)
        self.canvas = OffscreenRenderer(scene, pygame.Surface(self.size, 0, 32), keys=window)
        self.writer = open_writer(self.path, self.size, fps, scene)
        self.maker = SnapshotMaker(sim)
        self.clock = FrameClock(fps, sim.time)
        self.frames = 0
        """Frames handed to the writer so far (the video's length once closed)."""
        self.failure: BaseException | None = None
        """What stopped the writer thread, if anything did."""
        self._closed = False
        self._belief: Belief | None = None
        """The belief the last frame handed over shows."""
        self._queue: queue.Queue[tuple[Snapshot, int] | None] = queue.Queue(BACKLOG)
        self._thread = threading.Thread(target=self._write, name="simmer-video", daemon=True)
        self._thread.start()
        self.clock.frames = 1
        self._hand_over(1)
        sim.add_observer(self)

    @property
    def seconds(self) -> float:
        """The video's length so far, in seconds."""
        return self.frames / self.fps

    def __call__(self, event: Event) -> None:
        """Observe one event: hand over a frame for each frame time a step reached."""
        count = self.clock.due(event)
        if count:
            self._hand_over(count)

    def _hand_over(self, count: int) -> None:
        """Give the writer ``count`` frames of the simulation as it is now."""
        if self.failure is None:
            snap = self.maker.snapshot(self.controls)
            self._queue.put((snap, count))
            self.frames += count
            self._belief = snap.belief

    def _write(self) -> None:
        """The writer thread: draw and encode each snapshot; after a failure, drain."""
        while (item := self._queue.get()) is not None:
            if self.failure is not None:
                continue
            snap, count = item
            try:
                changed = self.canvas.draw(snap)
                for _ in range(count):
                    self.writer.write(self.canvas.surface, changed)
                    changed = []
            except Exception as exc:  # reported by close(); the run goes on
                log.error("the video %s stopped: %s", self.path, exc)
                self.failure = exc

    def close(self) -> None:
        """Stop recording and finish the file; raise what stopped the writer, if anything."""
        if self._closed:
            return
        self._closed = True
        self.sim.remove_observer(self)
        if self.maker.snapshot(self.controls).belief is not self._belief:
            self._hand_over(1)  # shown after the last frame (the estimate after the last move)
        self.maker.close()
        self._queue.put(None)
        self._thread.join()
        try:
            self.writer.close()
        except Exception as exc:
            self.failure = self.failure or exc
        if self.failure is not None:
            raise self.failure

    def __enter__(self) -> VideoRecorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
