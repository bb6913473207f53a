"""Replay and clips of a recorded run (issue 11, item 4): a recorded noisy run re-simulated into
frames that match its trace; a tampered trace reported at its time and column; the playhead's
seeking and command steps; the command list's highlight; the window's trail where the trace
says the robot was; ``simmer render`` clips whose decoded length is the time asked for; one-line
errors for what cannot be replayed."""

from __future__ import annotations

import csv
import math
import shutil
from collections.abc import Iterator
from pathlib import Path

import av
import numpy as np
import pygame
import pytest
from PIL import Image
from typer.testing import CliRunner

from simmer import Simulation
from simmer.cli import app
from simmer.colors import TRAIL_COLOR
from simmer.errors import ReplayError
from simmer.record import RunRecorder
from simmer.ui.hud import LIT, paint_hud
from simmer.ui.render import RecordingRenderer
from simmer.ui.replay import (
    MAX_FRAME_SECONDS,
    REPLAY_HELP,
    ReplayWindow,
    TimelineBar,
    paint_panel,
    paint_timeline,
    replay_window_size,
    short_client,
)
from simmer.view.replay_model import FPS, SPEEDS, Playhead, Recording, Timeline

from helpers import LAB_SEQUENCE, noisy_config

pytestmark = pytest.mark.timeout(120)

CLIENT = "stream 127.0.0.1:50312"


def record_run(folder: Path) -> None:
    """A noisy run of about 15 simulated seconds: the lab's first three moves with the sensors
    read before each, held keys, and a last reading."""
    sim = Simulation(noisy_config(), seed=11)
    with RunRecorder(sim, folder):
        for message in LAB_SEQUENCE[:3]:
            sim.command("u0,u1,u2,u3", client=CLIENT)
            sim.command(message, client=CLIENT)
            while sim.robot.any_drive_moving:
                sim.step()
        sim.set_manual_keys("d")
        sim.step(30)
        sim.set_manual_keys("")
        sim.command("u0")
        sim.step(20)


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("replay") / "run"
    record_run(folder)
    return folder


@pytest.fixture(scope="module")
def recording(run_folder: Path) -> Recording:
    return Recording.load(run_folder)


@pytest.fixture
def copy(run_folder: Path, tmp_path: Path) -> Path:
    """A copy of the recorded run to spoil."""
    return Path(shutil.copytree(run_folder, tmp_path / "copy"))


@pytest.fixture
def window(recording: Recording) -> Iterator[ReplayWindow]:
    win = ReplayWindow(recording, surface=pygame.Surface(replay_window_size(recording.scene)))
    pygame.event.clear()
    yield win
    win.close()


def trace_rows(folder: Path) -> list[dict[str, str]]:
    with (folder / "trace.csv").open(newline="") as file:
        return list(csv.DictReader(file))


def press(win: ReplayWindow, key: int, unicode: str = "") -> None:
    pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=key, unicode=unicode, mod=0))
    assert win.frame(0.0)


def mouse(win: ReplayWindow, kind: int, x: float) -> None:
    pos = (round(x), win.timeline_rect.centery)
    if kind == pygame.MOUSEMOTION:
        event = pygame.event.Event(kind, pos=pos, rel=(0, 0), buttons=(1, 0, 0))
    else:
        event = pygame.event.Event(kind, pos=pos, button=1)
    pygame.event.post(event)
    assert win.frame(0.0)


# ----------------------------------------------------------------------------- the model


def test_the_replay_of_a_recorded_noisy_run_matches_its_trace(
    recording: Recording, run_folder: Path
) -> None:
    check = recording.check
    assert check.matches
    assert check.lines() == [
        f"the re-simulation matches the recording ({check.rows} trace rows, every reply)"
    ]
    rows = trace_rows(run_folder)
    assert check.rows == len(rows) > 300
    # A frame every 1/30 s, each where the trace's row of that time says the robot was.
    assert recording.timeline.frames == len(recording.frames) == round(recording.duration * FPS) + 1
    by_time = {round(float(row["time"]) * FPS): row for row in rows}
    for index, frame in enumerate(recording.frames):
        row = by_time[index]
        assert (frame.pose.x, frame.pose.y) == pytest.approx((float(row["x"]), float(row["y"])))
    assert [c.event.message for c in recording.commands][:2] == ["u0,u1,u2,u3", "w0-36"]
    assert not any(command.differs for command in recording.commands)


