"""The heads-up display: heartbeat, key lights, time, Task 2 stopwatch, pose, commands, help,
and a red warning for each device switched off because its code raised.

:class:`Stopwatch` and :class:`CommandLog` observe the simulation in its own thread; the painters
read only a :class:`~simmer.ui.snapshot.Snapshot` (and the static configuration).
"""

from __future__ import annotations

import logging
import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from simmer.geometry import FloatArray, Pose
from simmer.ui.render import Color, Renderer
from simmer.ui.scene import PANEL_HEIGHT, tint
from simmer.ui.snapshot import HasScene, Snapshot
from simmer.world import Simulation
from simmer.world.events import CommandEvent, Event, ResetEvent, StepEvent
from simmer.world.simulation import MANUAL_KEYS

log = logging.getLogger("simmer.ui")

REACH_DISTANCE = 1.0
"""The robot "reaches" the block when its outline comes within this many inches of it."""
KEY_LAYOUT = (("q", "w", "e"), ("a", "s", "d"))
TEXT: Color = (235, 240, 240)
DIM: Color = (150, 175, 175)
LIT: Color = (255, 210, 0)
UNLIT: Color = (60, 70, 70)
ALARM: Color = (255, 90, 90)
BOX: Color = (20, 30, 30)
SWITCHED_OFF_SHOWN = 3
"""At most this many switched-off devices are named on screen (all of them are in the log)."""

HELP = (
    ("W / S", "drive forward / backward (6 in/s)"),
    ("A / D", "turn anticlockwise / clockwise (120 deg/s)"),
    ("Q / E", "slide sideways toward robot +x / -x"),
    ("Space", "pause / resume"),
    (".", "one step while paused"),
    ("+ / -", "faster / slower (simulation speed)"),
    ("R", "reset robot, block, sensors and stopwatch"),
    ("left-drag", "move the robot (refused onto a wall)"),
    ("right-drag", "turn the robot"),
    ("H", "show / hide this help"),
    ("Esc", "quit (or close the window)"),
)


def polygon_gap(a: FloatArray, b: FloatArray) -> float:
    """Smallest distance between the outlines of two polygons (0 if their edges cross)."""
    best = math.inf
    for points, poly in ((a, b), (b, a)):
        starts = poly
        ends = np.roll(poly, -1, axis=0)
        edge = ends - starts
        length2 = np.maximum((edge**2).sum(axis=1), 1e-12)
        for p in points:
            t = np.clip(((p - starts) * edge).sum(axis=1) / length2, 0.0, 1.0)
            nearest = starts + t[:, None] * edge
            best = min(best, float(np.sqrt(((p - nearest) ** 2).sum(axis=1)).min()))
    return best


class Stopwatch:
    """The lab's Task 2 timer, in simulated seconds, fed by the simulation's events.

    It starts at the first step in which the robot moves and stops when the robot's outline
    comes within :data:`REACH_DISTANCE` of the block; the result is logged. A reset of the
    simulation resets it.
    """

    def __init__(self, sim: Simulation) -> None:
        self.sim = sim
        self.start: float | None = None
        self.stop: float | None = None
        self._last_pose: Pose = sim.robot.pose
        robot_radius = float(np.sqrt((sim.robot.outline**2).sum(axis=1)).max())
        self._near = robot_radius + sim.block.size * math.sqrt(0.5) + REACH_DISTANCE

    def reset(self) -> None:
        """Clear the timer; the next motion starts it again."""
        self.start = self.stop = None
        self._last_pose = self.sim.robot.pose

    def __call__(self, event: Event) -> None:
        """Observe one simulation event."""
        if isinstance(event, ResetEvent):
            self.reset()
        elif isinstance(event, StepEvent) and self.stop is None:
            if self.start is None:
                if event.pose == self._last_pose:
                    return
                self.start = event.time - self.sim.dt
            if self.reached():
                self.stop = event.time
                log.info("Task 2 stopwatch: reached the block in %.2f s", self.stop - self.start)

    def reached(self) -> bool:
        """True if the robot's outline is within :data:`REACH_DISTANCE` of the block."""
        sim = self.sim
        pose = sim.robot.pose
        if math.hypot(pose.x - sim.block.x, pose.y - sim.block.y) > self._near:
            return False
        return polygon_gap(sim.robot.polygon(), sim.block.polygon) <= REACH_DISTANCE

    def elapsed(self) -> float | None:
        """Seconds on the clock (frozen once stopped), or None before the first motion."""
        if self.start is None:
            return None
        end = self.stop if self.stop is not None else self.sim.time
        return end - self.start


