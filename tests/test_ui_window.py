"""The window driven by real pygame events (dummy video driver; no wall-clock timing)."""

from __future__ import annotations

import logging
import math
import os
import threading
from collections.abc import Iterator

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

import pygame
import pytest

from simmer import Simulation
from simmer.client import connect
from simmer.runner import Runner
from simmer.transport import Link
from simmer.ui import Window, run_window
from simmer.ui.hud import Stopwatch
from simmer.ui.window import LocalControls, faster, slower


@pytest.fixture
def window() -> Iterator[Window]:
    """A real (dummy-driver) window on the built-in default: lab rover at (6, 42), heading 180."""
    win = Window(Simulation.from_config())
    pygame.event.clear()
    yield win
    win.close()


def key(code: int, down: bool = True, unicode: str = "") -> None:
    """Post a key press or release."""
    kind = pygame.KEYDOWN if down else pygame.KEYUP
    pygame.event.post(pygame.event.Event(kind, key=code, unicode=unicode, mod=0, scancode=0))


def mouse(kind: int, win: Window, x: float, y: float, button: int = 1) -> None:
    """Post a mouse event at a world point (inches)."""
    px, py = win.view.point(x, y)
    pos = (round(px), round(py))
    if kind == pygame.MOUSEMOTION:
        buttons = (1, 0, 0) if button == 1 else (0, 0, 1)
        event = pygame.event.Event(kind, pos=pos, rel=(0, 0), buttons=buttons)
    else:
        event = pygame.event.Event(kind, pos=pos, button=button)
    pygame.event.post(event)


def test_holding_w_for_one_second_drives_six_inches(window: Window) -> None:
    sim = window.sim
    start = sim.robot.pose
    key(pygame.K_w)
    assert window.frame()
    assert window.held == {"w"}
    sim.step(round(1.0 / sim.dt))
    pose = sim.robot.pose
    assert math.hypot(pose.x - start.x, pose.y - start.y) == pytest.approx(6.0)
    assert pose.y == pytest.approx(start.y - 6.0)  # heading 180: forward is up the screen
    key(pygame.K_w, down=False)
    window.frame()
    sim.step(10)
    assert sim.robot.pose == pose  # released: no more motion


def test_turn_keys(window: Window) -> None:
    sim = window.sim
    key(pygame.K_d)
    window.frame()
    sim.step(round(0.5 / sim.dt))
    assert sim.robot.pose.heading == pytest.approx(240.0)  # 120 deg/s clockwise


def test_r_mid_drive_restores_the_start_and_clears_the_drive(window: Window) -> None:
    sim = window.sim
    start = sim.robot.pose
    sim.command("w0-24")
    sim.step(30)
    key(pygame.K_q)
    window.frame()
    sim.step(5)
    assert sim.robot.pose != start
    assert window.stopwatch.start is not None
    key(pygame.K_r, unicode="r")
    window.frame()
    assert sim.robot.pose == start
    assert sim.time == 0.0
    assert not sim.robot.any_drive_moving
    assert not sim.manual_keys
    assert not window.held
    assert window.stopwatch.elapsed() is None
    sim.step(30)
    assert sim.robot.pose == start


def test_space_pauses_and_period_steps(window: Window) -> None:
    key(pygame.K_SPACE, unicode=" ")
    window.frame()
    assert window.local.paused
    key(pygame.K_PERIOD, unicode=".")
    window.frame()
    assert window.sim.frame == 1
    key(pygame.K_SPACE, unicode=" ")
    window.frame()
    assert not window.local.paused
    key(pygame.K_PERIOD, unicode=".")
    window.frame()
    assert window.sim.frame == 1  # '.' only steps while paused


def test_keys_act_on_the_runner(window: Window) -> None:
    runner = Runner(window.sim, speed=1.0)
    key(pygame.K_SPACE, unicode=" ")
    key(pygame.K_EQUALS, unicode="+")
    assert window.frame(runner)
    assert runner.paused
    assert runner.speed == 2.0
    assert not window.local.paused
    key(pygame.K_MINUS, unicode="-")
    key(pygame.K_MINUS, unicode="-")
    window.frame(runner)
    assert runner.speed == 0.5


def test_window_as_the_runner_frame_hook(window: Window) -> None:
    sim = window.sim
    start = sim.robot.pose
    key(pygame.K_w)
    Runner(sim, speed=None).run(on_frame=window.frame, until=1.0)
    assert sim.time == pytest.approx(1.0)
    assert sim.robot.pose.y == pytest.approx(start.y - 6.0)


def test_escape_and_close_quit(window: Window) -> None:
    assert window.frame()
    key(pygame.K_ESCAPE)
    assert not window.frame()
    pygame.event.post(pygame.event.Event(pygame.QUIT))
    assert not window.frame()


def test_h_toggles_help(window: Window) -> None:
    key(pygame.K_h, unicode="h")
    window.frame()
    assert window.show_help
    key(pygame.K_h, unicode="h")
    window.frame()
    assert not window.show_help


def test_drag_moves_the_robot(window: Window) -> None:
    sim = window.sim
    mouse(pygame.MOUSEBUTTONDOWN, window, 6, 42)
    mouse(pygame.MOUSEMOTION, window, 18, 42)
    mouse(pygame.MOUSEBUTTONUP, window, 18, 42)
    window.frame()
    pose = sim.robot.pose
    assert pose.x == pytest.approx(18, abs=0.1)
    assert pose.y == pytest.approx(42, abs=0.1)
    assert pose.heading == 180.0
    assert window.drag is None


