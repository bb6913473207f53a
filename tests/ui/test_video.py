"""Video without a display (issue 11, item 2) and the off-screen renderer (item 5): frames at a
fixed rate in simulated time, drawn by the window's own code, encoded as they come; checked by
reading the files back with PyAV and Pillow."""

from __future__ import annotations

import math
import os
import re
import resource
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import av
import numpy as np
import pygame
import pytest
from PIL import Image

from simmer import Simulation
from simmer.client import connect
from simmer.geometry import Pose
from simmer.ui import Bridge, Window
from simmer.ui.hud import ALARM, HELP, paint_hud
from simmer.ui.offscreen import OffscreenRenderer, even_size
from simmer.ui.render import RecordingRenderer
from simmer.ui.scene import ScenePainter, View, default_window_size
from simmer.ui.video import VideoRecorder
from simmer.view.frames import FrameClock, check_video_path
from simmer.view.snapshot import StaticScene
from simmer.world.events import StepEvent

from helpers import wait_for

pytestmark = pytest.mark.timeout(180)

FPS = 30
PORTS = ["--port", "0", "--port-rx", "0", "--port-tx", "0"]


def drive_12_inches(path: Path, fps: int = FPS) -> tuple[VideoRecorder, Simulation]:
    """The lab rover drives 12 in forward (2 simulated seconds) into a video at ``path``."""
    sim = Simulation.from_config()
    recorder = VideoRecorder(sim, path, fps=fps)
    assert sim.command("w0-12") == [float("inf")]
    assert sim.run_until_idle()
    recorder.close()
    return recorder, sim


def inside_robot(pose: Pose) -> tuple[float, float]:
    """A world point on the robot's fill (robot frame (1.5, -1.5) at heading 180)."""
    assert pose.heading == pytest.approx(180.0)
    return (pose.x - 1.5, pose.y + 1.5)


def pixel(frame: np.ndarray, view: View, point: tuple[float, float]) -> np.ndarray:
    """The RGB pixel of a world point in an (H, W, 3) frame."""
    px, py = view.point(*point)
    return frame[int(py), int(px)].astype(int)


def off_by(frame: np.ndarray, view: View, point: tuple[float, float], color: object) -> int:
    """How far a world point's pixel is from ``color`` (sum over R, G, B)."""
    return int(np.abs(pixel(frame, view, point) - np.array(color)).sum())


def decoded(path: Path) -> tuple[list[np.ndarray], av.video.stream.VideoStream, float]:
    """Every frame of an MP4 as RGB arrays, its video stream, and its length in seconds."""
    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        frames = [frame.to_ndarray(format="rgb24") for frame in container.decode(stream)]
        assert stream.duration is not None
        assert stream.time_base is not None
        seconds = float(stream.duration * stream.time_base)
    return frames, stream, seconds


@pytest.mark.slow
def test_an_mp4_of_a_headless_run_plays_in_simulated_time(tmp_path: Path) -> None:
    path = tmp_path / "run.mp4"
    recorder, sim = drive_12_inches(path)  # as fast as it goes: the video keeps simulated time
    seconds = sim.time
    assert seconds == pytest.approx(2.0, abs=0.05)
    frames, stream, length = decoded(path)
    expected = round(seconds * FPS)
    assert abs(len(frames) - expected) <= 1
    assert len(frames) == recorder.frames == stream.frames
    assert abs(length - seconds) <= 1 / FPS + 1e-9
    assert stream.codec_context.name == "h264"
    assert stream.codec_context.pix_fmt == "yuv420p"
    assert stream.average_rate == FPS
    size = default_window_size(sim)
    assert (stream.width, stream.height) == size == (1576, 920)
    assert stream.width % 2 == 0
    assert stream.height % 2 == 0
    assert frames[0].shape == (size[1], size[0], 3)
    # The robot moved 12 in: its fill is where it was in the first frame, then where it ended.
    view = View.fit(sim, size)
    fill = ScenePainter(sim).robot_fill  # H.264 moves a flat colour by a few levels at most
    start_point = inside_robot(Pose(6.0, 42.0, 180.0))
    end_point = inside_robot(sim.robot.pose)
    assert sim.robot.pose.y == pytest.approx(30.0)
    assert off_by(frames[0], view, start_point, fill) < 30
    assert off_by(frames[-1], view, end_point, fill) < 30
    assert off_by(frames[0], view, end_point, fill) > 90  # the floor, before the robot came
    assert off_by(frames[-1], view, start_point, fill) > 90
    # Half way (1 s in) the robot is 6 in along.
    assert off_by(frames[FPS], view, inside_robot(Pose(6.0, 36.0, 180.0)), fill) < 30


