"""The window driven by real pygame events (dummy video driver; no wall-clock timing).

Most tests run both sides in this thread for determinism: post events, ``tick`` (the window
handles them and posts actions, the bridge applies them and publishes a snapshot, the window
draws it), step the simulation. The last tests run the real two threads.
"""

from __future__ import annotations

import json
import logging
import math
import os
import threading
from collections.abc import Callable, Iterator
from pathlib import Path

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

import os

import numpy as np
import pygame
import pytest

from simmer import Simulation
from simmer.client import connect
from simmer.colors import TRAIL_COLOR
from simmer.devices.base import Segment
from simmer.geometry import Pose
from simmer.localize.messages import Localization
from simmer.options import RunOptions
from simmer.runner import Runner
from simmer.serve import serve
from simmer.transport import Transports
from simmer.ui import Bridge, RecordingRenderer, Window, run_window
from simmer.ui.belief import BELIEF_COLOR, ESTIMATE_COLOR
from simmer.ui.bridge import Controls, PlaceRobot
from simmer.ui.hud import ALARM, HELP, LIT, TEXT, paint_hud
from simmer.ui.scene import default_window_size
from simmer.ui.window import LocalControls, faster, slower
from simmer.view.snapshot import Snapshot
from simmer.world.outcome import Outcome, OutcomeReport

from helpers import wait_for

TIMEOUT = 30.0
"""Generous seconds for anything another thread must do (never a speed assertion)."""


@pytest.fixture
def window() -> Iterator[Window]:
    """A real (dummy-driver) window on the built-in default: lab rover at (6, 42), heading 180."""
    bridge = Bridge(Simulation.from_config())
    win = Window(bridge)
    pygame.event.clear()
    yield win
    win.close()
    bridge.close()


def tick(win: Window, controls: Controls | None = None) -> bool:
    """One frame, both sides in this thread: events -> actions -> applied -> snapshot -> drawn."""
    keep = win.frame()
    keep = win.bridge.sync(controls) and keep
    win.draw()
    return keep


def shown_outcome(win: Window) -> OutcomeReport:
    """The outcome in the window's latest snapshot (what the HUD draws)."""
    outcome = win.bridge.latest.outcome
    assert outcome is not None
    return outcome


def hud_texts(win: Window) -> dict[str, object]:
    """Each text the HUD draws for the window's latest snapshot, with its colour."""
    r = RecordingRenderer()
    paint_hud(r, win.bridge.latest)
    return {str(args[0]): args[2] for args in r.of("text")}


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
    sim = window.bridge.sim
    start = sim.robot.pose
    key(pygame.K_w)
    assert tick(window)
    assert window.held == {"w"}
    sim.step(round(1.0 / sim.dt))
    pose = sim.robot.pose
    assert math.hypot(pose.x - start.x, pose.y - start.y) == pytest.approx(6.0)
    assert pose.y == pytest.approx(start.y - 6.0)  # heading 180: forward is up the screen
    key(pygame.K_w, down=False)
    tick(window)
    sim.step(10)
    assert sim.robot.pose == pose  # released: no more motion


def test_turn_keys(window: Window) -> None:
    sim = window.bridge.sim
    key(pygame.K_d)
    tick(window)
    sim.step(round(0.5 / sim.dt))
    assert sim.robot.pose.heading == pytest.approx(240.0)  # 120 deg/s clockwise


def test_r_mid_drive_restores_the_start_and_clears_the_drive(window: Window) -> None:
    sim = window.bridge.sim
    start = sim.robot.pose
    sim.command("w0-24")
    sim.step(30)
    key(pygame.K_q)
    tick(window)
    sim.step(5)
    assert sim.robot.pose != start
    tick(window)
    assert shown_outcome(window).first_motion == 0.0
    assert shown_outcome(window).path_length > 0
    key(pygame.K_r, unicode="r")
    tick(window)
    assert sim.robot.pose == start
    assert sim.time == 0.0
    assert not sim.robot.any_drive_moving
    assert not sim.manual_keys
    assert not window.held
    assert shown_outcome(window) == Outcome(Simulation.from_config()).report()  # all cleared
    assert "starts when the robot first moves" in hud_texts(window)
    sim.step(30)
    assert sim.robot.pose == start