@pytest.mark.slow
def test_a_tampered_trace_cell_is_reported_at_its_time_and_column(copy: Path) -> None:
    path = copy / "trace.csv"
    lines = path.read_text().splitlines(keepends=True)
    cells = lines[200].split(",")
    header = lines[0].strip().split(",")
    column = header.index("y")
    cells[column] = "12.5"
    lines[200] = ",".join(cells)
    path.write_text("".join(lines))
    time = float(cells[header.index("time")])

    check = Recording.load(copy).check
    assert not check.matches
    difference = check.difference
    assert difference is not None
    assert (difference.time, difference.column, difference.recorded) == (time, "y", "12.5")
    assert check.difference_time == pytest.approx(time)
    assert check.lines()[0] == (
        f"the re-simulation DIFFERS from the recording at {time:.3f} s in column y: "
        f"recorded 12.5, re-simulated {difference.replayed}"
    )
    assert check.lines()[1].startswith("recorded with SimMeR ")
    assert check.lines()[2].startswith("replayed with SimMeR ")
    assert "numpy" in check.lines()[2]

    result = CliRunner().invoke(app, ["replay", "--check", str(copy)])
    assert result.exit_code == 1
    assert f"DIFFERS from the recording at {time:.3f} s in column y" in result.stderr


@pytest.mark.slow
def test_simmer_replay_check_says_a_run_matches(run_folder: Path) -> None:
    result = CliRunner().invoke(app, ["replay", "--check", str(run_folder)])
    assert result.exit_code == 0, result.output
    assert "the re-simulation matches the recording" in result.stdout


def test_commands_land_on_the_first_frame_that_shows_them(recording: Recording) -> None:
    timeline = recording.timeline
    for command in recording.commands:
        assert timeline.frame_time(command.frame) > command.time - 1e-9
        assert timeline.frame_time(command.frame - 1) <= command.time + 1e-9
        shown = (command.event.time, command.event.message)
        hud = recording.snapshot(min(command.frame, timeline.frames - 1)).commands
        assert shown in [(event.time, event.message) for event in hud]
        before = recording.snapshot(command.frame - 1).commands
        assert shown not in [(event.time, event.message) for event in before]


def test_seeking_and_next_and_previous_command_land_on_the_right_times(
    recording: Recording,
) -> None:
    playhead = Playhead(recording.timeline)
    timeline = recording.timeline
    commands = recording.commands
    assert playhead.command == -1
    landed = []
    for _ in commands:
        playhead.next_command()
        landed.append((playhead.command, playhead.time))
    assert landed == [(i, timeline.frame_time(c.frame)) for i, c in enumerate(commands)]
    playhead.next_command()  # after the last: stays
    assert playhead.command == len(commands) - 1
    for i in reversed(range(len(commands) - 1)):
        playhead.previous_command()
        assert (playhead.command, playhead.time) == (i, timeline.frame_time(commands[i].frame))
    playhead.previous_command()
    assert (playhead.command, playhead.time) == (-1, 0.0)

    # Past a command, "previous" goes back to it first.
    index = next(i for i, c in enumerate(commands) if commands[i + 1].frame - c.frame > FPS)
    playhead.seek(timeline.frame_time(commands[index].frame) + 0.5)
    assert playhead.command == index
    playhead.previous_command()
    assert (playhead.command, playhead.time) == (index, timeline.frame_time(commands[index].frame))

    playhead.seek(5.01)
    assert playhead.frame == 150
    assert playhead.command == timeline.command_at(150)
    assert commands[playhead.command].time <= 5.0 < commands[playhead.command + 1].time
    playhead.seek(-3)
    assert playhead.time == 0
    playhead.seek(1e6)
    assert playhead.time == recording.duration
    assert playhead.at_end


