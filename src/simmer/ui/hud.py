"""The heads-up display: heartbeat, key lights, time, the run's outcome (Task 2 stopwatch,
collisions and blocked moves, path length, busy and NaN replies), pose, commands, help, the
file a screenshot or video went to, and a red warning for each device switched off because its
code raised; a blocked move is also drawn over the maze (:func:`paint_blocked`).

The outcome is the simulation's own :class:`~simmer.world.outcome.Outcome` (the figures a
headless run prints); it and :class:`~simmer.view.commands.CommandLog` observe the simulation
in its thread, and the painters read only a :class:`~simmer.view.snapshot.Snapshot` (and the
static configuration).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from simmer.colors import TRAIL_COLOR, Color, tint
from simmer.ui.render import Renderer
from simmer.ui.scene import PANEL_HEIGHT, View
from simmer.view.commands import RepeatedCommand
from simmer.view.snapshot import HasScene, Snapshot
from simmer.world.outcome import OutcomeReport
from simmer.world.simulation import MANUAL_KEYS

KEY_LAYOUT = (("q", "w", "e"), ("a", "s", "d"))
TEXT: Color = (235, 240, 240)
DIM: Color = (150, 175, 175)
LIT: Color = (255, 210, 0)
UNLIT: Color = (60, 70, 70)
ALARM: Color = (255, 90, 90)
BOX: Color = (20, 30, 30)
HUD_COLORS = (TEXT, DIM, LIT, UNLIT, ALARM, BOX, (0, 0, 0), (255, 255, 255))
"""Every flat colour the HUD paints with (the heartbeat fades between the last and UNLIT)."""
SWITCHED_OFF_SHOWN = 3
"""At most this many switched-off devices are named on screen (all of them are in the log)."""
LETTER = 0.38
"""Width of a letter of pygame's default font, in em, a little over the average."""

HELP = (
    ("W / S", "drive forward / backward (6 in/s)"),
    ("A / D", "turn anticlockwise / clockwise (120 deg/s)"),
    ("Q / E", "slide sideways toward robot +x / -x"),
    ("Space", "pause / resume"),
    (".", "one step while paused"),
    ("+ / -", "faster / slower (simulation speed)"),
    ("R", "reset robot, block, sensors and the outcome"),
    ("T", "show / hide the path driven so far (videos show it)"),
    ("B", "show / hide the program's belief (robot.show; videos show it)"),
    ("left-drag", "move the robot (refused onto a wall)"),
    ("right-drag", "turn the robot"),
    ("V", "start / stop a video (simmer-*.mp4, named above)"),
    ("P", "screenshot (simmer-*.png, named above)"),
    ("H", "show / hide this help"),
    ("Esc", "quit (or close the window)"),
    ("reached", "the robot's outline within 1 in of the block's"),
    ("stopwatch", "Task 2: from the first motion until reached"),
    ("busy", "a drive command refused while a drive moves"),
    ("blocked", "a drive command a wall or the block stopped (red over the robot)"),
    ("axes", "x right, y down; heading 0 faces +y (down), 90 faces -x (left)"),
    ("turns", "a positive r0 turns clockwise on screen (heading grows)"),
)
HELP_WHAT_X = 140
"""Where the help's second column starts, from the box's left edge."""


def reply_text(value: float) -> str:
    """A reply as the HUD shows it: ``ok`` for +inf (accepted), ``NaN``, or 4 digits."""
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
PATH_LABEL_X = 490
"""The path length sits beside the collisions, in the last row."""
PATH_X = 530
DIAL_X = 662
"""The heading dial's centre, after the pose's text and before the commands."""
DIAL_RADIUS = 9
COMMANDS_X = 700
REPLIES_X = COMMANDS_X + 200
"""Reply counts, beside the commands' heading."""
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
    for spec in config.devices:
        color = getattr(spec.params, "beam_color", None)
        if color is not None:
            items.append((color, "time-of-flight beams"))
            break
    items.append((TRAIL_COLOR, "path so far (T)"))
    return items


