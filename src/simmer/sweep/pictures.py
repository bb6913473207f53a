"""The pictures of a sweep's summary: success rate per setting with 95% Wilson intervals, and
final positions over the maze coloured by success. Matplotlib (Agg, no pyplot) is imported
only when they are drawn."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from simmer.sweep.results import SettingSummary
from simmer.sweep.spec import SweepSpec

if TYPE_CHECKING:
    from matplotlib.figure import Figure

SUCCESS_COLOR = "#2a9d4b"
FAILURE_COLOR = "#d1495b"


def draw_pictures(
    folder: Path,
    spec: SweepSpec,
    rows: Sequence[Mapping[str, str]],
    summaries: Sequence[SettingSummary],
) -> list[str]:
    """Draw ``success_rate.png`` and ``final_positions.png`` into ``folder``; their names."""
    from matplotlib import style

    with style.context("default"):
        _save(_rate_figure(spec, summaries), folder / "success_rate.png")
        _save(_positions_figure(spec, rows), folder / "final_positions.png")
    return ["success_rate.png", "final_positions.png"]


def _save(fig: Figure, target: Path) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)
    fig.savefig(target, format="png")


def _label(spec: SweepSpec, setting: Sequence[str]) -> str:
    return (
        "\n".join(
            f"{c.rsplit('.', 1)[-1] if len(spec.columns) > 1 else c} = {v}"
            for c, v in zip(spec.columns, setting, strict=True)
        )
        or "all runs"
    )


def _rate_figure(spec: SweepSpec, summaries: Sequence[SettingSummary]) -> Figure:
    """Success rate of each setting, with its 95% Wilson interval as the error bar."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(max(4.0, 1.3 * len(summaries) + 1.5), 4.0), layout="constrained")
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
        )
    ax.set_xticks(places, [_label(spec, s.setting) for s in summaries], fontsize=8)
    ax.set_xlim(-0.6, len(summaries) - 0.4)
    ax.set_ylim(-0.05, 1.05)
    ax.set_ylabel("success rate (95% Wilson interval)")
    ax.set_title(f"success: {spec.success}", fontsize=9)
    ax.grid(axis="y", alpha=0.3)
    return fig


def _positions_figure(spec: SweepSpec, rows: Sequence[Mapping[str, str]]) -> Figure:
    """Every run's final position over the (first) maze, green for success, red otherwise."""
    from matplotlib.figure import Figure

    from simmer.sweep.runs import build_config
    from simmer.world.maze import Maze

    settings = build_config(str(spec.configs[0]), ()).settings
    maze = Maze.from_settings(settings)
    fig = Figure(figsize=(7.0, 7.0 * maze.height / maze.width + 0.6), layout="constrained")
    ax = fig.add_subplot()
    for x1, y1, x2, y2 in maze.segments:
        ax.plot([x1, x2], [y1, y2], color="black", lw=2)
    bx, by = settings.block_position
    ax.plot(bx, by, "s", ms=10, mfc="none", mec="#555555", label="block")
    sx, sy = settings.robot_start_position
    ax.plot(sx, sy, "^", ms=9, mfc="none", mec="#555555", label="start")
    for success, color, name in (
        (True, SUCCESS_COLOR, "success"),
        (False, FAILURE_COLOR, "failure"),
    ):
        chosen = [r for r in rows if (r["success"] == "True") == success and r["final_x"]]
        ax.scatter(
            [float(r["final_x"]) for r in chosen],
            [float(r["final_y"]) for r in chosen],
            s=18,
            color=color,
            alpha=0.7,
            label=f"{name} ({len(chosen)})",
            zorder=3,
        )
    margin = maze.cell * 0.15
    ax.set_xlim(-margin, maze.width + margin)
    ax.set_ylim(maze.height + margin, -margin)  # +y down the page, as in the window
    ax.set_aspect("equal")
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8)
    ax.set_title("final positions", fontsize=10)
    return fig
