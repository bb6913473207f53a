"""Runs side by side (issue 35, item 4): two recorded runs of one maze in one picture, each in
its colour, the one that collided crossed in red from the frame it collided, one timeline as
long as the longer run; the window's keys and timeline; ``simmer replay A B --check`` and
``simmer render A B`` (a decoded video of the longer run's length); runs that cannot be put
side by side refused in one line."""

from __future__ import annotations

from pathlib import Path

import av
import numpy as np
import pygame
import pytest
from typer.testing import CliRunner

from simmer import Simulation
from simmer.cli import app
from simmer.colors import COLLISION_COLOR, RUN_COLORS
from simmer.errors import ReplayError
from simmer.record import RunRecorder
from simmer.ui.compare import CompareCanvas, CompareWindow, compare_size, write_comparison
from simmer.ui.replay import TIMELINE_HEIGHT
from simmer.view.compare import MAX_COMPARED, Comparison, run_labels
from simmer.view.replay_model import Recording

from helpers import default_data, make_config

pytestmark = pytest.mark.timeout(120)


def record(folder: Path, messages: list[str], data: dict[str, object] | None = None) -> None:
    """A run of ``messages``, each driven to its end, then a second standing."""
    sim = Simulation(make_config(data or default_data()), seed=3)
    with RunRecorder(sim, folder):
        for message in messages:
            sim.command(message)
            while sim.robot.any_drive_moving:
                sim.step()
        sim.step(60)


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    root = tmp_path_factory.mktemp("compare")
    careful, reckless = root / "careful", root / "reckless"
    record(careful, ["w0-3", "r0-180", "w0-3"])
    record(reckless, ["w0-40"])  # into the wall ahead: it collides
    return careful, reckless


@pytest.fixture(scope="module")
def comparison(runs: tuple[Path, Path]) -> Comparison:
    return Comparison([Recording.load(folder) for folder in runs])


def pixels_of(surface: pygame.Surface, color: tuple[int, int, int], top: int, bottom: int) -> int:
    array = pygame.surfarray.pixels3d(surface)[:, top:bottom]
    return int(np.all(array == np.array(color, dtype=np.uint8), axis=2).sum())


def test_the_model_puts_both_runs_on_the_longer_ones_timeline(comparison: Comparison) -> None:
    careful, reckless = comparison.runs
    assert (careful.label, reckless.label) == ("careful", "reckless")
    assert (careful.color, reckless.color) == RUN_COLORS[:2]
    frames = [len(run.recording.frames) for run in comparison.runs]
    assert comparison.timeline.frames == max(frames)
    assert careful.first_collision() is None
    hit = reckless.first_collision()
    assert hit is not None
    assert 0 < hit < reckless.recording.duration
    before = comparison.timeline.frame_at(hit) - 1
    assert reckless.collisions(before) == 0
    assert reckless.collisions(comparison.timeline.frames - 1) >= 1
    shorter = min(comparison.runs, key=lambda run: len(run.recording.frames))
    assert shorter.ended(comparison.timeline.frames - 1)
    last = shorter.recording.frames[-1]
    assert shorter.frame(comparison.timeline.frames - 1) is last  # held at its last frame


def test_a_frame_shows_each_run_in_its_colour_and_the_collided_one_crossed(
    comparison: Comparison,
) -> None:
    canvas = CompareCanvas(comparison)
    width, height = canvas.surface.get_size()
    assert (width, height) == compare_size(comparison)
    maze_bottom = height - TIMELINE_HEIGHT
    reckless = comparison.runs[1]
    hit = reckless.first_collision()
    assert hit is not None
    canvas.draw(comparison.timeline.frame_at(hit) - 2)
    assert pixels_of(canvas.surface, COLLISION_COLOR, 120, maze_bottom) == 0
    canvas.draw(comparison.timeline.frames - 1)
    for run in comparison.runs:  # robot edge and path in the maze, a swatch in the legend
        assert pixels_of(canvas.surface, run.color, 120, maze_bottom) > 200
        assert pixels_of(canvas.surface, run.color, 0, 112) >= 22 * 22
    assert pixels_of(canvas.surface, COLLISION_COLOR, 120, maze_bottom) > 50
    # the timeline: a lane per run in its colour, the collision's tick in red
    assert pixels_of(canvas.surface, COLLISION_COLOR, maze_bottom, height) > 0
    for run in comparison.runs:
        assert pixels_of(canvas.surface, run.color, maze_bottom, height) > 100