def paint_hud_static(r: Renderer, scene: HasScene, width: int, *, keys: bool = True) -> None:
    """The HUD's fixed parts: unlit key caps (unless ``keys`` is False: a video of a run
    without a window, where no key was there to press), labels, colour legend (painted
    once)."""
    if keys:
        for key in MANUAL_KEYS:
            _key_cap(r, key, lit=False)
        r.draw_text("h: help", (12, 78), DIM, 20)
    from simmer.config.zones import project_run

    second = "project" if project_run(scene.config) else "Task 2 stopwatch"
    for label, y in zip(("time", second, "true pose", "collisions"), ROWS, strict=True):
        r.draw_text(label, (LABEL_X, y), DIM, 22)
    r.draw_text("path", (PATH_LABEL_X, ROWS[3]), DIM, 22)
    r.draw_text("last commands -> replies", (COMMANDS_X, ROWS[0]), DIM, 20)
    x = width - LEGEND_WIDTH
    if x < CLIENTS_X + 220:  # no room beside the clients column: leave it out
        return
    for i, (color, label) in enumerate(legend(scene)):
        y = 10 + 20 * i
        r.draw_rect((x, y + 2, 14, 14), color)
        r.draw_text(label, (x + 22, y), TEXT, 20)


def paint_hud(r: Renderer, snap: Snapshot, width: int | None = None, *, keys: bool = True) -> None:
    """The HUD's changing values; everything in simulated time. ``width``: the surface's, if
    long lines must be cut to fit it. ``keys`` False (a video of a run without a window): no
    key lights and no speed (the video plays in real time, whatever the run's speed was)."""
    # Heartbeat: fades from white once per simulated second (slower flashing = falling behind).
    r.draw_rect((12, 12, 28, 28), tint((255, 255, 255), snap.time % 1.0, UNLIT))
    if keys:
        for key in sorted(snap.held):
            _key_cap(r, key, lit=True)

    paused = snap.paused
    state = "PAUSED (Space resumes)" if paused else "running"  # ends before the commands
    speed = f"   speed {speed_text(snap.speed)}   {state}" if keys else ""
    r.draw_text(
        f"{snap.time:.2f} s{speed}",
        (VALUE_X, ROWS[0]),
        LIT if paused else TEXT,
        22,
    )
    pose = snap.pose
    r.draw_text(
        f"x {pose.x:.2f} in   y {pose.y:.2f} in   heading {pose.heading:.1f} deg",
        (VALUE_X, ROWS[2]),
        TEXT,
        22,
    )
    paint_heading_dial(r, pose.heading, (DIAL_X, ROWS[2] + 9))
    if snap.outcome is not None:
        paint_outcome(r, snap.outcome)

    commands = snap.commands
    if not commands:
        r.draw_text("none yet", (COMMANDS_X, 32), DIM, 18)
    for i, event in enumerate(reversed(commands)):
        replies = ", ".join(reply_text(v) for v in event.replies)
        line = f"{event.time:7.2f} s  {event.message[:28]} -> {replies[:40]}"
        if isinstance(event, RepeatedCommand):
            line += f"  x{event.count}"
        r.draw_text(line, (COMMANDS_X, 32 + 16 * i), TEXT, 18)

    clients = snap.clients
    link = snap.outcome.link if snap.outcome is not None else None
    if clients is not None:
        r.draw_text("connected clients", (CLIENTS_X, ROWS[0]), DIM, 20)
        shown = clients[: 5 if link is None else 2]  # the link's two lines below them
        for i, client in enumerate(shown):
            r.draw_text(client, (CLIENTS_X, 32 + 16 * i), TEXT, 18)
        if not clients:
            r.draw_text("none", (CLIENTS_X, 32), DIM, 18)
        if link is not None:
            paint_link(r, link, 32 + 16 * max(1, len(shown)))
    if snap.switched_off:
        paint_switched_off(r, snap.switched_off, width)
    if snap.recording is not None:  # the file's name is in the notice
        r.draw_circle((18, 102), 5, ALARM)
        r.draw_text("REC", (28, 95), ALARM, 18)
    if snap.notice is not None:
        paint_notice(r, snap.notice, width)