def test_space_pauses_and_period_steps(window: Window) -> None:
    key(pygame.K_SPACE, unicode=" ")
    tick(window)
    assert window.bridge.local.paused
    key(pygame.K_PERIOD, unicode=".")
    tick(window)
    assert window.bridge.sim.steps == 1
    key(pygame.K_SPACE, unicode=" ")
    tick(window)
    assert not window.bridge.local.paused
    key(pygame.K_PERIOD, unicode=".")
    tick(window)
    assert window.bridge.sim.steps == 1  # '.' only steps while paused


def test_keys_act_on_the_runner(window: Window) -> None:
    runner = Runner(window.bridge.sim, speed=1.0)
    key(pygame.K_SPACE, unicode=" ")
    key(pygame.K_EQUALS, unicode="+")
    assert tick(window, runner)
    assert runner.paused
    assert runner.speed == 2.0
    assert not window.bridge.local.paused
    key(pygame.K_MINUS, unicode="-")
    key(pygame.K_MINUS, unicode="-")
    tick(window, runner)
    assert runner.speed == 0.5


def test_the_window_only_posts_actions(window: Window) -> None:
    sim = window.bridge.sim
    key(pygame.K_w)
    key(pygame.K_SPACE, unicode=" ")
    assert window.frame()
    assert not sim.manual_keys  # nothing reached the simulation yet: it is another thread's
    assert not window.bridge.local.paused
    assert not window.bridge.latest.held
    assert window.bridge.sync()
    assert sim.manual_keys == {"w"}
    assert window.bridge.local.paused
    snap = window.bridge.latest
    assert snap.held == {"w"}
    assert snap.paused
    assert not snap.robot.flags.writeable  # snapshots are immutable
    window.draw()
    assert window.bridge.latest is snap


def test_window_and_runner_in_two_threads(window: Window) -> None:
    sim = window.bridge.sim
    start = sim.robot.pose
    key(pygame.K_w)
    assert window.frame()  # posted before the simulation thread starts: applied at its 1st sync
    window.run(Runner(sim, speed=None), until=1.0)
    assert sim.time == pytest.approx(1.0)
    assert sim.robot.pose.y == pytest.approx(start.y - 6.0)
    assert window.bridge.latest.time == pytest.approx(sim.time, abs=sim.dt)


def test_window_rejects_another_simulation(window: Window) -> None:
    with pytest.raises(ValueError, match="another simulation"):
        window.run(Runner(Simulation.from_config()), until=0.1)


def test_escape_and_close_quit(window: Window) -> None:
    assert tick(window)
    key(pygame.K_ESCAPE)
    assert not tick(window)
    pygame.event.post(pygame.event.Event(pygame.QUIT))
    assert not tick(window)


def test_h_toggles_help(window: Window) -> None:
    key(pygame.K_h, unicode="h")
    tick(window)
    assert window.show_help
    key(pygame.K_h, unicode="h")
    tick(window)
    assert not window.show_help


def test_the_path_so_far_is_drawn_over_the_rays_of_a_short_drive(window: Window) -> None:
    """Straight back along a short drive, the rear sensor's ray covered the path (the test
    below turns first so that none does): the path is painted over the rays now."""
    sim = window.bridge.sim
    sim.command("w0-6")  # from (6, 42) up to (6, 36): the rear ray looks back along it
    # (the robot covers the path up to y = 40)
    assert sim.run_until_idle()
    tick(window)
    pixels = [window.view.point(6.0, y) for y in np.arange(41.0, 42.5, 0.5)]
    colours = [tuple(window.screen.get_at((round(x), round(y))))[:3] for x, y in pixels]
    assert all(colour == TRAIL_COLOR for colour in colours), colours
    shapes = Snapshot.of(sim).shapes
    assert any(  # a ray does lie along it
        isinstance(s, Segment) and abs(s.start.x - 6) < 0.5 and abs(s.end.x - 6) < 0.5
        and s.end.y > 42 for s in shapes
    )  # fmt: skip


def test_t_shows_and_hides_the_path_driven_so_far(window: Window) -> None:
    sim = window.bridge.sim
    sim.command("w0-12")  # from (6, 42) up to (6, 30)
    assert sim.run_until_idle()
    sim.command("r0-45")  # so that no sensor looks back along the path
    assert sim.run_until_idle()
    tick(window)
    screen = window.screen

    def trail_shown() -> list[bool]:
        """Whether the trail's colour is at each inch the robot drove and left behind."""
        pixels = [window.view.point(6.0, y) for y in range(35, 43)]
        return [tuple(screen.get_at((round(x), round(y))))[:3] == TRAIL_COLOR for x, y in pixels]

    assert all(trail_shown())
    key(pygame.K_t, unicode="t")
    tick(window)
    assert not window.canvas.show_trail
    assert not any(trail_shown())
    key(pygame.K_t, unicode="t")
    tick(window)
    assert all(trail_shown())
    window.reset()  # a new run: a new trail
    tick(window)
    assert not any(trail_shown())
    assert "T" in dict(HELP)