def test_the_window_plays_steps_and_seeks_on_one_timeline(comparison: Comparison) -> None:
    size = compare_size(comparison)
    window = CompareWindow(comparison, surface=pygame.Surface(size))
    pygame.event.clear()
    try:
        assert window.draw()
        assert not window.draw()
        pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_END, unicode="", mod=0))
        assert window.frame(0.0)
        assert window.playhead.frame == comparison.timeline.frames - 1
        pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_COMMA, mod=0))
        assert window.frame(0.0)
        assert window.playhead.frame == comparison.timeline.frames - 2
        middle = (size[0] // 2 + 88, size[1] - TIMELINE_HEIGHT // 2)
        pygame.event.post(pygame.event.Event(pygame.MOUSEBUTTONDOWN, pos=middle, button=1))
        pygame.event.post(pygame.event.Event(pygame.MOUSEBUTTONUP, pos=middle, button=1))
        assert window.frame(0.0)
        assert abs(window.playhead.time - comparison.duration / 2) < 0.1 * comparison.duration
        pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_SPACE, mod=0))
        assert window.frame(0.0)
        assert window.playhead.playing
        assert window.frame(0.5)
        assert window.playhead.time > comparison.duration / 2
        pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_ESCAPE, mod=0))
        assert not window.frame(0.0)
    finally:
        window.close()


@pytest.mark.slow
def test_render_of_two_runs_is_a_video_as_long_as_the_longer(
    runs: tuple[Path, Path], comparison: Comparison, tmp_path: Path
) -> None:
    target = tmp_path / "both.mp4"
    result = CliRunner().invoke(app, ["render", *map(str, runs), "-o", str(target)])
    assert result.exit_code == 0, result.output
    with av.open(str(target)) as video:
        frames = sum(1 for _ in video.decode(video=0))
        stream = video.streams.video[0]
        assert (stream.width, stream.height) == compare_size(comparison)
    assert frames == comparison.timeline.frames
    check = CliRunner().invoke(app, ["replay", "--check", *map(str, runs)])
    assert check.exit_code == 0, check.output
    assert check.output.count("matches the recording") == 2


def test_runs_that_cannot_be_side_by_side_are_refused_in_one_line(
    runs: tuple[Path, Path], comparison: Comparison, tmp_path: Path
) -> None:
    data = default_data()
    data.update(wall_segment_length=10, robot_start_position=[5, 35], block_position=[55, 5])
    other = tmp_path / "other" / "careful"
    record(other, ["w0-3"], data)
    with pytest.raises(ReplayError, match="another maze"):
        Comparison([comparison.runs[0].recording, Recording.load(other)])
    mixed = CliRunner().invoke(app, ["replay", str(runs[0]), str(other)])
    assert mixed.exit_code == 1
    assert "another maze" in mixed.output
    assert "Traceback" not in mixed.output
    with pytest.raises(ReplayError, match="2 to"):
        Comparison([comparison.runs[0].recording])
    with pytest.raises(ReplayError, match="MAX_COMPARED"):
        Comparison([comparison.runs[0].recording] * (MAX_COMPARED + 1))
    too_many = CliRunner().invoke(app, ["replay", *[str(runs[0])] * (MAX_COMPARED + 1)])
    assert too_many.exit_code == 1
    assert "MAX_COMPARED" in too_many.output
    assert "Traceback" not in too_many.output
    assert run_labels([runs[0], other]) == [f"{runs[0].parent.name}/careful", "other/careful"]
    out = tmp_path / "clip.txt"
    with pytest.raises(ReplayError, match=r"\.mp4 or \.gif"):
        write_comparison(comparison, out)
    assert not out.exists()