def paint_notice(r: Renderer, text: str, width: int | None = None) -> None:
    """A box just under the panel, over the maze's top left, naming the file a screenshot or
    video went to (cut to ``width`` if given)."""
    size = 20
    if width is not None:
        fits = max(8, int((width - 40) / (LETTER * size)))
        text = text if len(text) <= fits else "..." + text[-(fits - 3) :]  # keep the name
    box = (10, PANEL_HEIGHT + 24, 20 + round(LETTER * size * len(text)), 28)
    r.draw_rect(box, BOX)
    r.draw_rect(box, LIT, 1)
    r.draw_text(text, (20, PANEL_HEIGHT + 30), LIT, size)


def stopwatch_text(outcome: OutcomeReport) -> tuple[str, Color]:
    """The Task 2 stopwatch line and its colour: waiting, running, or stopped at the block."""
    if outcome.first_motion is None:
        return "starts when the robot first moves", DIM
    if outcome.task2_time is None:
        return f"{outcome.time - outcome.first_motion:.2f} s", TEXT
    return f"reached the block in {outcome.task2_time:.2f} s", LIT


PROJECT_WORDS = {
    "entered_loading": "in",
    "picked_up": "picked",
    "left_loading": "out",
    "delivered": "delivered",
}
"""The project's milestones as the HUD names them, in order."""


def project_text(outcome: OutcomeReport) -> tuple[str, Color]:
    """The project line: the target, the score and the milestones met so far (the times are
    in the outcome the run prints and in report.md)."""
    project = outcome.project
    assert project is not None
    met = [word for name, word in PROJECT_WORDS.items() if getattr(project, name)]
    if project.wrong_zone is not None and not project.delivered:
        met.append(f"in {project.wrong_zone}, not the target")
    done = " | ".join(met) if met else "no milestone yet"
    color = LIT if project.delivered else TEXT
    return f"target {project.target or '-'}  score {project.score:g}  {done}", color


def paint_outcome(r: Renderer, outcome: OutcomeReport) -> None:
    """The run's outcome: Task 2 stopwatch, collisions (and when the first was), path length,
    and how many replies were busy (a drive still moving) or NaN."""
    watch, color = stopwatch_text(outcome) if outcome.project is None else project_text(outcome)
    r.draw_text(watch, (VALUE_X, ROWS[1]), color, 22 if outcome.project is None else 20)
    collisions = str(outcome.collisions)
    if outcome.blocked_moves:  # what a student must see first: moves that went nowhere
        moves = "move" if outcome.blocked_moves == 1 else "moves"
        collisions += f", {outcome.blocked_moves} {moves} blocked"
    elif outcome.first_collision is not None:
        collisions += f" (first at {outcome.first_collision:.2f} s)"
    r.draw_text(collisions, (VALUE_X, ROWS[3]), ALARM if outcome.blocked_moves else TEXT, 22)
    r.draw_text(f"{outcome.path_length:.1f} in", (PATH_X, ROWS[3]), TEXT, 22)
    replies = "reply" if outcome.commands == 1 else "replies"
    r.draw_text(
        f"{outcome.commands} {replies}: {outcome.busy_replies} busy, {outcome.nan_replies} NaN",
        (REPLIES_X, ROWS[0]),
        TEXT,
        20,
    )


def paint_link(r: Renderer, link: dict[str, float], y: int) -> None:
    """What the link model did, in two short lines under the connected clients: what it
    lost or changed (lit while anything was), and its dropouts and time."""
    hurt = link["lost"] or link["corrupted"]
    r.draw_text(
        f"link: {link['lost']:.0f} lost, {link['corrupted']:.0f} corrupted",
        (CLIENTS_X, y),
        ALARM if hurt else TEXT,
        18,
    )
    drops = "dropout" if link["dropouts"] == 1 else "dropouts"
    r.draw_text(
        f"{link['dropouts']:.0f} {drops}, {link['seconds']:.2f} s on it",
        (CLIENTS_X, y + 16),
        TEXT,
        18,
    )