@dataclass(frozen=True)
class RepeatedCommand(CommandEvent):
    """A message answered the same way ``count`` times in a row; ``time`` is the last one's."""

    count: int = 1


class CommandLog:
    """The last few messages and their replies, collected from the simulation's events.

    A message answered as the one before it was (``wait_idle()`` polling ``w0-0`` until the
    drive is done) extends that entry's count instead of taking a line, so the student's own
    commands stay on screen.
    """

    def __init__(self, size: int = 5) -> None:
        self.entries: deque[CommandEvent] = deque(maxlen=size)

    def __call__(self, event: Event) -> None:
        """Observe one simulation event."""
        if not isinstance(event, CommandEvent):
            return
        last = self.entries[-1] if self.entries else None
        if last is None or last.message != event.message or not _same(last.replies, event.replies):
            self.entries.append(event)
            return
        count = last.count if isinstance(last, RepeatedCommand) else 1
        self.entries[-1] = RepeatedCommand(event.time, event.message, event.replies, count + 1)


def _same(a: Sequence[float], b: Sequence[float]) -> bool:
    """Equal reply values, NaN equal to NaN."""
    return len(a) == len(b) and all(
        x == y or (math.isnan(x) and math.isnan(y)) for x, y in zip(a, b, strict=True)
    )


def _reply(value: float) -> str:
    if math.isnan(value):
        return "NaN"
    if math.isinf(value):
        return "ok" if value > 0 else "-inf"
    return f"{value:.4g}"


def speed_text(speed: float | None) -> str:
    """``x1``, ``x0.5``, ``max``."""
    return "max" if speed is None else f"x{speed:g}"


LABEL_X = 160
VALUE_X = 320
ROWS = (10, 36, 62, 88)
COMMANDS_X = 700
CLIENTS_X = 1160
LEGEND_WIDTH = 190


def _key_cap(r: Renderer, key: str, lit: bool) -> None:
    row = next(i for i, keys in enumerate(KEY_LAYOUT) if key in keys)
    x, y = 52 + KEY_LAYOUT[row].index(key) * 30, 12 + row * 30
    r.draw_rect((x, y, 26, 26), LIT if lit else UNLIT)
    r.draw_text(key.upper(), (x + 8, y + 6), (0, 0, 0) if lit else TEXT, 20)


def legend(scene: HasScene) -> list[tuple[Color, str]]:
    """What the scene's colours mean."""
    config = scene.config
    settings = config.settings
    items = [
        (settings.wall_color, "wall"),
        (settings.block_color, "block (the target)"),
        (settings.robot_color, "robot, devices"),
    ]
    for spec in config.devices:
        color = getattr(spec.params, "ray_color", None)
        if color is not None:
            items.append((color, "ultrasonic rays"))
            break
    return items


def paint_hud_static(r: Renderer, scene: HasScene, width: int) -> None:
    """The HUD's fixed parts: unlit key caps, labels, colour legend (painted once)."""
    for key in MANUAL_KEYS:
        _key_cap(r, key, lit=False)
    x = width - LEGEND_WIDTH
    if x < CLIENTS_X + 220:  # no room beside the clients column: leave it out
        return
    for i, (color, label) in enumerate(legend(scene)):
        y = 12 + 22 * i
        r.draw_rect((x, y + 2, 14, 14), color)
        r.draw_text(label, (x + 22, y), TEXT, 20)
    r.draw_text("h: help", (12, 78), DIM, 20)
    for label, y in zip(("time", "Task 2 stopwatch", "true pose", "collisions"), ROWS, strict=True):
        r.draw_text(label, (LABEL_X, y), DIM, 22)
    r.draw_text("last commands -> replies", (COMMANDS_X, ROWS[0]), DIM, 20)