def test_playing_pausing_and_speeds() -> None:
    playhead = Playhead(Timeline(fps=30, frames=301, command_frames=(10, 10, 40)))
    assert playhead.timeline.duration == 10.0
    playhead.advance(1.0)
    assert playhead.time == 0  # paused
    playhead.toggle()
    playhead.advance(1.0)
    assert (playhead.time, playhead.frame, playhead.command) == (1.0, 30, 1)
    for _ in range(10):
        playhead.faster()
    assert playhead.speed == SPEEDS[-1] == 16
    playhead.advance(0.25)
    assert playhead.time == 5.0
    for _ in range(10):
        playhead.slower()
    assert playhead.speed == SPEEDS[0] == 0.25
    playhead.advance(2.0)
    assert playhead.time == 5.5
    playhead.speed = 16
    playhead.advance(1.0)
    assert (playhead.time, playhead.playing) == (10.0, False)  # stops at the end
    playhead.toggle()  # at the end: from the start
    assert (playhead.time, playhead.playing) == (0.0, True)
    playhead.step(-1)
    assert (playhead.frame, playhead.playing) == (0, False)
    playhead.step(3)
    assert playhead.frame == 3
    # Two commands done by the same frame: next and previous step through both.
    playhead.seek(0)
    playhead.next_command()
    assert (playhead.command, playhead.frame) == (0, 10)
    playhead.next_command()
    assert (playhead.command, playhead.frame) == (1, 10)
    playhead.previous_command()
    assert (playhead.command, playhead.frame) == (0, 10)


# ----------------------------------------------------------------------------- the window


def test_the_command_list_highlights_the_current_command(
    window: ReplayWindow, recording: Recording
) -> None:
    playhead = window.playhead

    def highlighted() -> list[object]:
        r = RecordingRenderer()
        paint_panel(r, window.panel_rect.size, recording, playhead)
        return [args[0] for args in r.of("text") if args[2] == LIT]

    assert highlighted() == []  # before the first command
    for index, command in enumerate(recording.commands):
        playhead.next_command()
        assert playhead.command == index
        assert highlighted()[:2] == [f"{command.time:.2f}", command.event.message]
    playhead.seek(6.5)
    command = recording.commands[recording.timeline.command_at(playhead.frame)]
    assert command.time <= 6.5
    assert highlighted()[:2] == [f"{command.time:.2f}", command.event.message]
    r = RecordingRenderer()
    paint_panel(r, window.panel_rect.size, recording, playhead)
    assert "stream 50312" in [args[0] for args in r.of("text")]
    assert short_client(CLIENT) == "stream 50312"
    assert short_client("") == "python"
    assert short_client("serial /dev/pts/3") == "serial 3"


def test_the_window_draws_the_trail_where_the_trace_says_the_robot_was(
    window: ReplayWindow, recording: Recording, run_folder: Path
) -> None:
    press(window, pygame.K_END)
    assert window.playhead.at_end
    end = recording.frames[-1].pose
    view = window.canvas.view

    def on_trail(surface: pygame.Surface, row: dict[str, str]) -> bool:
        """Whether the trail's colour is at (or next to) the pixel of the row's position."""
        x, y = (int(v) for v in view.point(float(row["x"]), float(row["y"])))
        near = pygame.surfarray.pixels3d(surface)[x - 1 : x + 2, y - 1 : y + 2]
        return bool(np.all(near == TRAIL_COLOR, axis=-1).any())

    # The robot's own positions, more than 5 in from where it ends (not under the robot).
    rows = [
        row
        for row in trace_rows(run_folder)
        if math.dist((float(row["x"]), float(row["y"])), end[:2]) > 5
    ]
    assert len(rows) > 100
    # Under what each frame draws (the layer the trail is painted in): the whole path.
    assert all(on_trail(window.canvas.static, row) for row in rows)
    # On the screen: all but where the rays of the last frame cross it.
    shown = [on_trail(window.screen, row) for row in rows]
    assert shown.count(True) >= 0.9 * len(rows)
    press(window, pygame.K_t)  # hidden
    assert not any(on_trail(window.screen, row) for row in rows)
    press(window, pygame.K_t)
    assert [on_trail(window.screen, row) for row in rows] == shown
    press(window, pygame.K_HOME)  # back at the start: no trail yet
    assert not any(on_trail(window.screen, row) for row in rows)
    assert "T" in dict(REPLAY_HELP)


def test_a_replay_plays_from_the_start_however_long_the_window_took_to_appear(
    window: ReplayWindow, recording: Recording
) -> None:
    """The issue saw a replay open "at the end, paused": it plays from the start (as
    run_replay starts it), but a first frame that took seconds (the window appearing on a busy
    machine) moved the playhead past a short run's end. A frame now moves it on by
    MAX_FRAME_SECONDS at most, and the end says how to play again."""
    playhead = window.playhead
    assert playhead.time == 0
    playhead.playing = True  # as run_replay opens it
    assert window.frame(30.0)  # the first frame after a 30 s stall
    assert recording.duration > 2 * MAX_FRAME_SECONDS
    assert (playhead.time, playhead.playing) == (MAX_FRAME_SECONDS, True)
    while playhead.playing:
        assert window.frame(30.0)
    assert playhead.at_end

    def state() -> str:
        r = RecordingRenderer()
        paint_timeline(r, window.timeline_rect.size, recording, playhead)
        return str(r.of("text")[0][0])

    assert state().startswith("end: Space")
    press(window, pygame.K_SPACE)  # again, from the start
    assert (playhead.time, playhead.playing) == (0, True)
    assert state().startswith("playing")