def paint_heading_dial(r: Renderer, heading: float, center: tuple[float, float]) -> None:
    """A small dial beside the pose: an arrow pointing where the robot faces on screen
    (heading 0 is +y, down the screen; 90 is -x, to the left; a positive turn is clockwise
    on screen), so the number and the picture say the same."""
    rad = math.radians(heading)
    dx, dy = -math.sin(rad), math.cos(rad)  # the robot's +y in the world; y is down on screen
    cx, cy = center
    r.draw_circle(center, DIAL_RADIUS, DIM, 1)
    tip = (cx + dx * DIAL_RADIUS, cy + dy * DIAL_RADIUS)
    r.draw_segment((cx - dx * 4, cy - dy * 4), tip, TEXT, 2)
    side = (-dy * 3.5, dx * 3.5)
    back = (tip[0] - dx * 5, tip[1] - dy * 5)
    r.draw_polygon(
        [tip, (back[0] + side[0], back[1] + side[1]), (back[0] - side[0], back[1] - side[1])],
        TEXT,
    )


def paint_blocked(r: Renderer, view: View, snap: Snapshot) -> None:
    """A blocked move over the maze: the robot's outline in red and, above it, which command
    a wall or the block stops and how far it got (its reply was +inf, accepted, as the
    original's: this is where a student sees that it went nowhere)."""
    if snap.blocked is None:
        return
    points = view.points(snap.outline)
    r.draw_polygon(points, ALARM, 3)
    x = sum(p[0] for p in points) / len(points)
    top = min(p[1] for p in points)
    width = int(len(snap.blocked) * 18 * LETTER) + 12
    box = (int(x - width / 2), int(top - 30), width, 22)
    r.draw_rect(box, BOX)
    r.draw_rect(box, ALARM, 1)
    r.draw_text(snap.blocked, (x, top - 19), ALARM, 18, centered=True)


def paint_switched_off(
    r: Renderer, switched_off: tuple[tuple[str, str], ...], width: int | None = None
) -> None:
    """One red line per device switched off, in a red-edged box at the bottom right of the
    panel, over the older commands (never over the maze): a student must notice that their
    device no longer answers, and why. Lines are cut to fit ``width`` if given."""
    lines = [f"{device_id} switched off: {reason}"[:120] for device_id, reason in switched_off]
    if len(lines) > SWITCHED_OFF_SHOWN:
        more = len(lines) - SWITCHED_OFF_SHOWN + 1
        lines[SWITCHED_OFF_SHOWN - 1 :] = [f"... and {more} more devices switched off"]
    hint = "switched-off devices answer NaN; the traceback is in the log; R (reset) restarts them"
    size, step, hint_size = 18, 18, 16
    x = COMMANDS_X - 10
    if width is not None:
        fits = max(8, int((width - x - 20) / (LETTER * size)))
        lines = [line if len(line) <= fits else line[: fits - 3] + "..." for line in lines]
        hint = hint if len(hint) <= fits else hint[: fits - 3] + "..."
    box_width = 20 + round(LETTER * size * max(len(line) for line in [*lines, hint]))
    if width is not None:
        box_width = min(box_width, width - x)
    height = 8 + step * len(lines) + hint_size + 4
    y = PANEL_HEIGHT - height - 2
    r.draw_rect((x, y, box_width, height), BOX)
    r.draw_rect((x, y, box_width, height), ALARM, 1)
    for i, line in enumerate(lines):
        r.draw_text(line, (x + 10, y + 6 + step * i), ALARM, size)
    r.draw_text(hint, (x + 10, y + 6 + step * len(lines)), DIM, hint_size)


def paint_help(r: Renderer, size: tuple[int, int], keys: Sequence[tuple[str, str]] = HELP) -> None:
    """The list of ``keys`` (key, what it does), in a box over the maze."""
    longest = max((len(what) for _, what in keys), default=0)
    width = max(560, HELP_WHAT_X + int(longest * 22 * LETTER) + 24)  # every line inside
    height = 44 + 26 * len(keys)
    x0 = max(0, (size[0] - width) // 2)
    y0 = max(PANEL_HEIGHT, (size[1] - height) // 2)
    r.draw_rect((x0, y0, width, height), BOX)
    r.draw_rect((x0, y0, width, height), LIT, 2)
    r.draw_text("Keys and mouse; what the display says", (x0 + 16, y0 + 12), LIT, 24)
    for i, (key, what) in enumerate(keys):
        y = y0 + 42 + 26 * i
        r.draw_text(key, (x0 + 16, y), LIT, 22)
        r.draw_text(what, (x0 + HELP_WHAT_X, y), TEXT, 22)