@pytest.mark.slow
def test_b_shows_and_hides_the_programs_belief(window: Window) -> None:
    sim = window.bridge.sim
    cloud = [[54.0 + i % 7, 18.0 + i % 5, 10.0 * i, 1.0] for i in range(200)]
    belief = json.dumps({"particles": cloud, "pose": [54.0, 18.0, 90.0], "ellipse": [4, 2, 0]})
    Localization(sim).answer(f"%show {belief}", "test")  # as the loop answers a program's show
    tick(window)

    def shown(color: tuple[int, int, int]) -> int:
        """Pixels of ``color`` on the screen."""
        pixels = pygame.surfarray.pixels3d(window.screen)
        return int(np.all(pixels == color, axis=-1).sum())

    assert shown(BELIEF_COLOR) > 50
    assert shown(ESTIMATE_COLOR) > 50
    key(pygame.K_b, unicode="b")
    tick(window)
    assert not window.canvas.show_belief
    assert shown(BELIEF_COLOR) == shown(ESTIMATE_COLOR) == 0
    key(pygame.K_b, unicode="b")
    tick(window)
    assert shown(ESTIMATE_COLOR) > 50
    window.reset()  # a new run: no belief yet
    tick(window)
    assert shown(ESTIMATE_COLOR) == 0
    assert "B" in dict(HELP)


@pytest.mark.slow
def test_drag_moves_the_robot(window: Window) -> None:
    sim = window.bridge.sim
    mouse(pygame.MOUSEBUTTONDOWN, window, 6, 42)
    mouse(pygame.MOUSEMOTION, window, 18, 42)
    mouse(pygame.MOUSEBUTTONUP, window, 18, 42)
    tick(window)
    pose = sim.robot.pose
    assert pose.x == pytest.approx(18, abs=0.1)
    assert pose.y == pytest.approx(42, abs=0.1)
    assert pose.heading == 180.0
    assert window.drag is None


def test_drag_restarts_the_stopwatch_and_adds_no_path(window: Window) -> None:
    sim = window.bridge.sim
    sim.command("w0-3")
    sim.run_until_idle()
    sim.step(10)
    tick(window)
    assert shown_outcome(window).first_motion == 0.0
    mouse(pygame.MOUSEBUTTONDOWN, window, 6, 39)
    mouse(pygame.MOUSEMOTION, window, 12, 42)
    tick(window)
    sim.step(5)  # the simulation steps between the drag's moves
    mouse(pygame.MOUSEMOTION, window, 18, 42)
    mouse(pygame.MOUSEBUTTONUP, window, 18, 42)
    tick(window)
    sim.step(5)
    tick(window)
    assert (sim.robot.pose.x, sim.robot.pose.y) == pytest.approx((18, 42), abs=0.1)
    outcome = shown_outcome(window)
    assert outcome.first_motion is None  # starts again at the next motion
    assert outcome.path_length == pytest.approx(3.0)  # the hand's move is not the robot's path
    assert outcome.messages == 1
    moved_at = sim.time
    sim.command("w0-1")
    sim.run_until_idle()
    tick(window)
    assert shown_outcome(window).first_motion == pytest.approx(moved_at)
    assert shown_outcome(window).path_length == pytest.approx(4.0)


def test_the_window_shows_the_outcome_a_served_run_reports() -> None:
    sim = Simulation.from_config()
    outcome = Outcome.attach(sim)  # as serve() does before it opens the window
    bridge = Bridge(sim)
    assert bridge.outcome is outcome
    assert sim.observers.count(outcome) == 1  # the figures are counted once
    sim.command("w0-2")
    sim.run_until_idle()
    bridge.sync()
    assert bridge.latest.outcome == outcome.report()
    bridge.close()
    assert sim.observers == [outcome]  # the run's outcome outlives the window
    alone = Simulation.from_config()
    own = Bridge(alone)
    assert isinstance(own.outcome, Outcome)
    assert own.outcome in alone.observers
    own.close()
    assert not alone.observers


