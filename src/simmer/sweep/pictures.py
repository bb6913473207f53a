"""The pictures of a sweep's summary: success rate per setting with 95% Wilson intervals, final
positions over the maze marked by how each run ended, the Task 2 time's distribution per
setting (a project sweep's score and delivery time instead), and with a random sample, success
against each sampled key. Matplotlib (Agg, no pyplot) is imported only when they are drawn."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from simmer.record.page import draw_items
from simmer.record.plots import save_png
from simmer.scene import Look, Walls, maze_items, open_cell_items
from simmer.sweep.results import SettingSummary, wilson_interval
from simmer.sweep.spec import Distribution, SweepSpec

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

SUCCESS_COLOR = "#2a9d4b"
FAILURE_COLOR = "#d1495b"
HISTOGRAM_COLOR = "#3a6ea5"
FAILURE_MARKERS = {
    "collision": ("X", "collision"),
    "timeout": ("s", "timeout"),
    "stopped-short": ("v", "stopped short"),
    "no-pickup": ("v", "no pickup"),
    "not-delivered": ("P", "not delivered"),
    "wrong-zone": ("*", "wrong zone"),
    "condition": ("D", "condition false"),
}
"""How each kind of failure is marked among the final positions (a crashed run has none)."""
SCORE_STEP = 5.0
"""Points each bar of a project sweep's score histogram spans (milestones earn tens, a
collision costs 2)."""
SAMPLE_BINS = 8
"""Bins at most along a sampled key (fewer for few draws: about 5 runs a bin at least)."""


def draw_pictures(
    folder: Path,
    spec: SweepSpec,
    rows: Sequence[Mapping[str, str]],
    summaries: Sequence[SettingSummary],
) -> list[tuple[str, str]]:
    """Draw the summary's pictures into ``folder``; each one's file name and caption."""
    from matplotlib import style

    drawn = []
    with style.context("default"):
        _save(_rate_figure(spec, summaries), folder / "success_rate.png")
        drawn.append(("success_rate.png", "Success rate per setting, with 95% Wilson intervals"))
        _save(_positions_figure(spec, rows), folder / "final_positions.png")
        drawn.append(("final_positions.png", "Where each run ended, marked by how it ended"))
        for name, caption, figure in _time_figures(spec, rows, summaries):
            _save(figure, folder / name)
            drawn.append((name, caption))
        if spec.sample:
            _save(_sample_figure(spec, rows), folder / "sampled.png")
            caption = "Success rate against each sampled key, all settings together"
            drawn.append(("sampled.png", caption))
        mazes = _mazes_figure(spec, rows)
        if mazes is not None:
            _save(mazes, folder / "mazes.png")
            caption = (
                "Each maze of the sweep, its frame and cells coloured by the success rate of "
                "its runs (red 0 to green 1), each run's end marked: in which mazes does the "
                "program fail?"
            )
            drawn.append(("mazes.png", caption))
        starts = [r for r in rows if r.get("start_x")]
        if spec.project and starts:
            _save(_start_cells_figure(spec, starts, START_PANELS), folder / "start_cells.png")
            caption = (
                "Success rate by start cell (all headings together), and the rate of each "
                "milestone: from where does the program fail?"
            )
            drawn.append(("start_cells.png", caption))
        if starts and any(r.get("estimates") for r in starts):
            figure = _start_cells_figure(spec, starts, LOCALIZED_PANELS)
            _save(figure, folder / "localized_start_cells.png")
            caption = (
                "Rate of runs that localized (within 3 in and 15 deg to the end) by start cell, "
                "with the median time to localize: from where is the robot hard to place?"
            )
            drawn.append(("localized_start_cells.png", caption))
    return drawn


START_PANELS = (
    ("success", "success"),
    ("entered_loading", "entered the loading zone"),
    ("picked_up", "picked up the block"),
    ("left_loading", "left the loading zone holding it"),
    ("delivered", "delivered to the target"),
)
"""The start-cell pictures: success, then each project milestone."""
LOCALIZED = "localized_at"
LOCALIZED_PANELS = ((LOCALIZED, "localized: time to localize (median) by start cell"),)
"""The localization start-cell picture: runs whose program localized, and how fast."""


def _met(run: Mapping[str, str], column: str) -> bool:
    """Whether a run met a panel's column: True, or for :data:`LOCALIZED` any time at all."""
    if column == LOCALIZED:
        return bool(run.get(column))
    return run.get(column) == "True"


