"""Runs side by side, without a display: several recorded runs of the same maze on one
timeline (``simmer replay RUN_A RUN_B ...``, ``simmer render RUN_A RUN_B ... -o both.mp4``).

Each run is a :class:`~simmer.view.replay_model.Recording` (re-simulated once, up front) with
a label and a colour of its own (:data:`~simmer.colors.RUN_COLORS`). The timeline is the
longest run's; a run that ended earlier stays at its last frame. Whether a run has collided by
a frame is read from that frame's outcome, so the mark appears when the collision happens.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from simmer.colors import RUN_COLORS, Color
from simmer.errors import ReplayError
from simmer.view.replay_model import Frame, Recording, Timeline
from simmer.view.snapshot import StaticScene

__all__ = ["MAX_COMPARED", "ComparedRun", "Comparison", "run_labels"]

MAX_COMPARED = len(RUN_COLORS)
"""Runs shown side by side at most: one colour each, told apart at a glance (and a legend
line each in the panel above the maze)."""


@dataclass(frozen=True)
class ComparedRun:
    """One run of a comparison: its recording, its label in the legend and its colour."""

    recording: Recording
    label: str
    color: Color

    def frame(self, index: int) -> Frame:
        """Its frame at the comparison's frame ``index`` (its last, once it has ended)."""
        frames = self.recording.frames
        return frames[min(max(index, 0), len(frames) - 1)]

    def collisions(self, index: int) -> int:
        """Collisions so far at frame ``index``."""
        outcome = self.frame(index).outcome
        return 0 if outcome is None else outcome.collisions

    def first_collision(self) -> float | None:
        """Seconds from the start when it first collided (None: it never did)."""
        outcome = self.recording.frames[-1].outcome
        if outcome is None or not outcome.collisions:
            return None
        return next(
            (i / self.recording.timeline.fps for i in range(len(self.recording.frames))
             if self.collisions(i)),
            None,
        )  # fmt: skip

    def ended(self, index: int) -> bool:
        """Whether the run is over by frame ``index`` (it shows its last frame)."""
        return index >= len(self.recording.frames) - 1


def run_labels(folders: Sequence[Path]) -> list[str]:
    """Each run's name in the legend: its folder's name, or with its parent's where two
    runs' folders have the same name."""
    names = [folder.resolve().name for folder in folders]
    return [
        f"{folder.resolve().parent.name}/{name}" if names.count(name) > 1 else name
        for folder, name in zip(folders, names, strict=True)
    ]


class Comparison:
    """Several recordings of one maze, side by side on one timeline (see the module doc).

    :class:`ReplayError` if there are fewer than two or more than :data:`MAX_COMPARED`, or if
    their mazes or frame rates differ (the runs would not be in one picture)."""

    def __init__(self, recordings: Sequence[Recording], labels: Sequence[str] | None = None):
        count = len(recordings)
        if not 2 <= count <= MAX_COMPARED:
            raise ReplayError(
                f"{count} run folders: side by side shows 2 to {MAX_COMPARED} runs "
                f"(MAX_COMPARED; one colour each)"
            )
        first = recordings[0]
        for other in recordings[1:]:
            if not _same_maze(first.scene, other.scene):
                raise ReplayError(
                    f"{other.folder} was run in another maze than {first.folder}: runs side by "
                    "side must share their maze (its cells and their size)"
                )
            if other.timeline.fps != first.timeline.fps:
                raise ReplayError(f"{other.folder}: another frame rate than {first.folder}")
        names = list(labels) if labels is not None else run_labels([r.folder for r in recordings])
        self.runs = tuple(
            ComparedRun(recording, name, RUN_COLORS[i])
            for i, (recording, name) in enumerate(zip(recordings, names, strict=True))
        )
        self.scene: StaticScene = first.scene
        """The maze and the first run's configuration (walls, zones, colours)."""
        self.timeline = Timeline(first.timeline.fps, max(r.timeline.frames for r in recordings), ())

    @property
    def duration(self) -> float:
        """The longest run's seconds."""
        return self.timeline.duration

    @property
    def matches(self) -> bool:
        """Whether every re-simulation matches its recording."""
        return all(run.recording.check.matches for run in self.runs)


def _same_maze(a: StaticScene, b: StaticScene) -> bool:
    """Whether two scenes have the same maze: its cells and their size (the floor's pattern
    is drawn as the first run's)."""
    return (a.maze.cells, a.maze.cell) == (b.maze.cells, b.maze.cell)