@pytest.mark.slow
def test_dragging_onto_a_wall_is_refused(window: Window) -> None:
    sim = window.bridge.sim
    start = sim.robot.pose
    mouse(pygame.MOUSEBUTTONDOWN, window, 6, 42)
    mouse(pygame.MOUSEMOTION, window, 18, 30)  # the solid cell at row 2, column 1
    tick(window)
    assert sim.robot.pose == start
    ghost = window.bridge.latest.ghost
    assert ghost is not None  # the refused place is shown as a red outline
    expected = sim.robot.polygon(Pose(18, 30, 180))  # the dragged-to place, to a pixel
    assert ghost == pytest.approx(expected, abs=0.1)
    mouse(pygame.MOUSEBUTTONUP, window, 18, 30)
    tick(window)
    assert sim.robot.pose == start
    assert window.bridge.latest.ghost is None


def test_right_drag_turns_the_robot(window: Window) -> None:
    sim = window.bridge.sim
    mouse(pygame.MOUSEBUTTONDOWN, window, 6, 40, button=3)
    mouse(pygame.MOUSEMOTION, window, 8, 42, button=3)
    mouse(pygame.MOUSEBUTTONUP, window, 8, 42, button=3)
    tick(window)
    pose = sim.robot.pose
    assert (pose.x, pose.y) == (6.0, 42.0)
    assert pose.heading == pytest.approx(270.0, abs=1.0)


def test_click_off_the_robot_does_nothing(window: Window) -> None:
    start = window.bridge.sim.robot.pose
    mouse(pygame.MOUSEBUTTONDOWN, window, 30, 42)
    mouse(pygame.MOUSEMOTION, window, 40, 42)
    tick(window)
    assert window.drag is None
    assert window.bridge.sim.robot.pose == start


def test_resize_rescales_the_scene(window: Window) -> None:
    before = window.view.ppi
    pygame.display.set_mode((800, 500), pygame.RESIZABLE)
    pygame.event.post(pygame.event.Event(pygame.VIDEORESIZE, size=(800, 500), w=800, h=500))
    tick(window)
    assert window.screen.get_size() == (800, 500)
    assert window.view.ppi < before
    left, _ = window.view.point(0, 0)
    right, bottom = window.view.point(window.bridge.sim.maze.width, window.bridge.sim.maze.height)
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
    assert sim.steps == 1


def test_hud_shows_the_runs_outcome(window: Window) -> None:
    sim = window.bridge.sim
    block = sim.block
    # Facing the block from below, 1.2 in short of it (heading 180: up; the nose is 4 in ahead),
    # put there by hand: no motion, no path.
    window.bridge.post(PlaceRobot(Pose(block.x, block.y + block.size / 2 + 1.2 + 4, 180)))
    tick(window)
    sim.step(30)
    sim.command("zz")  # no such device: NaN
    sim.command("w0-0.5")
    sim.step()
    tick(window)
    texts = hud_texts(window)
    assert texts[f"{sim.dt:.2f} s"] == TEXT  # the stopwatch runs from the first motion ...
    assert texts["0.1 in"] == TEXT  # ... and the path grows
    assert texts["2 replies: 0 busy, 1 NaN"] == TEXT
    assert texts["0"] == TEXT  # no collisions
    sim.run_until_idle()
    sim.step(10)
    tick(window)
    texts = hud_texts(window)
    assert texts[f"reached the block in {2 * sim.dt:.2f} s"] == LIT  # 1 in away after 2 steps
    assert texts["0.5 in"] == TEXT
    sim.command("w0--60")  # backwards into the bottom wall
    sim.run_until_idle()
    tick(window)
    outcome = shown_outcome(window)
    assert outcome.collisions == 1
    assert outcome.first_collision is not None
    assert outcome.blocked_moves == 1  # the move into the wall went part of its way
    assert hud_texts(window)["1, 1 move blocked"] == ALARM


def test_run_window_quits_on_escape(caplog: pytest.LogCaptureFixture) -> None:
    sim = Simulation.from_config()
    pygame.display.init()
    key(pygame.K_ESCAPE)
    with caplog.at_level(logging.WARNING, logger="simmer.ui"):
        run_window(Runner(sim, speed=None))
    assert not sim.observers  # the window let go of the simulation
    # With no screen (the dummy driver), the student is told why nothing shows.
    assert "no screen found (SDL video driver 'dummy')" in caplog.text