def test_keys_and_the_timeline_move_the_playhead(
    window: ReplayWindow, recording: Recording
) -> None:
    playhead = window.playhead
    press(window, pygame.K_SPACE)
    assert playhead.playing
    assert window.frame(0.5)
    assert playhead.time == 0.5
    press(window, pygame.K_PLUS, "+")
    assert playhead.speed == 2
    press(window, pygame.K_MINUS, "-")
    press(window, pygame.K_MINUS, "-")
    assert playhead.speed == 0.5
    press(window, pygame.K_SPACE)
    assert not playhead.playing
    press(window, pygame.K_RIGHT)
    first = recording.commands[playhead.command]
    assert playhead.time == recording.timeline.frame_time(first.frame)
    press(window, pygame.K_RIGHT)
    press(window, pygame.K_LEFT)
    assert recording.commands[playhead.command] is first
    press(window, pygame.K_PERIOD)
    press(window, pygame.K_PERIOD)
    press(window, pygame.K_COMMA)
    assert playhead.frame == first.frame + 1
    press(window, pygame.K_END)
    assert playhead.time == recording.duration
    press(window, pygame.K_HOME)
    assert playhead.time == 0

    bar = TimelineBar(window.timeline_rect.w, recording.duration)
    press(window, pygame.K_SPACE)  # playing while the bar is dragged: it goes on after
    mouse(window, pygame.MOUSEBUTTONDOWN, bar.x(3.0))
    assert playhead.time == pytest.approx(3.0, abs=recording.duration / (bar.right - bar.left))
    assert not playhead.playing
    mouse(window, pygame.MOUSEMOTION, bar.x(7.0))
    mouse(window, pygame.MOUSEBUTTONUP, bar.right + 50)  # past the end of the bar: the end
    assert playhead.time == recording.duration
    assert not playhead.playing  # at the end
    press(window, pygame.K_SPACE)  # at the end: from the start
    assert (playhead.time, playhead.playing) == (0, True)
    mouse(window, pygame.MOUSEBUTTONDOWN, bar.x(6.0))
    mouse(window, pygame.MOUSEBUTTONUP, bar.x(6.0))
    assert playhead.playing
    assert window.frame(0.0)
    hud = RecordingRenderer()
    paint_hud(hud, recording.snapshot(playhead.frame))
    assert f"{recording.frames[playhead.frame].time:.2f} s" in str(hud.of("text")[0][0])
    pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=pygame.K_ESCAPE, unicode="", mod=0))
    assert not window.frame(0.0)


def test_p_saves_a_screenshot_of_the_replay(recording: Recording, tmp_path: Path) -> None:
    surface = pygame.Surface(replay_window_size(recording.scene))
    win = ReplayWindow(recording, surface=surface, save_dir=tmp_path)
    pygame.event.clear()
    win.draw()
    press(win, pygame.K_p)  # saves what the window shows
    (path,) = tmp_path.glob("simmer-*.png")
    saved = pygame.surfarray.array3d(pygame.image.load(str(path)))
    assert np.array_equal(saved, pygame.surfarray.array3d(surface))
    win.close()


# ----------------------------------------------------------------------------- render


def decoded_mp4(path: Path) -> tuple[int, int, int]:
    """Frames, width and height of an MP4, decoded."""
    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        frames = sum(1 for _ in container.decode(stream))
        return frames, stream.width, stream.height