def paint_hud(r: Renderer, snap: Snapshot) -> None:
    """The HUD's changing values; everything in simulated time."""
    # Heartbeat: fades from white once per simulated second (slower flashing = falling behind).
    r.draw_rect((12, 12, 28, 28), tint((255, 255, 255), snap.time % 1.0, UNLIT))
    for key in sorted(snap.held):
        _key_cap(r, key, lit=True)

    paused = snap.paused
    state = "PAUSED (Space resumes, . steps)" if paused else "running"
    r.draw_text(
        f"{snap.time:.2f} s   speed {speed_text(snap.speed)}   {state}",
        (VALUE_X, ROWS[0]),
        LIT if paused else TEXT,
        22,
    )
    elapsed = snap.watch_elapsed
    if elapsed is None:
        watch, color = "starts when the robot first moves", DIM
    elif not snap.watch_stopped:
        watch, color = f"{elapsed:.2f} s", TEXT
    else:
        watch, color = f"reached the block in {elapsed:.2f} s", LIT
    r.draw_text(watch, (VALUE_X, ROWS[1]), color, 22)
    pose = snap.pose
    r.draw_text(
        f"x {pose.x:.2f} in   y {pose.y:.2f} in   heading {pose.heading:.1f} deg",
        (VALUE_X, ROWS[2]),
        TEXT,
        22,
    )
    r.draw_text(str(snap.collisions), (VALUE_X, ROWS[3]), TEXT, 22)

    commands = snap.commands
    if not commands:
        r.draw_text("none yet", (COMMANDS_X, 32), DIM, 18)
    for i, event in enumerate(reversed(commands)):
        replies = ", ".join(_reply(v) for v in event.replies)
        line = f"{event.time:7.2f} s  {event.message[:28]} -> {replies[:40]}"
        if isinstance(event, RepeatedCommand):
            line += f"  x{event.count}"
        r.draw_text(line, (COMMANDS_X, 32 + 16 * i), TEXT, 18)

    clients = snap.clients
    if clients is not None:
        r.draw_text("connected clients", (CLIENTS_X, ROWS[0]), DIM, 20)
        for i, client in enumerate(clients[:5]):
            r.draw_text(client, (CLIENTS_X, 32 + 16 * i), TEXT, 18)
        if not clients:
            r.draw_text("none", (CLIENTS_X, 32), DIM, 18)
    if snap.switched_off:
        paint_switched_off(r, snap.switched_off)


def paint_switched_off(r: Renderer, switched_off: tuple[tuple[str, str], ...]) -> None:
    """One red line per device switched off, in a dark box over the top of the maze: a student
    must notice that their device no longer answers, and why."""
    lines = [f"{device_id} switched off: {reason}"[:120] for device_id, reason in switched_off]
    if len(lines) > SWITCHED_OFF_SHOWN:
        more = len(lines) - SWITCHED_OFF_SHOWN + 1
        lines[SWITCHED_OFF_SHOWN - 1 :] = [f"... and {more} more devices switched off"]
    hint = "switched-off devices answer NaN; the traceback is in the log; R (reset) restarts them"
    size, step = 20, 20
    width = 24 + size * 2 * max(len(line) for line in [*lines, hint]) // 5  # ~0.4 em a letter
    x, y = 8, PANEL_HEIGHT + 4
    r.draw_rect((x, y, width, 10 + step * (len(lines) + 1)), BOX)
    for i, line in enumerate(lines):
        r.draw_text(line, (x + 10, y + 6 + step * i), ALARM, size)
    r.draw_text(hint, (x + 10, y + 6 + step * len(lines)), DIM, 18)


def paint_help(r: Renderer, size: tuple[int, int]) -> None:
    """The key list, in a box over the maze."""
    width, height = 560, 44 + 26 * len(HELP)
    x0 = max(0, (size[0] - width) // 2)
    y0 = max(PANEL_HEIGHT, (size[1] - height) // 2)
    r.draw_rect((x0, y0, width, height), (20, 30, 30))
    r.draw_rect((x0, y0, width, height), LIT, 2)
    r.draw_text("Keys and mouse", (x0 + 16, y0 + 12), LIT, 24)
    for i, (key, what) in enumerate(HELP):
        y = y0 + 42 + 26 * i
        r.draw_text(key, (x0 + 16, y), LIT, 22)
        r.draw_text(what, (x0 + 140, y), TEXT, 22)