def serve_with_window(
    window: Window,
    runner: Runner,
    program: Callable[[int], None],
    stop: threading.Event,
    until: float,
) -> threading.Thread:
    """Serve the persistent protocol and run ``window`` (this thread) with ``runner`` (its own
    thread) while ``program(port)`` runs in a third; tear everything down; return that thread."""
    link = Transports(runner.bus, runner.sim.config, RunOptions.free_ports())
    with link:
        thread = threading.Thread(target=program, args=(link.stream.port,))
        thread.start()
        window.run(runner, stop=stop, until=until)
        thread.join(TIMEOUT)
    runner.bus.close()
    window.close()
    window.bridge.close()
    return thread


def test_window_and_control_programs_share_one_simulation() -> None:
    sim = Simulation.from_config()
    runner = Runner(sim, speed=1.0)
    bridge = Bridge(sim)
    window = Window(bridge)
    stop = threading.Event()
    replies: list[list[float]] = []
    clients_seen: list[str] = []
    errors: list[BaseException] = []

    def program(port: int) -> None:
        try:
            with connect(port=port) as client:
                replies.append(client.send("u0,u1"))
                wait_for(lambda: bridge.latest.clients, "the window to show the client", TIMEOUT)
                clients_seen.extend(bridge.latest.clients or ())
        except BaseException as exc:
            errors.append(exc)
        finally:
            stop.set()

    serve_with_window(window, runner, program, stop, until=120.0)
    assert not errors
    assert replies == [[pytest.approx(39.5), pytest.approx(3.5)]]
    assert bridge.latest.commands[-1].message == "u0,u1"
    assert clients_seen


def test_drawing_never_starves_the_control_link(monkeypatch: pytest.MonkeyPatch) -> None:
    """While the window thread is stuck in the flip, commands are still answered."""
    sim = Simulation.from_config()
    runner = Runner(sim, speed=1.0)
    bridge = Bridge(sim)
    window = Window(bridge)
    in_flip, release, stop = threading.Event(), threading.Event(), threading.Event()
    flips = {"entered": 0, "returned": 0}
    answered: list[tuple[list[float], int]] = []
    errors: list[BaseException] = []

    def blocking_flip(*args: object) -> None:
        flips["entered"] += 1
        in_flip.set()
        assert release.wait(TIMEOUT)
        flips["returned"] += 1

    monkeypatch.setattr(pygame.display, "update", blocking_flip)
    monkeypatch.setattr(pygame.display, "flip", blocking_flip)

    def program(port: int) -> None:
        try:
            assert in_flip.wait(TIMEOUT)
            with connect(port=port) as client:
                for message in ("u0,u1", "w0-3", "u0", "r0-90", "xx", "u1"):
                    answered.append((client.send(message), flips["returned"]))
        except BaseException as exc:
            errors.append(exc)
        finally:
            release.set()
            stop.set()

    thread = serve_with_window(window, runner, program, stop, until=600.0)
    assert not errors
    assert flips["entered"] == 1  # the window thread never got past its first flip ...
    assert [returned for _, returned in answered] == [0] * 6  # ... while all six were answered
    replies = [reply for reply, _ in answered]
    assert replies[0] == [pytest.approx(39.5), pytest.approx(3.5)]
    assert replies[1] == [math.inf]
    assert len(replies) == 6
    assert all(len(reply) == 1 for reply in replies[1:])
    assert not thread.is_alive()


def test_the_window_says_one_thing_when_no_screen_is_found(
    caplog: pytest.LogCaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    said: list[str] = []
    with caplog.at_level(logging.WARNING, logger="simmer.ui"):
        serve(
            Simulation.from_config(),
            RunOptions.free_ports(window=True, speed=None, seconds=0.1),
            echo=said.append,
        )
    assert "no screen found" in caplog.text
    assert not any("window open" in line for line in said)
    # with a screen, the window says it is open
    from simmer.ui import window

    monkeypatch.setattr(window.pygame.display, "get_driver", lambda: "x11")
    said.clear()
    serve(
        Simulation.from_config(),
        RunOptions.free_ports(window=True, speed=None, seconds=0.1),
        echo=said.append,
    )
    assert "window open (press h for help)" in said


def test_the_screenshots_file_is_said_in_the_terminal_too(tmp_path: Path) -> None:
    """Under --program the log goes to a file: the screenshot's path was only there."""
    sim = Simulation.from_config()
    said: list[str] = []
    bridge = Bridge(sim, echo=said.append)
    window = Window(bridge, surface=pygame.Surface(default_window_size(sim)), save_dir=tmp_path)
    tick(window)
    key(pygame.K_p, unicode="p")
    tick(window)
    (png,) = tmp_path.glob("simmer-*.png")
    assert said == [f"saved the screenshot {png}"]
    window.close()
    bridge.close()