@pytest.mark.slow
def test_a_gif_of_the_same_run_has_every_frame_and_real_delays(tmp_path: Path) -> None:
    path = tmp_path / "run.gif"
    recorder, sim = drive_12_inches(path)
    size = default_window_size(sim)
    view = View.fit(sim, size)
    fill = tuple(ScenePainter(sim).robot_fill)
    with Image.open(path) as gif:
        assert gif.size == size
        assert gif.n_frames == recorder.frames
        assert abs(gif.n_frames - round(sim.time * FPS)) <= 1
        delays = []
        frames = {}
        for index in range(gif.n_frames):
            gif.seek(index)
            delays.append(gif.info["duration"])
            if index in (0, gif.n_frames - 1):
                frames[index] = np.asarray(gif.convert("RGB"))
    assert set(delays) == {30, 40}  # 3 or 4 centiseconds: 30 frames a second on average
    assert sum(delays) / 1000 == pytest.approx(recorder.seconds, abs=0.01)
    first, last = frames[0], frames[recorder.frames - 1]
    start_point = inside_robot(Pose(6.0, 42.0, 180.0))
    end_point = inside_robot(sim.robot.pose)
    assert tuple(pixel(first, view, start_point)) == fill  # the palette keeps it exact
    assert tuple(pixel(last, view, end_point)) == fill
    assert tuple(pixel(first, view, end_point)) != fill
    assert tuple(pixel(last, view, start_point)) != fill


def test_frames_are_due_in_simulated_time_across_resets() -> None:
    sim = Simulation.from_config()
    clock = FrameClock(10, sim.time)
    due: list[int] = []
    sim.add_observer(lambda event: due.append(clock.due(event)))
    clock.frames = 1  # the first frame, at the start
    sim.step(30)  # 0.5 s: frames at 0.1, 0.2, 0.3, 0.4, 0.5
    assert (clock.frames, sum(due)) == (6, 5)
    assert due[:7] == [0, 0, 0, 0, 0, 1, 0]  # the sixth step (0.1 s) reaches the first one
    sim.reset()  # the simulation's clock restarts; the video's goes on
    assert sim.time == 0.0
    sim.step(30)
    assert clock.frames == 11
    sim.command("u0")  # other events are no frame times
    assert due[-1] == 0
    fast = FrameClock(120, sim.time)  # more frames than steps: each step shows twice
    fast.frames = 1
    steps = [StepEvent(sim.time + n * sim.dt, sim.robot.pose) for n in (1, 2, 3)]
    assert [fast.due(step) for step in steps] == [2, 2, 2]


def test_the_window_and_the_video_draw_the_same_pixels() -> None:
    sim = Simulation.from_config()
    sim.command("w0-12")
    sim.step(45)
    size = default_window_size(sim)
    bridge = Bridge(sim)
    window = Window(bridge, surface=pygame.Surface(size))
    window.draw()
    offscreen = OffscreenRenderer(StaticScene.of(sim), pygame.Surface(size, 0, 32))
    offscreen.draw(bridge.latest)
    assert np.array_equal(
        pygame.surfarray.array3d(window.screen), pygame.surfarray.array3d(offscreen.surface)
    )
    window.close()
    bridge.close()


