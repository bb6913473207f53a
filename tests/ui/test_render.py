"""The renderer is separate from the model: recorded draw calls, then real pixels."""

from __future__ import annotations

import os
from pathlib import Path

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

import numpy as np
import pygame
import pytest

from simmer import Simulation
from simmer.colors import BLACK_TILE, WHITE_TILE
from simmer.devices.base import Segment
from simmer.ui import (
    Bridge,
    PygameRenderer,
    RecordingRenderer,
    ScenePainter,
    View,
    Window,
    render_scene,
)
from simmer.ui.hud import (
    ALARM,
    COMMANDS_X,
    DIAL_RADIUS,
    DIAL_X,
    LIT,
    PATH_X,
    ROWS,
    TEXT,
    VALUE_X,
    paint_hud,
)
from simmer.ui.offscreen import OffscreenRenderer
from simmer.ui.render import TextCache, merge_rects
from simmer.ui.scene import PANEL_HEIGHT, default_window_size
from simmer.view.snapshot import Snapshot, StaticScene
from simmer.world.outcome import Outcome

from helpers import LAB_SEQUENCE, default_data, make_sim, run_sequence

SMALL = """
walls = [[1, 1]]
block_position = [18, 6]
robot_start_position = [6, 6]
robot_start_rotation = 0
ppi = 10
border_pixels = 20
"""


def assert_close(actual: object, expected: object) -> None:
    """Pixel coordinates equal to rounding error (nested sequences allowed)."""
    np.testing.assert_allclose(np.asarray(actual, dtype=float), np.asarray(expected, dtype=float))


@pytest.fixture
def small(tmp_path: Path) -> Simulation:
    """A 24 × 12 in maze of two open cells, a square robot, no devices."""
    path = tmp_path / "small.toml"
    path.write_text(SMALL)
    return Simulation.from_config(path)


def test_static_layer_draw_calls(small: Simulation) -> None:
    view = View(10.0, 20.0, 30.0)
    rec = RecordingRenderer()
    ScenePainter(StaticScene.of(small)).paint_static(rec, view, (280, 170))
    settings = small.config.settings
    assert rec.calls[0].op == "fill"
    assert rec.calls[0].args == (settings.background_color,)
    rects = rec.of("rect")
    tiles = [args for args in rects if args[1] in (WHITE_TILE, BLACK_TILE)]
    assert len(tiles) == 8 * 4  # 3-in tiles over 24 × 12 in
    for row in range(4):
        for col in range(8):
            rect, color, width = tiles[row * 8 + col]
            assert rect == (20 + 30 * col, 30 + 30 * row, 30, 30)
            assert color == (WHITE_TILE if small.maze.floor_white[row, col] else BLACK_TILE)
            assert width == 0
    walls = [args[0] for args in rects if args[1] == settings.wall_color]
    # The boundary only (the two open cells share no wall): top, bottom, left, right.
    half = settings.wall_thickness / 2 * 10
    assert set(walls) == {
        (20 - half, 30 - half, 240 + 2 * half, 2 * half),
        (20 - half, 150 - half, 240 + 2 * half, 2 * half),
        (20 - half, 30 - half, 2 * half, 120 + 2 * half),
        (260 - half, 30 - half, 2 * half, 120 + 2 * half),
    }
    assert len(walls) == 4


def test_dynamic_layer_draw_calls(small: Simulation) -> None:
    view = View(10.0, 20.0, 30.0)
    rec = RecordingRenderer()
    painter = ScenePainter(StaticScene.of(small))
    painter.paint_dynamic(rec, view, Snapshot.of(small))
    settings = small.config.settings
    ops = [call.op for call in rec.calls]
    # block fill + outline, robot fill + outline, heading mark; no floor or walls
    assert ops == ["polygon", "polygon", "polygon", "polygon", "segment"]
    block_points, block_color, _ = rec.calls[0].args
    assert block_color == settings.block_color
    assert_close(block_points, [(20 + x * 10, 30 + y * 10) for x, y in small.block.polygon])
    robot_points, robot_fill, _ = rec.calls[2].args
    assert robot_fill == painter.robot_fill
    assert_close(robot_points, [(80 + x * 10, 90 + y * 10) for x, y in small.robot.outline])
    outline = rec.calls[3].args
    assert outline[1] == settings.robot_color
    assert outline[2] == round(settings.robot_thickness * 10)
    start, end, _, _ = rec.calls[4].args
    assert isinstance(start, tuple)
    assert isinstance(end, tuple)
    assert_close(start, (80, 90))
    assert end[1] > start[1]  # heading 0 points down the screen