def _cell_text(runs: Sequence[Mapping[str, str]], column: str, met: int) -> str:
    """``k/n``, and for :data:`LOCALIZED` the median time to localize of those that did."""
    text = f"{met}/{len(runs)}"
    if column == LOCALIZED and met:
        times = sorted(float(r[column]) for r in runs if r.get(column))
        text += f"\n{float(np.median(times)):.1f} s"
    return text


def _start_cells_figure(
    spec: SweepSpec, rows: Sequence[Mapping[str, str]], panels: Sequence[tuple[str, str]]
) -> Figure:
    """The maze once per panel of ``panels`` (column, title), each start cell coloured by the
    rate of runs starting there that met it (red 0 to green 1), with ``k/n`` written in it."""
    from matplotlib import colormaps
    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle

    from simmer.config.maze import Maze
    from simmer.config.zones import Zones
    from simmer.sweep.runs import build_config

    settings = build_config(str(spec.configs[0]), ()).settings
    maze = Maze.from_settings(settings)
    cell = maze.cell
    by_cell: dict[tuple[int, int], list[Mapping[str, str]]] = {}
    for r in rows:
        place = (int(float(r["start_y"]) // cell), int(float(r["start_x"]) // cell))
        by_cell.setdefault(place, []).append(r)
    cmap = colormaps["RdYlGn"]
    panel_height = 4.2 * maze.height / maze.width + 0.5
    fig = Figure(figsize=(8.0, panel_height * len(panels)), layout="constrained")
    scene = maze_items(maze, settings, Look.MAP, Zones.from_settings(settings))
    for i, (column, title) in enumerate(panels):
        ax = fig.add_subplot(len(panels), 1, i + 1)
        draw_items(ax, scene)
        met_total = 0
        for (row, col), runs in by_cell.items():
            met = sum(_met(r, column) for r in runs)
            met_total += met
            rate = met / len(runs)
            ax.add_patch(Rectangle((col * cell, row * cell), cell, cell, fc=cmap(rate), ec="white"))
            ax.text(
                (col + 0.5) * cell,
                (row + 0.5) * cell,
                _cell_text(runs, column, met),
                ha="center",
                va="center",
                fontsize=8,
            )
        ax.set_xlim(-1, maze.width + 1)
        ax.set_ylim(maze.height + 1, -1)  # +y down the page, as in the window
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_title(f"{title}: {met_total}/{len(rows)} runs", fontsize=9)
    return fig


MAZE_THUMBNAILS = 60
"""Mazes drawn at most in a sweep's mazes.png (the first in the sweep's order; a sweep over
more says so in the picture's title)."""


def _maze_columns(spec: SweepSpec) -> list[str]:
    """The swept or sampled columns that choose the maze: ``maze`` (files) and ``maze.*``."""
    return [c for c in spec.columns if c == "maze" or c.startswith("maze.")]


def _mazes_figure(spec: SweepSpec, rows: Sequence[Mapping[str, str]]) -> Figure | None:
    """Each maze a sweep runs over (``maze`` or ``maze.*`` swept) as a thumbnail: its open
    cells and frame coloured by the success rate of its runs (red 0 to green 1), each run's
    end a dot (green success, red failure), ``k/n`` in its title; None if no maze is swept."""
    columns = _maze_columns(spec)
    if not columns:
        return None
    from matplotlib import colormaps
    from matplotlib.figure import Figure

    from simmer.config.maze import Maze
    from simmer.config.mazegen import measure
    from simmer.config.zones import Zones
    from simmer.errors import SimmerError
    from simmer.sweep.runs import build_config

    index = [spec.columns.index(c) for c in columns]
    chosen: dict[tuple[str, ...], list[Mapping[str, str]]] = {}
    for r in rows:
        chosen.setdefault(tuple(r[c] for c in columns), []).append(r)
    built: dict[tuple[str, ...], Any] = {}
    for run in spec.iter_runs():  # the overrides that make each maze, as its runs had them
        key = tuple(str(run.setting[i]) for i in index)
        if key in chosen and key not in built:
            try:
                built[key] = build_config(run.config, run.overrides).settings
            except SimmerError:  # an invalid maze: its runs are `invalid`, it is left out
                built[key] = None
        if len(built) == min(len(chosen), MAZE_THUMBNAILS):
            break
    keys = [k for k in chosen if built.get(k) is not None][:MAZE_THUMBNAILS]
    if not keys:
        return None
    across = min(len(keys), 5)
    down = math.ceil(len(keys) / across)
    first = Maze.from_settings(built[keys[0]])
    fig = Figure(
        figsize=(2.4 * across, (2.4 * first.height / first.width + 0.45) * down + 0.4),
        layout="constrained",
    )
    cmap = colormaps["RdYlGn"]
    successes = 0
    for i, key in enumerate(keys):
        settings, runs = built[key], chosen[key]
        maze = Maze.from_settings(settings)
        met = sum(r["success"] == "True" for r in runs)
        successes += met
        colour = cmap(met / len(runs))
        ax = fig.add_subplot(down, across, i + 1)
        tint = tuple(round(255 * v) for v in colour[:3])
        items = maze_items(maze, settings, Look.MAP, Zones.from_settings(settings))
        items += open_cell_items(settings.walls, maze.cell, (tint[0], tint[1], tint[2]))
        draw_items(ax, sorted(items, key=lambda item: item.layer))
        for r in runs:
            if r["final_x"]:
                ok = r["success"] == "True"
                ax.plot(
                    float(r["final_x"]), float(r["final_y"]), "o", ms=4,
                    color=SUCCESS_COLOR if ok else FAILURE_COLOR, zorder=4,
                )  # fmt: skip
        for side in ax.spines.values():
            side.set_edgecolor(colour)
            side.set_linewidth(3)
        ax.set_xlim(-1, maze.width + 1)
        ax.set_ylim(maze.height + 1, -1)  # +y down the page, as in the window
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        name = ", ".join(
            f"{c.split('.')[-1]} {_short(v)}" for c, v in zip(columns, key, strict=True)
        )
        opened = np.array(settings.walls) != 0
        alike = measure(opened, maze.cell, 1.0, loading_zone=False).ambiguity
        ax.set_title(f"{name}: {met}/{len(runs)} (ambiguity {alike:.2f})", fontsize=8)
    total = sum(len(chosen[k]) for k in keys)
    more = f" (the first {len(keys)} of {len(chosen)})" if len(chosen) > len(keys) else ""
    fig.suptitle(f"{len(keys)} mazes{more}: {successes}/{total} runs succeeded", fontsize=10)
    return fig


def _short(value: str) -> str:
    """A maze file by its name alone, a seed as it is."""
    return Path(value).name if ("/" in value or "\\" in value) else value


def _save(fig: Figure, target: Path) -> None:
    save_png(fig, target, run_folder=False, dpi=100)  # a sweep's folder is not a run folder


def _label(spec: SweepSpec, setting: Sequence[str], sep: str = "\n") -> str:
    """A setting in a few words: each key by its last three names (``w0.error.y = 0.05``)."""
    return (
        sep.join(
            f"{'.'.join(c.split('.')[-3:])} = {v}"
            for c, v in zip(spec.setting_columns, setting, strict=True)
        )
        or "all runs"
    )


def _in(spec: SweepSpec, summary: SettingSummary, r: Mapping[str, str]) -> bool:
    return tuple(r[c] for c in spec.setting_columns) == summary.setting


def _rate_figure(spec: SweepSpec, summaries: Sequence[SettingSummary]) -> Figure:
    """Success rate of each setting, with its 95% Wilson interval as the error bar."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(max(4.5, 1.4 * len(summaries) + 1.5), 4.2), layout="constrained")
    ax = fig.add_subplot()
    places = list(range(len(summaries)))
    rates = [s.successes / s.runs for s in summaries]
    low = [max(0.0, r - s.interval[0]) for r, s in zip(rates, summaries, strict=True)]
    high = [max(0.0, s.interval[1] - r) for r, s in zip(rates, summaries, strict=True)]
    ax.errorbar(places, rates, yerr=[low, high], fmt="o", capsize=5, color="black")
    for place, s in zip(places, summaries, strict=True):
        ax.annotate(
            f"{s.successes}/{s.runs}",
            (place, s.successes / s.runs),
            xytext=(8, 0),
            textcoords="offset points",
            va="center",
            fontsize=8,
        )
    ax.set_xticks(places, [_label(spec, s.setting) for s in summaries], fontsize=8)
    ax.set_xlim(-0.6, len(summaries) - 0.4)
    ax.set_ylim(-0.05, 1.05)
    ax.set_ylabel("success rate (95% Wilson interval)")
    ax.set_title(f"success: {spec.success}", fontsize=9)
    ax.grid(axis="y", alpha=0.3)
    return fig


def _positions_figure(spec: SweepSpec, rows: Sequence[Mapping[str, str]]) -> Figure:
    """Every run's final position over the (first) maze: green for success, red otherwise,
    with a marker for each kind of failure."""
    from matplotlib.figure import Figure

    from simmer.config.maze import Maze
    from simmer.sweep.runs import build_config

    settings = build_config(str(spec.configs[0]), ()).settings
    maze = Maze.from_settings(settings)
    fig = Figure(figsize=(8.0, 7.0 * maze.height / maze.width + 0.6), layout="constrained")
    ax = fig.add_subplot()
    draw_items(
        ax, [item for item in maze_items(maze, settings, Look.MAP) if isinstance(item, Walls)]
    )
    if not spec.project:  # a project run's block and start may be drawn: each its own
        bx, by = settings.block_position
        ax.plot(bx, by, "s", ms=10, mfc="none", mec="#555555", label="block")
        sx, sy = settings.robot_start_position
        ax.plot(sx, sy, "^", ms=9, mfc="none", mec="#555555", label="start")
    groups = [("", "o", "success", SUCCESS_COLOR)] + [
        (kind, marker, name, FAILURE_COLOR) for kind, (marker, name) in FAILURE_MARKERS.items()
    ]
    for kind, marker, name, color in groups:
        chosen = [r for r in rows if r["failure"] == kind and r["final_x"]]
        if not chosen and kind:
            continue
        ax.scatter(
            [float(r["final_x"]) for r in chosen],
            [float(r["final_y"]) for r in chosen],
            s=32,
            marker=marker,
            color=color,
            alpha=0.65,
            linewidths=0,
            label=f"{name} ({len(chosen)})",
            zorder=3,
        )
    margin = maze.cell * 0.15
    ax.set_xlim(-margin, maze.width + margin)
    ax.set_ylim(maze.height + margin, -margin)  # +y down the page, as in the window
    ax.set_aspect("equal")
    ax.set_xlabel("x (in)")
    ax.set_ylabel("y (in)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8)
    ax.set_title(f"final positions of {len(rows)} runs", fontsize=10)
    return fig


def _time_figures(
    spec: SweepSpec, rows: Sequence[Mapping[str, str]], summaries: Sequence[SettingSummary]
) -> list[tuple[str, str, Figure]]:
    """The histograms a sweep's runs call for, each file name, caption and figure: a
    project sweep's score and delivery time, another's Task 2 time (none drawn if no run
    has the figure)."""
    if spec.project:
        wanted = [
            ("score.png", "Score of every run (the rubric's points), per setting",
             Histogram("score", "scored", "score (points)", "Score of every run", " points",
                       SCORE_STEP)),
            ("delivery_time.png",
             "Delivery time (simulated seconds from the start) of the runs that delivered "
             "the block to its target",
             Histogram("delivered_at", "delivered", "delivery time (s), from the start",
                       "Delivery time of the runs that delivered the block")),
        ]  # fmt: skip
    else:
        wanted = [
            ("task2_time.png", "Task 2 time (first motion to the block) of the runs that "
             "reached it",
             Histogram("task2_time", "reached", "Task 2 time (s), from the first motion to "
                       "reaching the block", "Task 2 time of the runs that reached the block")),
        ]  # fmt: skip
    drawn = []
    for name, caption, histogram in wanted:
        figure = _histogram_figure(spec, rows, summaries, histogram)
        if figure is not None:
            drawn.append((name, caption, figure))
    return drawn


@dataclass(frozen=True)
class Histogram:
    """One histogram per setting of a results column: its column, what a run with a value
    did, the x axis's label and the figure's title."""

    column: str
    did: str
    axis: str
    title: str
    unit: str = " s"
    step: float | None = None
    """Each bar's width, bars from 0 up to 100 at least (a score's): all 100s are one bar on
    a 0-to-100 axis, not one in the middle of 99.6 to 100.4; None: bins fitted to the data."""


def _histogram_figure(
    spec: SweepSpec,
    rows: Sequence[Mapping[str, str]],
    summaries: Sequence[SettingSummary],
    histogram: Histogram,
) -> Figure | None:
    """A histogram of a column per setting (shared bins and axis), of the runs with a value;
    None if none has one."""
    from matplotlib.figure import Figure

    column = histogram.column
    times = [
        [float(r[column]) for r in rows if _in(spec, s, r) and r.get(column)] for s in summaries
    ]
    every = [t for group in times for t in group]
    if not every:
        return None
    if histogram.step is not None:
        step = histogram.step
        low = min(0.0, math.floor(min(every) / step) * step)
        high = max(100.0, math.floor(max(every) / step) * step) + step
        bins = np.arange(low, high + step / 2, step)
    else:
        count = min(30, max(8, 2 * round(math.sqrt(len(every)))))
        bins = np.histogram_bin_edges(every, bins=count)
    fig = Figure(figsize=(7.0, 1.0 + 1.25 * len(summaries)), layout="constrained")
    axes = fig.subplots(len(summaries), 1, sharex=True, squeeze=False)[:, 0]
    for ax, s, group in zip(axes, summaries, times, strict=True):
        counts, _, _ = ax.hist(group, bins=bins, color=HISTOGRAM_COLOR)
        reached = f"{len(group)}/{s.runs} {histogram.did}"
        if group:
            reached += f", median {float(np.median(group)):.4g}{histogram.unit}"
        ax.set_title(f"{_label(spec, s.setting, ', ')}: {reached}", loc="left", fontsize=8)
        ax.set_ylim(0, max(1.0, float(np.max(counts))) * 1.1)
        ax.set_ylabel("runs", fontsize=8)
        ax.yaxis.get_major_locator().set_params(integer=True)
        ax.tick_params(labelsize=8)
        ax.grid(axis="x", alpha=0.3)
    axes[-1].set_xlabel(histogram.axis)
    fig.suptitle(histogram.title, fontsize=10)
    return fig


def _sample_figure(spec: SweepSpec, rows: Sequence[Mapping[str, str]]) -> Figure:
    """For each sampled key, the success rate (95% Wilson interval) in bins of its values, or
    per value of a choice, over every setting; each run a tick above (success) or below."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(4.6 * len(spec.sample), 3.8), layout="constrained")
    axes = fig.subplots(1, len(spec.sample), squeeze=False)[0]
    for ax, (key, distribution) in zip(axes, spec.sample, strict=True):
        _sample_panel(ax, key, distribution, rows)
    return fig


def _sample_panel(
    ax: Axes, key: str, distribution: Distribution, rows: Sequence[Mapping[str, str]]
) -> None:
    ok = [r["success"] == "True" for r in rows]
    if distribution.kind == "choice":
        labels = list(dict.fromkeys(str(v) for v in distribution.values))
        where = np.array([labels.index(r[key]) for r in rows], dtype=float)
        centres = np.arange(len(labels), dtype=float)
        members = [where == i for i in range(len(labels))]
        ax.set_xticks(centres, labels)
    else:
        where = np.array([float(r[key]) for r in rows])
        count = max(1, min(SAMPLE_BINS, len(rows) // 5))
        edges = np.linspace(where.min(), where.max(), count + 1)
        place = np.clip(np.searchsorted(edges, where, side="right") - 1, 0, count - 1)
        centres = (edges[:-1] + edges[1:]) / 2
        members = [place == i for i in range(count)]
    success = np.array(ok)
    rates, low, high, shown = [], [], [], []
    for centre, member in zip(centres, members, strict=True):
        runs = int(member.sum())
        if not runs:
            continue
        wins = int(success[member].sum())
        a, b = wilson_interval(wins, runs)
        rates.append(wins / runs)
        low.append(max(0.0, wins / runs - a))
        high.append(max(0.0, b - wins / runs))
        shown.append(centre)
        ax.annotate(
            f"{wins}/{runs}", (centre, wins / runs), xytext=(6, 0), textcoords="offset points",
            va="center", fontsize=7,
        )  # fmt: skip
    ax.errorbar(shown, rates, yerr=[low, high], fmt="o", capsize=4, color="black")
    ax.plot(where[success], np.full(int(success.sum()), 1.1), "|", color=SUCCESS_COLOR, ms=8)
    ax.plot(where[~success], np.full(int((~success).sum()), -0.1), "|", color=FAILURE_COLOR, ms=8)
    ax.set_ylim(-0.18, 1.18)
    ax.set_yticks([0, 0.25, 0.5, 0.75, 1])
    ax.set_xlabel(f"{key} ~ {distribution}", fontsize=8)
    ax.set_ylabel("success rate", fontsize=8)
    ax.tick_params(labelsize=8)
    ax.grid(axis="y", alpha=0.3)