@pytest.mark.slow
def test_a_video_is_made_without_any_display(tmp_path: Path) -> None:
    code = (
        "import sys; from simmer import Simulation; from simmer.ui.video import VideoRecorder\n"
        "sim = Simulation.from_config()\n"
        "with VideoRecorder(sim, sys.argv[1], fps=10):\n"
        "    sim.step(30)\n"
        "import pygame; print(pygame.display.get_init())\n"
    )
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["SDL_VIDEODRIVER"] = "no-such-driver"  # opening a display would fail
    path = tmp_path / "no_display.mp4"
    command = [sys.executable, "-c", code, str(path)]
    done = subprocess.run(command, check=False, capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().endswith("False")
    frames, _, length = decoded(path)
    assert len(frames) == 6
    assert length == pytest.approx(0.6)


@pytest.mark.slow
def test_memory_does_not_grow_with_the_length_of_the_video(tmp_path: Path) -> None:
    sim = Simulation.from_config()
    path = tmp_path / "long.mp4"
    sim.command("r0-3600")  # turning on the spot: every frame differs
    with VideoRecorder(sim, path) as recorder:
        (writing,) = tmp_path.glob(".long.mp4.*")  # put at its name when closed
        sim.step(5 * 60)
        early = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        written = writing.stat().st_size
        sim.step(20 * 60)
        late = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        assert writing.stat().st_size > written > 0  # encoded as they come, not at the end
    assert path.stat().st_size > written
    assert not writing.exists()
    assert recorder.frames == 25 * FPS + 1
    assert (late - early) * 1024 < 40e6  # 600 more frames would hold 1.3 GB of pixels


def test_bad_video_paths_are_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"\.mp4 or \.gif"):
        check_video_path(tmp_path / "run.avi")
    with pytest.raises(ValueError, match="1 to 50"):
        check_video_path(tmp_path / "run.gif", fps=60)
    assert check_video_path(tmp_path / "run.MP4") == tmp_path / "run.MP4"
    assert even_size((1577, 921)) == (1576, 920)
    sim = Simulation.from_config()
    with pytest.raises(OSError, match="No such file"):
        VideoRecorder(sim, tmp_path / "missing" / "run.mp4")
    assert sim.observers == []


# ----------------------------------------------------------------------------- window keys


@pytest.fixture
def window(tmp_path: Path) -> Iterator[Window]:
    """A window (dummy driver) on the lab maze that saves its files in ``tmp_path``."""
    bridge = Bridge(Simulation.from_config())
    win = Window(bridge, save_dir=tmp_path)
    pygame.event.clear()
    yield win
    win.close()
    bridge.close()


def press(win: Window, key: int) -> None:
    """Press a key; the window handles it, the simulation side applies what it posted."""
    pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=key, unicode="", mod=0, scancode=0))
    assert win.frame()
    win.bridge.sync()


