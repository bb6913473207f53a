"""``simmer plot`` of a tap's run folder: what the program sent the real robot and what it
answered, over time, in ``timeline.png``.

A real run has no true pose, so there is no path to draw; what the tap saw is the traffic. The
picture has a panel of commands (a row per drive: each move at the time it was sent, labelled
with its amount; the zero-length polls a program sends while it waits as faint ticks; a
command the robot refused or never answered in red) and a panel per sensor (every reading it
replied, against the time its message was sent). The time axis is the tap's: wall-clock
seconds since it started.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from simmer.protocol import parse_message
from simmer.tap.folder import TapRun

TIMELINE_IMAGE = "timeline.png"
"""The picture ``simmer plot`` writes into a tap's run folder."""
LABELLED = 60
"""Moves labelled with their amount (the first ones); the rest are drawn unlabelled."""
LABEL_GAP = 0.04
"""A move's label goes above the previous one's when the two are closer than this share of
the time axis (about 45 pixels: a label's width), so neighbours' labels do not run together."""


@dataclass(frozen=True)
class Traffic:
    """What a tap's run says, sorted for the picture."""

    drives: dict[str, list[tuple[float, float, float]]]
    """Per drive: (time, amount, reply) of each command to it, polls (amount 0) too."""
    readings: dict[str, list[tuple[float, float]]]
    """Per sensor: (time, reading) of each finite reading."""
    unanswered: list[float]
    """When each other command (not a drive's, nor a sensor's finite reading) got NaN."""


def traffic(run: TapRun) -> Traffic:
    """``run``'s exchanges sorted by device: drives' commands, sensors' readings, the rest
    answered NaN (or never)."""
    groups = {spec.id: spec.group for spec in run.config.devices}
    lenient = run.config.settings.lenient_commands
    drives: dict[str, list[tuple[float, float, float]]] = {}
    readings: dict[str, list[tuple[float, float]]] = {}
    unanswered: list[float] = []
    for event in run.exchanges:
        commands = parse_message(event.message, lenient=lenient)
        replies = list(event.replies) + [math.nan] * (len(commands) - len(event.replies))
        for command, reply in zip(commands, replies, strict=False):
            group = groups.get(command.device, "")
            if group == "drives":
                drives.setdefault(command.device, []).append((event.time, command.value, reply))
            elif group == "sensors" and math.isfinite(reply):
                readings.setdefault(command.device, []).append((event.time, reply))
            elif math.isnan(reply):
                unanswered.append(event.time)
    return Traffic(drives, readings, unanswered)


def draw_tap_timeline(run: TapRun, target: Path) -> None:
    """Draw ``run``'s commands and readings over time into ``target`` (see the module doc)."""
    from matplotlib import style
    from matplotlib.figure import Figure

    from simmer.record.plots import save_png

    seen = traffic(run)
    drives, readings, unanswered = seen.drives, seen.readings, seen.unanswered
    rows = list(drives)
    with style.context("default"):
        panels = 1 + len(readings)
        fig = Figure(figsize=(12.0, 1.8 + 1.2 * max(len(rows), 1) + 1.9 * len(readings)), dpi=100)
        fig.set_layout_engine("constrained")
        ratios = [max(len(rows), 1) * 0.6 + 0.6] + [1.0] * len(readings)
        axes = fig.subplots(panels, 1, sharex=True, squeeze=False, height_ratios=ratios)[:, 0]
        ax = axes[0]
        labelled = 0
        last = run.exchanges[-1].time if run.exchanges else 0.0
        near = max(last, 1.0) * LABEL_GAP
        for row, drive in enumerate(rows):
            moves = [(t, v, r) for t, v, r in drives[drive] if v != 0.0]
            polls = [t for t, v, _ in drives[drive] if v == 0.0]
            if polls:
                ax.plot(polls, [row] * len(polls), "|", color="#bbbbbb", ms=6, label=None)
            previous, raised = -math.inf, False
            for t, value, reply in moves:
                refused = not math.isinf(reply)
                ax.plot([t], [row], "v" if value < 0 else "^", ms=7,
                        color="#d62728" if refused else "#3182bd")  # fmt: skip
                if labelled < LABELLED:
                    raised = t - previous < near and not raised  # a close one goes above it
                    ax.annotate(f"{value:+g}", (t, row), xytext=(0, 16 if raised else 7),
                                textcoords="offset points", ha="center", fontsize=7)  # fmt: skip
                    previous = t
                    labelled += 1
        if unanswered:
            ax.plot(unanswered, [len(rows)] * len(unanswered), "x", color="#d62728", ms=6)
        ticks = rows + (["NaN reply"] if unanswered else [])
        ax.set_yticks(range(len(ticks)), ticks)
        ax.set_ylim(-0.7, max(len(ticks), 1) - 0.3)
        ax.set_title(
            "commands sent: a move up or down by its sign (its amount above it; red: the robot "
            "refused it), the polls while a drive moves as grey ticks",
            loc="left",
            fontsize=9,
        )
        ax.grid(alpha=0.3, axis="x")
        for ax, (sensor, values) in zip(axes[1:], readings.items(), strict=True):
            ax.plot([t for t, _ in values], [v for _, v in values], ".", color="black", ms=3)
            ax.set_ylabel(sensor)
            ax.set_title(f"{sensor}: {len(values)} readings received", loc="left", fontsize=9)
            ax.grid(alpha=0.3)
        axes[-1].set_xlabel("time since the tap started (wall-clock seconds)")
        fig.suptitle(
            f"{run.folder.name}: the real robot's traffic through simmer tap (no true pose)\n"
            f"{len(run.exchanges)} exchanges over {last:.1f} s; {len(unanswered)} other commands "
            "answered NaN or never",
            fontsize=10,
        )
        save_png(fig, target)