def test_dragging_onto_a_wall_is_refused(window: Window) -> None:
    sim = window.sim
    start = sim.robot.pose
    mouse(pygame.MOUSEBUTTONDOWN, window, 6, 42)
    mouse(pygame.MOUSEMOTION, window, 18, 30)  # the solid cell at row 2, column 1
    window.frame()
    assert sim.robot.pose == start
    assert window.ghost is not None  # the refused place is shown as a red outline
    mouse(pygame.MOUSEBUTTONUP, window, 18, 30)
    window.frame()
    assert sim.robot.pose == start
    assert window.ghost is None


def test_right_drag_turns_the_robot(window: Window) -> None:
    sim = window.sim
    mouse(pygame.MOUSEBUTTONDOWN, window, 6, 40, button=3)
    mouse(pygame.MOUSEMOTION, window, 8, 42, button=3)
    mouse(pygame.MOUSEBUTTONUP, window, 8, 42, button=3)
    window.frame()
    pose = sim.robot.pose
    assert (pose.x, pose.y) == (6.0, 42.0)
    assert pose.heading == pytest.approx(270.0, abs=1.0)


def test_click_off_the_robot_does_nothing(window: Window) -> None:
    start = window.sim.robot.pose
    mouse(pygame.MOUSEBUTTONDOWN, window, 30, 42)
    mouse(pygame.MOUSEMOTION, window, 40, 42)
    window.frame()
    assert window.drag is None
    assert window.sim.robot.pose == start


def test_resize_rescales_the_scene(window: Window) -> None:
    before = window.view.ppi
    pygame.display.set_mode((800, 500), pygame.RESIZABLE)
    pygame.event.post(pygame.event.Event(pygame.VIDEORESIZE, size=(800, 500), w=800, h=500))
    window.frame()
    assert window.screen.get_size() == (800, 500)
    assert window.view.ppi < before
    left, _ = window.view.point(0, 0)
    right, bottom = window.view.point(window.sim.maze.width, window.sim.maze.height)
    assert 0 < left < right <= 800
    assert bottom <= 500


def test_speed_steps() -> None:
    assert faster(1.0) == 2.0
    assert slower(1.0) == 0.5
    assert faster(32.0) == 32.0
    assert slower(0.125) == 0.125
    assert faster(None) is None
    assert slower(None) == 32.0
    assert faster(3.0) == 4.0


def test_local_controls_step_once() -> None:
    sim = Simulation.from_config()
    LocalControls(sim).step_once()
    assert sim.frame == 1


def test_stopwatch_times_the_trip_to_the_block(caplog: pytest.LogCaptureFixture) -> None:
    sim = Simulation.from_config()
    watch = Stopwatch(sim)
    sim.add_observer(watch)
    sim.step(30)
    assert watch.elapsed() is None  # not moved yet
    block = sim.block
    # Just out of reach below the block, facing it (heading 180: up; the nose is 4 in ahead).
    assert sim.place_robot(block.x, block.y + block.size / 2 + 1.2 + 4, 180)
    watch.reset()
    sim.command("w0-2")  # closes the 1.2 in gap to within 1 in, then stops 0.8 in short
    with caplog.at_level(logging.INFO, logger="simmer.ui"):
        sim.run_until_idle()
    assert watch.start == pytest.approx(0.5)  # the start of the first step that moved
    elapsed = watch.elapsed()
    assert elapsed == pytest.approx(2 * sim.dt)  # 0.1 in per step: two steps close 0.2 in
    assert "reached the block" in caplog.text
    sim.step(10)
    assert watch.elapsed() == elapsed  # frozen once stopped
    sim.reset()
    assert watch.elapsed() is None


def test_run_window_quits_on_escape() -> None:
    sim = Simulation.from_config()
    pygame.display.init()
    key(pygame.K_ESCAPE)
    run_window(Runner(sim, speed=None))
    assert not sim.observers  # the window let go of the simulation


def test_window_and_control_programs_share_one_loop() -> None:
    sim = Simulation.from_config()
    runner = Runner(sim, speed=1.0)
    window = Window(sim)
    stop, answered, seen = threading.Event(), threading.Event(), threading.Event()
    replies: list[list[float]] = []
    clients_seen: list[str] = []

    def program(port: int) -> None:
        with connect(port=port) as client:
            replies.append(client.send("u0,u1"))
            answered.set()
            seen.wait(10)
        stop.set()

    def on_frame(loop: Runner) -> bool:
        if answered.is_set() and loop.clients and not seen.is_set():
            clients_seen.extend(loop.clients)
            seen.set()
        return window.frame(loop)

    link = Link(runner.bus, sim.config.settings, port_rx=0, port_tx=0, stream_port=0)
    with link:
        thread = threading.Thread(target=program, args=(link.stream.port,))
        thread.start()
        runner.run(on_frame=on_frame, stop_event=stop, until=60.0)
        thread.join()
    runner.bus.close()
    window.close()
    assert replies == [[pytest.approx(39.5), pytest.approx(3.5)]]
    assert window.commands.entries[-1].message == "u0,u1"
    assert clients_seen