@pytest.mark.slow
def test_v_starts_and_stops_a_video_and_the_hud_says_so(
    window: Window, tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    sim = window.bridge.sim
    caplog.set_level("INFO", logger="simmer.ui")
    press(window, pygame.K_v)
    recording = window.bridge.latest.recording
    assert recording is not None
    assert recording.startswith("simmer-")
    assert recording.endswith(".mp4")
    hud = RecordingRenderer()
    paint_hud(hud, window.bridge.latest)
    assert ("REC", (28, 95), ALARM, 18, False) in hud.of("text")
    path = tmp_path / recording
    said = f"recording the video {path} (V stops it)"
    assert said in [args[0] for args in hud.of("text")]  # the file's name, in the HUD
    sim.step(30)  # half a simulated second
    press(window, pygame.K_v)
    assert window.bridge.latest.recording is None
    assert window.bridge.latest.notice == f"saved the video {path} (0.5 s)"
    frames, stream, length = decoded(path)
    assert len(frames) == 16
    assert (stream.width, stream.height) == (1576, 920)
    assert length == pytest.approx(16 / FPS)
    assert f"saved the video {path}" in caplog.text
    assert "V" in dict(HELP)


@pytest.mark.slow
def test_closing_the_window_finishes_its_video(tmp_path: Path) -> None:
    bridge = Bridge(Simulation.from_config())
    win = Window(bridge, save_dir=tmp_path)
    pygame.event.clear()
    press(win, pygame.K_v)
    bridge.sim.step(10)
    win.close()
    bridge.close()
    (path,) = tmp_path.glob("simmer-*.mp4")
    assert len(decoded(path)[0]) == 1 + 5
    assert bridge.sim.observers == []


def test_p_saves_a_screenshot_of_the_window(
    window: Window, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(time, "strftime", lambda _: "simmer-now")
    window.draw()
    shown = pygame.surfarray.array3d(window.screen)
    press(window, pygame.K_p)
    press(window, pygame.K_p)  # a second one in the same second gets its own name
    first, second = tmp_path / "simmer-now.png", tmp_path / "simmer-now-2.png"
    assert sorted(tmp_path.iterdir()) == [second, first]
    saved = pygame.surfarray.array3d(pygame.image.load(str(first)))
    assert np.array_equal(saved, shown)
    assert window.bridge.latest.notice == f"saved the screenshot {second}"  # named in the HUD
    assert "P" in dict(HELP)


def test_a_screenshot_is_not_saved_through_a_link_at_its_name(
    window: Window, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(time, "strftime", lambda _: "simmer-now")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (tmp_path / "simmer-now.png").symlink_to(elsewhere / "written.png")  # pointing nowhere yet
    press(window, pygame.K_p)
    assert list(elsewhere.iterdir()) == []
    assert (tmp_path / "simmer-now-2.png").is_file()
    assert window.bridge.latest.notice == f"saved the screenshot {tmp_path / 'simmer-now-2.png'}"


# ----------------------------------------------------------------------------- simmer run


def simmer_run(*args: str) -> subprocess.CompletedProcess[str]:
    """``simmer run --headless`` on free ports, with these arguments."""
    command = [sys.executable, "-m", "simmer", "run", "--headless", *PORTS, *args]
    return subprocess.run(command, check=False, capture_output=True, text=True, timeout=60)


@pytest.mark.slow
def test_simmer_run_video_writes_a_decodable_file(tmp_path: Path) -> None:
    path = tmp_path / "out.mp4"
    done = simmer_run("--seconds", "1", "--video", str(path))
    assert done.returncode == 0, done.stderr
    assert f"video: {path} (31 frames, 1.03 s)" in done.stdout
    frames, stream, length = decoded(path)
    assert len(frames) == 31
    assert (stream.width, stream.height) == (1576, 920)
    assert length == pytest.approx(31 / FPS)


@pytest.mark.slow
def test_simmer_run_refuses_a_video_it_cannot_write(tmp_path: Path) -> None:
    wrong = simmer_run("--seconds", "1", "--video", str(tmp_path / "out.avi"))
    assert wrong.returncode == 2
    assert ".mp4 or .gif" in wrong.stderr
    (tmp_path / "a-file").write_text("in the way")
    blocked = simmer_run("--seconds", "1", "--video", str(tmp_path / "a-file" / "out.mp4"))
    assert blocked.returncode == 1
    assert "no writable folder" in blocked.stderr


@pytest.mark.slow
def test_simmer_run_video_makes_its_folder(tmp_path: Path) -> None:
    path = tmp_path / "runs" / "task1.mp4"  # as the Lab 1 page has it, in a new folder
    done = simmer_run("--seconds", "0.2", "--video", str(path))
    assert done.returncode == 0, done.stderr
    assert path.stat().st_size > 0


@pytest.mark.slow
@pytest.mark.usefixtures("ctrl_c")
def test_ctrl_c_finishes_the_video(tmp_path: Path) -> None:
    path = tmp_path / "stopped.mp4"
    command = [sys.executable, "-m", "simmer", "run", "--headless", "--video", str(path), *PORTS]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, text=True)
    try:
        assert process.stdout is not None
        for line in process.stdout:
            if line.startswith("persistent TCP"):
                port = int(line.split(" port ")[1].split()[0])
            if line.startswith("running headless"):
                break
        with connect(port=port) as robot:  # half a simulated second or more: 3 in at 6 in/s
            assert robot.send("w0-3") == [math.inf]
            wait_for(lambda: robot.send("w0-0") == [math.inf], "the drive to end")
        process.send_signal(signal.SIGINT)
        output, _ = process.communicate(timeout=30)
    finally:
        process.kill()
    assert process.returncode == 0
    assert "stopped" in output
    match = re.search(r"outcome after ([0-9.]+) s", output)
    assert match is not None
    simulated = float(match.group(1))
    frames, _, length = decoded(path)
    assert abs(len(frames) - (int(simulated * FPS + 1e-6) + 1)) <= 1  # Ctrl-C may cut one
    assert abs(length - simulated) <= 1 / FPS + 0.005  # the time is said to 0.01 s


def test_a_video_of_a_run_without_a_window_shows_no_keys_and_no_speed(tmp_path: Path) -> None:
    """A headless run's video showed "speed max" and key caps nobody could press."""
    frames = {}
    for window in (True, False):
        sim = Simulation.from_config()
        sim.manual_keys = frozenset("w")  # a key held: lit in a window's frame
        with VideoRecorder(sim, tmp_path / f"{window}.gif", fps=10, window=window) as recorder:
            sim.step(12)
        frames[window] = pygame.surfarray.array3d(recorder.canvas.surface)
        hud = RecordingRenderer()
        paint_hud(hud, recorder.maker.snapshot(recorder.controls), keys=window)
        texts = [str(call[0]) for call in hud.of("text")]
        time_line = next(text for text in texts if text.startswith(f"{sim.time:.2f} s"))
        assert ("speed" in time_line) is window, time_line
    caps = (slice(40, 150), slice(8, 100))  # where the window's key caps and help hint are
    panel = frames[False][caps]
    assert (panel == panel[0, 0]).all()  # the bare panel: no cap, no glyph
    assert not (frames[True][caps] == frames[True][caps][0, 0]).all()


def test_a_belief_shown_after_the_last_frame_is_the_videos_last_frame(tmp_path: Path) -> None:
    """The localization example's video ended on the estimate before its final move: a belief
    shown after the last frame (the program then exits) is one frame more at the end."""
    from simmer.client import Client
    from simmer.runner import LocalLink
    from simmer.ui.belief import ESTIMATE_COLOR

    sim = Simulation.from_config()
    robot = Client(LocalLink(sim), lockstep=True)
    with VideoRecorder(sim, tmp_path / "run.gif", fps=10, window=False) as recorder:
        robot.show(pose=(6.0, 42.0, 180.0))  # before the move
        robot.drive("w0", 12)
        robot.wait_idle()
        before = recorder.frames
        robot.show(pose=(30.0, 6.0, 180.0))  # after it (away from the robot, drawn over it)
    assert recorder.frames == before + 1
    last = pygame.surfarray.array3d(recorder.canvas.surface).transpose(1, 0, 2)
    view = recorder.canvas.view
    ring = [(30.0 + 0.6 * math.cos(a), 6.0 + 0.6 * math.sin(a)) for a in np.linspace(0, 6, 12)]
    assert min(off_by(last, view, point, ESTIMATE_COLOR) for point in ring) < 30
    with VideoRecorder(sim, tmp_path / "still.gif", fps=10, window=False) as still:
        sim.step(3)
        frames = still.frames
    assert still.frames == frames  # nothing shown since: no frame added