@pytest.mark.slow
def test_simmer_render_cuts_a_clip_of_the_time_asked_for(run_folder: Path, tmp_path: Path) -> None:
    clip = tmp_path / "clips" / "clip.mp4"  # its folder is made
    result = CliRunner().invoke(
        app, ["render", str(run_folder), "--from", "2", "--to", "5.5", "-o", str(clip)]
    )
    assert result.exit_code == 0, result.output
    frames, width, height = decoded_mp4(clip)
    assert abs(frames - 30 * (5.5 - 2)) <= 1
    assert (width % 2, height % 2) == (0, 0)
    assert (width, height) == (1576, 920)
    assert f"wrote {clip} ({frames} frames, {frames / 30:.2f} s)" in result.stdout

    gif = tmp_path / "clip.gif"
    result = CliRunner().invoke(app, ["render", str(run_folder), "--to", "1", "-o", str(gif)])
    assert result.exit_code == 0, result.output
    with Image.open(gif) as image:
        assert abs(image.n_frames - 30) <= 1
        assert image.size == (1576, 920)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("times", "message"),
    [
        (["--from", "5", "--to", "2"], "--to 2 s must be after --from 5 s"),
        (["--from", "-1"], "--from -1 s is not within the run (0 to "),
        (["--from", "999"], "--from 999 s is not within the run (0 to "),
        (["--to", "999"], "--to 999 s is not within the run (0 to "),
        (["--to", "0"], "--to 0 s is not within the run (0 to "),
    ],
)
def test_bad_times_are_refused_in_one_line(
    run_folder: Path, tmp_path: Path, times: list[str], message: str
) -> None:
    clip = tmp_path / "clip.mp4"
    result = CliRunner().invoke(app, ["render", str(run_folder), *times, "-o", str(clip)])
    assert result.exit_code != 0
    assert result.stderr.strip().startswith(message)
    assert len(result.stderr.strip().splitlines()) == 1
    assert not clip.exists()


def test_what_cannot_be_replayed_is_said_in_one_line(tmp_path: Path, copy: Path) -> None:
    def fails(*args: str) -> str:
        result = CliRunner().invoke(app, list(args))
        assert result.exit_code == 1
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1, lines
        return lines[0]

    assert fails("replay", str(tmp_path / "nowhere")).endswith(
        "is not a folder; give a run folder (simmer run --record DIR)"
    )
    (tmp_path / "empty").mkdir()
    assert "is not a run folder: no manifest.json or events.jsonl" in fails(
        "replay", str(tmp_path / "empty")
    )
    assert fails("render", str(copy), "-o", str(tmp_path / "clip.avi")).startswith(
        "a video file ends in .mp4 or .gif"
    )
    (copy / "manifest.json").write_text("{not json")
    assert fails("replay", str(copy)).startswith(f"{copy / 'manifest.json'} is not readable JSON")
    with pytest.raises(ReplayError, match="is not readable JSON"):
        Recording.load(copy)


def test_a_run_cut_short_is_replayed_as_far_as_it_goes(copy: Path) -> None:
    """As ``kill -9`` leaves it: no report, events.jsonl whole up to the kill but for a cut
    last line, trace.csv flushed up to a moment before (its last line cut too)."""
    (copy / "report.json").unlink()
    events = copy / "events.jsonl"
    lines = events.read_text().splitlines(keepends=True)
    drive = max(i for i, line in enumerate(lines) if '"message":"w0-36"' in line)
    events.write_text("".join(lines[: drive + 1]) + lines[drive + 1][:9])  # killed while driving
    trace = copy / "trace.csv"
    lines = trace.read_text().splitlines(keepends=True)
    kept = [line for line in lines[1:] if float(line.split(",")[0]) < 9.0]
    trace.write_text(lines[0] + "".join(kept) + lines[len(kept) + 1][:12])

    recording = Recording.load(copy)
    check = recording.check
    assert check.matches
    assert check.incomplete is not None
    assert check.incomplete.startswith("the run was cut short at ")
    assert f"trace to {float(kept[-1].split(',')[0]):.2f} s" in check.incomplete
    assert check.lines()[-1] == check.incomplete
    assert recording.commands[-1].event.message == "w0-36"
    # Replayed past the last event, to the trace's last whole row (the drive went on).
    last = float(kept[-1].split(",")[0])
    assert recording.commands[-1].time < last - 1
    assert recording.frames[-1].time == pytest.approx(last, abs=1 / FPS)
    result = CliRunner().invoke(app, ["replay", "--check", str(copy)])
    assert result.exit_code == 0
    assert "the run was cut short" in result.stderr


@pytest.mark.slow
def test_replay_without_a_screen_says_what_to_do_instead(run_folder: Path) -> None:
    """A replay nobody can see would play forever: with no screen (the dummy driver here) it
    stops at once and names the commands that work without one."""
    result = CliRunner().invoke(app, ["replay", str(run_folder)])
    assert result.exit_code == 1
    assert "no screen found" in result.output
    assert "simmer render" in result.output
    assert "--check" in result.output