def test_measurements_and_devices_are_drawn() -> None:
    sim = Simulation.from_config()  # the lab rover, all four ultrasonic sensors simulated
    sim.step()
    rec = RecordingRenderer()
    painter = ScenePainter(StaticScene.of(sim))
    view = View.fit(sim, default_window_size(sim))
    painter.paint_dynamic(rec, view, Snapshot.of(sim))
    segments = rec.of("segment")
    rays = segments[:-1]  # first, under the path, the robot and its heading mark (the last)
    assert len(rays) == 4 * 7
    u0 = sim.robot.sensors["u0"]
    for (start, end, color, _), shape in zip(rays[:7], u0.shapes(sim), strict=True):
        assert isinstance(shape, Segment)
        assert_close(start, view.point(*shape.start))
        assert_close(end, view.point(*shape.end))
        assert color == (0, 255, 0)
    device_outlines = [args for args in rec.of("polygon") if args[2] == 2]
    visible = [d for d in sim.robot.devices.values() if d.visible]
    assert len(device_outlines) == len(visible) == 6  # two motors, four sensors
    assert_close(device_outlines[0][0], view.points(sim.robot.device_polygon(visible[0])))


def test_pixels_on_a_real_surface() -> None:
    sim = Simulation.from_config()
    size = default_window_size(sim)
    assert size == (1576, 920)  # fits a 1080p screen at the default ppi
    pygame.display.init()
    surface = pygame.Surface(size)
    bridge = Bridge(sim)
    window = Window(bridge, surface=surface)
    window.draw()
    view = window.view
    settings = sim.config.settings
    maze = sim.maze

    def pixel(x: float, y: float) -> tuple[int, int, int]:
        px, py = view.point(x, y)
        r, g, b, _ = surface.get_at((int(px), int(py)))
        return (r, g, b)

    # Walls: the middle of every wall segment.
    for x1, y1, x2, y2 in maze.segments.tolist():
        assert pixel((x1 + x2) / 2, (y1 + y2) / 2) == settings.wall_color
    # Floor tiles in open cells, away from the robot: colour matches floor_white.
    checked = {True: 0, False: 0}
    for row, col in np.ndindex(maze.floor_white.shape):
        x, y = (col + 0.5) * maze.tile, (row + 0.5) * maze.tile
        if maze.solid[int(y // maze.cell), int(x // maze.cell)] or abs(x - 6) + abs(y - 42) < 12:
            continue
        if abs(x - sim.block.x) + abs(y - sim.block.y) < 6:
            continue
        white = bool(maze.floor_white[row, col])
        assert pixel(x, y) == (WHITE_TILE if white else BLACK_TILE), (row, col)
        checked[white] += 1
    assert checked[True] > 20
    assert checked[False] > 20
    assert pixel(sim.block.x, sim.block.y) == settings.block_color
    pose = sim.robot.pose  # heading 180: robot frame (1.5, -1.5) is world (-1.5, +1.5)
    assert pixel(pose.x - 1.5, pose.y + 1.5) == window.painter.robot_fill
    assert pixel(pose.x + 2.875, pose.y + 3) == settings.robot_color  # robot frame (-2.875, -3)
    window.close()
    bridge.close()


def test_partial_redraw_matches_a_full_redraw() -> None:
    sim = Simulation.from_config()
    pygame.display.init()
    size = default_window_size(sim)
    bridge = Bridge(sim)
    window = Window(bridge, surface=pygame.Surface(size))
    window.draw()
    sim.command("w0-12")
    for _ in range(40):
        sim.step()
        bridge.sync()
        window.draw()
    other = Simulation.from_config()
    other.command("w0-12")
    other.step(40)
    fresh = Window(Bridge(other), surface=pygame.Surface(size))
    fresh.draw()
    maze_top = PANEL_HEIGHT + 1
    area = pygame.Rect(0, maze_top, size[0], size[1] - maze_top)
    a = pygame.surfarray.array3d(window.screen.subsurface(area))
    b = pygame.surfarray.array3d(fresh.screen.subsurface(area))
    assert np.array_equal(a, b)


def test_merge_rects_joins_overlapping_neighbours() -> None:
    merged = merge_rects(
        [pygame.Rect(0, 0, 10, 10), pygame.Rect(2, 2, 10, 10), pygame.Rect(500, 500, 5, 5)]
    )
    assert merged == [pygame.Rect(0, 0, 12, 12), pygame.Rect(500, 500, 5, 5)]
    assert merge_rects([]) == []


def test_pygame_renderer_tracks_what_it_drew() -> None:
    surface = pygame.Surface((100, 100))
    r = PygameRenderer(surface)
    r.draw_rect((10, 10, 5, 5), (255, 0, 0))
    r.draw_text("hi", (50, 50), (255, 255, 255), 18)
    assert r.dirty[0] == pygame.Rect(10, 10, 5, 5)
    assert r.dirty[1].topleft == (50, 50)


def test_render_scene_saves_an_image(tmp_path: Path) -> None:
    sim = Simulation.from_config()
    sim.step()
    path = tmp_path / "scene.png"
    surface = render_scene(sim, path)
    assert surface.get_size() == default_window_size(sim)
    assert pygame.image.load(str(path)).get_size() == surface.get_size()
    assert not sim.observers


def test_exposed_window_is_redrawn_whole() -> None:
    sim = Simulation.from_config()
    pygame.display.init()
    bridge = Bridge(sim)
    window = Window(bridge, surface=pygame.Surface(default_window_size(sim)))
    window.draw()
    assert window._updated is None
    window.draw()
    assert window._updated is not None  # only what changed
    window.handle(pygame.event.Event(pygame.WINDOWEXPOSED))
    window.draw()
    assert window._updated is None
    window.close()
    bridge.close()


def test_hud_is_painted_from_the_snapshot_alone() -> None:
    sim = Simulation.from_config()
    bridge = Bridge(sim)
    sim.command("u0")
    sim.set_manual_keys({"w"})
    bridge.local.paused = True
    bridge.local.clients = ["127.0.0.1:50000"]
    bridge.sync()
    snap = bridge.latest
    first = RecordingRenderer()
    paint_hud(first, snap)
    texts = [args[0] for args in first.of("text")]
    assert any("PAUSED" in str(text) for text in texts)
    assert any(str(text).strip().startswith("0.00 s  u0 -> ") for text in texts)
    assert "127.0.0.1:50000" in texts
    assert ((52 + 30, 12, 26, 26), LIT, 0) in first.of("rect")  # the W key lit
    sim.step(60)  # the simulation moves on; the snapshot does not
    again = RecordingRenderer()
    paint_hud(again, snap)
    assert again.calls == first.calls
    bridge.close()


def test_hud_image_after_reaching_the_block(tmp_path: Path) -> None:
    sim = make_sim()
    pygame.display.init()
    bridge = Bridge(sim)
    window = Window(bridge, surface=pygame.Surface(default_window_size(sim)))
    run_sequence(sim, LAB_SEQUENCE)
    bridge.sync()
    window.draw()
    outcome = bridge.latest.outcome
    assert outcome is not None
    assert outcome.task2_time is not None
    path = tmp_path / "hud.png"
    width = window.screen.get_width()
    pygame.image.save(window.screen.subsurface((0, 0, width, PANEL_HEIGHT)), str(path))
    pixels = pygame.surfarray.array3d(pygame.image.load(str(path)))
    font = TextCache().font(22)

    def ink(x: int, row: int, color: tuple[int, int, int]) -> tuple[int, int]:
        """First and last column drawn in exactly ``color`` in a row, from ``x`` to the
        commands' column."""
        band = pixels[x:COMMANDS_X, ROWS[row] : ROWS[row] + 16]
        columns = np.flatnonzero((band == color).all(axis=-1).any(axis=1))
        return x + int(columns[0]), x + int(columns[-1])

    # The stopwatch stopped, in yellow, as wide as its text; the pose row is not highlighted.
    watch = f"reached the block in {outcome.task2_time:.2f} s"
    first, last = ink(VALUE_X, 1, LIT)
    assert first - VALUE_X <= 2
    assert last - first == pytest.approx(font.size(watch)[0], abs=4)
    assert not (pixels[:, ROWS[2] : ROWS[2] + 16] == LIT).all(axis=-1).any()
    # The path length beside the collisions.
    first, last = ink(PATH_X, 3, TEXT)
    assert last - first == pytest.approx(font.size(f"{outcome.path_length:.1f} in")[0], abs=4)
    window.close()
    bridge.close()


def test_a_snapshot_maker_shares_the_observers_a_simulation_has_already() -> None:
    """A frame drawn after a run (a sweep's last frame) shows the run's own last commands,
    outcome and trail, not empty ones of its own."""
    from simmer.view.commands import CommandLog
    from simmer.view.maker import LocalControls, SnapshotMaker
    from simmer.view.trail import Trail

    sim = Simulation.from_config()
    log, trail = CommandLog(), Trail(sim.robot.pose)
    sim.add_observer(log)
    sim.add_observer(trail)
    sim.command("u0")
    maker = SnapshotMaker(sim)
    assert maker.commands is log
    assert maker.trail is trail
    assert [entry.message for entry in maker.snapshot(LocalControls(sim)).commands] == ["u0"]
    maker.close()
    assert log in sim.observers  # what it did not add, it does not take away
    fresh = SnapshotMaker(Simulation.from_config())
    assert fresh.commands is not log
    fresh.close()


def test_the_hud_shows_what_the_link_model_did_under_the_clients() -> None:
    from simmer.ui.hud import ALARM, CLIENTS_X

    sim = Simulation.from_config()
    bridge = Bridge(sim)
    counts = {"messages": 40.0, "bytes": 400.0, "seconds": 1.25, "lost": 3.0}
    counts |= {"corrupted": 1.0, "dropouts": 1.0, "in_dropout": 2.0}
    bridge.outcome.link_counts = lambda: counts
    bridge.local.clients = ["stream 127.0.0.1:50000", "serial /dev/pts/3", "two-port x"]
    bridge.sync()
    painted = RecordingRenderer()
    paint_hud(painted, bridge.latest)
    texts = {args[0]: args[1:] for args in painted.of("text")}
    # two clients, then the link's two lines (the first red: bytes were lost)
    assert "two-port x" not in texts
    assert texts["link: 3 lost, 1 corrupted"][:2] == ((CLIENTS_X, 64), ALARM)
    assert texts["1 dropout, 1.25 s on it"][:2] == ((CLIENTS_X, 80), TEXT)
    bridge.outcome.link_counts = None  # the model off: no link line, every client listed
    bridge.sync()
    plain = RecordingRenderer()
    paint_hud(plain, bridge.latest)
    texts = {args[0]: args[1:] for args in plain.of("text")}
    assert "two-port x" in texts
    assert not any(str(text).startswith("link:") for text in texts)
    bridge.close()


def _frame(
    sim: Simulation, outcome: Outcome | None = None, *, show_help: bool = False
) -> np.ndarray:
    """One frame of ``sim`` drawn off screen, as pixels (x, y, rgb)."""
    offscreen = OffscreenRenderer(StaticScene.of(sim))
    report = outcome.report() if outcome is not None else None
    offscreen.draw(Snapshot.of(sim, outcome=report), show_help=show_help)
    return pygame.surfarray.array3d(offscreen.surface)


def test_every_help_line_stays_inside_its_box() -> None:
    """The help box is as wide as its longest line (the B line once ran past it): every pixel
    the help changes lies within its frame."""
    sim = make_sim()
    changed = (_frame(sim, show_help=True) != _frame(sim)).any(axis=-1)
    xs, ys = np.nonzero(changed)
    left, right, top, bottom = xs.min(), xs.max(), ys.min(), ys.max()
    for edge in (
        (pixels := _frame(sim, show_help=True))[left, top:bottom],
        pixels[right, top:bottom],
    ):
        assert (edge == LIT).all(axis=-1).all(), "text outside the help's frame"
    assert (pixels[left:right, top] == LIT).all(axis=-1).all()


def test_a_blocked_move_is_drawn_in_red_over_the_robot_and_counted_in_the_hud() -> None:
    sim = make_sim()
    outcome = Outcome.attach(sim)
    free = _frame(sim, outcome)
    sim.command("w0-60")  # up the first column into the wall
    sim.run_until_idle()
    sim.step(30)  # within the two seconds the window keeps showing it
    assert sim.blocked_now() is not None
    assert "'w0-60'" in sim.blocked_now()
    blocked = _frame(sim, outcome)
    below_panel = slice(PANEL_HEIGHT, None)
    assert not (free[:, below_panel] == ALARM).all(axis=-1).any()
    assert (blocked[:, below_panel] == ALARM).all(axis=-1).sum() > 100  # outline and label
    collisions_row = blocked[VALUE_X:PATH_X, ROWS[3] : ROWS[3] + 16]
    assert (collisions_row == ALARM).all(axis=-1).any()  # "1, 1 move blocked" in red
    sim.step(200)
    assert sim.blocked_now() is None


@pytest.mark.parametrize(
    ("heading", "side"), [(0, "down"), (90, "left"), (180, "up"), (270, "right")]
)
def test_the_heading_dial_points_where_the_robot_faces_on_screen(heading: float, side: str) -> None:
    """Heading 0 faces +y, down the screen; 90 faces -x, left; a positive turn is clockwise."""
    data = default_data()
    data["robot_start_rotation"] = heading
    pixels = _frame(make_sim(data))
    cx, cy = DIAL_X, ROWS[2] + 9
    box = pixels[cx - DIAL_RADIUS : cx + DIAL_RADIUS + 1, cy - DIAL_RADIUS : cy + DIAL_RADIUS + 1]
    xs, ys = np.nonzero((box == TEXT).all(axis=-1))
    dx, dy = xs.mean() - DIAL_RADIUS, ys.mean() - DIAL_RADIUS
    expected = {"down": (0, 1), "left": (-1, 0), "up": (0, -1), "right": (1, 0)}[side]
    assert dx * expected[0] + dy * expected[1] > 2  # the arrow's ink lies on that side


def test_the_axes_mark_is_drawn_in_the_rulers_margin_at_the_origin() -> None:
    sim = make_sim()
    scene = StaticScene.of(sim)
    rec = RecordingRenderer()
    view = View.fit(scene, default_window_size(sim))
    ScenePainter(scene).paint_static(rec, view, default_window_size(sim))
    x0, y0 = view.point(0, 0)
    letters = [call for call in rec.of("text") if call[0] in ("x", "y")]
    assert len(letters) == 2
    (_, (xx, xy), *_), (_, (yx, yy), *_) = sorted(letters, key=lambda c: str(c[0]))
    assert xx > x0 + 20  # right of the origin,
    assert xy < y0  # above the maze
    assert yx < x0  # left of the maze,
    assert yy > y0  # below the origin
    arrows = [c for c in rec.of("segment") if c[0][0] >= x0 - 20 and c[0][1] <= y0 + 80]
    assert any(end[0] > start[0] + 20 and end[1] == start[1] for start, end, *_ in arrows)
    assert any(end[1] > start[1] + 20 and end[0] == start[0] for start, end, *_ in arrows)


def test_a_beliefs_label_sits_in_a_box_readable_over_its_cloud() -> None:
    """A label under a thick particle cloud was purple on purple: it has a light box now."""
    from simmer.localize.belief import read_belief
    from simmer.ui.belief import BELIEF_COLOR, LABEL_BACK, paint_belief

    rng = np.random.default_rng(0)
    particles = [[30 + rng.normal(0, 2), 20 + rng.normal(0, 2), rng.uniform(0, 360), 1.0]
                 for _ in range(3000)]  # fmt: skip
    belief, _ = read_belief({"particles": particles, "labels": [[30, 20, "here"]]})
    surface = pygame.Surface((800, 500))
    view = View(16.0, 0.0, 0.0)
    paint_belief(PygameRenderer(surface), view, belief, (96.0, 48.0))
    pixels = pygame.surfarray.array3d(surface)
    x, y = (round(v) for v in view.point(30, 20))
    around = pixels[x - 20 : x + 20, y - 6 : y + 6]
    back = (around == LABEL_BACK).all(axis=-1).mean()
    ink = (around == BELIEF_COLOR).all(axis=-1).mean()
    assert back > 0.4  # the box behind the text, not the cloud
    assert 0.02 < ink < 0.6  # the text itself, on it
